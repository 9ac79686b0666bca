/* test_scene.c - the JSON scene description: exact structs from a full
 * scene, defaults, every error with its key path, warnings, files, and a
 * loaded scene that sss_apply accepts. */
#include "sss_camera_fields.h"
#include "synth.h"
#include "test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static sss_result parse(const char *json, sss_scene **out, char *warn,
                        size_t warn_len, char *err, size_t err_len)
{
	return sss_scene_parse(json, strlen(json), out, warn, warn_len, err,
	                       err_len);
}

static int camera_equal(const sss_camera *a, const sss_camera *b)
{
	return a->struct_size == b->struct_size && a->type == b->type &&
	       a->lens_mm == b->lens_mm &&
	       a->sensor_width_mm == b->sensor_width_mm &&
	       a->sensor_height_mm == b->sensor_height_mm &&
	       a->sensor_fit == b->sensor_fit && a->shift_x == b->shift_x &&
	       a->shift_y == b->shift_y && a->ortho_scale == b->ortho_scale &&
	       a->pixel_aspect_x == b->pixel_aspect_x &&
	       a->pixel_aspect_y == b->pixel_aspect_y &&
	       a->unit_scale == b->unit_scale;
}

static int options_equal(const sss_options *a, const sss_options *b)
{
	return a->struct_size == b->struct_size && a->method == b->method &&
	       a->radius_scale == b->radius_scale && a->taps == b->taps &&
	       a->num_threads == b->num_threads &&
	       a->background_depth == b->background_depth &&
	       a->max_support_px == b->max_support_px &&
	       a->samples == b->samples && a->crease == b->crease;
}

/* sss_material has only 4-byte members (no padding), and both sides start
 * from sss_material_default's memset, so bytes compare exactly. */
static int material_equal(const sss_material *a, const sss_material *b)
{
	return memcmp(a, b, sizeof *a) == 0;
}

static void set3(float *v, float a, float b, float c)
{
	v[0] = a;
	v[1] = b;
	v[2] = c;
}

static const char *full_scene =
	"{\n"
	"  \"version\": 1,\n"
	"  \"camera\": {\"type\": \"ORTHO\", \"lens\": 85, \"sensor_width\": 35,"
	" \"sensor_height\": 20.5, \"sensor_fit\": \"VERTICAL\", \"shift_x\": 0.1,"
	" \"shift_y\": -0.25, \"ortho_scale\": 4.5, \"clip_start\": 0.01,"
	" \"clip_end\": 250, \"pixel_aspect_x\": 2, \"pixel_aspect_y\": 1.5},\n"
	"  \"unit_scale\": 0.01,\n"
	"  \"method\": \"reference\",\n"
	"  \"radius_scale\": 1.5, \"taps\": 65, \"threads\": 4,\n"
	"  \"background_depth\": 5e9, \"max_support_px\": 128,\n"
	"  \"crease\": 0,\n"
	"  \"materials\": [\n"
	"    {\"pass_index\": 7, \"name\": \"Skin\", \"profile\": \"burley\","
	" \"strength\": 0.75, \"texturing\": \"pre-and-post\", \"taps\": 21,"
	" \"radius\": [0.004, 0.002, 0.001], \"mapping\": \"random-walk\","
	" \"albedo\": [0.9, 0.5, 0.25]},\n"
	"    {\"pass_index\": 2, \"name\": \"Marble\", \"profile\": \"gaussians\","
	" \"gaussians\": [{\"variance\": 0.5, \"weight\": [1, 0.5, 0.25]},"
	" {\"variance\": 2, \"weight\": [0, 0.5, 0.75]}], \"scale\": 2.5},\n"
	"    {\"pass_index\": 65535, \"profile\": \"jimenez\", \"texturing\":"
	" \"post\", \"width\": 0.02, \"strength_rgb\": [0.5, 0.25, 0.125],"
	" \"falloff\": [1, 0.5, 0.25]},\n"
	"    {\"pass_index\": 1, \"name\": \"Wax\", \"profile\": \"near-far\","
	" \"strength\": 0, \"scatter_scale\": 3, \"balance\": 0.25,"
	" \"near_sigma\": [0.5, 0.25, 0.125], \"far_sigma\": [2, 1, 0.5]},\n"
	"    {\"pass_index\": 9, \"name\": \"\", \"profile\": \"none\"}\n"
	"  ]\n"
	"}\n";

static void test_full_scene(void)
{
	char warn[256], err[256];
	sss_scene *sc = NULL;
	CHECK_STATUS("full-1", SSS_OK,
	             parse(full_scene, &sc, warn, sizeof warn, err, sizeof err));
	CHECK("full-2", sc != NULL, "no scene: %s", err);
	CHECK("full-3", warn[0] == '\0', "warnings: %s", warn);
	if (!sc)
		return;

	sss_camera cam;
	sss_camera_default(&cam);
	cam.type = SSS_CAMERA_ORTHOGRAPHIC;
	cam.lens_mm = 85;
	cam.sensor_width_mm = 35;
	cam.sensor_height_mm = 20.5;
	cam.sensor_fit = SSS_SENSOR_FIT_VERTICAL;
	cam.shift_x = 0.1;
	cam.shift_y = -0.25;
	cam.ortho_scale = 4.5;
	cam.pixel_aspect_x = 2;
	cam.pixel_aspect_y = 1.5;
	cam.unit_scale = 0.01;
	CHECK("full-camera", camera_equal(sss_scene_camera(sc), &cam),
	      "camera differs");

	sss_options opt;
	sss_options_default(&opt);
	opt.method = SSS_METHOD_REFERENCE;
	opt.radius_scale = 1.5f;
	opt.taps = 65;
	opt.num_threads = 4;
	opt.background_depth = 5e9;
	opt.max_support_px = 128;
	opt.crease = 0;
	CHECK("full-options", options_equal(sss_scene_options(sc), &opt),
	      "options differ");

	sss_material m[5];
	sss_material_default(&m[0], SSS_PROFILE_BURLEY);
	m[0].pass_index = 7;
	m[0].strength = 0.75f;
	m[0].texturing = SSS_TEXTURING_PRE_AND_POST;
	m[0].taps = 21;
	set3(m[0].radius, 0.004f, 0.002f, 0.001f);
	m[0].burley_mapping = SSS_BURLEY_RANDOM_WALK;
	set3(m[0].albedo, 0.9f, 0.5f, 0.25f);

	sss_material_default(&m[1], SSS_PROFILE_GAUSSIANS);
	m[1].pass_index = 2;
	memset(m[1].gaussian_variance, 0, sizeof m[1].gaussian_variance);
	memset(m[1].gaussian_weight, 0, sizeof m[1].gaussian_weight);
	m[1].gaussian_count = 2;
	m[1].gaussian_variance[0] = 0.5f;
	set3(m[1].gaussian_weight[0], 1.0f, 0.5f, 0.25f);
	m[1].gaussian_variance[1] = 2.0f;
	set3(m[1].gaussian_weight[1], 0.0f, 0.5f, 0.75f);
	m[1].gaussian_scale = 2.5f;

	sss_material_default(&m[2], SSS_PROFILE_JIMENEZ);
	m[2].pass_index = 65535;
	m[2].jimenez_width = 0.02f;
	set3(m[2].jimenez_strength, 0.5f, 0.25f, 0.125f);
	set3(m[2].jimenez_falloff, 1.0f, 0.5f, 0.25f);

	sss_material_default(&m[3], SSS_PROFILE_NEAR_FAR);
	m[3].pass_index = 1;
	m[3].strength = 0.0f;
	m[3].scatter_scale = 3.0f;
	m[3].near_far_balance = 0.25f;
	set3(m[3].near_sigma, 0.5f, 0.25f, 0.125f);
	set3(m[3].far_sigma, 2.0f, 1.0f, 0.5f);

	sss_material_default(&m[4], SSS_PROFILE_NONE);
	m[4].pass_index = 9;

	int32_t count = -1;
	const sss_material *got = sss_scene_materials(sc, &count);
	CHECK("full-count", count == 5, "count %d", count);
	static const char *const names[5] = {"Skin", "Marble", "material 65535",
	                                     "Wax", ""};
	for (int i = 0; i < 5 && i < count; i++) {
		CHECK("full-material", material_equal(&got[i], &m[i]),
		      "material %d differs", i);
		const char *name = sss_scene_material_name(sc, i);
		CHECK("full-name", name && strcmp(name, names[i]) == 0,
		      "name %d is '%s'", i, name ? name : "(null)");
	}
	CHECK("full-name-range", sss_scene_material_name(sc, 5) == NULL &&
	      sss_scene_material_name(sc, -1) == NULL, "out of range name");
	sss_scene_free(sc);
}

