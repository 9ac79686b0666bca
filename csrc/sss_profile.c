/* sss_profile.c - diffusion profiles: Burley and Gaussian sums, their 1-D
 * separable kernels, and the tables the blur loops read.
 *
 * Every profile is a radial density R(r) that integrates to 1 over the
 * plane. The separable method needs a 1-D kernel M(x); we use the MARGINAL
 * of R (its line integral across the blur direction),
 *
 *     M(x) = integral R(sqrt(x^2 + y^2)) dy,
 *
 * rather than R(|x|) sampled along a line (EEVEE, Jimenez): with the
 * marginal, two 1-D passes reproduce the 2-D profile exactly on any light
 * that varies along one direction only (a shadow edge, a terminator), which
 * is where screen-space SSS is looked at; and it is exact for one Gaussian.
 *   Gaussian g2(v): M = g1(v).
 *   Burley: R = (e^{-r/d} + e^{-r/3d}) / (8 pi d r). Since
 *           integral e^{-a sqrt(x^2+y^2)} / sqrt(x^2+y^2) dy = 2 K0(a|x|),
 *           M(x) = (K0(x/d) + K0(x/(3d))) / (4 pi d), which integrates to 1.
 * Jimenez's kernel is defined by sampling his profile along the line, so
 * that kind keeps his construction (line_sampled).
 */
#include "sss_internal.h"

#include <string.h>

/* ------------------------------------------------------------ Bessel K0 */

/* Modified Bessel function K0, Abramowitz & Stegun 9.8.1, 9.8.5, 9.8.6:
 * absolute error < 1e-8 for x <= 2, relative < 2e-7 above. */
static double bessel_k0(double x)
{
	if (x <= 0.0)
		return INFINITY;
	if (x <= 2.0) {
		double u = (x / 3.75) * (x / 3.75);
		double i0 = 1.0 + u * (3.5156229 + u * (3.0899424 + u * (1.2067492
		            + u * (0.2659732 + u * (0.0360768 + u * 0.0045813)))));
		double t = x * x / 4.0;
		return -log(x / 2.0) * i0 + (-0.57721566 + t * (0.42278420
		       + t * (0.23069756 + t * (0.03488590 + t * (0.00262698
		       + t * (0.00010750 + t * 0.00000740))))));
	}
	if (x > 745.0)
		return 0.0; /* e^{-x} underflows double */
	double t = 2.0 / x;
	double p = 1.25331414 + t * (-0.07832358 + t * (0.02189568
	           + t * (-0.01062446 + t * (0.00587872 + t * (-0.00251540
	           + t * 0.00053208)))));
	return exp(-x) / sqrt(x) * p;
}

/* --------------------------------------------------------------- Burley */

double sss_burley_profile(double r, double d)
{
	if (!(d > 0.0) || !(r > 0.0))
		return (r == 0.0 && d > 0.0) ? INFINITY : 0.0;
	return (exp(-r / d) + exp(-r / (3.0 * d))) / (8.0 * SSS__PI * d * r);
}

double sss_burley_cdf(double r, double d)
{
	if (!(d > 0.0))
		return r >= 0.0 ? 1.0 : 0.0;
	if (!(r > 0.0))
		return 0.0;
	return 1.0 - 0.25 * exp(-r / d) - 0.75 * exp(-r / (3.0 * d));
}

double sss_burley_inverse_cdf(double u, double d)
{
	/* Golubev 2018: with the CCDF v = 1 - u,
	 * G = 1 + 4v(2v + sqrt(1 + 4v^2)), r/d = 3 ln((1 + G^-1/3 + G^1/3)/(4v)).
	 * log1p keeps precision where v -> 1 (u -> 0). */
	if (!(u > 0.0) || !(d > 0.0))
		return 0.0;
	if (u >= 1.0)
		return INFINITY;
	double v = 1.0 - u;
	double g = 1.0 + 4.0 * v * (2.0 * v + sqrt(1.0 + 4.0 * v * v));
	double c = cbrt(g);
	double ratio = (1.0 + 1.0 / c + c) / (4.0 * v); /* >= 1 */
	return 3.0 * d * log1p(ratio - 1.0);
}

/* -------------------------------------------------------------- channels */

/* One colour channel of a profile, in scene units. */
typedef struct channel {
	int burley;           /* else a Gaussian sum */
	double d;             /* Burley shape */
	int n;                /* Gaussians */
	double var[SSS_MAX_GAUSSIANS];
	double w[SSS_MAX_GAUSSIANS];      /* 2-D weights, sum 1 */
	double wline[SSS_MAX_GAUSSIANS];  /* weights of g1 in the 1-D kernel */
} channel;

