/* sss_internal.h - private types and helpers shared by libsss's files. */
#ifndef SSS_INTERNAL_H
#define SSS_INTERNAL_H

#include "sss.h"

#include <math.h>
#include <stdarg.h>

#define SSS__PI 3.14159265358979323846

/* Profile tables are sampled at x = support * (k / (N-1))^2: dense near
 * the centre, where Burley's 1/r and its marginal's log singularity live. */
#define SSS__TABLE_SIZE 1024

/* The energy calibration's gain table of one material: g at the measured
 * view angles and albedos (sss_calibration.c), made once per material. */
#define SSS__CAL_TABLE (7 * 16)

/* A material turned into what the blur loops read: everything in scene
 * units (after unit_scale and radius_scale), tabulated once per call. */
typedef struct sss__kernel {
	double support;      /* scene units; 0 = no scattering */
	double len;          /* scene units per metre of profile length */
	float mix[3];        /* per-channel share that scatters (strength) */
	float calibration_fade[3]; /* 0..1 per channel: how much of the
	                              energy calibration applies at this
	                              radius (sss__calibration_fade) */
	float calibration_gain[SSS__CAL_TABLE]; /* the material's gain table
	                              (sss__calibration_table) */
	float walk_radius[3]; /* scene units per channel: the radius Cycles'
	                         walk sees (the calibration's shape term) */
	int32_t texturing;   /* sss_texturing */
	int32_t taps;        /* odd, >= 1 */
	/* Per channel, at x_k = support * (k/(N-1))^2: */
	float line_cdf[3][SSS__TABLE_SIZE]; /* integral of M over [0, x] */
	float area[3][SSS__TABLE_SIZE];     /* radial profile R(r) per area */
	float area_cdf[3][SSS__TABLE_SIZE]; /* radial CDF: mass inside r */
} sss__kernel;

/* Pinhole or orthographic projection in pixels (Blender's viewplane). */
typedef struct sss__projection {
	int ortho;
	double fx, fy; /* pixels per scene unit at depth 1 (ortho: at any depth) */
	double cx, cy; /* principal point, pixels from the left / the top edge */
} sss__projection;

/* The working memory of a scatter, kept between scatters of one frame
 * (sss_workspace.c): one block per use below, grown as needed. */
typedef struct sss__workspace sss__workspace;
enum {
	SSS__WS_SLOT,      /* sss_apply: the slot map */
	SSS__WS_SIGNAL,    /* sss_apply: the light to scatter */
	SSS__WS_SCRATCH,   /* sss_apply: scratch when no output is packed */
	SSS__WS_CREASE,    /* sss_apply: what sharp edges carried */
	SSS__WS_DEPTH_H,   /* separable: depth, packed */
	SSS__WS_DEPTH_V,   /* separable: depth, transposed */
	SSS__WS_SLOTS,     /* separable: the slots both ways */
	SSS__WS_EDGE_POS,  /* crease: positions */
	SSS__WS_EDGE_NRM,  /* crease: normals */
	SSS__WS_EDGE_SIDE, /* crease: which side of an edge */
	SSS__WS_EDGE_NEAR, /* crease: near an edge */
	SSS__WS_EDGE_KEY,  /* crease: what its geometry was made for */
	SSS__WS_EDGE_SLOT, /* crease: and the slot map */
	SSS__WS_VIEW,      /* sss_apply: the view cosine of each pixel */
	SSS__WS_VIEW_SLOT, /* sss_apply: the slot map it was made with */
	SSS__WS_VIEW_KEY,  /* sss_apply: and the camera */
	SSS__WS_PLANE_SLOT, /* separable: the slot map its planes hold */
	SSS__WS_BREAKS,    /* sss_apply: where creases part the faces */
	SSS__WS_BLOCKS
};
sss__workspace *sss__workspace_new(void);
void sss__workspace_free(sss__workspace *ws); /* NULL is fine */
/* Block `block` of at least `bytes` bytes (zeroed if asked), valid until
 * the next get of that block; ws NULL: malloc (calloc), freed by
 * sss__ws_put. */
void *sss__ws_get(sss__workspace *ws, int block, size_t bytes, int zeroed);
void sss__ws_put(sss__workspace *ws, void *p); /* frees only without ws */
/* Block `block` as the last scatter left it, if it holds at least
 * `bytes` bytes; else (or without ws) NULL. */
