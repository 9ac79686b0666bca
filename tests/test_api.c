/* test_api.c - status tables, defaults, struct sizes and the exact status
 * of every bad argument to the public entry points. */
#include "synth.h"
#include "test_util.h"

#include <math.h>
#include <string.h>

static void test_status_tables(void)
{
	for (int c = SSS_OK; c <= SSS_ERR_UNKNOWN; c++) {
		CHECK("status-1", strncmp(sss_status_name(c), "SSS_", 4) == 0,
		      "code %d has name %s", c, sss_status_name(c));
		CHECK("status-2", strlen(sss_status_string(c)) > 3,
		      "code %d has no message", c);
		for (int d = SSS_OK; d < c; d++)
			CHECK("status-3", strcmp(sss_status_name(c),
			                         sss_status_name(d)) != 0,
			      "codes %d and %d share a name", c, d);
	}
	CHECK("status-4", strcmp(sss_status_name(-5), "SSS_ERR_UNKNOWN") == 0,
	      "negative code");
	CHECK("status-5", strcmp(sss_status_name(999), "SSS_ERR_UNKNOWN") == 0,
	      "large code");
	CHECK("status-6", sss_abi_version() == SSS_ABI_VERSION, "abi");
	CHECK("status-7", strcmp(sss_version_string(), SSS_VERSION_STRING) == 0,
	      "version");
}

static void test_struct_sizes(void)
{
	CHECK("size-1", sss_struct_size("sss_options") == sizeof(sss_options),
	      "options");
	CHECK("size-2", sss_struct_size("sss_material") == sizeof(sss_material),
	      "material");
	CHECK("size-3", sss_struct_size("sss_camera") == sizeof(sss_camera),
	      "camera");
	CHECK("size-4", sss_struct_size("sss_passes") == sizeof(sss_passes),
	      "passes");
	CHECK("size-5", sss_struct_size("sss_image") == sizeof(sss_image),
	      "image");
	CHECK("size-6", sss_struct_size("nope") == 0, "unknown name");
	CHECK("size-7", sss_struct_size(NULL) == 0, "NULL name");
}