static double channel_area(const channel *ch, double r)
{
	if (ch->burley)
		return sss_burley_profile(r, ch->d);
	double s = 0.0;
	for (int i = 0; i < ch->n; i++)
		s += ch->w[i] * exp(-r * r / (2.0 * ch->var[i])) /
		     (2.0 * SSS__PI * ch->var[i]);
	return s;
}

static double channel_area_cdf(const channel *ch, double r)
{
	if (ch->burley)
		return sss_burley_cdf(r, ch->d);
	double s = 0.0;
	for (int i = 0; i < ch->n; i++)
		s += ch->w[i] * -expm1(-r * r / (2.0 * ch->var[i]));
	return s;
}

static double channel_line(const channel *ch, double x)
{
	if (ch->burley)
		return (bessel_k0(x / ch->d) + bessel_k0(x / (3.0 * ch->d))) /
		       (4.0 * SSS__PI * ch->d);
	double s = 0.0;
	for (int i = 0; i < ch->n; i++)
		s += ch->wline[i] * exp(-x * x / (2.0 * ch->var[i])) /
		     sqrt(2.0 * SSS__PI * ch->var[i]);
	return s;
}

/* Gauss-Legendre, 8 nodes on [-1, 1]. */
static const double gl_x[4] = {0.1834346424956498, 0.5255324099163290,
                               0.7966664774136267, 0.9602898564975363};
static const double gl_w[4] = {0.3626837833783620, 0.3137066238953681,
                               0.2223810344533745, 0.1012285362903763};

/* Integral of the Burley marginal over [a, b], 0 <= a < b, substituting
 * x = t^2 so that K0's log singularity at 0 becomes a zero of 2t M(t^2). */
static double burley_line_integral(const channel *ch, double a, double b)
{
	double ta = sqrt(a), tb = sqrt(b);
	double mid = 0.5 * (ta + tb), half = 0.5 * (tb - ta), s = 0.0;
	for (int i = 0; i < 4; i++) {
		for (int sign = -1; sign <= 1; sign += 2) {
			double t = mid + sign * half * gl_x[i];
			s += gl_w[i] * 2.0 * t * channel_line(ch, t * t);
		}
	}
	return s * half;
}

double sss__burley_line_mass(double a, double b, double d)
{
	if (!(b > a) || !(d > 0.0))
		return 0.0;
	channel ch = {.burley = 1, .d = d};
	return burley_line_integral(&ch, fmax(a, 0.0), b);
}

static double channel_line_cdf_gauss(const channel *ch, double x)
{
	double s = 0.0;
	for (int i = 0; i < ch->n; i++)
		s += ch->wline[i] * 0.5 * erf(x / sqrt(2.0 * ch->var[i]));
	return s;
}

/* Radius holding all but 1e-5 of a Gaussian sum's mass (bisection). */
static double gauss_support(const channel *ch)
{
	double hi = 0.0;
	for (int i = 0; i < ch->n; i++)
		if (ch->w[i] > 0.0 && sqrt(ch->var[i]) * 10.0 > hi)
			hi = sqrt(ch->var[i]) * 10.0;
	double lo = 0.0;
	for (int it = 0; it < 100; it++) {
		double mid = 0.5 * (lo + hi);
		if (1.0 - channel_area_cdf(ch, mid) > 1e-5)
			lo = mid;
		else
			hi = mid;
	}
	return hi;
}

static void gauss_normalise(channel *ch)
{
	double s = 0.0;
	for (int i = 0; i < ch->n; i++)
		s += ch->w[i];
	for (int i = 0; i < ch->n; i++) {
		ch->w[i] = s > 0.0 ? ch->w[i] / s : 0.0;
		ch->wline[i] = ch->w[i];
	}
}

/* Jimenez et al. 2012 (SeparableSSS.cpp): the red column of d'Eon's skin
 * without its first, "directly bounced" Gaussian, r in mm. */
static const double jimenez_var[5] = {0.0484, 0.187, 0.567, 1.99, 7.41};
static const double jimenez_w[5] = {0.100, 0.118, 0.113, 0.358, 0.078};

