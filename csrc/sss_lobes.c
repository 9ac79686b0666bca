/* sss_lobes.c - the per-lobe separable method ("separable-exact"): two 1-D
 * passes for every Gaussian lobe of the profile, summed with the lobes'
 * weights.
 *
 * A 2-D Gaussian factorises, exp(-(x^2 + y^2) / 2v) = exp(-x^2 / 2v)
 * exp(-y^2 / 2v), so a horizontal then a vertical 1-D pass reproduce one
 * lobe exactly; running them per lobe makes the method exact for any sum
 * of Gaussians (d'Eon's skin, near/far, Jimenez's five Gaussians), where
 * the ordinary separable method convolves the mixed 1-D kernel with itself
 * and blurs too much in the diagonals. A tap's weight for lobe i is its
 * cell's exact 1-D mass (normal CDF) at the screen-axis distance a (view space,
 * from depth) between the two surface points, times exp(-o^2 / 2v_i) for
 * the rest of their true 3-D distance d (o^2 = d^2 - a^2: the depth
 * difference and the off-axis drift): that is the 3-D Gaussian's own
 * factor for the off-axis part.
 *
 * The passes are NOT normalised per lobe: each keeps its weighted sum and
 * its weight sum per channel, and the pixel's result is
 * sum_i w_i A_i / sum_i w_i W_i. On a flat surface with nothing rejected
 * (also at the image's borders, where the rejection is itself separable)
 * this is exactly the 2-D sum the reference computes, each pixel weighted
 * by the profile's exact mass over its square; near materials and depth
 * steps the mixture is renormalised as a whole, like the reference does.
 *
 * Burley's profile is not a Gaussian sum. It is fitted, per channel and
 * per kernel build, with SSS__BURLEY_LOBES Gaussians of fixed standard
 * deviations sigma_j = c_j d (c_j found once by a nonlinear least-squares
 * fit of the CDF of Burley truncated at 16 d, see burley_sigma) and
 * weights from a non-negative least-squares fit to that channel's radial
 * CDF truncated at the kernel's support, then normalised to 1 so every
 * channel conserves its light. Fit error (tests/test_methods.c measures it
 * again): radial CDF within 3.5e-3 of Burley's (4.8e-3 for channels whose
 * truncation lies further out), L1 distance of the radial densities 3.9e-2
 * (4.3e-2); most of that is below a tenth of d, where Burley's 1/r
 * singularity meets Gaussians that are flat at the centre.
 *
 * Cost: two passes per lobe, each as wide as that lobe (about 4.5 sigma)
 * and at most `taps` taps; memory: 12 floats per pixel besides the
 * caller's scratch.
 */
#include "sss_internal.h"

#include <stdlib.h>
#include <string.h>

#define MAX_LOBES SSS_MAX_GAUSSIANS

/* A lobe reaches LOBE_CUT standard deviations: the 1-D tail beyond is
 * 6.8e-6 of its mass, and the reference drops no more than 1e-5. */
#define LOBE_CUT 4.5

/* Burley in units of d: standard deviations of the fitted lobes (nonlinear
 * fit of the CDF at 256 points r = 16 d (k/255)^2, numpy/scipy). */
static const double burley_sigma[SSS__BURLEY_LOBES] = {
	0.028921, 0.147521, 0.436543, 1.045810, 2.297590, 4.828094,
};

typedef struct lobe {
	double weight[3];   /* 2-D mass of this lobe per channel */
	double sigma[3];    /* scene units */
	double inv_sigma[3];
	double exp_k[3];    /* 1 / (2 sigma^2) */
	double reach;       /* scene units: LOBE_CUT sigma, at most the support */
	int shared;         /* the same sigma in every channel that uses it */
} lobe;

typedef struct lobe_set {
	int count;
	lobe lobes[MAX_LOBES];
} lobe_set;

/* ------------------------------------------------------------ the fit */

/* Solves G_PP z_P = g_P on the passive set (Gaussian elimination with
 * partial pivoting); z is 0 outside it. Returns 0 if singular. */