static void test_material_validation(void)
{
	char err[256];
	int kinds[] = {SSS_PROFILE_NONE, SSS_PROFILE_BURLEY,
	               SSS_PROFILE_GAUSSIANS, SSS_PROFILE_JIMENEZ,
	               SSS_PROFILE_NEAR_FAR};
	for (size_t i = 0; i < sizeof kinds / sizeof *kinds; i++) {
		sss_material m;
		sss_material_default(&m, kinds[i]);
		m.pass_index = 1;
		CHECK_STATUS("mat-default", SSS_OK, sss_material_validate(&m, err,
		                                                        sizeof err));
	}
	/* "No upper bound" is 1e30 as a float holds it (1.0000000150e30). */
	{
		sss_material big;
		sss_material_default(&big, SSS_PROFILE_BURLEY);
		big.pass_index = 1;
		big.radius[0] = 1e30f;
		CHECK_STATUS("mat-radius-1e30", SSS_OK,
		             sss_material_validate(&big, err, sizeof err));
		big.radius[0] = 2e30f;
		CHECK_STATUS("mat-radius-2e30", SSS_ERR_INVALID_ARGUMENT,
		             sss_material_validate(&big, err, sizeof err));
		sss_material_default(&big, SSS_PROFILE_GAUSSIANS);
		big.pass_index = 1;
		big.gaussian_variance[0] = 1e30f;
		big.gaussian_weight[0][0] = 1e30f;
		CHECK_STATUS("mat-gaussian-1e30", SSS_OK,
		             sss_material_validate(&big, err, sizeof err));
	}
	sss_material m;

#define BAD(id, kind, stmt, needle)                                          \
	do {                                                                     \
		sss_material_default(&m, kind);                                      \
		m.pass_index = 7;                                                    \
		stmt;                                                                \
		err[0] = 0;                                                          \
		CHECK_STATUS(id, SSS_ERR_INVALID_ARGUMENT,                           \
		             sss_material_validate(&m, err, sizeof err));            \
		CHECK(id, strstr(err, needle) != NULL, "message '%s' lacks '%s'",    \
		      err, needle);                                                  \
	} while (0)

	BAD("mat-1", SSS_PROFILE_BURLEY, m.radius[1] = -0.001f, "radius.g");
	BAD("mat-2", SSS_PROFILE_BURLEY, m.radius[0] = NAN, "radius.r");
	BAD("mat-3", SSS_PROFILE_BURLEY, m.strength = NAN, "strength");
	BAD("mat-4", SSS_PROFILE_BURLEY, m.strength = 1.5f, "strength");
	BAD("mat-5", SSS_PROFILE_BURLEY, m.pass_index = 0, "pass_index");
	BAD("mat-6", SSS_PROFILE_BURLEY, m.pass_index = 70000, "pass_index");
	BAD("mat-7", SSS_PROFILE_BURLEY, m.burley_mapping = 9, "burley_mapping");
	BAD("mat-8", SSS_PROFILE_BURLEY,
	    (m.burley_mapping = SSS_BURLEY_RANDOM_WALK, m.albedo[2] = 2.0f),
	    "albedo.b");
	BAD("mat-9", SSS_PROFILE_GAUSSIANS, m.gaussian_count = 0,
	    "gaussian_count");
	BAD("mat-10", SSS_PROFILE_GAUSSIANS, m.gaussian_variance[2] = 0.0f,
	    "gaussian_variance[2]");
	BAD("mat-11", SSS_PROFILE_GAUSSIANS, m.gaussian_weight[1][0] = -1.0f,
	    "gaussian_weight[1]");
	BAD("mat-12", SSS_PROFILE_JIMENEZ, m.jimenez_falloff[2] = 0.0f,
	    "jimenez_falloff.b");
	BAD("mat-13", SSS_PROFILE_JIMENEZ, m.jimenez_width = INFINITY,
	    "jimenez_width");
	BAD("mat-14", SSS_PROFILE_NEAR_FAR, m.near_far_balance = -0.1f,
	    "near_far_balance");
	BAD("mat-15", SSS_PROFILE_NEAR_FAR, m.near_sigma[0] = 0.0f,
	    "near_sigma.r");
	BAD("mat-16", SSS_PROFILE_BURLEY, m.taps = 5000, "taps");
	BAD("mat-17", SSS_PROFILE_BURLEY, m.texturing = 3, "texturing");
	BAD("mat-18", SSS_PROFILE_BURLEY, m.kind = 42, "kind");
	BAD("mat-19", SSS_PROFILE_BURLEY, m.struct_size = 3, "struct_size");
	BAD("mat-20", SSS_PROFILE_GAUSSIANS,
	    (m.gaussian_count = 1, m.gaussian_weight[0][1] = 0.0f), "channel 1");
	CHECK_STATUS("mat-21", SSS_ERR_INVALID_ARGUMENT,
	             sss_material_validate(NULL, NULL, 0));
}

