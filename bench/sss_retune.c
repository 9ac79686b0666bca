/* sss_retune.c - what a live re-tune costs the library: one EXR frame's
 * passes read once (sss_frame_read), then scattered again and again with
 * the scene description at the given radius scales, as a re-tune does.
 *
 *   build/sss-retune PASSES.exr SCENE.json [--threads N] [--repeat N]
 *                    [--radius-scale F]... [--method NAME]
 *
 * Prints one CSV line per radius scale: radius_scale,width,height,
 * threads,best_seconds,median_seconds,mpx_per_s (of the whole frame). */
#include "sss.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return t.tv_sec + 1e-9 * t.tv_nsec;
}

static int by_value(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
	const char *passes = NULL, *scene_path = NULL;
	int threads = 0, repeat = 5, method = -1, nscales = 0;
	float scales[16];
	for (int i = 1; i < argc; i++) {
		if (!strcmp(argv[i], "--threads") && i + 1 < argc)
			threads = atoi(argv[++i]);
		else if (!strcmp(argv[i], "--repeat") && i + 1 < argc)
			repeat = atoi(argv[++i]);
		else if (!strcmp(argv[i], "--radius-scale") && i + 1 < argc &&
		         nscales < 16)
			scales[nscales++] = (float)atof(argv[++i]);
		else if (!strcmp(argv[i], "--method") && i + 1 < argc) {
			const char *name = argv[++i];
			for (int m = 0; sss_method_name(m); m++)
				if (!strcmp(name, sss_method_name(m)))
					method = m;
			if (method < 0) {
				fprintf(stderr, "sss-retune: unknown method %s\n", name);
				return 2;
			}
		} else if (!passes)
			passes = argv[i];
		else if (!scene_path)
			scene_path = argv[i];
		else {
			fprintf(stderr, "sss-retune: unexpected %s\n", argv[i]);
			return 2;
		}
	}
	if (!passes || !scene_path || repeat < 1) {
		fprintf(stderr, "usage: sss-retune PASSES.exr SCENE.json "
		        "[--threads N] [--repeat N] [--radius-scale F]... "
		        "[--method NAME]\n");
		return 2;
	}
	if (!nscales)
		scales[nscales++] = 1.0f;
	char err[1024];
	sss_scene *scene = NULL;
	sss_frame *frame = NULL;
	if (sss_scene_load(scene_path, &scene, NULL, 0, err, sizeof err) ||
	    sss_frame_read(passes, NULL, NULL, &frame, err, sizeof err)) {
		fprintf(stderr, "sss-retune: %s\n", err);
		sss_scene_free(scene);
		return 1;
	}
	int32_t w = sss_frame_width(frame), h = sss_frame_height(frame);
	float *out = malloc((size_t)w * h * 4 * sizeof *out);
	double *times = malloc((size_t)repeat * sizeof *times);
	int rc = 0;
	for (int s = 0; s < nscales && out && times && !rc; s++) {
		sss_process_options opt;
		sss_process_options_default(&opt);
		opt.num_threads = threads;
		opt.method = method;
		opt.radius_scale = scales[s];
		sss_image oc = {out, w, h, 4, 0};
		for (int r = 0; r < repeat && !rc; r++) {
			double t0 = now();
			if (sss_frame_scatter(frame, scene, &opt, &oc, NULL, NULL, err,
			                      sizeof err)) {
				fprintf(stderr, "sss-retune: %s\n", err);
				rc = 1;
			}
			times[r] = now() - t0;
		}
		if (rc)
			break;
		qsort(times, (size_t)repeat, sizeof *times, by_value);
		printf("%g,%d,%d,%d,%.4f,%.4f,%.2f\n", (double)scales[s], w, h,
		       threads, times[0], times[repeat / 2],
		       (double)w * h / times[0] * 1e-6);
	}
	free(out);
	free(times);
	sss_frame_free(frame);
	sss_scene_free(scene);
	return rc;
}
