/* test_calibration.c - the measured match to Cycles' random walk: the
 * energy tables (finite, reflectance A g(A) never decreasing, gain 1 where
 * no calibration applies), the cycles-random-walk and cycles4-random-walk
 * radius mappings, and
 * sss_apply's invariants with a calibrated material (radius 0, strength 0
 * and radius_scale 0 stay the identity; the gain scales a flat field by
 * exactly g(DiffCol)). */
#include "test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define W 24
#define H 20

/* The orthographic camera of run(): ORTHO scene units across W pixels. */
#define ORTHO 0.5

/* A flat field on a plane turned `tilt` radians about the vertical axis
 * from facing the camera (depth grows to the right). */
static void flat_passes(sss_passes *p, float *dd, float *col, float *z,
                        float *idx, float light, const float c3[3],
                        double tilt)
{
	for (int i = 0; i < W * H; i++) {
		for (int c = 0; c < 3; c++) {
			dd[3 * i + c] = light;
			col[3 * i + c] = c3[c];
		}
		z[i] = (float)(2.0 + tan(tilt) * (i % W + 0.5) * ORTHO / W);
		idx[i] = 1.0f;
	}
	memset(p, 0, sizeof *p);
	p->diff_dir = (sss_image){dd, W, H, 3, 0};
	p->diff_col = (sss_image){col, W, H, 3, 0};
	p->depth = (sss_image){z, W, H, 1, 0};
	p->index_ma = (sss_image){idx, W, H, 1, 0};
}

/* sss_calibration_gain for a Burley material of calibration cal whose walk
 * enters through index ior (roughness 0.5). */
static sss_result gain_of(int32_t cal, float ior, const float *albedo,
                          float mu, float *g)
{
	sss_material m;
	sss_material_default(&m, SSS_PROFILE_BURLEY);
	m.pass_index = 1;
	m.calibration = cal;
	m.walk_ior = ior;
	return sss_calibration_gain(&m, albedo, mu, g);
}

