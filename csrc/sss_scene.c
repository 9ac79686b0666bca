/* sss_scene.c - the JSON scene description (docs/scene.md): camera, unit
 * scale, options and the material table, checked so that a loaded scene is
 * always accepted by sss_apply. */
#include "sss_internal.h"

#include <cJSON.h>

#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* A scene file larger than this is certainly not a scene description. */
#define SCENE_MAX_BYTES ((size_t)16 << 20)
/* sss_apply's limit on the material table. */
#define SCENE_MAX_MATERIALS 32767
#define PATH_LEN 96

struct sss_scene {
	sss_camera camera;
	sss_options options;
	int32_t material_count;
	sss_material *materials; /* material_count rows (at least one slot) */
	char **names;            /* material_count strings, owned */
};

/* Where messages go while one text is parsed. */
typedef struct ctx {
	char *err;
	size_t err_len;
	char *warn;
	size_t warn_len;
	size_t warn_used; /* strlen(warn) */
	int warn_full;    /* truncated: later warnings are dropped */
} ctx;

#define FAIL(c, ...) sss__fail((c)->err, (c)->err_len, \
                               SSS_ERR_INVALID_ARGUMENT, __VA_ARGS__)

/* Appends one line to warnbuf; when it no longer fits, what fits is kept
 * and the buffer ends in "..." so that the cut is visible. */
static void warn(ctx *c, const char *fmt, ...)
	__attribute__((format(printf, 2, 3)));
static void warn(ctx *c, const char *fmt, ...)
{
	if (!c->warn || c->warn_len == 0 || c->warn_full)
		return;
	char line[256];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(line, sizeof line, fmt, ap);
	va_end(ap);
	size_t room = c->warn_len - 1 - c->warn_used;
	size_t len = strlen(line);
	size_t need = (c->warn_used ? 1 : 0) + len;
	char *p = c->warn + c->warn_used;
	if (need <= room) {
		if (c->warn_used)
			*p++ = '\n';
		memcpy(p, line, len + 1);
		c->warn_used += need;
		return;
	}
	c->warn_full = 1;
	if (c->warn_used && room > 0) {
		*p++ = '\n';
		room--;
	}
	memcpy(p, line, room);
	p[room] = '\0';
	if (c->warn_len >= 4)
		memcpy(c->warn + c->warn_len - 4, "...", 3);
}

/* A user-supplied string made safe for a one-line message: at most 40
 * bytes, control characters as '?'. */
static const char *printable(const char *s, char *buf, size_t n)
{
	size_t i = 0;
	for (; s[i] && i < 40 && i + 4 < n; i++)
		buf[i] = (unsigned char)s[i] < 0x20 || s[i] == 0x7f ? '?' : s[i];
	if (s[i] && i + 4 <= n) {
		memcpy(buf + i, "...", 3);
		i += 3;
	}
	buf[i] = '\0';
	return buf;
}

/* "an array of 2", "a string", ... for "expected X, got Y" messages. */
static const char *describe(const cJSON *it, char *buf, size_t n)
{
	if (cJSON_IsNull(it))
		return "null";
	if (cJSON_IsTrue(it))
		return "true";
	if (cJSON_IsFalse(it))
		return "false";
	if (cJSON_IsNumber(it))
		return "a number";
	if (cJSON_IsString(it))
		return "a string";
	if (cJSON_IsObject(it))
		return "an object";
	if (cJSON_IsArray(it)) {
		snprintf(buf, n, "an array of %d", cJSON_GetArraySize(it));
		return buf;
	}
	return "an invalid value";
}

static sss_result type_error(ctx *c, const char *path, const char *expected,
                             const cJSON *it)
{
	char buf[32];
	return FAIL(c, "%s: expected %s, got %s", path, expected,
	            describe(it, buf, sizeof buf));
}

/* dst = a b c, cut to PATH_LEN - 1 bytes (known key paths are short). */
static void cat3(char *dst, const char *a, const char *b, const char *c)
{
	const char *parts[3] = {a, b, c};
	size_t n = 0;
	for (int i = 0; i < 3; i++)
		for (const char *s = parts[i]; *s && n + 1 < PATH_LEN; s++)
			dst[n++] = *s;
	dst[n] = '\0';
}

/* "camera" + "lens" -> "camera.lens"; "" + "taps" -> "taps". */
static void join(char *dst, const char *path, const char *key)
{
	cat3(dst, path, *path ? "." : "", key);
}

/* "materials" + 2 -> "materials[2]". */
static void join_index(char *dst, const char *path, int i)
{
	char idx[16];
	snprintf(idx, sizeof idx, "[%d]", i);
	cat3(dst, path, idx, "");
}

/* Finds an object's known members: found[k] is the member named keys[k]
 * or NULL. Unknown members are warnings; a known key given twice is an
 * error, since which one was meant is unclear. */
