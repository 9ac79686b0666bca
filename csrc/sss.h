/*
 * sss.h - screen-space subsurface scattering on Blender render passes.
 *
 * libsss blurs the diffuse light of a render (L = DiffDir + DiffInd) with a
 * per-material diffusion profile that is projected through the real camera
 * at every pixel's depth, and recombines the result with the other passes
 * exactly as Blender does:
 *
 *   Combined = SSS(L) * DiffCol + (GlossDir + GlossInd) * GlossCol
 *            + (TransDir + TransInd) * TransCol + Emit + Env
 *
 * USAGE
 *   sss_passes passes = {0};          // views of the caller's pass buffers
 *   passes.diff_dir = (sss_image){dd, w, h, 3, 0}; ... depth, index_ma ...
 *   sss_camera cam;   sss_camera_default(&cam);   cam.lens_mm = 85; ...
 *   sss_material mat; sss_material_default(&mat, SSS_PROFILE_BURLEY);
 *   mat.pass_index = 1; mat.radius[0] = 0.004; ...           // metres
 *   sss_options opt;  sss_options_default(&opt);
 *   char err[256];
 *   sss_result r = sss_apply(&passes, &cam, &mat, 1, &opt, &out, NULL,
 *                            err, sizeof err);
 *   if (r != SSS_OK) fprintf(stderr, "%s: %s\n", sss_status_string(r), err);
 *
 * UNITS
 *   Depth and Position passes are in scene units; sss_camera.unit_scale says
 *   how many metres one scene unit is (Blender's Unit Scale). Profile
 *   lengths are in metres (Burley radius, Jimenez width), Gaussian variances
 *   in mm^2 and near/far sigmas in mm, as in the literature they come from.
 *
 * PIXELS AND POLICIES
 *   Images are row-major, top row first (as in EXR), float32, with any
 *   channel count >= what the pass needs (extra channels are ignored).
 *   The caller owns all memory; the library allocates scratch memory inside
 *   a call and frees it before returning.
 *   A pixel scatters when its material index (IndexMA, rounded) is in the
 *   material table with a profile other than SSS_PROFILE_NONE and its depth
 *   is finite, > 0 and < sss_options.background_depth. Every other pixel is
 *   passed through untouched and is never used as a sample.
 *   Non-finite values (NaN, Inf) in the light or colour passes are never
 *   spread: such a sample is dropped like a sample on another material, and
 *   the pixel itself keeps its own (non-finite) value.
 *   Samples on another material, on the background, outside the image or
 *   beyond the profile's support in true 3-D distance are dropped and the
 *   remaining weights renormalised per channel: no halos, no bleeding, no
 *   darkening at borders, and a constant image stays constant.
 *
 * THREADS
 *   No global mutable state. Concurrent calls on different output buffers
 *   are safe. Results are identical for any sss_options.num_threads.
 */
#ifndef SSS_H
#define SSS_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(_WIN32)
#define SSS_API __declspec(dllexport)
#else
#define SSS_API __attribute__((visibility("default")))
#endif

/* Bumped whenever a public struct or signature changes. */
#define SSS_ABI_VERSION 15
#define SSS_VERSION_STRING "0.1.0"

/* ---------------------------------------------------------------- status */

typedef int32_t sss_result; /* fixed-size return type; values are sss_status */

enum sss_status {
	SSS_OK = 0,                  /* success */
	SSS_ERR_INVALID_ARGUMENT = 1,/* NULL, negative, NaN or out-of-range value */
	SSS_ERR_SIZE_MISMATCH = 2,   /* pass buffers of different sizes */
	SSS_ERR_MISSING_PASS = 3,    /* a required pass is absent */
	SSS_ERR_OUT_OF_MEMORY = 4,   /* an allocation failed */
	SSS_ERR_UNSUPPORTED = 5,     /* valid but not implemented (e.g. method) */
	SSS_ERR_IO = 6,              /* file could not be read or written */
	SSS_ERR_EXR = 7,             /* the EXR library reported an error */
	SSS_ERR_UNKNOWN = 8          /* keep last */
};

/* "SSS_ERR_INVALID_ARGUMENT" etc.; "SSS_ERR_UNKNOWN" for unknown codes. */
SSS_API const char *sss_status_name(sss_result code);
/* A human sentence for the code; never NULL. */
SSS_API const char *sss_status_string(sss_result code);

SSS_API uint32_t sss_abi_version(void);
SSS_API const char *sss_version_string(void);

/* --------------------------------------------------------------- images */

/* A non-owning view of one pass. data == NULL means "pass absent". */
typedef struct sss_image {
	float *data;
	int32_t width;
	int32_t height;
	int32_t channels;   /* floats per pixel */
	int64_t row_stride; /* floats between rows; 0 = width * channels */
} sss_image;

/* The render passes, as Blender names them. Absent passes count as zero
 * (a missing colour pass as zero too, so its light is not added). */
typedef struct sss_passes {
	sss_image diff_dir;  /* required, RGB: diffuse direct light */
	sss_image diff_ind;  /* RGB, Cycles only */
	sss_image diff_col;  /* required, RGB: diffuse colour (albedo) */
	sss_image gloss_dir, gloss_ind, gloss_col;
	sss_image trans_dir, trans_ind, trans_col;
	sss_image emit;      /* RGB */
	sss_image env;       /* RGB */
	sss_image combined;  /* optional RGBA; only its alpha is used */
	sss_image depth;     /* required, 1 channel: planar view Z, scene units */
	sss_image index_ma;  /* required, 1 channel: material pass_index */
	sss_image position;  /* optional XYZ world position, scene units */
	/* Transmission (optional; see sss_transmission). The light arriving
	 * at each pixel through the object from behind: DiffDir and DiffInd
	 * of a view layer whose material override is a white Translucent BSDF
	 * (SSS_BACKLIGHT_LAYER in an EXR). Without back_dir nothing is
	 * transmitted. */
	sss_image back_dir;  /* RGB */
	sss_image back_ind;  /* RGB, optional */
	sss_image thickness; /* 1 channel: the object's local thickness behind
	                        the pixel, scene units; required with back_dir
	                        when a material transmits */
	sss_image facing;    /* optional, 1 channel: N . V in [0, 1] (the
	                        fast model's view term; 1 when absent) */
} sss_passes;