static void test_table(void)
{
	static const int32_t cals[] = {SSS_CALIBRATION_CYCLES_RANDOM_WALK,
	                               SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN,
	                               SSS_CALIBRATION_CYCLES4_RANDOM_WALK};
	/* the walk's surface: clamped below the first table, between two,
	 * past the last */
	static const float etas[] = {1.0f, 1.01f, 1.25f, 1.5f, 1.7f, 3.8f};
	for (int k = 0; k < 3; k++) {
		int monotone = 1, finite = 1, sane = 1, ok = 1;
		for (int e = 0; e < 6; e++)
		for (int v = 0; v <= 20; v++) {
			float mu = 1.0f - (float)v / 20.0f, prev = -1.0f;
			for (int i = 0; i <= 1000; i++) {
				float a = (float)i / 1000.0f, al[3] = {a, a, a}, g[3];
				ok &= gain_of(cals[k], etas[e], al, mu, g) ==
				      SSS_OK;
				finite &= isfinite(g[0]) && g[0] == g[1] && g[1] == g[2];
				sane &= g[0] > 0.7f && g[0] < 1.8f;
				/* Reflectance A g(A) never decreases with A. */
				if (a * g[0] < prev - 1e-6f)
					monotone = 0;
				prev = a * g[0];
			}
		}
		CHECK("table-status", ok, "calibration %d: an error", cals[k]);
		CHECK("table-finite", finite, "calibration %d: non-finite or "
		      "channel-dependent gain", cals[k]);
		CHECK("table-sane", sane, "calibration %d: gain outside (0.7, 1.8)",
		      cals[k]);
		CHECK("table-monotone", monotone, "calibration %d: A g(A) "
		      "decreases somewhere", cals[k]);
	}
	/* 4.x/5.x head-on: the measured points (section 4 of
	 * sss_calibration.c). */
	float al4[3] = {0.05f, 0.5f, 0.9f}, g4[3];
	gain_of(SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN, 1.5f, al4, 1.0f, g4);
	CHECK("table4-skin", fabsf(g4[0] - 0.8975f) < 1e-6f &&
	      fabsf(g4[1] - 0.9537f) < 1e-6f && fabsf(g4[2] - 0.9923f) < 1e-6f,
	      "%g %g %g", (double)g4[0], (double)g4[1], (double)g4[2]);
	gain_of(SSS_CALIBRATION_CYCLES4_RANDOM_WALK, 1.01f, al4, 1.0f,
	                     g4);
	CHECK("table4-rw", fabsf(g4[0] - 0.7675f) < 1e-6f &&
	      fabsf(g4[1] - 0.8806f) < 1e-6f && fabsf(g4[2] - 0.9780f) < 1e-6f,
	      "%g %g %g", (double)g4[0], (double)g4[1], (double)g4[2]);
	/* plain Random Walk through Principled's default surface (1.5), and
	 * at 70 degrees between 1.01 and 1.5, linear in eta */
	gain_of(SSS_CALIBRATION_CYCLES4_RANDOM_WALK, 1.5f, al4, 1.0f,
	                     g4);
	CHECK("table4-rw-ior", fabsf(g4[0] - 0.7761f) < 1e-6f &&
	      fabsf(g4[1] - 0.8851f) < 1e-6f && fabsf(g4[2] - 0.9787f) < 1e-6f,
	      "%g %g %g", (double)g4[0], (double)g4[1], (double)g4[2]);
	{
		float lo[3], hi[3], at[3], mu70 = 0.3420201f;
		gain_of(SSS_CALIBRATION_CYCLES4_RANDOM_WALK, 1.01f,
		                     al4, mu70, lo);
		gain_of(SSS_CALIBRATION_CYCLES4_RANDOM_WALK, 1.5f, al4,
		                     mu70, hi);
		gain_of(SSS_CALIBRATION_CYCLES4_RANDOM_WALK, 1.255f,
		                     al4, mu70, at);
		CHECK("table4-rw-ior-between", fabsf(lo[0] - 1.2732f) < 1e-6f &&
		      fabsf(hi[0] - 0.9738f) < 1e-6f &&
		      fabsf(at[0] - 0.5f * (lo[0] + hi[0])) < 1e-5f,
		      "%g at 1.01, %g at 1.5, %g at 1.255", (double)lo[0],
		      (double)hi[0], (double)at[0]);
		CHECK_STATUS("bad-walk-ior", SSS_ERR_INVALID_ARGUMENT,
		             gain_of(SSS_CALIBRATION_CYCLES4_RANDOM_WALK, 0.9f, al4,
		                     1.0f, at));
		CHECK_STATUS("nan-walk-ior", SSS_ERR_INVALID_ARGUMENT,
		             gain_of(SSS_CALIBRATION_CYCLES4_RANDOM_WALK, NAN, al4,
		                     1.0f, at));
		sss_material m;
		sss_material_default(&m, SSS_PROFILE_BURLEY);
		m.pass_index = 1;
		m.calibration = SSS_CALIBRATION_CYCLES4_RANDOM_WALK;
		m.walk_roughness = 1.5f;
		CHECK_STATUS("bad-walk-roughness", SSS_ERR_INVALID_ARGUMENT,
		             sss_calibration_gain(&m, al4, 1.0f, at));
		CHECK_STATUS("null-material", SSS_ERR_INVALID_ARGUMENT,
		             sss_calibration_gain(NULL, al4, 1.0f, at));
		/* and its roughness: linear between the measured 0.25 and 0.5,
		 * far brighter at 1 (A = 0.05 at 70 degrees through 1.5) */
		float r25[3], r50[3], r100[3];
		m.walk_ior = 1.5f;
		m.walk_roughness = 0.25f;
		sss_calibration_gain(&m, al4, mu70, r25);
		m.walk_roughness = 0.5f;
		sss_calibration_gain(&m, al4, mu70, r50);
		m.walk_roughness = 1.0f;
		sss_calibration_gain(&m, al4, mu70, r100);
		m.walk_roughness = 0.375f;
		sss_calibration_gain(&m, al4, mu70, at);
		CHECK("table4-rw-roughness",
		      fabsf(at[0] - 0.5f * (r25[0] + r50[0])) < 1e-5f &&
		      r50[0] == hi[0] && r100[0] > 1.15f && r25[0] < 0.92f,
		      "%g at 0.25, %g at 0.375, %g at 0.5, %g at 1", (double)r25[0],
		      (double)at[0], (double)r50[0], (double)r100[0]);
	}
	/* Seen at 60 degrees (mu 0.5, a row), the sign of mu ignored; past
	 * the last row (85 degrees) held; between rows linear in mu. */
	gain_of(SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN, 1.5f, al4, -0.5f,
	                     g4);
	CHECK("table4-skin-60", fabsf(g4[0] - 1.0423f) < 1e-6f &&
	      fabsf(g4[1] - 1.0294f) < 1e-6f && fabsf(g4[2] - 1.0077f) < 1e-6f,
	      "%g %g %g", (double)g4[0], (double)g4[1], (double)g4[2]);
	gain_of(SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN, 1.5f, al4, 0.0f,
	                     g4);
	CHECK("table4-skin-90", fabsf(g4[0] - 1.2665f) < 1e-6f &&
	      fabsf(g4[1] - 1.1137f) < 1e-6f, "%g %g", (double)g4[0],
	      (double)g4[1]);
	float mid = 0.5f * (0.5f + 0.3420201f), g60[3], g70[3];
	gain_of(SSS_CALIBRATION_CYCLES4_RANDOM_WALK, 1.5f, al4, mid, g4);
	gain_of(SSS_CALIBRATION_CYCLES4_RANDOM_WALK, 1.5f, al4, 0.5f, g60);
	gain_of(SSS_CALIBRATION_CYCLES4_RANDOM_WALK, 1.5f, al4, 0.3420201f,
	                     g70);
	CHECK("table4-between", fabsf(g4[1] - 0.5f * (g60[1] + g70[1])) < 1e-5f,
	      "%g between %g and %g", (double)g4[1], (double)g60[1],
	      (double)g70[1]);

	/* 3.4: a gain of about 1.01 head-on, from the view alone beyond. */
	float al[3] = {0.3f, 0.8f, 1.0f}, g[3];
	gain_of(SSS_CALIBRATION_CYCLES_RANDOM_WALK, 1.5f, al, 1.0f, g);
	CHECK("table-measured", fabsf(g[0] - 1.0138f) < 1e-6f &&
	      fabsf(g[1] - 1.0080f) < 1e-6f && fabsf(g[2] - 0.9211f) < 1e-6f,
	      "%g %g %g", (double)g[0], (double)g[1], (double)g[2]);
	gain_of(SSS_CALIBRATION_CYCLES_RANDOM_WALK, 1.5f, al, NAN, g4);
	CHECK("table-nan-view", g4[0] == g[0] && g4[1] == g[1] && g4[2] == g[2],
	      "%g %g %g", (double)g4[0], (double)g4[1], (double)g4[2]);
	float odd[3] = {-1.0f, 2.0f, NAN};
	gain_of(SSS_CALIBRATION_CYCLES_RANDOM_WALK, 1.5f, odd, 1.0f, g);
	CHECK("table-clamp", g[0] == 1.0090f && g[1] == 0.9211f && g[2] == 1.0f,
	      "%g %g %g", (double)g[0], (double)g[1], (double)g[2]);

	gain_of(SSS_CALIBRATION_NONE, 1.5f, al, 1.0f, g);
	CHECK("none-is-one", g[0] == 1.0f && g[1] == 1.0f && g[2] == 1.0f,
	      "%g %g %g", (double)g[0], (double)g[1], (double)g[2]);
	CHECK_STATUS("bad-calibration", SSS_ERR_INVALID_ARGUMENT,
	             gain_of(7, 1.5f, al, 1.0f, g));
	CHECK_STATUS("null", SSS_ERR_INVALID_ARGUMENT,
	             gain_of(SSS_CALIBRATION_NONE, 1.5f, NULL, 1.0f, g));
}

