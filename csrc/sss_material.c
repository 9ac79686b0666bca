/* sss_material.c - material defaults, validation and Burley's radius
 * mapping: everything about one row of the table, before any tabulation. */
#include "sss_internal.h"

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

static void set3(float *v, float a, float b, float c)
{
	v[0] = a;
	v[1] = b;
	v[2] = c;
}

void sss_material_default(sss_material *mat, int32_t kind)
{
	if (!mat)
		return;
	memset(mat, 0, sizeof *mat);
	mat->struct_size = sizeof *mat;
	mat->kind = kind;
	mat->strength = 1.0f;
	mat->texturing = SSS_TEXTURING_POST;

	/* Burley: Jensen 2001 "skin1" diffuse mean free paths, in metres. */
	set3(mat->radius, 0.00367f, 0.00137f, 0.00068f);
	mat->burley_mapping = SSS_BURLEY_CYCLES;
	set3(mat->albedo, 0.8f, 0.8f, 0.8f);

	mat->gaussian_count = 6;
	for (int i = 0; i < 6; i++) {
		mat->gaussian_variance[i] = sss__deon_variance[i];
		memcpy(mat->gaussian_weight[i], sss__deon_weight[i],
		       sizeof(float) * 3);
	}
	mat->gaussian_scale = 1.0f;

	/* Jimenez et al. demo defaults (SeparableSSS.cpp). */
	mat->jimenez_width = 0.012f;
	set3(mat->jimenez_strength, 0.48f, 0.41f, 0.28f);
	set3(mat->jimenez_falloff, 1.0f, 0.37f, 0.3f);
	if (kind == SSS_PROFILE_JIMENEZ)
		mat->taps = 17;

	/* Near/far Gaussians: the artist model's defaults, sigmas in mm. */
	mat->scatter_scale = 1.0f;
	mat->near_far_balance = 0.5f;
	set3(mat->near_sigma, 0.35f, 0.07f, 0.035f);
	set3(mat->far_sigma, 1.0f, 0.12f, 0.10f);

	/* Transmission: off; when turned on, the profile's own model. */
	mat->transmission = SSS_TRANSMISSION_OFF;
	mat->transmission_strength = 1.0f;
	set3(mat->transmission_color, 1.0f, 1.0f, 1.0f);
	mat->transmission_distance = 0.01f;
	mat->transmission_translucency = 0.83f; /* Jimenez's demo */
	mat->transmission_distortion = 0.2f;
	mat->transmission_power = 4.0f;
	mat->transmission_scale = 1.0f;
	mat->transmission_ambient = 0.0f;
	mat->thickness_scale = 1.0f;

	mat->calibration = SSS_CALIBRATION_NONE;
}

#define FAIL(...) sss__fail(errbuf, errbuf_len, SSS_ERR_INVALID_ARGUMENT, \
                            __VA_ARGS__)

static int in_range(float v, float lo, float hi)
{
	return isfinite(v) && v >= lo && v <= hi;
}

static sss_result check3(const float *v, float lo, float hi, int open_lo,
                         const char *field, int32_t idx, char *errbuf,
                         size_t errbuf_len)
{
	static const char rgb[3] = {'r', 'g', 'b'};
	for (int c = 0; c < 3; c++) {
		if (!in_range(v[c], lo, hi) || (open_lo && v[c] <= lo))
			return FAIL("material %d: %s.%c = %g must be %s %g and <= %g",
			            idx, field, rgb[c], (double)v[c],
			            open_lo ? ">" : ">=", (double)lo, (double)hi);
	}
	return SSS_OK;
}