static int solve_passive(int n, double G[MAX_LOBES][MAX_LOBES],
                         const double *g, const int *passive, double *z)
{
	int idx[MAX_LOBES], m = 0;
	double a[MAX_LOBES][MAX_LOBES + 1];
	for (int i = 0; i < n; i++) {
		z[i] = 0.0;
		if (passive[i])
			idx[m++] = i;
	}
	for (int r = 0; r < m; r++) {
		for (int c = 0; c < m; c++)
			a[r][c] = G[idx[r]][idx[c]];
		a[r][m] = g[idx[r]];
	}
	for (int col = 0; col < m; col++) {
		int piv = col;
		for (int r = col + 1; r < m; r++)
			if (fabs(a[r][col]) > fabs(a[piv][col]))
				piv = r;
		if (!(fabs(a[piv][col]) > 0.0))
			return 0;
		if (piv != col)
			for (int c = 0; c <= m; c++) {
				double t = a[col][c];
				a[col][c] = a[piv][c];
				a[piv][c] = t;
			}
		for (int r = col + 1; r < m; r++) {
			double f = a[r][col] / a[col][col];
			for (int c = col; c <= m; c++)
				a[r][c] -= f * a[col][c];
		}
	}
	for (int r = m - 1; r >= 0; r--) {
		double s = a[r][m];
		for (int c = r + 1; c < m; c++)
			s -= a[r][c] * z[idx[c]];
		z[idx[r]] = s / a[r][r];
	}
	return 1;
}

/* min |A x - b| subject to x >= 0, from the normal equations G = A^T A,
 * g = A^T b (Lawson & Hanson 1974, ch. 23), n <= MAX_LOBES. */
static void nnls(int n, double G[MAX_LOBES][MAX_LOBES], const double *g,
                 double *x)
{
	int passive[MAX_LOBES] = {0};
	double gmax = 0.0;
	for (int i = 0; i < n; i++) {
		x[i] = 0.0;
		gmax = fmax(gmax, fabs(g[i]));
	}
	for (int outer = 0; outer < 4 * n; outer++) {
		int t = -1;
		double best = 1e-12 * gmax;
		for (int j = 0; j < n; j++) {
			if (passive[j])
				continue;
			double wj = g[j];
			for (int i = 0; i < n; i++)
				wj -= G[j][i] * x[i];
			if (wj > best) {
				best = wj;
				t = j;
			}
		}
		if (t < 0)
			return;
		passive[t] = 1;
		for (int inner = 0; inner < 4 * n; inner++) {
			double z[MAX_LOBES];
			if (!solve_passive(n, G, g, passive, z))
				return;
			int feasible = 1;
			for (int j = 0; j < n; j++)
				if (passive[j] && !(z[j] > 0.0))
					feasible = 0;
			if (feasible) {
				memcpy(x, z, sizeof(double) * n);
				break;
			}
			double alpha = 1.0;
			for (int j = 0; j < n; j++)
				if (passive[j] && !(z[j] > 0.0) && x[j] - z[j] > 0.0)
					alpha = fmin(alpha, x[j] / (x[j] - z[j]));
			for (int j = 0; j < n; j++) {
				x[j] += alpha * (z[j] - x[j]);
				if (passive[j] && !(x[j] > 1e-15)) {
					passive[j] = 0;
					x[j] = 0.0;
				}
			}
		}
	}
}

int sss__burley_lobes(double truncate, double sigma[], double weight[])
{
	enum { K = 256 };
	int n = SSS__BURLEY_LOBES;
	double G[MAX_LOBES][MAX_LOBES] = {{0}}, g[MAX_LOBES] = {0};
	double total = sss_burley_cdf(truncate, 1.0);
	for (int k = 0; k < K; k++) {
		double t = (double)k / (K - 1);
		double x = truncate * t * t;
		double target = sss_burley_cdf(x, 1.0) / total;
		double basis[MAX_LOBES];
		for (int j = 0; j < n; j++)
			basis[j] = -expm1(-x * x / (2.0 * burley_sigma[j] *
			                             burley_sigma[j]));
		for (int i = 0; i < n; i++) {
			g[i] += basis[i] * target;
			for (int j = 0; j < n; j++)
				G[i][j] += basis[i] * basis[j];
		}
	}
	nnls(n, G, g, weight);
	double sum = 0.0;
	for (int j = 0; j < n; j++) {
		sigma[j] = burley_sigma[j];
		sum += weight[j];
	}
	for (int j = 0; j < n; j++)
		weight[j] = sum > 0.0 ? weight[j] / sum : 0.0;
	return n;
}

