/* test_profile.c - profile math: Burley's CDF and its inverse, the radius
 * mappings, supports, and the 1-D kernels every kind produces. */
#include "test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_SQRT2
#define M_SQRT2 1.41421356237309504880
#endif
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static void test_burley_cdf(void)
{
	const double ds[] = {1e-6, 0.01, 1.0, 250.0};
	for (size_t k = 0; k < sizeof ds / sizeof *ds; k++) {
		double d = ds[k], worst = 0;
		/* u from 1e-6 to 1 - 1e-6, log-spaced at both ends. */
		for (int i = 0; i <= 2000; i++) {
			double t = i / 2000.0;
			double u = t < 0.5 ? pow(10.0, -6 + 12 * t) * 0.5
			                   : 1.0 - pow(10.0, -6 + 12 * (1 - t)) * 0.5;
			if (u < 1e-6)
				u = 1e-6;
			if (u > 1 - 1e-6)
				u = 1 - 1e-6;
			double r = sss_burley_inverse_cdf(u, d);
			double back = sss_burley_cdf(r, d);
			if (fabs(back - u) > worst)
				worst = fabs(back - u);
		}
		CHECK("cdf-roundtrip", worst < 1e-5, "d=%g worst |P(P^-1(u))-u| = %g",
		      d, worst);
	}
	/* Published quantiles of s r (Golubev 2018 / research notes). */
	const double q[][2] = {{0.5, 1.552}, {0.9, 6.062}, {0.99, 12.95},
	                       {0.997, 16.56}};
	for (int i = 0; i < 4; i++) {
		double r = sss_burley_inverse_cdf(q[i][0], 1.0);
		CHECK("cdf-quantile", fabs(r - q[i][1]) < 0.01, "u=%g: r=%g, want %g",
		      q[i][0], r, q[i][1]);
	}
	CHECK("cdf-trunc", fabs(sss_burley_cdf(16.0, 1.0) - 0.996379) < 1e-6,
	      "P(16d) = %.7f", sss_burley_cdf(16.0, 1.0));
	CHECK("cdf-ends", sss_burley_cdf(0, 1) == 0 && sss_burley_cdf(-1, 1) == 0
	      && sss_burley_inverse_cdf(0, 1) == 0, "CDF at 0");
	CHECK("cdf-inf", isinf(sss_burley_inverse_cdf(1.0, 1.0)), "u = 1");
}

/* 2 pi r R(r) integrates to 1 and is the derivative of the CDF. */
static void test_burley_integral(void)
{
	double d = 0.37, sum = 0, worst = 0;
	int n = 200000;
	double rmax = 200 * d, h = rmax / n;
	for (int i = 0; i < n; i++) {
		double r = (i + 0.5) * h;
		double dens = 2 * M_PI * r * sss_burley_profile(r, d);
		sum += dens * h;
		if (i % 1000 == 0) {
			double deriv = (sss_burley_cdf(r + 1e-6, d) -
			                sss_burley_cdf(r - 1e-6, d)) / 2e-6;
			double e = fabs(deriv - dens);
			if (e > worst)
				worst = e;
		}
	}
	CHECK("profile-integral", fabs(sum - 1.0) < 1e-6, "integral %.9f", sum);
	CHECK("profile-derivative", worst < 1e-5, "dP/dr vs 2 pi r R: %g", worst);
	CHECK("profile-zero-d", sss_burley_profile(1.0, 0.0) == 0.0, "d = 0");
}

static void test_mappings(void)
{
	sss_material m;
	sss_material_default(&m, SSS_PROFILE_BURLEY);
	m.radius[0] = 1.0f;
	m.radius[1] = 0.5f;
	m.radius[2] = 0.0f;
	double d[3];
	m.burley_mapping = SSS_BURLEY_CYCLES;
	sss_burley_d(&m, d);
	CHECK("map-cycles", fabs(d[0] - 0.25 / M_PI) < 1e-9 && d[2] == 0,
	      "d = %g", d[0]);
	m.burley_mapping = SSS_BURLEY_EEVEE;
	sss_burley_d(&m, d);
	CHECK("map-eevee", fabs(d[1] - 0.5 * 0.0459101) < 1e-9, "d = %g", d[1]);
	m.burley_mapping = SSS_BURLEY_RANDOM_WALK;
	m.albedo[0] = 0.8f;
	sss_burley_d(&m, d);
	/* Christensen-Burley table: s3(0.8) = 8.38. */
	CHECK("map-rw", fabs(1.0 / d[0] - 8.38) < 0.01, "s = %g", 1.0 / d[0]);

	double support;
	m.burley_mapping = SSS_BURLEY_CYCLES;
	sss_material_support(&m, &support);
	CHECK("support-burley", fabs(support - 16 * 0.25 / M_PI) < 1e-6,
	      "support %g", support);
	sss_material g;
	sss_material_default(&g, SSS_PROFILE_GAUSSIANS);
	g.pass_index = 1;
	g.gaussian_count = 1;
	g.gaussian_variance[0] = 4.0f; /* sigma 2 mm */
	sss_material_support(&g, &support);
	double want = 2e-3 * sqrt(2 * log(1e5));
	CHECK("support-gauss", fabs(support - want) < 1e-6 * want + 1e-9,
	      "support %g, want %g", support, want);
}