/* A valid 8x6 call, then one field broken at a time. */
static void test_apply_arguments(void)
{
	synth *s = synth_new(8, 6);
	synth_plane(s, 0, 0, 8, 6, 2.0f, 1.0f);
	sss_passes p = synth_passes(s);
	sss_camera cam;
	sss_camera_default(&cam);
	sss_material mat;
	sss_material_default(&mat, SSS_PROFILE_BURLEY);
	mat.pass_index = 1;
	sss_options opt;
	sss_options_default(&opt);
	float *buf = calloc(8 * 6 * 4, sizeof(float));
	sss_image out = {buf, 8, 6, 4, 0};
	char err[256];

	CHECK_STATUS("apply-ok", SSS_OK,
	             sss_apply(&p, &cam, &mat, 1, &opt, &out, NULL, err,
	                       sizeof err));
	CHECK_STATUS("apply-null-opt", SSS_OK,
	             sss_apply(&p, &cam, &mat, 1, NULL, &out, NULL, NULL, 0));

#define BAD_APPLY(id, code, setup, undo, needle)                             \
	do {                                                                     \
		setup;                                                               \
		err[0] = 0;                                                          \
		CHECK_STATUS(id, code, sss_apply(&p, &cam, &mat, 1, &opt, &out,      \
		                                 NULL, err, sizeof err));            \
		CHECK(id, strstr(err, needle) != NULL, "message '%s' lacks '%s'",    \
		      err, needle);                                                  \
		undo;                                                                \
	} while (0)

	BAD_APPLY("apply-1", SSS_ERR_MISSING_PASS, p.depth.data = NULL,
	          p.depth.data = s->depth, "Depth");
	BAD_APPLY("apply-2", SSS_ERR_MISSING_PASS, p.index_ma.data = NULL,
	          p.index_ma.data = s->index, "IndexMA");
	BAD_APPLY("apply-3", SSS_ERR_MISSING_PASS, p.diff_col.data = NULL,
	          p.diff_col.data = s->diff_col, "DiffCol");
	BAD_APPLY("apply-4", SSS_ERR_SIZE_MISMATCH, p.gloss_dir.width = 7,
	          p.gloss_dir.width = 8, "GlossDir");
	BAD_APPLY("apply-5", SSS_ERR_INVALID_ARGUMENT,
	          (p.diff_dir.width = 0, p.diff_dir.height = 0),
	          (p.diff_dir.width = 8, p.diff_dir.height = 6), "DiffDir");
	BAD_APPLY("apply-6", SSS_ERR_INVALID_ARGUMENT, p.diff_col.channels = 1,
	          p.diff_col.channels = 3, "DiffCol");
	BAD_APPLY("apply-7", SSS_ERR_INVALID_ARGUMENT, p.emit.row_stride = 5,
	          p.emit.row_stride = 0, "Emit");
	BAD_APPLY("apply-8", SSS_ERR_INVALID_ARGUMENT, mat.radius[0] = -1.0f,
	          mat.radius[0] = 0.01f, "radius");
	BAD_APPLY("apply-9", SSS_ERR_INVALID_ARGUMENT, mat.strength = NAN,
	          mat.strength = 1.0f, "strength");
	BAD_APPLY("apply-10", SSS_ERR_INVALID_ARGUMENT, opt.radius_scale = -1,
	          opt.radius_scale = 1,
	          "options: radius_scale -1 must be finite and >= 0");
	BAD_APPLY("apply-11", SSS_ERR_INVALID_ARGUMENT, opt.taps = 0,
	          opt.taps = 33, "options: taps 0 must be 1..4097");
	BAD_APPLY("apply-12", SSS_ERR_INVALID_ARGUMENT, opt.samples = 0,
	          opt.samples = 64,
	          "options: samples 0 must be 1..4096");
	BAD_APPLY("apply-12b", SSS_ERR_INVALID_ARGUMENT, opt.crease = 3,
	          opt.crease = 1, "options: crease 3 must be 0..2");
	BAD_APPLY("apply-13", SSS_ERR_INVALID_ARGUMENT, opt.method = 17,
	          opt.method = 0,
	          "options: unknown method 17 (expected 0..4)");
	BAD_APPLY("apply-14", SSS_ERR_INVALID_ARGUMENT, cam.lens_mm = 0,
	          cam.lens_mm = 50,
	          "camera: lens_mm = 0 is out of range (must be finite and > 0)");
	BAD_APPLY("apply-15", SSS_ERR_INVALID_ARGUMENT, cam.unit_scale = NAN,
	          cam.unit_scale = 1,
	          "camera: unit_scale = nan is out of range (must be finite "
	          "and > 0)");
	BAD_APPLY("apply-16", SSS_ERR_INVALID_ARGUMENT, out.data = s->diff_dir,
	          out.data = buf, "overlaps");
	BAD_APPLY("apply-17", SSS_ERR_SIZE_MISMATCH, out.height = 5,
	          out.height = 6, "combined");
	BAD_APPLY("apply-18", SSS_ERR_INVALID_ARGUMENT, opt.struct_size = 1,
	          opt.struct_size = sizeof opt, "struct_size");
	BAD_APPLY("apply-19", SSS_ERR_INVALID_ARGUMENT, opt.num_threads = -1,
	          opt.num_threads = 0,
	          "options: num_threads -1 must be 0..256");
	BAD_APPLY("apply-20", SSS_ERR_INVALID_ARGUMENT,
	          opt.background_depth = NAN, opt.background_depth = 1e9,
	          "background_depth");

	sss_material two[2] = {mat, mat};
	err[0] = 0;
	CHECK_STATUS("apply-dup", SSS_ERR_INVALID_ARGUMENT,
	             sss_apply(&p, &cam, two, 2, &opt, &out, NULL, err,
	                       sizeof err));
	CHECK("apply-dup", strstr(err, "twice") != NULL, "message '%s'", err);
	CHECK_STATUS("apply-noout", SSS_ERR_INVALID_ARGUMENT,
	             sss_apply(&p, &cam, &mat, 1, &opt, NULL, NULL, err,
	                       sizeof err));
	CHECK_STATUS("apply-nopasses", SSS_ERR_INVALID_ARGUMENT,
	             sss_apply(NULL, &cam, &mat, 1, &opt, &out, NULL, err,
	                       sizeof err));
	CHECK_STATUS("apply-count", SSS_ERR_INVALID_ARGUMENT,
	             sss_apply(&p, &cam, NULL, 3, &opt, &out, NULL, err,
	                       sizeof err));
	CHECK_STATUS("apply-empty-table", SSS_OK,
	             sss_apply(&p, &cam, NULL, 0, &opt, &out, NULL, err,
	                       sizeof err));
	BAD_APPLY("apply-21", SSS_ERR_INVALID_ARGUMENT, opt.max_support_px = 0,
	          opt.max_support_px = 256,
	          "options: max_support_px 0 must be >= 1");
	BAD_APPLY("apply-22", SSS_ERR_INVALID_ARGUMENT, cam.type = 2,
	          cam.type = SSS_CAMERA_PERSPECTIVE,
	          "camera: unknown type 2 (expected 0, 1)");
	BAD_APPLY("apply-23", SSS_ERR_INVALID_ARGUMENT, cam.shift_x = INFINITY,
	          cam.shift_x = 0, "camera: shift_x = inf is out of range "
	          "(must be finite)");
	/* What the options and the camera accepted before their checks were
	 * made from their tables, they still accept: an infinite background
	 * depth, any finite radius scale, the lengths a camera type does not
	 * read. */
	opt.background_depth = INFINITY;
	opt.radius_scale = 1e35f;
	cam.type = SSS_CAMERA_ORTHOGRAPHIC;
	cam.lens_mm = 0;
	CHECK_STATUS("apply-still-accepted", SSS_OK,
	             sss_apply(&p, &cam, &mat, 1, &opt, &out, NULL, err,
	                       sizeof err));
	sss_options_default(&opt);
	sss_camera_default(&cam);
	cam.type = SSS_CAMERA_ORTHOGRAPHIC;
	cam.ortho_scale = -1;
	err[0] = 0;
	CHECK_STATUS("apply-ortho-scale", SSS_ERR_INVALID_ARGUMENT,
	             sss_apply(&p, &cam, &mat, 1, &opt, &out, NULL, err,
	                       sizeof err));
	CHECK("apply-ortho-scale.msg", strstr(err, "ortho_scale") != NULL,
	      "message '%s'", err);
	sss_camera_default(&cam);
	/* A stride near 2^60 overflowed the image's span (UBSan), no status. */
	BAD_APPLY("apply-stride-huge", SSS_ERR_INVALID_ARGUMENT,
	          out.row_stride = (int64_t)1 << 60, out.row_stride = 0,
	          "address space");
	BAD_APPLY("apply-stride-huge-in", SSS_ERR_INVALID_ARGUMENT,
	          p.depth.row_stride = INT64_MAX / 2, p.depth.row_stride = 0,
	          "address space");
	/* Both outputs in one buffer: both were wrong, with SSS_OK. */
	sss_image light = {buf + 4, 8, 6, 3, 32};
	err[0] = 0;
	CHECK_STATUS("apply-outputs-shared", SSS_ERR_INVALID_ARGUMENT,
	             sss_apply(&p, &cam, &mat, 1, &opt, &out, &light, err,
	                       sizeof err));
	CHECK("apply-outputs-shared.msg", strstr(err, "share memory") != NULL,
	      "message '%s'", err);
	free(buf);
	synth_free(s);
}