/* The transmission fields, checked only when the material transmits. */
static sss_result check_transmission(const sss_material *mat, char *errbuf,
                                     size_t errbuf_len)
{
	int32_t idx = mat->pass_index;
	if (mat->transmission < SSS_TRANSMISSION_OFF ||
	    mat->transmission > SSS_TRANSMISSION_FAST)
		return FAIL("material %d: unknown transmission model %d", idx,
		            mat->transmission);
	if (mat->transmission == SSS_TRANSMISSION_OFF)
		return SSS_OK;
	static const char rgb[3] = {'r', 'g', 'b'};
	if (!in_range(mat->transmission_strength, 0.0f, 1.0f))
		return FAIL("material %d: transmission_strength %g must be in "
		            "[0, 1]", idx, (double)mat->transmission_strength);
	for (int c = 0; c < 3; c++)
		if (!in_range(mat->transmission_color[c], 0.0f, 1.0f))
			return FAIL("material %d: transmission_color.%c = %g must be "
			            "in [0, 1]", idx, rgb[c],
			            (double)mat->transmission_color[c]);
	if (!in_range(mat->transmission_distance, 0.0f, 1e30f) ||
	    !(mat->transmission_distance > 0.0f))
		return FAIL("material %d: transmission_distance %g must be > 0 "
		            "(metres)", idx, (double)mat->transmission_distance);
	if (!in_range(mat->transmission_translucency, 0.0f, 1.0f))
		return FAIL("material %d: transmission_translucency %g must be in "
		            "[0, 1]", idx, (double)mat->transmission_translucency);
	if (!in_range(mat->transmission_distortion, 0.0f, 1.0f))
		return FAIL("material %d: transmission_distortion %g must be in "
		            "[0, 1]", idx, (double)mat->transmission_distortion);
	if (!in_range(mat->transmission_power, 0.0f, 1e30f) ||
	    !(mat->transmission_power > 0.0f))
		return FAIL("material %d: transmission_power %g must be > 0", idx,
		            (double)mat->transmission_power);
	if (!in_range(mat->transmission_scale, 0.0f, 1e30f))
		return FAIL("material %d: transmission_scale %g must be >= 0", idx,
		            (double)mat->transmission_scale);
	if (!in_range(mat->transmission_ambient, 0.0f, 1e30f))
		return FAIL("material %d: transmission_ambient %g must be >= 0",
		            idx, (double)mat->transmission_ambient);
	if (!in_range(mat->thickness_scale, 0.0f, 1e30f))
		return FAIL("material %d: thickness_scale %g must be >= 0", idx,
		            (double)mat->thickness_scale);
	if (!in_range(mat->transmission_baked_scale, 0.0f, 1e30f))
		return FAIL("material %d: transmission_baked_scale %g must be >= "
		            "0", idx, (double)mat->transmission_baked_scale);
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
	if (mat->kind < SSS_PROFILE_NONE || mat->kind > SSS_PROFILE_NEAR_FAR)
		return FAIL("material %d: unknown profile kind %d", idx, mat->kind);
	if (!in_range(mat->strength, 0.0f, 1.0f))
		return FAIL("material %d: strength %g must be in [0, 1]", idx,
		            (double)mat->strength);
	if (mat->texturing != SSS_TEXTURING_POST &&
	    mat->texturing != SSS_TEXTURING_PRE_AND_POST)
		return FAIL("material %d: unknown texturing mode %d", idx,
		            mat->texturing);
	if (mat->taps < 0 || mat->taps > 4097)
		return FAIL("material %d: taps %d must be 0 (default) or 1..4097",
		            idx, mat->taps);

	if ((r = check_transmission(mat, errbuf, errbuf_len)))
		return r;
	if (mat->calibration < SSS_CALIBRATION_NONE ||
	    mat->calibration > SSS_CALIBRATION_CYCLES4_RANDOM_WALK)
		return FAIL("material %d: unknown calibration %d", idx,
		            mat->calibration);

	switch (mat->kind) {
	case SSS_PROFILE_BURLEY:
		if ((r = check3(mat->radius, 0.0f, 1e30f, 0, "radius", idx, errbuf,
		                errbuf_len)))
			return r;
		if (mat->burley_mapping < SSS_BURLEY_CYCLES ||
		    mat->burley_mapping > SSS_BURLEY_CYCLES4_RANDOM_WALK)
			return FAIL("material %d: unknown burley_mapping %d", idx,
			            mat->burley_mapping);
		if (mat->burley_mapping >= SSS_BURLEY_RANDOM_WALK &&
		    (r = check3(mat->albedo, 0.0f, 1.0f, 0, "albedo", idx, errbuf,
		                errbuf_len)))
			return r;
		break;
	case SSS_PROFILE_GAUSSIANS: {
		int n = mat->gaussian_count;
		if (n < 1 || n > SSS_MAX_GAUSSIANS)
			return FAIL("material %d: gaussian_count %d must be 1..%d", idx,
			            n, SSS_MAX_GAUSSIANS);
		if (!in_range(mat->gaussian_scale, 0.0f, 1e30f))
			return FAIL("material %d: gaussian_scale %g must be >= 0", idx,
			            (double)mat->gaussian_scale);
		double sum[3] = {0, 0, 0};
		for (int i = 0; i < n; i++) {
			float v = mat->gaussian_variance[i];
			if (!in_range(v, 0.0f, 1e30f) || v <= 0.0f)
				return FAIL("material %d: gaussian_variance[%d] = %g must "
				            "be > 0 (mm^2)", idx, i, (double)v);
			char field[32];
			snprintf(field, sizeof field, "gaussian_weight[%d]", i);
			if ((r = check3(mat->gaussian_weight[i], 0.0f, 1e30f, 0, field,
			                idx, errbuf, errbuf_len)))
				return r;
			for (int c = 0; c < 3; c++)
				sum[c] += mat->gaussian_weight[i][c];
		}
		for (int c = 0; c < 3; c++)
			if (!(sum[c] > 0.0))
				return FAIL("material %d: gaussian weights of channel %d "
				            "sum to 0", idx, c);
		break;
	}
	case SSS_PROFILE_JIMENEZ:
		if (!in_range(mat->jimenez_width, 0.0f, 1e30f))
			return FAIL("material %d: jimenez_width %g must be >= 0 (m)",
			            idx, (double)mat->jimenez_width);
		if ((r = check3(mat->jimenez_strength, 0.0f, 1.0f, 0,
		                "jimenez_strength", idx, errbuf, errbuf_len)))
			return r;
		if ((r = check3(mat->jimenez_falloff, 0.0f, 1e30f, 1,
		                "jimenez_falloff", idx, errbuf, errbuf_len)))
			return r;
		break;
	case SSS_PROFILE_NEAR_FAR:
		if (!in_range(mat->scatter_scale, 0.0f, 1e30f))
			return FAIL("material %d: scatter_scale %g must be >= 0", idx,
			            (double)mat->scatter_scale);
		if (!in_range(mat->near_far_balance, 0.0f, 1.0f))
			return FAIL("material %d: near_far_balance %g must be in "
			            "[0, 1]", idx, (double)mat->near_far_balance);
		if ((r = check3(mat->near_sigma, 0.0f, 1e30f, 1, "near_sigma", idx,
		                errbuf, errbuf_len)))
			return r;
		if ((r = check3(mat->far_sigma, 0.0f, 1e30f, 1, "far_sigma", idx,
		                errbuf, errbuf_len)))
			return r;
		break;
	default:
		break;
	}
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
