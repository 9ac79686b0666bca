/* test_oom.c - allocation failure at every point of every public entry
 * point: fail the 1st, 2nd, ... allocation the library makes until the
 * call succeeds. Each failing call must return SSS_ERR_OUT_OF_MEMORY, leave
 * no partial file behind, and leak nothing (make check runs this under
 * ASan/LeakSanitizer). The library's own malloc/calloc/realloc calls are
 * redirected here with the linker's --wrap (see the Makefile). */
#include "synth.h"
#include "test_util.h"

#include <dirent.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

void *__real_malloc(size_t n);
void *__real_calloc(size_t n, size_t size);
void *__real_realloc(void *p, size_t n);
void *__wrap_malloc(size_t n);
void *__wrap_calloc(size_t n, size_t size);
void *__wrap_realloc(void *p, size_t n);

/* Allocation countdown: 0 = never fail. Only the test's main thread runs
 * the loops below, but decoding threads may allocate too: atomics keep the
 * count exact. */
static _Atomic long fail_at, calls;

static int should_fail(void)
{
	long n = ++calls;
	return fail_at > 0 && n == fail_at;
}

void *__wrap_malloc(size_t n)
{
	return should_fail() ? NULL : __real_malloc(n);
}

void *__wrap_calloc(size_t n, size_t size)
{
	return should_fail() ? NULL : __real_calloc(n, size);
}

void *__wrap_realloc(void *p, size_t n)
{
	return should_fail() ? NULL : __real_realloc(p, n);
}

typedef sss_result (*entry_fn)(void *ctx);

/* Runs fn with the n-th allocation failing, n = 1, 2, ... until it
 * succeeds; every failure must be SSS_ERR_OUT_OF_MEMORY. */
static void oom_loop(const char *id, entry_fn fn, void *ctx,
                     void (*after_failure)(void *ctx, const char *id))
{
	long n;
	for (n = 1; n < 100000; n++) {
		fail_at = n;
		calls = 0;
		sss_result r = fn(ctx);
		fail_at = 0;
		if (r == SSS_OK)
			break;
		CHECK(id, r == SSS_ERR_OUT_OF_MEMORY,
		      "allocation %ld failed: got %s", n, sss_status_name(r));
		if (after_failure)
			after_failure(ctx, id);
		if (r != SSS_ERR_OUT_OF_MEMORY)
			break;
	}
	printf("report: %s: %ld allocation points\n", id, n - 1);
	CHECK(id, n > 1, "the call allocated nothing: the test cannot fail");
}

/* ------------------------------------------------------------- sss_apply */

typedef struct apply_ctx {
	synth *s;
	sss_material mats[2];
	sss_options opt;
	float *out;
} apply_ctx;

static sss_result run_apply(void *vctx)
{
	apply_ctx *c = vctx;
	sss_passes p = synth_passes(c->s);
	sss_camera cam;
	sss_camera_default(&cam);
	sss_image out = {c->out, c->s->w, c->s->h, 4, 0};
	return sss_apply(&p, &cam, c->mats, 2, &c->opt, &out, NULL, NULL, 0);
}

static sss_result run_kernel(void *vctx)
{
	apply_ctx *c = vctx;
	float off[64], w[192];
	int32_t n = 64;
	return sss_kernel_1d(&c->mats[0], 2000.0, 33, off, w, &n);
}

/* ------------------------------------------------------------ files */

static char dir[] = "/tmp/sss_oom_XXXXXX";

static int count_files(const char *path)
{
	DIR *d = opendir(path);
	int n = 0;
	struct dirent *e;
	while (d && (e = readdir(d)))
		n += e->d_name[0] != '.' || strstr(e->d_name, ".tmp-") != NULL;
	if (d)
		closedir(d);
	return n;
}

static void no_partial_output(void *ctx, const char *id)
{
	(void)ctx;
	CHECK(id, count_files(dir) == 0, "a partial output was left behind");
}

/* Out of memory is said as such, never as a damaged file. */
static int oom_as_corrupt, oom_said;

static sss_result run_read(void *ctx)
{
	(void)ctx;
	sss_exr *exr = NULL;
	char err[512];
	sss_result r = sss_exr_read("tests/data/blender_8x8.exr", NULL, &exr,
	                            err, sizeof err);
	if (r == SSS_ERR_OUT_OF_MEMORY) {
		oom_as_corrupt += strstr(err, "corrupt") != NULL;
		oom_said += strstr(err, "out of memory") != NULL;
	}
	sss_exr_free(exr);
	return r;
}

typedef struct write_ctx {
	sss_exr *exr;
	char path[256];
} write_ctx;

static sss_result run_add_and_write(void *vctx)
{
	write_ctx *c = vctx;
	float data[8 * 8 * 3] = {0};
	sss_result r = sss_exr_add_pass(c->exr, "Extra", "Pass", "RGB", data,
	                                NULL, 0);
	if (r)
		return r;
	r = sss_exr_write(c->exr, c->path, NULL, NULL, 0);
	if (r == SSS_OK)
		unlink(c->path);
	return r;
}

static const char scene_json[] =
	"{\"camera\": {\"lens\": 50}, \"method\": \"separable\", "
	"\"materials\": [{\"pass_index\": 1, \"profile\": \"burley\", "
	"\"radius\": [0.3, 0.1, 0.05]}, {\"pass_index\": 2, \"profile\": "
	"\"gaussians\"}, {\"pass_index\": 3, \"profile\": \"jimenez\"}]}";