static sss_result scan(ctx *c, const cJSON *obj, const char *path,
                       const char *const *keys, int nkeys,
                       const cJSON **found)
{
	for (int k = 0; k < nkeys; k++)
		found[k] = NULL;
	const cJSON *it;
	cJSON_ArrayForEach(it, obj) {
		int k = 0;
		while (k < nkeys && strcmp(it->string, keys[k]) != 0)
			k++;
		if (k == nkeys) {
			char buf[48];
			warn(c, "warning: unknown key '%s%s%s' (ignored)", path,
			     *path ? "." : "", printable(it->string, buf, sizeof buf));
		} else if (found[k]) {
			char p[PATH_LEN];
			join(p, path, keys[k]);
			return FAIL(c, "%s: key given twice", p);
		} else {
			found[k] = it;
		}
	}
	return SSS_OK;
}

/* ------------------------------------------------------------ values */

/* Allowed numbers: [lo, hi], lo excluded when lo_open. */
typedef struct span {
	double lo, hi;
	int lo_open;
} span;

static const span ANY = {-DBL_MAX, DBL_MAX, 0};
static const span POSITIVE = {0.0, DBL_MAX, 1};
/* Float fields share sss_material_validate's upper bound. */
static const span POSITIVE_F = {0.0, 1e30, 1};
static const span NONNEG_F = {0.0, 1e30, 0};
static const span UNIT = {0.0, 1.0, 0};

static sss_result get_f64(ctx *c, const cJSON *it, const char *path,
                          span s, double *out)
{
	if (!cJSON_IsNumber(it))
		return type_error(c, path, "a number", it);
	double v = it->valuedouble;
	if (!isfinite(v)) /* JSON has no NaN; 1e999 overflows to Inf */
		return FAIL(c, "%s: number out of range (overflows a double)", path);
	if (v < s.lo || (s.lo_open && v <= s.lo) || v > s.hi) {
		/* 1e30 and up is "no upper bound" unless it is what was hit. */
		if (s.hi < 1e30)
			return FAIL(c, "%s: %g is out of range (must be in %c%g, %g])",
			            path, v, s.lo_open ? '(' : '[', s.lo, s.hi);
		if (v > s.hi)
			return FAIL(c, "%s: %g is out of range (must be <= %g)", path,
			            v, s.hi);
		return FAIL(c, "%s: %g is out of range (must be %s %g)", path, v,
		            s.lo_open ? ">" : ">=", s.lo);
	}
	*out = v;
	return SSS_OK;
}

static sss_result get_f32(ctx *c, const cJSON *it, const char *path,
                          span s, float *out)
{
	double v = 0.0;
	sss_result r = get_f64(c, it, path, s, &v);
	if (r)
		return r;
	if (fabs(v) > FLT_MAX)
		return FAIL(c, "%s: %g is too large for a 32-bit float", path, v);
	float f = (float)v;
	if (s.lo_open && !(f > s.lo))
		return FAIL(c, "%s: %g is too small (it rounds to %g as a 32-bit "
		            "float)", path, v, (double)f);
	*out = f;
	return SSS_OK;
}

static sss_result get_int(ctx *c, const cJSON *it, const char *path,
                          int32_t lo, int32_t hi, int32_t *out)
{
	if (!cJSON_IsNumber(it))
		return type_error(c, path, "an integer", it);
	double v = it->valuedouble;
	if (!isfinite(v) || v != floor(v))
		return FAIL(c, "%s: expected an integer, got %g", path, v);
	if (v < lo || v > hi) {
		if (hi == INT32_MAX)
			return FAIL(c, "%s: %g is out of range (must be >= %d)", path,
			            v, lo);
		return FAIL(c, "%s: %g is out of range (must be %d..%d)", path, v,
		            lo, hi);
	}
	*out = (int32_t)v;
	return SSS_OK;
}

static sss_result get_vec3(ctx *c, const cJSON *it, const char *path,
                           span s, float out[3])
{
	if (!cJSON_IsArray(it) || cJSON_GetArraySize(it) != 3)
		return type_error(c, path, "an array of 3 numbers", it);
	float v[3];
	for (int i = 0; i < 3; i++) {
		char p[PATH_LEN];
		join_index(p, path, i);
		sss_result r = get_f32(c, cJSON_GetArrayItem(it, i), p, s, &v[i]);
		if (r)
			return r;
	}
	memcpy(out, v, sizeof v);
	return SSS_OK;
}

typedef struct name_value {
	const char *name;
	int32_t value;
} name_value;

static sss_result get_enum(ctx *c, const cJSON *it, const char *path,
                           const char *what, const name_value *tab, int n,
                           int32_t *out)
{
	if (!cJSON_IsString(it))
		return type_error(c, path, "a string", it);
	for (int i = 0; i < n; i++) {
		if (strcmp(it->valuestring, tab[i].name) == 0) {
			*out = tab[i].value;
			return SSS_OK;
		}
	}
	char list[160] = "", buf[48];
	for (int i = 0; i < n; i++) {
		size_t used = strlen(list);
		snprintf(list + used, sizeof list - used, "%s%s", i ? ", " : "",
		         tab[i].name);
	}
	return FAIL(c, "%s: unknown %s '%s' (expected %s)", path, what,
	            printable(it->valuestring, buf, sizeof buf), list);
}

#define COUNT(a) ((int)(sizeof(a) / sizeof *(a)))

