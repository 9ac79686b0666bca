/* sss_separable.c - the separable method: a horizontal then a vertical 1-D
 * pass, each depth-aware and renormalised per channel.
 *
 * At every scattering pixel the kernel's support (scene units) is projected
 * through the camera at that pixel's depth, giving a half-width R in pixels.
 * If the whole kernel fits in the tap budget (2 floor(R) + 1 <= taps) every
 * pixel under it is a tap ("dense"); otherwise `taps` taps are spread with
 * Jimenez's quadratic spacing o_i = R (i/h)^2 and midpoint footprints, and
 * read with linear interpolation ("sparse"). A tap's weight is its
 * footprint times the 1-D profile at the TRUE 3-D distance between the two
 * surface points, so foreshortened surfaces blur less on screen and a
 * sample across a depth step beyond the support weighs nothing. The centre
 * tap's weight is the profile integrated over its own footprint, which is
 * finite even for Burley's singular centre.
 */
#include "sss_internal.h"

#include <stdlib.h>
#include <string.h>

typedef struct pass_ctx {
	const sss__job *job;
	const float *src;
	float *dst;
	int vertical;
	int blend; /* dst holds the unscattered signal: blend into it */
} pass_ctx;

typedef struct accum {
	double acc[3];
	double wsum[3];
} accum;

/* Adds pixel (px, py) seen from the centre through a tap at offset `o`
 * pixels whose cell spans [o - below, o + above] pixels along the axis;
 * `share` is the pixel's part of an interpolated tap. The weight is the
 * 1-D profile's mass over the cell, placed at the pixel's true 3-D
 * distance; samples on another material or beyond the support drop out. */
static void add_sample(const pass_ctx *ctx, const sss__kernel *k, int16_t slot,
                       const double centre[3], int32_t cx, int32_t cy,
                       int32_t px, int32_t py, double o, double below,
                       double above, double share, double units_per_px,
                       accum *a)
{
	const sss__job *job = ctx->job;
	int64_t j = (int64_t)py * job->width + px;
	if (job->slot[j] != slot)
		return;
	double d;
	if (px == cx && py == cy) {
		d = fabs(o) * units_per_px;
	} else {
		double p[3];
		sss__pixel_position(job, px, py, p);
		double dx = p[0] - centre[0], dy = p[1] - centre[1],
		       dz = p[2] - centre[2];
		d = sqrt(dx * dx + dy * dy + dz * dz);
	}
	double near = d - below * units_per_px;
	if (!(near < k->support))
		return;
	double mass[3];
	sss__line_mass3(k, near, d + above * units_per_px, mass);
	const float *v = ctx->src + 3 * j;
	for (int c = 0; c < 3; c++) {
		double w = share * mass[c];
		a->acc[c] += w * v[c];
		a->wsum[c] += w;
	}
}

/* The centre tap and the taps right of it for a kernel of half-width r
 * pixels, as offsets and cells (pixels). If every pixel under the kernel
 * fits in the tap budget, each is a tap with a one-pixel cell ("dense");
 * otherwise `taps` taps follow Jimenez's quadratic spacing o_i = r (i/h)^2
 * and each cell reaches halfway to the neighbouring taps, the midpoint rule
 * of his "area" weights. Returns the number of taps right of the centre. */
int32_t sss__tap_layout(int32_t taps, double r, sss__tap *tap)
{
	int32_t half_taps = (taps - 1) / 2;
	/* Every pixel whose cell reaches into the support. */
	int32_t dense = (int32_t)(r + 0.5);
	tap[0] = (sss__tap){0.0, -0.5, 0.5};
	if (half_taps == 0)
		return 0; /* one tap: the centre alone, the identity */
	if (dense <= half_taps) {
		for (int32_t t = 1; t <= dense; t++)
			tap[t] = (sss__tap){t, t - 0.5, t + 0.5};
		return dense;
	}
	double inv_h = 1.0 / half_taps;
	for (int32_t t = 0; t <= half_taps; t++)
		tap[t].offset = r * (t * inv_h) * (t * inv_h);
	for (int32_t t = 0; t <= half_taps; t++) {
		double prev = t ? tap[t - 1].offset : -tap[1].offset;
		double next = t < half_taps ? tap[t + 1].offset : tap[t].offset;
		tap[t].lo = 0.5 * (prev + tap[t].offset);
		tap[t].hi = 0.5 * (tap[t].offset + next);
	}
	return half_taps;
}

/* The 1-D blur of ctx->src at pixel (x, y) into b; 0 if it is the
 * identity there (kernel narrower than a pixel at this depth). */
