/* test_frame.c - a frame kept in memory (sss_frame.c): scattered again and
 * again with other scene descriptions, it gives the same bits as the
 * whole-file path (sss_process_exr) on the same passes, is not changed by
 * a scatter, writes the same file, and refuses misuse with a status. */
#include "test_util.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define INPUT "tests/data/blender_8x8.exr"
#define SCENE "tests/data/blender_8x8.json"

static char tmpdir[64];

static void tpath(char *out, size_t len, const char *name)
{
	snprintf(out, len, "%s/%s", tmpdir, name);
}

/* The SSS layer's Combined pass of an EXR the library wrote, copied. */
static float *result_of(const char *path, int32_t *w, int32_t *h)
{
	char err[512];
	sss_exr *exr = NULL;
	if (sss_exr_read(path, NULL, &exr, err, sizeof err) != SSS_OK) {
		printf("cannot read %s: %s\n", path, err);
		return NULL;
	}
	sss_image v;
	float *copy = NULL;
	if (sss_exr_find(exr, SSS_RESULT_LAYER, "Combined", &v) == SSS_OK &&
	    v.channels == 4) {
		size_t n = (size_t)v.width * (size_t)v.height * 4;
		copy = malloc(n * sizeof *copy);
		if (copy)
			memcpy(copy, v.data, n * sizeof *copy);
		*w = v.width;
		*h = v.height;
	}
	sss_exr_free(exr);
	return copy;
}

/* sss_process_exr's result with this radius scale, for comparison. */
static float *processed(const sss_scene *scene, float radius_scale,
                        const char *name, int32_t *w, int32_t *h)
{
	char err[512], out[128];
	tpath(out, sizeof out, name);
	sss_process_options opt;
	sss_process_options_default(&opt);
	opt.radius_scale = radius_scale;
	sss_result r = sss_process_exr(INPUT, out, scene, &opt, NULL, err,
	                               sizeof err);
	CHECK("frame.process", r == SSS_OK, "%s", err);
	return r == SSS_OK ? result_of(out, w, h) : NULL;
}

static int same_bits(const float *a, const float *b, size_t n)
{
	return a && b && memcmp(a, b, n * sizeof *a) == 0;
}

