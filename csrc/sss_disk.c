/* sss_disk.c - the disk method (Golubev 2018, Unity HDRP's screen-space
 * SSS): at every scattering pixel, n point samples of the 2-D profile.
 *
 * Radii are stratified and importance-sampled through the inverse of the
 * radial CDF of one channel (the widest that scatters: the kernel's
 * area_cdf table, inverted by binary search and exactly as
 * sss__table_lookup interpolates it), u_i = (i + 1/2) / n over the mass
 * within reach; angles follow the golden-angle sequence
 * phi_i = 2 pi frac(i / golden + rotation), with a rotation per pixel from
 * a hash of its coordinates, so the pattern's structure becomes noise and
 * the result does not depend on the thread count. A pixel takes
 * n = clamp(round(pi R^2 / 4), 1, samples) samples for a kernel R pixels
 * wide (one sample per 4 pixels of the disk, HDRP's rate).
 *
 * Each sample reads the nearest pixel and is weighed, per channel, by the
 * profile at the distance r3 = sqrt(r^2 + e^2) divided by the sampling
 * channel's profile at r (the importance-sampling ratio; 1 for that
 * channel on a flat surface), where r is the sampled radius and e the part
 * of the true 3-D distance to the pixel that is not across the screen
 * (the depth difference; HDRP's bilateral weight). Samples on another
 * material, off the image, on pixels that do not scatter or beyond the
 * support are dropped and the weights renormalised per channel, as in the
 * other methods: a constant image stays constant exactly.
 *
 * What it gets wrong is noise: the result is an unbiased-in-the-limit
 * estimate, so an impulse's light is conserved on average over pixels, not
 * exactly as with the deterministic methods, and fine detail gets grain
 * at low budgets (tests/test_methods.c measures both).
 */
#include "sss_internal.h"

#include <stdlib.h>
#include <string.h>

#define INV_GOLDEN 0.6180339887498949

typedef struct disk_ctx {
	const sss__job *job;
	const int8_t *sampler;   /* per kernel: the channel radii follow, -1 */
	const double *base;      /* per sample i: cos, sin of 2 pi frac(i/g) */
	int32_t samples;
	/* Per-source normalisation (NULL: none): each pixel's share of its
	 * profile's mass that lands on pixels of its material, per channel,
	 * which the first pass measures instead of the blur. */
	float *available;
	const uint8_t *per_source; /* per kernel, or NULL */
	int measuring, undoing;
} disk_ctx;

/* A fixed hash of the pixel's coordinates in [0, 1). */
static double rotation(int32_t x, int32_t y)
{
	uint32_t h = (uint32_t)x * 0x9E3779B1u ^ ((uint32_t)y * 0x85EBCA77u +
	                                          0x27D4EB2Fu);
	h ^= h >> 16;
	h *= 0x7FEB352Du;
	h ^= h >> 15;
	h *= 0x846CA68Bu;
	h ^= h >> 16;
	return (double)(h >> 8) * (1.0 / 16777216.0);
}

/* x with sss__table_lookup(cdf, x) = t, for t within the table's range
 * (the table is non-decreasing). */
static double inverse_lookup(const float *cdf, double support, double t)
{
	int lo = 0, hi = SSS__TABLE_SIZE - 1;
	if (!(t > cdf[0]))
		return 0.0;
	if (!(t < cdf[hi]))
		return support;
	while (hi - lo > 1) { /* cdf[lo] < t <= cdf[hi] */
		int mid = (lo + hi) / 2;
		if (cdf[mid] < t)
			lo = mid;
		else
			hi = mid;
	}
	double step = (double)cdf[hi] - cdf[lo];
	double u = lo + (step > 0.0 ? (t - cdf[lo]) / step : 0.0);
	u /= SSS__TABLE_SIZE - 1;
	return support * u * u;
}

/* The channel whose radii the samples follow: the widest (largest mean
 * radius) among those that scatter; -1 if none. */
