/* test_methods.c - the per-lobe separable method ("separable-exact") and
 * the disk method against the brute-force reference: accuracy on noise
 * (the hardest light for a separable or sampled kernel), on flat and
 * tilted surfaces, the Burley fit's own error, convergence of the disk
 * method with its sample budget, the `samples` option, and timings. */
#include "sss_internal.h"
#include "synth.h"
#include "test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double ppm_at(int w, double z)
{
	return w * 50.0 / 36.0 / z;
}

/* A material of `kind` whose support spans about `px` pixels at depth z. */
static sss_material material_px(int kind, double px, int w, double z)
{
	sss_material m;
	sss_material_default(&m, kind);
	m.pass_index = 1;
	double support;
	sss_material_support(&m, &support);
	double scale = px / (support * ppm_at(w, z));
	for (int c = 0; c < 3; c++)
		m.radius[c] *= (float)scale;
	m.gaussian_scale *= (float)scale;
	m.jimenez_width *= (float)scale;
	m.scatter_scale *= (float)scale;
	if (kind == SSS_PROFILE_JIMENEZ)
		for (int c = 0; c < 3; c++)
			m.jimenez_strength[c] = 1.0f;
	return m;
}

static double now(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* The scattered light (caller frees); *seconds gets sss_apply's time. */
static float *light_of(const synth *s, const sss_material *m,
                       const sss_options *o, double *seconds)
{
	float *light = calloc((size_t)3 * s->w * s->h, sizeof(float));
	sss_passes p = synth_passes(s);
	sss_camera cam;
	sss_camera_default(&cam);
	sss_image ol = {light, s->w, s->h, 3, 0};
	char err[256] = "";
	double t0 = now();
	sss_result r = sss_apply(&p, &cam, m, 1, o, NULL, &ol, err, sizeof err);
	if (seconds)
		*seconds = now() - t0;
	if (r) {
		printf("sss_apply: %s: %s\n", sss_status_name(r), err);
		free(light);
		return NULL;
	}
	return light;
}

static sss_options options(int method)
{
	sss_options o;
	sss_options_default(&o);
	o.method = method;
	return o;
}

/* max |a - b| and its RMS over the scattering pixels (all here). */
static double compare(const float *a, const float *b, size_t n, double *rms)
{
	double worst = 0, sq = 0;
	for (size_t i = 0; i < n; i++) {
		double d = fabs((double)a[i] - b[i]);
		worst = fmax(worst, d);
		sq += d * d;
	}
	*rms = sqrt(sq / n);
	return worst;
}

static synth *noise_plane(int w, int h, int tilted, uint32_t seed)
{
	synth *s = synth_new(w, h);
	synth_plane(s, 0, 0, w, h, 2.0f, 1.0f);
	if (tilted)
		for (int y = 0; y < h; y++)
			for (int x = 0; x < w; x++)
				s->depth[(size_t)y * w + x] = 2.0f + 0.02f * x + 0.01f * y;
	synth_noise(s, 0, 1, seed);
	return s;
}

/* Method `method` vs the reference on one image: max and RMS; NAN if a
 * call failed. */
static double versus_reference(const synth *s, const sss_material *m,
                               sss_options o, double *rms)
{
	sss_options ro = options(SSS_METHOD_REFERENCE);
	float *a = light_of(s, m, &o, NULL), *b = light_of(s, m, &ro, NULL);
	double worst = NAN;
	*rms = NAN;
	if (a && b)
		worst = compare(a, b, (size_t)3 * s->w * s->h, rms);
	free(a);
	free(b);
	return worst;
}

/* ------------------------------------------------------- Burley's fit */

static void test_burley_fit(void)
{
	static const double truncations[] = {16.0, 32.0, 86.0};
	for (size_t t = 0; t < 3; t++) {
		double T = truncations[t];
		double sigma[SSS_MAX_GAUSSIANS], w[SSS_MAX_GAUSSIANS];
		int n = sss__burley_lobes(T, sigma, w);
		double sum = 0, cdf_err = 0, l1 = 0;
		int positive = 1;
		for (int j = 0; j < n; j++) {
			sum += w[j];
			positive &= w[j] >= 0.0;
		}
		double total = sss_burley_cdf(T, 1.0);
		/* CDF error on a fine grid; L1 distance of the radial densities
		 * 2 pi r R(r) by the midpoint rule. */
		int steps = 200000;
		for (int i = 0; i <= steps; i++) {
			double r = T * i / steps;
			double fit = 0, dens = 0;
			for (int j = 0; j < n; j++) {
				double v = sigma[j] * sigma[j];
				fit += w[j] * -expm1(-r * r / (2 * v));
			}
			cdf_err = fmax(cdf_err, fabs(fit - sss_burley_cdf(r, 1.0) /
			                             total));
			double rm = T * (i + 0.5) / steps;
			if (i < steps) {
				for (int j = 0; j < n; j++) {
					double v = sigma[j] * sigma[j];
					dens += w[j] * rm / v * exp(-rm * rm / (2 * v));
				}
				double want = (exp(-rm) + exp(-rm / 3)) / 4 / total;
				l1 += fabs(dens - want) * T / steps;
			}
		}
		printf("report: burley fit, %d lobes, truncated at %g d: CDF max "
		       "error %.2e, L1 of radial density %.2e\n", n, T, cdf_err,
		       l1);
		char id[48];
		snprintf(id, sizeof id, "burley-fit-%g", T);
		CHECK(id, positive && fabs(sum - 1.0) < 1e-12, "weights: sum %g",
		      sum);
		CHECK(id, cdf_err < 6e-3 && l1 < 5e-2, "CDF error %g, L1 %g",
		      cdf_err, l1);
	}
}

/* -------------------------------------------------- separable-exact */

/* Gaussian sums are exact: flat plane, noise, kernels crossing the
 * borders; also against the ordinary separable method. */
static void test_exact_gaussians(void)
{
	int w = 48, h = 48;
	static const int kinds[] = {SSS_PROFILE_GAUSSIANS, SSS_PROFILE_NEAR_FAR};
	static const char *names[] = {"d'Eon skin", "near/far"};
	for (int k = 0; k < 2; k++)
		for (int px = 8; px <= 16; px += 8) {
			synth *s = noise_plane(w, h, 0, 17);
			sss_material m = material_px(kinds[k], px, w, 2.0);
			sss_options ex = options(SSS_METHOD_SEPARABLE_EXACT);
			ex.taps = 4097; /* dense: every pixel a tap */
			sss_options sep = options(SSS_METHOD_SEPARABLE);
			sep.taps = 4097;
			double rms_ex, rms_sep;
			double max_ex = versus_reference(s, &m, ex, &rms_ex);
			double max_sep = versus_reference(s, &m, sep, &rms_sep);
			printf("report: %s %2d px flat %dx%d noise: separable-exact vs "
			       "reference max %.2e rms %.2e (separable max %.2e rms "
			       "%.2e)\n", names[k], px, w, h, max_ex, rms_ex, max_sep,
			       rms_sep);
			char id[48];
			snprintf(id, sizeof id, "exact-gauss-%d-%d", kinds[k], px);
			CHECK(id, max_ex < 1e-4, "max |exact - reference| = %g", max_ex);
			CHECK(id, rms_ex < rms_sep, "exact rms %g not below separable %g",
			      rms_ex, rms_sep);
			/* The default tap budget (sparse taps for the wide lobes)
			 * stays close. */
			sss_options def = options(SSS_METHOD_SEPARABLE_EXACT);
			double rms_def, max_def = versus_reference(s, &m, def, &rms_def);
			printf("report: %s %2d px flat, default taps: separable-exact "
			       "vs reference max %.2e rms %.2e\n", names[k], px, max_def,
			       rms_def);
			CHECK(id, rms_def < 2e-3, "default taps rms %g", rms_def);
			synth_free(s);
		}
}

/* A tilted plane: depth changes along both axes, so the off-axis factor
 * and the foreshortening come into play; close, not exact. */
static void test_exact_tilted(void)
{
	int w = 48, h = 48;
	synth *s = noise_plane(w, h, 1, 23);
	sss_material m = material_px(SSS_PROFILE_GAUSSIANS, 12, w, 2.0);
	sss_options ex = options(SSS_METHOD_SEPARABLE_EXACT);
	ex.taps = 4097;
	sss_options sep = options(SSS_METHOD_SEPARABLE);
	sep.taps = 4097;
	double rms_ex, rms_sep;
	double max_ex = versus_reference(s, &m, ex, &rms_ex);
	double max_sep = versus_reference(s, &m, sep, &rms_sep);
	printf("report: d'Eon skin 12 px tilted %dx%d noise: separable-exact vs "
	       "reference max %.2e rms %.2e (separable max %.2e rms %.2e)\n", w,
	       h, max_ex, rms_ex, max_sep, rms_sep);
	CHECK("exact-tilted", rms_ex < 3e-3 && max_ex < 3e-2, "max %g rms %g",
	      max_ex, rms_ex);
	CHECK("exact-tilted", rms_ex < rms_sep, "exact rms %g, separable %g",
	      rms_ex, rms_sep);
	synth_free(s);
}

/* Burley and Jimenez through the fit / truncated lobes: report, and the
 * per-lobe method must beat the ordinary separable one on noise. */
static void test_exact_other_profiles(void)
{
	int w = 48, h = 48;
	static const int kinds[] = {SSS_PROFILE_BURLEY, SSS_PROFILE_JIMENEZ};
	static const char *names[] = {"burley", "jimenez"};
	for (int k = 0; k < 2; k++)
		for (int px = 4; px <= 16; px *= 2) {
			synth *s = noise_plane(w, h, 0, 5);
			sss_material m = material_px(kinds[k], px, w, 2.0);
			sss_options ex = options(SSS_METHOD_SEPARABLE_EXACT);
			sss_options sep = options(SSS_METHOD_SEPARABLE);
			double rms_ex, rms_sep;
			double max_ex = versus_reference(s, &m, ex, &rms_ex);
			double max_sep = versus_reference(s, &m, sep, &rms_sep);
			printf("report: %s %2d px flat %dx%d noise: separable-exact vs "
			       "reference max %.2e rms %.2e (separable max %.2e rms "
			       "%.2e)\n", names[k], px, w, h, max_ex, rms_ex, max_sep,
			       rms_sep);
			char id[48];
			snprintf(id, sizeof id, "exact-%s-%d", names[k], px);
			CHECK(id, rms_ex < 0.6 * rms_sep, "exact rms %g, separable %g",
			      rms_ex, rms_sep);
			synth_free(s);
		}
}

/* ------------------------------------------------------------- disk */

/* Error against the reference falls as the budget grows, per profile. */
static void test_disk_convergence(void)
{
	int w = 48, h = 48;
	static const int kinds[] = {SSS_PROFILE_BURLEY, SSS_PROFILE_GAUSSIANS};
	static const char *names[] = {"burley", "d'Eon skin"};
	static const int budgets[] = {4, 16, 64, 256, 1024};
	for (int k = 0; k < 2; k++) {
		synth *s = noise_plane(w, h, 0, 29);
		/* 32 px: a pixel takes up to pi 32^2 / 4 = 804 samples. */
		sss_material m = material_px(kinds[k], 32, w, 2.0);
		double prev = INFINITY;
		for (size_t b = 0; b < sizeof budgets / sizeof *budgets; b++) {
			sss_options o = options(SSS_METHOD_DISK);
			o.samples = budgets[b];
			double rms, worst = versus_reference(s, &m, o, &rms);
			printf("report: %s 32 px flat %dx%d noise: disk, %4d samples, vs "
			       "reference max %.2e rms %.2e\n", names[k], w, h,
			       budgets[b], worst, rms);
			char id[48];
			snprintf(id, sizeof id, "disk-converges-%d-%d", kinds[k],
			         budgets[b]);
			CHECK(id, rms < 0.8 * prev, "rms %g after %g", rms, prev);
			prev = rms;
		}
		CHECK("disk-converged", prev < 0.02, "rms %g at 1024 samples", prev);
		synth_free(s);
	}
}

/* An impulse's light is conserved on average over the pixels' rotations
 * (each sample index lands on the impulse from one pixel in expectation),
 * not exactly: report the spread over 25 impulse positions. (A 12 px
 * kernel takes at most 113 samples, whatever the budget above.) */
static void test_disk_energy(void)
{
	int w = 53, h = 53;
	static const int budgets[] = {16, 64, 1024};
	for (size_t b = 0; b < 3; b++) {
		double total = 0, worst = 0;
		int impulses = 0;
		for (int dy = -2; dy <= 2; dy++)
			for (int dx = -2; dx <= 2; dx++) {
				synth *s = synth_new(w, h);
				synth_plane(s, 0, 0, w, h, 2.0f, 1.0f);
				size_t at = (size_t)(26 + dy) * w + 26 + dx;
				for (int c = 0; c < 3; c++)
					s->diff_dir[3 * at + c] = 1.0f;
				sss_material m = material_px(SSS_PROFILE_BURLEY, 12, w, 2.0);
				sss_options o = options(SSS_METHOD_DISK);
				o.samples = budgets[b];
				float *light = light_of(s, &m, &o, NULL);
				double sum = 0;
				for (size_t i = 0; light && i < (size_t)w * h; i++)
					sum += light[3 * i];
				total += sum;
				worst = fmax(worst, fabs(sum - 1.0));
				impulses++;
				free(light);
				synth_free(s);
			}
		double mean = total / impulses;
		printf("report: disk, %4d samples: an impulse of 1 spreads to %.4f on "
		       "average over %d positions (worst %.4f off)\n", budgets[b],
		       mean, impulses, worst);
		char id[48];
		snprintf(id, sizeof id, "disk-energy-%d", budgets[b]);
		CHECK(id, fabs(mean - 1.0) < (budgets[b] < 64 ? 0.05 : 0.02),
		      "mean %g", mean);
	}
}

/* The option: range checked with the field named; 1 sample is allowed. */
static void test_samples_option(void)
{
	synth *s = noise_plane(8, 8, 0, 3);
	sss_material m = material_px(SSS_PROFILE_BURLEY, 4, 8, 2.0);
	sss_passes p = synth_passes(s);
	sss_camera cam;
	sss_camera_default(&cam);
	float light[3 * 64];
	sss_image ol = {light, 8, 8, 3, 0};
	static const int32_t values[] = {0, -1, 4097, 1, 4096};
	for (size_t i = 0; i < 5; i++) {
		sss_options o = options(SSS_METHOD_DISK);
		o.samples = values[i];
		char err[256] = "";
		sss_result r = sss_apply(&p, &cam, &m, 1, &o, NULL, &ol, err,
		                         sizeof err);
		char id[48];
		snprintf(id, sizeof id, "samples-%d", values[i]);
		if (i < 3)
			CHECK(id, r == SSS_ERR_INVALID_ARGUMENT &&
			      strstr(err, "samples") != NULL, "%s: '%s'",
			      sss_status_name(r), err);
		else
			CHECK(id, r == SSS_OK, "%s: %s", sss_status_name(r), err);
	}
	sss_options d;
	sss_options_default(&d);
	CHECK("samples-default", d.samples == 64 &&
	      d.struct_size == sss_struct_size("sss_options"), "%d", d.samples);
	synth_free(s);
}

/* ------------------------------------------------------------ timings */

/* All four methods on one 128x128 frame (Burley, 16 px kernel, default
 * taps and samples, one thread), with the error of each against the
 * reference. */
static void test_timings(void)
{
	int w = 128, h = 128;
	synth *s = noise_plane(w, h, 0, 31);
	sss_material m = material_px(SSS_PROFILE_BURLEY, 16, w, 2.0);
	static const int order[] = {SSS_METHOD_REFERENCE, SSS_METHOD_SEPARABLE,
	                            SSS_METHOD_SEPARABLE_EXACT, SSS_METHOD_DISK};
	static const char *names[] = {"reference", "separable",
	                              "separable-exact", "disk"};
	float *ref = NULL;
	for (int i = 0; i < 4; i++) {
		sss_options o = options(order[i]);
		o.num_threads = 1;
		double t;
		float *light = light_of(s, &m, &o, &t);
		double rms = 0, worst = 0;
		if (i == 0)
			ref = light;
		else if (light && ref)
			worst = compare(light, ref, (size_t)3 * w * h, &rms);
		printf("report: timing %dx%d burley 16 px, 1 thread: %-15s %7.3f s, "
		       "vs reference max %.2e rms %.2e\n", w, h, names[i], t, worst,
		       rms);
		CHECK("timing", light != NULL, "%s failed", names[i]);
		if (i)
			free(light);
	}
	free(ref);
	synth_free(s);
}

int main(void)
{
	test_burley_fit();
	test_exact_gaussians();
	test_exact_tilted();
	test_exact_other_profiles();
	test_disk_convergence();
	test_disk_energy();
	test_samples_option();
	test_timings();
	return tu_finish("test_methods");
}