/* The render passes libsss reads (the members of sss_passes above
 * back_dir), one entry each, in sss_passes order. */
enum sss_pass_need {
	SSS_PASS_OPTIONAL = 0, /* used when present */
	SSS_PASS_REQUIRED = 1, /* always needed */
	SSS_PASS_CYCLES = 2    /* needed of a Cycles render (an EXR whose
	                          header Cycles stamped) */
};

typedef struct sss_pass_info {
	const char *name;       /* its short name in Blender's EXR: "DiffDir" */
	const char *components; /* those read, in order: "RGB" */
	const char *alt;        /* or this single component, or NULL */
	int32_t need;           /* sss_pass_need */
	const char *blender;    /* Blender's view layer use_pass_<blender> */
	const char *hint;       /* under View Layer Properties > Passes */
} sss_pass_info;

/* Fills *info with pass i (0, 1, ...); SSS_ERR_INVALID_ARGUMENT past the
 * last one or when info is NULL. The strings are the library's. */
SSS_API sss_result sss_render_pass(int32_t i, sss_pass_info *info);

/* Names the add-on and sss_process_exr use in Blender's multilayer EXR: the
 * back-light view layer, and its AOVs: SSSThicknessSq (thickness squared,
 * scene units^2: the mean over samples of AO(inside, Distance D) x D^2,
 * which is t^2 for a slab of thickness t < D; read as the root of its mean
 * over each pixel and its eight neighbours of the same material), or
 * SSSThickness (scene units), and SSSFacing (N . V). */
#define SSS_BACKLIGHT_LAYER "SSSBackLight"
/* The layer sss_process_exr adds: Combined (RGBA) and DiffLight (RGB). */
#define SSS_RESULT_LAYER "SSS"
#define SSS_THICKNESS_SQ_PASS "SSSThicknessSq"
#define SSS_THICKNESS_PASS "SSSThickness"
#define SSS_FACING_PASS "SSSFacing"

/* --------------------------------------------------------------- camera */

enum sss_camera_type {
	SSS_CAMERA_PERSPECTIVE = 0,
	SSS_CAMERA_ORTHOGRAPHIC = 1
};

enum sss_sensor_fit { /* Blender's Camera.sensor_fit */
	SSS_SENSOR_FIT_AUTO = 0,
	SSS_SENSOR_FIT_HORIZONTAL = 1,
	SSS_SENSOR_FIT_VERTICAL = 2
};

/* Blender's camera intrinsics; fill with sss_camera_default(). */
typedef struct sss_camera {
	uint32_t struct_size;
	int32_t type;            /* sss_camera_type */
	double lens_mm;          /* focal length, > 0 (perspective) */
	double sensor_width_mm;  /* > 0 */
	double sensor_height_mm; /* > 0 */
	int32_t sensor_fit;      /* sss_sensor_fit */
	double shift_x, shift_y; /* lens shift, fraction of the larger side */
	double ortho_scale;      /* > 0 (orthographic), scene units */
	double pixel_aspect_x;   /* > 0, Blender's render pixel_aspect_x */
	double pixel_aspect_y;   /* > 0 */
	double unit_scale;       /* > 0, metres per scene unit */
} sss_camera;

SSS_API void sss_camera_default(sss_camera *cam);
/* Horizontal pixels per metre on a plane facing the camera at planar depth
 * `depth` (scene units; any for an orthographic camera) in a width x height
 * image: how wide a length looks, for UIs (the add-on's kernel widths). */
SSS_API sss_result sss_camera_pixels_per_metre(const sss_camera *cam,
                                               int32_t width, int32_t height,
                                               double depth,
                                               double *pixels_per_metre,
                                               char *errbuf,
                                               size_t errbuf_len);

/* ------------------------------------------------------------- profiles */

enum sss_profile_kind {
	SSS_PROFILE_NONE = 0,      /* material does not scatter */
	SSS_PROFILE_BURLEY = 1,    /* Christensen-Burley normalized diffusion */
	SSS_PROFILE_GAUSSIANS = 2, /* sum of Gaussians (d'Eon skin by default) */
	SSS_PROFILE_JIMENEZ = 3,   /* Jimenez separable kernel */
	SSS_PROFILE_NEAR_FAR = 4   /* artist near/far Gaussian pair */
};

/* How Blender's Subsurface Radius becomes Burley's shape parameter d. */
enum sss_burley_mapping {
	SSS_BURLEY_CYCLES = 0,      /* d = radius / (4 pi), Cycles' Burley */
	SSS_BURLEY_EEVEE = 1,       /* d = 0.0459101 radius, EEVEE legacy */
	SSS_BURLEY_RANDOM_WALK = 2, /* radius = diffuse mean free path:
	                               d = radius / (3.5 + 100 (A - 0.33)^4) */
	SSS_BURLEY_CYCLES_RANDOM_WALK = 3, /* what Cycles 3.x's Random Walk
	                               (and 4.x/5.x's Random Walk (Skin), the
	                               same within 5 %) does with the radius,
	                               as measured (sss_calibration.c): mean
	                               free path l = radius sqrt(3 (1 - a')),
	                               a' from Jensen's dipole Rd(a') = A
	                               (eta 1.4), d = l / (1.9 - A + 3.5
	                               (A - 0.8)^2) */
	SSS_BURLEY_CYCLES4_RANDOM_WALK = 4 /* what Cycles 4.x/5.x's Random
	                               Walk (not Skin) does with the radius,
	                               as measured: d / radius from 0.017 at
	                               A = 0.05 to 0.104 at A >= 0.95 */
};