static int8_t pick_sampler(const sss__kernel *k)
{
	int8_t best = -1;
	double widest = -1.0;
	for (int c = 0; c < 3; c++) {
		const float *cdf = k->area_cdf[c];
		if (!(k->mix[c] > 0.0f) || !(k->area[c][0] > 0.0f))
			continue;
		double total = cdf[SSS__TABLE_SIZE - 1], mean = 0.0;
		if (!(total > 0.0))
			continue;
		for (int i = 0; i + 1 < SSS__TABLE_SIZE; i++) {
			double t0 = (double)i / (SSS__TABLE_SIZE - 1);
			double t1 = (double)(i + 1) / (SSS__TABLE_SIZE - 1);
			double tail = 1.0 - 0.5 * (cdf[i] + cdf[i + 1]) / total;
			mean += tail * (t1 * t1 - t0 * t0);
		}
		if (mean > widest) {
			widest = mean;
			best = (int8_t)c;
		}
	}
	return best;
}

static double depth_at(const sss__job *job, int32_t x, int32_t y)
{
	return job->depth[y * job->depth_stride +
	                  (int64_t)x * job->depth_channels];
}

/* View-space x, y of a pixel from its depth. */
static void lateral(const sss__job *job, int32_t x, int32_t y, double z,
                    double out[2])
{
	const sss__projection *p = &job->proj;
	double scale = p->ortho ? 1.0 : z;
	out[0] = (x + 0.5 - p->cx) / p->fx * scale;
	out[1] = (p->cy - (y + 0.5)) / p->fy * scale;
}

/* The radii and their pdf for one (kernel, sample count, mass within
 * reach): a pure function of those three, kept while neighbouring pixels
 * share them, so caching changes no result. */
typedef struct radii {
	int16_t slot;
	int32_t n;
	double mass;
	double r[4096], inv_pdf[4096]; /* 0 where the pdf is 0 */
} radii;

/* The squared part of the 3-D distance from the centre to pixel (qx, qy)
 * that is not across the screen. From depth alone the lateral parts
 * cancel and it is the depth difference squared; with a Position pass,
 * |P - C|^2 minus the lateral part. */
static double off_screen_distance2(const sss__job *job, int32_t qx,
                                   int32_t qy, const double centre[3],
                                   const double lc[2])
{
	double zq = depth_at(job, qx, qy);
	if (!job->position) {
		double dz = zq - centre[2];
		return dz * dz;
	}
	double p[3], lq[2];
	sss__pixel_position(job, qx, qy, p);
	lateral(job, qx, qy, zq, lq);
	double dx = p[0] - centre[0], dy = p[1] - centre[1],
	       dz = p[2] - centre[2];
	double ax = lq[0] - lc[0], ay = lq[1] - lc[1];
	return (dx * dx + dy * dy + dz * dz) - (ax * ax + ay * ay);
}

