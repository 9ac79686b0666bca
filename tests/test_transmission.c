/* test_transmission.c - back-lit transmission: a thin slab lit from behind
 * through sss_apply, every model's transmittance, the extremes of the
 * thickness pass, energy, validation, the scene JSON and the back-light
 * layer of an EXR through sss_process_exr. */
#include "test_util.h"
#include "transmission4_rw_measured.h"
#include "transmission4_skin_measured.h"
#include "thin4_skin_measured.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define W 32
#define H 16

/* A fronto-parallel slab filling the image, 1 m from the camera, dark in
 * front (DiffDir 0), lit from behind with back light B, thickness t. */
typedef struct slab {
	float dd[W * H * 3], col[W * H * 3], depth[W * H], index[W * H];
	float back[W * H * 3], thick[W * H], facing[W * H];
	float out[W * H * 3];
	sss_passes p;
} slab;

static void slab_make(slab *s, float b, float t)
{
	memset(s, 0, sizeof *s);
	for (int i = 0; i < W * H; i++) {
		for (int c = 0; c < 3; c++) {
			s->col[3 * i + c] = 0.8f;
			s->back[3 * i + c] = b;
		}
		s->depth[i] = 1.0f;
		s->index[i] = 1.0f;
		s->thick[i] = t;
		s->facing[i] = 1.0f;
	}
	s->p.diff_dir = (sss_image){s->dd, W, H, 3, 0};
	s->p.diff_col = (sss_image){s->col, W, H, 3, 0};
	s->p.depth = (sss_image){s->depth, W, H, 1, 0};
	s->p.index_ma = (sss_image){s->index, W, H, 1, 0};
	s->p.back_dir = (sss_image){s->back, W, H, 3, 0};
	s->p.thickness = (sss_image){s->thick, W, H, 1, 0};
}

static sss_material skin(int32_t model, float radius)
{
	sss_material m;
	sss_material_default(&m, SSS_PROFILE_BURLEY);
	m.pass_index = 1;
	m.radius[0] = radius;
	m.radius[1] = radius * 0.5f;
	m.radius[2] = radius * 0.25f;
	m.transmission = model;
	return m;
}

static sss_result run(slab *s, const sss_material *m, float radius_scale,
                      char *err, size_t errlen)
{
	sss_camera cam;
	sss_camera_default(&cam);
	sss_options opt;
	sss_options_default(&opt);
	opt.radius_scale = radius_scale;
	opt.num_threads = 1;
	sss_image out = {s->out, W, H, 3, 0};
	return sss_apply(&s->p, &cam, m, 1, &opt, NULL, &out, err, errlen);
}

/* The front's light at the centre of the slab, channel c. */
static float front(slab *s, int c)
{
	return s->out[3 * ((H / 2) * W + W / 2) + c];
}

static int all_finite(const float *v, int n)
{
	for (int i = 0; i < n; i++)
		if (!isfinite(v[i]))
			return 0;
	return 1;
}

static slab S; /* big: static, not on the stack */

static void test_slab(void)
{
	char err[256];
	const float b = 2.0f;
	/* Off: the front stays dark, and so it does with no back light. */
	slab_make(&S, b, 0.001f);
	sss_material m = skin(SSS_TRANSMISSION_OFF, 0.01f);
	CHECK_STATUS("slab.off", SSS_OK, run(&S, &m, 1, err, sizeof err));
	CHECK("slab.off.dark", front(&S, 0) == 0.0f && front(&S, 2) == 0.0f,
	      "%g", (double)front(&S, 0));
	m = skin(SSS_TRANSMISSION_BURLEY, 0.01f);
	S.p.back_dir.data = NULL;
	S.p.thickness.data = NULL;
	CHECK_STATUS("slab.nolight", SSS_OK, run(&S, &m, 1, err, sizeof err));
	CHECK("slab.nolight.dark", front(&S, 0) == 0.0f, "%g",
	      (double)front(&S, 0));

	/* On: the front brightens as the slab thins, and as the radius
	 * grows; it matches T(t) B (uniform light stays uniform). */
	static const int32_t models[] = {
		SSS_TRANSMISSION_BURLEY, SSS_TRANSMISSION_JIMENEZ,
		SSS_TRANSMISSION_BEER_LAMBERT, SSS_TRANSMISSION_FAST};
	static const char *names[] = {"burley", "jimenez", "beer", "fast"};
	for (int k = 0; k < 4; k++) {
		float prev = -1.0f;
		int mono = 1, match = 1;
		char id[64];
		for (int i = 12; i >= 0; i--) {
			float t = i == 0 ? 0.0f : 0.0005f * (float)(1 << (i - 1)) / 8;
			slab_make(&S, b, t);
			m = skin(models[k], 0.01f);
			m.transmission_distance = 0.005f;
			m.transmission_color[0] = 0.9f;
			m.transmission_color[1] = 0.5f;
			m.transmission_color[2] = 0.3f;
			if (run(&S, &m, 1, err, sizeof err) != SSS_OK) {
				mono = 0;
				break;
			}
			double T[3];
			sss_transmittance(&m, t, 1.0, T);
			if (fabs(front(&S, 0) - T[0] * b) > 1e-4 * b + 1e-6)
				match = 0;
			if (front(&S, 0) < prev - 1e-7f)
				mono = 0;
			prev = front(&S, 0);
		}
		snprintf(id, sizeof id, "slab.%s.thinner-brighter", names[k]);
		CHECK(id, mono, "not monotonic (%s)", err);
		snprintf(id, sizeof id, "slab.%s.equals-T-B", names[k]);
		CHECK(id, match, "front light is not T(t) x B");
		snprintf(id, sizeof id, "slab.%s.lit", names[k]);
		CHECK(id, prev > 0.1f * b, "T(0) B = %g", (double)prev);
	}
	/* Radius grows: brighter, for the profile-based models. */
	for (int k = 0; k < 2; k++) {
		float prev = -1.0f;
		int mono = 1;
		for (int i = 0; i < 10; i++) {
			slab_make(&S, b, 0.004f);
			m = skin(models[k], 0.002f * (float)(i + 1));
			m.jimenez_width = 0.002f * (float)(i + 1);
			run(&S, &m, 1, err, sizeof err);
			if (front(&S, 0) < prev - 1e-7f)
				mono = 0;
			prev = front(&S, 0);
		}
		CHECK(k ? "slab.jimenez.wider-brighter" : "slab.burley.wider-"
		      "brighter", mono && prev > 0.0f, "last %g", (double)prev);
	}
	/* The transmitted light is not blurred (it spreads over the part's
	 * thickness, not the radius): a sharp patch of back light stays
	 * where it crossed, T(0) x B there, while the same light arriving in
	 * front spreads over the radius. */
	slab_make(&S, 0.0f, 0.0f);
	for (int y = 6; y < 10; y++)
		for (int x = 14; x < 18; x++)
			for (int c = 0; c < 3; c++)
				S.back[3 * (y * W + x) + c] = 1.0f;
	m = skin(SSS_TRANSMISSION_BURLEY, 1.0f); /* d = 3.5 px */
	run(&S, &m, 1, err, sizeof err);
	double T0[3];
	sss_transmittance(&m, 0.0, 1.0, T0);
	double outside = 0.0, worst = 0.0;
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++)
			for (int c = 0; c < 3; c++) {
				double v = S.out[3 * (y * W + x) + c];
				double want = (double)S.back[3 * (y * W + x) + c] * T0[c];
				worst = fmax(worst, fabs(v - want) / T0[c]);
				if (x < 14 || x > 17 || y < 6 || y > 9)
					outside += fabs(v);
			}
	CHECK("slab.not-blurred", outside == 0.0 && worst < 1e-6,
	      "outside %g, worst %g of T(0) B", outside, worst);
	for (int i = 0; i < W * H * 3; i++)
		S.dd[i] = (float)((double)S.back[i] * T0[i % 3]);
	m.transmission = SSS_TRANSMISSION_OFF;
	run(&S, &m, 1, err, sizeof err);
	double total = 0.0;
	outside = 0.0;
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) {
			float v = S.out[3 * (y * W + x)];
			total += v;
			if (x < 14 || x > 17 || y < 6 || y > 9)
				outside += v;
		}
	CHECK("slab.front-light-blurred", outside > 0.05 * total,
	      "outside %g of %g", outside, total);
}