/* d / radius of m with `mapping` at each albedo a[i] against fit[i],
 * within the relative tolerance tol. */
static void check_mapping(sss_material *m, int32_t mapping, float radius,
                          const float *a, const double *fit, int n,
                          double tol)
{
	m->burley_mapping = mapping;
	for (int i = 0; i < n; i++) {
		m->radius[0] = m->radius[1] = m->radius[2] = radius;
		m->albedo[0] = m->albedo[1] = m->albedo[2] = a[i];
		double d[3];
		CHECK_STATUS("mapping-status", SSS_OK, sss_burley_d(m, d));
		CHECK("mapping-fit", fabs(d[0] / (radius * fit[i]) - 1.0) < tol,
		      "mapping %d, A %g: d/r %g, measured %g", (int)mapping,
		      (double)a[i], d[0] / radius, fit[i]);
	}
}

static void test_material(void)
{
	sss_material m;
	sss_material_default(&m, SSS_PROFILE_BURLEY);
	m.pass_index = 1;
	CHECK("default-none", m.calibration == SSS_CALIBRATION_NONE, "%d",
	      m.calibration);
	m.calibration = 4;
	CHECK_STATUS("validate-bad", SSS_ERR_INVALID_ARGUMENT,
	             sss_material_validate(&m, NULL, 0));
	for (int32_t c = SSS_CALIBRATION_CYCLES_RANDOM_WALK;
	     c <= SSS_CALIBRATION_CYCLES4_RANDOM_WALK; c++) {
		m.calibration = c;
		CHECK_STATUS("validate-ok", SSS_OK,
		             sss_material_validate(&m, NULL, 0));
	}
	m.burley_mapping = 5;
	CHECK_STATUS("validate-mapping", SSS_ERR_INVALID_ARGUMENT,
	             sss_material_validate(&m, NULL, 0));
	m.burley_mapping = SSS_BURLEY_CYCLES;

	/* The measured mapping: d / r against the slab fits (within 8 %). */
	static const float a[] = {0.1f, 0.3f, 0.5f, 0.7f, 0.8f, 0.9f, 0.95f};
	static const double fit[] = {0.316, 0.210, 0.145, 0.098, 0.067, 0.034,
	                             0.034};
	check_mapping(&m, SSS_BURLEY_CYCLES_RANDOM_WALK, 1.0f, a, fit, 7, 0.08);
	/* 4.x/5.x's Random Walk: d / r measured, growing with the albedo (the
	 * table itself, at another radius). */
	static const float a4[] = {0.05f, 0.3f, 0.6f, 0.8f, 0.9f, 1.0f};
	static const double fit4[] = {0.0171, 0.0304, 0.0541, 0.0825, 0.100,
	                              0.1039};
	check_mapping(&m, SSS_BURLEY_CYCLES4_RANDOM_WALK, 2.0f, a4, fit4, 6,
	              1e-5);
	m.albedo[2] = 1.5f;
	CHECK_STATUS("mapping4-albedo", SSS_ERR_INVALID_ARGUMENT,
	             sss_material_validate(&m, NULL, 0));
	m.burley_mapping = SSS_BURLEY_CYCLES_RANDOM_WALK;
	CHECK_STATUS("mapping-albedo", SSS_ERR_INVALID_ARGUMENT,
	             sss_material_validate(&m, NULL, 0));
	m.albedo[2] = 0.5f;
	m.radius[0] = m.radius[1] = m.radius[2] = 0.0f;
	double d[3];
	sss_burley_d(&m, d);
	CHECK("mapping-zero", d[0] == 0.0 && d[1] == 0.0 && d[2] == 0.0,
	      "%g", d[0]);
}