static void test_defaults(void)
{
	char err[256];
	sss_scene *sc = NULL;
	sss_camera cam;
	sss_camera_default(&cam);
	sss_options opt;
	sss_options_default(&opt);

	CHECK_STATUS("def-empty", SSS_OK,
	             parse("{}", &sc, NULL, 0, err, sizeof err));
	int32_t count = -1;
	CHECK("def-empty-2", sc && sss_scene_materials(sc, &count) != NULL &&
	      count == 0, "empty table");
	CHECK("def-camera", sc && camera_equal(sss_scene_camera(sc), &cam),
	      "camera");
	CHECK("def-options", sc && options_equal(sss_scene_options(sc), &opt),
	      "options");
	sss_scene_free(sc);

	/* Each kind with only the required keys gets exactly its defaults. */
	static const struct {
		const char *name;
		int32_t kind;
	} kinds[] = {
		{"burley", SSS_PROFILE_BURLEY}, {"gaussians", SSS_PROFILE_GAUSSIANS},
		{"jimenez", SSS_PROFILE_JIMENEZ}, {"near-far", SSS_PROFILE_NEAR_FAR},
		{"none", SSS_PROFILE_NONE},
	};
	for (size_t k = 0; k < sizeof kinds / sizeof *kinds; k++) {
		char json[160];
		snprintf(json, sizeof json, "{\"materials\": [{\"pass_index\": %d, "
		         "\"profile\": \"%s\"}], \"materials_note\": 1}",
		         (int)k + 3, kinds[k].name);
		char warn[128];
		sc = NULL;
		CHECK_STATUS("def-kind", SSS_OK,
		             parse(json, &sc, warn, sizeof warn, err, sizeof err));
		sss_material m;
		sss_material_default(&m, kinds[k].kind);
		m.pass_index = (int32_t)k + 3;
		const sss_material *got = sss_scene_materials(sc, &count);
		CHECK("def-kind-2", got && count == 1 && material_equal(got, &m),
		      "%s defaults differ", kinds[k].name);
		char name[32];
		snprintf(name, sizeof name, "material %d", (int)k + 3);
		CHECK("def-kind-name", sc && strcmp(sss_scene_material_name(sc, 0),
		                                    name) == 0, "default name");
		CHECK("def-kind-profile-name", sss_profile_name(kinds[k].kind) &&
		      strcmp(sss_profile_name(kinds[k].kind), kinds[k].name) == 0,
		      "sss_profile_name(%d)", (int)kinds[k].kind);
		CHECK("def-kind-warn", strcmp(warn, "warning: unknown key "
		                              "'materials_note' (ignored)") == 0,
		      "warn '%s'", warn);
		sss_scene_free(sc);
	}

	/* Omitted "materials" gives an empty table; every method name maps to
	 * the enum. */
	sc = NULL;
	CHECK_STATUS("def-method", SSS_OK,
	             parse("{\"method\": \"disk\", \"version\": 1.0}", &sc, NULL,
	                   0, err, sizeof err));
	CHECK("def-method-2", sc && sss_scene_options(sc)->method ==
	      SSS_METHOD_DISK, "disk");
	sss_scene_free(sc);
	sc = NULL;
	CHECK_STATUS("def-method-3", SSS_OK,
	             parse("{\"method\": \"separable-exact\"}", &sc, NULL, 0,
	                   err, sizeof err));
	CHECK("def-method-4", sc && sss_scene_options(sc)->method ==
	      SSS_METHOD_SEPARABLE_EXACT, "separable-exact");
	sss_scene_free(sc);

	/* The disk method's budget: default, set, range named. */
	sc = NULL;
	CHECK_STATUS("def-samples", SSS_OK,
	             parse("{\"method\": \"disk\", \"samples\": 256}", &sc,
	                   NULL, 0, err, sizeof err));
	CHECK("def-samples-2", sc && sss_scene_options(sc)->samples == 256,
	      "samples");
	sss_scene_free(sc);
	sc = NULL;
	CHECK_STATUS("def-samples-3", SSS_OK,
	             parse("{}", &sc, NULL, 0, err, sizeof err));
	CHECK("def-samples-4", sc && sss_scene_options(sc)->samples == 64,
	      "default samples");
	sss_scene_free(sc);
	sc = NULL;
	CHECK_STATUS("def-samples-5", SSS_ERR_INVALID_ARGUMENT,
	             parse("{\"samples\": 0}", &sc, NULL, 0, err, sizeof err));
	CHECK("def-samples-6", strstr(err, "samples") != NULL, "'%s'", err);
	sss_scene_free(sc);

	/* clip_end alone never moves background_depth. */
	sc = NULL;
	CHECK_STATUS("def-clip", SSS_OK,
	             parse("{\"camera\": {\"clip_end\": 50}}", &sc, NULL, 0, err,
	                   sizeof err));
	CHECK("def-clip-2", sc && sss_scene_options(sc)->background_depth ==
	      1e9, "background_depth changed");
	sss_scene_free(sc);
}

