/* sss_scene.c - the JSON scene description (docs/scene.md): camera, unit
 * scale, options and the material table, checked so that a loaded scene is
 * always accepted by sss_apply. */
#include "sss_camera_fields.h"
#include "sss_fields.h"
#include "sss_internal.h"
#include "sss_option_fields.h"

#include <cJSON.h>

#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* A scene file larger than this is certainly not a scene description. */
#define SCENE_MAX_BYTES ((size_t)16 << 20)
/* Values in one: 32767 materials of 60 values are 2M (~100 MB in cJSON). */
#define SCENE_MAX_VALUES (1 << 21)
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

/* The reader's failure: SSS_ERR_INVALID_ARGUMENT into the context's
 * errbuf (FAIL and FAILX, sss_internal.h, take a function's own). */
#define PARSE_FAIL(c, ...) sss__fail((c)->err, (c)->err_len, \
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
	return PARSE_FAIL(c, "%s: expected %s, got %s", path, expected,
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

/* ------------------------------------------------------------ fields
 *
 * Each JSON object is read through one table of its keys: the key, where
 * its value goes in the struct being filled and what it may hold. The
 * tables are made from the schemas, one line per field: a material's in
 * SSS_MATERIAL_FIELDS (sss_fields.h), an option's in SSS_OPTION_FIELDS
 * (sss_option_fields.h), a camera's in SSS_CAMERA_FIELDS
 * (sss_camera_fields.h); only the keys a reader handles itself (clipping,
 * a material's profile, ...) are written out here. */

/* Allowed numbers: [lo, hi], lo excluded when lo_open. */
typedef struct span {
	double lo, hi;
	int lo_open;
} span;

#define POSITIVE {0.0, DBL_MAX, 1}
/* Float fields share sss_material_validate's upper bound. */
#define POSITIVE_F {0.0, 1e30, 1}
#define NONNEG_F {0.0, 1e30, 0}

enum field_type {
	FIELD_F64,     /* double within range */
	FIELD_F32,     /* float within range */
	FIELD_VEC3,    /* float[3], each within range */
	FIELD_INT,     /* int32_t in [lo, hi] */
	FIELD_ENUM,    /* int32_t, one of names */
	FIELD_METHOD,  /* int32_t, one of sss_method_name's */
	FIELD_SPECIAL  /* read by the object's own code */
};

typedef sss__name_value name_value;

typedef struct field {
	const char *key;
	int8_t profile;  /* materials: the profile it belongs to, -1 = every */
	uint8_t type;    /* field_type */
	size_t offset;   /* in the struct being filled */
	span range;      /* F64, F32, VEC3 */
	int32_t lo, hi;  /* INT */
	const char *what;        /* ENUM: "profile" in "unknown profile 'x'" */
	const name_value *names; /* ENUM */
	int name_count;
} field;

#define COUNT(a) ((int)(sizeof(a) / sizeof *(a)))

/* Finds an object's known members: found[k] is the member named
 * fields[k].key or NULL. Unknown members are warnings; a known key given
 * twice is an error, since which one was meant is unclear. */
static sss_result scan(ctx *c, const cJSON *obj, const char *path,
                       const field *fields, int nfields, const cJSON **found)
{
	for (int k = 0; k < nfields; k++)
		found[k] = NULL;
	const cJSON *it;
	cJSON_ArrayForEach(it, obj) {
		int k = 0;
		while (k < nfields && strcmp(it->string, fields[k].key) != 0)
			k++;
		if (k == nfields) {
			char buf[48];
			warn(c, "warning: unknown key '%s%s%s' (ignored)", path,
			     *path ? "." : "", printable(it->string, buf, sizeof buf));
		} else if (found[k]) {
			char p[PATH_LEN];
			join(p, path, fields[k].key);
			return PARSE_FAIL(c, "%s: key given twice", p);
		} else {
			found[k] = it;
		}
	}
	return SSS_OK;
}

/* ------------------------------------------------------------ values */

static sss_result get_f64(ctx *c, const cJSON *it, const char *path,
                          span s, double *out)
{
	if (!cJSON_IsNumber(it))
		return type_error(c, path, "a number", it);
	double v = it->valuedouble;
	if (!isfinite(v)) /* JSON has no NaN; 1e999 overflows to Inf */
		return PARSE_FAIL(c, "%s: number out of range (overflows a double)",
		                  path);
	if (v < s.lo || (s.lo_open && v <= s.lo) || v > s.hi) {
		/* 1e30 and up is "no upper bound" unless it is what was hit. */
		if (s.hi < 1e30)
			return PARSE_FAIL(c, "%s: %g is out of range (must be in "
			                  "%c%g, %g])", path, v, s.lo_open ? '(' : '[',
			                  s.lo, s.hi);
		if (v > s.hi)
			return PARSE_FAIL(c, "%s: %g is out of range (must be <= %g)", path,
			                  v, s.hi);
		return PARSE_FAIL(c, "%s: %g is out of range (must be %s %g)", path, v,
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
		return PARSE_FAIL(c, "%s: %g is too large for a 32-bit float", path, v);
	float f = (float)v;
	if (s.lo_open && !(f > s.lo))
		return PARSE_FAIL(c, "%s: %g is too small (it rounds to %g as a 32-bit "
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
		return PARSE_FAIL(c, "%s: expected an integer, got %g", path, v);
	if (v < lo || v > hi) {
		if (hi == INT32_MAX && v < lo)
			return PARSE_FAIL(c, "%s: %g is out of range (must be >= %d)", path,
			                  v, lo);
		return PARSE_FAIL(c, "%s: %g is out of range (must be %d..%d)", path, v,
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
	return PARSE_FAIL(c, "%s: unknown %s '%s' (expected %s)", path, what,
	                  printable(it->valuestring, buf, sizeof buf), list);
}

static const char *profile_name(int32_t kind)
{
	for (int i = 0; i < COUNT(sss__profile_names); i++)
		if (sss__profile_names[i].value == kind)
			return sss__profile_names[i].name;
	return "?";
}

/* Reads every given key of a table whose type is not FIELD_SPECIAL into
 * base, in table order. */
static sss_result parse_fields(ctx *c, const char *path, const field *fields,
                               int nfields, const cJSON *const *found,
                               void *base)
{
	for (int k = 0; k < nfields; k++) {
		const field *fd = &fields[k];
		const cJSON *it = found[k];
		if (!it || fd->type == FIELD_SPECIAL)
			continue;
		char p[PATH_LEN];
		join(p, path, fd->key);
		void *dst = (char *)base + fd->offset;
		name_value methods[8];
		int nmethods = 0;
		sss_result r = SSS_OK;
		switch (fd->type) {
		case FIELD_F64:
			r = get_f64(c, it, p, fd->range, dst);
			break;
		case FIELD_F32:
			r = get_f32(c, it, p, fd->range, dst);
			break;
		case FIELD_VEC3:
			r = get_vec3(c, it, p, fd->range, dst);
			break;
		case FIELD_INT:
			r = get_int(c, it, p, fd->lo, fd->hi, dst);
			break;
		case FIELD_ENUM:
			r = get_enum(c, it, p, fd->what, fd->names, fd->name_count,
			             dst);
			break;
		case FIELD_METHOD:
			while (nmethods < COUNT(methods) &&
			       sss_method_name(nmethods)) {
				methods[nmethods].name = sss_method_name(nmethods);
				methods[nmethods].value = nmethods;
				nmethods++;
			}
			r = get_enum(c, it, p, "method", methods, nmethods, dst);
			break;
		default:
			break;
		}
		if (r)
			return r;
	}
	return SSS_OK;
}

#define AT(type, member) offsetof(type, member)
#define ENUM(table, noun) .what = noun, .names = table, \
                          .name_count = COUNT(table)

/* ------------------------------------------------------------ camera */

/* The keys of "camera": clipping (read by parse_camera itself), then
 * the camera schema's (sss_camera_fields.h) rows whose place is CAMERA. */
#define ROW(...) ROW_(__VA_ARGS__)
#define ROW_(k, member, t, place, when, def, lo_, hi_, lo_open, names_, \
             count, help) \
	IN_##place({.key = k, .profile = -1, .type = FIELD_##t, \
	            .offset = AT(sss_camera, member), \
	            .range = {lo_, hi_, lo_open}, .what = k, .names = names_, \
	            .name_count = count},)
#define IN_CAMERA(...) __VA_ARGS__
#define IN_TOP(...)
static const field camera_fields[] = {
	{.key = "clip_start", .type = FIELD_SPECIAL},
	{.key = "clip_end", .type = FIELD_SPECIAL},
	SSS_CAMERA_FIELDS(ROW)
};
#undef ROW
#undef ROW_
#undef IN_CAMERA
#undef IN_TOP
enum { C_CLIP_START, C_CLIP_END, C_COUNT = COUNT(camera_fields) };

static sss_result parse_camera(ctx *c, const cJSON *obj, sss_camera *cam)
{
	if (!cJSON_IsObject(obj))
		return type_error(c, "camera", "an object", obj);
	const cJSON *f[C_COUNT];
	sss_result r = scan(c, obj, "camera", camera_fields, C_COUNT, f);
	/* Every given length is checked even when the camera type does not
	 * use it: a bad value is a bug in whatever wrote the file. */
	if (r || (r = parse_fields(c, "camera", camera_fields, C_COUNT, f, cam)))
		return r;
	/* Clipping is not stored: the background is told by
	 * background_depth, since Blender writes 1e10 there whatever clip_end
	 * says. The values are still checked like Blender's. */
	double clip_start = 0.0, clip_end = 0.0;
	if (f[C_CLIP_START] && (r = get_f64(c, f[C_CLIP_START],
	                                    "camera.clip_start",
	                                    (span)POSITIVE, &clip_start)))
		return r;
	if (f[C_CLIP_END] && (r = get_f64(c, f[C_CLIP_END], "camera.clip_end",
	                                  (span)POSITIVE, &clip_end)))
		return r;
	if (f[C_CLIP_START] && f[C_CLIP_END] && !(clip_end > clip_start))
		return PARSE_FAIL(c, "camera.clip_end: %g must be greater than "
		                  "camera.clip_start (%g)", clip_end, clip_start);
	return SSS_OK;
}

/* ---------------------------------------------------------- materials */

/* The keys of a "materials" entry: the four read by parse_material
 * itself, then the schema (sss_fields.h). .profile: the profile a key
 * belongs to (-1: every profile reads it); another profile's keys are
 * warned about and ignored. */
#define ROW(...) ROW_(__VA_ARGS__)
#define ROW_(k, member, t, p, when, d0, d1, d2, lo_, hi_, lo_open, names_, \
            count, help) \
	{.key = k, .profile = SSS__P_##p, .type = FIELD_##t, \
	 .offset = AT(sss_material, member), .range = {lo_, hi_, lo_open}, \
	 .lo = (int32_t)((hi_) < 1e9 ? (lo_) : 0), \
	 .hi = (int32_t)((hi_) < 1e9 ? (hi_) : 0), .what = k, \
	 .names = names_, .name_count = count},
static const field material_fields[] = {
	{.key = "pass_index", .profile = -1, .type = FIELD_SPECIAL},
	{.key = "name", .profile = -1, .type = FIELD_SPECIAL},
	{.key = "profile", .profile = -1, .type = FIELD_SPECIAL},
	{.key = "gaussians", .profile = SSS_PROFILE_GAUSSIANS,
	 .type = FIELD_SPECIAL},
	SSS_MATERIAL_FIELDS(ROW)
};
#undef ROW
#undef ROW_
enum { M_PASS_INDEX, M_NAME, M_PROFILE, M_GAUSSIANS,
       M_COUNT = COUNT(material_fields) };

static const field gaussian_fields[2] = {
	{.key = "variance", .type = FIELD_SPECIAL},
	{.key = "weight", .type = FIELD_SPECIAL},
};

static sss_result parse_gaussians(ctx *c, const cJSON *arr, const char *path,
                                  sss_material *m)
{
	int n = cJSON_IsArray(arr) ? cJSON_GetArraySize(arr) : -1;
	if (n < 1 || n > SSS_MAX_GAUSSIANS) {
		char buf[32];
		return PARSE_FAIL(c, "%s: expected an array of 1 to %d objects "
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
		sss_result r = scan(c, g, gp, gaussian_fields, 2, f);
		if (r)
			return r;
		for (int k = 0; k < 2; k++) {
			join(p, gp, gaussian_fields[k].key);
			if (!f[k])
				return PARSE_FAIL(c, "%s: missing (required)", p);
			r = k == 0 ? get_f32(c, f[k], p, (span)POSITIVE_F,
			                     &m->gaussian_variance[i])
			           : get_vec3(c, f[k], p, (span)NONNEG_F,
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
			return PARSE_FAIL(c, "%s: the weights of channel %c sum to 0 "
			                  "(every channel needs some weight)", path,
			                  rgb[ch]);
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
	sss_result r = scan(c, obj, mp, material_fields, M_COUNT, f);
	if (r)
		return r;

	/* The profile first: its defaults are what the other keys change. */
	int32_t kind = SSS_PROFILE_NONE;
	join(p, mp, "profile");
	if (!f[M_PROFILE])
		return PARSE_FAIL(c, "%s: missing (required: burley, gaussians, "
		                  "jimenez, near-far or none)", p);
	if ((r = get_enum(c, f[M_PROFILE], p, "profile", sss__profile_names,
	                  COUNT(sss__profile_names), &kind)))
		return r;
	sss_material_default(m, kind);

	join(p, mp, "pass_index");
	if (!f[M_PASS_INDEX])
		return PARSE_FAIL(c, "%s: missing (required, 1..65535)", p);
	if ((r = get_int(c, f[M_PASS_INDEX], p, 1, 65535, &m->pass_index)))
		return r;
	int32_t pi = m->pass_index;
	if (used[pi >> 3] & (1u << (pi & 7))) {
		int32_t j = 0;
		while (j < i && earlier[j].pass_index != pi)
			j++;
		return PARSE_FAIL(c, "%s: %d is already used by materials[%d]", p, pi,
		                  (int)j);
	}
	used[pi >> 3] |= (uint8_t)(1u << (pi & 7));

	/* Another profile's keys are most likely left over from switching
	 * profiles: said, not applied. */
	for (int k = 0; k < M_COUNT; k++) {
		if (f[k] && material_fields[k].profile >= 0 &&
		    material_fields[k].profile != kind) {
			join(p, mp, material_fields[k].key);
			warn(c, "warning: key '%s' is not used by profile '%s' "
			     "(ignored)", p, profile_name(kind));
			f[k] = NULL;
		}
	}

	if (f[M_NAME] && !cJSON_IsString(f[M_NAME])) {
		join(p, mp, "name");
		return type_error(c, p, "a string", f[M_NAME]);
	}
	if ((r = parse_fields(c, mp, material_fields, M_COUNT, f, m)))
		return r;
	join(p, mp, "gaussians");
	if (f[M_GAUSSIANS] && (r = parse_gaussians(c, f[M_GAUSSIANS], p, m)))
		return r;

	/* The library's own check has the last word, so a loaded material is
	 * always one sss_apply accepts. */
	char msg[200];
	if (sss_material_validate(m, msg, sizeof msg))
		return PARSE_FAIL(c, "%s: %s", mp, msg);

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
		return PARSE_FAIL(c, "materials: %d entries, at most %d", n,
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

/* The top level's keys: the three read by parse_root itself, the camera
 * schema's rows whose place is TOP (unit_scale), then the options schema
 * (sss_option_fields.h), with its ranges, which are sss_apply's. */
#define ROW(...) ROW_(__VA_ARGS__)
#define ROW_(k, member, t, place, when, def, lo_, hi_, lo_open, names_, \
             count, help) \
	IN_##place({.key = k, .profile = -1, .type = FIELD_##t, \
	            .offset = AT(sss_scene, camera.member), \
	            .range = {lo_, hi_, lo_open}},)
#define IN_CAMERA(...)
#define IN_TOP(...) __VA_ARGS__
#define OPTION(k, member, t, def, lo_, hi_, lo_open, help) \
	{.key = k, .profile = -1, .type = FIELD_##t, \
	 .offset = AT(sss_scene, options.member), \
	 .range = {lo_, hi_, lo_open}, .lo = INT_##t(lo_), .hi = INT_##t(hi_)},
/* An INT row's bounds; other types have none. */
#define INT_INT(v) (int32_t)(v)
#define INT_F32(v) 0
#define INT_F64(v) 0
#define INT_METHOD(v) 0
static const field top_fields[] = {
	{.key = "version", .type = FIELD_SPECIAL},
	{.key = "camera", .type = FIELD_SPECIAL},
	{.key = "materials", .type = FIELD_SPECIAL},
	SSS_CAMERA_FIELDS(ROW)
	SSS_OPTION_FIELDS(OPTION)
};
#undef ROW
#undef ROW_
#undef IN_CAMERA
#undef IN_TOP
#undef OPTION
#undef INT_INT
#undef INT_F32
#undef INT_F64
#undef INT_METHOD
enum { T_VERSION, T_CAMERA, T_MATERIALS, T_COUNT = COUNT(top_fields) };

static sss_result parse_root(ctx *c, const cJSON *root, sss_scene *sc)
{
	if (!cJSON_IsObject(root)) {
		char buf[32];
		return PARSE_FAIL(c, "expected a JSON object at the top level, got %s",
		                  describe(root, buf, sizeof buf));
	}
	const cJSON *f[T_COUNT];
	sss_result r = scan(c, root, "", top_fields, T_COUNT, f);
	if (r)
		return r;

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
	if (f[T_CAMERA] && (r = parse_camera(c, f[T_CAMERA], &sc->camera)))
		return r;
	if ((r = parse_fields(c, "", top_fields, T_COUNT, f, sc)))
		return r;
	if (f[T_MATERIALS] && (r = parse_materials(c, f[T_MATERIALS], sc)))
		return r;
	/* The camera model's own check, as sss_apply runs it. */
	sss__projection proj;
	return sss__projection_make(&sc->camera, 1, 1, &proj, c->err,
	                            c->err_len);
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
		return PARSE_FAIL(c, "%s at line %d, column %d (at the end of the "
		                  "text)", what, line, col);
	char near[24], buf[48];
	size_t n = 0;
	while (at[n] && at[n] != '\n' && at[n] != '\r' && n + 1 < sizeof near) {
		near[n] = at[n];
		n++;
	}
	near[n] = '\0';
	return PARSE_FAIL(c, "%s at line %d, column %d (near '%s')", what, line,
	                  col, printable(near, buf, sizeof buf));
}

/* Values (numbers, strings, literals, arrays, objects; keys count as
 * strings) in a JSON text, roughly: every ',' '[' '{' ':' outside
 * strings, plus one. *nul: where a string holds \u0000, else NULL. */
static long long count_values(const char *text, const char **nul)
{
	long long n = 1;
	int in_string = 0;
	*nul = NULL;
	for (const char *s = text; *s; s++) {
		if (in_string) {
			if (*s == '\\') {
				if (s[1] == 'u' && strncmp(s + 2, "0000", 4) == 0) {
					*nul = s;
					return n;
				}
				if (s[1])
					s++;
			} else if (*s == '"') {
				in_string = 0;
			}
		} else if (*s == '"') {
			in_string = 1;
		} else if (*s == ',' || *s == '[' || *s == '{' || *s == ':') {
			n++;
		}
	}
	return n;
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
		return PARSE_FAIL(&c, "out is NULL");
	if (!json && json_len)
		return PARSE_FAIL(&c, "JSON text is NULL");

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
		r = PARSE_FAIL(&c, "empty JSON text");
		goto done;
	}
	/* Before cJSON sees it: a "\u0000" in a string would end that
	 * string early in cJSON's C strings ("unit_scale\u0000junk" read as
	 * "unit_scale"), and every value costs cJSON ~40 times its text (a
	 * 6 MB array took 248 MB), so values are counted first. */
	const char *bad = NULL;
	long long values = count_values(text, &bad);
	if (bad) {
		r = syntax_error(&c, text, bad, "a string holds \\u0000 (a NUL "
		                 "character), which no key or name may contain");
		goto done;
	}
	if (values > SCENE_MAX_VALUES) {
		r = PARSE_FAIL(&c, "more than %d JSON values (%lld); a scene "
		               "description holds far fewer", SCENE_MAX_VALUES, values);
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