/* Runs sss_apply on flat passes facing an orthographic camera; returns
 * the middle pixel's light. */
static sss_result run_tilted(const sss_material *m, float radius_scale,
                             const float col[3], float light, double tilt,
                             float out[3], int *identical);
static sss_result run(const sss_material *m, float radius_scale,
                      const float col[3], float light, float out[3],
                      int *identical)
{
	return run_tilted(m, radius_scale, col, light, 0.0, out, identical);
}

static sss_result run_tilted(const sss_material *m, float radius_scale,
                             const float col[3], float light, double tilt,
                             float out[3], int *identical)
{
	float *dd = malloc(sizeof(float) * 3 * W * H);
	float *dc = malloc(sizeof(float) * 3 * W * H);
	float *z = malloc(sizeof(float) * W * H);
	float *idx = malloc(sizeof(float) * W * H);
	float *o = malloc(sizeof(float) * 3 * W * H);
	sss_passes p;
	flat_passes(&p, dd, dc, z, idx, light, col, tilt);
	sss_camera cam;
	sss_camera_default(&cam);
	cam.type = SSS_CAMERA_ORTHOGRAPHIC;
	cam.ortho_scale = ORTHO;
	sss_options opt;
	sss_options_default(&opt);
	opt.radius_scale = radius_scale;
	opt.num_threads = 1;
	sss_image ol = {o, W, H, 3, 0};
	sss_result r = sss_apply(&p, &cam, m, 1, &opt, NULL, &ol, NULL, 0);
	memcpy(out, o + 3 * (W * (H / 2) + W / 2), sizeof(float) * 3);
	*identical = memcmp(o, dd, sizeof(float) * 3 * W * H) == 0;
	free(dd);
	free(dc);
	free(z);
	free(idx);
	free(o);
	return r;
}

