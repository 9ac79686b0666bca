/* sss_reference.c - the brute-force reference: a 2-D sum over every pixel
 * within the projected support, each weighted by the radial profile's mass
 * over that pixel's footprint at its true 3-D distance. Slow (radius^2 per
 * pixel, several profile evaluations per pixel) and exact in screen space:
 * the oracle the fast methods are measured against.
 *
 * Each pixel is a small patch facing the camera at its own depth. Its mass
 * is integrated with a tensor Gauss-Legendre rule (6x6 points within two
 * pixels of the centre, where Burley's 1/r varies fastest, 3x3 beyond);
 * the centre pixel's own mass comes from the radial CDF in closed form.
 */
#include "sss_internal.h"

#include <stdlib.h>
#include <string.h>

typedef struct ref_ctx {
	const sss__job *job;
} ref_ctx;

/* Mass of the radial profile over the centre pixel's rectangle
 * [-hx, hx] x [-hy, hy]: (2/pi) [ int_0^t* P(hx / cos a) da
 * + int_t*^{pi/2} P(hy / sin a) da ] with the radial CDF P, by
 * Gauss-Legendre on both smooth pieces. Finite for Burley's 1/r centre. */
static double centre_mass(const sss__kernel *k, int c, double hx, double hy)
{
	static const double gx[4] = {0.1834346424956498, 0.5255324099163290,
	                             0.7966664774136267, 0.9602898564975363};
	static const double gw[4] = {0.3626837833783620, 0.3137066238953681,
	                             0.2223810344533745, 0.1012285362903763};
	double split = atan2(hy, hx), inv = 1.0 / k->support, total = 0.0;
	for (int piece = 0; piece < 2; piece++) {
		double lo = piece ? split : 0.0, hi = piece ? SSS__PI / 2 : split;
		double mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo), s = 0.0;
		for (int i = 0; i < 4; i++) {
			for (int sign = -1; sign <= 1; sign += 2) {
				double a = mid + sign * half * gx[i];
				double rho = piece ? hy / sin(a) : hx / cos(a);
				s += gw[i] * sss__table_lookup(k->area_cdf[c], rho, inv);
			}
		}
		total += s * half;
	}
	return total * 2.0 / SSS__PI;
}

/* Gauss-Legendre nodes and weights on [-1/2, 1/2], weights summing to 1. */
static const double gl3_x[3] = {-0.3872983346207417, 0.0, 0.3872983346207417};
static const double gl3_w[3] = {5.0 / 18, 8.0 / 18, 5.0 / 18};
static const double gl6_x[6] = {-0.4662347571015760, -0.3306046932331323,
                                -0.1193095930415985, 0.1193095930415985,
                                0.3306046932331323, 0.4662347571015760};
static const double gl6_w[6] = {0.0856622461895852, 0.1803807865240693,
                                0.2339569672863455, 0.2339569672863455,
                                0.1803807865240693, 0.0856622461895852};

/* View-space offset of a point (u, v) pixels from pixel centre at depth z. */
static void view_offset(const sss__projection *p, double du, double dv,
                        double z, double out[2])
{
	double scale = p->ortho ? 1.0 : z;
	out[0] = du / p->fx * scale;
	out[1] = -dv / p->fy * scale;
}