static const name_value camera_types[] = {
	{"PERSP", SSS_CAMERA_PERSPECTIVE}, {"ORTHO", SSS_CAMERA_ORTHOGRAPHIC},
};
static const name_value sensor_fits[] = {
	{"AUTO", SSS_SENSOR_FIT_AUTO}, {"HORIZONTAL", SSS_SENSOR_FIT_HORIZONTAL},
	{"VERTICAL", SSS_SENSOR_FIT_VERTICAL},
};
static const name_value methods[] = {
	{"separable", SSS_METHOD_SEPARABLE}, {"reference", SSS_METHOD_REFERENCE},
	{"separable-exact", SSS_METHOD_SEPARABLE_EXACT},
	{"disk", SSS_METHOD_DISK},
};
static const name_value profiles[] = {
	{"burley", SSS_PROFILE_BURLEY}, {"gaussians", SSS_PROFILE_GAUSSIANS},
	{"jimenez", SSS_PROFILE_JIMENEZ}, {"near-far", SSS_PROFILE_NEAR_FAR},
	{"none", SSS_PROFILE_NONE},
};
static const name_value mappings[] = {
	{"cycles", SSS_BURLEY_CYCLES}, {"eevee", SSS_BURLEY_EEVEE},
	{"random-walk", SSS_BURLEY_RANDOM_WALK},
	{"cycles-random-walk", SSS_BURLEY_CYCLES_RANDOM_WALK},
	{"cycles4-random-walk", SSS_BURLEY_CYCLES4_RANDOM_WALK},
};
static const name_value calibrations[] = {
	{"none", SSS_CALIBRATION_NONE},
	{"cycles-random-walk", SSS_CALIBRATION_CYCLES_RANDOM_WALK},
	{"cycles4-random-walk-skin", SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN},
	{"cycles4-random-walk", SSS_CALIBRATION_CYCLES4_RANDOM_WALK},
};
static const name_value transmissions[] = {
	{"off", SSS_TRANSMISSION_OFF}, {"burley", SSS_TRANSMISSION_BURLEY},
	{"jimenez", SSS_TRANSMISSION_JIMENEZ},
	{"beer-lambert", SSS_TRANSMISSION_BEER_LAMBERT},
	{"fast", SSS_TRANSMISSION_FAST},
};
static const name_value texturings[] = {
	{"post", SSS_TEXTURING_POST},
	{"pre-and-post", SSS_TEXTURING_PRE_AND_POST},
};

static const char *profile_name(int32_t kind)
{
	for (int i = 0; i < COUNT(profiles); i++)
		if (profiles[i].value == kind)
			return profiles[i].name;
	return "?";
}

/* ------------------------------------------------------------ camera */

enum {
	C_TYPE, C_LENS, C_SENSOR_WIDTH, C_SENSOR_HEIGHT, C_SENSOR_FIT,
	C_SHIFT_X, C_SHIFT_Y, C_ORTHO_SCALE, C_CLIP_START, C_CLIP_END,
	C_PIXEL_ASPECT_X, C_PIXEL_ASPECT_Y, C_COUNT
};
static const char *const camera_keys[C_COUNT] = {
	"type", "lens", "sensor_width", "sensor_height", "sensor_fit",
	"shift_x", "shift_y", "ortho_scale", "clip_start", "clip_end",
	"pixel_aspect_x", "pixel_aspect_y",
};

static sss_result parse_camera(ctx *c, const cJSON *obj, sss_camera *cam)
{
	if (!cJSON_IsObject(obj))
		return type_error(c, "camera", "an object", obj);
	const cJSON *f[C_COUNT];
	sss_result r = scan(c, obj, "camera", camera_keys, C_COUNT, f);
	if (r)
		return r;
	/* Every given length is checked even when the camera type does not
	 * use it: a bad value is a bug in whatever wrote the file. */
	struct {
		int key;
		double *field;
		span s;
	} nums[] = {
		{C_LENS, &cam->lens_mm, POSITIVE},
		{C_SENSOR_WIDTH, &cam->sensor_width_mm, POSITIVE},
		{C_SENSOR_HEIGHT, &cam->sensor_height_mm, POSITIVE},
		{C_SHIFT_X, &cam->shift_x, ANY},
		{C_SHIFT_Y, &cam->shift_y, ANY},
		{C_ORTHO_SCALE, &cam->ortho_scale, POSITIVE},
		{C_PIXEL_ASPECT_X, &cam->pixel_aspect_x, POSITIVE},
		{C_PIXEL_ASPECT_Y, &cam->pixel_aspect_y, POSITIVE},
	};
	char p[PATH_LEN];
	if (f[C_TYPE] && (r = get_enum(c, f[C_TYPE], "camera.type",
	                               "camera type", camera_types,
	                               COUNT(camera_types), &cam->type)))
		return r;
	for (int i = 0; i < COUNT(nums); i++) {
		if (!f[nums[i].key])
			continue;
		join(p, "camera", camera_keys[nums[i].key]);
		if ((r = get_f64(c, f[nums[i].key], p, nums[i].s, nums[i].field)))
			return r;
	}
	if (f[C_SENSOR_FIT] &&
	    (r = get_enum(c, f[C_SENSOR_FIT], "camera.sensor_fit", "sensor fit",
	                  sensor_fits, COUNT(sensor_fits), &cam->sensor_fit)))
		return r;
	/* Clipping is not stored: the background is told by
	 * background_depth, since Blender writes 1e10 there whatever clip_end
	 * says. The values are still checked like Blender's. */
	double clip_start = 0.0, clip_end = 0.0;
	if (f[C_CLIP_START] && (r = get_f64(c, f[C_CLIP_START],
	                                    "camera.clip_start", POSITIVE,
	                                    &clip_start)))
		return r;
	if (f[C_CLIP_END] && (r = get_f64(c, f[C_CLIP_END], "camera.clip_end",
	                                  POSITIVE, &clip_end)))
		return r;
	if (f[C_CLIP_START] && f[C_CLIP_END] && !(clip_end > clip_start))
		return FAIL(c, "camera.clip_end: %g must be greater than "
		            "camera.clip_start (%g)", clip_end, clip_start);
	return SSS_OK;
}

