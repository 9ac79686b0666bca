/* test_blur.c - behaviour of the blur and the composite on synthetic
 * passes: invariants, the separable method against the brute-force
 * reference, depth awareness, the material table, threads, texturing. */
#include "sss_blur1d.h"
#include "synth.h"
#include "test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static const int kinds[] = {SSS_PROFILE_BURLEY, SSS_PROFILE_GAUSSIANS,
                            SSS_PROFILE_JIMENEZ, SSS_PROFILE_NEAR_FAR};
static const int methods[] = {SSS_METHOD_SEPARABLE, SSS_METHOD_REFERENCE,
                               SSS_METHOD_SEPARABLE_EXACT, SSS_METHOD_DISK};
#define NMETHODS (sizeof methods / sizeof *methods)

/* Pixels per metre at depth z for the default camera (36 mm sensor across
 * the width, 50 mm lens). */
static double ppm_at(int w, double z)
{
	return w * 50.0 / 36.0 / z;
}

/* A material of `kind` whose support spans about `px` pixels at depth z. */
static sss_material material_px(int kind, int index, double px, int w,
                                 double z)
{
	sss_material m;
	sss_material_default(&m, kind);
	m.pass_index = index;
	double support;
	sss_material_support(&m, &support);
	double scale = px / (support * ppm_at(w, z));
	switch (kind) {
	case SSS_PROFILE_BURLEY:
		for (int c = 0; c < 3; c++)
			m.radius[c] *= (float)scale;
		break;
	case SSS_PROFILE_GAUSSIANS:
		m.gaussian_scale *= (float)scale;
		break;
	case SSS_PROFILE_JIMENEZ:
		m.jimenez_width *= (float)scale;
		for (int c = 0; c < 3; c++)
			m.jimenez_strength[c] = 1.0f;
		break;
	case SSS_PROFILE_NEAR_FAR:
		m.scatter_scale *= (float)scale;
		break;
	}
	return m;
}

/* One Gaussian lobe whose support spans `px` pixels at depth z. */
static sss_material single_gaussian(int index, double px, int w, double z)
{
	sss_material m;
	sss_material_default(&m, SSS_PROFILE_GAUSSIANS);
	m.pass_index = index;
	m.gaussian_count = 1;
	m.gaussian_variance[0] = 1.0f;
	for (int c = 0; c < 3; c++)
		m.gaussian_weight[0][c] = 1.0f;
	double support;
	sss_material_support(&m, &support);
	m.gaussian_scale = (float)(px / (support * ppm_at(w, z)));
	return m;
}

typedef struct run {
	float *light;    /* RGB */
	float *combined; /* RGBA */
	sss_result status;
} run;

static run apply_cam(const synth *s, const sss_material *mats, int n,
                     const sss_options *opt, const sss_camera *cam);

static run apply(const synth *s, const sss_material *mats, int n,
                 const sss_options *opt)
{
	sss_camera cam;
	sss_camera_default(&cam);
	return apply_cam(s, mats, n, opt, &cam);
}

static run apply_cam(const synth *s, const sss_material *mats, int n,
                     const sss_options *opt, const sss_camera *cam)
{
	run r;
	size_t np = (size_t)s->w * s->h;
	r.light = calloc(3 * np, sizeof(float));
	r.combined = calloc(4 * np, sizeof(float));
	sss_passes p = synth_passes(s);
	sss_image ol = {r.light, s->w, s->h, 3, 0};
	sss_image oc = {r.combined, s->w, s->h, 4, 0};
	char err[256] = "";
	r.status = sss_apply(&p, cam, mats, n, opt, &oc, &ol, err, sizeof err);
	if (r.status)
		printf("sss_apply: %s: %s\n", sss_status_name(r.status), err);
	return r;
}

static void run_free(run *r)
{
	free(r->light);
	free(r->combined);
}

static sss_options options(int method)
{
	sss_options o;
	sss_options_default(&o);
	o.method = method;
	return o;
}

/* Constant light on a scene with holes, a depth ramp and two materials
 * stays constant for every kind, method and texturing mode. */
static void test_constant(void)
{
	int w = 40, h = 30;
	for (size_t k = 0; k < 4; k++)
		for (size_t mt = 0; mt < NMETHODS; mt++)
			for (int tex = 0; tex < 2; tex++) {
				synth *s = synth_new(w, h);
				for (int y = 0; y < h; y++)
					for (int x = 0; x < w; x++) {
						size_t i = (size_t)y * w + x;
						s->depth[i] = 2.0f + 0.02f * x; /* slanted */
						s->index[i] = x < 25 ? 1.0f : 2.0f;
						if ((x - 12) * (x - 12) + (y - 15) * (y - 15) < 9)
							s->depth[i] = 1e10f; /* a hole */
						s->diff_dir[3 * i] = 0.2f;
						s->diff_dir[3 * i + 1] = 0.5f;
						s->diff_dir[3 * i + 2] = 0.9f;
						s->diff_ind[3 * i] = 0.1f;
						s->diff_col[3 * i + 1] = 0.6f;
					}
				sss_material m[2] = {material_px(kinds[k], 1, 9, w, 2),
				                     material_px(kinds[k], 2, 5, w, 2)};
				m[0].texturing = m[1].texturing = tex;
				sss_options o = options(methods[mt]);
				run r = apply(s, m, 2, &o);
				double worst = 0;
				for (size_t i = 0; i < (size_t)w * h; i++)
					for (int c = 0; c < 3; c++) {
						double want = s->diff_dir[3 * i + c] +
						              s->diff_ind[3 * i + c];
						worst = fmax(worst, fabs(r.light[3 * i + c] - want));
					}
				char id[48];
				snprintf(id, sizeof id, "constant-%zu.%zu.%d", k, mt, tex);
				CHECK(id, r.status == SSS_OK && worst < 2e-6,
				      "max deviation %g", worst);
				run_free(&r);
				synth_free(s);
			}
}