/* Matching another renderer's energy (sss_material.calibration). */
enum sss_calibration {
	SSS_CALIBRATION_NONE = 0,
	SSS_CALIBRATION_CYCLES_RANDOM_WALK = 1, /* Cycles 3.x's Random Walk:
	                               the diffuse light of a scattering pixel
	                               is scaled per channel by g(DiffCol), the
	                               random walk's reflectance over the
	                               Principled diffuse lobe's, measured on
	                               thick slabs (sss_calibration.c), after
	                               the blur (a brighter DiffCol where
	                               light leaves, as the random walk has),
	                               at the pixel's view angle and, with a
	                               Burley profile, times what a convex
	                               surface adds (measured on spheres, at
	                               the pixel's mean curvature from the
	                               Depth pass; not where back-lit
	                               transmission applies) */
	SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN = 2, /* the same for Cycles
	                               4.x/5.x's Random Walk (Skin) */
	SSS_CALIBRATION_CYCLES4_RANDOM_WALK = 3 /* and for 4.x/5.x's Random
	                               Walk */
};

enum sss_texturing {
	SSS_TEXTURING_POST = 0,         /* blur L, multiply by DiffCol after */
	SSS_TEXTURING_PRE_AND_POST = 1  /* blur L*sqrt(DiffCol), times sqrt after */
};

#define SSS_MAX_GAUSSIANS 8

/* Back-lit transmission: light that arrives at the back of a thin part
 * (sss_passes.back_dir + back_ind, B) and crosses its thickness t is added
 * to the diffuse light AFTER the blur, not blurred: it spread sideways over
 * the part's thickness, which B (a Translucent BSDF's chords through the
 * part) already holds, not over the radius. L' = blur(L) + strength x T(t)
 * x B per channel, with T <= 1 (the diffuse colour, i.e. the albedo,
 * multiplies it as it does all diffuse light).
 * Thickness NaN or negative means "unknown": nothing is added there. */
enum sss_transmission {
	SSS_TRANSMISSION_OFF = 0,
	SSS_TRANSMISSION_BURLEY = 1,  /* the profile's own medium. Burley: 1-D
	                                 diffusion through a slab of thickness
	                                 t in Cycles' random-walk medium (the
	                                 share leaving by the far face; about
	                                 1/2 at t = 0, see sss_transmission.c);
	                                 Gaussian sums: their mass beyond a
	                                 plane at t, sum w_i e^{-t^2/2v_i};
	                                 times transmission_color */
	SSS_TRANSMISSION_JIMENEZ = 2, /* Jimenez et al. 2010: d'Eon's skin
	                                 sum w_i e^{-s^2/v_i}, s (mm) = t x 8.25
	                                 (1 - translucency) / jimenez_width;
	                                 times transmission_color */
	SSS_TRANSMISSION_BEER_LAMBERT = 3, /* transmission_color^(t / distance):
	                                 the colour seen through
	                                 transmission_distance */
	SSS_TRANSMISSION_FAST = 4     /* GDC 2011: (saturate((1 - distortion)
	                                 N.V)^power x scale + ambient) x
	                                 max(0, 1 - t / distance), at most 1,
	                                 times transmission_color. L = -N: the
	                                 light that crossed a part leaves it
	                                 along its normal (no per-pixel L) */
};

/* One row of the per-material table. Fill with sss_material_default(),
 * which sets the kind's published defaults, then change what you need. */
typedef struct sss_material {
	uint32_t struct_size;
	int32_t pass_index;   /* 1..65535: the material's IndexMA value */
	int32_t kind;         /* sss_profile_kind */
	float strength;       /* 0..1: share of the diffuse light that scatters */
	int32_t texturing;    /* sss_texturing */
	int32_t taps;         /* taps per 1-D pass, 0 = sss_options.taps; 1..4097 */

	/* SSS_PROFILE_BURLEY */
	float radius[3];      /* metres per channel (Subsurface Radius x factor) */
	int32_t burley_mapping; /* sss_burley_mapping */
	float albedo[3];      /* 0..1, used by SSS_BURLEY_RANDOM_WALK */

	/* SSS_PROFILE_GAUSSIANS: R(r) = sum_i weight[i][c] G(variance[i], r) */
	int32_t gaussian_count;                     /* 1..SSS_MAX_GAUSSIANS */
	float gaussian_variance[SSS_MAX_GAUSSIANS]; /* mm^2, > 0 */
	float gaussian_weight[SSS_MAX_GAUSSIANS][3];/* >= 0, any sum > 0 */
	float gaussian_scale;                       /* >= 0, multiplies radii */

	/* SSS_PROFILE_JIMENEZ (Jimenez et al. 2012 separable kernel) */
	float jimenez_width;       /* metres: world span of 3 kernel units */
	float jimenez_strength[3]; /* 0..1 per channel, like (0.48,0.41,0.28) */
	float jimenez_falloff[3];  /* > 0 per channel, like (1.0,0.37,0.3) */

	/* SSS_PROFILE_NEAR_FAR */
	float scatter_scale;   /* >= 0, multiplies both sigmas */
	float near_far_balance;/* 0..1: 1 = all near, 0 = all far */
	float near_sigma[3];   /* mm per channel, > 0 */
	float far_sigma[3];    /* mm per channel, > 0 */

	/* Transmission (sss_transmission; all kinds). Lengths are metres and
	 * follow sss_options.radius_scale like the profile's. */
	int32_t transmission;            /* sss_transmission (OFF) */
	float transmission_strength;     /* 0..1 (1) */
	float transmission_color[3];     /* 0..1: tint (white); Beer-Lambert:
	                                    the colour at transmission_distance */
	float transmission_distance;     /* metres, > 0 (0.01): Beer-Lambert's
	                                    distance; fast: fade-out thickness */
	float transmission_translucency; /* 0..1 (0.83): Jimenez */
	float transmission_distortion;   /* 0..1 (0.2): fast, normal shift */
	float transmission_power;        /* > 0 (4): fast */
	float transmission_scale;        /* >= 0 (1): fast */
	float transmission_ambient;      /* >= 0 (0): fast */
	float thickness_scale;           /* >= 0 (1): multiplies the pass */
	float thin_reflectance;          /* 0..1 (0): share of the loss of
	                                    light a thin part reflects, lit
	                                    from the front, against a thick
	                                    one (measured for Blender 4.x's
	                                    Random Walk (Skin); others: none),
	                                    at the thickness pass x
	                                    thickness_scale; no pass: none */
	float transmission_baked_scale;  /* >= 0 (0: not baked): the back
	                                    light already holds the slab's
	                                    T(t) / T(0) for sss_options.
	                                    radius_scale = this (the add-on's
	                                    slab override): T(0) is applied
	                                    whatever the thickness pass
	                                    says, and any other
	                                    radius_scale but 0 is refused, as
	                                    T(t) could not follow it */

	/* Energy calibration (sss_calibration; all kinds; NONE by default).
	 * The gain is 1 + strength (g - 1), so strength 0 stays the
	 * identity. */
	int32_t calibration;
	float walk_ior;                  /* 1..3.8 (1.5): the index of the
	                                    surface the walk enters through;
	                                    4.x's plain Random Walk
	                                    (SSS_CALIBRATION_CYCLES4_RANDOM_WALK)
	                                    takes it from the Principled
	                                    BSDF's IOR and Specular IOR Level
	                                    (1.5 by default, 1 at Level 0),
	                                    and its energy follows it */
	float walk_roughness;            /* 0..1 (0.5): that surface's
	                                    roughness (the Principled BSDF's
	                                    Roughness), which plain Random
	                                    Walk's energy follows too */
} sss_material;

