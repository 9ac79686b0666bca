/* test_shape.c - the calibration's shape term: the mean curvature the
 * library reads from the Depth pass (spheres seen orthographically and in
 * perspective, a cylinder, a bowl, tilted planes, silhouettes), the shape
 * tables (1 on flat and concave surfaces and without a calibration,
 * finite, continuous in x), how a rise and a fall apply, and sss_apply
 * on a sphere, whose middle gets the flat gain times the table's at
 * radius / a, unless light also comes from behind; and the auto method,
 * which runs the separable method as if alone where the radius is under
 * the curvature radius, and from there the disk method normalised per
 * source (the light that enters the sphere leaves it). */
#include "sss_internal.h"
#include "test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define N 96       /* image side, pixels */
#define SPAN 3.0   /* the orthographic view's width, in sphere radii */

enum surface { SPHERE, CYLINDER, BOWL, PLANE };

/* Depth of `surface` (radius a = 1, centre at depth 4) through pixel
 * (x, y), or 0 where the ray misses it; the plane is turned `tilt`
 * radians about the vertical axis. */
static double depth_at(const sss__projection *p, enum surface s, int x,
                       int y, double tilt)
{
	double u = (x + 0.5 - p->cx) / p->fx, v = (p->cy - (y + 0.5)) / p->fy;
	const double zc = 4.0;
	if (s == PLANE) /* z = zc + tan(tilt) X, X = u (ortho) or u z */
		return p->ortho ? zc + tan(tilt) * u : zc / (1.0 - tan(tilt) * u);
	if (p->ortho) {
		double r2 = s == CYLINDER ? u * u : u * u + v * v;
		if (r2 >= 1.0)
			return 0.0;
		return s == BOWL ? zc + sqrt(1.0 - r2) : zc - sqrt(1.0 - r2);
	}
	/* (u t, v t, t) on the sphere |P - (0, 0, zc)| = 1 */
	double k = u * u + v * v + 1.0, disc = zc * zc - k * (zc * zc - 1.0);
	if (s != SPHERE || disc <= 0.0)
		return 0.0;
	return (zc - sqrt(disc)) / k;
}

static void make_depth(const sss__projection *p, enum surface s,
                       double tilt, float *z, int16_t *slot)
{
	for (int y = 0; y < N; y++)
		for (int x = 0; x < N; x++) {
			double d = depth_at(p, s, x, y, tilt);
			z[y * N + x] = (float)d;
			slot[y * N + x] = d > 0.0 ? 0 : -1;
		}
}

static sss__projection projection(int ortho)
{
	sss_camera cam;
	sss_camera_default(&cam);
	if (ortho) {
		cam.type = SSS_CAMERA_ORTHOGRAPHIC;
		cam.ortho_scale = SPAN;
	} else {
		/* the sphere fills about the same share of the frame */
		cam.lens_mm = 36.0 * 4.0 / SPAN;
	}
	sss__projection p;
	sss__projection_make(&cam, N, N, &p, NULL, 0);
	return p;
}

/* The largest relative error of H a against `want` over the pixels whose
 * point lies within `inner` radii of the view axis. */
static double worst(const sss__projection *p, enum surface s, double tilt,
                    double rho, double inner, double want, int *count)
{
	float *z = malloc(sizeof(float) * N * N);
	int16_t *slot = malloc(sizeof(int16_t) * N * N);
	make_depth(p, s, tilt, z, slot);
	sss_image depth = {z, N, N, 1, 0};
	double err = 0.0;
	*count = 0;
	for (int y = 0; y < N; y++)
		for (int x = 0; x < N; x++) {
			/* a circle that leaves the image shrinks; the
			   outermost rows and columns keep only a part */
			if (slot[y * N + x] < 0 || x < 4 || y < 4 || x >= N - 4 ||
			    y >= N - 4)
				continue;
			double u = (x + 0.5 - p->cx) / p->fx * (p->ortho ? 1.0 : 4.0);
			double v = (p->cy - (y + 0.5)) / p->fy * (p->ortho ? 1.0 : 4.0);
			double r2 = s == CYLINDER ? u * u : u * u + v * v;
			double h = sss__mean_curvature(&depth, slot, p, N, N, x, y,
			                               rho);
			if (!isfinite(h)) {
				err = INFINITY;
				continue;
			}
			if (r2 > inner * inner)
				continue;
			double e = want == 0.0 ? fabs(h) : fabs(h / want - 1.0);
			err = e > err ? e : err;
			(*count)++;
		}
	free(z);
	free(slot);
	return err;
}