/* The lobes of material m, whose kernel k has support > 0. */
static void lobes_build(const sss_material *mat, const sss_options *opt,
                        const sss__kernel *k, lobe_set *set)
{
	double var[3][MAX_LOBES], w[3][MAX_LOBES];
	int n = 0;
	memset(set, 0, sizeof *set);
	for (int c = 0; c < 3; c++) {
		double d;
		int nc = sss__profile_gaussians(mat, opt, k->len, c, var[c], w[c],
		                                &d);
		if (nc == 0) { /* Burley: fit this channel */
			double sigma[MAX_LOBES];
			nc = SSS__BURLEY_LOBES;
			if (d > 0.0 && isfinite(k->support / d)) {
				sss__burley_lobes(k->support / d, sigma, w[c]);
				for (int j = 0; j < nc; j++)
					var[c][j] = (sigma[j] * d) * (sigma[j] * d);
			} else { /* a channel that does not scatter */
				for (int j = 0; j < nc; j++)
					var[c][j] = w[c][j] = 0.0;
			}
		}
		n = nc;
	}
	for (int j = 0; j < n; j++) {
		lobe *L = &set->lobes[set->count];
		double widest = 0.0, first = -1.0;
		int any = 0;
		L->shared = 1;
		for (int c = 0; c < 3; c++) {
			/* A channel that does not scatter (Burley d = 0) keeps its
			 * light: it takes no part in any lobe. */
			double wc = k->mix[c] > 0.0f && var[c][j] > 0.0 ? w[c][j] : 0.0;
			double s = sqrt(var[c][j]);
			L->weight[c] = wc;
			L->sigma[c] = s;
			L->inv_sigma[c] = wc > 0.0 ? 1.0 / s : 0.0;
			L->exp_k[c] = wc > 0.0 ? 1.0 / (2.0 * s * s) : 0.0;
			if (wc > 0.0) {
				any = 1;
				widest = fmax(widest, s);
				if (first < 0.0)
					first = s;
				else if (s != first)
					L->shared = 0;
			}
		}
		if (!any || !isfinite(L->inv_sigma[0] + L->inv_sigma[1] +
		                      L->inv_sigma[2]))
			continue;
		L->reach = fmin(LOBE_CUT * widest, k->support);
		set->count++;
	}
}

/* ------------------------------------------------------------ the blur */

#define MAX_HALF_TAPS SSS__MAX_HALF_TAPS

/* The standard normal CDF minus 1/2, tabulated on [0, PHI_MAX] once per
 * call (linear interpolation: error below 1e-8; beyond 8 sigma the tail is
 * 6e-16): an erf per tap and channel would triple the method's cost. */
#define PHI_MAX 8.0
#define PHI_N 16384

static double phi(const double *tab, double t)
{
	double a = fabs(t) * (PHI_N / PHI_MAX), v = 0.5;
	if (a < PHI_N) {
		int i = (int)a;
		v = tab[i] + (a - i) * (tab[i + 1] - tab[i]);
	}
	return t < 0.0 ? -v : v;
}

typedef struct pass_ctx {
	const double *phi;    /* PHI_N + 1 entries */
	const sss__job *job;
	const lobe_set *sets; /* per kernel */
	int lobe;
	int vertical;
	float *h;             /* 6 floats per pixel: the horizontal A, W */
	float *acc;           /* 6 floats per pixel: sum_i w_i A_i, w_i W_i */
} pass_ctx;

static double depth_at(const sss__job *job, int32_t x, int32_t y)
{
	return job->depth[y * job->depth_stride +
	                  (int64_t)x * job->depth_channels];
}

/* The pixel's view-space coordinate along the pass's axis, from depth. */
static double axis_coord(const sss__job *job, int vertical, int32_t x,
                         int32_t y, double z)
{
	const sss__projection *p = &job->proj;
	double scale = p->ortho ? 1.0 : z;
	return vertical ? (p->cy - (y + 0.5)) / p->fy * scale
	                : (x + 0.5 - p->cx) / p->fx * scale;
}