/* Sets struct_size, kind and that kind's defaults (d'Eon skin for
 * Gaussians, the demo values for Jimenez and near/far, Blender's default
 * radius (1, 0.2, 0.1) cm-scale for Burley). pass_index is left 0. */
SSS_API void sss_material_default(sss_material *mat, int32_t kind);

/* The material schema, one entry per key of a scene description's
 * "materials" entry (docs/scene.md), in the table's order: what it sets,
 * its default, its range and one line of help. */
enum sss_field_type {
	SSS_FIELD_FLOAT = 0, /* float */
	SSS_FIELD_RGB = 1,   /* float[3] */
	SSS_FIELD_INT = 2,   /* int32_t in [lo, hi] */
	SSS_FIELD_ENUM = 3,  /* int32_t, one of values[], named names[] */
	SSS_FIELD_DOUBLE = 4 /* double (sss_option_field only) */
};

typedef struct sss_field_info {
	const char *key;      /* the JSON key */
	const char *member;   /* the member it sets (sss_material's, or
	                         sss_options' for sss_option_field) */
	int32_t type;         /* sss_field_type */
	int32_t profile;      /* the sss_profile_kind reading it, -1 = every */
	int32_t transmits;    /* 1: read and checked only when transmission
	                         is not SSS_TRANSMISSION_OFF */
	double default_value[3]; /* sss_material_default's (one used unless
	                         SSS_FIELD_RGB); taps: 17 for Jimenez */
	double lo, hi;        /* the range; hi 1e30: no upper bound */
	int32_t lo_open;      /* 1: lo itself is excluded */
	int32_t name_count;   /* SSS_FIELD_ENUM: how many names it has */
	const char *help;     /* one line */
} sss_field_info;

/* Fills *info with field i (0, 1, ...); SSS_ERR_INVALID_ARGUMENT past
 * the last one or when info is NULL. The strings are the library's,
 * valid as long as it is loaded. */
SSS_API sss_result sss_material_field(int32_t i, sss_field_info *info);

/* Name j (0 .. name_count - 1) of enum field i and, when value is not
 * NULL, its value; NULL past the end. */
SSS_API const char *sss_material_field_name(int32_t i, int32_t j,
                                            int32_t *value);

/* The scene description's name of profile kind `kind` (sss_profile_kind:
 * "none", "burley", ...); NULL for any other value. */
SSS_API const char *sss_profile_name(int32_t kind);

/* Checks one material; detail about the first bad field goes to errbuf. */
SSS_API sss_result sss_material_validate(const sss_material *mat,
                                         char *errbuf, size_t errbuf_len);

/* Burley d (metres) per channel for a Burley material, as used. */
SSS_API sss_result sss_burley_d(const sss_material *mat, double d_out[3]);

/* Burley radial CDF P(r) = 1 - e^{-r/d}/4 - 3 e^{-r/(3d)}/4 (d > 0). */
SSS_API double sss_burley_cdf(double r, double d);
/* Its closed-form inverse for u in [0, 1); r for P(r) = u. */
SSS_API double sss_burley_inverse_cdf(double u, double d);
/* Burley profile R(r) = (e^{-r/d} + e^{-r/(3d)}) / (8 pi d r), per area. */
SSS_API double sss_burley_profile(double r, double d);

/* Distance (metres) beyond which the material's profile is treated as 0:
 * the largest over channels, before sss_options.radius_scale. */
SSS_API sss_result sss_material_support(const sss_material *mat,
                                        double *metres);

/* The 1-D kernel the separable method uses for this material at a given
 * projection (pixels per metre) on a flat, fronto-parallel surface with
 * nothing rejected: tap offsets in pixels and per-channel weights that sum
 * to 1. taps <= 0 means the material's or the default tap count; a kernel
 * whose half-width is at most 64 px has every pixel as a tap whatever the
 * count (up to 129). On input *count is the capacity of the arrays
 * (weights has 3 * capacity floats); on output the number of taps
 * written. A kernel more than 2^24 pixels wide (pixels_per_metre far past
 * any image) is SSS_ERR_INVALID_ARGUMENT. */