static void test_curvature(void)
{
	sss__projection ortho = projection(1), persp = projection(0);
	int n;
	double e;
	/* Exact on a sphere whatever the circle: drop / chord^2 = 1 / 2a. */
	const double rhos[] = {0.1, 0.25, 0.5};
	for (int k = 0; k < 3; k++) {
		e = worst(&ortho, SPHERE, 0, rhos[k], 0.6, 1.0, &n);
		CHECK("sphere-ortho", e < 0.03 && n > 500, "rho %g: error %g over "
		      "%d pixels", rhos[k], e, n);
	}
	e = worst(&persp, SPHERE, 0, 0.25, 0.5, 1.0, &n);
	CHECK("sphere-perspective", e < 0.05 && n > 300, "error %g over %d "
	      "pixels", e, n);
	e = worst(&ortho, CYLINDER, 0, 0.25, 0.5, 0.5, &n);
	CHECK("cylinder", e < 0.05 && n > 500, "error %g over %d pixels", e, n);
	e = worst(&ortho, BOWL, 0, 0.25, 0.6, -1.0, &n);
	CHECK("bowl-concave", e < 0.03 && n > 500, "error %g over %d pixels",
	      e, n);
	const double tilts[] = {0.0, 0.5, 1.2};
	for (int k = 0; k < 3; k++) {
		e = worst(&ortho, PLANE, tilts[k], 0.25, 10.0, 0.0, &n);
		CHECK("plane-flat", e < 1e-3 && n > 7000, "tilt %g: |H| %g",
		      tilts[k], e);
		e = worst(&persp, PLANE, tilts[k], 0.25, 10.0, 0.0, &n);
		CHECK("plane-flat-perspective", e < 1e-3, "tilt %g: |H| %g",
		      tilts[k], e);
	}
	/* Near the silhouette the circle shrinks until it fits: still finite
	 * everywhere (worst() flags a NaN as infinite), and the sphere's
	 * curvature up to 0.9 radii out. */
	e = worst(&ortho, SPHERE, 0, 0.5, 0.9, 1.0, &n);
	CHECK("sphere-rim", e < 0.1, "error %g", e);
	/* A circle far wider than the object, or a NaN or zero scale. */
	float z[N * N];
	int16_t slot[N * N];
	make_depth(&ortho, SPHERE, 0, z, slot);
	sss_image depth = {z, N, N, 1, 0};
	double h = sss__mean_curvature(&depth, slot, &ortho, N, N, N / 2, N / 2,
	                               1e6);
	CHECK("huge-circle", fabs(h - 1.0) < 0.03, "%g", h);
	CHECK("bad-scale", sss__mean_curvature(&depth, slot, &ortho, N, N, N / 2,
	                                       N / 2, NAN) == 0.0 &&
	      sss__mean_curvature(&depth, slot, &ortho, N, N, N / 2, N / 2,
	                          0.0) == 0.0, "not 0");
	/* A lone pixel tells nothing. */
	for (int i = 0; i < N * N; i++)
		slot[i] = -1;
	slot[N * N / 2 + N / 2] = 0;
	CHECK("lone-pixel", sss__mean_curvature(&depth, slot, &ortho, N, N,
	                                        N / 2, N / 2, 0.25) == 0.0,
	      "not 0");
}