static void test_helpers_reject(void)
{
	sss_material m;
	sss_material_default(&m, SSS_PROFILE_BURLEY);
	m.pass_index = 1;
	float off[8], w[24];
	int32_t n = 8;
	CHECK_STATUS("kern-1", SSS_ERR_INVALID_ARGUMENT,
	             sss_kernel_1d(&m, -1.0, 0, off, w, &n));
	n = 8;
	CHECK_STATUS("kern-2", SSS_ERR_INVALID_ARGUMENT,
	             sss_kernel_1d(&m, NAN, 0, off, w, &n));
	n = 1; /* too small for a visible kernel */
	CHECK_STATUS("kern-3", SSS_ERR_INVALID_ARGUMENT,
	             sss_kernel_1d(&m, 1e4, 0, off, w, &n));
	/* 1e12 pixels per metre overflowed a float-to-int conversion
	 * (UBSan) and returned SSS_OK with every weight 0. */
	n = 8;
	CHECK_STATUS("kern-huge-ppm", SSS_ERR_INVALID_ARGUMENT,
	             sss_kernel_1d(&m, 1e12, 0, off, w, &n));
	n = 8;
	CHECK_STATUS("kern-max-ppm", SSS_ERR_INVALID_ARGUMENT,
	             sss_kernel_1d(&m, 1.7e308, 0, off, w, &n));
	double metres;
	CHECK_STATUS("support-1", SSS_ERR_INVALID_ARGUMENT,
	             sss_material_support(NULL, &metres));
	double d[3];
	sss_material g;
	sss_material_default(&g, SSS_PROFILE_GAUSSIANS);
	CHECK_STATUS("burley-d-1", SSS_ERR_INVALID_ARGUMENT, sss_burley_d(&g, d));
}

