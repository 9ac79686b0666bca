/* sss_thin.c - thin parts lit from the front reflect less light.
 *
 * Light that enters a part thinner than a few mean free paths partly
 * leaves through its back, so the random walk reflects less of it than a
 * thick part does; the calibration, measured on thick slabs, does not
 * hold that (docs/transmission.md, "Thin parts lit from the front"). The
 * light entering each pixel is multiplied, before the blur, by
 *
 *     g_c = 1 - s (1 - G(t / l_c, A_c)),
 *
 * G the measured share (sss_walk4_skin_thin_table.c), t the thickness
 * pass times the material's thickness_scale, l_c and A_c the channel's
 * mean free path and albedo (as the transmission's slab), s the
 * material's thin_reflectance. Before the blur, so that the thickness
 * pass's noise is averaged over the kernel like the light's. G is read
 * from a table made per call, evenly in t (LUT steps over the measured
 * range), so that a pixel costs a multiplication and an interpolation a
 * channel. */
#include "sss_internal.h"
#include "sss_transmission.h"

#include <stdlib.h>

#define LUT 1024

typedef struct thin_mat {
	int on;
	float per_unit[3]; /* LUT steps per scene unit of thickness */
	float g[3][LUT + 1];
} thin_mat;

struct sss__thin {
	sss_image thickness;
	thin_mat **mats; /* per material, NULL: no gain */
	int32_t count;
};

/* The table measured for the material's walk, or NULL: none. */
static const sss__thin_table *measured_table(const sss_material *mat)
{
	if (mat->kind == SSS_PROFILE_BURLEY &&
	    mat->calibration == SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN &&
	    mat->burley_mapping == SSS_BURLEY_CYCLES_RANDOM_WALK)
		return &sss__walk4_skin_thin;
	return NULL;
}

/* The measured table material m asks for, or NULL: none measured for
 * its walk, thin_reflectance 0 or the thickness scaled to nothing. */
static const sss__thin_table *thin_table(const sss_material *mat)
{
	if (mat->thin_reflectance > 0.0f && mat->thickness_scale > 0.0f)
		return measured_table(mat);
	return NULL;
}

sss_result sss_thin_measured(const sss_material *mat, int *measured)
{
	if (!measured)
		return SSS_ERR_INVALID_ARGUMENT;
	*measured = 0;
	sss_result r = sss_material_validate(mat, NULL, 0);
	if (r)
		return r;
	*measured = measured_table(mat) != NULL;
	return SSS_OK;
}

/* G of one table row at x (1 from the last column on). */
static double thin_row(const sss__thin_table *tb, int k, double x)
{
	const float *xs = tb->x, *r = tb->g[k];
	if (!(x < xs[SSS__THIN_NX - 1]))
		return 1.0;
	int j = 0;
	while (j < SSS__THIN_NX - 2 && x >= xs[j + 1])
		j++;
	double f = (x - xs[j]) / (xs[j + 1] - xs[j]);
	return r[j] + f * (r[j + 1] - r[j]);
}

static void thin_make(const sss_material *mat, const sss__thin_table *tb,
                      double len, thin_mat *m)
{
	double s = mat->thin_reflectance;
	double x_end = tb->x[SSS__THIN_NX - 1];
	m->on = 0;
	for (int c = 0; c < 3; c++) {
		double A = mat->albedo[c], f;
		int i;
		sss__walk4_albedo_row(tb->albedo, A, &i, &f);
		/* l in scene units, as the transmission's slab */
		double l = (double)mat->radius[c] * len *
		           sss__cycles_rw_mfp_over_radius(A);
		if (!(l > 0.0) || !isfinite(l)) {
			m->per_unit[c] = 0.0f; /* reads g[c][0] = 1 */
			for (int k = 0; k <= LUT; k++)
				m->g[c][k] = 1.0f;
			continue;
		}
		/* thickness_scale multiplies the pass */
		m->per_unit[c] = (float)(LUT * (double)mat->thickness_scale /
		                         (x_end * l));
		for (int k = 0; k <= LUT; k++) {
			double x = x_end * k / LUT;
			double G = (1.0 - f) * thin_row(tb, i, x) +
			           f * thin_row(tb, i + 1, x);
			m->g[c][k] = (float)(1.0 - s * (1.0 - G));
		}
		m->on = 1;
	}
}

sss_result sss__thin_prepare(const sss_passes *p,
                             const sss_material *materials, int32_t count,
                             const sss_options *opt, double unit_scale,
                             sss__thin **out, char *errbuf,
                             size_t errbuf_len)
{
	*out = NULL;
	if (!p->thickness.data || !(opt->radius_scale > 0.0f))
		return SSS_OK;
	int any = 0;
	for (int32_t m = 0; m < count && !any; m++)
		any = thin_table(&materials[m]) != NULL;
	if (!any)
		return SSS_OK;
	sss__thin *t = calloc(1, sizeof *t);
	thin_mat **mats = t ? calloc((size_t)count, sizeof *mats) : NULL;
	if (!mats) {
		free(t);
		return sss__fail(errbuf, errbuf_len, SSS_ERR_OUT_OF_MEMORY,
		                 "cannot allocate the thin-part tables");
	}
	t->mats = mats;
	t->count = count;
	t->thickness = p->thickness;
	double len = (double)opt->radius_scale / unit_scale;
	for (int32_t m = 0; m < count; m++) {
		const sss_material *mat = &materials[m];
		const sss__thin_table *tb = thin_table(mat);
		if (!tb)
			continue;
		if (!(mats[m] = malloc(sizeof **mats))) {
			sss__thin_free(t);
			return sss__fail(errbuf, errbuf_len, SSS_ERR_OUT_OF_MEMORY,
			                 "cannot allocate the thin-part tables");
		}
		thin_make(mat, tb, len, mats[m]);
		if (!mats[m]->on) {
			free(mats[m]);
			mats[m] = NULL;
		}
	}
	*out = t;
	return SSS_OK;
}

void sss__thin_apply(const sss__thin *t, int32_t m, int32_t x, int32_t y,
                     float light[3])
{
	const thin_mat *tm = t ? t->mats[m] : NULL;
	if (!tm)
		return;
	float th = sss__at(&t->thickness, x, y)[0];
	if (!(th >= 0.0f) || !(th < INFINITY))
		return; /* no measurement here */
	for (int c = 0; c < 3; c++) {
		float u = th * tm->per_unit[c];
		if (!(u < (float)LUT))
			continue; /* thick: G = 1 */
		int32_t k = (int32_t)u;
		float f = u - (float)k;
		const float *g = tm->g[c];
		light[c] *= g[k] + f * (g[k + 1] - g[k]);
	}
}

void sss__thin_free(sss__thin *t)
{
	if (!t)
		return;
	for (int32_t m = 0; m < t->count; m++)
		free(t->mats[m]);
	free(t->mats);
	free(t);
}