static void test_table(void)
{
	const int32_t shaped[] = {SSS_CALIBRATION_CYCLES_RANDOM_WALK,
	                          SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN,
	                          SSS_CALIBRATION_CYCLES4_RANDOM_WALK};
	int flat = 1, finite = 1, continuous = 1;
	for (int k = 0; k < 3; k++)
		for (int i = 0; i <= 100; i++) {
			float a = (float)i / 100.0f, prev = 1.0f;
			flat &= sss__shape_gain(shaped[k], a, 0.0f) == 1.0f &&
			        sss__shape_gain(shaped[k], a, -3.0f) == 1.0f &&
			        sss__shape_gain(shaped[k], a, NAN) == 1.0f;
			/* 20 steps a decade from 1e-4 to 1e3 */
			for (int j = 0; j <= 140; j++) {
				float x = 1e-4f * powf(10.0f, (float)j / 20.0f);
				float g = sss__shape_gain(shaped[k], a, x);
				finite &= isfinite(g) && g > 0.05f && g < 5.0f;
				continuous &= fabsf(g - prev) < 0.2f;
				prev = g;
			}
		}
	CHECK("table-flat", flat, "a gain other than 1 on a flat or concave "
	      "surface");
	CHECK("table-finite", finite, "a gain outside (0.05, 5)");
	CHECK("table-continuous", continuous, "a jump of 0.2 or more");
	CHECK("table-none", sss__shape_gain(SSS_CALIBRATION_NONE, 0.5f, 1.0f) ==
	      1.0f && sss__shape_gain(99, 0.5f, 1.0f) == 1.0f,
	      "a shape gain without a calibration");
	/* Measured: convex objects return more light at low albedo. */
	CHECK("table-measured",
	      sss__shape_gain(SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN, 0.05f,
	                      0.3f) > 1.5f &&
	      sss__shape_gain(SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN, 0.8f,
	                      0.01f) < 1.01f, "not the measured table");
}

/* An orthographic sphere of radius 1 m under an even light of 2, DiffCol
 * a3, with a back-light pass (no light, the sphere's diameter as
 * thickness) that a test may hand to sss_apply. */
typedef struct sphere_frame {
	sss__projection proj;
	float *dd, *col, *z, *idx, *back, *thick, *out;
	int16_t *slot;
	sss_passes ps;
	sss_camera cam;
	sss_options opt;
} sphere_frame;

static void sphere_frame_make(sphere_frame *f, const float a3[3])
{
	f->proj = projection(1);
	f->dd = malloc(sizeof(float) * 3 * N * N);
	f->col = malloc(sizeof(float) * 3 * N * N);
	f->z = malloc(sizeof(float) * N * N);
	f->idx = malloc(sizeof(float) * N * N);
	f->back = calloc(3 * N * N, sizeof(float));
	f->thick = malloc(sizeof(float) * N * N);
	f->out = malloc(sizeof(float) * 3 * N * N);
	f->slot = malloc(sizeof(int16_t) * N * N);
	make_depth(&f->proj, SPHERE, 0, f->z, f->slot);
	for (int i = 0; i < N * N; i++) {
		f->idx[i] = f->slot[i] >= 0 ? 1.0f : 0.0f;
		if (f->slot[i] < 0)
			f->z[i] = 1e10f;
		f->thick[i] = 2.0f; /* the sphere's diameter: no light crosses */
		for (int c = 0; c < 3; c++) {
			f->dd[3 * i + c] = 2.0f;
			f->col[3 * i + c] = a3[c];
		}
	}
	memset(&f->ps, 0, sizeof f->ps);
	f->ps.diff_dir = (sss_image){f->dd, N, N, 3, 0};
	f->ps.diff_col = (sss_image){f->col, N, N, 3, 0};
	f->ps.depth = (sss_image){f->z, N, N, 1, 0};
	f->ps.index_ma = (sss_image){f->idx, N, N, 1, 0};
	sss_camera_default(&f->cam);
	f->cam.type = SSS_CAMERA_ORTHOGRAPHIC;
	f->cam.ortho_scale = SPAN;
	sss_options_default(&f->opt);
	f->opt.num_threads = 1;
	/* The calibration's terms on the method that reads the light as it
	 * is: auto's per-source normalisation (test_auto) moves it. */
	f->opt.method = SSS_METHOD_SEPARABLE;
}