static void disk_pixel(const disk_ctx *ctx, int16_t slot, int32_t x,
                       int32_t y, radii *cache, float *out)
{
	const sss__job *job = ctx->job;
	const sss__kernel *k = &job->kernels[slot];
	int32_t w = job->width, h = job->height;
	const float *s = job->signal + 3 * ((int64_t)y * w + x);
	memcpy(out, s, 3 * sizeof(float));
	int sc = ctx->sampler[slot];
	double z = depth_at(job, x, y);
	double ppx = sss__pixels_per_unit_x(&job->proj, z);
	double ppy = sss__pixels_per_unit_y(&job->proj, z);
	if (sc < 0 || (!(k->support * ppx >= 1.0) && !(k->support * ppy >= 1.0)))
		return; /* nothing but the centre within reach */

	/* Sample only the mass within reach of the pixel caps. */
	double cap_px = fmin((double)job->max_support_px, hypot(w, h));
	double reach = fmin(k->support, cap_px / fmax(ppx, ppy));
	double inv_support = 1.0 / k->support;
	const float *cdf = k->area_cdf[sc];
	double mass = reach < k->support
	              ? sss__table_lookup(cdf, reach, inv_support)
	              : cdf[SSS__TABLE_SIZE - 1];
	double area = SSS__PI * (reach * ppx) * (reach * ppy) / 4.0;
	int32_t n = area < ctx->samples ? (int32_t)floor(area + 0.5)
	                                : ctx->samples;
	if (n < 1)
		n = 1;

	double centre[3], lc[2];
	sss__pixel_position(job, x, y, centre);
	lateral(job, x, y, z, lc);
	if (cache->slot != slot || cache->n != n || cache->mass != mass) {
		for (int32_t i = 0; i < n; i++) {
			double r = inverse_lookup(cdf, k->support, (i + 0.5) / n * mass);
			double pdf = sss__table_lookup(k->area[sc], r, inv_support);
			cache->r[i] = r;
			cache->inv_pdf[i] = pdf > 0.0 ? 1.0 / pdf : 0.0;
		}
		cache->slot = slot;
		cache->n = n;
		cache->mass = mass;
	}
	double rot = 2.0 * SSS__PI * rotation(x, y);
	double cr = cos(rot), sr = sin(rot);
	double acc[3] = {0, 0, 0}, wsum[3] = {0, 0, 0};
	for (int32_t i = 0; i < n; i++) {
		double r = cache->r[i], inv_pdf = cache->inv_pdf[i];
		if (!(inv_pdf > 0.0))
			continue;
		/* cos, sin of 2 pi frac(i / golden) + rot */
		double c0 = ctx->base[2 * i], s0 = ctx->base[2 * i + 1];
		double ca = c0 * cr - s0 * sr, sa = s0 * cr + c0 * sr;
		int32_t qx = x + (int32_t)floor(r * ppx * ca + 0.5);
		int32_t qy = y - (int32_t)floor(r * ppy * sa + 0.5);
		if (qx < 0 || qx >= w || qy < 0 || qy >= h)
			continue;
		int64_t j = (int64_t)qy * w + qx;
		if (job->slot[j] != slot)
			continue;
		double r3 = r;
		if (qx != x || qy != y) {
			double e2 = off_screen_distance2(job, qx, qy, centre, lc);
			if (e2 > 0.0)
				r3 = sqrt(r * r + e2);
		}
		if (!(r3 < k->support))
			continue;
		const float *v = job->signal + 3 * j;
		/* sss__table_lookup's interpolation, one square root for all
		 * three channels. */
		double u = sqrt(r3 * inv_support) * (SSS__TABLE_SIZE - 1);
		int t = SSS__TABLE_SIZE - 2;
		float f = 1.0f;
		if (u < SSS__TABLE_SIZE - 1) {
			t = (int)u;
			f = (float)(u - t);
		}
		for (int c = 0; c < 3; c++) {
			const float *a = k->area[c];
			double wc = (c == sc && r3 == r)
			            ? 1.0
			            : (double)(a[t] + f * (a[t + 1] - a[t])) * inv_pdf;
			acc[c] += wc * v[c];
			wsum[c] += wc;
		}
	}
	if (ctx->measuring) {
		if (!ctx->per_source[slot])
			return; /* keeps 1 */
		/* The samples cover `mass` of the profile; each weight is the
		 * profile over the sampling pdf, 1 on average where all land. */
		float *a = ctx->available + 3 * ((int64_t)y * w + x);
		for (int c = 0; c < 3; c++)
			a[c] = (float)(mass * wsum[c] / n);
		return;
	}
	for (int c = 0; c < 3; c++)
		if (wsum[c] > 0.0)
			out[c] = (float)(acc[c] / wsum[c]);
}

static void disk_rows(void *vctx, int32_t y0, int32_t y1)
{
	const disk_ctx *ctx = vctx;
	const sss__job *job = ctx->job;
	radii cache;
	cache.slot = -1;
	cache.n = 0;
	cache.mass = 0.0;
	for (int32_t y = y0; y < y1; y++)
		for (int32_t x = 0; x < job->width; x++) {
			int64_t i = (int64_t)y * job->width + x;
			int16_t slot = job->slot[i];
			if (slot >= 0)
				disk_pixel(ctx, slot, x, y, &cache, job->scratch + 3 * i);
		}
}