SSS_API sss_result sss_kernel_1d(const sss_material *mat,
                                 double pixels_per_metre, int32_t taps,
                                 float *offsets, float *weights,
                                 int32_t *count);

/* The transmittance factor of a material (what multiplies the back light;
 * strength and colour included) at a thickness in metres, with N . V =
 * facing (the fast model's view term; others ignore it), radius_scale 1.
 * Thickness NaN or negative gives 0; +Inf gives the thick limit. At most
 * strength x colour, except for Blender 4.x's Random Walk (Skin) (a
 * Burley profile with SSS_BURLEY_CYCLES_RANDOM_WALK and
 * SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN) and Random Walk
 * (SSS_BURLEY_CYCLES4_RANDOM_WALK and SSS_CALIBRATION_CYCLES4_RANDOM_WALK),
 * whose measured walks let more than the albedo through thin parts: there at most strength x
 * colour / albedo per channel (albedo times it at most 1; the albedo
 * multiplies it in the image). */
SSS_API sss_result sss_transmittance(const sss_material *mat,
                                     double thickness_metres, double facing,
                                     double out[3]);

/* How thick a part of this material can be before its transmittance
 * (strength and colour aside) falls below 1 % of what a thin part lets
 * through, in metres at radius_scale 1: how far a thickness measurement
 * must reach (the add-on's ambient-occlusion distance). 0 when the
 * material does not transmit. */
SSS_API sss_result sss_transmission_reach(const sss_material *mat,
                                          double *metres);

/* Whether the library has measured how much light this material's thin
 * parts reflect, lit from the front (thin_reflectance has an effect):
 * *measured 1 for a Burley profile with Blender 4.x's Random Walk (Skin)
 * calibration and mapping, 0 otherwise, whatever its thin_reflectance.
 * An invalid material (sss_material_validate) is
 * SSS_ERR_INVALID_ARGUMENT. */
SSS_API sss_result sss_thin_measured(const sss_material *mat, int *measured);

/* The diffusion slab behind SSS_TRANSMISSION_BURLEY on a Burley profile,
 * per channel, in metres at radius_scale 1 (sss_transmission.c): T(t) =
 * (1 - e^{-2 s a}) e^{-s (L - 2 a)} / (1 - e^{-2 s L}), L = max(t + 2 zb,
 * 2 a), s = sigma_tr (a / L when s L < 1e-6). A channel without a medium
 * (radius 0) gets zeros. SSS_ERR_UNSUPPORTED when the material's
 * transmission is not that slab. For Blender 4.x's two random walks
 * (see sss_transmittance) it is the medium's slab, whose mean free path
 * is 1.5 (a - zb); the transmittance is then the walk's, measured over
 * thickness / mean free path and albedo, not this formula. */
SSS_API sss_result sss_transmission_slab(const sss_material *mat,
                                         double sigma_tr[3], double a[3],
                                         double zb[3]);

/* The same slab's transmittance relative to a part of thickness 0,
 * T(t) / T(0) per channel (sss_transmittance's T, Blender 4.x's measured
 * walk included), sampled for a renderer that cannot call the
 * library (the add-on's back-light layer looks it up in an image while
 * it renders, then writes thickness 0, which the library turns into
 * T(0)): table[3 i + c] is channel c at the thickness (of the thickness
 * pass, in metres at radius_scale 1, the material's thickness_scale
 * applied as sss_transmittance applies it)
 *
 *   t_i = step (e^{i g} - 1),  g = ln(1 + span / step) / (n - 1),
 *
 * i = 0 .. n - 1: evenly spaced (step apart, a quarter of the smallest
 * mean free path) near 0, evenly in ln t far away, t_0 = 0 and
 * t_{n-1} = span, where every channel has fallen below 1e-6 of T(0). A
 * lookup reads index ln(1 + t / step) / g. The last sample is 0: a
 * lookup that interpolates linearly between samples and holds the last
 * one beyond them lets nothing through where the library lets (nearly)
 * nothing through. A channel without a medium (radius 0) is 1 at i = 0
 * and 0 after, as sss_transmittance; with thickness_scale 0 every sample
 * is 1 (thickness plays no part). n >= 2; SSS_ERR_UNSUPPORTED when the
 * material's transmission is not that slab. */
SSS_API sss_result sss_transmission_table(const sss_material *mat,
                                          int32_t n, float *table,
                                          double *step, double *span);

/* The energy gain of a material's calibration (its calibration, and for
 * plain Random Walk its walk_ior and walk_roughness) for a diffuse colour
 * (albedo, clamped to [0, 1]; a non-finite channel gets 1) seen at
 * view_cosine, |cos| of the angle between the surface's normal and the ray
 * to the camera (1: head-on; measured to 85 degrees, held beyond): the
 * measured reflectance of the calibrated renderer over the plain diffuse
 * lobe's, on a flat surface (sss_apply also follows the surface's
 * curvature). NONE gives 1. An invalid material (sss_material_validate)
 * is SSS_ERR_INVALID_ARGUMENT. */
SSS_API sss_result sss_calibration_gain(const sss_material *mat,
                                        const float albedo[3],
                                        float view_cosine, float gain[3]);

/* --------------------------------------------------------------- options */