/* ---------------------------------------------------------- materials */

enum {
	M_PASS_INDEX, M_NAME, M_PROFILE, M_STRENGTH, M_TEXTURING, M_TAPS,
	M_RADIUS, M_MAPPING, M_ALBEDO,
	M_GAUSSIANS, M_SCALE,
	M_WIDTH, M_STRENGTH_RGB, M_FALLOFF,
	M_SCATTER_SCALE, M_BALANCE, M_NEAR_SIGMA, M_FAR_SIGMA,
	M_TRANSMISSION, M_T_STRENGTH, M_T_COLOR, M_T_DISTANCE,
	M_T_TRANSLUCENCY, M_T_DISTORTION, M_T_POWER, M_T_SCALE, M_T_AMBIENT,
	M_THICKNESS_SCALE,
	M_CALIBRATION,
	M_COUNT
};
static const char *const material_keys[M_COUNT] = {
	"pass_index", "name", "profile", "strength", "texturing", "taps",
	"radius", "mapping", "albedo",
	"gaussians", "scale",
	"width", "strength_rgb", "falloff",
	"scatter_scale", "balance", "near_sigma", "far_sigma",
	"transmission", "transmission_strength", "transmission_color",
	"transmission_distance", "transmission_translucency",
	"transmission_distortion", "transmission_power", "transmission_scale",
	"transmission_ambient", "thickness_scale",
	"calibration",
};
/* The profile a key belongs to; -1 for keys every profile reads. */
static const int8_t key_profile[M_COUNT] = {
	-1, -1, -1, -1, -1, -1,
	SSS_PROFILE_BURLEY, SSS_PROFILE_BURLEY, SSS_PROFILE_BURLEY,
	SSS_PROFILE_GAUSSIANS, SSS_PROFILE_GAUSSIANS,
	SSS_PROFILE_JIMENEZ, SSS_PROFILE_JIMENEZ, SSS_PROFILE_JIMENEZ,
	SSS_PROFILE_NEAR_FAR, SSS_PROFILE_NEAR_FAR, SSS_PROFILE_NEAR_FAR,
	SSS_PROFILE_NEAR_FAR,
	-1, -1, -1, -1, -1, -1, -1, -1, -1, -1, /* transmission: every kind */
	-1, /* calibration */
};

static const char *const gaussian_keys[2] = {"variance", "weight"};

static sss_result parse_gaussians(ctx *c, const cJSON *arr, const char *path,
                                  sss_material *m)
{
	int n = cJSON_IsArray(arr) ? cJSON_GetArraySize(arr) : -1;
	if (n < 1 || n > SSS_MAX_GAUSSIANS) {
		char buf[32];
		return FAIL(c, "%s: expected an array of 1 to %d objects "
		            "{\"variance\", \"weight\"}, got %s", path,
		            SSS_MAX_GAUSSIANS, describe(arr, buf, sizeof buf));
	}
	/* Rows beyond the given ones are cleared, not left at the default
	 * skin's values, so the struct shows exactly what the file says. */
	memset(m->gaussian_variance, 0, sizeof m->gaussian_variance);
	memset(m->gaussian_weight, 0, sizeof m->gaussian_weight);
	int i = 0;
	const cJSON *g;
	cJSON_ArrayForEach(g, arr) {
		char gp[PATH_LEN], p[PATH_LEN];
		join_index(gp, path, i);
		if (!cJSON_IsObject(g))
			return type_error(c, gp, "an object", g);
		const cJSON *f[2];
		sss_result r = scan(c, g, gp, gaussian_keys, 2, f);
		if (r)
			return r;
		for (int k = 0; k < 2; k++) {
			join(p, gp, gaussian_keys[k]);
			if (!f[k])
				return FAIL(c, "%s: missing (required)", p);
			r = k == 0 ? get_f32(c, f[k], p, POSITIVE_F,
			                     &m->gaussian_variance[i])
			           : get_vec3(c, f[k], p, NONNEG_F,
			                      m->gaussian_weight[i]);
			if (r)
				return r;
		}
		i++;
	}
	m->gaussian_count = n;
	static const char rgb[3] = {'r', 'g', 'b'};
	for (int ch = 0; ch < 3; ch++) {
		double sum = 0.0;
		for (int k = 0; k < n; k++)
			sum += m->gaussian_weight[k][ch];
		if (!(sum > 0.0))
			return FAIL(c, "%s: the weights of channel %c sum to 0 (every "
			            "channel needs some weight)", path, rgb[ch]);
	}
	return SSS_OK;
}