static void test_models(void)
{
	double T[3], T2[3];
	/* Burley: the 1-D diffusion slab (sss_transmission.c, slab_make),
	 * evaluated here in its sinh form from the medium with the blur's own
	 * d: mean free path l = d s(A), Cycles' alpha(A) (g = 0). */
	sss_material m = skin(SSS_TRANSMISSION_BURLEY, 0.01f);
	double d[3];
	sss_burley_d(&m, d);
	{
		double A = m.albedo[0], bl = pow(A, 0.25);
		double al = (1 - bl) * 1.8260523782 *
		            pow(atan(5.112467903288 * A), 1.09686102424) +
		            bl * 0.496310210422 *
		            pow(atan(4.2350090365 * A), 2.40602999408);
		double l = d[0] * (1.9 - A + 3.5 * (A - 0.8) * (A - 0.8));
		double D = (2 - al) * l / 3, zb = 2 * D, a = 2 * l / 3 + zb;
		double str = sqrt((1 - al) / l / D);
		for (int i = 0; i < 40; i++) {
			double t = 0.0005 * i;
			double L = fmax(t + 2 * zb, 2 * a);
			double want = sinh(str * a) / sinh(str * L) * exp(str * a);
			sss_transmittance(&m, t, 1.0, T);
			CHECK("model.burley.slab-form", fabs(T[0] - want) < 1e-9 *
			      fmax(want, 1e-300) + 1e-300, "t %g: %.12g vs %.12g", t,
			      T[0], want);
		}
		/* A thin part lets out about half of what enters at the back. */
		sss_transmittance(&m, 0.0, 1.0, T);
		double T0 = 1.0 / (1.0 + exp(-2 * str * a));
		CHECK("model.burley.T0", fabs(T[0] - T0) < 1e-12 && T[0] > 0.5 &&
		      T[0] < 0.7 && T[1] == T[0] && T[2] == T[0], "%g %g %g",
		      T[0], T[1], T[2]);
		m.transmission_strength = 0.5f;
		m.transmission_color[1] = 0.4f;
		sss_transmittance(&m, 0.0, 1.0, T);
		CHECK("model.burley.T0-tinted", fabs(T[0] - 0.5 * T0) < 1e-12 &&
		      fabs(T[1] - 0.2 * T0) < 1e-7, "%g %g", T[0], T[1]);
	}
	/* Against Cycles 3.4's random walk (measure_transmission.py
	 * --slab-sweep: build_scene.py's skin slab lit only from behind, 64x64,
	 * 256 spp, the middle of the slab): the effective transmittance
	 * (front - blur alone) / (back light x DiffCol) per channel, at the
	 * measured thickness, for Subsurface 0.02 and 0.05 (radius (1, 0.5,
	 * 0.25) x Subsurface, albedo mix(Base, Subsurface Color)). */
	{
		static const struct {
			double sub, t, rw[3];
		} meas[] = {
			{0.02, 0.0150, {0.0844, 0.0640, 0.0075}},
			{0.05, 0.0150, {0.2691, 0.3988, 0.1991}},
			{0.05, 0.0400, {0.0805, 0.0576, 0.0058}},
			{0.02, 0.0050, {0.3115, 0.4797, 0.2807}},
		};
		double worst = 0.0;
		for (size_t i = 0; i < sizeof meas / sizeof *meas; i++) {
			sss_material rw;
			sss_material_default(&rw, SSS_PROFILE_BURLEY);
			rw.transmission = SSS_TRANSMISSION_BURLEY;
			rw.burley_mapping = SSS_BURLEY_CYCLES_RANDOM_WALK;
			static const float base[3] = {0.8f, 0.55f, 0.45f};
			static const float sc[3] = {0.85f, 0.45f, 0.35f};
			static const float rad[3] = {1.0f, 0.5f, 0.25f};
			for (int c = 0; c < 3; c++) {
				float sub = (float)meas[i].sub;
				rw.albedo[c] = base[c] * (1 - sub) + sc[c] * sub;
				rw.radius[c] = rad[c] * sub;
			}
			sss_transmittance(&rw, meas[i].t, 1.0, T);
			for (int c = 0; c < 3; c++) {
				double e = fabs(log(T[c] / meas[i].rw[c]));
				worst = fmax(worst, e);
			}
		}
		/* Within 30 % everywhere (the thin 0.5 cm slab is the worst: its
		 * unscattered light is beyond diffusion); 3-6x low before. */
		CHECK("model.burley.random-walk", worst < log(1.3), "worst ratio "
		      "%g", exp(worst));
	}
	/* Every mapping and albedo: finite, in [0, 1], non-increasing in t,
	 * gone when thick. */
	{
		int bad = 0;
		static const float albedos[] = {0.0f, 1e-4f, 0.05f, 0.5f, 0.8f,
		                                0.95f, 0.995f, 1.0f};
		for (int mp = SSS_BURLEY_CYCLES; mp <= SSS_BURLEY_CYCLES_RANDOM_WALK;
		     mp++)
			for (size_t k = 0; k < sizeof albedos / sizeof *albedos; k++) {
				sss_material q = skin(SSS_TRANSMISSION_BURLEY, 0.01f);
				q.burley_mapping = mp;
				q.albedo[0] = q.albedo[1] = q.albedo[2] = albedos[k];
				double prev = 2.0;
				for (int i = 0; i <= 60; i++) {
					double t = i == 60 ? INFINITY
					           : i == 0 ? 0.0 : 1e-5 * pow(1.4, i);
					if (sss_transmittance(&q, t, 1.0, T) != SSS_OK)
						bad++;
					for (int c = 0; c < 3; c++)
						if (!(T[c] >= 0.0 && T[c] <= 1.0))
							bad++;
					if (T[0] > prev)
						bad++;
					prev = T[0];
				}
				if (prev != 0.0)
					bad++;
				sss_transmittance(&q, 1e4, 1.0, T);
				if (!(T[0] < 1e-3))
					bad++;
			}
		CHECK("model.burley.bounded-monotone", bad == 0, "%d bad", bad);
	}
	m = skin(SSS_TRANSMISSION_BURLEY, 0.01f);
	sss_transmittance(&m, 100 * d[0] * 4 * 3.14159, 1.0, T);
	CHECK("model.burley.thick", T[0] < 1e-6 && T[2] < 1e-6, "%g", T[0]);
	/* The Gaussian analogue on d'Eon's skin: sum w e^{-t^2 / 2v}. */
	sss_material_default(&m, SSS_PROFILE_GAUSSIANS);
	m.transmission = SSS_TRANSMISSION_BURLEY;
	double t = 0.0005, want = 0.0;
	for (int i = 0; i < 6; i++)
		want += m.gaussian_weight[i][0] *
		        exp(-t * t / (2e-6 * m.gaussian_variance[i]));
	sss_transmittance(&m, t, 1.0, T);
	CHECK("model.gaussians", fabs(T[0] - want) < 1e-6, "%g vs %g", T[0],
	      want);
	sss_transmittance(&m, 0.0, 1.0, T);
	CHECK("model.gaussians.T0", fabs(T[0] - 1) < 1e-6 &&
	      fabs(T[2] - 1) < 1e-6, "%g %g", T[0], T[2]);
	/* Jimenez: s = t 8.25 (1 - 0.83) / 0.012 = 116.875 t; his T(s). */
	sss_material_default(&m, SSS_PROFILE_BURLEY);
	m.transmission = SSS_TRANSMISSION_JIMENEZ;
	t = 0.004;
	double s = t * 8.25 * (1 - 0.83) / 0.012;
	static const double jw[6] = {0.233, 0.100, 0.118, 0.113, 0.358, 0.078};
	static const double jv[6] = {0.0064, 0.0484, 0.187, 0.567, 1.99, 7.41};
	want = 0.0;
	for (int i = 0; i < 6; i++)
		want += jw[i] * exp(-s * s / jv[i]);
	sss_transmittance(&m, t, 1.0, T);
	CHECK("model.jimenez", fabs(T[0] - want) < 1e-5, "%g vs %g", T[0],
	      want);
	m.transmission_translucency = 1.0f;
	sss_transmittance(&m, 1.0, 1.0, T);
	CHECK("model.jimenez.translucent", fabs(T[0] - 1) < 1e-6, "%g", T[0]);
	/* Beer-Lambert: the colour at the distance, 1 at 0, 0 far away. */
	m.transmission = SSS_TRANSMISSION_BEER_LAMBERT;
	m.transmission_distance = 0.002f;
	m.transmission_color[0] = 0.94f;
	m.transmission_color[1] = 0.14f;
	m.transmission_color[2] = 0.0f;
	sss_transmittance(&m, 0.002, 1.0, T);
	CHECK("model.beer.at-distance", fabs(T[0] - 0.94) < 1e-6 &&
	      fabs(T[1] - 0.14) < 1e-6 && T[2] == 0.0, "%g %g %g", T[0], T[1],
	      T[2]);
	sss_transmittance(&m, 0.0, 1.0, T);
	CHECK("model.beer.T0", T[0] == 1 && T[1] == 1 && T[2] == 1, "%g", T[2]);
	sss_transmittance(&m, 0.004, 1.0, T);
	CHECK("model.beer.squared", fabs(T[0] - 0.94 * 0.94) < 1e-6, "%g",
	      T[0]);
	/* Fast: view term, fade-out, cap at 1. */
	m.transmission = SSS_TRANSMISSION_FAST;
	m.transmission_distance = 0.01f;
	m.transmission_color[0] = m.transmission_color[1] = 1.0f;
	m.transmission_color[2] = 1.0f;
	sss_transmittance(&m, 0.005, 1.0, T);
	want = pow(0.8, 4.0) * 0.5;
	CHECK("model.fast", fabs(T[0] - want) < 1e-6, "%g vs %g", T[0], want);
	sss_transmittance(&m, 0.005, 0.5, T2);
	CHECK("model.fast.grazing-dimmer", T2[0] < T[0], "%g", T2[0]);
	sss_transmittance(&m, 0.02, 1.0, T);
	CHECK("model.fast.thick", T[0] == 0.0, "%g", T[0]);
	m.transmission_scale = 50.0f;
	m.transmission_ambient = 3.0f;
	sss_transmittance(&m, 0.0, 1.0, T);
	CHECK("model.fast.capped", T[0] == 1.0, "%g", T[0]);
	/* Off, and a profile that does not scatter: nothing. */
	m = skin(SSS_TRANSMISSION_OFF, 0.01f);
	sss_transmittance(&m, 0.0, 1.0, T);
	CHECK("model.off", T[0] == 0 && T[1] == 0 && T[2] == 0, "%g", T[0]);
}

