/* fuzz_exr.c - libFuzzer harness for libsss's file inputs: the EXR reader
 * (and what a frame goes through after it: render passes, sss_apply, add
 * pass, writer) and the JSON scene parser.
 *
 * Input selector: a first byte '{' is a scene description (JSON); a first
 * byte 'J' is JSON too, starting after it (any text: arrays, leading
 * blanks, empty); anything else is an EXR file (magic 76 2f 31 01). Both corpora share one harness so that one replay
 * binary (replay.c, built by `make test` without libFuzzer) covers both.
 *
 * Besides "no crash, no leak, no undefined behaviour" it checks two
 * contracts the library states, and abort()s (a crash to the fuzzer) when
 * one breaks:
 *   - a written EXR reads back with the same size and passes, and with the
 *     same pixels for the lossless codecs (sss.h, sss_exr_write);
 *   - a scene that parses is accepted by sss_apply (sss_scene.c's header).
 *
 * Build (see scripts/fuzz.sh): clang -fsanitize=fuzzer,address,undefined
 * with csrc/sss_*.c but not sss_main.c; for replay, any C11 compiler with
 * replay.c instead of libFuzzer. */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE /* memfd_create */
#endif
#include "sss.h"

#include <fcntl.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Small caps keep each run fast: the reader's size checks are what is
 * exercised, not the allocator. */
#define MAX_SIDE 512
#define MAX_PIXELS ((int64_t)1 << 18)
/* sss_apply and the round trip only on tiny images (cost ~ pixels). */
#define APPLY_PIXELS (64 * 64)
#define REFERENCE_PIXELS (16 * 16)