static void test_retune(void)
{
	char err[512], warn[512];
	sss_scene *scene = NULL;
	CHECK_STATUS("frame.scene", SSS_OK,
	             sss_scene_load(SCENE, &scene, warn, sizeof warn, err,
	                            sizeof err));
	if (!scene)
		return;
	int32_t w = 0, h = 0;
	float *want1 = processed(scene, 1.0f, "p1.exr", &w, &h);
	float *want3 = processed(scene, 100.0f, "p3.exr", &w, &h);
	CHECK("frame.radius-matters", want1 && want3 &&
	      !same_bits(want1, want3, (size_t)w * h * 4),
	      "a 100x radius gives the same image: the test cannot fail");

	sss_frame *frame = NULL;
	CHECK_STATUS("frame.read", SSS_OK,
	             sss_frame_read(INPUT, NULL, NULL, &frame, err, sizeof err));
	if (!frame || !want1 || !want3)
		goto done;
	CHECK("frame.size", sss_frame_width(frame) == w &&
	      sss_frame_height(frame) == h, "%dx%d, file %dx%d",
	      sss_frame_width(frame), sss_frame_height(frame), w, h);
	CHECK("frame.layer", strcmp(sss_frame_layer(frame), "ViewLayer") == 0,
	      "layer '%s'", sss_frame_layer(frame));
	CHECK("frame.exr", sss_exr_width(sss_frame_exr(frame)) == w,
	      "the frame's passes are not the file's");

	size_t n = (size_t)w * (size_t)h;
	float *combined = malloc(n * 4 * sizeof *combined);
	float *light = malloc(n * 3 * sizeof *light);
	sss_image oc = {combined, w, h, 4, 0}, ol = {light, w, h, 3, 0};
	sss_process_options opt;
	sss_process_options_default(&opt);
	double seconds = -1.0;
	/* 1x, 100x, then 1x again: each equals the whole-file path's bits, so
	 * a scatter leaves the frame as it was. */
	const float scales[3] = {1.0f, 100.0f, 1.0f};
	const float *wants[3] = {want1, want3, want1};
	for (int i = 0; i < 3; i++) {
		opt.radius_scale = scales[i];
		sss_result r = sss_frame_scatter(frame, scene, &opt, &oc, &ol,
		                                 &seconds, err, sizeof err);
		CHECK("frame.scatter", r == SSS_OK, "%s", err);
		CHECK("frame.same-as-process", same_bits(combined, wants[i], n * 4),
		      "scatter %d (radius x%g) differs from sss_process_exr's", i,
		      (double)scales[i]);
	}
	CHECK("frame.seconds", seconds >= 0.0 && seconds < 60.0, "%g", seconds);
	/* Those scatters reused the frame's working memory; without it, and
	 * then reusing it, into outputs with padded rows (so the library's
	 * own scratch), the same bits. */
	sss_frame_trim(frame);
	sss_frame_trim(NULL);
	{
		float *wide = calloc(n * 5 + 5 * (size_t)h, sizeof *wide);
		sss_image pc = {wide, w, h, 5, (int64_t)w * 5 + 5};
		opt.radius_scale = 100.0f;
		for (int i = 0; wide && i < 2; i++) {
			CHECK_STATUS("frame.scatter-trimmed", SSS_OK,
			             sss_frame_scatter(frame, scene, &opt, &pc, NULL,
			                               NULL, err, sizeof err));
			int same = 1;
			for (int32_t y = 0; y < h; y++)
				for (int32_t x = 0; x < w; x++)
					same &= memcmp(wide + y * ((int64_t)w * 5 + 5) + x * 5,
					               want3 + ((size_t)y * w + x) * 4,
					               4 * sizeof *wide) == 0;
			CHECK("frame.trimmed-same", same, "scatter %d after a trim, "
			      "into padded rows, differs from sss_process_exr's", i);
		}
		free(wide);
	}

	/* Written only when asked: the same pixels as the whole-file path. */
	char out[128];
	tpath(out, sizeof out, "written.exr");
	CHECK_STATUS("frame.write", SSS_OK,
	             sss_frame_write(frame, out, combined, light, NULL, err,
	                             sizeof err));
	int32_t w2 = 0, h2 = 0;
	float *written = result_of(out, &w2, &h2);
	CHECK("frame.write-pixels", w2 == w && h2 == h &&
	      same_bits(written, want1, n * 4), "the written file differs");
	free(written);
	CHECK_STATUS("frame.write-input", SSS_ERR_INVALID_ARGUMENT,
	             sss_frame_write(frame, INPUT, combined, light, NULL, err,
	                             sizeof err));
	/* A scatter after a write still reads the render's own passes. */
	opt.radius_scale = 100.0f;
	CHECK_STATUS("frame.scatter-after-write", SSS_OK,
	             sss_frame_scatter(frame, scene, &opt, &oc, &ol, NULL, err,
	                               sizeof err));
	CHECK("frame.after-write", same_bits(combined, want3, n * 4),
	      "the written SSS layer leaked into the passes");
	sss_image v;
	CHECK_STATUS("frame.not-kept", SSS_ERR_MISSING_PASS,
	             sss_exr_find(sss_frame_exr(frame), SSS_RESULT_LAYER,
	                          "Combined", &v));

	/* Misuse is a status with a message, never a crash. */
	sss_image small = {combined, w - 1, h, 4, 0};
	CHECK_STATUS("frame.bad-size", SSS_ERR_SIZE_MISMATCH,
	             sss_frame_scatter(frame, scene, &opt, &small, NULL, NULL, err,
	                               sizeof err));
	CHECK("frame.bad-size-says", strstr(err, INPUT) != NULL, "%s", err);
	opt.radius_scale = -1.0f;
	CHECK_STATUS("frame.bad-scale", SSS_ERR_INVALID_ARGUMENT,
	             sss_frame_scatter(frame, scene, &opt, &oc, NULL, NULL, err,
	                               sizeof err));
	CHECK("frame.bad-scale-says", strstr(err, "radius scale -1 must be "
	      "finite and >= 0") != NULL, "%s", err);
	opt.radius_scale = 1.0f;
	opt.struct_size = 3;
	CHECK_STATUS("frame.bad-struct", SSS_ERR_INVALID_ARGUMENT,
	             sss_frame_scatter(frame, scene, &opt, &oc, NULL, NULL, err,
	                               sizeof err));
	CHECK_STATUS("frame.no-scene", SSS_ERR_INVALID_ARGUMENT,
	             sss_frame_scatter(frame, NULL, NULL, &oc, NULL, NULL, err,
	                               sizeof err));
	CHECK_STATUS("frame.no-frame", SSS_ERR_INVALID_ARGUMENT,
	             sss_frame_scatter(NULL, scene, NULL, &oc, NULL, NULL, err,
	                               sizeof err));
	CHECK_STATUS("frame.write-null", SSS_ERR_INVALID_ARGUMENT,
	             sss_frame_write(frame, out, NULL, light, NULL, err,
	                             sizeof err));
	/* A file that is already an output (it has the result layer): its
	 * passes can be re-tuned, only writing it back is refused. */
	sss_frame *again = NULL;
	char p1[128];
	tpath(p1, sizeof p1, "p1.exr");
	CHECK_STATUS("frame.output-read", SSS_OK,
	             sss_frame_read(p1, NULL, NULL, &again, err, sizeof err));
	if (again) {
		sss_process_options_default(&opt);
		CHECK_STATUS("frame.output-scatter", SSS_OK,
		             sss_frame_scatter(again, scene, &opt, &oc, &ol, NULL,
		                               err, sizeof err));
		CHECK("frame.output-same", same_bits(combined, want1, n * 4),
		      "the output's passes scatter differently");
		tpath(out, sizeof out, "again.exr");
		CHECK_STATUS("frame.output-write", SSS_ERR_INVALID_ARGUMENT,
		             sss_frame_write(again, out, combined, light, NULL, err,
		                             sizeof err));
		CHECK("frame.output-says", strstr(err, "result layer") != NULL,
		      "%s", err);
		CHECK("frame.output-nothing", access(out, F_OK) != 0,
		      "a refused write left %s", out);
		sss_frame_free(again);
	}
	free(combined);
	free(light);
done:
	sss_frame_free(frame);
	free(want1);
	free(want3);
	sss_scene_free(scene);
}