static void sphere_frame_free(sphere_frame *f)
{
	free(f->dd);
	free(f->col);
	free(f->z);
	free(f->idx);
	free(f->back);
	free(f->thick);
	free(f->out);
	free(f->slot);
}

/* Burley matched to 4.x's Random Walk (Skin), radius r m, albedo a3. */
static sss_material skin_walk(float r, const float a3[3])
{
	sss_material m;
	sss_material_default(&m, SSS_PROFILE_BURLEY);
	m.pass_index = 1;
	m.calibration = SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN;
	m.burley_mapping = SSS_BURLEY_CYCLES_RANDOM_WALK;
	memcpy(m.albedo, a3, 3 * sizeof *a3);
	m.radius[0] = m.radius[1] = m.radius[2] = r;
	return m;
}

/* sss_apply on the sphere: the blur keeps the even light, so the middle
 * pixel (seen head-on) is the light times g(A, 1) times the shape gain at
 * x = radius (up to x = 10, where the far term, test_far, starts). */
static void test_apply(void)
{
	const float a3[3] = {0.2f, 0.5f, 0.8f};
	sphere_frame f;
	sphere_frame_make(&f, a3);
	const float radii[] = {0.03f, 0.3f, 1.0f, 8.0f};
	for (int k = 0; k < 4; k++) {
		sss_material m = skin_walk(radii[k], a3);
		sss_image ol = {f.out, N, N, 3, 0};
		CHECK_STATUS("apply-status", SSS_OK,
		             sss_apply(&f.ps, &f.cam, &m, 1, &f.opt, NULL, &ol,
		                       NULL, 0));
		float g[3];
		sss_calibration_gain(&m, a3, 1.0f, g);
		const float *o = f.out + 3 * (N * (N / 2) + N / 2);
		for (int c = 0; c < 3; c++) {
			double want = 2.0 * g[c] *
			              fmax(sss__shape_gain(m.calibration, a3[c],
			                                   radii[k]), 1.0);
			CHECK("apply-sphere", fabs(o[c] / want - 1.0) < 0.02,
			      "radius %g channel %d: %g, expected %g",
			      (double)radii[k], c, (double)o[c], want);
		}
		/* Half a radius out the view is 30 degrees off the normal: the
		 * flat gain there, times the shape's rise scaled by the view
		 * cosine (no fall). */
		int x = N / 2 + (int)(0.5 * N / SPAN), y = N / 2;
		float mu = sss__view_cosine(&f.ps.depth, f.slot, &f.proj, N, N, x,
		                            y);
		double H = sss__mean_curvature(&f.ps.depth, f.slot, &f.proj, N, N,
		                               x, y, radii[k]);
		sss_calibration_gain(&m, a3, mu, g);
		o = f.out + 3 * (N * y + x);
		for (int c = 0; c < 3; c++) {
			double sg = sss__shape_gain(m.calibration, a3[c],
			                            (float)(H * radii[k]));
			double want = 2.0 * g[c] * (sg > 1.0 ? 1.0 + mu * (sg - 1.0)
			                                     : 1.0);
			CHECK("apply-sphere-view", fabs(o[c] / want - 1.0) < 1e-4 &&
			      fabs(mu - 0.866) < 0.03 && fabs(H - 1.0) < 0.03,
			      "radius %g channel %d: %g, expected %g (mu %g, H %g)",
			      (double)radii[k], c, (double)o[c], want, (double)mu, H);
		}
	}
	sphere_frame_free(&f);
}

/* A rise counts times the view cosine; a fall (the object's thickness,
 * which curvature does not tell) is not applied; no shape, no change. */