static void test_apply(void)
{
	const float col[3] = {0.3f, 0.8f, 0.97f};
	float g[3], out[3];
	int same;
	gain_of(SSS_CALIBRATION_CYCLES_RANDOM_WALK, 1.5f, col, 1.0f, g);
	for (int t = 0; t < 2; t++) {
		sss_material m;
		sss_material_default(&m, SSS_PROFILE_BURLEY);
		m.pass_index = 1;
		m.texturing = t ? SSS_TEXTURING_PRE_AND_POST : SSS_TEXTURING_POST;
		m.calibration = SSS_CALIBRATION_CYCLES_RANDOM_WALK;
		m.burley_mapping = SSS_BURLEY_CYCLES_RANDOM_WALK;
		memcpy(m.albedo, col, sizeof col);
		m.radius[0] = m.radius[1] = m.radius[2] = 0.05f;

		/* A flat field stays flat, times g(DiffCol) exactly. */
		CHECK_STATUS("apply-status", SSS_OK, run(&m, 1.0f, col, 2.0f, out,
		                                         &same));
		for (int c = 0; c < 3; c++)
			CHECK("apply-gain", fabsf(out[c] - 2.0f * g[c]) < 2e-5f,
			      "texturing %d channel %d: %g, expected %g", t, c,
			      (double)out[c], 2.0 * g[c]);

		/* Nothing scatters: nothing is scaled, bit for bit. */
		run(&m, 0.0f, col, 2.0f, out, &same);
		CHECK("radius-scale-0", same, "texturing %d", t);
		m.strength = 0.0f;
		run(&m, 1.0f, col, 2.0f, out, &same);
		CHECK("strength-0", same, "texturing %d", t);
		m.strength = 1.0f;
		m.radius[0] = m.radius[1] = m.radius[2] = 0.0f;
		run(&m, 1.0f, col, 2.0f, out, &same);
		CHECK("radius-0", same, "texturing %d", t);

		/* Half the strength: half the gain's change. */
		m.radius[0] = m.radius[1] = m.radius[2] = 0.05f;
		m.strength = 0.5f;
		run(&m, 1.0f, col, 2.0f, out, &same);
		for (int c = 0; c < 3; c++)
			CHECK("strength-half", fabsf(out[c] - 2.0f * (1.0f + 0.5f *
			      (g[c] - 1.0f))) < 2e-5f, "channel %d: %g", c,
			      (double)out[c]);

		/* Calibration off: the flat field is unchanged. */
		m.strength = 1.0f;
		m.calibration = SSS_CALIBRATION_NONE;
		run(&m, 1.0f, col, 2.0f, out, &same);
		for (int c = 0; c < 3; c++)
			CHECK("none-flat", fabsf(out[c] - 2.0f) < 2e-5f, "%g",
			      (double)out[c]);
	}
}

/* A Burley material of radius 0.05 m with 4.x's Random Walk calibration
 * and mapping for the diffuse colour col. */
static sss_material calibrated(const float col[3])
{
	sss_material m;
	sss_material_default(&m, SSS_PROFILE_BURLEY);
	m.pass_index = 1;
	m.calibration = SSS_CALIBRATION_CYCLES4_RANDOM_WALK;
	m.burley_mapping = SSS_BURLEY_CYCLES_RANDOM_WALK;
	memcpy(m.albedo, col, 3 * sizeof *col);
	m.radius[0] = m.radius[1] = m.radius[2] = 0.05f;
	return m;
}

