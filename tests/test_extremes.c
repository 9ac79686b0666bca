/* test_extremes.c - numerical soundness at the extremes: tiny and huge
 * radii, bad depths, NaN/Inf/huge/denormal pass values, degenerate image
 * shapes and tap counts, for every method.
 *
 * Policy under test (see sss.h): a pixel with a non-finite light or colour
 * keeps its own value and is never used as a sample; a pixel with a depth
 * that is not finite and > 0, or at/after the background depth, is passed
 * through and never sampled. Everything else must come out finite. */
#include "synth.h"
#include "test_util.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const int methods[] = {SSS_METHOD_SEPARABLE, SSS_METHOD_REFERENCE,
                               SSS_METHOD_SEPARABLE_EXACT, SSS_METHOD_DISK};
#define NMETHODS (sizeof methods / sizeof *methods)

typedef struct shape {
	int w, h;
} shape;

static const shape shapes[] = {{1, 1}, {1, 7}, {7, 1}, {3, 3}, {9, 5},
                               {257, 129}};

enum poison_kind { POISON_NONE, POISON_DEPTH, POISON_LIGHT, POISON_COLOUR };

static const struct poison {
	const char *name;
	int kind;
	float value;
} poisons[] = {
	{"none", POISON_NONE, 0},
	{"depth=0", POISON_DEPTH, 0.0f},
	{"depth=-1", POISON_DEPTH, -1.0f},
	{"depth=NaN", POISON_DEPTH, NAN},
	{"depth=Inf", POISON_DEPTH, INFINITY},
	{"depth=1e10", POISON_DEPTH, 1e10f},
	{"depth=1e-6", POISON_DEPTH, 1e-6f},
	{"light=0", POISON_LIGHT, 0.0f},
	{"light=1", POISON_LIGHT, 1.0f},
	{"light=1e-38", POISON_LIGHT, 1e-38f},
	{"light=NaN", POISON_LIGHT, NAN},
	{"light=Inf", POISON_LIGHT, INFINITY},
	{"light=-Inf", POISON_LIGHT, -INFINITY},
	{"light=1e30", POISON_LIGHT, 1e30f},
	{"light=65504", POISON_LIGHT, 65504.0f},
	{"light=denormal", POISON_LIGHT, 1e-40f},
	{"colour=NaN", POISON_COLOUR, NAN},
	{"colour=1e30", POISON_COLOUR, 1e30f},
};

static const float radii[] = {0.0f, 1e-9f, 1e-4f, 0.01f, 1.0f, 1e3f};
static const int taps[] = {1, 3, 0, 1000}; /* 0: the default */