/* The lobe's 1-D mass over [lo, hi] (scene units) in each channel. */
static void cell_mass(const double *tab, const lobe *L, double lo, double hi,
                      double m[3])
{
	for (int c = 0; c < 3; c++) {
		if (!(L->weight[c] > 0.0)) {
			m[c] = 0.0;
			continue;
		}
		if (c > 0 && L->shared && L->weight[c - 1] > 0.0) {
			m[c] = m[c - 1];
			continue;
		}
		double k = L->inv_sigma[c];
		m[c] = phi(tab, hi * k) - phi(tab, lo * k);
	}
}

static void lobe_pixel(const pass_ctx *ctx, int16_t slot, int32_t x,
                       int32_t y)
{
	const sss__job *job = ctx->job;
	const sss__kernel *k = &job->kernels[slot];
	const lobe *L = &ctx->sets[slot].lobes[ctx->lobe];
	int vert = ctx->vertical;
	int32_t extent = vert ? job->height : job->width;
	int32_t pos = vert ? y : x;
	int64_t i = (int64_t)y * job->width + x;
	double zc = depth_at(job, x, y);
	double ppu = vert ? sss__pixels_per_unit_y(&job->proj, zc)
	                  : sss__pixels_per_unit_x(&job->proj, zc);
	double r = fmin(fmin(L->reach * ppu, job->max_support_px), extent);
	double centre[3];
	sss__pixel_position(job, x, y, centre);
	double ac = axis_coord(job, vert, x, y, zc);
	double py_ratio = sss__pixels_per_unit_y(&job->proj, zc);

	/* a[0..2]: weighted sums, a[3..5]: weight sums. */
	double a[6] = {0, 0, 0, 0, 0, 0}, m[3];
	sss__tap t[MAX_HALF_TAPS + 1]; /* the separable method's layout */
	int32_t n = sss__tap_layout(k->taps, r, t);
	double upp = 1.0 / ppu;
	cell_mass(ctx->phi, L, t[0].lo * upp, t[0].hi * upp, m);
	const float *src = vert ? ctx->h + 6 * i : job->signal + 3 * i;
	for (int c = 0; c < 3; c++) {
		a[c] += m[c] * src[c];
		a[3 + c] += vert ? m[c] * src[3 + c] : m[c];
	}
	for (int32_t ti = 1; ti <= n; ti++) {
		double below = t[ti].offset - t[ti].lo;
		double above = t[ti].hi - t[ti].offset;
		for (int sign = -1; sign <= 1; sign += 2) {
			double at = pos + sign * t[ti].offset;
			double fl = floor(at), f = at - fl;
			for (int e = 0; e < 2; e++) {
				int32_t q = (int32_t)fl + e;
				double share = e ? f : 1.0 - f;
				if (share <= 0.0 || q < 0 || q >= extent)
					continue;
				int32_t qx = vert ? x : q, qy = vert ? q : y;
				int64_t j = (int64_t)qy * job->width + qx;
				if (job->slot[j] != slot)
					continue;
				double p[3];
				sss__pixel_position(job, qx, qy, p);
				double dx = p[0] - centre[0], dy = p[1] - centre[1],
				       dz = p[2] - centre[2];
				double d2 = dx * dx + dy * dy + dz * dz;
				double zq = depth_at(job, qx, qy);
				double uq = 1.0 / (vert ? sss__pixels_per_unit_y(&job->proj,
				                                                  zq)
				                        : sss__pixels_per_unit_x(&job->proj,
				                                                  zq));
				/* Beyond the support in true 3-D distance: dropped, as
				 * every method drops it. */
				if (!(sqrt(d2) - below * uq < k->support))
					continue;
				double along = fabs(axis_coord(job, vert, qx, qy, zq) - ac);
				double off2 = d2 - along * along;
				cell_mass(ctx->phi, L, along - below * uq,
				          along + above * uq, m);
				/* The vertical pass will weigh this pixel with the cell
				 * height of the centre's row; the pixel's own height
				 * differs by its depth (perspective): correct it here,
				 * so that the pair of passes weighs each pixel by its
				 * own area, as the reference does. */
				double tall = vert ? 1.0 : py_ratio / sss__pixels_per_unit_y(
				                                      &job->proj, zq);
				const float *v = vert ? ctx->h + 6 * j : job->signal + 3 * j;
				for (int c = 0; c < 3; c++) {
					double wc = share * tall * m[c];
					if (off2 > 0.0 && wc > 0.0)
						wc *= exp(-off2 * L->exp_k[c]);
					a[c] += wc * v[c];
					a[3 + c] += vert ? wc * v[3 + c] : wc;
				}
			}
		}
	}
	if (!vert) {
		float *o = ctx->h + 6 * i;
		for (int c = 0; c < 6; c++)
			o[c] = (float)a[c];
	} else {
		float *o = ctx->acc + 6 * i;
		for (int c = 0; c < 3; c++) {
			o[c] += (float)(L->weight[c] * a[c]);
			o[3 + c] += (float)(L->weight[c] * a[3 + c]);
		}
	}
}