enum sss_method {
	SSS_METHOD_AUTO = 0,      /* per material: separable, or where the
	                             radius reaches the surface's curvature
	                             radius disk, with the light that enters
	                             a pixel leaving it in all (see
	                             sss_process_options' chosen_methods) */
	SSS_METHOD_SEPARABLE = 1, /* two 1-D passes, all lobes at once */
	SSS_METHOD_SEPARABLE_EXACT = 2, /* two 1-D passes per Gaussian lobe:
	                                   exact for sums of Gaussians; Burley
	                                   is fitted with 6 lobes */
	SSS_METHOD_DISK = 3,      /* stratified inverse-CDF disk sampling,
	                             up to `samples` samples per pixel */
	SSS_METHOD_REFERENCE = 4  /* brute-force 2-D, true distances: slow */
};

/* The method's name in scene descriptions and on the command line
 * ("separable", ...) and one line on what it trades; NULL for a value that
 * is not a method, so that counting from 0 up to the first NULL lists
 * every method. */
SSS_API const char *sss_method_name(int32_t method);
SSS_API const char *sss_method_summary(int32_t method);

typedef struct sss_options {
	uint32_t struct_size;
	int32_t method;          /* sss_method */
	float radius_scale;      /* >= 0, multiplies every profile length */
	int32_t taps;            /* default taps per 1-D pass, 1..4097 (odd);
	                            the separable method reads every pixel
	                            of a kernel whose half-width is at most
	                            64 px whatever the budget, which only
	                            thins wider ones */
	int32_t num_threads;     /* 0 = all cores, 1..256 */
	double background_depth; /* > 0: depth >= this is background (1e9) */
	int32_t max_support_px;  /* >= 1: cap on a kernel's half-width */
	int32_t samples;         /* SSS_METHOD_DISK: most samples per pixel,
	                            1..4096 (64); a pixel takes
	                            pi R^2 / 4 for a kernel R pixels wide */
	int32_t crease;          /* 1 (default): a calibrated material also
	                            carries light over sharp convex edges
	                            onto the next face, as the walk does;
	                            0: not (what its measurement compares);
	                            2: the separable blur stops at them
	                            (with 1 only where the calibration has
	                            a measured loss) and nothing is
	                            carried over (what the gain and the lit
	                            face's loss are fitted against) */
} sss_options;

/* sss_options_default's taps, and what a material's taps 0 means. */
#define SSS_DEFAULT_TAPS 33

SSS_API void sss_options_default(sss_options *opt);

/* The options' schema, one entry per sss_options member in the order
 * sss_apply checks them, with its key at a scene description's top level
 * (docs/scene.md; "threads" sets num_threads), sss_options_default's
 * value, its range and one line of help, as sss_material_field gives a
 * material's: type SSS_FIELD_FLOAT (float), SSS_FIELD_DOUBLE,
 * SSS_FIELD_INT (lo..hi, inclusive; hi 2147483647: no upper bound) or
 * SSS_FIELD_ENUM (the method: values 0..name_count - 1, named by
 * sss_method_name). A number's hi 1e30 means no upper bound (finite; a
 * scene description's at most 1e30), +Inf none at all. profile is -1,
 * transmits 0. SSS_ERR_INVALID_ARGUMENT past the last one or when info
 * is NULL. */
SSS_API sss_result sss_option_field(int32_t i, sss_field_info *info);

/* Sizes of the public structs, so bindings can check their layouts. */
SSS_API size_t sss_struct_size(const char *struct_name);

/* ------------------------------------------------------------------ run */

/* Scatters the diffuse light and writes the recombined image.
 * out_combined: RGB or RGBA (alpha from passes->combined, else 1), may be
 * NULL if only the light is wanted. out_diffuse_light: RGB, optional: the
 * scattered diffuse light, so that contribution = light * DiffCol.
 * Outputs must have the passes' size and must not alias any input. A
 * packed output (row_stride 0 or width x channels) also serves as
 * working memory during the call, which saves a third of the memory: if
 * the call fails, its contents are unspecified.
 * errbuf (optional) receives a sentence naming the bad pass or field. */
SSS_API sss_result sss_apply(const sss_passes *passes, const sss_camera *cam,
                             const sss_material *materials,
                             int32_t material_count, const sss_options *opt,
                             const sss_image *out_combined,
                             const sss_image *out_diffuse_light,
                             char *errbuf, size_t errbuf_len);


/* ------------------------------------------------------------ EXR files
 * (sss_exr*.c, through the OpenEXR C API). An sss_exr holds one image part
 * decoded to float, grouped into passes: channel "ViewLayer.DiffDir.R"
 * is component R of pass "DiffDir" in layer "ViewLayer" (render output
 * naming); "DiffDir.R" has layer "" (File Output node naming); a channel
 * without a dot ("R") belongs to pass "" of layer "". A pass's components
 * are interleaved in canonical order (R G B A, X Y Z W, U V, then the rest
 * alphabetically), whatever order the file stores them in. */

typedef struct sss_exr sss_exr;

enum sss_exr_compression { /* values are OpenEXR's */
	SSS_EXR_NONE = 0, SSS_EXR_RLE = 1, SSS_EXR_ZIPS = 2, SSS_EXR_ZIP = 3,
	SSS_EXR_PIZ = 4, SSS_EXR_PXR24 = 5, SSS_EXR_B44 = 6, SSS_EXR_B44A = 7,
	SSS_EXR_DWAA = 8, SSS_EXR_DWAB = 9
};