static void blend_rows(void *vctx, int32_t y0, int32_t y1)
{
	const sss__job *job = ((const disk_ctx *)vctx)->job;
	for (int64_t i = (int64_t)y0 * job->width; i < (int64_t)y1 * job->width;
	     i++)
		if (job->slot[i] >= 0)
			sss__blend_pixel(&job->kernels[job->slot[i]],
			                 job->scratch + 3 * i, job->signal + 3 * i);
}

/* Per-source normalisation: light is conserved per pixel where it
 * enters, not where it leaves. With W(q) the share of q's profile that
 * lands on its material, the light leaving p is
 * sum_q K(p, q) L(q) / W(q) = W(p) N(L / W)(p), N the normalised blur
 * the samples estimate; on a surface the kernel sees whole, W = 1 and it
 * is that blur. Light entering near a rim or an edge then leaves near
 * there rather than spreading inwards (measured in docs/comparison.md).
 * A source under AVAILABLE_FLOOR of its profile on screen is taken as
 * having that much: the rest leaves where the camera cannot see. */
#define AVAILABLE_FLOOR 0.05f

/* L / W before the blur; after it, W N(L / W) and L back. */
static void per_source_rows(void *vctx, int32_t y0, int32_t y1)
{
	const disk_ctx *ctx = vctx;
	const sss__job *job = ctx->job;
	for (int64_t i = (int64_t)y0 * job->width; i < (int64_t)y1 * job->width;
	     i++)
		if (job->slot[i] >= 0)
			for (int c = 0; c < 3; c++) {
				float *a = ctx->available + 3 * i + c;
				if (ctx->undoing) {
					job->signal[3 * i + c] *= *a;
					job->scratch[3 * i + c] *= *a;
				} else {
					*a = *a > AVAILABLE_FLOOR ? *a : AVAILABLE_FLOOR;
					job->signal[3 * i + c] /= *a;
				}
			}
}

sss_result sss__disk(const sss__job *job, int32_t samples,
                     int32_t num_threads, const uint8_t *per_source)
{
	size_t npix = (size_t)job->width * (size_t)job->height;
	int32_t kernels = 0;
	for (size_t i = 0; i < npix; i++)
		if (job->slot[i] >= kernels)
			kernels = job->slot[i] + 1;
	int8_t *sampler = malloc(kernels ? (size_t)kernels : 1);
	double *base = malloc(2 * (size_t)samples * sizeof *base);
	int any = 0;
	for (int32_t m = 0; per_source && m < kernels; m++)
		any |= per_source[m];
	float *available = any ? malloc(3 * npix * sizeof *available) : NULL;
	if (!sampler || !base || (any && !available)) {
		free(sampler);
		free(base);
		free(available);
		return SSS_ERR_OUT_OF_MEMORY;
	}
	for (int32_t m = 0; m < kernels; m++)
		sampler[m] = job->kernels[m].support > 0.0
		             ? pick_sampler(&job->kernels[m]) : -1;
	for (int32_t i = 0; i < samples; i++) {
		double t = i * INV_GOLDEN;
		double a = 2.0 * SSS__PI * (t - floor(t));
		base[2 * i] = cos(a);
		base[2 * i + 1] = sin(a);
	}
	disk_ctx ctx = {job, sampler, base, samples, available, per_source, 0,
	                0};
	if (available) {
		/* Pixels with nothing but the centre within reach keep 1. */
		for (size_t i = 0; i < 3 * npix; i++)
			available[i] = 1.0f;
		ctx.measuring = 1;
		sss__parallel_rows(job->height, num_threads, disk_rows, &ctx);
		ctx.measuring = 0;
		sss__parallel_rows(job->height, num_threads, per_source_rows, &ctx);
	}
	sss__parallel_rows(job->height, num_threads, disk_rows, &ctx);
	if (available) {
		ctx.undoing = 1;
		sss__parallel_rows(job->height, num_threads, per_source_rows, &ctx);
	}
	sss__parallel_rows(job->height, num_threads, blend_rows, &ctx);
	free(sampler);
	free(base);
	free(available);
	return SSS_OK;
}
