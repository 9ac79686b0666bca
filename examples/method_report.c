/* method_report.c - how far the separable method is from the brute-force
 * reference for Burley, and what each costs, on synthetic passes.
 *
 *   build/sss-report [SIZE]     (make report: SIZE = 512)
 *
 * The light is what SSS is looked at for: smooth shading with hard shadow
 * edges (horizontal, vertical and diagonal) plus fine noise, on one plane
 * at 2 m. Errors are over the scattering pixels; timings use all cores and
 * are measured in the same run, so their ratio is what to read. */
#include "synth.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return t.tv_sec + 1e-9 * t.tv_nsec;
}

static void fill_light(synth *s)
{
	uint32_t st = 17;
	for (int y = 0; y < s->h; y++)
		for (int x = 0; x < s->w; x++) {
			double u = (double)x / s->w, v = (double)y / s->h;
			double shade = 0.3 + 0.6 * u;                 /* smooth ramp */
			int shadow = (u > 0.45 && u < 0.55) ||        /* vertical bar */
			             (v > 0.30 && v < 0.36) ||        /* horizontal */
			             fabs(u - v - 0.2) < 0.03;        /* diagonal */
			for (int c = 0; c < 3; c++) {
				float n = 0.1f * synth_rand(&st);
				s->diff_dir[3 * ((size_t)y * s->w + x) + c] =
					shadow ? 0.02f + n * 0.1f : (float)shade + n;
			}
		}
}

static double run(const synth *s, const sss_material *m, int method,
                  float *light)
{
	sss_passes p = synth_passes(s);
	sss_camera cam;
	sss_camera_default(&cam);
	sss_options o;
	sss_options_default(&o);
	o.method = method;
	sss_image ol = {light, s->w, s->h, 3, 0};
	char err[256];
	double t0 = now();
	sss_result r = sss_apply(&p, &cam, m, 1, &o, NULL, &ol, err, sizeof err);
	double t = now() - t0;
	if (r) {
		fprintf(stderr, "sss-report: %s: %s\n", sss_status_string(r), err);
		exit(1);
	}
	return t;
}

int main(int argc, char **argv)
{
	int size = argc > 1 ? atoi(argv[1]) : 512;
	if (size < 16 || size > 8192) {
		fprintf(stderr, "usage: sss-report [SIZE 16..8192]\n");
		return 2;
	}
	synth *s = synth_new(size, size);
	synth_plane(s, 0, 0, size, size, 2.0f, 1.0f);
	fill_light(s);
	size_t n = (size_t)3 * size * size;
	float *sep = malloc(n * sizeof *sep), *ref = malloc(n * sizeof *ref);
	double ppm = size * 50.0 / 36.0 / 2.0; /* pixels per metre at 2 m */
	double mean = 0;
	for (size_t i = 0; i < n; i++)
		mean += s->diff_dir[i];
	mean /= n;

	printf("Burley (Cycles mapping), %dx%d, one plane at 2 m, mean light "
	       "%.3f\n", size, size, mean);
	printf("%-10s %-12s %10s %10s %10s %10s %12s %12s %8s\n", "support",
	       "radius (R)", "rms", "rel rms", "max", "p99.9",
	       "separable s", "reference s", "ratio");
	const double support_px[] = {4, 8, 16};
	for (int k = 0; k < 3; k++) {
		sss_material m;
		sss_material_default(&m, SSS_PROFILE_BURLEY);
		m.pass_index = 1;
		double support;
		sss_material_support(&m, &support);
		double scale = support_px[k] / (support * ppm);
		for (int c = 0; c < 3; c++)
			m.radius[c] *= (float)scale;
		double ts = run(s, &m, SSS_METHOD_SEPARABLE, sep);
		double tr = run(s, &m, SSS_METHOD_REFERENCE, ref);
		double sq = 0, worst = 0;
		float *err = malloc(n * sizeof *err);
		for (size_t i = 0; i < n; i++) {
			double d = fabs((double)sep[i] - ref[i]);
			err[i] = (float)d;
			sq += d * d;
			worst = fmax(worst, d);
		}
		/* 99.9th percentile by a histogram over [0, worst]. */
		size_t hist[1000] = {0};
		for (size_t i = 0; i < n; i++)
			hist[worst > 0 ? (size_t)(err[i] / worst * 999) : 0]++;
		size_t acc = 0, b = 0;
		while (b < 999 && (acc += hist[b]) < n * 0.999)
			b++;
		free(err);
		char radius[32];
		snprintf(radius, sizeof radius, "%.2f mm", m.radius[0] * 1e3);
		char sup[32];
		snprintf(sup, sizeof sup, "%.0f px", support_px[k]);
		printf("%-10s %-12s %10.2e %9.3f%% %10.2e %10.2e %12.3f %12.3f "
		       "%7.0fx\n", sup, radius, sqrt(sq / n),
		       100 * sqrt(sq / n) / mean, worst, (b + 1) * worst / 1000, ts,
		       tr, tr / ts);
	}
	free(sep);
	free(ref);
	synth_free(s);
	return 0;
}
