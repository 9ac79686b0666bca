/* sss_bench.c - what the library costs on synthetic render passes.
 *
 *   build/sss-bench [--quick] [--csv FILE]
 *
 * The surface is a sphere-like dome filling the frame (depth changes
 * everywhere, as on a real object), lit by smooth shading with shadow
 * edges and noise. Coverage: the share of pixels whose material scatters
 * (the rest is a non-scattering material). Radius: the kernel's projected
 * half-width in pixels at the centre of the frame. Every figure is the
 * best of several runs; ratios are measured side by side in one run. */
#include "synth.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

static double now(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return t.tv_sec + 1e-9 * t.tv_nsec;
}

#define DEPTH 2.0

/* A dome: depth grows towards the edges like a large sphere's, so every
 * kernel sees depth differences. Coverage: scattering inside a centred
 * ellipse of the given area share (1 = everything). */
static void fill(synth *s, double coverage)
{
	uint32_t st = 17;
	int w = s->w, h = s->h;
	double a2 = coverage >= 1.0 ? INFINITY : coverage * w * h / 3.14159265358979;
	double aspect = (double)w / h;
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			size_t i = (size_t)y * w + x;
			double u = (x + 0.5) / w - 0.5, v = (y + 0.5) / h - 0.5;
			s->depth[i] = (float)(DEPTH + 0.6 * (u * u + v * v));
			double ex = (x + 0.5 - w / 2.0), ey = (y + 0.5 - h / 2.0) * aspect;
			s->index[i] = ex * ex + ey * ey * 1.0 <= a2 * aspect ? 1.0f : 2.0f;
			double shade = 0.3 + 0.6 * (u + 0.5);
			int shadow = fabs(u) < 0.05 || fabs(v + 0.2) < 0.03 ||
			             fabs(u - v - 0.2) < 0.03;
			for (int c = 0; c < 3; c++) {
				float n = 0.1f * synth_rand(&st);
				s->diff_dir[3 * i + c] = shadow ? 0.02f + 0.01f * n
				                                : (float)shade + n;
			}
		}
}

static double covered(const synth *s)
{
	size_t n = 0;
	for (size_t i = 0; i < (size_t)s->w * s->h; i++)
		n += s->index[i] == 1.0f;
	return (double)n / ((size_t)s->w * s->h);
}

/* Burley (skin radii) scaled so that its support spans `px` pixels at the
 * centre of a `w` pixels wide frame; `calibrated`: matched to 4.x's
 * Random Walk (Skin), its radius mapping and energy. */
static sss_material material(double px, int w, int calibrated)
{
	sss_material m;
	sss_material_default(&m, SSS_PROFILE_BURLEY);
	m.pass_index = 1;
	if (calibrated) {
		m.calibration = SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN;
		m.burley_mapping = SSS_BURLEY_CYCLES_RANDOM_WALK;
	}
	double support;
	sss_material_support(&m, &support);
	double ppm = w * 50.0 / 36.0 / DEPTH;
	for (int c = 0; c < 3; c++)
		m.radius[c] *= (float)(px / (support * ppm));
	return m;
}

/* Peak resident memory of this process so far, MiB. */
static double peak_rss_mib(void)
{
	struct rusage u;
	getrusage(RUSAGE_SELF, &u);
	return u.ru_maxrss / 1024.0;
}

static int method_by_name(const char *name)
{
	for (int32_t m = 0; sss_method_name(m); m++)
		if (!strcmp(name, sss_method_name(m)))
			return m;
	fprintf(stderr, "sss-bench: unknown method '%s'\n", name);
	exit(2);
}

static int dump(const char *path, const float *data, size_t n)
{
	FILE *f = fopen(path, "wb");
	if (!f || fwrite(data, sizeof *data, n, f) != n || fclose(f)) {
		fprintf(stderr, "sss-bench: cannot write %s\n", path);
		return 1;
	}
	return 0;
}

typedef struct setup {
	int method, threads, scalar;
} setup;