/* Extremes: every model, thickness 0, negative, NaN, tiny, huge, Inf;
 * never NaN, never more than the back light (T in [0, 1]). */
static void test_extremes(void)
{
	static const double ts[] = {0.0, -0.0, -1.0, NAN, 1e-30, 1e-6, 1.0,
	                            1e30, INFINITY, -INFINITY};
	static const double fs[] = {1.0, 0.0, -1.0, NAN, 2.0};
	static const int32_t kinds[] = {SSS_PROFILE_BURLEY,
	                                SSS_PROFILE_GAUSSIANS,
	                                SSS_PROFILE_JIMENEZ,
	                                SSS_PROFILE_NEAR_FAR};
	int bad = 0;
	for (int k = 0; k < 4; k++)
		for (int model = 1; model <= 4; model++)
			for (size_t i = 0; i < sizeof ts / sizeof *ts; i++)
				for (size_t j = 0; j < sizeof fs / sizeof *fs; j++) {
					sss_material m;
					sss_material_default(&m, kinds[k]);
					m.transmission = model;
					m.transmission_scale = 1e6f;
					m.transmission_ambient = 1e6f;
					double T[3];
					if (sss_transmittance(&m, ts[i], fs[j], T) != SSS_OK)
						bad++;
					for (int c = 0; c < 3; c++)
						if (!(T[c] >= 0.0 && T[c] <= 1.0)) {
							if (bad++ < 5)
								printf("T %g for kind %d model %d t %g f "
								       "%g\n", T[c], kinds[k], model,
								       ts[i], fs[j]);
						}
					if (!(ts[i] >= 0.0) && (T[0] || T[1] || T[2]))
						bad++;
				}
	CHECK("extremes.transmittance", bad == 0, "%d bad", bad);

	/* Through sss_apply: per-pixel extremes in the thickness and the back
	 * light; nothing non-finite appears, NaN light is never spread. */
	char err[256];
	static const float pix_t[] = {0.0f, -0.0f, -1.0f, NAN, 1e30f,
	                              INFINITY, 1e-30f, 0.001f};
	static const float pix_b[] = {1.0f, 0.0f, -5.0f, 1e30f, 65504.0f,
	                              1e-40f, 3.0f, 0.5f};
	for (int model = 1; model <= 4; model++) {
		slab_make(&S, 1.0f, 0.0f);
		for (int i = 0; i < W * H; i++) {
			S.thick[i] = pix_t[i % 8];
			for (int c = 0; c < 3; c++)
				S.back[3 * i + c] = pix_b[(i / 8) % 8];
		}
		S.back[3 * 40] = NAN;
		S.back[3 * 41 + 1] = INFINITY;
		S.p.facing = (sss_image){S.facing, W, H, 1, 0};
		S.facing[5] = NAN;
		sss_material m = skin(model, 0.02f);
		char id[48];
		snprintf(id, sizeof id, "extremes.apply.%d", model);
		CHECK_STATUS(id, SSS_OK, run(&S, &m, 1, err, sizeof err));
		snprintf(id, sizeof id, "extremes.finite.%d", model);
		CHECK(id, all_finite(S.out, W * H * 3), "non-finite output");
	}
	/* Negative or NaN thickness adds nothing: a slab of them stays dark. */
	for (int i = 0; i < 2; i++) {
		slab_make(&S, 1.0f, i ? NAN : -0.5f);
		sss_material m = skin(SSS_TRANSMISSION_BURLEY, 0.02f);
		run(&S, &m, 1, err, sizeof err);
		CHECK(i ? "extremes.nan-thickness-dark" : "extremes.negative-"
		      "thickness-dark", front(&S, 0) == 0.0f, "%g",
		      (double)front(&S, 0));
	}
	/* radius_scale 0 is the identity, transmission included. */
	slab_make(&S, 1.0f, 0.0f);
	for (int i = 0; i < W * H * 3; i++)
		S.dd[i] = 0.25f + 0.001f * (float)i;
	sss_material m = skin(SSS_TRANSMISSION_BURLEY, 0.02f);
	run(&S, &m, 0.0f, err, sizeof err);
	CHECK("extremes.radius-scale-0", memcmp(S.out, S.dd, sizeof S.dd) == 0,
	      "not the identity");
	/* Energy: with random back light and thickness, the added light never
	 * exceeds the light arriving at the back, pixel by pixel before the
	 * blur (strength 1, white) and in total after it. */
	unsigned seed = 12345;
	double added = 0.0, arrived = 0.0;
	slab_make(&S, 0.0f, 0.0f);
	for (int i = 0; i < W * H; i++) {
		seed = seed * 1103515245u + 12345u;
		S.thick[i] = (float)((seed >> 8) % 1000) * 1e-5f;
		for (int c = 0; c < 3; c++) {
			seed = seed * 1103515245u + 12345u;
			S.back[3 * i + c] = (float)((seed >> 8) % 1000) * 1e-3f;
			arrived += S.back[3 * i + c];
		}
	}
	for (int model = 1; model <= 4; model++) {
		sss_material mm = skin(model, 0.03f);
		mm.transmission_scale = 10.0f;
		run(&S, &mm, 1, err, sizeof err);
		added = 0.0;
		for (int i = 0; i < W * H * 3; i++)
			added += S.out[i];
		char id[48];
		snprintf(id, sizeof id, "energy.total.%d", model);
		CHECK(id, added <= arrived * 1.0001 && added > 0.0, "added %g, "
		      "arrived %g", added, arrived);
	}
}

