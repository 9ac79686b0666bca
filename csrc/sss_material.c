/* sss_material.c - material defaults, validation and Burley's radius
 * mapping: everything about one row of the table, before any tabulation. */
#include "sss_fields.h"
#include "sss_internal.h"

#include <stddef.h>
#include <stdio.h>
#include <string.h>

/* d'Eon & Luebke 2007 (GPU Gems 3 ch. 14) six-Gaussian skin: variances in
 * mm^2 and RGB weights; each channel sums to 1. */
const float sss__deon_variance[6] = {0.0064f, 0.0484f, 0.187f,
                                    0.567f, 1.99f, 7.41f};
const float sss__deon_weight[6][3] = {
	{0.233f, 0.455f, 0.649f}, {0.100f, 0.336f, 0.344f},
	{0.118f, 0.198f, 0.000f}, {0.113f, 0.007f, 0.007f},
	{0.358f, 0.004f, 0.000f}, {0.078f, 0.000f, 0.000f},
};

/* The schema (sss_fields.h) as data: where each field lives and what it
 * may hold. */
typedef struct field {
	const char *key, *member;
	int32_t type; /* sss_field_type */
	int32_t profile, when;
	size_t offset;
	float def[3];
	double lo, hi;
	int32_t lo_open;
	const sss__name_value *names;
	int32_t name_count;
	const char *help;
} field;

#define TYPE_F32 SSS_FIELD_FLOAT
#define TYPE_VEC3 SSS_FIELD_RGB
#define TYPE_INT SSS_FIELD_INT
#define TYPE_ENUM SSS_FIELD_ENUM
#define ROW(...) ROW_(__VA_ARGS__)
#define ROW_(key, member, type, profile, when, d0, d1, d2, lo, hi, lo_open, \
            names, count, help) \
	{key, #member, TYPE_##type, SSS__P_##profile, SSS__WHEN_##when, \
	 offsetof(sss_material, member), {d0, d1, d2}, lo, hi, lo_open, names, \
	 count, help},
static const field fields[] = {SSS_MATERIAL_FIELDS(ROW)};
#undef ROW
#undef ROW_
#undef TYPE_F32
#undef TYPE_VEC3
#undef TYPE_INT
#undef TYPE_ENUM

void sss_material_default(sss_material *mat, int32_t kind)
{
	if (!mat)
		return;
	memset(mat, 0, sizeof *mat);
	mat->struct_size = sizeof *mat;
	mat->kind = kind;
	for (int k = 0; k < SSS__COUNT(fields); k++) {
		const field *f = &fields[k];
		char *at = (char *)mat + f->offset;
		if (f->type == SSS_FIELD_FLOAT || f->type == SSS_FIELD_RGB)
			memcpy(at, f->def, sizeof(float) *
			       (f->type == SSS_FIELD_RGB ? 3 : 1));
		else
			*(int32_t *)(void *)at = (int32_t)f->def[0];
	}
	/* Gaussians: d'Eon's six-Gaussian skin (a list, not a table row). */
	mat->gaussian_count = 6;
	for (int i = 0; i < 6; i++) {
		mat->gaussian_variance[i] = sss__deon_variance[i];
		memcpy(mat->gaussian_weight[i], sss__deon_weight[i],
		       sizeof(float) * 3);
	}
	/* Jimenez et al.'s demo (SeparableSSS.cpp) uses 17 taps. */
	if (kind == SSS_PROFILE_JIMENEZ)
		mat->taps = 17;
}

sss_result sss_material_field(int32_t i, sss_field_info *info)
{
	if (!info || i < 0 || i >= SSS__COUNT(fields))
		return SSS_ERR_INVALID_ARGUMENT;
	const field *f = &fields[i];
	memset(info, 0, sizeof *info);
	info->key = f->key;
	info->member = f->member;
	info->type = f->type;
	info->profile = f->profile;
	info->transmits = f->when == SSS__WHEN_TRANSMITS;
	for (int c = 0; c < 3; c++)
		info->default_value[c] = f->def[c];
	info->lo = f->lo;
	info->hi = f->hi;
	info->lo_open = f->lo_open;
	info->name_count = f->name_count;
	info->help = f->help;
	return SSS_OK;
}