/* Each case must fail with `code` and a message containing `needle`. */
static const struct {
	const char *id;
	const char *json;
	sss_result code;
	const char *needle;
} errors[] = {
	{"err-no-pass-index", "{\"materials\": [{\"profile\": \"burley\"}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].pass_index: missing"},
	{"err-no-profile", "{\"materials\": [{\"pass_index\": 1}, "
	 "{\"pass_index\": 2}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].profile: missing"},
	{"err-type-lens", "{\"camera\": {\"lens\": \"50\"}}",
	 SSS_ERR_INVALID_ARGUMENT, "camera.lens: expected a number, got a string"},
	{"err-type-camera", "{\"camera\": [50]}",
	 SSS_ERR_INVALID_ARGUMENT, "camera: expected an object, got an array"},
	{"err-type-taps", "{\"taps\": 33.5}",
	 SSS_ERR_INVALID_ARGUMENT, "taps: expected an integer"},
	{"err-type-threads", "{\"threads\": true}",
	 SSS_ERR_INVALID_ARGUMENT, "threads: expected an integer, got true"},
	{"err-type-name", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"none\", \"name\": 5}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].name: expected a string"},
	{"err-type-method", "{\"method\": null}",
	 SSS_ERR_INVALID_ARGUMENT, "method: expected a string, got null"},
	{"err-type-pass-index", "{\"materials\": [{\"pass_index\": \"1\", "
	 "\"profile\": \"none\"}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].pass_index: expected an integer"},
	{"err-type-radius", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"burley\", \"radius\": 0.004}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].radius: expected an array of 3 "
	 "numbers, got a number"},
	{"err-radius-2", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"none\"}, {\"pass_index\": 2, \"profile\": \"burley\", \"radius\": "
	 "[0.004, 0.002]}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[1].radius: expected an array of 3 "
	 "numbers, got an array of 2"},
	{"err-radius-str", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"burley\", \"radius\": [0.004, \"a\", 0.001]}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].radius[1]: expected a number"},
	{"err-albedo-4", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"burley\", \"albedo\": [0.5, 0.5, 0.5, 0.5]}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].albedo: expected an array of 3"},
	{"err-profile", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"burly\"}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].profile: unknown profile 'burly' "
	 "(expected burley, gaussians, jimenez, near-far, none)"},
	{"err-mapping", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"burley\", \"mapping\": \"CYCLES\"}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].mapping: unknown mapping "
	 "'CYCLES' (expected cycles, eevee, random-walk, "
	 "cycles-random-walk, cycles4-random-walk)"},
	{"err-texturing", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"none\", \"texturing\": \"pre\"}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].texturing: unknown texturing "
	 "'pre'"},
	{"err-method", "{\"method\": \"fast\"}",
	 SSS_ERR_INVALID_ARGUMENT, "method: unknown method 'fast'"},
	{"err-camera-type", "{\"camera\": {\"type\": \"PANO\"}}",
	 SSS_ERR_INVALID_ARGUMENT, "camera.type: unknown type 'PANO' "
	 "(expected PERSP, ORTHO)"},
	{"err-sensor-fit", "{\"camera\": {\"sensor_fit\": \"auto\"}}",
	 SSS_ERR_INVALID_ARGUMENT, "camera.sensor_fit: unknown sensor_fit "
	 "'auto' (expected AUTO, HORIZONTAL, VERTICAL)"},
	{"err-radius-neg", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"burley\", \"radius\": [0.004, -0.001, 0.001]}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].radius[1]: -0.001 is out of "
	 "range (must be >= 0)"},
	{"err-strength", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"none\", \"strength\": 1.5}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].strength: 1.5 is out of range"},
	{"err-huge", "{\"radius_scale\": 1e999}",
	 SSS_ERR_INVALID_ARGUMENT, "radius_scale: number out of range"},
	{"err-huge-neg", "{\"camera\": {\"shift_x\": -1e999}}",
	 SSS_ERR_INVALID_ARGUMENT, "camera.shift_x: number out of range"},
	{"err-float-overflow", "{\"materials\": [{\"pass_index\": 1, "
	 "\"profile\": \"jimenez\", \"width\": 1e39}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].width: 1e+39 is out of range "
	 "(must be <= 1e+30)"},
	{"err-float-underflow", "{\"materials\": [{\"pass_index\": 1, "
	 "\"profile\": \"jimenez\", \"falloff\": [1, 1e-60, 1]}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].falloff[1]: 1e-60 is too small"},
	{"err-bg-depth", "{\"background_depth\": 1e400}",
	 SSS_ERR_INVALID_ARGUMENT, "background_depth: number out of range"},
	{"err-nan", "{\"unit_scale\": NaN}",
	 SSS_ERR_INVALID_ARGUMENT, "invalid JSON at line 1, column 16"},
	{"err-lens-0", "{\"camera\": {\"lens\": 0}}",
	 SSS_ERR_INVALID_ARGUMENT, "camera.lens: 0 is out of range (must be > 0)"},
	{"err-sensor-neg", "{\"camera\": {\"sensor_height\": -24}}",
	 SSS_ERR_INVALID_ARGUMENT, "camera.sensor_height: -24 is out of range"},
	{"err-aspect", "{\"camera\": {\"pixel_aspect_y\": 0}}",
	 SSS_ERR_INVALID_ARGUMENT, "camera.pixel_aspect_y"},
	{"err-clip", "{\"camera\": {\"clip_start\": 10, \"clip_end\": 5}}",
	 SSS_ERR_INVALID_ARGUMENT, "camera.clip_end: 5 must be greater than "
	 "camera.clip_start"},
	{"err-clip-0", "{\"camera\": {\"clip_end\": 0}}",
	 SSS_ERR_INVALID_ARGUMENT, "camera.clip_end: 0 is out of range"},
	{"err-unit-scale", "{\"unit_scale\": 0}",
	 SSS_ERR_INVALID_ARGUMENT, "unit_scale: 0 is out of range"},
	{"err-taps-0", "{\"taps\": 0}",
	 SSS_ERR_INVALID_ARGUMENT, "taps: 0 is out of range (must be 1..4097)"},
	{"err-taps-big", "{\"taps\": 4099}",
	 SSS_ERR_INVALID_ARGUMENT, "taps: 4099 is out of range"},
	{"err-threads", "{\"threads\": 257}",
	 SSS_ERR_INVALID_ARGUMENT, "threads: 257 is out of range (must be 0..256)"},
	{"err-max-support", "{\"max_support_px\": 0}",
	 SSS_ERR_INVALID_ARGUMENT, "max_support_px: 0 is out of range (must be "
	 ">= 1)"},
	{"err-crease", "{\"crease\": 3}",
	 SSS_ERR_INVALID_ARGUMENT, "crease: 3 is out of range (must be 0..2)"},
	{"err-radius-scale", "{\"radius_scale\": -1}",
	 SSS_ERR_INVALID_ARGUMENT, "radius_scale: -1 is out of range"},
	{"err-mat-taps", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"none\", \"taps\": -1}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].taps: -1 is out of range (must "
	 "be 0..4097)"},
	{"err-pass-index-0", "{\"materials\": [{\"pass_index\": 0, \"profile\": "
	 "\"none\"}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].pass_index: 0 is out of range "
	 "(must be 1..65535)"},
	{"err-pass-index-big", "{\"materials\": [{\"pass_index\": 65536, "
	 "\"profile\": \"none\"}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].pass_index: 65536 is out of "
	 "range"},
	{"err-duplicate", "{\"materials\": [{\"pass_index\": 4, \"profile\": "
	 "\"none\"}, {\"pass_index\": 5, \"profile\": \"none\"}, "
	 "{\"pass_index\": 4, \"profile\": \"burley\"}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[2].pass_index: 4 is already used "
	 "by materials[0]"},
	{"err-duplicate-key", "{\"camera\": {\"lens\": 50, \"lens\": 85}}",
	 SSS_ERR_INVALID_ARGUMENT, "camera.lens: key given twice"},
	{"err-gauss-empty", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"gaussians\", \"gaussians\": []}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].gaussians: expected an array of "
	 "1 to 8 objects"},
	{"err-gauss-9", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"gaussians\", \"gaussians\": [{},{},{},{},{},{},{},{},{}]}]}",
	 SSS_ERR_INVALID_ARGUMENT, "got an array of 9"},
	{"err-gauss-entry", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"gaussians\", \"gaussians\": [{\"variance\": 1, \"weight\": [1,1,1]},"
	 " 3]}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].gaussians[1]: expected an "
	 "object, got a number"},
	{"err-gauss-variance", "{\"materials\": [{\"pass_index\": 1, \"profile\":"
	 " \"gaussians\", \"gaussians\": [{\"weight\": [1,1,1]}]}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].gaussians[0].variance: missing"},
	{"err-gauss-variance-0", "{\"materials\": [{\"pass_index\": 1, "
	 "\"profile\": \"gaussians\", \"gaussians\": [{\"variance\": 0, "
	 "\"weight\": [1,1,1]}]}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].gaussians[0].variance: 0 is out "
	 "of range"},
	{"err-gauss-weight", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"gaussians\", \"gaussians\": [{\"variance\": 1, \"weight\": [1,1]}]}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].gaussians[0].weight: expected an "
	 "array of 3 numbers"},
	{"err-gauss-sum", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"gaussians\", \"gaussians\": [{\"variance\": 1, \"weight\": [1,0,1]}]}"
	 "]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].gaussians: the weights of "
	 "channel g sum to 0"},
	{"err-balance", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"near-far\", \"balance\": 2}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].balance: 2 is out of range "
	 "(must be in [0, 1])"},
	{"err-sigma", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"near-far\", \"far_sigma\": [1, 1, 0]}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].far_sigma[2]: 0 is out of range "
	 "(must be > 0)"},
	{"err-strength-rgb", "{\"materials\": [{\"pass_index\": 1, \"profile\": "
	 "\"jimenez\", \"strength_rgb\": [1, 1, 1.01]}]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0].strength_rgb[2]"},
	{"err-mat-type", "{\"materials\": [1]}",
	 SSS_ERR_INVALID_ARGUMENT, "materials[0]: expected an object, got a "
	 "number"},
	{"err-materials-object", "{\"materials\": {\"pass_index\": 1}}",
	 SSS_ERR_INVALID_ARGUMENT, "materials: expected an array of objects, got "
	 "an object"},
	{"err-not-object", "[1, 2]",
	 SSS_ERR_INVALID_ARGUMENT, "expected a JSON object at the top level, got "
	 "an array of 2"},
	{"err-not-object-2", "\"scene\"",
	 SSS_ERR_INVALID_ARGUMENT, "expected a JSON object at the top level, got "
	 "a string"},
	{"err-empty", "",
	 SSS_ERR_INVALID_ARGUMENT, "empty JSON text"},
	{"err-blank", " \n\t \r\n",
	 SSS_ERR_INVALID_ARGUMENT, "empty JSON text"},
	{"err-json", "{\n  \"taps\": 33,\n  \"method\" \"separable\"\n}",
	 SSS_ERR_INVALID_ARGUMENT, "invalid JSON at line 3, column 12 (near "
	 "'\"separable\"')"},
	{"err-json-comma", "{\"taps\": 33,}",
	 SSS_ERR_INVALID_ARGUMENT, "invalid JSON at line 1, column"},
	{"err-json-eof", "{\"camera\": {\"lens\": 50}\n",
	 SSS_ERR_INVALID_ARGUMENT, "invalid JSON at line"},
	{"err-trailing", "{\"taps\": 33}\n\n  x",
	 SSS_ERR_INVALID_ARGUMENT, "unexpected text after the JSON value at line "
	 "3, column 3"},
	{"err-version", "{\"version\": 2}",
	 SSS_ERR_UNSUPPORTED, "version: 2 is newer"},
	{"err-version-0", "{\"version\": 0}",
	 SSS_ERR_INVALID_ARGUMENT, "version: 0 is out of range"},
};

