/* sss_process.c - one EXR frame end to end: read, scatter, add the SSS
 * layer, write. Shared by the `sss` command and the Blender add-on so that
 * both take exactly the same path. */
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

/* The library passes pixels with a bad depth through one by one; a Depth
 * pass without a single usable value is a broken file. */
static int has_usable_depth(const sss_image *depth)
{
	int64_t stride = depth->row_stride ? depth->row_stride
	                 : (int64_t)depth->width * depth->channels;
	for (int32_t y = 0; y < depth->height; y++)
		for (int32_t x = 0; x < depth->width; x++) {
			float z = depth->data[y * stride + (int64_t)x * depth->channels];
			if (z > 0.0f && z < 3.0e38f)
				return 1;
		}
	return 0;
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

/* The back-light layer's passes (SSS_BACKLIGHT_LAYER: DiffDir, DiffInd and
 * the thickness and facing AOVs) into passes; a thickness stored squared
 * becomes its square root in *thick_buf (allocated). No layer: nothing. */
static sss_result back_light_passes(const sss_exr *exr, const char *layer,
                                    sss_passes *passes, float **thick_buf,
                                    const char *in, char *err, size_t errlen)
{
	sss_image v;
	if (strcmp(layer, SSS_BACKLIGHT_LAYER) == 0 ||
	    sss_exr_find(exr, SSS_BACKLIGHT_LAYER, "DiffDir", &v) != SSS_OK)
		return SSS_OK;
	if (v.channels < 3)
		return sss__fail(err, errlen, SSS_ERR_MISSING_PASS, "%s: layer '%s'"
		                 ": pass DiffDir has %d channel(s), needs RGB", in,
		                 SSS_BACKLIGHT_LAYER, v.channels);
	passes->back_dir = v;
	if (sss_exr_find(exr, SSS_BACKLIGHT_LAYER, "DiffInd", &v) == SSS_OK &&
	    v.channels >= 3)
		passes->back_ind = v;
	if (sss_exr_find(exr, SSS_BACKLIGHT_LAYER, SSS_FACING_PASS, &v) ==
	    SSS_OK)
		passes->facing = v;
	if (sss_exr_find(exr, SSS_BACKLIGHT_LAYER, SSS_THICKNESS_PASS, &v) ==
	    SSS_OK) {
		passes->thickness = v;
		return SSS_OK;
	}
	if (sss_exr_find(exr, SSS_BACKLIGHT_LAYER, SSS_THICKNESS_SQ_PASS, &v) !=
	    SSS_OK)
		return SSS_OK; /* sss_apply names the missing thickness */
	int64_t stride = v.row_stride ? v.row_stride
	                 : (int64_t)v.width * v.channels;
	float *t = malloc((size_t)v.width * (size_t)v.height * sizeof *t);
	if (!t)
		return sss__fail(err, errlen, SSS_ERR_OUT_OF_MEMORY, "%s: out of "
		                 "memory for the thickness pass", in);
	/* The mean of t^2 over the samples: its root is the thickness; a
	 * slightly negative value (filter noise) is 0, NaN stays NaN. */
	for (int32_t y = 0; y < v.height; y++)
		for (int32_t x = 0; x < v.width; x++) {
			float sq = v.data[y * stride + (int64_t)x * v.channels];
			t[(size_t)y * v.width + x] = sq > 0.0f ? sqrtf(sq)
			                             : sq <= 0.0f ? 0.0f : sq;
		}
	*thick_buf = t;
	passes->thickness = (sss_image){t, v.width, v.height, 1, 0};
	return SSS_OK;
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
	if (opt.struct_size != sizeof opt)
		return sss__fail(err, errlen, SSS_ERR_INVALID_ARGUMENT,
		                 "process options: struct_size %u, expected %zu",
		                 opt.struct_size, sizeof opt);
	if (!(isfinite(opt.radius_scale) && opt.radius_scale >= 0.0f))
		return sss__fail(err, errlen, SSS_ERR_INVALID_ARGUMENT,
		                 "radius scale %g must be finite and >= 0",
		                 (double)opt.radius_scale);
	if (same_file(in, out))
		return sss__fail(err, errlen, SSS_ERR_INVALID_ARGUMENT,
		                 "%s: output is the input file; refusing to "
		                 "overwrite it", in);
	/* The output can be written (its folder takes a new file): said
	 * before the frame is read and scattered, not after. */
	sss_result ok = sss_exr_check_output(out, err, errlen);
	if (ok)
		return ok;

	sss_timings t = {0, 0, 0};
	sss_exr *exr = NULL;
	float *combined = NULL, *light = NULL, *thickness = NULL;
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
	if ((r = sss_exr_read(in, &opt.exr, &exr, err, errlen)))
		goto done;
	t.read = now() - t0;

	/* The result layer is added beside every input channel: an input
	 * layer of that name (a view layer called SSS, or a file that is
	 * already an output) would be replaced, so it is refused. So is an
	 * image the OpenEXR in use could not write back whole. */
	for (int32_t i = 0; i < sss_exr_pass_count(exr); i++) {
		const char *l, *p;
		sss_exr_pass(exr, i, &l, &p, NULL, NULL);
		if (strcmp(l, SSS_RESULT_LAYER) == 0) {
			r = sss__fail(err, errlen, SSS_ERR_INVALID_ARGUMENT, "%s: has "
			              "a layer '%s' (pass %s), the name of the result "
			              "layer, which would replace it; rename that view "
			              "layer in Blender, or give a render, not an "
			              "output of sss", in, SSS_RESULT_LAYER, p);
			goto done;
		}
	}
	int64_t channels = sss__exr_channel_count(exr) + 7; /* + the result */
	if (channels > sss__exr_max_channels()) {
		r = sss__fail(err, errlen, SSS_ERR_UNSUPPORTED, "%s: %lld channels "
		              "with the result's 7, more than the %d one file can "
		              "hold with this OpenEXR; nothing was done", in,
		              (long long)channels, sss__exr_max_channels());
		goto done;
	}

	sss_passes passes;
	const char *layer = NULL;
	if ((r = sss_exr_render_passes(exr, opt.layer, &passes, &layer, err,
	                               errlen)))
		goto done;
	if (!has_usable_depth(&passes.depth)) {
		r = sss__fail(err, errlen, SSS_ERR_INVALID_ARGUMENT,
		              "%s (layer '%s'): the Depth pass has no finite "
		              "positive value (NaN-filled or empty)", in, layer);
		goto done;
	}
	if ((r = back_light_passes(exr, layer, &passes, &thickness, in, err,
	                           errlen)))
		goto done;
	int32_t w = sss_exr_width(exr), h = sss_exr_height(exr);
	size_t n = (size_t)w * (size_t)h;
	combined = malloc(n * 4 * sizeof *combined);
	light = malloc(n * 3 * sizeof *light);
	if (!combined || !light) {
		r = sss__fail(err, errlen, SSS_ERR_OUT_OF_MEMORY, "%s: out of "
		              "memory for a %dx%d frame", in, w, h);
		goto done;
	}

	sss_options o = *sss_scene_options(scene);
	if (opt.method >= 0)
		o.method = opt.method;
	if (opt.num_threads >= 0)
		o.num_threads = opt.num_threads;
	if (opt.samples >= 0)
		o.samples = opt.samples;
	o.radius_scale = o.radius_scale * opt.radius_scale;
	int32_t count;
	const sss_material *mats = sss_scene_materials(scene, &count);
	sss_image oc = {combined, w, h, 4, 0}, ol = {light, w, h, 3, 0};
	char detail[512];
	tell(&prog, "scatter", 0.0);
	t0 = now();
	r = sss__apply_report(&passes, sss_scene_camera(scene), mats, count, &o,
	                      &oc, &ol, opt.chosen_methods, detail,
	                      sizeof detail);
	t.scatter = now() - t0;
	if (r) {
		sss__fail(err, errlen, r, "%s (layer '%s'): %s: %s", in, layer,
		          sss_status_string(r), detail);
		goto done;
	}

	tell(&prog, "scatter", 1.0);
	tell(&prog, "write", 0.0);
	t0 = now();
	if ((r = sss_exr_add_pass(exr, SSS_RESULT_LAYER, "Combined", "RGBA", combined, err,
	                          errlen)) ||
	    (r = sss_exr_add_pass(exr, SSS_RESULT_LAYER, "DiffLight", "RGB", light, err,
	                          errlen)) ||
	    (r = sss_exr_write(exr, out, &opt.exr, err, errlen)))
		goto done;
	t.write = now() - t0;
done:
	if (timings)
		*timings = t;
	free(combined);
	free(light);
	free(thickness);
	sss_exr_free(exr);
	return r;
}