/* Adds the mass of pixel (qx, qy) around the centre (x, y). */
static void add_pixel(const sss__job *job, const sss__kernel *k, int32_t x,
                      int32_t y, int32_t qx, int32_t qy, const double c[3],
                      double acc[3], double wsum[3])
{
	double p[3];
	sss__pixel_position(job, qx, qy, p);
	double dx = p[0] - c[0], dy = p[1] - c[1], dz = p[2] - c[2];
	double d2 = dx * dx + dy * dy + dz * dz;
	double zq = job->depth[qy * job->depth_stride +
	                       (int64_t)qx * job->depth_channels];
	double ppx = sss__pixels_per_unit_x(&job->proj, zq);
	double ppy = sss__pixels_per_unit_y(&job->proj, zq);
	/* The nearest point of the pixel is at most half its diagonal closer. */
	double reach = 0.5 * sqrt(1.0 / (ppx * ppx) + 1.0 / (ppy * ppy));
	if (!(sqrt(d2) - reach < k->support))
		return;
	/* Sub-pixel offsets move the point within the pixel's own facing patch;
	 * in view space the centre-to-pixel vector is known from depth, so
	 * |v + delta|^2 = d^2 + 2 v.delta + |delta|^2 (exact without Position,
	 * and consistent with it when the two agree). */
	double zc = job->depth[y * job->depth_stride +
	                       (int64_t)x * job->depth_channels];
	double vc[2], vq[2];
	view_offset(&job->proj, x + 0.5 - job->proj.cx,
	            y + 0.5 - job->proj.cy, zc, vc);
	view_offset(&job->proj, qx + 0.5 - job->proj.cx,
	            qy + 0.5 - job->proj.cy, zq, vq);
	double vx = vq[0] - vc[0], vy = vq[1] - vc[1];
	int near = abs(qx - x) <= 2 && abs(qy - y) <= 2;
	int n = near ? 6 : 3;
	const double *gx = near ? gl6_x : gl3_x, *gw = near ? gl6_w : gl3_w;
	double mass[3] = {0, 0, 0}, inv = 1.0 / k->support;
	for (int a = 0; a < n; a++) {
		for (int b = 0; b < n; b++) {
			double delta[2];
			view_offset(&job->proj, gx[a], gx[b], zq, delta);
			double s2 = d2 + 2.0 * (vx * delta[0] + vy * delta[1]) +
			            delta[0] * delta[0] + delta[1] * delta[1];
			double d = sqrt(s2 > 0.0 ? s2 : 0.0);
			if (!(d < k->support))
				continue;
			double wgt = gw[a] * gw[b];
			for (int ch = 0; ch < 3; ch++)
				mass[ch] += wgt * sss__table_lookup(k->area[ch], d, inv);
		}
	}
	double area = 1.0 / (ppx * ppy);
	const float *v = job->signal + 3 * ((int64_t)qy * job->width + qx);
	for (int ch = 0; ch < 3; ch++) {
		double wq = area * mass[ch];
		acc[ch] += wq * v[ch];
		wsum[ch] += wq;
	}
}

static void ref_rows(void *vctx, int32_t y0, int32_t y1)
{
	const ref_ctx *ctx = vctx;
	const sss__job *job = ctx->job;
	int32_t w = job->width, h = job->height;
	for (int32_t y = y0; y < y1; y++) {
		for (int32_t x = 0; x < w; x++) {
			int64_t i = (int64_t)y * w + x;
			const float *s = job->signal + 3 * i;
			float *out = job->scratch + 3 * i;
			memcpy(out, s, 3 * sizeof(float));
			int16_t slot = job->slot[i];
			if (slot < 0)
				continue;
			const sss__kernel *k = &job->kernels[slot];
			double z = job->depth[y * job->depth_stride +
			                      (int64_t)x * job->depth_channels];
			double ppx = sss__pixels_per_unit_x(&job->proj, z);
			double ppy = sss__pixels_per_unit_y(&job->proj, z);
			double rx = fmin(fmin(k->support * ppx, job->max_support_px), w);
			double ry = fmin(fmin(k->support * ppy, job->max_support_px), h);
			if (!(rx >= 1.0) && !(ry >= 1.0))
				continue;
			/* One more pixel than the support: a pixel whose centre is
			 * beyond it can still hold some of the profile's mass. */
			int32_t kx = (int32_t)rx + 1, ky = (int32_t)ry + 1;
			double centre[3];
			sss__pixel_position(job, x, y, centre);
			double acc[3] = {0, 0, 0}, wsum[3] = {0, 0, 0};
			for (int c = 0; c < 3; c++) {
				double wc = centre_mass(k, c, 0.5 / ppx, 0.5 / ppy);
				acc[c] += wc * s[c];
				wsum[c] += wc;
			}
			for (int32_t qy = y - ky; qy <= y + ky; qy++) {
				if (qy < 0 || qy >= h)
					continue;
				for (int32_t qx = x - kx; qx <= x + kx; qx++) {
					if (qx < 0 || qx >= w || (qx == x && qy == y))
						continue;
					if (job->slot[(int64_t)qy * w + qx] != slot)
						continue;
					add_pixel(job, k, x, y, qx, qy, centre, acc, wsum);
				}
			}
			for (int c = 0; c < 3; c++)
				if (wsum[c] > 0.0)
					out[c] = (float)(acc[c] / wsum[c]);
		}
	}
}

static void blend_rows(void *vctx, int32_t y0, int32_t y1)
{
	const sss__job *job = ((const ref_ctx *)vctx)->job;
	for (int64_t i = (int64_t)y0 * job->width; i < (int64_t)y1 * job->width;
	     i++)
		if (job->slot[i] >= 0)
			sss__blend_pixel(&job->kernels[job->slot[i]],
			                 job->scratch + 3 * i, job->signal + 3 * i);
}

sss_result sss__reference(const sss__job *job, int32_t num_threads)
{
	ref_ctx ctx = {job};
	sss__parallel_rows(job->height, num_threads, ref_rows, &ctx);
	sss__parallel_rows(job->height, num_threads, blend_rows, &ctx);
	return SSS_OK;
}