static void test_errors(void)
{
	for (size_t i = 0; i < sizeof errors / sizeof *errors; i++) {
		char err[256] = "unset", warn[256];
		sss_scene *sc = (sss_scene *)&err; /* must be reset to NULL */
		sss_result r = parse(errors[i].json, &sc, warn, sizeof warn, err,
		                     sizeof err);
		CHECK(errors[i].id, r == errors[i].code, "got %s, expected %s (%s)",
		      sss_status_name(r), sss_status_name(errors[i].code), err);
		CHECK(errors[i].id, strstr(err, errors[i].needle) != NULL,
		      "message '%s' lacks '%s'", err, errors[i].needle);
		CHECK(errors[i].id, sc == NULL, "*out not NULL on error");
		sss_scene_free(r == SSS_OK ? sc : NULL);
	}

	/* More materials than sss_apply takes. */
	size_t n = 32768;
	char *big = malloc(n * 3 + 32);
	if (big) {
		char *p = big + sprintf(big, "{\"materials\": [");
		for (size_t i = 0; i < n; i++) {
			memcpy(p, i ? ",{}" : "{}", i ? 3 : 2);
			p += i ? 3 : 2;
		}
		strcpy(p, "]}");
		char err[256] = "";
		sss_scene *sc = NULL;
		CHECK_STATUS("err-too-many", SSS_ERR_INVALID_ARGUMENT,
		             parse(big, &sc, NULL, 0, err, sizeof err));
		CHECK("err-too-many-2", strstr(err, "materials: 32768 entries, at "
		                               "most 32767") != NULL, "'%s'", err);
		free(big);
	}

	/* Bad arguments; errbuf may be NULL or tiny. */
	sss_scene *sc = NULL;
	char err[256];
	CHECK_STATUS("arg-out", SSS_ERR_INVALID_ARGUMENT,
	             sss_scene_parse("{}", 2, NULL, NULL, 0, err, sizeof err));
	CHECK("arg-out-2", strstr(err, "out is NULL") != NULL, "'%s'", err);
	CHECK_STATUS("arg-json", SSS_ERR_INVALID_ARGUMENT,
	             sss_scene_parse(NULL, 4, &sc, NULL, 0, err, sizeof err));
	CHECK_STATUS("arg-json-0", SSS_ERR_INVALID_ARGUMENT,
	             sss_scene_parse(NULL, 0, &sc, NULL, 0, NULL, 0));
	char tiny[8];
	CHECK_STATUS("arg-tiny-err", SSS_ERR_INVALID_ARGUMENT,
	             parse("{\"taps\": 0}", &sc, NULL, 0, tiny, sizeof tiny));
	CHECK("arg-tiny-err-2", strcmp(tiny, "taps: 0") == 0, "'%s'", tiny);
}