const char *sss_material_field_name(int32_t i, int32_t j, int32_t *value)
{
	if (i < 0 || i >= SSS__COUNT(fields) || j < 0 ||
	    j >= fields[i].name_count)
		return NULL;
	if (value)
		*value = fields[i].names[j].value;
	return fields[i].names[j].name;
}

const char *sss_profile_name(int32_t kind)
{
	for (int i = 0; i < SSS__COUNT(sss__profile_names); i++)
		if (sss__profile_names[i].value == kind)
			return sss__profile_names[i].name;
	return NULL;
}


/* Compared as floats, as the field holds them: 1e30 read into a float
 * is 1.0000000150e30, which is still "at most 1e30". */
static int in_span(float v, const field *f)
{
	float lo = (float)f->lo, hi = (float)f->hi;
	return isfinite(v) && v >= lo && v <= hi && !(f->lo_open && v <= lo);
}

/* "in [0, 1]", "> 0", ">= 0" */
static const char *span_text(const field *f, char *buf, size_t len)
{
	if (f->hi < SSS__BIG)
		snprintf(buf, len, "in %c%g, %g]", f->lo_open ? '(' : '[', f->lo,
		         f->hi);
	else
		snprintf(buf, len, "%s %g", f->lo_open ? ">" : ">=", f->lo);
	return buf;
}

static int has_name(const field *f, int32_t v)
{
	for (int j = 0; j < f->name_count; j++)
		if (f->names[j].value == v)
			return 1;
	return 0;
}

/* One field of the table, whatever its type. */
static sss_result check_field(const sss_material *mat, const field *f,
                              char *errbuf, size_t errbuf_len)
{
	static const char rgb[3] = {'r', 'g', 'b'};
	int32_t idx = mat->pass_index;
	const char *at = (const char *)mat + f->offset;
	char span[48];
	switch (f->type) {
	case SSS_FIELD_FLOAT:
	case SSS_FIELD_RGB:
		for (int c = 0; c < (f->type == SSS_FIELD_RGB ? 3 : 1); c++) {
			float v;
			memcpy(&v, at + c * sizeof(float), sizeof v);
			if (in_span(v, f))
				continue;
			if (f->type == SSS_FIELD_FLOAT)
				return FAIL("material %d: %s %g must be %s", idx, f->member,
				            (double)v, span_text(f, span, sizeof span));
			return FAIL("material %d: %s.%c = %g must be %s", idx,
			            f->member, rgb[c], (double)v,
			            span_text(f, span, sizeof span));
		}
		return SSS_OK;
	case SSS_FIELD_INT: {
		int32_t v = *(const int32_t *)(const void *)at;
		if (v < f->lo || v > f->hi)
			return FAIL("material %d: %s %d must be %g..%g", idx, f->member,
			            v, f->lo, f->hi);
		return SSS_OK;
	}
	default: {
		int32_t v = *(const int32_t *)(const void *)at;
		if (!has_name(f, v))
			return FAIL("material %d: unknown %s %d", idx, f->member, v);
		return SSS_OK;
	}
	}
}

/* Whether the material reads field f. */
static int reads(const sss_material *mat, const field *f)
{
	if (f->profile >= 0 && f->profile != mat->kind)
		return 0;
	if (f->when == SSS__WHEN_TRANSMITS)
		return mat->transmission != SSS_TRANSMISSION_OFF;
	if (f->when == SSS__WHEN_ALBEDO)
		return mat->burley_mapping >= SSS_BURLEY_RANDOM_WALK;
	return 1;
}