/* One "materials" entry into m and *name (allocated). used[] marks the
 * pass indices taken by earlier entries. */
static sss_result parse_material(ctx *c, const cJSON *obj, int32_t i,
                                 const sss_material *earlier,
                                 uint8_t *used, sss_material *m, char **name)
{
	char mp[PATH_LEN], p[PATH_LEN];
	join_index(mp, "materials", (int)i);
	if (!cJSON_IsObject(obj))
		return type_error(c, mp, "an object", obj);
	const cJSON *f[M_COUNT];
	sss_result r = scan(c, obj, mp, material_keys, M_COUNT, f);
	if (r)
		return r;

	/* The profile first: its defaults are what the other keys change. */
	int32_t kind = SSS_PROFILE_NONE;
	join(p, mp, "profile");
	if (!f[M_PROFILE])
		return FAIL(c, "%s: missing (required: burley, gaussians, jimenez, "
		            "near-far or none)", p);
	if ((r = get_enum(c, f[M_PROFILE], p, "profile", profiles,
	                  COUNT(profiles), &kind)))
		return r;
	sss_material_default(m, kind);

	join(p, mp, "pass_index");
	if (!f[M_PASS_INDEX])
		return FAIL(c, "%s: missing (required, 1..65535)", p);
	if ((r = get_int(c, f[M_PASS_INDEX], p, 1, 65535, &m->pass_index)))
		return r;
	int32_t pi = m->pass_index;
	if (used[pi >> 3] & (1u << (pi & 7))) {
		int32_t j = 0;
		while (j < i && earlier[j].pass_index != pi)
			j++;
		return FAIL(c, "%s: %d is already used by materials[%d]", p, pi,
		            (int)j);
	}
	used[pi >> 3] |= (uint8_t)(1u << (pi & 7));

	/* Another profile's keys are most likely left over from switching
	 * profiles: said, not applied. */
	for (int k = 0; k < M_COUNT; k++) {
		if (f[k] && key_profile[k] >= 0 && key_profile[k] != kind) {
			join(p, mp, material_keys[k]);
			warn(c, "warning: key '%s' is not used by profile '%s' "
			     "(ignored)", p, profile_name(kind));
			f[k] = NULL;
		}
	}

	if (f[M_NAME] && !cJSON_IsString(f[M_NAME])) {
		join(p, mp, "name");
		return type_error(c, p, "a string", f[M_NAME]);
	}

	/* Every remaining key, in table order. */
	struct {
		int key;
		float *field;
		span s;
		int vec3;
	} nums[] = {
		{M_STRENGTH, &m->strength, UNIT, 0},
		{M_RADIUS, m->radius, NONNEG_F, 1},
		{M_ALBEDO, m->albedo, UNIT, 1},
		{M_SCALE, &m->gaussian_scale, NONNEG_F, 0},
		{M_WIDTH, &m->jimenez_width, NONNEG_F, 0},
		{M_STRENGTH_RGB, m->jimenez_strength, UNIT, 1},
		{M_FALLOFF, m->jimenez_falloff, POSITIVE_F, 1},
		{M_SCATTER_SCALE, &m->scatter_scale, NONNEG_F, 0},
		{M_BALANCE, &m->near_far_balance, UNIT, 0},
		{M_NEAR_SIGMA, m->near_sigma, POSITIVE_F, 1},
		{M_FAR_SIGMA, m->far_sigma, POSITIVE_F, 1},
		{M_T_STRENGTH, &m->transmission_strength, UNIT, 0},
		{M_T_COLOR, m->transmission_color, UNIT, 1},
		{M_T_DISTANCE, &m->transmission_distance, POSITIVE_F, 0},
		{M_T_TRANSLUCENCY, &m->transmission_translucency, UNIT, 0},
		{M_T_DISTORTION, &m->transmission_distortion, UNIT, 0},
		{M_T_POWER, &m->transmission_power, POSITIVE_F, 0},
		{M_T_SCALE, &m->transmission_scale, NONNEG_F, 0},
		{M_T_AMBIENT, &m->transmission_ambient, NONNEG_F, 0},
		{M_THICKNESS_SCALE, &m->thickness_scale, NONNEG_F, 0},
	};
	for (int k = 0; k < COUNT(nums); k++) {
		const cJSON *it = f[nums[k].key];
		if (!it)
			continue;
		join(p, mp, material_keys[nums[k].key]);
		r = nums[k].vec3 ? get_vec3(c, it, p, nums[k].s, nums[k].field)
		                 : get_f32(c, it, p, nums[k].s, nums[k].field);
		if (r)
			return r;
	}
	join(p, mp, "texturing");
	if (f[M_TEXTURING] &&
	    (r = get_enum(c, f[M_TEXTURING], p, "texturing", texturings,
	                  COUNT(texturings), &m->texturing)))
		return r;
	join(p, mp, "taps");
	if (f[M_TAPS] && (r = get_int(c, f[M_TAPS], p, 0, 4097, &m->taps)))
		return r;
	join(p, mp, "mapping");
	if (f[M_MAPPING] &&
	    (r = get_enum(c, f[M_MAPPING], p, "mapping", mappings,
	                  COUNT(mappings), &m->burley_mapping)))
		return r;
	join(p, mp, "transmission");
	if (f[M_TRANSMISSION] &&
	    (r = get_enum(c, f[M_TRANSMISSION], p, "transmission model",
	                  transmissions, COUNT(transmissions),
	                  &m->transmission)))
		return r;
	join(p, mp, "calibration");
	if (f[M_CALIBRATION] &&
	    (r = get_enum(c, f[M_CALIBRATION], p, "calibration", calibrations,
	                  COUNT(calibrations), &m->calibration)))
		return r;
	join(p, mp, "gaussians");
	if (f[M_GAUSSIANS] && (r = parse_gaussians(c, f[M_GAUSSIANS], p, m)))
		return r;

	/* The library's own check has the last word, so a loaded material is
	 * always one sss_apply accepts. */
	char msg[200];
	if (sss_material_validate(m, msg, sizeof msg))
		return FAIL(c, "%s: %s", mp, msg);

	/* Allocated last, so that no error path has to free it. */
	char fallback[32];
	snprintf(fallback, sizeof fallback, "material %d", (int)pi);
	const char *src = f[M_NAME] ? f[M_NAME]->valuestring : fallback;
	size_t len = strlen(src);
	if (!(*name = malloc(len + 1)))
		return sss__fail(c->err, c->err_len, SSS_ERR_OUT_OF_MEMORY,
		                 "%s: cannot allocate the name", mp);
	memcpy(*name, src, len + 1);
	return SSS_OK;
}