static void test_rise_and_fall(void)
{
	sss_material m;
	sss_material_default(&m, SSS_PROFILE_BURLEY);
	m.pass_index = 1;
	m.calibration = SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN;
	const float fade[3] = {1, 1, 1}, col[3] = {0.3f, 0.5f, 0.8f};
	const float rise[3] = {1, 1, 1}, fall[3] = {100, 100, 100};
	const float mu = 0.6f;
	float g[3];
	CHECK_STATUS("rise-gain", SSS_OK, sss_calibration_gain(&m, col, mu, g));
	float up[3] = {1, 1, 1}, down[3] = {1, 1, 1}, flat[3] = {1, 1, 1};
	float table[SSS__CAL_TABLE];
	sss__calibration_table(&m, table);
	sss__calibration_apply(&m, table, fade, mu, rise, NULL, col, up);
	sss__calibration_apply(&m, table, fade, mu, fall, NULL, col, down);
	sss__calibration_apply(&m, table, fade, mu, NULL, NULL, col, flat);
	for (int c = 0; c < 3; c++) {
		float sr = sss__shape_gain(m.calibration, col[c], 1.0f);
		float sf = sss__shape_gain(m.calibration, col[c], 100.0f);
		CHECK("rise-times-view", sr > 1.0f &&
		      fabsf(up[c] - g[c] * (1.0f + mu * (sr - 1.0f))) < 1e-6f,
		      "channel %d: %g", c, (double)up[c]);
		CHECK("fall-not-applied", sf < 1.0f && down[c] == g[c],
		      "channel %d: %g", c, (double)down[c]);
		CHECK("no-shape", flat[c] == g[c], "channel %d", c);
	}
}

/* A material lit from behind (a back-light pass and transmission on)
 * does not follow the shape: the back-lit transmission stands for what a
 * finite object adds, and both counted that light twice. With no back
 * light at all, the same material does. */
static void test_backlit(void)
{
	const float a3[3] = {0.2f, 0.5f, 0.8f};
	sphere_frame f;
	sphere_frame_make(&f, a3);
	sss_material m = skin_walk(0.3f, a3);
	m.transmission = SSS_TRANSMISSION_BURLEY;
	sss_image ol = {f.out, N, N, 3, 0};
	float g[3];
	sss_calibration_gain(&m, a3, 1.0f, g);
	const float *o = f.out + 3 * (N * (N / 2) + N / 2);
	for (int lit = 0; lit < 2; lit++) {
		if (lit) {
			f.ps.back_dir = (sss_image){f.back, N, N, 3, 0};
			f.ps.thickness = (sss_image){f.thick, N, N, 1, 0};
		}
		CHECK_STATUS("backlit-status", SSS_OK,
		             sss_apply(&f.ps, &f.cam, &m, 1, &f.opt, NULL, &ol,
		                       NULL, 0));
		for (int c = 0; c < 3; c++) {
			double want = 2.0 * g[c] *
			              (lit ? 1.0 : sss__shape_gain(m.calibration,
			                                           a3[c], 0.3f));
			CHECK("backlit-shape", fabs(o[c] / want - 1.0) < 0.02,
			      "back light %d, channel %d: %g, expected %g", lit, c,
			      (double)o[c], want);
		}
	}
	sphere_frame_free(&f);
}

/* One run of `method` on the frame: the diffuse light into out, the
 * method each material ran into chosen. */
static sss_result run_method(sphere_frame *f, const sss_material *m,
                             int32_t count, int32_t method, float *out,
                             int32_t *chosen)
{
	sss_options o = f->opt;
	o.method = method;
	sss_image ol = {out, N, N, 3, 0};
	return sss__apply_report(&f->ps, &f->cam, m, count, &o, NULL, &ol,
	                         NULL, NULL, chosen, NULL, 0);
}

/* Whether out equals want exactly on the pixels of pass index idx. */
static int same_on(const sphere_frame *f, const float *out,
                   const float *want, float idx)
{
	for (int i = 0; i < N * N; i++)
		if (f->idx[i] == idx &&
		    memcmp(out + 3 * i, want + 3 * i, 3 * sizeof *out) != 0)
			return 0;
	return 1;
}

/* Burley with radius r m on every channel, no calibration: the light
 * out is the light scattered, nothing added. */
static sss_material plain_burley(float r)
{
	sss_material m;
	sss_material_default(&m, SSS_PROFILE_BURLEY);
	m.pass_index = 1;
	m.radius[0] = m.radius[1] = m.radius[2] = r;
	return m;
}