/* Radius 0, strength 0, radius_scale 0 and an empty table are the identity
 * bit for bit, for the light and for the composite. */
static void test_identity(void)
{
	int w = 24, h = 20;
	synth *s = synth_new(w, h);
	synth_plane(s, 0, 0, w, h, 2.0f, 1.0f);
	synth_noise(s, 0, 1, 7);
	uint32_t st = 3;
	for (size_t i = 0; i < (size_t)3 * w * h; i++) {
		s->diff_col[i] = synth_rand(&st);
		s->gloss_dir[i] = synth_rand(&st);
		s->gloss_col[i] = 0.04f;
	}
	sss_options o = options(SSS_METHOD_SEPARABLE);
	run base = apply(s, NULL, 0, &o);
	for (size_t mt = 0; mt < NMETHODS; mt++)
		for (int variant = 0; variant < 3; variant++)
			for (int tex = 0; tex < 2; tex++) {
				sss_material m = material_px(SSS_PROFILE_BURLEY, 1, 8, w, 2);
				m.texturing = tex;
				sss_options oo = options(methods[mt]);
				if (variant == 0)
					m.radius[0] = m.radius[1] = m.radius[2] = 0;
				if (variant == 1)
					m.strength = 0;
				if (variant == 2)
					oo.radius_scale = 0;
				run r = apply(s, &m, 1, &oo);
				char id[48];
				snprintf(id, sizeof id, "identity-%zu.%d.%d", mt, variant, tex);
				CHECK(id, memcmp(r.light, base.light,
				                 3 * sizeof(float) * w * h) == 0 &&
				      memcmp(r.combined, base.combined,
				             4 * sizeof(float) * w * h) == 0,
				      "not bit-identical");
				run_free(&r);
			}
	/* And the light without a table is exactly DiffDir + DiffInd. */
	int same = 1;
	for (size_t i = 0; i < (size_t)3 * w * h; i++)
		same &= base.light[i] == s->diff_dir[i] + s->diff_ind[i];
	CHECK("identity-light", same, "light differs from DiffDir + DiffInd");
	run_free(&base);
	synth_free(s);
}

/* The impulse response is symmetric under mirroring in x and in y. */
static void test_impulse_symmetry(void)
{
	int w = 33, h = 33;
	for (size_t k = 0; k < 4; k++)
		for (size_t mt = 0; mt < NMETHODS; mt++)
			for (int px = 6; px <= 60; px += 54) { /* dense and sparse */
				/* The disk method's per-pixel rotations are noise with
				 * no mirror symmetry (tests/test_methods.c measures it). */
				if (methods[mt] == SSS_METHOD_DISK)
					continue;
				synth *s = synth_new(w, h);
				synth_plane(s, 0, 0, w, h, 2.0f, 1.0f);
				size_t centre = (size_t)16 * w + 16;
				for (int c = 0; c < 3; c++)
					s->diff_dir[3 * centre + c] = 1.0f;
				sss_material m = material_px(kinds[k], 1, px, w, 2);
				sss_options o = options(methods[mt]);
				run r = apply(s, &m, 1, &o);
				double worst = 0, peak = 0;
				for (int y = 0; y < h; y++)
					for (int x = 0; x < w; x++)
						for (int c = 0; c < 3; c++) {
							float v = r.light[3 * (y * w + x) + c];
							float mx = r.light[3 * (y * w + (w - 1 - x)) + c];
							float my = r.light[3 * ((h - 1 - y) * w + x) + c];
							worst = fmax(worst, fmax(fabs(v - mx),
							                         fabs(v - my)));
							peak = fmax(peak, v);
						}
				char id[48];
				snprintf(id, sizeof id, "impulse-%zu.%zu.%d", k, mt, px);
				CHECK(id, worst <= 1e-6 * peak && peak <= 1.0f,
				      "asymmetry %g of peak %g", worst, peak);
				run_free(&r);
				synth_free(s);
			}
}

static double max_diff(const float *a, const float *b, size_t n,
                       double *rms)
{
	double worst = 0, sq = 0;
	for (size_t i = 0; i < n; i++) {
		double d = fabs((double)a[i] - b[i]);
		worst = fmax(worst, d);
		sq += d * d;
	}
	if (rms)
		*rms = sqrt(sq / n);
	return worst;
}

/* One Gaussian lobe on a flat plane: separable == reference to 1e-4. */
static void test_gaussian_vs_reference(void)
{
	int w = 64, h = 48;
	synth *s = synth_new(w, h);
	synth_plane(s, 0, 0, w, h, 2.0f, 1.0f);
	synth_noise(s, 0, 1, 11);
	for (int px = 8; px <= 24; px += 8) {
		sss_material m = single_gaussian(1, px, w, 2);
		sss_options sep = options(SSS_METHOD_SEPARABLE);
		sep.taps = 2 * px + 3; /* dense */
		sss_options ref = options(SSS_METHOD_REFERENCE);
		run a = apply(s, &m, 1, &sep), b = apply(s, &m, 1, &ref);
		double rms, worst = max_diff(a.light, b.light, (size_t)3 * w * h,
		                             &rms);
		char id[48];
		snprintf(id, sizeof id, "gauss-vs-ref-%d", px);
		CHECK(id, worst < 1e-4, "max |separable - reference| = %g", worst);
		printf("report: gaussian %2d px: separable vs reference max %.2e rms "
		       "%.2e\n", px, worst, rms);
		run_free(&a);
		run_free(&b);
	}
	synth_free(s);
}