static sss_result parse_materials(ctx *c, const cJSON *arr, sss_scene *sc)
{
	if (!cJSON_IsArray(arr))
		return type_error(c, "materials", "an array of objects", arr);
	int n = cJSON_GetArraySize(arr);
	if (n > SCENE_MAX_MATERIALS)
		return FAIL(c, "materials: %d entries, at most %d", n,
		            SCENE_MAX_MATERIALS);
	sc->materials = calloc(n ? (size_t)n : 1, sizeof *sc->materials);
	sc->names = calloc(n ? (size_t)n : 1, sizeof *sc->names);
	uint8_t *used = calloc(65536 / 8, 1);
	sss_result r = SSS_OK;
	if (!sc->materials || !sc->names || !used) {
		r = sss__fail(c->err, c->err_len, SSS_ERR_OUT_OF_MEMORY,
		              "materials: cannot allocate %d entries", n);
		goto done;
	}
	const cJSON *it;
	cJSON_ArrayForEach(it, arr) {
		int32_t i = sc->material_count;
		if ((r = parse_material(c, it, i, sc->materials, used,
		                        &sc->materials[i], &sc->names[i])))
			break;
		sc->material_count++;
	}
done:
	free(used);
	return r;
}

/* ------------------------------------------------------------ scene */

enum {
	T_VERSION, T_CAMERA, T_UNIT_SCALE, T_METHOD, T_RADIUS_SCALE, T_TAPS,
	T_THREADS, T_BACKGROUND_DEPTH, T_MAX_SUPPORT_PX, T_MATERIALS, T_SAMPLES,
	T_COUNT
};
static const char *const top_keys[T_COUNT] = {
	"version", "camera", "unit_scale", "method", "radius_scale", "taps",
	"threads", "background_depth", "max_support_px", "materials", "samples",
};