static void test_warnings(void)
{
	const char *json =
		"{\"colour\": 1, \"camera\": {\"foo\": 2, \"lens\": 35},"
		" \"materials\": [{\"pass_index\": 1, \"profile\": \"gaussians\","
		" \"gaussians\": [{\"variance\": 1, \"weight\": [1, 1, 1],"
		" \"bar\": 0}], \"radius\": \"ignored\", \"Strength\": 1}]}";
	char warn[512], err[256];
	sss_scene *sc = NULL;
	CHECK_STATUS("warn-1", SSS_OK,
	             parse(json, &sc, warn, sizeof warn, err, sizeof err));
	const char *expected =
		"warning: unknown key 'colour' (ignored)\n"
		"warning: unknown key 'camera.foo' (ignored)\n"
		"warning: unknown key 'materials[0].Strength' (ignored)\n"
		"warning: key 'materials[0].radius' is not used by profile "
		"'gaussians' (ignored)\n"
		"warning: unknown key 'materials[0].gaussians[0].bar' (ignored)";
	CHECK("warn-2", strcmp(warn, expected) == 0, "warnings:\n%s", warn);
	CHECK("warn-3", sc && sss_scene_camera(sc)->lens_mm == 35.0, "lens");
	sss_scene_free(sc);

	/* A small buffer is cut, terminated and ends in "...". */
	char small[24];
	memset(small, 'x', sizeof small);
	sc = NULL;
	CHECK_STATUS("warn-cut", SSS_OK,
	             parse(json, &sc, small, sizeof small, err, sizeof err));
	CHECK("warn-cut-2", strlen(small) == sizeof small - 1 &&
	      strcmp(small + sizeof small - 4, "...") == 0 &&
	      strncmp(small, "warning: unknown key", 20) == 0, "'%s'", small);
	sss_scene_free(sc);

	/* The second line does not fit: the first stays whole. */
	char two[48];
	sc = NULL;
	CHECK_STATUS("warn-cut-3", SSS_OK,
	             parse(json, &sc, two, sizeof two, err, sizeof err));
	CHECK("warn-cut-4", strncmp(two, "warning: unknown key 'colour' "
	                            "(ignored)\nwar", 43) == 0 &&
	      strcmp(two + sizeof two - 4, "...") == 0, "'%s'", two);
	sss_scene_free(sc);

	/* No buffer at all is fine; a key with a control character prints
	 * as '?' so a warning stays one line. */
	sc = NULL;
	CHECK_STATUS("warn-null", SSS_OK,
	             parse(json, &sc, NULL, 0, NULL, 0));
	sss_scene_free(sc);
	sc = NULL;
	CHECK_STATUS("warn-ctl", SSS_OK,
	             parse("{\"a\\nb\": 1}", &sc, warn, sizeof warn, NULL, 0));
	CHECK("warn-ctl-2", strcmp(warn, "warning: unknown key 'a?b' "
	                           "(ignored)") == 0, "'%s'", warn);
	sss_scene_free(sc);
}

/* The text ends at json_len or at a NUL, and is never read past. */
static void test_lengths(void)
{
	const char *src = "{\"taps\": 17}";
	size_t n = strlen(src);
	char *exact = malloc(n); /* no terminator: ASan sees any over-read */
	if (!exact)
		return;
	memcpy(exact, src, n);
	sss_scene *sc = NULL;
	char err[256];
	CHECK_STATUS("len-exact", SSS_OK,
	             sss_scene_parse(exact, n, &sc, NULL, 0, err, sizeof err));
	CHECK("len-exact-2", sc && sss_scene_options(sc)->taps == 17, "taps");
	sss_scene_free(sc);
	sc = NULL;
	CHECK_STATUS("len-short", SSS_ERR_INVALID_ARGUMENT,
	             sss_scene_parse(exact, n - 1, &sc, NULL, 0, err,
	                             sizeof err));
	CHECK("len-short-2", strstr(err, "invalid JSON at line 1") != NULL,
	      "'%s'", err);
	free(exact);
	CHECK_STATUS("len-nul", SSS_OK,
	             sss_scene_parse("{\"taps\": 9}\0garbage", 20, &sc, NULL, 0,
	                             err, sizeof err));
	CHECK("len-nul-2", sc && sss_scene_options(sc)->taps == 9, "taps");
	sss_scene_free(sc);
}

static void test_accessors(void)
{
	int32_t count = 5;
	CHECK("acc-1", sss_scene_camera(NULL) == NULL, "camera");
	CHECK("acc-2", sss_scene_options(NULL) == NULL, "options");
	CHECK("acc-3", sss_scene_materials(NULL, &count) == NULL && count == 0,
	      "materials");
	CHECK("acc-4", sss_scene_materials(NULL, NULL) == NULL, "NULL count");
	CHECK("acc-5", sss_scene_material_name(NULL, 0) == NULL, "name");
	sss_scene_free(NULL);
}