/* Burley is not separable: report the separable method's error against the
 * reference on noise at three radii (and bound it loosely), and check the
 * marginal kernel's promise: on light that varies along x only, the two
 * agree closely away from the top and bottom borders. */
static void test_burley_vs_reference(void)
{
	int w = 64, h = 64;
	for (int px = 4; px <= 16; px *= 2) {
		synth *s = synth_new(w, h);
		synth_plane(s, 0, 0, w, h, 2.0f, 1.0f);
		synth_noise(s, 0, 1, 5);
		sss_material m = material_px(SSS_PROFILE_BURLEY, 1, px, w, 2);
		sss_options sep = options(SSS_METHOD_SEPARABLE);
		sss_options ref = options(SSS_METHOD_REFERENCE);
		run a = apply(s, &m, 1, &sep), b = apply(s, &m, 1, &ref);
		double rms, worst = max_diff(a.light, b.light, (size_t)3 * w * h,
		                             &rms);
		printf("report: burley %2d px noise: separable vs reference max %.2e rms "
		       "%.2e\n", px, worst, rms);
		char id[48];
		snprintf(id, sizeof id, "burley-noise-%d", px);
		CHECK(id, rms < 0.05, "rms %g", rms);
		run_free(&a);
		run_free(&b);

		/* A hard vertical shadow edge. */
		for (int y = 0; y < h; y++)
			for (int x = 0; x < w; x++)
				for (int c = 0; c < 3; c++)
					s->diff_dir[3 * (y * w + x) + c] = x < w / 2 ? 1.0f : 0.1f;
		a = apply(s, &m, 1, &sep);
		b = apply(s, &m, 1, &ref);
		double edge = 0;
		for (int y = px + 1; y < h - px - 1; y++)
			for (int i = 0; i < 3 * w; i++)
				edge = fmax(edge, fabs(a.light[3 * y * w + i] -
				                       b.light[3 * y * w + i]));
		printf("report: burley %2d px edge: separable vs reference max %.2e\n", px,
		       edge);
		snprintf(id, sizeof id, "burley-edge-%d", px);
		CHECK(id, edge < 3e-3, "edge error %g", edge);
		run_free(&a);
		run_free(&b);
		synth_free(s);
	}
}

/* Up to 64 px every pixel under the kernel is a tap, whatever the budget
 * (reading them all costs less than a thin budget's gathered pairs and
 * follows the profile at least as closely): budgets of 9, 33 and 129 taps
 * give the same image bit for bit on a tilted plane (depth changes under
 * the kernel) with noise. Beyond 64 px the budget thins the kernel. */
static void test_budget_below_dense_limit(void)
{
	int w = 128, h = 72; /* wider than every kernel: none is cut */
	static const int budgets[] = {9, 33, 129}, widths[] = {12, 40, 60, 96};
	for (int k = 0; k < 4; k++) {
		int px = widths[k];
		synth *s = synth_new(w, h);
		synth_plane(s, 0, 0, w, h, 2.0f, 1.0f);
		for (int y = 0; y < h; y++)
			for (int x = 0; x < w; x++)
				s->depth[y * w + x] = 2.0f + 0.004f * x + 0.002f * y;
		synth_noise(s, 0, 1, 31);
		run r[3];
		for (int b = 0; b < 3; b++) {
			sss_material m = material_px(SSS_PROFILE_BURLEY, 1, px, w, 2);
			m.taps = budgets[b];
			sss_options o = options(SSS_METHOD_SEPARABLE);
			r[b] = apply(s, &m, 1, &o);
		}
		size_t n = (size_t)3 * w * h;
		int same = !r[0].status && !r[1].status && !r[2].status &&
		           !memcmp(r[0].light, r[1].light, n * sizeof(float)) &&
		           !memcmp(r[0].light, r[2].light, n * sizeof(float));
		char id[48];
		snprintf(id, sizeof id, "dense-budget-%d", px);
		if (px <= 64)
			CHECK(id, same, "budgets 9, 33 and 129 differ at %d px", px);
		else
			CHECK(id, !same, "budgets 9, 33 and 129 agree at %d px: "
			      "nothing thins the kernel", px);
		for (int b = 0; b < 3; b++)
			run_free(&r[b]);
		synth_free(s);
	}
}

/* Standard deviation (pixels, along x) of the response to an impulse. */
static double spread_x(const float *light, int w, int y, int x0, int x1,
                       int cx)
{
	double m0 = 0, m2 = 0;
	for (int x = x0; x < x1; x++) {
		double v = light[3 * (y * w + x)];
		m0 += v;
		m2 += v * (x - cx) * (x - cx);
	}
	return sqrt(m2 / m0);
}

/* The same material on a plane at depth 2 and one at depth 4: the far one
 * blurs half as many pixels; and nothing crosses the depth step. */