static sss_result run_scene_parse(void *ctx)
{
	(void)ctx;
	sss_scene *scene = NULL;
	char warn[64];
	sss_result r = sss_scene_parse(scene_json, sizeof scene_json - 1, &scene,
	                               warn, sizeof warn, NULL, 0);
	sss_scene_free(scene);
	return r;
}

static sss_result run_scene_load(void *ctx)
{
	(void)ctx;
	sss_scene *scene = NULL;
	sss_result r = sss_scene_load("tests/data/blender_8x8.json", &scene,
	                              NULL, 0, NULL, 0);
	sss_scene_free(scene);
	return r;
}

typedef struct process_ctx {
	sss_scene *scene;
	char path[256];
} process_ctx;

static sss_result run_process(void *vctx)
{
	process_ctx *c = vctx;
	sss_result r = sss_process_exr("tests/data/blender_8x8.exr", c->path,
	                               c->scene, NULL, NULL, NULL, 0);
	if (r == SSS_OK)
		unlink(c->path);
	return r;
}

int main(void)
{
	apply_ctx a;
	a.s = synth_new(24, 16);
	synth_plane(a.s, 0, 0, 12, 16, 2.0f, 1.0f);
	synth_plane(a.s, 12, 0, 24, 16, 2.0f, 2.0f);
	synth_noise(a.s, 0, 1, 5);
	sss_material_default(&a.mats[0], SSS_PROFILE_BURLEY);
	sss_material_default(&a.mats[1], SSS_PROFILE_JIMENEZ);
	a.mats[0].pass_index = 1;
	a.mats[1].pass_index = 2;
	for (int c = 0; c < 3; c++)
		a.mats[0].radius[c] = 0.05f;
	a.mats[1].jimenez_width = 0.05f;
	a.out = calloc(24 * 16 * 4, sizeof(float));
	sss_options_default(&a.opt);
	a.opt.num_threads = 2;
	oom_loop("oom-apply-separable", run_apply, &a, NULL);
	a.opt.method = SSS_METHOD_REFERENCE;
	oom_loop("oom-apply-reference", run_apply, &a, NULL);
	oom_loop("oom-kernel-1d", run_kernel, &a, NULL);

	/* A convex edge along the middle rows (45-degree faces for the
	 * default camera at 2 m) and a calibrated Burley: the crease term's
	 * allocations too. */
	for (int y = 0; y < 16; y++)
		for (int x = 0; x < 24; x++) {
			a.s->depth[y * 24 + x] = 2.0f + 0.06f * fabsf(y - 7.5f);
			a.s->index[y * 24 + x] = 1.0f;
			for (int c = 0; c < 3; c++) /* the walk at 1: no crease */
				a.s->diff_col[3 * (y * 24 + x) + c] = 0.6f;
		}
	a.mats[0].calibration = SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN;
	a.mats[0].burley_mapping = SSS_BURLEY_CYCLES_RANDOM_WALK;
	a.opt.method = SSS_METHOD_SEPARABLE;
	float *plain = calloc(24 * 16 * 4, sizeof(float));
	a.opt.crease = 0;
	CHECK_STATUS("oom-crease-setup", SSS_OK, run_apply(&a));
	memcpy(plain, a.out, 24 * 16 * 4 * sizeof(float));
	a.opt.crease = 1;
	CHECK_STATUS("oom-crease-setup", SSS_OK, run_apply(&a));
	CHECK("oom-crease-active", memcmp(plain, a.out,
	                                  24 * 16 * 4 * sizeof(float)) != 0,
	      "the edge carried no light: the loop below would not reach the "
	      "crease term");
	free(plain);
	oom_loop("oom-apply-crease", run_apply, &a, NULL);
	free(a.out);
	synth_free(a.s);

	if (!mkdtemp(dir)) {
		perror("mkdtemp");
		return 1;
	}
	oom_loop("oom-exr-read", run_read, NULL, NULL);
	CHECK("oom-exr-read.message", oom_as_corrupt == 0 && oom_said > 0,
	      "%d failures said 'corrupt', %d 'out of memory'", oom_as_corrupt,
	      oom_said);
	write_ctx w;
	snprintf(w.path, sizeof w.path, "%s/out.exr", dir);
	CHECK_STATUS("oom-exr-setup", SSS_OK,
	             sss_exr_read("tests/data/blender_8x8.exr", NULL, &w.exr,
	                          NULL, 0));
	oom_loop("oom-exr-add-write", run_add_and_write, &w, no_partial_output);
	sss_exr_free(w.exr);
	oom_loop("oom-scene-parse", run_scene_parse, NULL, NULL);
	oom_loop("oom-scene-load", run_scene_load, NULL, NULL);
	process_ctx p;
	snprintf(p.path, sizeof p.path, "%s/processed.exr", dir);
	CHECK_STATUS("oom-process-setup", SSS_OK,
	             sss_scene_load("tests/data/blender_8x8.json", &p.scene, NULL,
	                            0, NULL, 0));
	oom_loop("oom-process", run_process, &p, no_partial_output);
	sss_scene_free(p.scene);
	rmdir(dir);
	return tu_finish("test_oom");
}