/* Every kind, several projections and tap counts: weights sum to 1 per
 * channel, offsets and weights are symmetric, and all are finite. */
static void test_kernels_normalised(void)
{
	int kinds[] = {SSS_PROFILE_BURLEY, SSS_PROFILE_GAUSSIANS,
	               SSS_PROFILE_JIMENEZ, SSS_PROFILE_NEAR_FAR};
	double ppms[] = {10, 1e3, 1e4, 1e5, 1e7};
	int taps[] = {1, 3, 17, 33, 1000};
	int cap = 4200;
	float *off = malloc(cap * sizeof *off), *w = malloc(3 * cap * sizeof *w);
	for (size_t a = 0; a < 4; a++)
		for (size_t b = 0; b < 5; b++)
			for (size_t c = 0; c < 5; c++) {
				sss_material m;
				sss_material_default(&m, kinds[a]);
				m.pass_index = 1;
				int32_t n = cap;
				char id[64];
				snprintf(id, sizeof id, "kernel-%zu.%zu.%zu", a, b, c);
				sss_result r = sss_kernel_1d(&m, ppms[b], taps[c], off, w, &n);
				CHECK(id, r == SSS_OK, "%s", sss_status_name(r));
				/* A kernel within 64 px reads every pixel, whatever
				 * the budget. */
				int dense = n <= 129 && n >= 1 && off[0] == -(n - 1) / 2;
				CHECK(id, n >= 1 && n % 2 == 1 &&
				      (n <= (taps[c] | 1) || dense),
				      "count %d for taps %d", n, taps[c]);
				for (int ch = 0; ch < 3; ch++) {
					double s = 0;
					int finite = 1, sym = 1;
					for (int i = 0; i < n; i++) {
						s += w[3 * i + ch];
						finite &= isfinite(w[3 * i + ch]) && w[3 * i + ch] >= 0;
						sym &= w[3 * i + ch] == w[3 * (n - 1 - i) + ch] &&
						       off[i] == -off[n - 1 - i];
					}
					CHECK(id, fabs(s - 1.0) < 1e-5, "channel %d sums to %.7f",
					      ch, s);
					CHECK(id, finite, "channel %d has a bad weight", ch);
					CHECK(id, sym, "channel %d is not symmetric", ch);
				}
			}
	free(off);
	free(w);
}

/* The Burley 1-D kernel is the profile's marginal, (K0(x/d) + K0(x/3d)) /
 * (4 pi d): compare weight ratios with a direct numerical line integral of
 * R(sqrt(x^2 + y^2)) over y, which does not use K0 at all. */
static double marginal_numeric(double x, double d)
{
	double s = 0, ymax = 40 * d;
	int n = 400000;
	double h = ymax / n;
	for (int i = 0; i < n; i++) {
		double y = (i + 0.5) * h;
		s += 2 * h * sss_burley_profile(sqrt(x * x + y * y), d);
	}
	return s;
}

/* Mass of the marginal over pixel k's cell (Simpson, 9 points). */
static double cell_numeric(int k, double ppm, double d)
{
	double s = 0;
	for (int i = 0; i <= 8; i++) {
		double wt = (i == 0 || i == 8) ? 1 : (i % 2 ? 4 : 2);
		s += wt * marginal_numeric((k - 0.5 + i / 8.0) / ppm, d);
	}
	return s / 24.0 / ppm;
}

