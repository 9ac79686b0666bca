/* sss_process.c - one EXR frame end to end: read, scatter, add the SSS
 * layer, write. Shared by the `sss` command and the Blender add-on so that
 * both take exactly the same path (a frame kept in memory, sss_frame.c,
 * is what it reads into). */
#include "sss_internal.h"

#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

static double now(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

void sss_process_options_default(sss_process_options *opt)
{
	if (!opt)
		return;
	memset(opt, 0, sizeof *opt);
	opt->struct_size = sizeof *opt;
	opt->method = -1;
	opt->radius_scale = 1.0f;
	opt->num_threads = -1;
	sss_exr_options_default(&opt->exr);
	opt->samples = -1;
}

/* Same file, by name or by inode: never write over an input. */
static int same_file(const char *a, const char *b)
{
	struct stat sa, sb;
	if (strcmp(a, b) == 0)
		return 1;
	if (stat(a, &sa) || stat(b, &sb))
		return 0;
	return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

/* The caller's progress_fn, told which stage the EXR options' own
 * progress belongs to. */
typedef struct progress {
	const sss_process_options *opt;
	const char *stage;
} progress;

static void stage_progress(double done, void *user)
{
	const progress *p = user;
	p->opt->progress_fn(p->stage, done, p->opt->progress_user);
}

static void tell(progress *p, const char *stage, double done)
{
	p->stage = stage;
	if (p->opt->progress_fn)
		p->opt->progress_fn(stage, done, p->opt->progress_user);
}

sss_result sss_process_exr(const char *in, const char *out,
                           const sss_scene *scene,
                           const sss_process_options *user_opt,
                           sss_timings *timings, char *err, size_t errlen)
{
	sss_process_options opt;
	sss_process_options_default(&opt);
	if (user_opt)
		opt = *user_opt;
	if (err && errlen)
		err[0] = '\0';
	if (!in || !out || !scene)
		return sss__fail(err, errlen, SSS_ERR_INVALID_ARGUMENT,
		                 "input, output and scene are required");
	sss_result ok = sss__process_options_check(&opt, err, errlen);
	if (ok)
		return ok;
	if (same_file(in, out))
		return sss__fail(err, errlen, SSS_ERR_INVALID_ARGUMENT,
		                 "%s: output is the input file; refusing to "
		                 "overwrite it", in);
	/* The output can be written (its folder takes a new file): said
	 * before the frame is read and scattered, not after. */
	if ((ok = sss_exr_check_output(out, err, errlen)))
		return ok;

	sss_timings t = {0, 0, 0};
	sss_frame *frame = NULL;
	float *combined = NULL, *light = NULL;
	sss_result r;
	progress prog = {&opt, "read"};
	opt.exr.progress_fn = opt.progress_fn ? stage_progress : NULL;
	opt.exr.progress_user = &prog;

	/* The thread count holds for the EXR decode and encode too, unless
	 * the EXR options set their own. */
	if (opt.exr.num_threads == 0)
		opt.exr.num_threads = opt.num_threads >= 0 ? opt.num_threads
		                      : sss_scene_options(scene)->num_threads;

	tell(&prog, "read", 0.0);
	double t0 = now();
	if ((r = sss_frame_read(in, opt.layer, &opt.exr, &frame, err, errlen)))
		goto done;
	t.read = now() - t0;

	/* Before the scatter: whether the result could be written at all. */
	if ((r = sss__frame_check_result(frame, err, errlen)))
		goto done;

	int32_t w = sss_frame_width(frame), h = sss_frame_height(frame);
	size_t n = (size_t)w * (size_t)h;
	combined = malloc(n * 4 * sizeof *combined);
	light = malloc(n * 3 * sizeof *light);
	if (!combined || !light) {
		r = sss__fail(err, errlen, SSS_ERR_OUT_OF_MEMORY, "%s: out of "
		              "memory for a %dx%d frame", in, w, h);
		goto done;
	}

	sss_image oc = {combined, w, h, 4, 0}, ol = {light, w, h, 3, 0};
	sss_process_options scatter_opt = opt;
	scatter_opt.progress_fn = NULL; /* told here, in order */
	tell(&prog, "scatter", 0.0);
	if ((r = sss_frame_scatter(frame, scene, &scatter_opt, &oc, &ol,
	                           &t.scatter, err, errlen)))
		goto done;
	tell(&prog, "scatter", 1.0);
	tell(&prog, "write", 0.0);
	t0 = now();
	if ((r = sss_frame_write(frame, out, combined, light, &opt.exr, err,
	                         errlen)))
		goto done;
	t.write = now() - t0;
done:
	if (timings)
		*timings = t;
	free(combined);
	free(light);
	sss_frame_free(frame);
	return r;
}