static void test_depth(void)
{
	int w = 96, h = 48;
	for (size_t mt = 0; mt < NMETHODS; mt++) {
		synth *s = synth_new(w, h);
		synth_plane(s, 0, 0, 48, h, 2.0f, 1.0f);
		synth_plane(s, 48, 0, w, h, 4.0f, 1.0f);
		size_t near = (size_t)24 * w + 24, far = (size_t)24 * w + 72;
		s->diff_dir[3 * near] = s->diff_dir[3 * far] = 1.0f;
		sss_material m = single_gaussian(1, 20, w, 2);
		sss_options o = options(methods[mt]);
		o.taps = 65;
		if (methods[mt] == SSS_METHOD_DISK) {
			/* A point sampler sees a single lit pixel from few pixels:
			 * light a column instead (the same spread along x for a
			 * Gaussian) and give it every sample it can take. */
			for (int y = 0; y < h; y++)
				s->diff_dir[3 * (y * w + 24)] = s->diff_dir[3 * (y * w + 72)]
				                              = 1.0f;
			o.samples = 4096;
		}
		run r = apply(s, &m, 1, &o);
		double sn = spread_x(r.light, w, 24, 0, 48, 24);
		double sf = spread_x(r.light, w, 24, 48, w, 72);
		if (methods[mt] == SSS_METHOD_DISK) { /* average out the noise */
			sn = sf = 0;
			for (int y = 8; y < 40; y++) {
				sn += spread_x(r.light, w, y, 0, 48, 24) / 32;
				sf += spread_x(r.light, w, y, 48, w, 72) / 32;
			}
		}
		char id[48];
		snprintf(id, sizeof id, "depth-scale-%zu", mt);
		CHECK(id, fabs(sn / sf - 2.0) < 0.1, "near %g px, far %g px", sn, sf);
		/* A step edge in light right at the depth step stays sharp. */
		for (int y = 0; y < h; y++)
			for (int x = 0; x < w; x++)
				s->diff_dir[3 * (y * w + x)] = x < 48 ? 1.0f : 0.0f;
		run_free(&r);
		r = apply(s, &m, 1, &o);
		int clean = 1;
		for (int y = 0; y < h; y++)
			for (int x = 40; x < 56; x++)
				clean &= r.light[3 * (y * w + x)] == (x < 48 ? 1.0f : 0.0f);
		snprintf(id, sizeof id, "depth-edge-%zu", mt);
		CHECK(id, clean, "light crossed a depth step");
		run_free(&r);
		synth_free(s);
	}
}

/* Two materials side by side keep their own kernels; index 0 is left
 * alone; no light crosses from one material to the other. */
static void test_materials(void)
{
	int w = 80, h = 40;
	for (size_t mt = 0; mt < NMETHODS; mt++) {
		synth *s = synth_new(w, h);
		synth_plane(s, 0, 0, 40, h, 2.0f, 1.0f);
		synth_plane(s, 40, 0, 70, h, 2.0f, 2.0f);
		synth_plane(s, 70, 0, w, h, 2.0f, 0.0f); /* a non-scattering strip */
		synth_noise(s, 0, 1, 9);
		sss_material m[2] = {material_px(SSS_PROFILE_GAUSSIANS, 1, 12, w, 2),
		                     material_px(SSS_PROFILE_BURLEY, 2, 6, w, 2)};
		sss_options o = options(methods[mt]);
		run both = apply(s, m, 2, &o);
		/* Each material alone on the same image. */
		run one = apply(s, &m[0], 1, &o), two = apply(s, &m[1], 1, &o);
		int own = 1, untouched = 1;
		for (int y = 0; y < h; y++)
			for (int x = 0; x < w; x++)
				for (int c = 0; c < 3; c++) {
					size_t i = 3 * ((size_t)y * w + x) + c;
					float want = x < 40 ? one.light[i]
					             : x < 70 ? two.light[i]
					             : s->diff_dir[i];
					own &= both.light[i] == want;
					if (x >= 70)
						untouched &= both.light[i] == s->diff_dir[i];
				}
		char id[48];
		snprintf(id, sizeof id, "materials-own-%zu", mt);
		CHECK(id, own, "a material's result depends on its neighbour");
		snprintf(id, sizeof id, "materials-index0-%zu", mt);
		CHECK(id, untouched, "index 0 pixels changed");
		/* Material 1's pixels next to material 2 see only material 1:
		 * make material 2 very bright and check nothing leaks. */
		for (int y = 0; y < h; y++)
			for (int x = 40; x < 70; x++)
				s->diff_dir[3 * (y * w + x)] = 1000.0f;
		run lit = apply(s, m, 2, &o);
		int sealed = 1;
		for (int y = 0; y < h; y++)
			for (int x = 0; x < 40; x++)
				sealed &= lit.light[3 * (y * w + x)] ==
				          both.light[3 * (y * w + x)];
		snprintf(id, sizeof id, "materials-no-bleed-%zu", mt);
		CHECK(id, sealed, "light leaked between materials");
		run_free(&both);
		run_free(&one);
		run_free(&two);
		run_free(&lit);
		synth_free(s);
	}
}

/* Identical output for any thread count. */
static void test_threads(void)
{
	int w = 50, h = 37;
	synth *s = synth_new(w, h);
	synth_plane(s, 0, 0, w, h, 2.0f, 1.0f);
	synth_plane(s, 30, 10, w, 30, 2.5f, 2.0f);
	synth_noise(s, 0, 1, 21);
	sss_material m[2] = {material_px(SSS_PROFILE_BURLEY, 1, 40, w, 2),
	                     material_px(SSS_PROFILE_JIMENEZ, 2, 7, w, 2)};
	for (size_t mt = 0; mt < NMETHODS; mt++) {
		sss_options o = options(methods[mt]);
		o.num_threads = 1;
		run one = apply(s, m, 2, &o);
		int threads[] = {2, 3, 7, 0, 64};
		for (size_t t = 0; t < 5; t++) {
			o.num_threads = threads[t];
			run r = apply(s, m, 2, &o);
			char id[48];
			snprintf(id, sizeof id, "threads-%zu.%d", mt, threads[t]);
			CHECK(id, memcmp(r.light, one.light, 3 * sizeof(float) * w * h)
			      == 0 && memcmp(r.combined, one.combined,
			                     4 * sizeof(float) * w * h) == 0,
			      "differs from one thread");
			run_free(&r);
		}
		run_free(&one);
	}
	synth_free(s);
}