static void test_validation(void)
{
	char err[256];
	sss_material m = skin(SSS_TRANSMISSION_BURLEY, 0.01f);
	m.transmission = 7;
	CHECK_STATUS("valid.model", SSS_ERR_INVALID_ARGUMENT,
	             sss_material_validate(&m, err, sizeof err));
	CHECK("valid.model.msg", strstr(err, "transmission") != NULL, "%s", err);
	m = skin(SSS_TRANSMISSION_BURLEY, 0.01f);
	m.transmission_strength = 1.5f;
	sss_material_validate(&m, err, sizeof err);
	CHECK("valid.strength", strstr(err, "transmission_strength") != NULL,
	      "%s", err);
	m = skin(SSS_TRANSMISSION_BEER_LAMBERT, 0.01f);
	m.transmission_color[2] = NAN;
	sss_material_validate(&m, err, sizeof err);
	CHECK("valid.color", strstr(err, "transmission_color.b") != NULL, "%s",
	      err);
	m = skin(SSS_TRANSMISSION_BEER_LAMBERT, 0.01f);
	m.transmission_distance = 0.0f;
	sss_material_validate(&m, err, sizeof err);
	CHECK("valid.distance", strstr(err, "transmission_distance") != NULL,
	      "%s", err);
	m = skin(SSS_TRANSMISSION_FAST, 0.01f);
	m.transmission_power = -1.0f;
	sss_material_validate(&m, err, sizeof err);
	CHECK("valid.power", strstr(err, "transmission_power") != NULL, "%s",
	      err);
	m = skin(SSS_TRANSMISSION_FAST, 0.01f);
	m.thickness_scale = INFINITY;
	sss_material_validate(&m, err, sizeof err);
	CHECK("valid.thickness-scale", strstr(err, "thickness_scale") != NULL,
	      "%s", err);
	/* Off: the other fields are not read, so not checked. */
	m = skin(SSS_TRANSMISSION_OFF, 0.01f);
	m.transmission_strength = NAN;
	CHECK_STATUS("valid.off-unchecked", SSS_OK,
	             sss_material_validate(&m, err, sizeof err));

	/* Passes: back light without thickness, wrong size, aliasing. */
	slab_make(&S, 1.0f, 0.0f);
	m = skin(SSS_TRANSMISSION_BURLEY, 0.01f);
	S.p.thickness.data = NULL;
	CHECK_STATUS("passes.no-thickness", SSS_ERR_MISSING_PASS,
	             run(&S, &m, 1, err, sizeof err));
	CHECK("passes.no-thickness.msg", strstr(err, "Thickness") != NULL, "%s",
	      err);
	slab_make(&S, 1.0f, 0.0f);
	S.p.back_dir.width = W / 2;
	CHECK_STATUS("passes.size", SSS_ERR_SIZE_MISMATCH,
	             run(&S, &m, 1, err, sizeof err));
	CHECK("passes.size.msg", strstr(err, "BackDir") != NULL, "%s", err);
	slab_make(&S, 1.0f, 0.0f);
	S.p.thickness.channels = 0;
	CHECK_STATUS("passes.channels", SSS_ERR_INVALID_ARGUMENT,
	             run(&S, &m, 1, err, sizeof err));
	slab_make(&S, 1.0f, 0.0f);
	S.p.back_ind = (sss_image){S.out, W, H, 3, 0};
	CHECK_STATUS("passes.alias", SSS_ERR_INVALID_ARGUMENT,
	             run(&S, &m, 1, err, sizeof err));
	CHECK("passes.alias.msg", strstr(err, "BackInd") != NULL, "%s", err);
	/* Without a transmitting material, the back-light passes are only
	 * checked, never required. */
	slab_make(&S, 1.0f, 0.0f);
	m = skin(SSS_TRANSMISSION_OFF, 0.01f);
	S.p.thickness.data = NULL;
	CHECK_STATUS("passes.not-needed", SSS_OK,
	             run(&S, &m, 1, err, sizeof err));
}

/* A back light whose attenuation the add-on baked at one radius scale
 * (transmission_baked_scale): that scale and 0 (no scattering, exactly
 * the plain light) run; any other is refused, naming the field, since
 * T(0) would leave the baked light as it is. */
static void test_baked_scale(void)
{
	char err[256];
	sss_material m = skin(SSS_TRANSMISSION_BURLEY, 0.01f);
	m.transmission_baked_scale = 2.0f;
	slab_make(&S, 1.0f, 0.0f);
	CHECK_STATUS("baked.same", SSS_OK, run(&S, &m, 2.0f, err, sizeof err));
	CHECK("baked.same.transmits", front(&S, 0) > 0.1f, "%g",
	      (double)front(&S, 0));
	slab_make(&S, 1.0f, 0.0f);
	CHECK_STATUS("baked.zero", SSS_OK, run(&S, &m, 0.0f, err, sizeof err));
	CHECK("baked.zero.plain", front(&S, 0) == 0.0f, "%g",
	      (double)front(&S, 0));
	float scales[] = {1.0f, 1e-9f, 2.5f};
	for (int k = 0; k < 3; k++) {
		slab_make(&S, 1.0f, 0.0f);
		CHECK_STATUS("baked.other", SSS_ERR_INVALID_ARGUMENT,
		             run(&S, &m, scales[k], err, sizeof err));
		CHECK("baked.other.msg", strstr(err, "transmission_baked_scale") &&
		      strstr(err, "render it again"), "%s", err);
	}
	/* Without back light nothing was baked into anything: runs. */
	slab_make(&S, 1.0f, 0.0f);
	S.p.back_dir.data = NULL;
	S.p.thickness.data = NULL;
	CHECK_STATUS("baked.no-back-light", SSS_OK,
	             run(&S, &m, 0.5f, err, sizeof err));
	m.transmission_baked_scale = -1.0f;
	CHECK_STATUS("baked.negative", SSS_ERR_INVALID_ARGUMENT,
	             sss_material_validate(&m, err, sizeof err));
	CHECK("baked.negative.msg", strstr(err, "transmission_baked_scale") !=
	      NULL, "%s", err);
}

/* As the radius vanishes, every model's output goes to the render without
 * SSS (radius_scale 0), transmission and calibration included: a slab
 * 5 mm thick, lit in front and from behind. */
static void test_vanishing_radius(void)
{
	static const int32_t models[] = {SSS_TRANSMISSION_BURLEY,
	                                 SSS_TRANSMISSION_JIMENEZ,
	                                 SSS_TRANSMISSION_BEER_LAMBERT,
	                                 SSS_TRANSMISSION_FAST};
	static const float scales[] = {1.0f, 1e-2f, 1e-4f, 1e-6f, 1e-9f};
	static float plain[W * H * 3];
	char err[256];
	for (int k = 0; k < 4; k++) {
		sss_material m = skin(models[k], 0.01f);
		m.calibration = SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN;
		m.transmission_distance = 0.02f;
		/* Beer-Lambert's colour at the distance: white would absorb
		 * nothing at any distance (no length to scale; see
		 * docs/transmission.md) */
		m.transmission_color[0] = 0.9f;
		m.transmission_color[1] = 0.6f;
		m.transmission_color[2] = 0.4f;
		slab_make(&S, 1.0f, 0.005f);
		for (int i = 0; i < W * H * 3; i++)
			S.dd[i] = 0.3f;
		CHECK_STATUS("vanish.plain", SSS_OK, run(&S, &m, 0.0f, err,
		                                         sizeof err));
		memcpy(plain, S.out, sizeof plain);
		double prev = INFINITY;
		for (int j = 0; j < 5; j++) {
			slab_make(&S, 1.0f, 0.005f);
			for (int i = 0; i < W * H * 3; i++)
				S.dd[i] = 0.3f;
			CHECK_STATUS("vanish.run", SSS_OK, run(&S, &m, scales[j], err,
			                                       sizeof err));
			double worst = 0.0;
			for (int i = 0; i < W * H * 3; i++)
				worst = fmax(worst, fabs(S.out[i] - plain[i]) / plain[i]);
			/* At the scene's radius the back light shows; then it
			 * fades, never growing again as the radius shrinks. */
			if (j == 0)
				CHECK("vanish.transmits", worst > 0.05,
				      "model %d: %g", models[k], worst);
			CHECK("vanish.monotone", worst <= prev + 1e-6,
			      "model %d at %g: %g after %g", models[k],
			      (double)scales[j], worst, prev);
			if (scales[j] <= 1e-4f)
				CHECK("vanish.plain-1e-3", worst <= 1e-3,
				      "model %d at %g (radius %g m): %g from plain",
				      models[k], (double)scales[j],
				      0.01 * scales[j], worst);
			prev = worst;
		}
	}
}