/* Reports a broken contract and crashes so that libFuzzer keeps the input. */
#define FUZZ_ASSERT(cond, ...)                                             \
	do {                                                                   \
		if (!(cond)) {                                                     \
			fprintf(stderr, "fuzz_exr: %s:%d: %s: ", __FILE__, __LINE__,   \
			        #cond);                                                \
			fprintf(stderr, __VA_ARGS__);                                  \
			fprintf(stderr, "\n");                                         \
			abort();                                                       \
		}                                                                  \
	} while (0)

/* ------------------------------------------------------------ the input
 * sss_exr_read takes a path. A memfd reached through /proc/self/fd keeps
 * the millions of inputs off the disk; without memfd or /proc, one temp
 * file per process is rewritten instead. Both live for the process. */

static int in_fd = -1;
static char in_path[64];
static char out_path[96];

static void remove_temp_input(void)
{
	unlink(in_path);
}

static int setup_paths(void)
{
	if (in_fd >= 0)
		return 0;
	/* Outputs go to tmpfs when there is one: the writer creates a
	 * temporary file beside the target and renames it. */
	const char *dir = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : NULL;
	if (!dir)
		dir = getenv("TMPDIR") && getenv("TMPDIR")[0] ? getenv("TMPDIR")
		                                              : "/tmp";
	snprintf(out_path, sizeof out_path, "%s/sss-fuzz-out-%ld.exr", dir,
	         (long)getpid());
#ifdef MFD_CLOEXEC
	int fd = memfd_create("sss-fuzz-input", MFD_CLOEXEC);
	if (fd >= 0) {
		snprintf(in_path, sizeof in_path, "/proc/self/fd/%d", fd);
		int probe = open(in_path, O_RDONLY | O_CLOEXEC);
		if (probe >= 0) {
			close(probe);
			in_fd = fd;
			return 0;
		}
		close(fd); /* no /proc: fall back to a file */
	}
#endif
	snprintf(in_path, sizeof in_path, "%s/sss-fuzz-in-XXXXXX", dir);
	in_fd = mkstemp(in_path);
	if (in_fd < 0)
		return -1;
	atexit(remove_temp_input);
	return 0;
}

/* The input file now holds exactly these bytes. */
static int put_input(const uint8_t *data, size_t size)
{
	if (setup_paths() || ftruncate(in_fd, 0))
		return -1;
	size_t done = 0;
	while (done < size) {
		ssize_t n = pwrite(in_fd, data + done, size - done, (off_t)done);
		if (n <= 0)
			return -1;
		done += (size_t)n;
	}
	return 0;
}

/* ---------------------------------------------------------------- EXR */

/* One row per profile kind, so sss_apply runs every kernel builder on
 * pixels whose IndexMA is 1..5 (the Blender corpus files use 1..3). */
static int default_materials(sss_material *m)
{
	sss_material_default(&m[0], SSS_PROFILE_BURLEY);
	m[0].pass_index = 1;
	sss_material_default(&m[1], SSS_PROFILE_BURLEY);
	m[1].pass_index = 2;
	m[1].burley_mapping = SSS_BURLEY_RANDOM_WALK;
	m[1].texturing = SSS_TEXTURING_PRE_AND_POST;
	sss_material_default(&m[2], SSS_PROFILE_GAUSSIANS);
	m[2].pass_index = 3;
	sss_material_default(&m[3], SSS_PROFILE_JIMENEZ);
	m[3].pass_index = 4;
	sss_material_default(&m[4], SSS_PROFILE_NEAR_FAR);
	m[4].pass_index = 5;
	return 5;
}

static int same_float(float a, float b)
{
	return a == b || (isnan(a) && isnan(b));
}

/* Reads the written file back: same size and passes; same pixels when
 * the codec is lossless (every channel keeps its pixel type on writing,
 * so values decoded once survive a second trip exactly). */
static void check_round_trip(const sss_exr *exr, const char *path,
                             int32_t compression)
{
	sss_exr_options o;
	sss_exr_options_default(&o);
	o.num_threads = 1;
	sss_exr *back = NULL;
	char err[512];
	sss_result r = sss_exr_read(path, &o, &back, err, sizeof err);
	unlink(path); /* before any abort: no file left behind per crash */
	FUZZ_ASSERT(r == SSS_OK, "written file does not read back: %s", err);
	FUZZ_ASSERT(sss_exr_width(back) == sss_exr_width(exr) &&
	            sss_exr_height(back) == sss_exr_height(exr) &&
	            sss_exr_pass_count(back) == sss_exr_pass_count(exr),
	            "read back as %dx%d with %d passes, wrote %dx%d with %d",
	            sss_exr_width(back), sss_exr_height(back),
	            sss_exr_pass_count(back), sss_exr_width(exr),
	            sss_exr_height(exr), sss_exr_pass_count(exr));
	int lossless = compression <= SSS_EXR_PIZ;
	for (int32_t i = 0; i < sss_exr_pass_count(exr); i++) {
		const char *layer, *pass;
		sss_image a, b;
		sss_exr_pass(exr, i, &layer, &pass, NULL, &a);
		r = sss_exr_find(back, layer, pass, &b);
		FUZZ_ASSERT(r == SSS_OK, "pass '%s'.'%s' lost", layer, pass);
		FUZZ_ASSERT(b.channels == a.channels, "pass '%s'.'%s': %d "
		            "components, wrote %d", layer, pass, b.channels,
		            a.channels);
		if (!lossless)
			continue;
		size_t n = (size_t)a.width * (size_t)a.height * (size_t)a.channels;
		for (size_t k = 0; k < n; k++)
			FUZZ_ASSERT(same_float(a.data[k], b.data[k]), "pass '%s'.'%s' "
			            "value %zu: %a read back as %a", layer, pass, k,
			            (double)a.data[k], (double)b.data[k]);
	}
	sss_exr_free(back);
}

static void fuzz_exr(const uint8_t *data, size_t size)
{
	if (put_input(data, size))
		return;
	sss_exr_options o;
	sss_exr_options_default(&o);
	o.max_width = MAX_SIDE;
	o.max_height = MAX_SIDE;
	o.max_pixels = MAX_PIXELS;
	o.num_threads = 1; /* libFuzzer runs are best single-threaded */
	/* The last byte picks the output codec (DWA ones are refused). */
	o.compression = size ? data[size - 1] % 10 : SSS_EXR_ZIP;

	sss_exr *exr = NULL;
	char err[1024];
	if (sss_exr_read(in_path, &o, &exr, err, sizeof err) != SSS_OK) {
		FUZZ_ASSERT(exr == NULL, "failed read left an image");
		return;
	}
	int32_t w = sss_exr_width(exr), h = sss_exr_height(exr);
	FUZZ_ASSERT(w >= 1 && h >= 1 && w <= MAX_SIDE && h <= MAX_SIDE &&
	            (int64_t)w * h <= MAX_PIXELS, "size %dx%d past the caps",
	            w, h);
	size_t npix = (size_t)w * (size_t)h;

	/* Every pass's view is inside the image and has its components. */
	for (int32_t i = 0; i < sss_exr_pass_count(exr); i++) {
		const char *layer, *pass, *comp;
		sss_image v;
		FUZZ_ASSERT(sss_exr_pass(exr, i, &layer, &pass, &comp, &v) == SSS_OK,
		            "pass %d", i);
		/* (comp may be "": a channel "x." has an empty component) */
		FUZZ_ASSERT(v.data && v.width == w && v.height == h &&
		            v.channels >= 1 && layer && pass && comp,
		            "pass %d view", i);
		/* touch the last value: ASan checks the buffer's extent */
		volatile float last = v.data[npix * (size_t)v.channels - 1];
		(void)last;
	}

	sss_passes passes;
	const char *layer = NULL;
	float *combined = NULL, *light = NULL;
	int applied = 0;
	if (sss_exr_render_passes(exr, NULL, &passes, &layer, err, sizeof err)
	    == SSS_OK && npix <= APPLY_PIXELS) {
		FUZZ_ASSERT(layer != NULL, "no layer_used on success");
		sss_material mats[5];
		int nmat = default_materials(mats);
		sss_camera cam;
		sss_camera_default(&cam);
		sss_options opt;
		sss_options_default(&opt);
		opt.num_threads = 1;
		if (size > 1 && (data[size - 2] & 1) && npix <= REFERENCE_PIXELS)
			opt.method = SSS_METHOD_REFERENCE;
		combined = malloc(npix * 4 * sizeof *combined);
		light = malloc(npix * 3 * sizeof *light);
		if (combined && light) {
			sss_image oc = {combined, w, h, 4, 0};
			sss_image ol = {light, w, h, 3, 0};
			sss_result r = sss_apply(&passes, &cam, mats, nmat, &opt, &oc,
			                         &ol, err, sizeof err);
			/* Valid passes from a file, a valid camera and table: any
			 * pixel values (NaN, Inf, huge depth) must be accepted. */
			FUZZ_ASSERT(r == SSS_OK, "sss_apply on layer '%s': %s: %s",
			            layer, sss_status_name(r), err);
			applied = 1;
		}
	}

	/* Add passes as the command does (replacing one that exists), then
	 * write; tiny images are read back and compared. */
	float *mask = calloc(npix, sizeof *mask);
	sss_result r = mask ? sss_exr_add_pass(exr, "Fuzz", "Mask", "Y", mask,
	                                       err, sizeof err)
	                    : SSS_ERR_OUT_OF_MEMORY;
	if (r == SSS_OK && applied)
		r = sss_exr_add_pass(exr, "SSS", "Combined", "RGBA", combined, err,
		                     sizeof err);
	if (r == SSS_OK && applied)
		r = sss_exr_add_pass(exr, "SSS", "DiffLight", "RGB", light, err,
		                     sizeof err);
	FUZZ_ASSERT(r == SSS_OK || r == SSS_ERR_OUT_OF_MEMORY,
	            "sss_exr_add_pass: %s", err);
	if (r == SSS_OK) {
		r = sss_exr_write(exr, out_path, &o, err, sizeof err);
		/* DWA is refused by OpenEXR 3.1; anything else must write. */
		FUZZ_ASSERT(r == SSS_OK || o.compression >= SSS_EXR_DWAA,
		            "sss_exr_write: %s: %s", sss_status_name(r), err);
		if (r == SSS_OK && npix <= APPLY_PIXELS)
			check_round_trip(exr, out_path, o.compression);
		unlink(out_path);
	}
	free(mask);
	free(combined);
	free(light);
	sss_exr_free(exr);
}

/* -------------------------------------------------------------- scene */

/* A scene that parses must be accepted by sss_apply: run it on 8x8
 * synthetic passes whose pixels use every material of its table. */
static void apply_scene(const sss_scene *scene)
{
	enum { W = 8, H = 8, N = W * H };
	static float dd[N * 3], dc[N * 3], z[N], idx[N], oc[N * 4], ol[N * 3];
	int32_t count = 0;
	const sss_material *mats = sss_scene_materials(scene, &count);
	for (int i = 0; i < N; i++) {
		for (int c = 0; c < 3; c++) {
			dd[i * 3 + c] = 1.0f + 0.1f * (float)(i % 7);
			dc[i * 3 + c] = 0.5f;
		}
		z[i] = 1.0f + 0.05f * (float)(i % W);
		idx[i] = count ? (float)mats[i % count].pass_index : 0.0f;
	}
	sss_passes p;
	memset(&p, 0, sizeof p);
	p.diff_dir = (sss_image){dd, W, H, 3, 0};
	p.diff_col = (sss_image){dc, W, H, 3, 0};
	p.depth = (sss_image){z, W, H, 1, 0};
	p.index_ma = (sss_image){idx, W, H, 1, 0};
	sss_options opt = *sss_scene_options(scene);
	opt.num_threads = 1; /* keep the fuzzer single-threaded */
	sss_image out_c = {oc, W, H, 4, 0}, out_l = {ol, W, H, 3, 0};
	char err[512];
	sss_result r = sss_apply(&p, sss_scene_camera(scene), mats, count, &opt,
	                         &out_c, &out_l, err, sizeof err);
	/* The reserved methods parse and are then refused as unsupported
	 * (docs/scene.md); everything else must run. */
	int reserved = opt.method == SSS_METHOD_SEPARABLE_EXACT ||
	               opt.method == SSS_METHOD_DISK;
	FUZZ_ASSERT(r == SSS_OK || (r == SSS_ERR_UNSUPPORTED && reserved),
	            "parsed scene refused by sss_apply: %s: %s",
	            sss_status_name(r), err);
}

static void fuzz_scene(const uint8_t *data, size_t size)
{
	sss_scene *scene = NULL;
	char warn[512], err[512];
	sss_result r = sss_scene_parse((const char *)data, size, &scene, warn,
	                               sizeof warn, err, sizeof err);
	if (r != SSS_OK) {
		FUZZ_ASSERT(scene == NULL, "failed parse left a scene");
		FUZZ_ASSERT(err[0] != '\0', "error without a message");
		return;
	}
	int32_t count = -1;
	sss_scene_materials(scene, &count);
	FUZZ_ASSERT(count >= 0, "material count %d", count);
	for (int32_t i = 0; i < count; i++)
		FUZZ_ASSERT(sss_scene_material_name(scene, i) != NULL, "name %d", i);
	FUZZ_ASSERT(sss_scene_material_name(scene, count) == NULL, "name past "
	            "the end");
	apply_scene(scene);
	sss_scene_free(scene);
}

/* ---------------------------------------------------------------- entry */

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	if (size > 0 && data[0] == '{')
		fuzz_scene(data, size);
	else if (size > 0 && data[0] == 'J')
		fuzz_scene(data + 1, size - 1);
	else
		fuzz_exr(data, size);
	return 0;
}