static sss_result parse_root(ctx *c, const cJSON *root, sss_scene *sc)
{
	if (!cJSON_IsObject(root)) {
		char buf[32];
		return FAIL(c, "expected a JSON object at the top level, got %s",
		            describe(root, buf, sizeof buf));
	}
	const cJSON *f[T_COUNT];
	sss_result r = scan(c, root, "", top_keys, T_COUNT, f);
	if (r)
		return r;
	sss_camera *cam = &sc->camera;
	sss_options *opt = &sc->options;

	if (f[T_VERSION]) {
		int32_t version = 1;
		if ((r = get_int(c, f[T_VERSION], "version", 1, INT32_MAX,
		                 &version)))
			return r;
		if (version != 1)
			return sss__fail(c->err, c->err_len, SSS_ERR_UNSUPPORTED,
			                 "version: %d is newer than this library "
			                 "reads (1)", (int)version);
	}
	if (f[T_CAMERA] && (r = parse_camera(c, f[T_CAMERA], cam)))
		return r;
	if (f[T_UNIT_SCALE] && (r = get_f64(c, f[T_UNIT_SCALE], "unit_scale",
	                                    POSITIVE, &cam->unit_scale)))
		return r;
	/* Bounds as sss_apply checks them. */
	if (f[T_METHOD] && (r = get_enum(c, f[T_METHOD], "method", "method",
	                                 methods, COUNT(methods), &opt->method)))
		return r;
	if (f[T_RADIUS_SCALE] &&
	    (r = get_f32(c, f[T_RADIUS_SCALE], "radius_scale", NONNEG_F,
	                 &opt->radius_scale)))
		return r;
	if (f[T_TAPS] && (r = get_int(c, f[T_TAPS], "taps", 1, 4097,
	                              &opt->taps)))
		return r;
	if (f[T_THREADS] && (r = get_int(c, f[T_THREADS], "threads", 0, 256,
	                                 &opt->num_threads)))
		return r;
	if (f[T_BACKGROUND_DEPTH] &&
	    (r = get_f64(c, f[T_BACKGROUND_DEPTH], "background_depth", POSITIVE,
	                 &opt->background_depth)))
		return r;
	if (f[T_MAX_SUPPORT_PX] &&
	    (r = get_int(c, f[T_MAX_SUPPORT_PX], "max_support_px", 1, INT32_MAX,
	                 &opt->max_support_px)))
		return r;
	if (f[T_SAMPLES] && (r = get_int(c, f[T_SAMPLES], "samples", 1, 4096,
	                                 &opt->samples)))
		return r;
	if (f[T_MATERIALS] && (r = parse_materials(c, f[T_MATERIALS], sc)))
		return r;
	/* The camera model's own check, as sss_apply runs it. */
	sss__projection proj;
	return sss__projection_make(cam, 1, 1, &proj, c->err, c->err_len);
}

/* cJSON's whitespace: every byte up to the space. */
static const char *skip_space(const char *s)
{
	while (*s && (unsigned char)*s <= ' ')
		s++;
	return s;
}

/* "invalid JSON at line L, column C (near '...')"; cJSON's error position
 * is approximate, so a few bytes of context help. */
static sss_result syntax_error(ctx *c, const char *text, const char *at,
                               const char *what)
{
	int line = 1, col = 1;
	for (const char *s = text; s < at; s++) {
		if (*s == '\n') {
			line++;
			col = 1;
		} else {
			col++;
		}
	}
	if (!*at)
		return FAIL(c, "%s at line %d, column %d (at the end of the text)",
		            what, line, col);
	char near[24], buf[48];
	size_t n = 0;
	while (at[n] && at[n] != '\n' && at[n] != '\r' && n + 1 < sizeof near) {
		near[n] = at[n];
		n++;
	}
	near[n] = '\0';
	return FAIL(c, "%s at line %d, column %d (near '%s')", what, line, col,
	            printable(near, buf, sizeof buf));
}

sss_result sss_scene_parse(const char *json, size_t json_len,
                           sss_scene **out, char *warnbuf,
                           size_t warnbuf_len, char *errbuf,
                           size_t errbuf_len)
{
	ctx c = {errbuf, errbuf_len, warnbuf, warnbuf_len, 0, 0};
	if (errbuf && errbuf_len)
		errbuf[0] = '\0';
	if (warnbuf && warnbuf_len)
		warnbuf[0] = '\0';
	if (out)
		*out = NULL;
	if (!out)
		return FAIL(&c, "out is NULL");
	if (!json && json_len)
		return FAIL(&c, "JSON text is NULL");

	/* The text ends at json_len or at a NUL byte, whichever is first. A
	 * terminated copy keeps cJSON off the end of a caller's buffer. */
	size_t n = json ? strnlen(json, json_len) : 0;
	char *text = malloc(n + 1);
	if (!text)
		return sss__fail(errbuf, errbuf_len, SSS_ERR_OUT_OF_MEMORY,
		                 "cannot copy %zu bytes of JSON", n);
	if (n)
		memcpy(text, json, n);
	text[n] = '\0';

	sss_result r;
	cJSON *root = NULL;
	sss_scene *sc = NULL;
	if (!*skip_space(text)) {
		r = FAIL(&c, "empty JSON text");
		goto done;
	}
	/* The end pointer, not cJSON_GetErrorPtr(): that one is global. */
	const char *end = NULL;
	root = cJSON_ParseWithOpts(text, &end, 0);
	if (!root) {
		r = syntax_error(&c, text, end ? end : text + n, "invalid JSON");
		goto done;
	}
	end = skip_space(end);
	if (*end) {
		r = syntax_error(&c, text, end, "unexpected text after the JSON "
		                 "value");
		goto done;
	}
	if (!(sc = calloc(1, sizeof *sc))) {
		r = sss__fail(errbuf, errbuf_len, SSS_ERR_OUT_OF_MEMORY,
		              "cannot allocate the scene");
		goto done;
	}
	sss_camera_default(&sc->camera);
	sss_options_default(&sc->options);
	if ((r = parse_root(&c, root, sc)))
		goto done;
	if (!sc->materials) { /* no "materials" key: an empty table */
		sc->materials = calloc(1, sizeof *sc->materials);
		sc->names = calloc(1, sizeof *sc->names);
		if (!sc->materials || !sc->names) {
			r = sss__fail(errbuf, errbuf_len, SSS_ERR_OUT_OF_MEMORY,
			              "cannot allocate the scene");
			goto done;
		}
	}
	*out = sc;
	sc = NULL;
done:
	sss_scene_free(sc);
	cJSON_Delete(root);
	free(text);
	return r;
}