void *sss__ws_kept(sss__workspace *ws, int block, size_t bytes);
/* What a kept plane was made from: block `block` holds a copy of the slot
 * map (sss__ws_note_slots), compared by sss__ws_same_slots (0 without
 * ws or copy); sss__ws_forget drops it (the plane is being remade). */
int sss__ws_same_slots(sss__workspace *ws, int block, const int16_t *slot,
                       size_t npix);
sss_result sss__ws_note_slots(sss__workspace *ws, int block,
                              const int16_t *slot, size_t npix);
void sss__ws_forget(sss__workspace *ws, int block);

/* Everything one blur needs, read-only while the threads run. */
typedef struct sss__job {
	int32_t width, height;
	const sss__kernel *kernels;
	const int16_t *slot;    /* per pixel: kernel index, or -1 = not scattering */
	const float *depth;     /* view of the Depth pass */
	int64_t depth_stride;
	int32_t depth_channels;
	const float *position;  /* optional Position pass */
	int64_t position_stride;
	int32_t position_channels;
	sss__projection proj;
	int32_t max_support_px;
	/* The light to scatter, RGB: component c of pixel i at
	 * signal[i * signal_px + c * signal_ch], packed (3, 1) or, for the
	 * separable method, planar (1, width * height). */
	float *signal;
	int64_t signal_px, signal_ch;
	/* 3 x width x height floats of working memory: the caller's output
	 * when it is packed (nothing in it is read before the recombination
	 * overwrites it), else allocated. */
	float *scratch;
	sss__workspace *ws; /* kept working memory, or NULL */
	/* Per pixel, where a crease (sss_crease.c) lies between it and its
	 * neighbour: SSS__BREAK_RIGHT, SSS__BREAK_DOWN; NULL: nowhere. The
	 * separable method carries no light across one (the crease term does). */
	const uint8_t *breaks;
} sss__job;

#define SSS__BREAK_RIGHT 1u
#define SSS__BREAK_DOWN 2u

/* "a directory", "a FIFO (named pipe)", ...: what a stat mode names, for
 * messages that refuse a file (sss_status.c). */
const char *sss__file_kind(unsigned mode);

/* d'Eon & Luebke 2007 six-Gaussian skin (sss_material.c): variances in
 * mm^2 and RGB weights, each channel summing to 1. */
extern const float sss__deon_variance[6];
extern const float sss__deon_weight[6][3];

/* Whether a frame's file could be written back with the result layer
 * (sss_frame.c): no input layer of its name, channels within OpenEXR's
 * ceiling. */
sss_result sss__frame_check_result(const sss_frame *frame, char *err,
                                   size_t errlen);
/* The process options' own checks (struct size, radius scale), before
 * any work (sss_frame.c). */
sss_result sss__process_options_check(const sss_process_options *opt,
                                      char *err, size_t errlen);
/* Removes every pass of a layer from an EXR image (sss_exr.c, the model). */
void sss__exr_remove_layer(sss_exr *exr, const char *layer);

/* errbuf helper: formats into errbuf when given, returns code. */
sss_result sss__fail(char *errbuf, size_t errbuf_len, sss_result code,
                     const char *fmt, ...)
	__attribute__((format(printf, 4, 5)));

/* In a function with errbuf and errbuf_len, the one way to fail: FAIL
 * with SSS_ERR_INVALID_ARGUMENT, FAILX with another status. */
#define FAIL(...) sss__fail(errbuf, errbuf_len, SSS_ERR_INVALID_ARGUMENT, \
                            __VA_ARGS__)
#define FAILX(code, ...) sss__fail(errbuf, errbuf_len, code, __VA_ARGS__)

/* A value against a schema row's range (sss_option_fields.h,
 * sss_camera_fields.h): at least lo (more than lo when lo_open) and at
 * most hi, where hi from 1e30 up means no upper bound but a finite value
 * and INFINITY none at all; NaN is never in range. */
int sss__in_range(double v, double lo, double hi, int lo_open);
/* The range as a message says it: "0..256", ">= 1" (integer), "> 0",
 * "finite and >= 0", "finite", "in [0, 1]"; into buf, returned. */
const char *sss__range_text(double lo, double hi, int lo_open, int integer,
                            char *buf, size_t len);
/* The options' check (sss_options.c, from sss_option_fields.h), as
 * sss_apply runs it; the first bad member named with its range. */