static int blur_pixel(const pass_ctx *ctx, const sss__kernel *k, int16_t slot,
                      int32_t x, int32_t y, float b[3])
{
	const sss__job *job = ctx->job;
	int32_t extent = ctx->vertical ? job->height : job->width;
	const float *s = ctx->src + 3 * ((int64_t)y * job->width + x);
	double centre[3];
	sss__pixel_position(job, x, y, centre);
	double z = job->depth[y * job->depth_stride +
	                      (int64_t)x * job->depth_channels];
	double ppu = ctx->vertical ? sss__pixels_per_unit_y(&job->proj, z)
	                           : sss__pixels_per_unit_x(&job->proj, z);
	double r = k->support * ppu;
	if (r > job->max_support_px)
		r = job->max_support_px;
	if (r > extent)
		r = extent;
	if (!(r >= 1.0))
		return 0; /* nothing but the centre within reach */

	double upp = 1.0 / ppu;
	int32_t pos = ctx->vertical ? y : x;
	accum a = {{0, 0, 0}, {0, 0, 0}};
	sss__tap tap[SSS__MAX_HALF_TAPS + 1];
	int32_t n = sss__tap_layout(k->taps, r, tap);
	for (int32_t t = 1; t <= n; t++) {
		double below = tap[t].offset - tap[t].lo;
		double above = tap[t].hi - tap[t].offset;
		for (int sign = -1; sign <= 1; sign += 2) {
			double o = sign * tap[t].offset;
			double at = pos + o;
			double fl = floor(at);
			double f = at - fl;
			/* Linear interpolation between the two pixels around the tap
			 * (dense taps sit on a pixel: f = 0). */
			for (int e = 0; e < 2; e++) {
				int32_t q = (int32_t)fl + e;
				double share = e ? f : 1.0 - f;
				if (share <= 0.0 || q < 0 || q >= extent)
					continue;
				add_sample(ctx, k, slot, centre, x, y, ctx->vertical ? x : q,
				           ctx->vertical ? q : y, o, below, above, share,
				           upp, &a);
			}
		}
	}
	double mass[3];
	sss__line_mass3(k, tap[0].lo * upp, tap[0].hi * upp, mass);
	for (int c = 0; c < 3; c++) {
		a.acc[c] += mass[c] * s[c];
		a.wsum[c] += mass[c];
		b[c] = a.wsum[c] > 0.0 ? (float)(a.acc[c] / a.wsum[c]) : s[c];
	}
	return 1;
}

static void pass_rows(void *vctx, int32_t y0, int32_t y1)
{
	const pass_ctx *ctx = vctx;
	const sss__job *job = ctx->job;
	for (int32_t y = y0; y < y1; y++) {
		for (int32_t x = 0; x < job->width; x++) {
			int64_t i = (int64_t)y * job->width + x;
			const float *s = ctx->src + 3 * i;
			float *out = ctx->dst + 3 * i;
			int16_t slot = job->slot[i];
			if (slot < 0) {
				if (!ctx->blend)
					memcpy(out, s, 3 * sizeof(float));
				continue;
			}
			const sss__kernel *k = &job->kernels[slot];
			float b[3];
			if (!blur_pixel(ctx, k, slot, x, y, b))
				memcpy(b, s, sizeof b);
			if (ctx->blend)
				sss__blend_pixel(k, b, out);
			else
				memcpy(out, b, sizeof b);
		}
	}
}

sss_result sss__separable(const sss__job *job, int32_t num_threads)
{
	pass_ctx horizontal = {job, job->signal, job->scratch, 0, 0};
	sss__parallel_rows(job->height, num_threads, pass_rows, &horizontal);
	/* The vertical pass reads only the horizontal result around a pixel
	 * and the signal at that pixel, so it can blend into the signal. */
	pass_ctx vertical = {job, job->scratch, job->signal, 1, 1};
	sss__parallel_rows(job->height, num_threads, pass_rows, &vertical);
	return SSS_OK;
}

sss_result sss_kernel_1d(const sss_material *mat, double pixels_per_metre,
                         int32_t taps, float *offsets, float *weights,
                         int32_t *count)
{
	if (!mat || !offsets || !weights || !count || *count < 1)
		return SSS_ERR_INVALID_ARGUMENT;
	if (!(isfinite(pixels_per_metre) && pixels_per_metre > 0.0))
		return SSS_ERR_INVALID_ARGUMENT;
	sss_material m = *mat;
	m.pass_index = 1; /* the table key plays no part in the shape */
	if (taps > 4097 || sss_material_validate(&m, NULL, 0) != SSS_OK)
		return SSS_ERR_INVALID_ARGUMENT;
	sss_options opt;
	sss_options_default(&opt);
	if (taps > 0)
		m.taps = taps;
	sss__kernel *k = malloc(sizeof *k);
	sss__tap *tap = malloc((SSS__MAX_HALF_TAPS + 1) * sizeof *tap);
	if (!k || !tap) {
		free(k);
		free(tap);
		return SSS_ERR_OUT_OF_MEMORY;
	}
	sss__kernel_build(&m, &opt, 1.0, k);

	/* On a flat fronto-parallel plane a tap's distance is its offset. */
	double r = k->support * pixels_per_metre;
	tap[0] = (sss__tap){0.0, -0.5, 0.5};
	int32_t n = r >= 1.0 ? sss__tap_layout(k->taps, r, tap) : 0;
	if (2 * n + 1 > *count) {
		free(k);
		free(tap);
		return SSS_ERR_INVALID_ARGUMENT;
	}
	double upm = 1.0 / pixels_per_metre;
	double mass[SSS__MAX_HALF_TAPS + 1][3], sum[3] = {0, 0, 0};
	for (int32_t t = 0; t <= n; t++) {
		if (k->support > 0.0)
			sss__line_mass3(k, tap[t].lo * upm, tap[t].hi * upm, mass[t]);
		else
			mass[t][0] = mass[t][1] = mass[t][2] = 1.0;
		for (int c = 0; c < 3; c++)
			sum[c] += (t ? 2.0 : 1.0) * mass[t][c];
	}
	for (int32_t t = -n; t <= n; t++) {
		int32_t at = t < 0 ? -t : t;
		offsets[t + n] = (float)(t < 0 ? -tap[at].offset : tap[at].offset);
		for (int c = 0; c < 3; c++)
			weights[3 * (t + n) + c] = (float)(mass[at][c] / sum[c]);
	}
	*count = 2 * n + 1;
	free(k);
	free(tap);
	return SSS_OK;
}