/* The composite is Blender's: with nothing scattering it equals the sum of
 * the passes to float precision; with scattering only the diffuse term
 * changes; alpha comes from Combined. */
static void test_composite(void)
{
	int w = 20, h = 16;
	synth *s = synth_new(w, h);
	synth_plane(s, 0, 0, w, h, 2.0f, 1.0f);
	uint32_t st = 99;
	float *all[] = {s->diff_dir, s->diff_ind, s->diff_col, s->gloss_dir,
	                s->gloss_ind, s->gloss_col, s->trans_dir, s->trans_ind,
	                s->trans_col, s->emit, s->env};
	for (size_t p = 0; p < sizeof all / sizeof *all; p++)
		for (size_t i = 0; i < (size_t)3 * w * h; i++)
			all[p][i] = synth_rand(&st) * 2.0f;
	for (size_t i = 0; i < (size_t)w * h; i++)
		s->combined[4 * i + 3] = synth_rand(&st);
	sss_options o = options(SSS_METHOD_SEPARABLE);
	run off = apply(s, NULL, 0, &o);
	double worst = 0, alpha = 0;
	for (size_t i = 0; i < (size_t)w * h; i++) {
		for (int c = 0; c < 3; c++) {
			size_t j = 3 * i + c;
			double want = ((double)s->diff_dir[j] + s->diff_ind[j]) *
			              s->diff_col[j] +
			              ((double)s->gloss_dir[j] + s->gloss_ind[j]) *
			              s->gloss_col[j] +
			              ((double)s->trans_dir[j] + s->trans_ind[j]) *
			              s->trans_col[j] + s->emit[j] + s->env[j];
			worst = fmax(worst, fabs(off.combined[4 * i + c] - want) / want);
		}
		alpha = fmax(alpha, fabs(off.combined[4 * i + 3] -
		                         s->combined[4 * i + 3]));
	}
	CHECK("composite-off", worst < 1e-6, "relative error %g", worst);
	CHECK("composite-alpha", alpha == 0, "alpha error %g", alpha);

	sss_material m = material_px(SSS_PROFILE_BURLEY, 1, 6, w, 2);
	run on = apply(s, &m, 1, &o);
	double rest = 0;
	for (size_t i = 0; i < (size_t)w * h; i++)
		for (int c = 0; c < 3; c++) {
			size_t j = 3 * i + c;
			double non_diffuse = off.combined[4 * i + c] -
			                     (double)off.light[j] * s->diff_col[j];
			double got = on.combined[4 * i + c] -
			             (double)on.light[j] * s->diff_col[j];
			rest = fmax(rest, fabs(got - non_diffuse));
		}
	CHECK("composite-on", rest < 1e-5, "non-diffuse terms moved by %g", rest);

	/* EEVEE-style input: no DiffInd, GlossInd, Trans, Env, Combined. */
	sss_passes p = synth_passes(s);
	p.diff_ind.data = p.gloss_ind.data = NULL;
	p.trans_dir.data = p.trans_ind.data = p.trans_col.data = NULL;
	p.env.data = p.combined.data = NULL;
	sss_camera cam;
	sss_camera_default(&cam);
	float *out = calloc((size_t)4 * w * h, sizeof(float));
	sss_image oc = {out, w, h, 4, 0};
	CHECK_STATUS("composite-eevee", SSS_OK,
	             sss_apply(&p, &cam, NULL, 0, &o, &oc, NULL, NULL, 0));
	double e = 0;
	for (size_t i = 0; i < (size_t)w * h; i++)
		for (int c = 0; c < 3; c++) {
			size_t j = 3 * i + c;
			double want = (double)s->diff_dir[j] * s->diff_col[j] +
			              (double)s->gloss_dir[j] * s->gloss_col[j] +
			              s->emit[j];
			e = fmax(e, fabs(out[4 * i + c] - want) / want);
		}
	CHECK("composite-eevee", e < 1e-6 && out[3] == 1.0f, "error %g", e);
	free(out);
	run_free(&off);
	run_free(&on);
	synth_free(s);
}

/* Pre-and-post texturing is blur(L sqrt(c)) sqrt(c): the same as scattering
 * L sqrt(c) with post texturing and multiplying by sqrt(c). */