static double run(const synth *s, const sss_material *m, setup st,
                  float *light, int repeat)
{
	sss_passes p = synth_passes(s);
	sss_camera cam;
	sss_camera_default(&cam);
	sss_options o;
	sss_options_default(&o);
	o.method = st.method;
	o.num_threads = st.threads;
	if (st.scalar)
		setenv("SSS_SIMD", "scalar", 1);
	else
		unsetenv("SSS_SIMD");
	sss_image ol = {light, s->w, s->h, 3, 0};
	char err[256];
	double best = INFINITY;
	for (int k = 0; k < repeat; k++) {
		double t0 = now();
		sss_result r = sss_apply(&p, &cam, m, 1, &o, NULL, &ol, err,
		                         sizeof err);
		double t = now() - t0;
		if (r) {
			fprintf(stderr, "sss-bench: %s: %s\n", sss_status_string(r), err);
			exit(1);
		}
		best = fmin(best, t);
	}
	unsetenv("SSS_SIMD");
	return best;
}

static void usage(void)
{
	fputs("usage: sss-bench [--size W H] [--coverage C] [--radius PX]\n"
	      "                 [--method NAME] [--threads N] [--scalar]\n"
	      "                 [--repeat N] [--rows N] [--dump PREFIX] [--header]\n"
	      "                 [--no-scatter] [--taps N] [--calibrated]\n"
	      "       sss-bench --methods   (the library's methods, one a line)\n"
	      "Prints one CSV line: method,width,height,rows,coverage,radius_px,\n"
	      "threads,simd,seconds,mpx_per_s,ns_per_scattering_px,rss_inputs_mib,\n"
	      "rss_peak_mib. --rows N times only the first N rows (the slow\n"
	      "reference on a band of the frame); --no-scatter gives the material\n"
	      "a pass index no pixel has (what every frame costs: the passes\n"
	      "read and recombined); --taps N sets the material's tap budget\n"
	      "(0: the library's default); --calibrated matches 4.x's Random\n"
	      "Walk (Skin) (the energy calibration at each pixel's view and\n"
	      "curvature); --dump writes PREFIX_light.f32\n"
	      "(RGB), PREFIX_depth.f32, PREFIX_index.f32 and PREFIX_scene.json.\n", stderr);
	exit(2);
}