typedef struct sss_exr_options {
	uint32_t struct_size;
	int32_t max_width;    /* reading: larger data windows are refused */
	int32_t max_height;   /* (default 32768 each) */
	int64_t max_pixels;   /* reading: width x height cap (default 2^28) */
	int32_t compression;  /* writing: sss_exr_compression (default ZIP);
	                         DWAA/DWAB are not available with OpenEXR 3.1 */
	int32_t num_threads;  /* chunks decoded/encoded in parallel; 0 = all
	                         cores; output identical for any count */
	/* writing: called with the temporary file's path once it exists and
	 * with NULL once it is gone (renamed over the output or removed), on
	 * the writing thread, so that a program stopped by a signal mid-write
	 * can remove it (the `sss` command does). The first call comes with
	 * the thread's signals blocked since the file was created: no signal
	 * sees it exist unannounced. NULL = not told. */
	void (*temporary_fn)(const char *path, void *user);
	void *temporary_user;
	/* Called on the calling thread with the share of the work done, in
	 * (0, 1]: reading, once the pixels are decoded; writing, after each
	 * round of chunks written. NULL = not told. */
	void (*progress_fn)(double done, void *user);
	void *progress_user;
	/* reading, checked from the header before any pixel is allocated:
	 * the most channels (default 4096; Blender's renders hold tens to a
	 * few hundred) and the most bytes the decoded image may take (width
	 * x height x channels x 4, uint channels 8; default 0: the machine's
	 * physical memory). A struct_size without these fields (ABI 8) reads
	 * as the defaults. */
	int32_t max_channels;
	int64_t max_bytes;
} sss_exr_options;

SSS_API void sss_exr_options_default(sss_exr_options *opt);

/* Reads a scanline or tiled EXR (level 0), half, float or uint channels
 * (converted to float; uint ones also kept in their own type for
 * writing), names split from the end as Blender splits them (layer, then
 * pass and component after the last two dots), any compression OpenEXR 3.1's C API decodes (all
 * but DWAA/DWAB: SSS_ERR_UNSUPPORTED). Every part of a multi-part file is
 * read (Blender 5.0 saves a part per pass); the parts must share one data
 * window, and a channel not named under its part's name is put under it.
 * Writing makes one part of it all, part 0's metadata kept. Errors name
 * the file and what is wrong (missing, truncated, corrupt, too large,
 * deep, parts of different sizes). */
SSS_API sss_result sss_exr_read(const char *path, const sss_exr_options *opt,
                                sss_exr **out, char *errbuf,
                                size_t errbuf_len);
SSS_API void sss_exr_free(sss_exr *exr); /* NULL is fine */

SSS_API int32_t sss_exr_width(const sss_exr *exr);
SSS_API int32_t sss_exr_height(const sss_exr *exr);
SSS_API int32_t sss_exr_pass_count(const sss_exr *exr);
/* Pass i's layer ("" if none), pass name and component letters
 * ("RGB", "Z", ...; comma-joined if any component name is longer than one
 * letter) and a view of its pixels (channels = components). Views stay
 * valid until their pass is replaced or the image is freed. */
SSS_API sss_result sss_exr_pass(const sss_exr *exr, int32_t i,
                                const char **layer, const char **pass,
                                const char **components, sss_image *view);
/* The pass with this layer and name (NULL means ""), or
 * SSS_ERR_MISSING_PASS. */
SSS_API sss_result sss_exr_find(const sss_exr *exr, const char *layer,
                                const char *pass, sss_image *view);

/* Fills the render passes libsss reads from a layer. layer NULL picks the
 * first layer (in file order) that has a DiffDir pass; *layer_used (if
 * given) says which, valid while exr lives. Missing required passes are
 * SSS_ERR_MISSING_PASS with the file's layers named in errbuf. */
SSS_API sss_result sss_exr_render_passes(const sss_exr *exr, const char *layer,
                                         sss_passes *passes,
                                         const char **layer_used,
                                         char *errbuf, size_t errbuf_len);

/* Adds (or replaces) a float pass, copying `data` (width x height x
 * strlen(components) floats, interleaved, packed). The layer may hold
 * dots ("SSS-ViewLayer.001"); the pass may not (names are read back
 * split from the end). */
SSS_API sss_result sss_exr_add_pass(sss_exr *exr, const char *layer,
                                    const char *pass, const char *components,
                                    const float *data, char *errbuf,
                                    size_t errbuf_len);

/* Whether path may be written by sss_exr_write, before any work: it must
 * be a file name (not empty, not ending in '/') that is absent or names a
 * writable regular file. Refused, naming the path and what it is: a
 * directory, FIFO, socket or device (`-o /dev/null` would otherwise
 * replace the device with a file), a symbolic link (it would be replaced
 * by a file, not written through: name its target instead), a file
 * without write permission (read-only outputs are kept) and a folder
 * that takes no new file (a temporary is created there and removed). */
SSS_API sss_result sss_exr_check_output(const char *path, char *errbuf,
                                        size_t errbuf_len);

/* Writes every pass as one single-part scanline file (original channels
 * keep their pixel type, so a round trip is lossless with NONE, RLE, ZIPS,
 * ZIP and PIZ) plus the input's header attributes, to a temporary file
 * beside `path` ("<dir>/.<name>.tmp-<pid>-<id><check>", the check a hash
 * of the name before it; held under an exclusive lock while written)
 * that is renamed over `path` only once complete; a replaced file's
 * permission bits are kept (its hard links are not: the rename gives the
 * name a new file). Temporaries an earlier, stopped writer left for
 * `path` are removed first, only those with a valid check and never the
 * file being read; one whose lock is held (a live writer, on this host or
 * another sharing the folder) is never touched. Refuses an image of more
 * channels than the OpenEXR in use can write (OpenEXRCore 3.1: 32767) and
 * what
 * sss_exr_check_output refuses and the file the image was read from (by
 * name, link or inode). */
SSS_API sss_result sss_exr_write(const sss_exr *exr, const char *path,
                                 const sss_exr_options *opt, char *errbuf,
                                 size_t errbuf_len);

/* ---------------------------------------------------- scene description
 * (sss_scene.c). A JSON file that the add-on writes and a farm can write
 * by hand: camera, unit scale, method and quality, and the per-material
 * table; see docs/scene.md. */

typedef struct sss_scene sss_scene;

/* Parses JSON text. Unknown keys are warnings (one line each, appended to
 * warnbuf); wrong types, bad values and unknown names are errors naming
 * the key path, e.g. "materials[1].radius: expected an array of 3
 * numbers". */