static void test_burley_marginal(void)
{
	sss_material m;
	sss_material_default(&m, SSS_PROFILE_BURLEY);
	m.pass_index = 1;
	m.radius[0] = m.radius[1] = m.radius[2] = 1.0f; /* d = 1/(4 pi) m */
	double d = 0.25 / M_PI;
	double ppm = 10.0; /* support 16 d = 1.27 m = 12.7 px: dense */
	float off[64], w[192];
	int32_t n = 64;
	sss_kernel_1d(&m, ppm, 65, off, w, &n);
	CHECK("marginal-dense", n == 27, "count %d", n);
	int c = n / 2;
	double ref1 = cell_numeric(1, ppm, d);
	for (int k = 2; k <= 10; k += 4) {
		double got = w[3 * (c + k)] / w[3 * (c + 1)];
		double want = cell_numeric(k, ppm, d) / ref1;
		CHECK("marginal-ratio", fabs(got / want - 1) < 2e-3,
		      "x=%d px: ratio %g, want %g", k, got, want);
	}
}

/* Jimenez's kernel: quadratic offsets and, before his strength lerp, the
 * centre weights behind his published 17-tap preset (0.536343, 0.624624,
 * 0.748867) = lerp(1, w0, strength). Ours integrates the profile over each
 * tap's cell where he multiplies the cell's width by the value at the tap,
 * so narrow lobes differ by a few percent. */
static void test_jimenez_kernel(void)
{
	sss_material m;
	sss_material_default(&m, SSS_PROFILE_JIMENEZ);
	m.pass_index = 1;
	float off[17], w[51];
	int32_t n = 17;
	double ppm = 1e5; /* support 2 * 0.004 m = 800 px: sparse */
	sss_kernel_1d(&m, ppm, 0, off, w, &n);
	CHECK("jimenez-taps", n == 17, "count %d", n);
	for (int i = 0; i <= 8; i++) {
		double want = 2.0 * (i / 8.0) * (i / 8.0); /* kernel units */
		double got = off[8 + i] / ppm / (m.jimenez_width / 3.0) * 1.0;
		CHECK("jimenez-offsets", fabs(got - want) < 1e-4, "tap %d: %g vs %g",
		      i, got, want);
	}
	const double preset[3] = {0.536343, 0.624624, 0.748867};
	for (int ch = 0; ch < 3; ch++) {
		double s = m.jimenez_strength[ch];
		double w0 = (preset[ch] - 1.0 + s) / s;
		CHECK("jimenez-centre", fabs(w[3 * 8 + ch] / w0 - 1) < 0.08,
		      "channel %d: centre %g, his %g", ch, w[3 * 8 + ch], w0);
	}
}

/* A single Gaussian's 1-D kernel is the 1-D Gaussian's mass per pixel. */
static void test_gaussian_kernel(void)
{
	sss_material m;
	sss_material_default(&m, SSS_PROFILE_GAUSSIANS);
	m.pass_index = 1;
	m.gaussian_count = 1;
	m.gaussian_variance[0] = 1.0f;
	m.gaussian_weight[0][0] = m.gaussian_weight[0][1] =
		m.gaussian_weight[0][2] = 1.0f;
	double ppm = 4000; /* sigma 1 mm = 4 px */
	float off[64], w[192];
	int32_t n = 64;
	sss_kernel_1d(&m, ppm, 63, off, w, &n);
	int c = n / 2;
	double worst = 0;
	for (int k = 1; k < c; k++) {
		/* sigma = 4 px: cell mass from erf. */
		double want = (erf((k + 0.5) / (4 * M_SQRT2)) -
		               erf((k - 0.5) / (4 * M_SQRT2))) /
		              (erf(1.5 / (4 * M_SQRT2)) - erf(0.5 / (4 * M_SQRT2)));
		double got = w[3 * (c + k)] / w[3 * (c + 1)];
		worst = fmax(worst, fabs(got - want));
	}
	CHECK("gauss-shape", worst < 1e-4, "worst ratio error %g", worst);
}

static void test_none_kernel(void)
{
	sss_material m;
	sss_material_default(&m, SSS_PROFILE_BURLEY);
	m.pass_index = 1;
	m.radius[0] = m.radius[1] = m.radius[2] = 0.0f;
	float off[4], w[12];
	int32_t n = 4;
	CHECK_STATUS("zero-radius", SSS_OK, sss_kernel_1d(&m, 1e4, 0, off, w, &n));
	CHECK("zero-radius", n == 1 && w[0] == 1 && w[1] == 1 && w[2] == 1,
	      "count %d", n);
}

int main(void)
{
	test_burley_cdf();
	test_burley_integral();
	test_mappings();
	test_kernels_normalised();
	test_burley_marginal();
	test_jimenez_kernel();
	test_gaussian_kernel();
	test_none_kernel();
	return tu_finish("test_profile");
}