static int write_file(const char *path, const char *text)
{
	FILE *f = fopen(path, "wb");
	if (!f)
		return 0;
	size_t n = strlen(text);
	int ok = fwrite(text, 1, n, f) == n;
	return fclose(f) == 0 && ok;
}

static void test_files(void)
{
	char warn[512], err[512];
	sss_scene *sc = (sss_scene *)&err;
	CHECK_STATUS("file-missing", SSS_ERR_IO,
	             sss_scene_load("no/such/scene.json", &sc, warn, sizeof warn,
	                            err, sizeof err));
	CHECK("file-missing-2", strcmp(err, "no/such/scene.json: cannot open: "
	                               "No such file or directory") == 0,
	      "'%s'", err);
	CHECK("file-missing-3", sc == NULL, "out not reset");
	CHECK_STATUS("file-null", SSS_ERR_INVALID_ARGUMENT,
	             sss_scene_load(NULL, &sc, NULL, 0, err, sizeof err));
	CHECK_STATUS("file-null-out", SSS_ERR_INVALID_ARGUMENT,
	             sss_scene_load("x.json", NULL, NULL, 0, err, sizeof err));
	CHECK_STATUS("file-dir", SSS_ERR_IO,
	             sss_scene_load("examples", &sc, NULL, 0, err, sizeof err));
	CHECK("file-dir-2", strcmp(err, "examples: is a directory, not a scene "
	                           "description file") == 0, "'%s'", err);

	/* Parse errors and warnings from a file. */
	char dir[] = "/tmp/test_scene_XXXXXX";
	if (!mkdtemp(dir)) {
		CHECK("file-tmp", 0, "mkdtemp failed");
		return;
	}
	char path[64];
	snprintf(path, sizeof path, "%s/bad.json", dir);
	CHECK("file-write", write_file(path, "{\n  \"taps\": 33\n  \"x\": 1\n}"),
	      "cannot write %s", path);
	CHECK_STATUS("file-bad", SSS_ERR_INVALID_ARGUMENT,
	             sss_scene_load(path, &sc, warn, sizeof warn, err,
	                            sizeof err));
	char needle[96];
	snprintf(needle, sizeof needle, "%s: invalid JSON at line 3", path);
	CHECK("file-bad-2", strncmp(err, needle, strlen(needle)) == 0,
	      "'%s' lacks '%s'", err, needle);
	CHECK("file-write-2", write_file(path, "{\"threads\": -1}"), "write");
	CHECK_STATUS("file-range", SSS_ERR_INVALID_ARGUMENT,
	             sss_scene_load(path, &sc, warn, sizeof warn, err,
	                            sizeof err));
	snprintf(needle, sizeof needle, "%s: threads: -1 is out of range", path);
	CHECK("file-range-2", strncmp(err, needle, strlen(needle)) == 0,
	      "'%s'", err);
	CHECK("file-write-3", write_file(path, ""), "write");
	CHECK_STATUS("file-empty", SSS_ERR_INVALID_ARGUMENT,
	             sss_scene_load(path, &sc, NULL, 0, err, sizeof err));
	snprintf(needle, sizeof needle, "%s: empty JSON text", path);
	CHECK("file-empty-2", strcmp(err, needle) == 0, "'%s'", err);
	CHECK("file-write-4", write_file(path, "{\"extra\": {\"deep\": [1]}}"),
	      "write");
	CHECK_STATUS("file-warn", SSS_OK,
	             sss_scene_load(path, &sc, warn, sizeof warn, err,
	                            sizeof err));
	CHECK("file-warn-2", strcmp(warn, "warning: unknown key 'extra' "
	                            "(ignored)") == 0, "'%s'", warn);
	sss_scene_free(sc);
	sc = NULL;

	/* Over 16 MiB is refused before parsing; exactly 16 MiB is read. */
	for (int over = 0; over < 2; over++) {
		size_t n = ((size_t)16 << 20) + (size_t)over;
		char *big = malloc(n + 1);
		if (!big)
			break;
		memset(big, ' ', n);
		memcpy(big, "{}", 2);
		big[n] = '\0';
		CHECK("file-write-big", write_file(path, big), "write");
		free(big);
		sss_result r = sss_scene_load(path, &sc, NULL, 0, err, sizeof err);
		if (over) {
			CHECK("file-big", r == SSS_ERR_IO &&
			      strstr(err, "larger than 16 MiB") != NULL, "'%s'", err);
		} else {
			CHECK_STATUS("file-16mib", SSS_OK, r);
		}
		sss_scene_free(sc);
		sc = NULL;
	}
	remove(path);
	rmdir(dir);

	/* The shipped examples load cleanly. */
	static const char *const examples[] = {"examples/scenes/skin.json",
	                                       "examples/scenes/all_profiles.json"};
	static const int32_t counts[] = {3, 5};
	for (int i = 0; i < 2; i++) {
		sc = NULL;
		warn[0] = 'x';
		CHECK_STATUS("file-example", SSS_OK,
		             sss_scene_load(examples[i], &sc, warn, sizeof warn, err,
		                            sizeof err));
		CHECK("file-example-warn", warn[0] == '\0', "%s: warnings: %s",
		      examples[i], warn);
		int32_t count = 0;
		sss_scene_materials(sc, &count);
		CHECK("file-example-count", count == counts[i], "%s: %d materials",
		      examples[i], count);
		sss_scene_free(sc);
	}

	/* all_profiles.json's Gaussian material is the d'Eon default. */
	sc = NULL;
	if (sss_scene_load(examples[1], &sc, NULL, 0, NULL, 0) == SSS_OK) {
		sss_material m;
		sss_material_default(&m, SSS_PROFILE_GAUSSIANS);
		m.pass_index = 2;
		m.texturing = SSS_TEXTURING_PRE_AND_POST;
		const sss_material *got = sss_scene_materials(sc, NULL);
		CHECK("file-example-deon", material_equal(&got[1], &m),
		      "gaussians differ from the default");
		sss_material_default(&m, SSS_PROFILE_BURLEY);
		m.pass_index = 1;
		CHECK("file-example-burley", material_equal(&got[0], &m),
		      "burley differs from the default");
	}
	sss_scene_free(sc);
}