static void test_scene_json(void)
{
	const char *json =
		"{\"materials\": [{\"pass_index\": 2, \"profile\": \"burley\","
		" \"transmission\": \"beer-lambert\", \"transmission_strength\": 0.5,"
		" \"transmission_color\": [0.9, 0.2, 0.1],"
		" \"transmission_distance\": 0.003, \"transmission_translucency\": 0.5,"
		" \"transmission_distortion\": 0.1, \"transmission_power\": 8,"
		" \"transmission_scale\": 2, \"transmission_ambient\": 0.1,"
		" \"thickness_scale\": 1.5, \"transmission_baked_scale\": 0.5}]}";
	sss_scene *sc = NULL;
	char warn[256], err[256];
	CHECK_STATUS("json.parse", SSS_OK, sss_scene_parse(json, strlen(json),
	             &sc, warn, sizeof warn, err, sizeof err));
	if (sc) {
		int32_t n;
		const sss_material *m = sss_scene_materials(sc, &n);
		CHECK("json.fields", n == 1 &&
		      m->transmission == SSS_TRANSMISSION_BEER_LAMBERT &&
		      m->transmission_strength == 0.5f &&
		      m->transmission_color[1] == 0.2f &&
		      m->transmission_distance == 0.003f &&
		      m->transmission_translucency == 0.5f &&
		      m->transmission_distortion == 0.1f &&
		      m->transmission_power == 8.0f &&
		      m->transmission_scale == 2.0f &&
		      m->transmission_ambient == 0.1f &&
		      m->thickness_scale == 1.5f &&
		      m->transmission_baked_scale == 0.5f, "fields differ");
		CHECK("json.no-warnings", warn[0] == '\0', "%s", warn);
		sss_scene_free(sc);
	}
	const char *bad = "{\"materials\": [{\"pass_index\": 2, \"profile\": "
	                  "\"burley\", \"transmission\": \"beer\"}]}";
	sc = NULL;
	CHECK_STATUS("json.bad-model", SSS_ERR_INVALID_ARGUMENT,
	             sss_scene_parse(bad, strlen(bad), &sc, NULL, 0, err,
	                             sizeof err));
	CHECK("json.bad-model.msg", strstr(err, "materials[0].transmission") &&
	      strstr(err, "beer-lambert"), "%s", err);
	const char *range = "{\"materials\": [{\"pass_index\": 2, \"profile\": "
	                    "\"burley\", \"transmission_distance\": 0}]}";
	CHECK_STATUS("json.range", SSS_ERR_INVALID_ARGUMENT,
	             sss_scene_parse(range, strlen(range), &sc, NULL, 0, err,
	                             sizeof err));
	CHECK("json.range.msg", strstr(err, "transmission_distance") != NULL,
	      "%s", err);
}

/* The 8x8 Cycles render (tests/data/blender_8x8.exr, 8 x 8 pixels) with a
 * layer SSSBackLight added, written to path: DiffDir rgb, DiffInd rgb too
 * when with_ind, and SSSThicknessSq sq. 0 when written. */
static int write_backlit(const char *path, const float *rgb, int with_ind,
                         const float *sq, const char *id)
{
	char err[512], check[64];
	sss_exr *exr = NULL;
	snprintf(check, sizeof check, "%s.read", id);
	if (sss_exr_read("tests/data/blender_8x8.exr", NULL, &exr, err,
	                 sizeof err) != SSS_OK) {
		CHECK(check, 0, "%s", err);
		return -1;
	}
	snprintf(check, sizeof check, "%s.add", id);
	CHECK_STATUS(check, SSS_OK,
	             sss_exr_add_pass(exr, SSS_BACKLIGHT_LAYER, "DiffDir", "RGB",
	                              rgb, err, sizeof err));
	if (with_ind)
		sss_exr_add_pass(exr, SSS_BACKLIGHT_LAYER, "DiffInd", "RGB", rgb,
		                 err, sizeof err);
	sss_exr_add_pass(exr, SSS_BACKLIGHT_LAYER, SSS_THICKNESS_SQ_PASS, "X",
	                 sq, err, sizeof err);
	snprintf(check, sizeof check, "%s.write", id);
	sss_result r = sss_exr_write(exr, path, NULL, err, sizeof err);
	CHECK_STATUS(check, SSS_OK, r);
	sss_exr_free(exr);
	return r == SSS_OK ? 0 : -1;
}

/* The back-light layer of a Blender EXR, end to end: the 8x8 Cycles
 * render gets a layer SSSBackLight (DiffDir, DiffInd, SSSThicknessSq);
 * with transmission its SSS light is brighter by what crossed, and the
 * auto-picked layer is still the render's own. */
static void test_process(void)
{
	char dir[] = "/tmp/sss_trans_XXXXXX";
	if (!mkdtemp(dir)) {
		CHECK("process.tmpdir", 0, "mkdtemp failed");
		return;
	}
	char in[96], out_on[96], out_off[96], err[512];
	snprintf(in, sizeof in, "%s/in.exr", dir);
	snprintf(out_on, sizeof out_on, "%s/on.exr", dir);
	snprintf(out_off, sizeof out_off, "%s/off.exr", dir);
	const int32_t w = 8, h = 8;
	float rgb[8 * 8 * 3], sq[8 * 8];
	for (int i = 0; i < w * h * 3; i++)
		rgb[i] = 0.5f;
	for (int i = 0; i < w * h; i++)
		sq[i] = 0.004f * 0.004f;
	if (write_backlit(in, rgb, 1, sq, "process"))
		return;

	const char *tmpl =
		"{\"materials\": [{\"pass_index\": 1, \"profile\": \"burley\","
		" \"radius\": [0.12, 0.048, 0.024], \"transmission\": \"%s\"}]}";
	double mean[2] = {0, 0};
	for (int on = 0; on < 2; on++) {
		char json[256];
		snprintf(json, sizeof json, tmpl, on ? "burley" : "off");
		sss_scene *sc = NULL;
		sss_scene_parse(json, strlen(json), &sc, NULL, 0, err, sizeof err);
		const char *o = on ? out_on : out_off;
		CHECK_STATUS(on ? "process.on" : "process.off", SSS_OK,
		             sss_process_exr(in, o, sc, NULL, NULL, err,
		                             sizeof err));
		sss_scene_free(sc);
		sss_exr *res = NULL;
		sss_image light, index;
		if (sss_exr_read(o, NULL, &res, err, sizeof err) == SSS_OK &&
		    sss_exr_find(res, "SSS", "DiffLight", &light) == SSS_OK) {
			sss_passes p;
			const char *layer = NULL;
			sss_exr_render_passes(res, NULL, &p, &layer, err, sizeof err);
			CHECK("process.auto-layer", layer &&
			      strcmp(layer, SSS_BACKLIGHT_LAYER) != 0, "%s",
			      layer ? layer : "(none)");
			index = p.index_ma;
			int n = 0;
			for (int i = 0; i < w * h; i++)
				if (index.data && fabsf(index.data[i] - 1.0f) < 0.5f) {
					mean[on] += light.data[3 * i];
					n++;
				}
			mean[on] /= n ? n : 1;
		}
		sss_exr_free(res);
	}
	/* Thickness 4 mm, red d = 0.12 / 4 pi: T = 0.89 or so, B = 1. */
	CHECK("process.brighter", mean[1] > mean[0] + 0.5, "on %g, off %g",
	      mean[1], mean[0]);
	unlink(in);
	unlink(out_on);
	unlink(out_off);
	rmdir(dir);
}

/* The squared thickness AOV (a few Ambient Occlusion rays a sample: zero
 * at most pixels of a thin part) is pooled over each pixel's 3 x 3
 * neighbours of its own material before the root (sss_frame.c). On the
 * 8x8 render's floor (material 2, rows 4 - 7), a thin Random Walk (Skin)
 * material: t^2 alternating 0 and 2 q gives the light of t^2 = q where
 * the root of each pixel would give a mean of G(0) and G(sqrt(2 q)); and
 * the other materials' t^2, however large, does not enter the floor's. */
static double floor_light(const char *dir, const char *name, const float *sq,
                          int c)
{
	char in[96], out[96], err[512];
	snprintf(in, sizeof in, "%s/%s_in.exr", dir, name);
	snprintf(out, sizeof out, "%s/%s_out.exr", dir, name);
	float zero[8 * 8 * 3] = {0};
	if (write_backlit(in, zero, 0, sq, "pool"))
		return NAN;
	const char *json =
		"{\"materials\": [{\"pass_index\": 2, \"profile\": \"burley\","
		" \"radius\": [0.05, 0.02, 0.01], \"albedo\": [0.8, 0.8, 0.8],"
		" \"mapping\": \"cycles-random-walk\", \"calibration\":"
		" \"cycles4-random-walk-skin\", \"thin_reflectance\": 1,"
		" \"transmission\": \"burley\"}]}";
	sss_scene *sc = NULL;
	sss_scene_parse(json, strlen(json), &sc, NULL, 0, err, sizeof err);
	CHECK_STATUS("pool.process", SSS_OK,
	             sss_process_exr(in, out, sc, NULL, NULL, err, sizeof err));
	sss_scene_free(sc);
	double sum = 0.0;
	sss_exr *res = NULL;
	sss_image light;
	if (sss_exr_read(out, NULL, &res, err, sizeof err) == SSS_OK &&
	    sss_exr_find(res, "SSS", "DiffLight", &light) == SSS_OK)
		for (int y = 4; y < 8; y++)
			for (int x = 0; x < 8; x++)
				sum += light.data[3 * (y * 8 + x) + c];
	else
		sum = NAN;
	sss_exr_free(res);
	unlink(in);
	unlink(out);
	return sum;
}