static void pass_rows(void *vctx, int32_t y0, int32_t y1)
{
	const pass_ctx *ctx = vctx;
	const sss__job *job = ctx->job;
	for (int32_t y = y0; y < y1; y++)
		for (int32_t x = 0; x < job->width; x++) {
			int16_t slot = job->slot[(int64_t)y * job->width + x];
			if (slot >= 0 && ctx->lobe < ctx->sets[slot].count)
				lobe_pixel(ctx, slot, x, y);
		}
}

/* acc -> the blurred light, blended into the signal. */
static void finish_rows(void *vctx, int32_t y0, int32_t y1)
{
	const pass_ctx *ctx = vctx;
	const sss__job *job = ctx->job;
	for (int32_t y = y0; y < y1; y++)
		for (int32_t x = 0; x < job->width; x++) {
			int64_t i = (int64_t)y * job->width + x;
			int16_t slot = job->slot[i];
			if (slot < 0)
				continue;
			const sss__kernel *k = &job->kernels[slot];
			double z = depth_at(job, x, y);
			/* Like the other methods: nothing but the centre within
			 * reach is the identity. */
			if (!(k->support * sss__pixels_per_unit_x(&job->proj, z) >= 1.0)
			    && !(k->support * sss__pixels_per_unit_y(&job->proj, z) >=
			         1.0))
				continue;
			float *s = job->signal + 3 * i;
			const float *o = ctx->acc + 6 * i;
			float b[3];
			for (int c = 0; c < 3; c++)
				b[c] = o[3 + c] > 0.0f ? (float)((double)o[c] / o[3 + c])
				                       : s[c];
			sss__blend_pixel(k, b, s);
		}
}

sss_result sss__separable_exact(const sss__job *job,
                                const sss_material *materials,
                                int32_t material_count,
                                const sss_options *opt)
{
	size_t npix = (size_t)job->width * (size_t)job->height;
	lobe_set *sets = calloc(material_count ? material_count : 1,
	                        sizeof *sets);
	float *h = malloc(npix * 6 * sizeof *h);
	float *acc = calloc(npix * 6, sizeof *acc);
	double *tab = malloc((PHI_N + 1) * sizeof *tab);
	if (!sets || !h || !acc || !tab) {
		free(sets);
		free(h);
		free(acc);
		free(tab);
		return SSS_ERR_OUT_OF_MEMORY;
	}
	for (int i = 0; i <= PHI_N; i++)
		tab[i] = 0.5 * erf(i * (PHI_MAX / PHI_N) / sqrt(2.0));
	int most = 0;
	for (int32_t m = 0; m < material_count; m++) {
		if (!(job->kernels[m].support > 0.0))
			continue;
		lobes_build(&materials[m], opt, &job->kernels[m], &sets[m]);
		if (sets[m].count > most)
			most = sets[m].count;
	}
	pass_ctx ctx = {tab, job, sets, 0, 0, h, acc};
	for (int l = 0; l < most; l++) {
		ctx.lobe = l;
		ctx.vertical = 0;
		sss__parallel_rows(job->height, opt->num_threads, pass_rows, &ctx);
		ctx.vertical = 1;
		sss__parallel_rows(job->height, opt->num_threads, pass_rows, &ctx);
	}
	sss__parallel_rows(job->height, opt->num_threads, finish_rows, &ctx);
	free(sets);
	free(h);
	free(acc);
	free(tab);
	return SSS_OK;
}