/* Whatever parses is accepted by sss_apply as is. */
static void test_apply_accepts(void)
{
	synth *s = synth_new(8, 6);
	synth_plane(s, 0, 0, 8, 6, 2.0f, 1.0f);
	synth_plane(s, 4, 0, 8, 6, 2.0f, 2.0f);
	for (size_t i = 0; i < 8 * 6 * 3; i++)
		s->diff_dir[i] = (float)(i % 7) / 7.0f;
	sss_passes p = synth_passes(s);
	float *buf = calloc(8 * 6 * 4, sizeof(float));
	sss_image out = {buf, 8, 6, 4, 0};
	const char *files[] = {"examples/scenes/skin.json",
	                       "examples/scenes/all_profiles.json"};
	for (int i = 0; i < 2 && buf; i++) {
		sss_scene *sc = NULL;
		char err[256] = "";
		if (sss_scene_load(files[i], &sc, NULL, 0, err, sizeof err)) {
			CHECK("apply-load", 0, "%s", err);
			continue;
		}
		int32_t count;
		const sss_material *m = sss_scene_materials(sc, &count);
		CHECK_STATUS("apply-example", SSS_OK,
		             sss_apply(&p, sss_scene_camera(sc), m, count,
		                       sss_scene_options(sc), &out, NULL, err,
		                       sizeof err));
		sss_scene_free(sc);
	}
	/* The full test scene too (reference method, ortho camera). */
	sss_scene *sc = NULL;
	if (parse(full_scene, &sc, NULL, 0, NULL, 0) == SSS_OK) {
		int32_t count;
		const sss_material *m = sss_scene_materials(sc, &count);
		char err[256] = "";
		CHECK_STATUS("apply-full", SSS_OK,
		             sss_apply(&p, sss_scene_camera(sc), m, count,
		                       sss_scene_options(sc), &out, NULL, err,
		                       sizeof err));
	}
	sss_scene_free(sc);
	free(buf);
	synth_free(s);
}

/* docs/scene.md's material tables against the library's schema: each
 * field's row has its key, type, default, range and member as
 * sss_material_field() gives them (the unit and the prose are the
 * document's own). */
static void doc_cells(const sss_field_info *f, int32_t i, char *type,
                      char *def, char *range, size_t len)
{
	static const char *const types[] = {"number", "RGB", "integer",
	                                    "string"};
	snprintf(type, len, "%s", types[f->type]);
	const double *d = f->default_value;
	size_t used = 0;
	switch (f->type) {
	case SSS_FIELD_FLOAT:
		snprintf(def, len, "%g", d[0]);
		break;
	case SSS_FIELD_RGB:
		snprintf(def, len, "[%g, %g, %g]", d[0], d[1], d[2]);
		break;
	case SSS_FIELD_INT:
		snprintf(def, len, "%d", (int)d[0]);
		break;
	default:
		for (int32_t j = 0, v; sss_material_field_name(i, j, &v); j++)
			if (v == (int32_t)d[0])
				snprintf(def, len, "`\"%s\"`", sss_material_field_name(i, j,
				                                                     NULL));
		range[0] = '\0';
		for (int32_t j = 0; j < f->name_count; j++) {
			used = strlen(range);
			snprintf(range + used, len - used, "%s`\"%s\"`", j ? ", " : "",
			         sss_material_field_name(i, j, NULL));
		}
		return;
	}
	const char *each = f->type == SSS_FIELD_RGB ? "each " : "";
	if (f->type == SSS_FIELD_INT || f->hi < 1e30)
		snprintf(range, len, "%s%g .. %g", each, f->lo, f->hi);
	else
		snprintf(range, len, "%s%s %g", each, f->lo_open ? ">" : ">=",
		         f->lo);
}

static int starts(const char *s, const char *prefix)
{
	return strncmp(s, prefix, strlen(prefix)) == 0;
}

static void test_doc_table(void)
{
	FILE *fp = fopen("docs/scene.md", "rb");
	CHECK("doc-open", fp != NULL, "docs/scene.md (run from the repository)");
	if (!fp)
		return;
	static char doc[1 << 17];
	size_t n = fread(doc, 1, sizeof doc - 1, fp);
	fclose(fp);
	doc[n] = '\0';
	/* Only the materials[] section: other objects reuse some keys. */
	const char *section = strstr(doc, "### `materials[]`");
	CHECK("doc-section", section != NULL, "no materials[] section");
	if (!section)
		return;
	sss_field_info f;
	int32_t i = 0;
	for (; sss_material_field(i, &f) == SSS_OK; i++) {
		char head[96], type[64], def[128], range[256], sets[96];
		snprintf(head, sizeof head, "\n| `%s` | ", f.key);
		const char *row = strstr(section, head);
		CHECK(f.key, row != NULL, "docs/scene.md has no row for '%s' "
		      "(make scene-doc writes one)", f.key);
		if (!row)
			continue;
		doc_cells(&f, i, type, def, range, sizeof range);
		snprintf(sets, sizeof sets, "`%s`", f.member);
		/* | key | type | unit | default | range | sets | */
		const char *cell[6];
		const char *p = row + 1;
		int k = 0;
		while (k < 6 && (p = strstr(p, "| ")) != NULL) {
			cell[k++] = p + 2;
			p += 2;
		}
		CHECK(f.key, k == 6, "row of '%s' has fewer than 6 cells", f.key);
		if (k < 6)
			continue;
		CHECK(f.key, starts(cell[1], type), "type should read '%s'", type);
		CHECK(f.key, starts(cell[3], def), "default should read '%s'", def);
		CHECK(f.key, starts(cell[4], range), "range should read '%s'",
		      range);
		CHECK(f.key, starts(cell[5], sets), "sets should start with %s",
		      sets);
	}
	CHECK("doc-count", i > 20, "%d fields", (int)i);
	CHECK_STATUS("field-past-end", SSS_ERR_INVALID_ARGUMENT,
	             sss_material_field(i, &f));
	CHECK_STATUS("field-null", SSS_ERR_INVALID_ARGUMENT,
	             sss_material_field(0, NULL));
	CHECK("field-name-past-end", !sss_material_field_name(0, 99, NULL),
	      "a name past the end");
	CHECK("profile-name-past-end", !sss_profile_name(5) &&
	      !sss_profile_name(-1), "a profile past the end");
}

/* A row's cells in a section of docs/scene.md: | key | type | unit |
 * default | range | sets |, each checked to start as given (the unit and
 * the prose after are the document's own). */