static void test_thickness_pool(void)
{
	char dir[] = "/tmp/sss_pool_XXXXXX";
	if (!mkdtemp(dir)) {
		CHECK("pool.tmpdir", 0, "mkdtemp failed");
		return;
	}
	const float q = 0.005f * 0.005f; /* 5 mm: thin against 5 and 2 cm */
	float even[64], checker[64], thick[64], apart[64];
	for (int i = 0; i < 64; i++) {
		int x = i % 8, y = i / 8;
		even[i] = q;
		checker[i] = (x + y) % 2 ? 2.0f * q : 0.0f;
		thick[i] = 100.0f;
	}
	for (int c = 0; c < 2; c++) { /* red and green */
		double e = floor_light(dir, "even", even, c);
		double k = floor_light(dir, "checker", checker, c);
		double t = floor_light(dir, "thick", thick, c);
		CHECK("pool.thin", e < 0.9 * t && e > 0.0, "channel %d: %g, thick %g",
		      c, e, t);
		CHECK("pool.mean", fabs(k - e) <= 0.02 * e,
		      "channel %d: alternating %g, even %g, thick %g", c, k, e, t);
	}
	/* Materials 1 and 3 and the background read thick, the floor q: the
	 * floor's light is the same as with q everywhere (its pixels next to
	 * materials 1 and 3 pool none of their 100). */
	const char *floor = "........"
	                    "..####.."
	                    "###..###"
	                    "###....#"
	                    "########"
	                    "########"
	                    "########"
	                    "########";
	for (int i = 0; i < 64; i++)
		apart[i] = floor[i] == '#' ? q : 100.0f;
	double a = floor_light(dir, "apart", apart, 0);
	double e = floor_light(dir, "even", even, 0);
	CHECK("pool.materials", a == e, "%g against %g", a, e);
	rmdir(dir);
}

/* What the add-on asks instead of computing it: how thick a part can be
 * before nothing crosses it (its thickness measurement's reach), and the
 * slab's coefficients (its shader evaluates the same T). */
static void test_reach_and_slab(void)
{
	static const int32_t models[] = {
		SSS_TRANSMISSION_BURLEY, SSS_TRANSMISSION_JIMENEZ,
		SSS_TRANSMISSION_BEER_LAMBERT, SSS_TRANSMISSION_FAST};
	static const char *names[] = {"burley", "jimenez", "beer", "fast"};
	for (int k = 0; k < 4; k++) {
		char id[64];
		sss_material m = skin(models[k], 0.01f);
		m.transmission_color[0] = 0.9f;
		m.transmission_color[1] = 0.5f;
		m.transmission_color[2] = 0.3f;
		double reach = -1.0, T[3], Th[3], T0[3];
		snprintf(id, sizeof id, "reach.%s.ok", names[k]);
		CHECK_STATUS(id, SSS_OK, sss_transmission_reach(&m, &reach));
		sss_transmittance(&m, 0.0, 1.0, T0);
		sss_transmittance(&m, reach, 1.0, T);
		sss_transmittance(&m, 0.5 * reach, 1.0, Th);
		int below = 1, before = 0;
		for (int c = 0; c < 3; c++) {
			double gain = m.transmission_strength *
			              (models[k] == SSS_TRANSMISSION_BEER_LAMBERT
			               ? 1.0 : m.transmission_color[c]);
			below &= T[c] <= 0.0101 * gain;
			before |= Th[c] > T[c] && T0[c] > Th[c];
		}
		snprintf(id, sizeof id, "reach.%s.nothing-beyond", names[k]);
		CHECK(id, reach > 0.0 && below, "reach %g m: T %g %g %g", reach,
		      T[0], T[1], T[2]);
		snprintf(id, sizeof id, "reach.%s.light-before", names[k]);
		CHECK(id, before, "T(reach / 2) %g", Th[0]);
	}
	sss_material off = skin(SSS_TRANSMISSION_OFF, 0.01f);
	double reach = -1.0;
	CHECK("reach.off", sss_transmission_reach(&off, &reach) == SSS_OK &&
	      reach == 0.0, "%g", reach);
	off.radius[0] = -1.0f;
	CHECK_STATUS("reach.invalid", SSS_ERR_INVALID_ARGUMENT,
	             sss_transmission_reach(&off, &reach));

	/* The slab's closed form from its coefficients is sss_transmittance. */
	sss_material m = skin(SSS_TRANSMISSION_BURLEY, 0.01f);
	m.radius[2] = 0.0f;
	double s[3], a[3], zb[3];
	CHECK_STATUS("slab-coefficients.ok", SSS_OK,
	             sss_transmission_slab(&m, s, a, zb));
	double worst = 0.0;
	for (int i = 0; i <= 20; i++) {
		double t = 0.001 * i, T[3];
		sss_transmittance(&m, t, 1.0, T);
		for (int c = 0; c < 2; c++) {
			double L = fmax(t + 2.0 * zb[c], 2.0 * a[c]);
			double v = -expm1(-2.0 * s[c] * a[c]) *
			           exp(-s[c] * (L - 2.0 * a[c])) /
			           -expm1(-2.0 * s[c] * L);
			worst = fmax(worst, fabs(fmin(v, 1.0) - T[c]));
		}
	}
	CHECK("slab-coefficients.closed-form", worst < 1e-12, "off by %g",
	      worst);
	CHECK("slab-coefficients.no-medium", s[2] == 0.0 && a[2] == 0.0 &&
	      zb[2] == 0.0 && s[0] > 0.0 && a[0] > 0.0 && zb[0] > 0.0,
	      "%g %g %g", s[2], a[2], zb[2]);
	m.transmission = SSS_TRANSMISSION_JIMENEZ;
	CHECK_STATUS("slab-coefficients.not-the-slab", SSS_ERR_UNSUPPORTED,
	             sss_transmission_slab(&m, s, a, zb));
	sss_material_default(&m, SSS_PROFILE_GAUSSIANS);
	m.transmission = SSS_TRANSMISSION_BURLEY;
	CHECK_STATUS("slab-coefficients.gaussians", SSS_ERR_UNSUPPORTED,
	             sss_transmission_slab(&m, s, a, zb));
}

/* The slab's table (sss_transmission_table): its samples are
 * sss_transmittance over its value at 0, and a linear lookup that holds
 * the last sample beyond the table follows the library, micrometre and
 * nanometre radii included, and lets nothing through where it lets
 * nothing through. */