/* The scene file's text with a calibrated material (its gain reads the
 * view cosine) and the given lens. */
static sss_scene *calibrated_scene(const char *lens)
{
	char text[8192], err[512];
	FILE *f = fopen(SCENE, "rb");
	size_t n = f ? fread(text, 1, sizeof text - 1, f) : 0;
	if (f)
		fclose(f);
	text[n] = '\0';
	char out[8300];
	const char *name = strstr(text, "\"name\"");
	const char *lens_at = strstr(text, "\"lens\": 50.0");
	sss_scene *scene = NULL;
	if (!name || !lens_at || name < lens_at)
		return NULL;
	snprintf(out, sizeof out, "%.*s\"lens\": %s%.*s\"calibration\": "
	         "\"cycles4-random-walk\", %s", (int)(lens_at - text), text, lens,
	         (int)(name - lens_at - strlen("\"lens\": 50.0")),
	         lens_at + strlen("\"lens\": 50.0"), name);
	sss_result r = sss_scene_parse(out, strlen(out), &scene, NULL, 0, err,
	                               sizeof err);
	CHECK("frame.calibrated-scene", r == SSS_OK, "%s", err);
	return scene;
}

/* A kept frame keeps the view cosine while the camera and the scattering
 * pixels stay: a change of camera between scatters must make it again. */
static void test_camera_change(void)
{
	sss_scene *a = calibrated_scene("50.0"), *b = calibrated_scene("20.0");
	int32_t w = 0, h = 0;
	float *want_a = a ? processed(a, 1.0f, "ca.exr", &w, &h) : NULL;
	float *want_b = b ? processed(b, 1.0f, "cb.exr", &w, &h) : NULL;
	size_t n = (size_t)w * (size_t)h;
	CHECK("frame.lens-matters", want_a && want_b &&
	      !same_bits(want_a, want_b, n * 4), "the lens changed nothing");
	char err[512];
	sss_frame *frame = NULL;
	CHECK_STATUS("frame.read-for-camera", SSS_OK,
	             sss_frame_read(INPUT, NULL, NULL, &frame, err, sizeof err));
	float *combined = malloc(n * 4 * sizeof *combined);
	sss_image oc = {combined, w, h, 4, 0};
	const sss_scene *order[3] = {a, b, a};
	const float *wants[3] = {want_a, want_b, want_a};
	for (int i = 0; frame && combined && want_a && want_b && i < 3; i++) {
		CHECK_STATUS("frame.scatter-camera", SSS_OK,
		             sss_frame_scatter(frame, order[i], NULL, &oc, NULL,
		                               NULL, err, sizeof err));
		CHECK("frame.camera-change", same_bits(combined, wants[i], n * 4),
		      "scatter %d (lens %s) differs from sss_process_exr's", i,
		      i == 1 ? "20" : "50");
	}
	free(combined);
	free(want_a);
	free(want_b);
	sss_frame_free(frame);
	sss_scene_free(a);
	sss_scene_free(b);
}