static void check_doc_row(const char *section, const char *key,
                          const char *type, const char *def,
                          const char *range, const char *sets)
{
	char head[96];
	snprintf(head, sizeof head, "\n| `%s` | ", key);
	const char *row = strstr(section, head);
	const char *end = strstr(section + 1, "\n### ");
	CHECK(key, row != NULL && (!end || row < end), "docs/scene.md has no "
	      "row for '%s' in its section", key);
	if (!row || (end && row > end))
		return;
	const char *cell[6];
	const char *p = row + 1;
	int k = 0;
	while (k < 6 && (p = strstr(p, "| ")) != NULL) {
		cell[k++] = p + 2;
		p += 2;
	}
	CHECK(key, k == 6, "row of '%s' has fewer than 6 cells", key);
	if (k < 6)
		return;
	CHECK(key, starts(cell[1], type), "type should read '%s'", type);
	CHECK(key, starts(cell[3], def), "default should read '%s'", def);
	CHECK(key, starts(cell[4], range), "range should read '%s'", range);
	CHECK(key, starts(cell[5], sets), "sets should start with %s", sets);
}

/* %g as the document writes it: 1e9, not 1e+09. */
static void doc_number(char *buf, size_t len, double v)
{
	char g[32];
	snprintf(g, sizeof g, "%g", v);
	char *e = strstr(g, "e+");
	if (e) {
		char *digits = e + 2;
		while (*digits == '0' && digits[1])
			digits++;
		memmove(e + 1, digits, strlen(digits) + 1);
	}
	snprintf(buf, len, "%s", g);
}

/* A number's range as the document writes it. */
static void doc_range(char *buf, size_t len, double lo, double hi,
                      int lo_open, int integer)
{
	char a[32], b[32];
	doc_number(a, sizeof a, lo);
	doc_number(b, sizeof b, hi);
	if (integer && hi < INT32_MAX)
		snprintf(buf, len, "%s .. %s", a, b);
	else if (!integer && lo <= -1e30 && hi >= 1e30)
		snprintf(buf, len, "finite");
	else if (integer || hi >= 1e30)
		snprintf(buf, len, "%s %s", lo_open ? ">" : ">=", a);
	else
		snprintf(buf, len, "%s .. %s", a, b);
}

static const char *doc_section(const char *doc, const char *title)
{
	const char *section = strstr(doc, title);
	CHECK(title, section != NULL, "docs/scene.md has no section %s", title);
	return section;
}

/* One row of the camera's schema against the document. */
static void camera_row(const char *section, const char *key,
                       const char *member, int type, int top, double def,
                       double lo, double hi, int lo_open,
                       const sss__name_value *names, int count)
{
	char cdef[64] = "", range[256] = "", sets[96];
	if (type == SSS_FIELD_ENUM) {
		for (int j = 0; j < count; j++) {
			size_t used = strlen(range);
			snprintf(range + used, sizeof range - used, "%s`\"%s\"`",
			         j ? ", " : "", names[j].name);
			if (names[j].value == (int32_t)def)
				snprintf(cdef, sizeof cdef, "`\"%s\"`", names[j].name);
		}
	} else {
		doc_number(cdef, sizeof cdef, def);
		doc_range(range, sizeof range, lo, hi, lo_open, 0);
	}
	snprintf(sets, sizeof sets, "`%s%s`", top ? "sss_camera." : "", member);
	check_doc_row(section, key, type == SSS_FIELD_ENUM ? "string" : "number",
	              cdef, range, sets);
}

/* docs/scene.md's top-level table against the options' schema
 * (sss_option_field) and its camera table against the camera's
 * (sss_camera_fields.h, whose TOP rows are top-level keys). */
static void test_doc_options_camera(void)
{
	FILE *fp = fopen("docs/scene.md", "rb");
	if (!fp)
		return; /* test_doc_table said so */
	static char doc[1 << 17];
	size_t n = fread(doc, 1, sizeof doc - 1, fp);
	fclose(fp);
	doc[n] = '\0';
	const char *top = doc_section(doc, "\n### Top level");
	const char *camera = doc_section(doc, "\n### `camera`");
	if (!top || !camera)
		return;
	sss_field_info f;
	int32_t i = 0;
	for (; sss_option_field(i, &f) == SSS_OK; i++) {
		char def[64], range[256] = "", sets[96];
		const char *type = f.type == SSS_FIELD_INT ? "integer"
		                   : f.type == SSS_FIELD_ENUM ? "string" : "number";
		if (f.type == SSS_FIELD_ENUM) {
			snprintf(def, sizeof def, "`\"%s\"`",
			         sss_method_name((int32_t)f.default_value[0]));
			for (int32_t j = 0; j < f.name_count; j++) {
				size_t used = strlen(range);
				snprintf(range + used, sizeof range - used, "%s`\"%s\"`",
				         j ? ", " : "", sss_method_name(j));
			}
			CHECK(f.key, f.lo == 0 && f.hi == f.name_count - 1 &&
			      !sss_method_name(f.name_count), "the methods' values");
		} else {
			doc_number(def, sizeof def, f.default_value[0]);
			doc_range(range, sizeof range, f.lo, f.hi, f.lo_open,
			          f.type == SSS_FIELD_INT);
		}
		snprintf(sets, sizeof sets, "`sss_options.%s`", f.member);
		check_doc_row(top, f.key, type, def, range, sets);
	}
	/* Every member, and sss_options_default's values. */
	CHECK("option-count", i == 8, "%d option fields", (int)i);
	sss_options d;
	sss_options_default(&d);
	CHECK("option-defaults", sss_option_field(2, &f) == SSS_OK &&
	      strcmp(f.key, "taps") == 0 && f.default_value[0] == d.taps &&
	      sss_option_field(4, &f) == SSS_OK && f.default_value[0] ==
	      d.background_depth && f.type == SSS_FIELD_DOUBLE,
	      "taps and background_depth");
	CHECK_STATUS("option-past-end", SSS_ERR_INVALID_ARGUMENT,
	             sss_option_field(i, &f));
	CHECK_STATUS("option-null", SSS_ERR_INVALID_ARGUMENT,
	             sss_option_field(0, NULL));

#define CAMERA_ROW(key, member, type, place, when, def, lo, hi, lo_open, \
                   names, count, help) \
	camera_row(place == SSS__PLACE_TOP ? top : camera, key, #member, \
	           SSS_FIELD_##type, place == SSS__PLACE_TOP, def, lo, hi, \
	           lo_open, names, count);
#define SSS_FIELD_F64 SSS_FIELD_DOUBLE
#define CAMERA SSS__PLACE_CAMERA
#define TOP SSS__PLACE_TOP
#define ROW(...) CAMERA_ROW(__VA_ARGS__)
	SSS_CAMERA_FIELDS(ROW)
#undef ROW
#undef TOP
#undef CAMERA
#undef SSS_FIELD_F64
#undef CAMERA_ROW
}

int main(void)
{
	test_full_scene();
	test_defaults();
	test_errors();
	test_warnings();
	test_lengths();
	test_accessors();
	test_files();
	test_apply_accepts();
	test_doc_table();
	test_doc_options_camera();
	return tu_finish("test_scene");
}