static void test_table(void)
{
	enum { N = 4096 };
	static float table[3 * N];
	static const float radii[] = {0.03f, 0.00367f, 1e-6f, 1e-9f};
	static const float scales[] = {1.0f, 0.4f};
	char id[64];
	for (int wi = 0; wi < 2; wi++)
	for (int ri = 0; ri < 4; ri++)
		for (int si = 0; si < 2; si++) {
			sss_material m = skin(SSS_TRANSMISSION_BURLEY, radii[ri]);
			m.burley_mapping = SSS_BURLEY_CYCLES_RANDOM_WALK;
			m.albedo[0] = 0.95f; /* red: a long reach */
			m.albedo[2] = 0.1f;  /* blue: 4.x's walk far above the slab */
			/* 3.x's walk (the slab) and 4.x's (the measured table) */
			m.calibration = wi ? SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN
			                   : SSS_CALIBRATION_CYCLES_RANDOM_WALK;
			m.thickness_scale = scales[si];
			double step = -1.0, span = -1.0;
			snprintf(id, sizeof id, "table%s.%g.%g", wi ? "4" : "",
			         radii[ri], scales[si]);
			CHECK_STATUS(id, SSS_OK, sss_transmission_table(&m, N, table,
			                                                &step, &span));
			double g = log1p(span / step) / (N - 1);
			double T0[3], worst = 0.0, worst_lookup = 0.0;
			int leaks = 0, rising = 0;
			sss_transmittance(&m, 0.0, 1.0, T0);
			for (int i = 0; i < N; i++)
				for (int c = 0; c < 3; c++) {
					double T[3];
					sss_transmittance(&m, i == N - 1 ? span
					                  : expm1(g * i) * step, 1.0, T);
					double want = i == N - 1 ? 0.0 : T[c] / T0[c];
					worst = fmax(worst, fabs(table[3 * i + c] - want));
					if (i && table[3 * i + c] > table[3 * (i - 1) + c])
						rising++;
				}
			/* Between and beyond the samples, as the add-on's image
			 * lookup reads them. */
			double gj = log1p(1.5 * span / step) / 20000.0;
			for (int j = 0; j <= 20000; j++) {
				double t = step * expm1(gj * j);
				double x = log1p(t / step) / g;
				int i = x >= N - 1 ? N - 2 : (int)x;
				double f = x >= N - 1 ? 1.0 : x - i, T[3];
				sss_transmittance(&m, t, 1.0, T);
				for (int c = 0; c < 3; c++) {
					double got = (1.0 - f) * table[3 * i + c] +
					             f * table[3 * (i + 1) + c];
					double want = T[c] / T0[c];
					worst_lookup = fmax(worst_lookup, fabs(got - want));
					leaks += want == 0.0 && got != 0.0;
				}
			}
			snprintf(id, sizeof id, "table%s.%g.%g.samples",
			         wi ? "4" : "", radii[ri], scales[si]);
			CHECK(id, step > 0.0 && span > step && worst < 1e-6,
			      "step %g, span %g, off by %g", step, span, worst);
			snprintf(id, sizeof id, "table%s.%g.%g.lookup",
			         wi ? "4" : "", radii[ri], scales[si]);
			CHECK(id, worst_lookup < 5e-4, "off by %g", worst_lookup);
			snprintf(id, sizeof id, "table%s.%g.%g.no-leak",
			         wi ? "4" : "", radii[ri], scales[si]);
			CHECK(id, leaks == 0 && rising == 0, "%d leaks, %d rising",
			      leaks, rising);
			/* The table ends where (almost) nothing crosses: its span is
			 * the pass thickness, the slab's divided by the scale. */
			double T[3];
			sss_transmittance(&m, span, 1.0, T);
			snprintf(id, sizeof id, "table%s.%g.%g.end",
			         wi ? "4" : "", radii[ri], scales[si]);
			CHECK(id, T[0] <= 1.01e-6 * T0[0] && T[1] <= 1.01e-6 * T0[1] &&
			      T[2] <= 1.01e-6 * T0[2], "T(end) %g %g %g", T[0], T[1],
			      T[2]);
		}
	/* A micrometre radius: under a millimetre of skin nothing crosses,
	 * in the library and in its table. */
	sss_material m = skin(SSS_TRANSMISSION_BURLEY, 1e-6f);
	double step, span, T[3];
	sss_transmission_table(&m, N, table, &step, &span);
	sss_transmittance(&m, 1e-3, 1.0, T);
	CHECK("table.micrometre", span < 1e-3 && T[0] == 0.0 && T[1] == 0.0 &&
	      T[2] == 0.0, "span %g, T(1 mm) %g", span, T[0]);
	m.thickness_scale = 0.0f;
	sss_transmission_table(&m, N, table, &step, &span);
	int ones = 0;
	for (int i = 0; i < 3 * N; i++)
		ones += table[i] == 1.0f;
	CHECK("table.thickness-scale-0", ones == 3 * N, "%d ones", ones);
	m.thickness_scale = 1.0f;
	m.radius[2] = 0.0f;
	sss_transmission_table(&m, N, table, &step, &span);
	CHECK("table.no-medium", table[2] == 1.0f && table[5] == 0.0f &&
	      table[3 * (N - 1) + 2] == 0.0f, "%g %g", table[2], table[5]);
	CHECK_STATUS("table.n", SSS_ERR_INVALID_ARGUMENT,
	             sss_transmission_table(&m, 1, table, &step, &span));
	CHECK_STATUS("table.null", SSS_ERR_INVALID_ARGUMENT,
	             sss_transmission_table(&m, N, NULL, &step, &span));
	m.transmission = SSS_TRANSMISSION_BEER_LAMBERT;
	CHECK_STATUS("table.not-the-slab", SSS_ERR_UNSUPPORTED,
	             sss_transmission_table(&m, N, table, &step, &span));
}

/* A skin material of one walk, albedo A in every channel: 3.x's Random
 * Walk (WALK_3X: the slab), 4.x's Random Walk (Skin) (WALK_SKIN) or
 * Random Walk (WALK_RW), both measured tables; WALK_RW_SLAB is WALK_RW's
 * medium with no calibration, so the slab. */
enum { WALK_3X, WALK_SKIN, WALK_RW, WALK_RW_SLAB };
static sss_material walk(int kind, float A)
{
	sss_material m = skin(SSS_TRANSMISSION_BURLEY, 0.02f);
	int four = kind == WALK_RW || kind == WALK_RW_SLAB;
	m.burley_mapping = four ? SSS_BURLEY_CYCLES4_RANDOM_WALK
	                        : SSS_BURLEY_CYCLES_RANDOM_WALK;
	m.calibration = kind == WALK_SKIN ? SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN
	                : kind == WALK_RW ? SSS_CALIBRATION_CYCLES4_RANDOM_WALK
	                : kind == WALK_3X ? SSS_CALIBRATION_CYCLES_RANDOM_WALK
	                                  : SSS_CALIBRATION_NONE;
	for (int c = 0; c < 3; c++)
		m.albedo[c] = A;
	return m;
}

/* The slab of sss.h from sss_transmission_slab's coefficients, the
 * operations in the library's order. */
static double slab_closed_form(double s, double a, double zb, double t)
{
	double L = t + 2.0 * zb;
	if (!(L > 2.0 * a))
		L = 2.0 * a;
	double x = s * L;
	if (x < 1e-6)
		return a / L;
	double y = s * a;
	double T = -expm1(-2.0 * y) * exp(-(x - 2.0 * y)) / -expm1(-2.0 * x);
	return T < 1.0 ? T : 1.0;
}

/* One of Blender 4.x's walks (sss_walk4_KIND_table.c) against the slab
 * of the same medium (kind WALK_SKIN against WALK_3X, WALK_RW against
 * WALK_RW_SLAB): the slab's materials keep it bit for bit; the walk's
 * follow the measured points within the fit's residual, never rise with
 * the thickness, let at most all of the light through (A T <= 1) and
 * nothing through an infinitely thick part. */
static void test_walk4(const char *name, int kind, int slab_kind,
                       const double (*measured)[3], size_t np,
                       double fit_rms, double fit_worst)
{
	static const float albedos[] = {0.0f, 0.02f, 0.05f, 0.13f, 0.45f,
	                                0.8f, 0.93f, 0.95f, 0.99f, 1.0f};
	int same = 1, differs = 0, rising = 0, over = 0, bad = 0, n = 0;
	char id[64];
	for (size_t k = 0; k < sizeof albedos / sizeof *albedos; k++) {
		sss_material m3 = walk(slab_kind, albedos[k]);
		sss_material m4 = walk(kind, albedos[k]);
		m3.albedo[1] = m4.albedo[1] = 0.6f;
		double s3[3], a3[3], z3[3], s4[3], a4[3], z4[3];
		sss_transmission_slab(&m3, s3, a3, z3);
		sss_transmission_slab(&m4, s4, a4, z4);
		double prev[3] = {INFINITY, INFINITY, INFINITY};
		for (int i = 0; i <= 400; i++) {
			double t = i == 400 ? INFINITY : 1e-5 * expm1(0.03 * i);
			double T3[3], T4[3];
			sss_transmittance(&m3, t, 1.0, T3);
			sss_transmittance(&m4, t, 1.0, T4);
			for (int c = 0; c < 3; c++) {
				same &= s3[c] == s4[c] && a3[c] == a4[c] && z3[c] == z4[c];
				if (a3[c] > 0.0) {
					double v = slab_closed_form(s3[c], a3[c], z3[c], t);
					same &= memcmp(&v, &T3[c], sizeof v) == 0;
				}
				differs += T4[c] != T3[c];
				rising += T4[c] > prev[c];
				over += m4.albedo[c] * T4[c] > 1.0;
				bad += !isfinite(T4[c]) || T4[c] < 0.0 ||
				       (i == 400 && T4[c] != 0.0);
				prev[c] = T4[c];
				n++;
			}
		}
	}
	snprintf(id, sizeof id, "%s.slab-unchanged", name);
	CHECK(id, same, "the slab is not the closed form");
	snprintf(id, sizeof id, "%s.differs", name);
	CHECK(id, differs > n / 2, "%d of %d differ", differs, n);
	snprintf(id, sizeof id, "%s.monotone", name);
	CHECK(id, rising == 0, "%d rising of %d", rising, n);
	snprintf(id, sizeof id, "%s.energy", name);
	CHECK(id, over == 0 && bad == 0, "%d over 1 / A, %d bad", over, bad);

	/* The measured points (tests/transmission4_KIND_measured.h). */
	double sum = 0.0, worst = 0.0;
	for (size_t i = 0; i < np; i++) {
		sss_material m = walk(kind, (float)measured[i][0]);
		double s[3], a[3], zb[3], T[3];
		sss_transmission_slab(&m, s, a, zb);
		double l = 1.5 * (a[0] - zb[0]);
		sss_transmittance(&m, measured[i][1] * l, 1.0, T);
		double e = fabs(log(T[0] / measured[i][2]));
		sum += e * e;
		worst = fmax(worst, e);
	}
	double rms = sqrt(sum / (double)np);
	snprintf(id, sizeof id, "%s.measured", name);
	CHECK(id, np > 50 && rms <= fit_rms + 2e-3 && worst <= fit_worst + 2e-3,
	      "%zu points: ln RMS %g (fit %g), largest %g (fit %g)", np, rms,
	      fit_rms, worst, fit_worst);
}