static int finite3(const float *v)
{
	return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

static void run_case(const shape *sh, const struct poison *po, float radius,
                     int tap, int method, int texturing, int *cases)
{
	int w = sh->w, h = sh->h;
	synth *s = synth_new(w, h);
	synth_plane(s, 0, 0, w, h, 2.0f, 1.0f);
	for (size_t i = 0; i < (size_t)3 * w * h; i++) {
		s->diff_dir[i] = 0.25f + 0.01f * (float)(i % 7);
		s->diff_col[i] = 0.5f;
	}
	size_t centre = (size_t)(h / 2) * w + w / 2;
	if (po->kind == POISON_DEPTH)
		s->depth[centre] = po->value;
	for (int c = 0; c < 3; c++) {
		if (po->kind == POISON_LIGHT)
			s->diff_dir[3 * centre + c] = po->value;
		if (po->kind == POISON_COLOUR)
			s->diff_col[3 * centre + c] = po->value;
	}
	sss_material m;
	sss_material_default(&m, SSS_PROFILE_BURLEY);
	m.pass_index = 1;
	m.radius[0] = radius;
	m.radius[1] = radius * 0.5f;
	m.radius[2] = radius * 0.25f;
	m.texturing = texturing;
	m.taps = tap;
	sss_options o;
	sss_options_default(&o);
	o.method = method;
	/* The reference is radius^2 per pixel: keep the big image cheap. */
	o.max_support_px = w * h > 1000 && method == SSS_METHOD_REFERENCE ? 2 : 64;
	sss_passes p = synth_passes(s);
	sss_camera cam;
	sss_camera_default(&cam);
	float *light = calloc((size_t)3 * w * h, sizeof(float));
	float *comb = calloc((size_t)4 * w * h, sizeof(float));
	sss_image ol = {light, w, h, 3, 0}, oc = {comb, w, h, 4, 0};
	char err[256] = "";
	sss_result r = sss_apply(&p, &cam, &m, 1, &o, &oc, &ol, err, sizeof err);

	char id[128];
	snprintf(id, sizeof id, "extreme-%dx%d/%s/r=%g/taps=%d/m=%d/t=%d", w, h,
	         po->name, (double)radius, tap, method, texturing);
	(*cases)++;
	CHECK(id, r == SSS_OK, "%s: %s", sss_status_name(r), err);
	int spread = 0, own = 1;
	for (size_t i = 0; i < (size_t)w * h; i++) {
		int input_finite = finite3(s->diff_dir + 3 * i) &&
		                   finite3(s->diff_col + 3 * i);
		int out_finite = finite3(light + 3 * i) && finite3(comb + 4 * i);
		if (i != centre && !out_finite)
			spread = 1;
		if (input_finite && !out_finite)
			own = 0;
	}
	CHECK(id, !spread, "a non-finite value reached a neighbour");
	CHECK(id, own, "a finite input pixel came out non-finite");
	free(light);
	free(comb);
	synth_free(s);
}

/* The scattered diffuse light of one material on s with the default
 * camera, radii times radius_scale (caller frees); *status receives
 * sss_apply's result. */
static float *scatter_light(const synth *s, const sss_material *m,
                            int method, float radius_scale,
                            sss_result *status)
{
	sss_options o;
	sss_options_default(&o);
	o.method = method;
	o.radius_scale = radius_scale;
	sss_passes p = synth_passes(s);
	sss_camera cam;
	sss_camera_default(&cam);
	float *light = calloc((size_t)3 * s->w * s->h, sizeof(float));
	sss_image ol = {light, s->w, s->h, 3, 0};
	*status = sss_apply(&p, &cam, m, 1, &o, NULL, &ol, NULL, 0);
	return light;
}

/* A constant image stays constant even for absurd radii and tap counts. */
static void test_constant_extremes(void)
{
	for (size_t r = 0; r < sizeof radii / sizeof *radii; r++)
		for (size_t t = 0; t < sizeof taps / sizeof *taps; t++)
			for (size_t mt = 0; mt < NMETHODS; mt++) {
				int w = 13, h = 11;
				synth *s = synth_new(w, h);
				synth_plane(s, 0, 0, w, h, 1.0f, 1.0f);
				for (size_t i = 0; i < (size_t)3 * w * h; i++)
					s->diff_dir[i] = 0.7f;
				sss_material m;
				sss_material_default(&m, SSS_PROFILE_BURLEY);
				m.pass_index = 1;
				m.radius[0] = m.radius[1] = m.radius[2] = radii[r];
				m.taps = taps[t];
				sss_result res;
				float *light = scatter_light(s, &m, methods[mt], 1.0f, &res);
				double worst = 0;
				for (size_t i = 0; i < (size_t)3 * w * h; i++)
					worst = fmax(worst, fabs(light[i] - 0.7f));
				char id[96];
				snprintf(id, sizeof id, "constant-r=%g/taps=%d/m=%zu",
				         (double)radii[r], taps[t], mt);
				CHECK(id, res == SSS_OK && worst < 1e-6, "deviation %g",
				      worst);
				free(light);
				synth_free(s);
			}
}

/* Huge unit scales and radius scales stay finite. */
static void test_scales(void)
{
	int w = 9, h = 9;
	synth *s = synth_new(w, h);
	synth_plane(s, 0, 0, w, h, 2.0f, 1.0f);
	synth_noise(s, 0, 1, 3);
	double unit_scales[] = {1e-30, 1e-3, 1, 1e30};
	float radius_scales[] = {0.0f, 1e-30f, 1.0f, 1e30f};
	for (int a = 0; a < 4; a++)
		for (int b = 0; b < 4; b++) {
			sss_material m;
			sss_material_default(&m, SSS_PROFILE_GAUSSIANS);
			m.pass_index = 1;
			sss_options o;
			sss_options_default(&o);
			o.radius_scale = radius_scales[b];
			sss_camera cam;
			sss_camera_default(&cam);
			cam.unit_scale = unit_scales[a];
			sss_passes p = synth_passes(s);
			float light[3 * 81];
			sss_image ol = {light, w, h, 3, 0};
			sss_result r = sss_apply(&p, &cam, &m, 1, &o, NULL, &ol, NULL, 0);
			int ok = r == SSS_OK;
			for (int i = 0; i < 3 * 81; i++)
				ok &= isfinite(light[i]) && light[i] >= 0 && light[i] <= 1;
			char id[64];
			snprintf(id, sizeof id, "scale-unit=%g/radius=%g", unit_scales[a],
			         (double)radius_scales[b]);
			CHECK(id, ok, "bad output (%s)", sss_status_name(r));
		}
	synth_free(s);
}

/* Radii far past everything a blur can reach: every method tends to one
 * limit (light spread over what it reaches, kernels shrunk alike by
 * sss__reach_limit), instead of some returning the input when their
 * tables underflowed. Past the limit the result no longer changes at
 * all; each method scatters and stays close to the reference. */
static void test_huge_radii_limit(void)
{
	int w = 24, h = 20;
	synth *s = synth_new(w, h);
	synth_plane(s, 0, 0, w, h, 2.0f, 1.0f);
	synth_noise(s, 0.0f, 1.0f, 7);
	const float scales[] = {1e9f, 1e15f, 1e20f, 1e30f};
	size_t n = (size_t)3 * w * h;
	float *ref = NULL;
	for (size_t mt = 0; mt < NMETHODS; mt++) {
		float *first = NULL;
		for (size_t k = 0; k < sizeof scales / sizeof *scales; k++) {
			sss_material m;
			sss_material_default(&m, SSS_PROFILE_BURLEY);
			m.pass_index = 1;
			sss_result r;
			float *light = scatter_light(s, &m, methods[mt], scales[k], &r);
			double moved = 0, sum_in = 0, sum_out = 0;
			for (size_t i = 0; i < n; i++) {
				moved = fmax(moved, fabs(light[i] - s->diff_dir[i]));
				sum_in += s->diff_dir[i];
				sum_out += light[i];
			}
			char id[96];
			snprintf(id, sizeof id, "huge-radius/m=%d/scale=%g", methods[mt],
			         (double)scales[k]);
			CHECK(id, r == SSS_OK && moved > 0.2, "%s, largest change %g "
			      "(the input came back)", sss_status_name(r), moved);
			CHECK(id, fabs(sum_out / sum_in - 1.0) < 0.03, "mean changed by "
			      "%.2f %%", 100 * (sum_out / sum_in - 1.0));
			if (!first) {
				first = light;
				continue;
			}
			CHECK(id, memcmp(first, light, n * sizeof *light) == 0,
			      "differs from scale %g: not at the limit", (double)scales[0]);
			free(light);
		}
		if (methods[mt] == SSS_METHOD_REFERENCE) {
			ref = first;
			continue;
		}
		if (ref) {
			double diff = 0;
			for (size_t i = 0; i < n; i++)
				diff += fabs(first[i] - ref[i]);
			char id[64];
			snprintf(id, sizeof id, "huge-radius/m=%d/vs-reference",
			         methods[mt]);
			CHECK(id, diff / n < 0.05, "mean |difference| %g", diff / n);
		}
		free(first);
	}
	free(ref);
	synth_free(s);
}

/* An impulse in the middle of a plane: its light is spread, not created
 * or lost (interior pixels, kernels inside the image), for every profile
 * kind, method and tap count. */
static void test_energy(void)
{
	static const int kinds[] = {SSS_PROFILE_BURLEY, SSS_PROFILE_GAUSSIANS,
	                            SSS_PROFILE_JIMENEZ, SSS_PROFILE_NEAR_FAR};
	static const int energy_taps[] = {3, 0, 1000};
	/* Every pixel that receives light must have its whole kernel inside
	 * the image, or border renormalisation (by design) adds energy. */
	int w = 53, h = 53;
	for (size_t k = 0; k < 4; k++)
		for (size_t mt = 0; mt < NMETHODS; mt++)
			for (size_t t = 0; t < 3; t++) {
				/* Taps mean nothing to the reference. The disk method
				 * conserves an impulse's light only on average (noise,
				 * see tests/test_methods.c, disk-energy). */
				if ((methods[mt] == SSS_METHOD_REFERENCE && t != 1) ||
				    methods[mt] == SSS_METHOD_DISK)
					continue;
				synth *s = synth_new(w, h);
				synth_plane(s, 0, 0, w, h, 2.0f, 1.0f);
				size_t centre = (size_t)26 * w + 26;
				for (int c = 0; c < 3; c++)
					s->diff_dir[3 * centre + c] = 1.0f;
				sss_material m;
				sss_material_default(&m, kinds[k]);
				m.pass_index = 1;
				m.taps = energy_taps[t];
				double support;
				sss_material_support(&m, &support);
				/* Support of 12 px at 2 m (default camera, 53 px wide). */
				double scale = 12.0 / (support * w * 50.0 / 36.0 / 2.0);
				for (int c = 0; c < 3; c++)
					m.radius[c] *= (float)scale;
				m.gaussian_scale *= (float)scale;
				m.jimenez_width *= (float)scale;
				m.scatter_scale *= (float)scale;
				sss_result r;
				float *light = scatter_light(s, &m, methods[mt], 1.0f, &r);
				double sum[3] = {0, 0, 0};
				for (size_t i = 0; i < (size_t)w * h; i++)
					for (int c = 0; c < 3; c++)
						sum[c] += light[3 * i + c];
				char id[64];
				snprintf(id, sizeof id, "energy-kind=%d/m=%d/taps=%d",
				         kinds[k], methods[mt], energy_taps[t]);
				for (int c = 0; c < 3; c++)
					CHECK(id, r == SSS_OK && fabs(sum[c] - 1.0) < 1e-4,
					      "channel %d: impulse of 1 spreads to %.7f", c,
					      sum[c]);
				free(light);
				synth_free(s);
			}
}

int main(void)
{
	/* A hang is a failure: nothing here may take minutes. */
	alarm(600);
	int cases = 0;
	for (size_t a = 0; a < sizeof shapes / sizeof *shapes; a++)
		for (size_t b = 0; b < sizeof poisons / sizeof *poisons; b++)
			for (size_t c = 0; c < sizeof radii / sizeof *radii; c++)
				for (size_t d = 0; d < sizeof taps / sizeof *taps; d++)
					for (size_t e = 0; e < NMETHODS; e++) {
						/* The big image: the non-finite and huge values,
						 * three radii, default taps. */
						if (shapes[a].w > 100 &&
						    (taps[d] != 0 || (c != 0 && c != 2 && c != 5) ||
						     (methods[e] == SSS_METHOD_REFERENCE &&
						      (c != 5 || (poisons[b].kind != POISON_NONE &&
						                  !isnan(poisons[b].value)))) ||
						     !(poisons[b].kind == POISON_NONE ||
						       !isfinite(poisons[b].value) ||
						       poisons[b].value > 1e29f)))
							continue;
						run_case(&shapes[a], &poisons[b], radii[c], taps[d],
						         methods[e], (int)(c % 2), &cases);
					}
	printf("report: %d extreme cases\n", cases);
	test_energy();
	test_constant_extremes();
	test_scales();
	test_huge_radii_limit();
	return tu_finish("test_extremes");
}