sss_result sss__options_check(const sss_options *o, char *errbuf,
                              size_t errbuf_len);
/* Whether v is in the range of option `key` (its scene description
 * key), said into range ("finite and >= 0"): for what overrides an
 * option (sss_process_options). */
int sss__option_in_range(const char *key, double v, char *range,
                         size_t range_len);

/* Profiles (sss_profile.c). A support beyond max_support (scene units;
 * 0 = no limit) is shrunk to it, profile lengths with it: see
 * sss__reach_limit. */
sss_result sss__kernel_build(const sss_material *mat, const sss_options *opt,
                             double unit_scale, double max_support,
                             sss__kernel *k);
float sss__table_lookup(const float *table, double x, double inv_support);
/* Mass of the 1-D profile over [a, b] (b >= a; either may be negative),
 * per channel. */
void sss__line_mass3(const sss__kernel *k, double a, double b,
                     double out[3]);

/* Mass of Burley's 1-D marginal (shape d) over [a, b], 0 <= a < b. */
double sss__burley_line_mass(double a, double b, double d);

/* Calibration against Cycles' random walk (sss_calibration.c): Burley d
 * over the radius for an albedo (SSS_BURLEY_CYCLES_RANDOM_WALK, and
 * SSS_BURLEY_CYCLES4_RANDOM_WALK), and the per-pixel energy gain
 * 1 + strength (g(DiffCol) - 1) on the scattered light. */
/* Cycles' random-walk mean free path over the radius, sqrt(3 (1 - a'))
 * with a' inverting Jensen's dipole at IOR 1.4 (bssrdf_setup_radius). */
double sss__cycles_rw_mfp_over_radius(double albedo);
double sss__cycles_rw_d_over_radius(double albedo);
double sss__cycles4_rw_d_over_radius(double albedo);
/* How much of the energy calibration applies to a channel whose radius
 * (Burley: Subsurface Radius x Scale; other profiles: their support / 16)
 * is `radius` scene units: 1 from 1e-3 up, 0 at and below 1e-5 (where
 * Cycles' walk loses light to float precision, and below 1e-8 renders its
 * diffuse BSDF), log-linear between, so the output tends continuously to
 * the uncalibrated blur, itself the identity there. */
float sss__calibration_fade(double radius);
/* Whether the material's gain is applied at all, and so depends on the
 * view (then sss__view_cosine is worth computing). */
int sss__calibration_needs_view(const sss_material *mat,
                                const float fade[3]);
/* Whether the material's calibration also follows the surface's shape
 * (then sss__mean_curvature is worth computing). */
int sss__calibration_needs_shape(const sss_material *mat,
                                 const float fade[3]);
/* The walk's energy on a convex object over a flat one's, for albedo a
 * and x = mean curvature x radius (the calibration's shape table; 1 for
 * x <= 0 and for calibrations without one). */
float sss__shape_gain(int32_t calibration, float albedo, float x);
/* The crease term (sss_calibration.c, sss_crease.c): what the walk
 * carries over a sharp convex edge onto the other face, at distance t
 * from the edge, over the scattered light entering near it, is
 * kappa F(t), F the tail beyond t of Burley's 1-D marginal with
 * d = gamma x the walk's radius; kappa 0 for calibrations without it. */
void sss__crease_params(int32_t calibration, float albedo, float *kappa,
                        float *gamma);
/* What the lit face loses near a crease where the blur is stopped there
 * (kappa 0: the calibration's blur is not stopped; the gain above was
 * fitted over the blur's own share). */
void sss__crease_loss_params(int32_t calibration, float albedo, float *kappa,
                             float *gamma);
/* Adds nothing where no pixel of an enabled kernel (per kernel: enabled,
 * and its material's calibration) has a crease: fills extra (3 floats a
 * pixel, packed, the signal's units) with the light that crosses one,
 * from job->signal before the blur. */
sss_result sss__crease(const sss__job *job, int32_t kernel_count,
                       const sss_image *diff_col, const uint8_t *enabled,
                       const int32_t *calibration, int32_t num_threads,
                       float *extra, uint8_t *breaks, int term);
/* What the walk returns over the whole visible side of an object whose
 * median x (mean curvature x radius) is x, over the flat slab's; *weight
 * (0 up to x = 10, 1 from 30) is how much of it stands in place of the
 * per-pixel shape term. */