static void test_texturing(void)
{
	int w = 32, h = 24;
	synth *s = synth_new(w, h);
	synth_plane(s, 0, 0, w, h, 2.0f, 1.0f);
	synth_noise(s, 0.2f, 1, 4);
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++)
			for (int c = 0; c < 3; c++)
				s->diff_col[3 * (y * w + x) + c] =
					((x / 4 + y / 4) % 2) ? 0.9f : 0.1f;
	sss_material m = material_px(SSS_PROFILE_BURLEY, 1, 8, w, 2);
	m.texturing = SSS_TEXTURING_PRE_AND_POST;
	sss_options o = options(SSS_METHOD_SEPARABLE);
	run pre = apply(s, &m, 1, &o);
	synth *t = synth_new(w, h);
	synth_plane(t, 0, 0, w, h, 2.0f, 1.0f);
	for (size_t i = 0; i < (size_t)3 * w * h; i++)
		t->diff_dir[i] = s->diff_dir[i] * sqrtf(s->diff_col[i]);
	m.texturing = SSS_TEXTURING_POST;
	run post = apply(t, &m, 1, &o);
	double worst = 0;
	for (size_t i = 0; i < (size_t)3 * w * h; i++) {
		double a = (double)pre.light[i] * s->diff_col[i];
		double b = (double)post.light[i] * sqrtf(s->diff_col[i]);
		worst = fmax(worst, fabs(a - b));
	}
	CHECK("texturing-pre-post", worst < 1e-5, "difference %g", worst);
	run_free(&pre);
	run_free(&post);
	synth_free(s);
	synth_free(t);
}

/* Giving the Position pass that the camera implies changes nothing. */
static void test_position_pass(void)
{
	int w = 40, h = 30;
	synth *s = synth_new(w, h);
	s->position = malloc((size_t)3 * w * h * sizeof(float));
	double fx = w * 50.0 / 36.0;
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			size_t i = (size_t)y * w + x;
			float z = 2.0f + 0.03f * x + 0.02f * y;
			s->depth[i] = z;
			s->index[i] = 1;
			s->position[3 * i] = (float)((x + 0.5 - w / 2.0) / fx * z);
			s->position[3 * i + 1] = (float)((h / 2.0 - (y + 0.5)) / fx * z);
			s->position[3 * i + 2] = z;
		}
	synth_noise(s, 0, 1, 13);
	sss_material m = material_px(SSS_PROFILE_BURLEY, 1, 10, w, 2);
	for (size_t mt = 0; mt < NMETHODS; mt++) {
		sss_options o = options(methods[mt]);
		run with = apply(s, &m, 1, &o);
		float *keep = s->position;
		s->position = NULL;
		run without = apply(s, &m, 1, &o);
		s->position = keep;
		double worst = max_diff(with.light, without.light,
		                        (size_t)3 * w * h, NULL);
		char id[48];
		snprintf(id, sizeof id, "position-%zu", mt);
		CHECK(id, worst < 1e-5, "difference %g", worst);
		run_free(&with);
		run_free(&without);
	}
	synth_free(s);
}

/* A curved surface: a sphere filling most of the frame, Burley and one
 * Gaussian on noise. The separable method's distances are true 3-D ones,
 * so it must stay close to the reference where the surface turns away. */
static void test_sphere_vs_reference(void)
{
	int w = 64, h = 64;
	for (int kind = 0; kind < 2; kind++) {
		synth *s = synth_new(w, h);
		synth_sphere(s, 2.0f, 0.4f, 1.0f);
		synth_noise(s, 0, 1, 17);
		sss_material m = kind ? single_gaussian(1, 10, w, 1.6)
		                      : material_px(SSS_PROFILE_BURLEY, 1, 10, w, 1.6);
		sss_options sep = options(SSS_METHOD_SEPARABLE);
		sss_options ref = options(SSS_METHOD_REFERENCE);
		run a = apply(s, &m, 1, &sep), b = apply(s, &m, 1, &ref);
		double rms, worst = max_diff(a.light, b.light, (size_t)3 * w * h,
		                             &rms);
		printf("report: %s sphere noise: separable vs reference max %.2e "
		       "rms %.2e\n", kind ? "gaussian" : "burley", worst, rms);
		char id[48];
		snprintf(id, sizeof id, "sphere-%s", kind ? "gaussian" : "burley");
		CHECK(id, rms < (kind ? 0.02 : 0.03), "rms %g", rms);
		run_free(&a);
		run_free(&b);

		/* A hard shadow edge across the sphere: light that varies in one
		 * direction, which two 1-D passes follow on a flat plane. */
		for (int y = 0; y < h; y++)
			for (int x = 0; x < w; x++)
				for (int c = 0; c < 3; c++)
					s->diff_dir[3 * (y * w + x) + c] = x < w / 2 ? 1.0f : 0.1f;
		a = apply(s, &m, 1, &sep);
		b = apply(s, &m, 1, &ref);
		worst = max_diff(a.light, b.light, (size_t)3 * w * h, &rms);
		printf("report: %s sphere edge: separable vs reference max %.2e "
		       "rms %.2e\n", kind ? "gaussian" : "burley", worst, rms);
		snprintf(id, sizeof id, "sphere-edge-%s", kind ? "gaussian" : "burley");
		CHECK(id, rms < 0.01, "rms %g", rms);
		run_free(&a);
		run_free(&b);
		synth_free(s);
	}
}

/* The vector inner loop gives the scalar loop's bits, in depth and in
 * position mode, dense and sparse layouts, partial vectors at the edges. */