/* The methods are named in one place: every enum value has a distinct
 * name and a summary, the list ends at the first NULL, and the scene
 * parser and sss_apply accept exactly those. */
static void test_method_names(void)
{
	int32_t n = 0;
	while (sss_method_name(n))
		n++;
	CHECK("methods.count", n == SSS_METHOD_REFERENCE + 1, "%d", n);
	CHECK("methods.out-of-range", !sss_method_name(-1) &&
	      !sss_method_summary(-1) && !sss_method_summary(n), "not NULL");
	for (int32_t m = 0; m < n; m++) {
		CHECK("methods.summary", sss_method_summary(m) &&
		      strlen(sss_method_summary(m)) > 10, "%d", m);
		for (int32_t k = 0; k < m; k++)
			CHECK("methods.distinct", strcmp(sss_method_name(m),
			      sss_method_name(k)) != 0, "%s", sss_method_name(m));
		char json[128], err[256];
		snprintf(json, sizeof json, "{\"method\": \"%s\"}",
		         sss_method_name(m));
		sss_scene *sc = NULL;
		CHECK_STATUS("methods.parsed", SSS_OK,
		             sss_scene_parse(json, strlen(json), &sc, NULL, 0, err,
		                             sizeof err));
		CHECK("methods.parsed-value", sc &&
		      sss_scene_options(sc)->method == m, "%s",
		      sss_method_name(m));
		sss_scene_free(sc);
	}
}