float sss__far_gain(int32_t calibration, float albedo, float x,
                    float *weight);
/* shape_x: per channel, the surface's mean curvature x the radius the
 * walk sees (NULL: flat, or not followed); far_x: per channel, the
 * material's median of the same over its pixels (NULL: not read). */
void sss__calibration_table(const sss_material *mat,
                            float table[SSS__CAL_TABLE]);
void sss__calibration_apply(const sss_material *mat, const float *table,
                            const float fade[3],
                            float view_cosine, const float *shape_x,
                            const float *far_x, const float *diff_col,
                            float *light);
/* The factors sss__calibration_apply multiplies light by (1 where the
 * material is not calibrated). */
void sss__calibration_factors(const sss_material *mat, const float *table,
                              const float fade[3], float view_cosine,
                              const float *shape_x, const float *far_x,
                              const float *diff_col, float factor[3]);

/* The mean curvature (1 / scene units, positive where convex) of the
 * visible surface at pixel (x, y), averaged over about rho scene units
 * around it, from the Depth pass and the pixels of its slot
 * (sss_curvature.c); 0 where it cannot be told. */
double sss__mean_curvature(const sss_image *depth, const int16_t *slot,
                           const sss__projection *p, int32_t w, int32_t h,
                           int32_t x, int32_t y, double rho);

/* One bounce of the transmitted light between facing visible parts of a
 * material (sss_glow.c), on a grid of sss__glow_points(w, h) points:
 * glow (3 a point) is the light the point's pixel sends out through
 * transmission (DiffCol applied; sss__glow_point_of says which pixel is
 * which point, -1 for the others), receives[slot] which slots take
 * part. sss__glow_row gives, for each pixel of row y, the light to
 * add to its diffuse light (times DiffCol in the image); glow may be
 * reused once made. */
typedef struct sss__glow sss__glow;
int64_t sss__glow_points(int32_t w, int32_t h);
int64_t sss__glow_point_of(int32_t w, int32_t h, int32_t x, int32_t y);
int sss__glow_on_row(int32_t w, int32_t h, int32_t y); /* any point there */
sss_result sss__glow_make(const float *glow, const sss_image *depth,
                          const int16_t *slot, const uint8_t *receives,
                          const sss__projection *proj, int32_t w, int32_t h,
                          int32_t num_threads, sss__glow **out);
void sss__glow_row(const sss__glow *g, int32_t y, const int16_t *slot_row,
                   float *out /* width x 3, 0 where nothing comes */);
void sss__glow_free(sss__glow *g); /* NULL is fine */

/* Camera (sss_camera.c). */
sss_result sss__projection_make(const sss_camera *cam, int32_t width,
                                int32_t height, sss__projection *p,
                                char *errbuf, size_t errbuf_len);
void sss__pixel_position(const sss__job *job, int32_t x, int32_t y,
                         double out[3]);
/* The view-space point of pixel (x, y) at depth z (the Depth pass's
 * planar view Z). */
void sss__view_point(const sss__projection *p, int32_t x, int32_t y,
                     double z, double out[3]);
/* |cos| of the angle between the surface at pixel (x, y) and the ray to
 * the camera, from the Depth pass (the surface's slope towards the
 * neighbours of the same slot, on each axis the side of nearer depth);
 * 1 where no neighbour of its slot tells the slope. */
float sss__view_cosine(const sss_image *depth, const int16_t *slot,
                       const sss__projection *p, int32_t w, int32_t h,
                       int32_t x, int32_t y);
int sss__same_projection(const sss__projection *a, const sss__projection *b);
double sss__pixels_per_unit_x(const sss__projection *p, double z);
double sss__pixels_per_unit_y(const sss__projection *p, double z);
/* The largest kernel support (scene units) worth tabulating for pixels at
 * depths [zmin, zmax]: SSS__REACH_FACTOR times the farthest distance a
 * blur can reach between two of them; 0 = no limit (a degenerate depth). */
double sss__reach_limit(const sss__projection *p, int32_t max_support_px,
                        int32_t width, int32_t height, double zmin,
                        double zmax);
/* Past it a profile's e^{-r/d} (Burley: support 16 d) varies by under
 * 2 % across everything the blur can see, so the shrunk kernel is the
 * huge one to that accuracy; the tables then resolve what the blur reads
 * (their first node would otherwise lie beyond the image, and the
 * per-area density 1/d^2 underflow a float). */