static sss_result check_gaussians(const sss_material *mat, char *errbuf,
                                  size_t errbuf_len)
{
	int32_t idx = mat->pass_index;
	int n = mat->gaussian_count;
	if (n < 1 || n > SSS_MAX_GAUSSIANS)
		return FAIL("material %d: gaussian_count %d must be 1..%d", idx, n,
		            SSS_MAX_GAUSSIANS);
	double sum[3] = {0, 0, 0};
	for (int i = 0; i < n; i++) {
		float v = mat->gaussian_variance[i];
		if (!isfinite(v) || !(v > 0.0f) || v > (float)SSS__BIG)
			return FAIL("material %d: gaussian_variance[%d] = %g must be "
			            "> 0 (mm^2)", idx, i, (double)v);
		for (int c = 0; c < 3; c++) {
			float w = mat->gaussian_weight[i][c];
			if (!isfinite(w) || !(w >= 0.0f) || w > (float)SSS__BIG)
				return FAIL("material %d: gaussian_weight[%d].%c = %g must "
				            "be >= 0", idx, i, "rgb"[c], (double)w);
			sum[c] += w;
		}
	}
	for (int c = 0; c < 3; c++)
		if (!(sum[c] > 0.0))
			return FAIL("material %d: gaussian weights of channel %d sum "
			            "to 0", idx, c);
	return SSS_OK;
}

sss_result sss_material_validate(const sss_material *mat, char *errbuf,
                                 size_t errbuf_len)
{
	sss_result r;
	if (!mat)
		return FAIL("material is NULL");
	int32_t idx = mat->pass_index;
	if (mat->struct_size != sizeof *mat)
		return FAIL("material %d: struct_size %u, expected %zu (use "
		            "sss_material_default)", idx, mat->struct_size,
		            sizeof *mat);
	if (idx < 1 || idx > 65535)
		return FAIL("material pass_index %d must be 1..65535 (0 means "
		            "'no material' and is never scattered)", idx);
	int known = 0;
	for (int j = 0; j < SSS__COUNT(sss__profile_names); j++)
		known |= sss__profile_names[j].value == mat->kind;
	if (!known)
		return FAIL("material %d: unknown profile kind %d", idx, mat->kind);
	/* The enums first: what the others mean depends on them. */
	for (int pass = 0; pass < 2; pass++)
		for (int k = 0; k < SSS__COUNT(fields); k++)
			if ((fields[k].type == SSS_FIELD_ENUM) == !pass &&
			    reads(mat, &fields[k]) &&
			    (r = check_field(mat, &fields[k], errbuf, errbuf_len)))
				return r;
	if (mat->kind == SSS_PROFILE_GAUSSIANS &&
	    (r = check_gaussians(mat, errbuf, errbuf_len)))
		return r;
	return SSS_OK;
}

sss_result sss_burley_d(const sss_material *mat, double d_out[3])
{
	if (!mat || !d_out || mat->kind != SSS_PROFILE_BURLEY)
		return SSS_ERR_INVALID_ARGUMENT;
	for (int c = 0; c < 3; c++) {
		double radius = mat->radius[c];
		switch (mat->burley_mapping) {
		case SSS_BURLEY_CYCLES: /* bssrdf.h: radius *= 0.25 / pi */
			d_out[c] = radius * 0.25 / SSS__PI;
			break;
		case SSS_BURLEY_EEVEE: /* gpu_material.c: l = r/(4 pi), d = 0.6 l / 1.04 */
			d_out[c] = radius * 0.0459101;
			break;
		case SSS_BURLEY_RANDOM_WALK: {
			/* Christensen & Burley 2015: the profile in terms of the
			 * diffuse mean free path uses the searchlight fit s3(A). */
			double a = mat->albedo[c] - 0.33;
			d_out[c] = radius / (3.5 + 100.0 * a * a * a * a);
			break;
		}
		case SSS_BURLEY_CYCLES_RANDOM_WALK:
			d_out[c] = radius * sss__cycles_rw_d_over_radius(
			                        mat->albedo[c]);
			break;
		case SSS_BURLEY_CYCLES4_RANDOM_WALK:
			d_out[c] = radius * sss__cycles4_rw_d_over_radius(
			                        mat->albedo[c]);
			break;
		default:
			return SSS_ERR_INVALID_ARGUMENT;
		}
	}
	return SSS_OK;
}