/* A frame scattered from several threads at once: each scatter takes the
 * frame's kept working memory or makes its own, and every result equals
 * the whole-file path's, whichever it got. */
typedef struct worker {
	const sss_frame *frame;
	const sss_scene *scene;
	const float *want[2];
	int32_t w, h;
	int same; /* every scatter matched */
} worker;

static void *scatter_worker(void *arg)
{
	worker *wk = arg;
	size_t n = (size_t)wk->w * wk->h;
	float *out = malloc(n * 4 * sizeof *out);
	sss_image oc = {out, wk->w, wk->h, 4, 0};
	sss_process_options opt;
	sss_process_options_default(&opt);
	opt.num_threads = 1;
	wk->same = out != NULL;
	for (int i = 0; out && i < 6; i++) {
		opt.radius_scale = i % 2 ? 100.0f : 1.0f;
		char err[512];
		wk->same &= sss_frame_scatter(wk->frame, wk->scene, &opt, &oc, NULL,
		                              NULL, err, sizeof err) == SSS_OK &&
		            same_bits(out, wk->want[i % 2], n * 4);
	}
	free(out);
	return NULL;
}

static void test_threads(void)
{
	char err[512];
	sss_scene *scene = NULL;
	sss_frame *frame = NULL;
	CHECK_STATUS("frame.threads-scene", SSS_OK,
	             sss_scene_load(SCENE, &scene, NULL, 0, err, sizeof err));
	int32_t w = 0, h = 0;
	float *want1 = scene ? processed(scene, 1.0f, "t1.exr", &w, &h) : NULL;
	float *want3 = scene ? processed(scene, 100.0f, "t3.exr", &w, &h) : NULL;
	CHECK_STATUS("frame.threads-read", SSS_OK,
	             sss_frame_read(INPUT, NULL, NULL, &frame, err, sizeof err));
	worker wk[4];
	pthread_t th[4];
	int started[4] = {0};
	for (int t = 0; frame && want1 && want3 && t < 4; t++) {
		wk[t] = (worker){frame, scene, {want1, want3}, w, h, 0};
		started[t] = pthread_create(&th[t], NULL, scatter_worker, &wk[t]) == 0;
		CHECK("frame.threads-start", started[t], "thread %d", t);
	}
	for (int t = 0; t < 4; t++)
		if (started[t]) {
			pthread_join(th[t], NULL);
			CHECK("frame.threads-same", wk[t].same, "thread %d: a scatter "
			      "differs from sss_process_exr's", t);
		}
	free(want1);
	free(want3);
	sss_frame_free(frame);
	sss_scene_free(scene);
}

static void test_read_errors(void)
{
	char err[512], path[128];
	sss_frame *frame = (sss_frame *)&frame;
	tpath(path, sizeof path, "absent.exr");
	sss_result r = sss_frame_read(path, NULL, NULL, &frame, err, sizeof err);
	CHECK("frame.missing", r != SSS_OK && frame == NULL &&
	      strstr(err, path) != NULL, "%s: %s", sss_status_name(r), err);
	CHECK_STATUS("frame.layer-missing", SSS_ERR_MISSING_PASS,
	             sss_frame_read(INPUT, "NoSuchLayer", NULL, &frame, err,
	                            sizeof err));
	CHECK("frame.layer-missing-null", frame == NULL, "frame not NULL");
	CHECK_STATUS("frame.no-out", SSS_ERR_INVALID_ARGUMENT,
	             sss_frame_read(INPUT, NULL, NULL, NULL, err, sizeof err));
	CHECK_STATUS("frame.no-path", SSS_ERR_INVALID_ARGUMENT,
	             sss_frame_read(NULL, NULL, NULL, &frame, err, sizeof err));
	CHECK("frame.null-accessors", sss_frame_width(NULL) == 0 &&
	      sss_frame_height(NULL) == 0 && sss_frame_layer(NULL) == NULL &&
	      sss_frame_exr(NULL) == NULL, "accessors on NULL");
	sss_frame_free(NULL);
}

int main(void)
{
	snprintf(tmpdir, sizeof tmpdir, "/tmp/sss_frame_XXXXXX");
	if (!mkdtemp(tmpdir)) {
		perror("mkdtemp");
		return 1;
	}
	test_retune();
	test_camera_change();
	test_threads();
	test_read_errors();
	int rc = tu_finish("test_frame");
	char cmd[128];
	snprintf(cmd, sizeof cmd, "rm -rf %s", tmpdir);
	if (system(cmd) != 0)
		printf("could not remove %s\n", tmpdir);
	return rc;
}