SSS_API sss_result sss_scene_parse(const char *json, size_t json_len,
                                   sss_scene **out, char *warnbuf,
                                   size_t warnbuf_len, char *errbuf,
                                   size_t errbuf_len);
/* The same from a file; errors name the file. */
SSS_API sss_result sss_scene_load(const char *path, sss_scene **out,
                                  char *warnbuf, size_t warnbuf_len,
                                  char *errbuf, size_t errbuf_len);
SSS_API void sss_scene_free(sss_scene *scene); /* NULL is fine */

SSS_API const sss_camera *sss_scene_camera(const sss_scene *scene);
SSS_API const sss_options *sss_scene_options(const sss_scene *scene);
SSS_API const sss_material *sss_scene_materials(const sss_scene *scene,
                                                int32_t *count);
SSS_API const char *sss_scene_material_name(const sss_scene *scene,
                                            int32_t i);

/* ------------------------------------------------------- one EXR frame
 * (sss_process.c): what the `sss` command and the add-on run per frame:
 * read, find the layer's passes, scatter, add the SSS layer (Combined
 * RGBA, DiffLight RGB), write atomically. */

typedef struct sss_process_options {
	uint32_t struct_size;
	const char *layer;     /* view layer, NULL = first with DiffDir */
	int32_t method;        /* sss_method, or -1 = the scene's */
	float radius_scale;    /* >= 0, multiplies the scene's (default 1) */
	int32_t num_threads;   /* 0..256, or -1 = the scene's */
	sss_exr_options exr;   /* size caps and output compression */
	int32_t samples;       /* 1..4096, or -1 = the scene's (disk method) */
	/* Called on the calling thread as the frame goes: the stage ("read",
	 * "scatter", "write", in that order) and the share of that stage
	 * done, 0 when it starts, 1 when it ends (writing: after each round
	 * of chunks). What a progress bar shows. NULL = not told; the exr
	 * options' own progress_fn is not used. */
	void (*progress_fn)(const char *stage, double done, void *user);
	void *progress_user;
	/* Optional, one per scene material (sss_scene_materials' count):
	 * receives the method each material ran this frame (SSS_METHOD_AUTO
	 * resolved to the one it chose), -1 for a material not on screen or
	 * that does not scatter. NULL = not told. */
	int32_t *chosen_methods;
} sss_process_options;

typedef struct sss_timings {
	double read, scatter, write; /* seconds */
} sss_timings;

SSS_API void sss_process_options_default(sss_process_options *opt);

/* Errors name the file (and layer); a Depth pass without one finite
 * positive value is an error (a broken file), as is an output path that
 * is the input file. timings may be NULL. */
SSS_API sss_result sss_process_exr(const char *input, const char *output,
                                   const sss_scene *scene,
                                   const sss_process_options *opt,
                                   sss_timings *timings, char *errbuf,
                                   size_t errbuf_len);

/* ------------------------------------------------ a frame kept in memory
 * (sss_frame.c): one EXR frame's passes read once and kept decoded, then
 * scattered again with any scene description (materials and options)
 * into the caller's buffers, with no file read or written: what re-tuning
 * SSS after the render needs. sss_process_exr is sss_frame_read,
 * sss_frame_scatter and sss_frame_write in a row. A frame may be scattered
 * from several threads at once; reading, writing and freeing it may not
 * overlap anything else on it. */

typedef struct sss_frame sss_frame;

/* Reads the file and finds the render passes of `layer` (NULL: the first
 * with DiffDir) and the back-light layer's, as sss_process_exr does; the
 * same errors, naming the file and layer. */
SSS_API sss_result sss_frame_read(const char *path, const char *layer,
                                  const sss_exr_options *opt,
                                  sss_frame **out, char *errbuf,
                                  size_t errbuf_len);
SSS_API void sss_frame_free(sss_frame *frame); /* NULL is fine */
SSS_API int32_t sss_frame_width(const sss_frame *frame);
SSS_API int32_t sss_frame_height(const sss_frame *frame);
/* The view layer scattered; valid while the frame lives. */
SSS_API const char *sss_frame_layer(const sss_frame *frame);
/* Every pass of the file (sss_exr_pass and sss_exr_find read it). */
SSS_API const sss_exr *sss_frame_exr(const sss_frame *frame);

/* Scatters the frame with the scene's camera, materials and options (the
 * process options' overrides, threads, progress and chosen_methods as in
 * sss_process_exr; their exr and layer fields are not used) into
 * out_combined (RGB or RGBA) and out_diffuse_light (RGB, optional), as
 * sss_apply. seconds (optional) receives the time the scatter took. */
SSS_API sss_result sss_frame_scatter(const sss_frame *frame,
                                     const sss_scene *scene,
                                     const sss_process_options *opt,
                                     const sss_image *out_combined,
                                     const sss_image *out_diffuse_light,
                                     double *seconds, char *errbuf,
                                     size_t errbuf_len);

/* A frame keeps the working memory of its last scatter for the next one,
 * with what in it depends only on the depth, the camera and which pixels
 * scatter (reused while those stay): about 70 MB at 1080p, 150 MB with the
 * crease term. This frees it, for when no re-tune is expected soon; the
 * next scatter makes it again. May not overlap a scatter of the frame. */
SSS_API void sss_frame_trim(sss_frame *frame); /* NULL is fine */

/* Writes the frame's file with the SSS layer (Combined RGBA and DiffLight
 * RGB, width x height x 4 and x 3 floats, packed) added, atomically, as
 * sss_exr_write; the frame keeps only the file's own passes (its
 * memory does not grow with a write). */
SSS_API sss_result sss_frame_write(sss_frame *frame, const char *path,
                                   const float *combined, const float *light,
                                   const sss_exr_options *opt, char *errbuf,
                                   size_t errbuf_len);

#ifdef __cplusplus
}
#endif
#endif /* SSS_H */