int main(int argc, char **argv)
{
	int w = 1920, h = 1080, rows = 0, header = 0, no_scatter = 0;
	int calibrated = 0;
	double px = 16;
	int threads = 1, scalar = 0, method = SSS_METHOD_SEPARABLE, repeat = 3, taps = 0;
	const char *method_name = "separable", *dump_prefix = NULL;
	double coverage = 1.0;
	for (int i = 1; i < argc; i++) {
		if (!strcmp(argv[i], "--size") && i + 2 < argc) {
			w = atoi(argv[++i]);
			h = atoi(argv[++i]);
		} else if (!strcmp(argv[i], "--radius") && i + 1 < argc)
			px = atof(argv[++i]);
		else if (!strcmp(argv[i], "--threads") && i + 1 < argc)
			threads = atoi(argv[++i]);
		else if (!strcmp(argv[i], "--coverage") && i + 1 < argc)
			coverage = atof(argv[++i]);
		else if (!strcmp(argv[i], "--scalar"))
			scalar = 1;
		else if (!strcmp(argv[i], "--method") && i + 1 < argc)
			method = method_by_name(method_name = argv[++i]);
		else if (!strcmp(argv[i], "--taps") && i + 1 < argc)
			taps = atoi(argv[++i]);
		else if (!strcmp(argv[i], "--repeat") && i + 1 < argc)
			repeat = atoi(argv[++i]);
		else if (!strcmp(argv[i], "--rows") && i + 1 < argc)
			rows = atoi(argv[++i]);
		else if (!strcmp(argv[i], "--dump") && i + 1 < argc)
			dump_prefix = argv[++i];
		else if (!strcmp(argv[i], "--header"))
			header = 1;
		else if (!strcmp(argv[i], "--no-scatter"))
			no_scatter = 1;
		else if (!strcmp(argv[i], "--calibrated"))
			calibrated = 1;
		else if (!strcmp(argv[i], "--methods")) {
			for (int32_t m = 0; sss_method_name(m); m++)
				puts(sss_method_name(m));
			return 0;
		} else
			usage();
	}
	if (w < 1 || h < 1 || repeat < 1 || !(coverage > 0 && coverage <= 1) ||
	    taps < 0 || taps > 4097)
		usage();
	synth *s = synth_new(w, h);
	fill(s, coverage);
	sss_material m = material(px, w, calibrated);
	m.taps = taps;
	if (no_scatter)
		m.pass_index = 3; /* fill() uses 1 and 2 */
	if (dump_prefix) {
		char path[4096];
		snprintf(path, sizeof path, "%s_light.f32", dump_prefix);
		if (dump(path, s->diff_dir, (size_t)3 * w * h))
			return 1;
		snprintf(path, sizeof path, "%s_depth.f32", dump_prefix);
		if (dump(path, s->depth, (size_t)w * h))
			return 1;
		snprintf(path, sizeof path, "%s_index.f32", dump_prefix);
		if (dump(path, s->index, (size_t)w * h))
			return 1;
		/* The scene for the sss command: the default camera, this
		 * material on pass index 1. */
		snprintf(path, sizeof path, "%s_scene.json", dump_prefix);
		FILE *f = fopen(path, "w");
		if (!f || fprintf(f, "{\"version\": 1, \"camera\": {\"type\": "
		                  "\"PERSP\", \"lens\": 50, \"sensor_width\": 36, "
		                  "\"sensor_fit\": \"AUTO\"}, \"unit_scale\": 1, "
		                  "\"materials\": [{\"pass_index\": 1, \"profile\": "
		                  "\"burley\", \"mapping\": \"%s\", %s\"radius\": "
		                  "[%.9g, %.9g, %.9g]}]}\n",
		                  calibrated ? "cycles-random-walk" : "cycles",
		                  calibrated ? "\"calibration\": "
		                               "\"cycles4-random-walk-skin\", " : "",
		                  m.radius[0], m.radius[1], m.radius[2]) < 0 ||
		    fclose(f)) {
			fprintf(stderr, "sss-bench: cannot write %s\n", path);
			return 1;
		}
	}
	/* A band of the frame (its top rows): the same kind of pixels, fewer
	 * of them; coverage and cost per pixel are the band's. */
	if (rows > 0 && rows < h)
		s->h = rows;
	double cov = no_scatter ? 0.0 : covered(s);
	size_t np = (size_t)s->w * s->h;
	float *light = malloc(3 * np * sizeof *light);
	if (!light)
		return 1;
	/* The output is the caller's, resident before the call like the
	 * inputs (a memset to 0 may become calloc's untouched pages, which
	 * would count as the library's memory). */
	for (size_t i = 0; i < 3 * np; i++)
		light[i] = 1.0f;
	double rss_inputs = peak_rss_mib();
	double t = run(s, &m, (setup){method, threads, scalar}, light, repeat);
	double rss_peak = peak_rss_mib();
	if (header)
		puts("method,width,height,rows,coverage,radius_px,threads,simd,"
		     "seconds,mpx_per_s,ns_per_scattering_px,rss_inputs_mib,"
		     "rss_peak_mib");
	printf("%s,%d,%d,%d,%.4f,%g,%d,%s,%.6f,%.4f,%.3f,%.1f,%.1f\n",
	       method_name, w, h, s->h, cov, px, threads,
	       scalar ? "scalar" : "auto", t, np / t * 1e-6,
	       t / (cov * np) * 1e9, rss_inputs, rss_peak);
	s->h = h;
	free(light);
	synth_free(s);
	return 0;
}