static void test_simd_matches_scalar(void)
{
	/* Without AVX2 both runs take the scalar loop: nothing is compared. */
	if (!sss__blur1d_avx2_supported()) {
		printf("skipped: simd-bits (this CPU has no AVX2: the vector loop "
		       "is not run)\n");
		return;
	}
	int w = 61, h = 47;
	synth *s = synth_new(w, h);
	synth_sphere(s, 2.0f, 0.5f, 1.0f);
	synth_plane(s, 0, 0, 12, h, 1.5f, 2.0f);
	synth_noise(s, 0, 1, 29);
	s->position = malloc((size_t)3 * w * h * sizeof(float));
	double fx = w * 50.0 / 36.0;
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			size_t i = (size_t)y * w + x;
			float z = s->depth[i];
			s->position[3 * i] = (float)((x + 0.5 - w / 2.0) / fx * z);
			s->position[3 * i + 1] = (float)((h / 2.0 - (y + 0.5)) / fx * z);
			s->position[3 * i + 2] = z;
		}
	sss_material m[2] = {material_px(SSS_PROFILE_BURLEY, 1, 9, w, 1.6),
	                     material_px(SSS_PROFILE_GAUSSIANS, 2, 30, w, 1.5)};
	for (int pos = 0; pos < 2; pos++) {
		float *keep = s->position;
		if (!pos)
			s->position = NULL;
		for (int taps = 9; taps <= 33; taps += 24) {
			sss_options o = options(SSS_METHOD_SEPARABLE);
			o.taps = taps;
			unsetenv("SSS_SIMD");
			run fast = apply(s, m, 2, &o);
			setenv("SSS_SIMD", "scalar", 1);
			run plain = apply(s, m, 2, &o);
			unsetenv("SSS_SIMD");
			char id[48];
			snprintf(id, sizeof id, "simd-bits-%s-%d", pos ? "position" : "depth",
			         taps);
			CHECK(id, fast.status == SSS_OK && memcmp(fast.light, plain.light,
			      3 * sizeof(float) * w * h) == 0, "vector and scalar differ");
			run_free(&fast);
			run_free(&plain);
		}
		s->position = keep;
	}
	synth_free(s);
}

/* An orthographic camera one unit wide and a Burley material (pass index
 * 1) whose support spans px pixels of a w-pixel-wide image under it. */
static void ortho_burley(int w, double px, sss_camera *cam, sss_material *m)
{
	sss_camera_default(cam);
	cam->type = SSS_CAMERA_ORTHOGRAPHIC;
	cam->ortho_scale = 1.0;
	sss_material_default(m, SSS_PROFILE_BURLEY);
	m->pass_index = 1;
	double support;
	sss_material_support(m, &support);
	double scale = px / (support * w / cam->ortho_scale);
	for (int c = 0; c < 3; c++)
		m->radius[c] *= (float)scale;
}

/* An orthographic camera: a sample's in-plane distance does not depend on
 * depth. A plane tilted away from the camera, Burley on noise and on a
 * shadow edge: separable close to the reference, and the vector loop gives
 * the scalar loop's bits. */
static void test_orthographic(void)
{
	int w = 56, h = 40;
	synth *s = synth_new(w, h);
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			s->depth[(size_t)y * w + x] = 2.0f + 0.02f * x;
			s->index[(size_t)y * w + x] = 1.0f;
		}
	synth_noise(s, 0, 1, 41);
	sss_camera cam;
	sss_material m;
	ortho_burley(w, 8.0, &cam, &m);
	sss_options sep = options(SSS_METHOD_SEPARABLE);
	sss_options ref = options(SSS_METHOD_REFERENCE);
	run a = apply_cam(s, &m, 1, &sep, &cam), b = apply_cam(s, &m, 1, &ref, &cam);
	double rms, worst = max_diff(a.light, b.light, (size_t)3 * w * h, &rms);
	printf("report: burley orthographic tilted noise: separable vs reference "
	       "max %.2e rms %.2e\n", worst, rms);
	CHECK("ortho-noise", a.status == SSS_OK && rms < 0.03, "rms %g", rms);
	setenv("SSS_SIMD", "scalar", 1);
	run c = apply_cam(s, &m, 1, &sep, &cam);
	unsetenv("SSS_SIMD");
	if (sss__blur1d_avx2_supported())
		CHECK("ortho-simd-bits", memcmp(a.light, c.light,
		      3 * sizeof(float) * w * h) == 0, "vector and scalar differ");
	else
		printf("skipped: ortho-simd-bits (this CPU has no AVX2)\n");
	run_free(&a);
	run_free(&b);
	run_free(&c);
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++)
			for (int k = 0; k < 3; k++)
				s->diff_dir[3 * (y * w + x) + k] = y < h / 2 ? 1.0f : 0.1f;
	a = apply_cam(s, &m, 1, &sep, &cam);
	b = apply_cam(s, &m, 1, &ref, &cam);
	worst = max_diff(a.light, b.light, (size_t)3 * w * h, &rms);
	printf("report: burley orthographic tilted edge: separable vs reference "
	       "max %.2e rms %.2e\n", worst, rms);
	CHECK("ortho-edge", rms < 0.01, "rms %g", rms);
	run_free(&a);
	run_free(&b);
	synth_free(s);
}

/* A kernel cut by max_support_px takes its weights from a table over the
 * depths of the cut pixels (sss_separable.c, cap_build); where those
 * depths span too much for a table, every pixel makes its own. The two
 * agree: the same slanted object, once alone (tabulated) and once with a
 * far copy of its material out of reach on screen (depths 4000 times
 * apart: made per pixel). */