/* The light out over the light in, over the pixels of pass index idx. */
static double light_ratio(const sphere_frame *f, const float *out,
                          float idx)
{
	double in = 0.0, sum = 0.0;
	for (int i = 0; i < N * N; i++)
		if (f->idx[i] == idx)
			for (int c = 0; c < 3; c++) {
				in += f->dd[3 * i + c];
				sum += out[3 * i + c];
			}
	return sum / in;
}

/* auto on the sphere (radius a = 1) lit along the view, with detail so
 * that the methods differ: x = radius / a below 1 runs separable, exactly
 * as when asked for; from 1 the disk method per source, which keeps the
 * light that enters (the normalised disk adds 3-5 % here, moving the
 * middle's light out to the darker rim); with two materials, one of
 * each, each half is its own method's (the signal is planar for the one
 * and packed for the other); a flat plane is separable at any radius; a
 * material not on screen reports -1. */
static void test_auto(void)
{
	const float a3[3] = {0.3f, 0.5f, 0.7f};
	sphere_frame f;
	sphere_frame_make(&f, a3);
	/* Lit along the view (the irradiance is the normal's z, bright in
	 * the middle, dark at the rim), with detail. */
	for (int i = 0; i < N * N; i++) {
		double u = (i % N + 0.5 - N / 2.0) * SPAN / N;
		double v = (i / N + 0.5 - N / 2.0) * SPAN / N;
		double nz = sqrt(fmax(0.0, 1.0 - u * u - v * v));
		for (int c = 0; c < 3; c++)
			f.dd[3 * i + c] = (float)(nz * (1.0 + 0.5 * sin(0.7 * (i % N) +
			                                               c) *
			                                     cos(0.45 * (i / N))));
	}
	float *a = malloc(sizeof(float) * 3 * N * N);
	float *b = malloc(sizeof(float) * 3 * N * N);
	const struct {
		float radius;
		int32_t method;
	} cases[] = {{0.05f, SSS_METHOD_SEPARABLE}, {0.5f, SSS_METHOD_SEPARABLE},
	             {1.5f, SSS_METHOD_DISK}, {20.0f, SSS_METHOD_DISK}};
	for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
		sss_material m[2] = {plain_burley(cases[k].radius),
		                     plain_burley(0.1f)};
		m[1].pass_index = 7; /* not on screen */
		int32_t chosen[2] = {-5, -5}, alone[2];
		CHECK_STATUS("auto-status", SSS_OK,
		             run_method(&f, m, 2, SSS_METHOD_AUTO, a, chosen));
		CHECK_STATUS("auto-alone-status", SSS_OK,
		             run_method(&f, m, 2, cases[k].method, b, alone));
		CHECK("auto-choice", chosen[0] == cases[k].method &&
		      chosen[1] == -1 && alone[0] == cases[k].method,
		      "radius %g: chose %d (expected %d), off screen %d",
		      (double)cases[k].radius, chosen[0], cases[k].method,
		      chosen[1]);
		if (cases[k].method == SSS_METHOD_SEPARABLE)
			CHECK("auto-same", same_on(&f, a, b, 1.0f),
			      "radius %g: auto differs from separable alone",
			      (double)cases[k].radius);
		else {
			/* Per source: the light that enters leaves, where the
			 * normalised blur moves it out to the rim's pixels. */
			double ra = light_ratio(&f, a, 1.0f);
			double rd = light_ratio(&f, b, 1.0f);
			CHECK("auto-per-source", fabs(ra - 1.0) < 0.01 &&
			      fabs(rd - 1.0) > 0.02,
			      "radius %g: light out / in %g (disk alone %g)",
			      (double)cases[k].radius, ra, rd);
		}
	}

	/* Left half narrow, right half wide. */
	for (int i = 0; i < N * N; i++)
		if (f.idx[i] > 0.0f && i % N >= N / 2)
			f.idx[i] = 2.0f;
	sss_material two[2] = {plain_burley(0.1f), plain_burley(4.0f)};
	two[1].pass_index = 2;
	int32_t chosen[2];
	CHECK_STATUS("auto-two-status", SSS_OK,
	             run_method(&f, two, 2, SSS_METHOD_AUTO, a, chosen));
	CHECK("auto-two-choice", chosen[0] == SSS_METHOD_SEPARABLE &&
	      chosen[1] == SSS_METHOD_DISK, "chose %d, %d", chosen[0],
	      chosen[1]);
	for (int d = 0; d < 2; d++) {
		int32_t method = d ? SSS_METHOD_DISK : SSS_METHOD_SEPARABLE;
		CHECK_STATUS("auto-two-alone", SSS_OK,
		             run_method(&f, two, 2, method, b, NULL));
		if (!d)
			CHECK("auto-two-same", same_on(&f, a, b, 1.0f),
			      "the left half differs from separable alone");
		else
			CHECK("auto-two-per-source",
			      fabs(light_ratio(&f, a, 2.0f) - 1.0) < 0.01,
			      "the right half: light out / in %g (disk alone %g)",
			      light_ratio(&f, a, 2.0f), light_ratio(&f, b, 2.0f));
	}

	/* A plane facing the camera, every pixel scattering. */
	for (int i = 0; i < N * N; i++) {
		f.z[i] = 4.0f;
		f.idx[i] = 1.0f;
	}
	sss_material wide = skin_walk(50.0f, a3);
	CHECK_STATUS("auto-plane-status", SSS_OK,
	             run_method(&f, &wide, 1, SSS_METHOD_AUTO, a, chosen));
	CHECK("auto-plane", chosen[0] == SSS_METHOD_SEPARABLE,
	      "a plane chose %d", chosen[0]);
	free(a);
	free(b);
	sphere_frame_free(&f);
}

