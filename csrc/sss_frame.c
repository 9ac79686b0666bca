/* sss_frame.c - one EXR frame's passes, read once and kept decoded, then
 * scattered again and again with new scene descriptions into the caller's
 * buffers, and written with the SSS layer only when a file is wanted. What
 * re-tuning SSS after the render needs; sss_process.c runs one frame end
 * to end through it, so the command, the add-on and a re-tune take the
 * same path. */
#include "sss_internal.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

struct sss_frame {
	sss_exr *exr;
	sss_passes passes;
	const char *layer;  /* the view layer scattered, owned by exr */
	float *thickness;   /* the square root of a squared thickness AOV */
	sss__frame_pre pre; /* what every scatter reads alike */
	/* The last scatter's working memory, for the next (sss_frame_trim
	 * frees it); a scatter takes it, or makes its own while another
	 * holds it, and leaves it here when none is. */
	_Atomic(sss__workspace *) spare;
	char *path;         /* the file read, for messages */
};

static double now(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
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

/* The thickness from its squared AOV into t (width x height): the root of
 * the mean of t^2 over the pixel and its eight neighbours of the same
 * material (a finite value each). The AOV is Ambient Occlusion with a few
 * rays a sample, (t / D)^2 for a slab: where a part is thin against D most
 * pixels read 0, and a thin part's reflectance (sss_thin.c), which falls
 * steeply towards t = 0, read those zeros as no thickness at all. Pooled
 * over nine pixels the bundled head's thin ears and eye sockets come out
 * closest to the random walk (docs/transmission.md, "Thin parts lit from
 * the front"). A slightly negative mean (filter noise) is 0, a pixel whose
 * own value is NaN stays NaN. */
static void thickness_from_squares(const sss_image *sq, const sss_image *index,
                                   float *t)
{
	/* the material pass, where it is the AOV's size */
	const sss_image *ix = index->data && index->width == sq->width &&
	                      index->height == sq->height ? index : NULL;
	for (int32_t y = 0; y < sq->height; y++)
		for (int32_t x = 0; x < sq->width; x++) {
			float own = sss__at(sq, x, y)[0];
			float mine = ix ? sss__at(ix, x, y)[0] : 0.0f;
			double sum = 0.0;
			int n = 0;
			for (int32_t v = y - 1; isfinite(own) && v <= y + 1; v++)
				for (int32_t u = x - 1; u <= x + 1; u++) {
					if (v < 0 || u < 0 || v >= sq->height ||
					    u >= sq->width || (ix &&
					    !(fabsf(sss__at(ix, u, v)[0] - mine) < 0.5f)))
						continue;
					float q = sss__at(sq, u, v)[0];
					if (isfinite(q)) {
						sum += q;
						n++;
					}
				}
			float mean = n ? (float)(sum / n) : own;
			t[(size_t)y * sq->width + x] = mean > 0.0f ? sqrtf(mean)
			                             : mean <= 0.0f ? 0.0f : mean;
		}
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
	float *t = malloc((size_t)v.width * (size_t)v.height * sizeof *t);
	if (!t)
		return sss__fail(err, errlen, SSS_ERR_OUT_OF_MEMORY, "%s: out of "
		                 "memory for the thickness pass", in);
	thickness_from_squares(&v, &passes->index_ma, t);
	*thick_buf = t;
	passes->thickness = (sss_image){t, v.width, v.height, 1, 0};
	return SSS_OK;
}

void sss_frame_free(sss_frame *frame)
{
	if (!frame)
		return;
	sss_exr_free(frame->exr);
	free(frame->thickness);
	sss__frame_pre_free(&frame->pre);
	sss__workspace_free(atomic_load(&frame->spare));
	free(frame->path);
	free(frame);
}

/* Takes exr (freed on failure too). */
static sss_result frame_from(sss_exr *exr, const char *path,
                             const char *layer, int32_t num_threads,
                             sss_frame **out, char *err, size_t errlen)
{
	sss_result r;
	sss_frame *f = calloc(1, sizeof *f);
	if (!f || !(f->path = malloc(strlen(path) + 1))) {
		free(f);
		sss_exr_free(exr);
		return sss__fail(err, errlen, SSS_ERR_OUT_OF_MEMORY, "%s: out of "
		                 "memory", path);
	}
	strcpy(f->path, path);
	f->exr = exr;
	if ((r = sss_exr_render_passes(exr, layer, &f->passes, &f->layer, err,
	                               errlen)))
		goto fail;
	if (!has_usable_depth(&f->passes.depth)) {
		r = sss__fail(err, errlen, SSS_ERR_INVALID_ARGUMENT,
		              "%s (layer '%s'): the Depth pass has no finite "
		              "positive value (NaN-filled or empty)", path, f->layer);
		goto fail;
	}
	if ((r = back_light_passes(exr, f->layer, &f->passes, &f->thickness,
	                           path, err, errlen)))
		goto fail;
	if ((r = sss__frame_pre_make(&f->passes, num_threads, &f->pre))) {
		r = sss__fail(err, errlen, r, "%s: out of memory", path);
		goto fail;
	}
	*out = f;
	return SSS_OK;
fail:
	sss_frame_free(f);
	return r;
}

sss_result sss_frame_read(const char *path, const char *layer,
                          const sss_exr_options *opt, sss_frame **out,
                          char *err, size_t errlen)
{
	if (err && errlen)
		err[0] = '\0';
	if (!out)
		return sss__fail(err, errlen, SSS_ERR_INVALID_ARGUMENT,
		                 "frame: out is required");
	*out = NULL;
	if (!path)
		return sss__fail(err, errlen, SSS_ERR_INVALID_ARGUMENT,
		                 "frame: path is required");
	sss_exr *exr = NULL;
	sss_result r = sss_exr_read(path, opt, &exr, err, errlen);
	if (r)
		return r;
	return frame_from(exr, path, layer, opt ? opt->num_threads : 0, out, err,
	                  errlen);
}

int32_t sss_frame_width(const sss_frame *frame)
{
	return frame ? sss_exr_width(frame->exr) : 0;
}

int32_t sss_frame_height(const sss_frame *frame)
{
	return frame ? sss_exr_height(frame->exr) : 0;
}

const char *sss_frame_layer(const sss_frame *frame)
{
	return frame ? frame->layer : NULL;
}

const sss_exr *sss_frame_exr(const sss_frame *frame)
{
	return frame ? frame->exr : NULL;
}

sss_result sss__process_options_check(const sss_process_options *opt,
                                      char *err, size_t errlen)
{
	if (opt->struct_size != sizeof *opt)
		return sss__fail(err, errlen, SSS_ERR_INVALID_ARGUMENT,
		                 "process options: struct_size %u, expected %zu",
		                 opt->struct_size, sizeof *opt);
	char range[48];
	if (!sss__option_in_range("radius_scale", opt->radius_scale, range,
	                          sizeof range))
		return sss__fail(err, errlen, SSS_ERR_INVALID_ARGUMENT,
		                 "radius scale %g must be %s",
		                 (double)opt->radius_scale, range);
	return SSS_OK;
}

/* The scene's options with the process options' overrides. */
static sss_result merged_options(const sss_scene *scene,
                                 const sss_process_options *opt,
                                 sss_options *o, char *err, size_t errlen)
{
	sss_result r = sss__process_options_check(opt, err, errlen);
	if (r)
		return r;
	*o = *sss_scene_options(scene);
	if (opt->method >= 0)
		o->method = opt->method;
	if (opt->num_threads >= 0)
		o->num_threads = opt->num_threads;
	if (opt->samples >= 0)
		o->samples = opt->samples;
	o->radius_scale = o->radius_scale * opt->radius_scale;
	return SSS_OK;
}

sss_result sss_frame_scatter(const sss_frame *frame, const sss_scene *scene,
                             const sss_process_options *user_opt,
                             const sss_image *out_combined,
                             const sss_image *out_diffuse_light,
                             double *seconds, char *err, size_t errlen)
{
	sss_process_options opt;
	sss_process_options_default(&opt);
	if (user_opt)
		opt = *user_opt;
	if (err && errlen)
		err[0] = '\0';
	if (seconds)
		*seconds = 0.0;
	if (!frame || !scene)
		return sss__fail(err, errlen, SSS_ERR_INVALID_ARGUMENT,
		                 "frame and scene are required");
	sss_options o;
	sss_result r = merged_options(scene, &opt, &o, err, errlen);
	if (r)
		return r;
	int32_t count;
	const sss_material *mats = sss_scene_materials(scene, &count);
	char detail[512];
	if (opt.progress_fn)
		opt.progress_fn("scatter", 0.0, opt.progress_user);
	double t0 = now();
	/* The frame is the caller's, allocated writable; only its spare
	 * workspace changes, atomically. */
	_Atomic(sss__workspace *) *spare = &((sss_frame *)frame)->spare;
	sss__workspace *ws = atomic_exchange(spare, NULL);
	if (!ws && !(ws = sss__workspace_new()))
		return sss__fail(err, errlen, SSS_ERR_OUT_OF_MEMORY, "%s (layer "
		                 "'%s'): out of memory", frame->path, frame->layer);
	r = sss__apply_report(&frame->passes, sss_scene_camera(scene), mats,
	                      count, &o, out_combined, out_diffuse_light,
	                      &frame->pre, ws, opt.chosen_methods, detail,
	                      sizeof detail);
	sss__workspace *none = NULL;
	if (!atomic_compare_exchange_strong(spare, &none, ws))
		sss__workspace_free(ws);
	if (seconds)
		*seconds = now() - t0;
	if (r)
		return sss__fail(err, errlen, r, "%s (layer '%s'): %s: %s",
		                 frame->path, frame->layer, sss_status_string(r),
		                 detail);
	if (opt.progress_fn)
		opt.progress_fn("scatter", 1.0, opt.progress_user);
	return SSS_OK;
}

void sss_frame_trim(sss_frame *frame)
{
	if (frame)
		sss__workspace_free(atomic_exchange(&frame->spare, NULL));
}

/* The result layer is added beside every input channel: an input layer
 * of that name (a view layer called SSS, or a file that is already an
 * output) would be replaced, so writing it is refused. So is an image the
 * OpenEXR in use could not write back whole. A frame with such a layer can
 * still be scattered: only its file cannot be written. */
sss_result sss__frame_check_result(const sss_frame *frame, char *err,
                                   size_t errlen)
{
	const sss_exr *exr = frame->exr;
	for (int32_t i = 0; i < sss_exr_pass_count(exr); i++) {
		const char *l, *p;
		sss_exr_pass(exr, i, &l, &p, NULL, NULL);
		if (strcmp(l, SSS_RESULT_LAYER) == 0)
			return sss__fail(err, errlen, SSS_ERR_INVALID_ARGUMENT, "%s: has "
			                 "a layer '%s' (pass %s), the name of the result "
			                 "layer, which would replace it; rename that "
			                 "view layer in Blender, or give a render, not "
			                 "an output of sss", frame->path,
			                 SSS_RESULT_LAYER, p);
	}
	int64_t channels = sss__exr_channel_count(exr) + 7; /* + the result */
	if (channels > sss__exr_max_channels())
		return sss__fail(err, errlen, SSS_ERR_UNSUPPORTED, "%s: %lld "
		                 "channels with the result's 7, more than the %d "
		                 "one file can hold with this OpenEXR; nothing was "
		                 "done", frame->path, (long long)channels,
		                 sss__exr_max_channels());
	return SSS_OK;
}

sss_result sss_frame_write(sss_frame *frame, const char *path,
                           const float *combined, const float *light,
                           const sss_exr_options *opt, char *err,
                           size_t errlen)
{
	if (err && errlen)
		err[0] = '\0';
	if (!frame || !path || !combined || !light)
		return sss__fail(err, errlen, SSS_ERR_INVALID_ARGUMENT,
		                 "frame, path, combined and light are required");
	sss_result r = sss__frame_check_result(frame, err, errlen);
	if (r)
		return r;
	if (!(r = sss_exr_add_pass(frame->exr, SSS_RESULT_LAYER, "Combined",
	                           "RGBA", combined, err, errlen)) &&
	    !(r = sss_exr_add_pass(frame->exr, SSS_RESULT_LAYER, "DiffLight",
	                           "RGB", light, err, errlen)))
		r = sss_exr_write(frame->exr, path, opt, err, errlen);
	/* A kept frame holds the render's passes, not the result's copy (the
	 * file had no layer of that name: sss__frame_check_result). */
	sss__exr_remove_layer(frame->exr, SSS_RESULT_LAYER);
	return r;
}