/* Thin parts lit from the front (sss_thin.c): on the slab lit only in
 * front, Random Walk (Skin) with thin_reflectance 1 over 0 follows the
 * measured share of a thick part's light (tests/thin4_skin_measured.h)
 * within the fit's residual; half of the loss at 0.5; nothing changes
 * without the pass, at a NaN or negative thickness, for another walk, or
 * at thin_reflectance 0; a baked back light still crosses at T(0). */
static float thin_front(sss_material *m, float A, float share, float t,
                        int pass, int c)
{
	char err[256];
	for (int k = 0; k < 3; k++)
		m->albedo[k] = A;
	m->thin_reflectance = share;
	slab_make(&S, 0.0f, t);
	for (int i = 0; i < W * H * 3; i++)
		S.dd[i] = 0.5f;
	if (!pass)
		S.p.thickness.data = NULL, S.p.back_dir.data = NULL;
	if (run(&S, m, 1.0f, err, sizeof err))
		return NAN;
	return front(&S, c);
}

static void test_thin(void)
{
	size_t np = sizeof thin4_skin_measured / sizeof *thin4_skin_measured;
	double sum = 0.0, worst = 0.0;
	sss_material m = walk(WALK_SKIN, 0.5f);
	for (size_t i = 0; i < np; i++) {
		float A = (float)thin4_skin_measured[i][0];
		sss_material q = walk(WALK_SKIN, A);
		double s[3], a[3], zb[3];
		sss_transmission_slab(&q, s, a, zb);
		float t = (float)(thin4_skin_measured[i][1] * 1.5 * (a[0] - zb[0]));
		double g = thin_front(&m, A, 1.0f, t, 1, 0) /
		           thin_front(&m, A, 0.0f, t, 1, 0);
		double e = fabs(g - thin4_skin_measured[i][2]);
		sum += e * e;
		worst = fmax(worst, e);
	}
	double rms = sqrt(sum / (double)np);
	CHECK("thin.measured", np > 100 && rms <= THIN4_SKIN_FIT_RMS + 3e-3 &&
	      worst <= THIN4_SKIN_FIT_WORST + 1e-2,
	      "%zu points: RMS %g (fit %g), largest %g (fit %g)", np, rms,
	      THIN4_SKIN_FIT_RMS, worst, THIN4_SKIN_FIT_WORST);

	float full = thin_front(&m, 0.8f, 0.0f, 0.004f, 1, 0);
	float one = thin_front(&m, 0.8f, 1.0f, 0.004f, 1, 0);
	float half = thin_front(&m, 0.8f, 0.5f, 0.004f, 1, 0);
	CHECK("thin.loses", one < 0.9f * full && one > 0.0f, "%g of %g",
	      (double)one, (double)full);
	CHECK("thin.half", fabsf(half - 0.5f * (one + full)) <= 1e-5f * full,
	      "%g, %g, %g", (double)half, (double)one, (double)full);
	CHECK("thin.thick", thin_front(&m, 0.8f, 1.0f, 10.0f, 1, 0) == full,
	      "a thick part changed");
	CHECK("thin.no-pass", thin_front(&m, 0.8f, 1.0f, 0.004f, 0, 0) ==
	      thin_front(&m, 0.8f, 0.0f, 0.004f, 0, 0), "changed");
	float bad[] = {NAN, -1.0f, INFINITY};
	for (int k = 0; k < 3; k++)
		CHECK("thin.bad-thickness", thin_front(&m, 0.8f, 1.0f, bad[k], 1, 0)
		      == thin_front(&m, 0.8f, 0.0f, bad[k], 1, 0), "%g",
		      (double)bad[k]);
	sss_material m3 = walk(WALK_3X, 0.8f);
	CHECK("thin.other-walk", thin_front(&m3, 0.8f, 1.0f, 0.004f, 1, 0) ==
	      thin_front(&m3, 0.8f, 0.0f, 0.004f, 1, 0), "changed");

	/* What sss_thin_measured says is what the scatter does: a table for
	 * 4.x's Random Walk (Skin) whatever thin_reflectance, none for the
	 * others. */
	int measured = -1;
	sss_material m0 = m;
	m0.thin_reflectance = 0.0f;
	CHECK("thin.query-skin", sss_thin_measured(&m0, &measured) == SSS_OK &&
	      measured == 1, "%d", measured);
	CHECK("thin.query-3x", sss_thin_measured(&m3, &measured) == SSS_OK &&
	      measured == 0, "%d", measured);
	sss_material plain = m;
	plain.calibration = SSS_CALIBRATION_NONE;
	CHECK("thin.query-none", sss_thin_measured(&plain, &measured) ==
	      SSS_OK && measured == 0 &&
	      thin_front(&plain, 0.8f, 1.0f, 0.004f, 1, 0) ==
	      thin_front(&plain, 0.8f, 0.0f, 0.004f, 1, 0), "%d", measured);
	sss_material badm = m;
	badm.thin_reflectance = 2.0f;
	CHECK("thin.query-invalid", sss_thin_measured(&badm, &measured) ==
	      SSS_ERR_INVALID_ARGUMENT && measured == 0, "%d", measured);
	CHECK("thin.query-null", sss_thin_measured(&m, NULL) ==
	      SSS_ERR_INVALID_ARGUMENT, "accepted");

	/* A baked back light: T(0) at any thickness the pass gives. */
	char err[256];
	sss_material b = walk(WALK_SKIN, 0.8f);
	b.transmission_baked_scale = 1.0f;
	float at0[3];
	slab_make(&S, 1.0f, 0.0f);
	CHECK_STATUS("thin.baked", SSS_OK, run(&S, &b, 1.0f, err, sizeof err));
	for (int c = 0; c < 3; c++)
		at0[c] = front(&S, c);
	slab_make(&S, 1.0f, 0.01f);
	CHECK_STATUS("thin.baked", SSS_OK, run(&S, &b, 1.0f, err, sizeof err));
	CHECK("thin.baked-T0", front(&S, 0) == at0[0] && front(&S, 2) == at0[2],
	      "%g against %g", (double)front(&S, 0), (double)at0[0]);
	b.thin_reflectance = 2.0f;
	CHECK_STATUS("thin.range", SSS_ERR_INVALID_ARGUMENT,
	             sss_material_validate(&b, err, sizeof err));
	CHECK("thin.range.msg", strstr(err, "thin_reflectance") != NULL, "%s",
	      err);
}

int main(void)
{
	test_slab();
	test_reach_and_slab();
	test_table();
	test_walk4("walk4", WALK_SKIN, WALK_3X, walk4_skin_measured,
	           sizeof walk4_skin_measured / sizeof *walk4_skin_measured,
	           WALK4_SKIN_FIT_RMS, WALK4_SKIN_FIT_WORST);
	test_walk4("walk4rw", WALK_RW, WALK_RW_SLAB, walk4_rw_measured,
	           sizeof walk4_rw_measured / sizeof *walk4_rw_measured,
	           WALK4_RW_FIT_RMS, WALK4_RW_FIT_WORST);
	test_thin();
	test_thickness_pool();
	test_models();
	test_extremes();
	test_validation();
	test_baked_scale();
	test_vanishing_radius();
	test_scene_json();
	test_process();
	return tu_finish("test_transmission");
}