/* A radius 40 and 100 times the sphere's, lit evenly from the front:
 * the walk's light spreads over the whole object and as much leaves by
 * the far side, so the visible side returns far less than the diffuse
 * render (8 cm sphere at 5 m in Blender 4.5: 0.35 / 0.49 / 0.62 of it;
 * ours kept the lit side's light and was 1.04, brighter than the diffuse
 * render). Over the sphere the mean is now the light times g(A, 1) times
 * the walk's whole-side gain at the median x, within the view gain's
 * spread; before, it was at least the light times g. */
static void test_far(void)
{
	const float a3[3] = {0.3f, 0.5f, 0.8f};
	sphere_frame f;
	sphere_frame_make(&f, a3);
	const float radii[] = {40.0f, 100.0f};
	int32_t chosen[1];
	for (int k = 0; k < 2; k++) {
		sss_material m = skin_walk(radii[k], a3);
		CHECK_STATUS("far-status", SSS_OK,
		             run_method(&f, &m, 1, SSS_METHOD_AUTO, f.out, chosen));
		float x = NAN;
		int32_t unused;
		CHECK_STATUS("far-median", SSS_OK,
		             sss__auto_methods(&f.ps.depth, f.slot, &f.proj, N, N,
		                               &(sss__kernel){.walk_radius =
		                                   {radii[k], radii[k], radii[k]}},
		                               1, &unused, &x));
		double sum[3] = {0, 0, 0};
		int n = 0;
		for (int i = 0; i < N * N; i++)
			if (f.slot[i] >= 0) {
				for (int c = 0; c < 3; c++)
					sum[c] += f.out[3 * i + c];
				n++;
			}
		float g[3];
		sss_calibration_gain(&m, a3, 1.0f, g);
		for (int c = 0; c < 3; c++) {
			float w;
			double whole = sss__far_gain(m.calibration, a3[c], x, &w);
			double got = sum[c] / n / 2.0;
			CHECK("far-mean", w == 1.0f && whole < 0.75 &&
			      fabs(got / (g[c] * whole) - 1.0) < 0.1,
			      "radius %g (median x %g) channel %d: mean %g of the "
			      "light, expected %g", (double)radii[k], (double)x, c,
			      got, g[c] * whole);
		}
	}
	sphere_frame_free(&f);
}

int main(void)
{
	test_curvature();
	test_table();
	test_apply();
	test_rise_and_fall();
	test_far();
	test_backlit();
	test_auto();
	return tu_finish("test_shape");
}