#define SSS__REACH_FACTOR 1000.0

/* Taps right of the centre (sss_separable.c); arrays hold
 * SSS__MAX_HALF_TAPS entries. */
#define SSS__MAX_HALF_TAPS 2048
typedef struct sss__tap {
	double offset;  /* pixels from the centre */
	double lo, hi;  /* the tap's cell along the axis, pixels */
} sss__tap;
int32_t sss__tap_layout(int32_t taps, double r, sss__tap *tap);

/* Methods (sss_separable.c, sss_reference.c): scatter job->signal in place
 * for every pixel whose slot >= 0. */
sss_result sss__separable(const sss__job *job, int32_t num_threads);
sss_result sss__reference(const sss__job *job, int32_t num_threads);

/* The per-lobe separable method (sss_lobes.c): materials[m] is the
 * material kernels[m] was built from; fits Burley with Gaussians. */
sss_result sss__separable_exact(const sss__job *job,
                                const sss_material *materials,
                                int32_t material_count,
                                const sss_options *opt);
/* Burley (d = 1) truncated at `truncate` as SSS__BURLEY_LOBES Gaussian
 * lobes: their standard deviations and weights (summing to 1), fitted to
 * the truncated radial CDF (sss_lobes.c). Returns the lobe count. */
#define SSS__BURLEY_LOBES 6
int sss__burley_lobes(double truncate, double sigma[], double weight[]);
/* SSS_METHOD_AUTO's choice per kernel (sss_auto.c): method[m] is
 * SSS_METHOD_DISK where the median over kernel m's pixels of its widest
 * walk radius x the surface's mean curvature reaches AUTO_DISK_X, else
 * SSS_METHOD_SEPARABLE; median_x (optional) receives that median. Reads
 * the slot map, so runs once it is filled. */
#define AUTO_DISK_X 1.0f
sss_result sss__auto_methods(const sss_image *depth, const int16_t *slot,
                             const sss__projection *proj, int32_t w,
                             int32_t h, const sss__kernel *kernels,
                             int32_t count, int32_t *method,
                             float *median_x);
/* What a frame's passes give every scatter alike (sss_frame_pre.c),
 * made once for a kept frame; sss_apply without one computes the same
 * per call through the same functions. */
typedef struct sss__frame_pre {
	float *rest;   /* 3 floats a pixel, packed: sss__rest_light */
	float *zrange; /* 2 per material pass index 0..65535: the least and
	                  greatest finite depth of its pixels (+inf, -inf
	                  where it has none): sss__index_zrange_scan */
} sss__frame_pre;
/* The light of the passes that do not scatter at pixel (x, y): glossy and
 * transmission (direct + indirect) x their colours, emission and
 * environment, summed in that order. */
void sss__rest_light(const sss_passes *p, int32_t x, int32_t y, float out[3]);
/* zrange (2 x 65536 floats) as in sss__frame_pre. */
void sss__index_zrange_scan(const sss_passes *p, float *zrange);
sss_result sss__frame_pre_make(const sss_passes *p, int32_t num_threads,
                               sss__frame_pre *pre);
void sss__frame_pre_free(sss__frame_pre *pre); /* zeroes it; twice is fine */

/* sss_apply, also telling the method each material ran (sss_apply.c):
 * chosen, one per material, -1 for one not on screen or that does not
 * scatter; may be NULL. pre: the frame's (NULL: computed here); ws: the
 * frame's kept working memory (NULL: allocated and freed here). */
sss_result sss__apply_report(const sss_passes *p, const sss_camera *cam,
                             const sss_material *materials,
                             int32_t material_count,
                             const sss_options *opt,
                             const sss_image *out_combined,
                             const sss_image *out_diffuse_light,
                             const sss__frame_pre *pre, sss__workspace *ws,
                             int32_t *chosen, char *errbuf,
                             size_t errbuf_len);
/* The stochastic disk method (sss_disk.c), at most `samples` per pixel;
 * per_source (per kernel, NULL = none): light conserved where it enters
 * rather than where it leaves (what the auto method runs; sss_disk.c). */
sss_result sss__disk(const sss__job *job, int32_t samples,
                     int32_t num_threads, const uint8_t *per_source);