/* As the radius vanishes the gain fades continuously to 1: none at and
 * below 1e-5 (Cycles' walk loses light to float precision there, and
 * renders its diffuse BSDF below 1e-8), all of it from 1e-3 up, log-linear
 * between; per channel, on the radius before the reach limit. */
static void test_fade(void)
{
	const float col[3] = {0.05f, 0.3f, 0.8f};
	float g[3], out[3], prev[3];
	int same;
	gain_of(SSS_CALIBRATION_CYCLES4_RANDOM_WALK, 1.5f, col, 1.0f, g);
	sss_material m = calibrated(col);
	const struct { double radius, fade; } at[] = {
		{1e-12, 0.0}, {1e-8, 0.0}, {1e-5, 0.0}, {1e-4, 0.5},
		{1e-3, 1.0}, {1e-2, 1.0}, {0.05, 1.0}, {1e3, 1.0}};
	for (size_t k = 0; k < sizeof at / sizeof *at; k++) {
		CHECK_STATUS("fade-status", SSS_OK,
		             run(&m, (float)(at[k].radius / 0.05), col, 2.0f, out,
		                 &same));
		for (int c = 0; c < 3; c++) {
			double want = 2.0 * (1.0 + at[k].fade * (g[c] - 1.0));
			CHECK("fade-at", fabs(out[c] - want) < 4e-5,
			      "radius %g channel %d: %g, expected %g",
			      at[k].radius, c, (double)out[c], want);
		}
	}
	/* Continuous: 16 steps a decade from 1e-7 to 1e-2 m, none jumps
	 * more than its share of the gain's change. */
	for (int k = 0; k <= 80; k++) {
		double radius = 1e-7 * pow(10.0, k / 16.0);
		run(&m, (float)(radius / 0.05), col, 2.0f, out, &same);
		for (int c = 0; c < 3 && k > 0; c++)
			CHECK("fade-continuous", fabsf(out[c] - prev[c]) <=
			      2.0f * fabsf(1.0f - g[c]) / 32.0f + 4e-5f,
			      "radius %g channel %d: %g after %g", radius, c,
			      (double)out[c], (double)prev[c]);
		memcpy(prev, out, sizeof out);
	}
	/* Per channel: only the channel below the switch loses its gain. */
	m.radius[0] = 1e-5f;
	m.radius[1] = m.radius[2] = 0.05f;
	run(&m, 1.0f, col, 2.0f, out, &same);
	CHECK("fade-channel", fabsf(out[0] - 2.0f) < 4e-5f &&
	      fabsf(out[1] - 2.0f * g[1]) < 4e-5f &&
	      fabsf(out[2] - 2.0f * g[2]) < 4e-5f, "%g %g %g", (double)out[0],
	      (double)out[1], (double)out[2]);
}

/* The gain follows the angle the surface is seen at, from the Depth
 * pass: planes turned 0 to 85 degrees get the table's gain there. */
static void test_view(void)
{
	const float col[3] = {0.05f, 0.4f, 0.8f};
	sss_material m = calibrated(col);
	const double degrees[] = {0, 20, 45, 60, 75, 85};
	for (size_t k = 0; k < sizeof degrees / sizeof *degrees; k++) {
		double tilt = degrees[k] * 3.14159265358979 / 180.0;
		float out[3], g[3];
		int same;
		CHECK_STATUS("view-status", SSS_OK,
		             run_tilted(&m, 1.0f, col, 2.0f, tilt, out, &same));
		sss_calibration_gain(&m, col, (float)cos(tilt), g);
		for (int c = 0; c < 3; c++)
			CHECK("view-gain", fabsf(out[c] - 2.0f * g[c]) < 2e-4f,
			      "%g degrees, channel %d: %g, expected %g", degrees[k],
			      c, (double)out[c], 2.0 * g[c]);
	}
}

int main(void)
{
	test_table();
	test_material();
	test_apply();
	test_fade();
	test_view();
	return tu_finish("test_calibration");
}