/* The render passes' table: every sss_passes member up to position, each
 * with its components and Blender's pass; the four the library needs. */
static void test_render_passes(void)
{
	sss_pass_info info;
	int32_t i = 0, required = 0;
	for (; sss_render_pass(i, &info) == SSS_OK; i++) {
		CHECK("pass-fields", info.name && info.components && info.blender &&
		      info.hint && strlen(info.components) >= 1, "pass %d", i);
		required += info.need == SSS_PASS_REQUIRED;
	}
	CHECK("pass-count", i == 15, "%d passes", i);
	CHECK("pass-required", required == 4, "%d required", required);
	CHECK_STATUS("pass-past-end", SSS_ERR_INVALID_ARGUMENT,
	             sss_render_pass(i, &info));
	CHECK_STATUS("pass-null", SSS_ERR_INVALID_ARGUMENT,
	             sss_render_pass(0, NULL));
	CHECK("pass-size", sss_struct_size("sss_pass_info") == sizeof info,
	      "size");
}

/* sss_camera_pixels_per_metre: Blender's projection as the blur uses it,
 * for UIs. */
static void test_camera_pixels_per_metre(void)
{
	char err[256];
	sss_camera cam;
	sss_camera_default(&cam);
	cam.lens_mm = 50.0;
	cam.sensor_width_mm = 36.0;
	double ppm = 0.0;
	CHECK_STATUS("ppm-persp", SSS_OK,
	             sss_camera_pixels_per_metre(&cam, 1920, 1080, 2.0, &ppm, err,
	                                         sizeof err));
	CHECK("ppm-persp-value", fabs(ppm - 1920.0 * 50.0 / (36.0 * 2.0)) < 1e-9,
	      "%g", ppm);
	cam.unit_scale = 0.01; /* centimetres: 2 units are 2 cm */
	sss_camera_pixels_per_metre(&cam, 1920, 1080, 2.0, &ppm, err, sizeof err);
	CHECK("ppm-units", fabs(ppm - 100.0 * 1920.0 * 50.0 / 72.0) < 1e-6,
	      "%g", ppm);
	cam.unit_scale = 1.0;
	cam.type = SSS_CAMERA_ORTHOGRAPHIC;
	cam.ortho_scale = 4.0;
	CHECK_STATUS("ppm-ortho", SSS_OK,
	             sss_camera_pixels_per_metre(&cam, 1000, 2000, 0.0, &ppm, err,
	                                         sizeof err));
	CHECK("ppm-ortho-value", fabs(ppm - 2000.0 / 4.0) < 1e-9,
	      "vertical fit (taller than wide): %g", ppm);
	cam.type = SSS_CAMERA_PERSPECTIVE;
	CHECK_STATUS("ppm-depth", SSS_ERR_INVALID_ARGUMENT,
	             sss_camera_pixels_per_metre(&cam, 64, 64, -1.0, &ppm, err,
	                                         sizeof err));
	CHECK("ppm-depth-says", strstr(err, "depth") != NULL, "%s", err);
	CHECK_STATUS("ppm-size", SSS_ERR_INVALID_ARGUMENT,
	             sss_camera_pixels_per_metre(&cam, 0, 64, 1.0, &ppm, err,
	                                         sizeof err));
	CHECK_STATUS("ppm-null", SSS_ERR_INVALID_ARGUMENT,
	             sss_camera_pixels_per_metre(&cam, 64, 64, 1.0, NULL, err,
	                                         sizeof err));
	cam.lens_mm = 0.0;
	CHECK_STATUS("ppm-camera", SSS_ERR_INVALID_ARGUMENT,
	             sss_camera_pixels_per_metre(&cam, 64, 64, 1.0, &ppm, err,
	                                         sizeof err));
}

int main(void)
{
	test_camera_pixels_per_metre();
	test_render_passes();
	test_status_tables();
	test_method_names();
	test_struct_sizes();
	test_material_validation();
	test_apply_arguments();
	test_helpers_reject();
	return tu_finish("test_api");
}