/* Reads the whole file, growing the buffer, so pipes work too (a shell's
 * <(...)). Opened without blocking: a FIFO nobody writes to reads as
 * empty instead of waiting forever; devices and sockets are refused. */
static sss_result read_file(const char *path, char **data, size_t *len,
                            char *errbuf, size_t errbuf_len)
{
	char msg[128];
	int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
	struct stat st;
	FILE *fp = NULL;
	if (fd >= 0 && fstat(fd, &st) == 0 && !S_ISREG(st.st_mode) &&
	    !S_ISFIFO(st.st_mode)) {
		close(fd);
		return sss__fail(errbuf, errbuf_len, SSS_ERR_IO, "%s: is %s, not "
		                 "a scene description file", path,
		                 sss__file_kind(st.st_mode));
	}
	/* Blocking again for the reads: a pipe's writer may be slow. */
	if (fd >= 0 && fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) & ~O_NONBLOCK) == 0)
		fp = fdopen(fd, "rb");
	if (!fp) {
		int e = errno;
		if (fd >= 0)
			close(fd);
		if (strerror_r(e, msg, sizeof msg))
			snprintf(msg, sizeof msg, "error %d", e);
		return sss__fail(errbuf, errbuf_len, SSS_ERR_IO,
		                 "%s: cannot open: %s", path, msg);
	}
	size_t cap = 0, n = 0;
	char *buf = NULL;
	sss_result r = SSS_OK;
	for (;;) {
		if (n == cap) {
			if (cap > SCENE_MAX_BYTES) {
				r = sss__fail(errbuf, errbuf_len, SSS_ERR_IO, "%s: larger "
				              "than %zu MiB; not a scene description",
				              path, SCENE_MAX_BYTES >> 20);
				break;
			}
			/* One byte over the cap is enough to tell. */
			size_t ncap = cap ? 2 * cap : 65536;
			if (ncap > SCENE_MAX_BYTES)
				ncap = SCENE_MAX_BYTES + 1;
			char *nbuf = realloc(buf, ncap);
			if (!nbuf) {
				r = sss__fail(errbuf, errbuf_len, SSS_ERR_OUT_OF_MEMORY,
				              "%s: cannot allocate %zu bytes", path, ncap);
				break;
			}
			buf = nbuf;
			cap = ncap;
		}
		size_t got = fread(buf + n, 1, cap - n, fp);
		n += got;
		if (got == 0) {
			if (ferror(fp)) {
				int e = errno;
				if (strerror_r(e, msg, sizeof msg))
					snprintf(msg, sizeof msg, "error %d", e);
				r = sss__fail(errbuf, errbuf_len, SSS_ERR_IO,
				              "%s: cannot read: %s", path, msg);
			}
			break;
		}
	}
	fclose(fp);
	if (r) {
		free(buf);
		return r;
	}
	*data = buf;
	*len = n;
	return SSS_OK;
}

sss_result sss_scene_load(const char *path, sss_scene **out, char *warnbuf,
                          size_t warnbuf_len, char *errbuf,
                          size_t errbuf_len)
{
	if (errbuf && errbuf_len)
		errbuf[0] = '\0';
	if (warnbuf && warnbuf_len)
		warnbuf[0] = '\0';
	if (out)
		*out = NULL;
	if (!path || !out)
		return sss__fail(errbuf, errbuf_len, SSS_ERR_INVALID_ARGUMENT,
		                 "%s is NULL", path ? "out" : "scene path");
	char *data = NULL;
	size_t len = 0;
	sss_result r = read_file(path, &data, &len, errbuf, errbuf_len);
	if (r)
		return r;
	char msg[512];
	r = sss_scene_parse(data ? data : "", len, out, warnbuf, warnbuf_len,
	                    msg, sizeof msg);
	if (r)
		sss__fail(errbuf, errbuf_len, r, "%s: %s", path, msg);
	free(data);
	return r;
}

void sss_scene_free(sss_scene *scene)
{
	if (!scene)
		return;
	if (scene->names)
		for (int32_t i = 0; i < scene->material_count; i++)
			free(scene->names[i]);
	free(scene->names);
	free(scene->materials);
	free(scene);
}

const sss_camera *sss_scene_camera(const sss_scene *scene)
{
	return scene ? &scene->camera : NULL;
}

const sss_options *sss_scene_options(const sss_scene *scene)
{
	return scene ? &scene->options : NULL;
}

const sss_material *sss_scene_materials(const sss_scene *scene,
                                        int32_t *count)
{
	if (count)
		*count = scene ? scene->material_count : 0;
	return scene ? scene->materials : NULL;
}

const char *sss_scene_material_name(const sss_scene *scene, int32_t i)
{
	if (!scene || i < 0 || i >= scene->material_count)
		return NULL;
	return scene->names[i];
}