/* Turns the material's channel c into scene units; returns its support. */
static double channel_make(const sss_material *mat, int c, double len,
                           int32_t taps, channel *ch)
{
	memset(ch, 0, sizeof *ch);
	switch (mat->kind) {
	case SSS_PROFILE_BURLEY: {
		double d[3];
		sss_burley_d(mat, d);
		ch->burley = 1;
		ch->d = d[c] * len;
		/* Blender and Cycles truncate Burley at 16 d (CDF 0.99638). */
		return 16.0 * ch->d;
	}
	case SSS_PROFILE_GAUSSIANS: {
		double mm = 1e-3 * len * mat->gaussian_scale;
		ch->n = mat->gaussian_count;
		for (int i = 0; i < ch->n; i++) {
			ch->var[i] = mat->gaussian_variance[i] * mm * mm;
			ch->w[i] = mat->gaussian_weight[i][c];
		}
		gauss_normalise(ch);
		return mm > 0.0 ? gauss_support(ch) : 0.0;
	}
	case SSS_PROFILE_NEAR_FAR: {
		double mm = 1e-3 * len * mat->scatter_scale;
		ch->n = 2;
		ch->var[0] = pow(mat->near_sigma[c] * mm, 2);
		ch->var[1] = pow(mat->far_sigma[c] * mm, 2);
		ch->w[0] = mat->near_far_balance;
		ch->w[1] = 1.0 - mat->near_far_balance;
		gauss_normalise(ch);
		return mm > 0.0 ? gauss_support(ch) : 0.0;
	}
	case SSS_PROFILE_JIMENEZ: {
		/* Kernel unit o (mm of his profile) lies at o * width / 3 in the
		 * world; falloff stretches r per channel. His term
		 * w e^{-(r/f)^2 / 2v} / (2 pi v) is a 2-D Gaussian of variance
		 * v f^2 carrying mass w f^2; his 1-D kernel samples it along
		 * the line, i.e. g1 weighted by w f^2 / sqrt(2 pi v f^2). */
		double unit = mat->jimenez_width * len / 3.0;
		double f = 0.001 + mat->jimenez_falloff[c];
		ch->n = 5;
		for (int i = 0; i < 5; i++) {
			ch->var[i] = jimenez_var[i] * f * f * unit * unit;
			ch->w[i] = jimenez_w[i] * f * f;
		}
		gauss_normalise(ch);
		for (int i = 0; i < 5; i++)
			ch->wline[i] = ch->var[i] > 0.0
			               ? ch->w[i] / sqrt(2.0 * SSS__PI * ch->var[i])
			               : 0.0;
		/* His kernels span +-2 units (+-3 above 20 taps). */
		return (taps > 20 ? 3.0 : 2.0) * unit;
	}
	default:
		return 0.0;
	}
}

/* ----------------------------------------------------------------- tables */

static double table_x(double support, int k)
{
	double t = (double)k / (SSS__TABLE_SIZE - 1);
	return support * t * t;
}

float sss__table_lookup(const float *table, double x, double inv_support)
{
	double u = sqrt(x * inv_support) * (SSS__TABLE_SIZE - 1);
	if (!(u < SSS__TABLE_SIZE - 1))
		return table[SSS__TABLE_SIZE - 1];
	int i = (int)u;
	float f = (float)(u - i);
	return table[i] + f * (table[i + 1] - table[i]);
}

/* The 1-D CDF from 0, extended as an odd function. */
static void line_cdf3(const sss__kernel *k, double x, double out[3])
{
	double ax = fabs(x), sign = x < 0 ? -1.0 : 1.0;
	double u = sqrt(ax / k->support) * (SSS__TABLE_SIZE - 1);
	if (!(u < SSS__TABLE_SIZE - 1)) {
		for (int c = 0; c < 3; c++)
			out[c] = sign * k->line_cdf[c][SSS__TABLE_SIZE - 1];
		return;
	}
	int i = (int)u;
	double f = u - i;
	for (int c = 0; c < 3; c++) {
		const float *t = k->line_cdf[c];
		out[c] = sign * (t[i] + f * (t[i + 1] - t[i]));
	}
}

void sss__line_mass3(const sss__kernel *k, double a, double b, double out[3])
{
	double lo[3], hi[3];
	line_cdf3(k, a, lo);
	line_cdf3(k, b, hi);
	for (int c = 0; c < 3; c++)
		out[c] = hi[c] - lo[c] > 0.0 ? hi[c] - lo[c] : 0.0;
}

static int32_t odd_taps(int32_t taps)
{
	return (taps % 2) ? taps : taps + 1;
}