/* Channel c of a material as a sum of 2-D Gaussians in scene units, len
 * scene units per metre of profile length (a kernel's len): fills
 * variances and weights (summing to 1) and returns their count; returns 0
 * for Burley with *burley_d set to d in scene units (0 for a channel that
 * does not scatter). (sss_profile.c) */
int sss__profile_gaussians(const sss_material *mat, const sss_options *opt,
                           double len, int c,
                           double var[SSS_MAX_GAUSSIANS],
                           double w[SSS_MAX_GAUSSIANS], double *burley_d);

/* out = out + mix (blurred - out) per channel; mix 0 leaves out untouched
 * bit for bit and mix 1 gives blurred exactly. */
static inline void sss__blend_pixel(const sss__kernel *k, const float *blurred,
                                    float *out)
{
	for (int c = 0; c < 3; c++) {
		float m = k->mix[c];
		if (m >= 1.0f)
			out[c] = blurred[c];
		else if (m > 0.0f)
			out[c] = out[c] + m * (blurred[c] - out[c]);
	}
}

/* Row-band threading (sss_threads.c): fn(ctx, y0, y1) over [0, height). */
typedef void (*sss__rows_fn)(void *ctx, int32_t y0, int32_t y1);
/* The CPUs this process may run on (its affinity mask, as taskset and
 * a farm's CPU pinning set it), else the online ones; "all cores". */
int32_t sss__cpu_count(void);
void sss__parallel_rows(int32_t height, int32_t num_threads, sss__rows_fn fn,
                        void *ctx);

/* Image views (sss_image): floats per row, the pixel at (x, y), and the
 * byte range a view touches (for the no-aliasing checks). */
static inline int64_t sss__stride(const sss_image *im)
{
	return im->row_stride ? im->row_stride
	                      : (int64_t)im->width * im->channels;
}

static inline const float *sss__at(const sss_image *im, int32_t x, int32_t y)
{
	return im->data + y * sss__stride(im) + (int64_t)x * im->channels;
}

static inline void sss__span(const sss_image *im, const char **lo,
                             const char **hi)
{
	*lo = (const char *)im->data;
	*hi = (const char *)(im->data + (im->height - 1) * sss__stride(im) +
	                     (int64_t)im->width * im->channels);
}

/* sss_exr.c, for sss_render_passes.c: the path an image was read from, and
 * whether its header has an attribute whose name starts with prefix. */
const char *sss__exr_path(const sss_exr *exr);
int sss__exr_has_attribute_prefix(const sss_exr *exr, const char *prefix);
/* Channels in the image, and the most one file can hold with the
 * OpenEXR in use (its coding pipelines count them in 16 bits). */
int64_t sss__exr_channel_count(const sss_exr *exr);
int32_t sss__exr_max_channels(void);

/* sss_zip.c: one chunk in OpenEXR's ZIP format through libdeflate.
 * Deflating writes at most out_cap bytes (libdeflate_zlib_compress_bound
 * of n) and returns how many: n when the chunk is stored raw (a copy of
 * raw), as OpenEXR stores what does not compress. Inflating fills out
 * with exactly n bytes, or returns 0 (a corrupt chunk). scratch holds n
 * bytes. */
struct libdeflate_compressor;
struct libdeflate_decompressor;
size_t sss__zip_deflate(struct libdeflate_compressor *deflate,
                        const uint8_t *raw, size_t n, uint8_t *scratch,
                        uint8_t *out, size_t out_cap);
int sss__zip_inflate(struct libdeflate_decompressor *inflate,
                     const uint8_t *in, size_t in_n, uint8_t *scratch,
                     uint8_t *out, size_t n);

/* One render pass libsss reads (sss_pass_table.h), where it goes in
 * sss_passes. */
typedef struct sss__pass_row {
	const char *name;
	size_t offset; /* of its sss_image in sss_passes */
	const char *components, *alt;
	int32_t need;  /* sss_pass_need */
	const char *blender, *hint;
} sss__pass_row;
extern const sss__pass_row sss__render_passes[];
extern const int32_t sss__render_pass_count;

/* Checks one pass view against the frame size w x h (sss_apply.c);
 * absent passes (data == NULL) are fine unless required. Errors name the
 * pass. */
sss_result sss__check_image(const char *name, const sss_image *im,
                            int32_t min_channels, int required, int32_t w,
                            int32_t h, char *errbuf, size_t errbuf_len);

static inline int sss__isfinite3(const float *v)
{
	return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

#endif /* SSS_INTERNAL_H */