static void test_cut_kernel_table(void)
{
	int w = 160, h = 40;
	synth *a = synth_new(w, h), *b = synth_new(w, h);
	for (int y = 0; y < h; y++)
		for (int x = 0; x < 60; x++) {
			float z = 1.0f + 0.005f * (float)x;
			synth_plane(a, x, y, x + 1, y + 1, z, 1.0f);
			synth_plane(b, x, y, x + 1, y + 1, z, 1.0f);
		}
	synth_plane(b, 120, 0, w, h, 4000.0f, 1.0f);
	synth_noise(a, 0, 1, 17);
	memcpy(b->diff_dir, a->diff_dir, (size_t)3 * w * h * sizeof(float));
	/* Wide enough to be cut at the far copy too. */
	sss_material m = material_px(SSS_PROFILE_BURLEY, 1, 40000.0, w, 1.0);
	sss_options o = options(SSS_METHOD_SEPARABLE);
	o.max_support_px = 8;
	run ra = apply(a, &m, 1, &o), rb = apply(b, &m, 1, &o);
	double worst = 0.0, moved = 0.0;
	for (int y = 0; y < h; y++)
		for (int x = 0; x < 60; x++)
			for (int c = 0; c < 3; c++) {
				size_t i = 3 * ((size_t)y * w + x) + c;
				worst = fmax(worst, fabs((double)ra.light[i] - rb.light[i]) /
				                    fmax(fabs((double)rb.light[i]), 1e-3));
				moved = fmax(moved, fabs((double)ra.light[i] -
				                         a->diff_dir[i]));
			}
	CHECK("cut-table-scatters", ra.status == SSS_OK && moved > 0.05,
	      "the cut kernel left the light as it was (%g)", moved);
	CHECK("cut-table-vs-per-pixel", rb.status == SSS_OK && worst < 5e-6,
	      "tabulated vs per-pixel weights: %g relative", worst);
	printf("report: cut kernel, table vs per-pixel weights: %.2e relative\n",
	       worst);
	run_free(&ra);
	run_free(&rb);
	synth_free(a);
	synth_free(b);
}

/* Kernels wide enough for far taps of four pixels and more sum those at
 * every fourth pixel of a row and interpolate between (sss_separable.c).
 * One row on a plane facing an orthographic camera, light a smooth wave
 * with a hard shadow edge, a 150 px Burley kernel: the result stays close
 * to the exact convolution with the profile's mass over every pixel
 * (sss_kernel_1d with a tap for each pixel), at the edge too: 5.2e-2
 * relative at worst, where the same sparse taps summed at every pixel are
 * 6.3e-2 off (the 33 taps' own sampling: each far tap steps as it crosses
 * the edge, and the interpolation smooths those steps). The vector loop
 * gives the scalar loop's bits there. */
static float far_light(int x)
{
	return (0.5f + 0.4f * sinf(6.2831853f * (float)x / 53.0f)) *
	       (x < 230 ? 1.0f : 0.3f);
}

static void test_far_interpolation(void)
{
	int w = 460, h = 1, reach = 160;
	sss_camera cam;
	sss_material m;
	ortho_burley(w, 150.0, &cam, &m);
	synth *s = synth_new(w, h);
	synth_plane(s, 0, 0, w, h, 2.0f, 1.0f);
	for (int x = 0; x < w; x++)
		for (int c = 0; c < 3; c++)
			s->diff_dir[3 * x + c] = far_light(x);
	sss_options o = options(SSS_METHOD_SEPARABLE);
	run r = apply_cam(s, &m, 1, &o, &cam);
	setenv("SSS_SIMD", "scalar", 1);
	run plain = apply_cam(s, &m, 1, &o, &cam);
	unsetenv("SSS_SIMD");
	if (sss__blur1d_avx2_supported())
		CHECK("far-simd-bits", r.status == SSS_OK &&
		      memcmp(r.light, plain.light, 3 * sizeof(float) * w * h) == 0,
		      "vector and scalar differ");
	/* The exact convolution: a tap on every pixel. */
	int32_t count = 4097;
	float *off = malloc(count * sizeof *off);
	float *wt = malloc(3 * (size_t)count * sizeof *wt);
	sss_result kr = sss_kernel_1d(&m, w / cam.ortho_scale, 4097, off, wt,
	                              &count);
	double worst = 0.0, moved = 0.0;
	for (int x = reach; kr == SSS_OK && x < w - reach; x++)
		for (int c = 0; c < 3; c++) {
			double sum = 0.0, mass = 0.0;
			for (int32_t t = 0; t < count; t++) {
				int j = x + (int)lrintf(off[t]);
				if (j < 0 || j >= w)
					continue;
				sum += wt[3 * t + c] * far_light(j);
				mass += wt[3 * t + c];
			}
			double exact = sum / mass, got = r.light[3 * x + c];
			worst = fmax(worst, fabs(got - exact) / exact);
			moved = fmax(moved, fabs(got - far_light(x)));
		}
	printf("report: far taps interpolated: 150 px Burley on a wave with a "
	       "shadow edge, against the exact convolution: %.2e relative\n",
	       worst);
	CHECK("far-kernel", kr == SSS_OK && count > 2 * 149, "kernel: %s, %d taps",
	      sss_status_name(kr), (int)count);
	CHECK("far-scatters", r.status == SSS_OK && moved > 0.05,
	      "the wide kernel left the light as it was (%g)", moved);
	CHECK("far-interpolation", worst < 0.058,
	      "%g relative from the exact convolution", worst);
	free(off);
	free(wt);
	run_free(&r);
	run_free(&plain);
	synth_free(s);
}

int main(void)
{
	test_constant();
	test_identity();
	test_impulse_symmetry();
	test_gaussian_vs_reference();
	test_burley_vs_reference();
	test_budget_below_dense_limit();
	test_depth();
	test_materials();
	test_threads();
	test_composite();
	test_texturing();
	test_position_pass();
	test_sphere_vs_reference();
	test_simd_matches_scalar();
	test_orthographic();
	test_cut_kernel_table();
	test_far_interpolation();
	return tu_finish("test_blur");
}