sss_result sss__kernel_build(const sss_material *mat, const sss_options *opt,
                             double unit_scale, double max_support,
                             sss__kernel *k)
{
	memset(k, 0, sizeof *k);
	k->texturing = mat->texturing;
	k->taps = odd_taps(mat->taps > 0 ? mat->taps : opt->taps);
	double len = (double)opt->radius_scale / unit_scale; /* metres -> units */
	const double unclamped_len = len;
	if (max_support > 0.0 && mat->kind != SSS_PROFILE_NONE) {
		/* Support grows linearly with len: past the limit every profile
		 * length is shrunk alike, so the kernel keeps its shape. */
		double per_len = 0.0;
		for (int c = 0; c < 3; c++) {
			channel one;
			double s = channel_make(mat, c, 1.0, k->taps, &one);
			if (s > per_len)
				per_len = s;
		}
		if (per_len > 0.0 && per_len * len > max_support)
			len = max_support / per_len;
	}
	k->len = len;

	int any = 0;
	for (int c = 0; c < 3; c++) {
		float s = mat->strength;
		if (mat->kind == SSS_PROFILE_JIMENEZ)
			s *= mat->jimenez_strength[c];
		k->mix[c] = s;
		any |= s > 0.0f;
	}
	if (mat->kind == SSS_PROFILE_NONE || !any)
		return SSS_OK;

	channel ch[3];
	double support = 0.0;
	for (int c = 0; c < 3; c++) {
		double s = channel_make(mat, c, len, k->taps, &ch[c]);
		if (s > support)
			support = s;
		/* The calibration follows the radius Cycles sees, in scene
		 * units and before the reach limit shrank it. */
		channel one;
		double radius = mat->kind == SSS_PROFILE_BURLEY
		                ? mat->radius[c] * unclamped_len
		                : channel_make(mat, c, unclamped_len, k->taps,
		                               &one) / 16.0;
		k->calibration_fade[c] = sss__calibration_fade(radius);
		k->walk_radius[c] = (float)radius;
	}
	sss__calibration_table(mat, k->calibration_gain);
	/* A profile too small for a double, or one that overflowed, does not
	 * scatter: the identity is the right limit of the former, and the
	 * latter was rejected by validation except through radius_scale. */
	if (!(support > 1e-300) || !isfinite(support))
		return SSS_OK;
	k->support = support;

	for (int c = 0; c < 3; c++) {
		const channel *h = &ch[c];
		int empty = h->burley ? !(h->d > 0.0) : 0;
		double cum = 0.0, prev = 0.0;
		for (int i = 0; i < SSS__TABLE_SIZE; i++) {
			double x = table_x(support, i);
			double lcdf = 0, area = 0, acdf = 0;
			if (!empty) {
				/* Node 0 is a singularity for Burley: store node 1. */
				double xs = i == 0 ? table_x(support, 1) : x;
				area = channel_area(h, xs);
				acdf = channel_area_cdf(h, x);
				if (h->burley) {
					if (i > 0)
						cum += burley_line_integral(h, prev, x);
					lcdf = cum;
				} else {
					lcdf = channel_line_cdf_gauss(h, x);
				}
			}
			/* A channel narrower than this kernel's support still has
			 * its mass inside; one with d = 0 has none to spread and
			 * keeps its centre only (weight 1 at x = 0). */
			if (empty) {
				area = 0.0;
				lcdf = 0.5;
				acdf = 1.0;
			}
			k->line_cdf[c][i] = (float)lcdf;
			k->area[c][i] = (float)area;
			k->area_cdf[c][i] = (float)acdf;
			prev = x;
		}
	}
	return SSS_OK;
}

int sss__profile_gaussians(const sss_material *mat, const sss_options *opt,
                           double len, int c,
                           double var[SSS_MAX_GAUSSIANS],
                           double w[SSS_MAX_GAUSSIANS], double *burley_d)
{
	channel ch;
	channel_make(mat, c, len, odd_taps(mat->taps > 0 ? mat->taps : opt->taps),
	             &ch);
	*burley_d = ch.burley ? ch.d : 0.0;
	if (ch.burley)
		return 0;
	for (int i = 0; i < ch.n; i++) {
		var[i] = ch.var[i];
		w[i] = ch.w[i];
	}
	return ch.n;
}

sss_result sss_material_support(const sss_material *mat, double *metres)
{
	if (!mat || !metres)
		return SSS_ERR_INVALID_ARGUMENT;
	sss_material m = *mat;
	m.pass_index = 1; /* the table key plays no part in the shape */
	sss_result r = sss_material_validate(&m, NULL, 0);
	if (r)
		return r;
	double support = 0.0;
	int32_t taps = odd_taps(mat->taps > 0 ? mat->taps : SSS_DEFAULT_TAPS);
	for (int c = 0; c < 3 && mat->kind != SSS_PROFILE_NONE; c++) {
		channel ch;
		double s = channel_make(mat, c, 1.0, taps, &ch);
		if (s > support)
			support = s;
	}
	*metres = support;
	return SSS_OK;
}
