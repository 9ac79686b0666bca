/* test_crease.c - the light a sharp convex edge carries onto the next face
 * (sss_crease.c): on a 90-degree edge seen at 45 degrees, lit on one face
 * only, for 4.x's Random Walk (Skin) and Random Walk and 3.x's Random
 * Walk, the unlit face gains in all kappa x the integral of F (0.7958 d
 * for Burley's marginal) times the lit face's light at the edge, and the
 * lit face loses the loss's kappa x 0.7958 d of it, whatever the pixel
 * size, orthographic or in perspective; nothing on a plane, a sphere,
 * without a calibration or with the option off; it vanishes with the
 * radius, and on a face narrower than the radius only the light of that
 * face crosses. */
#include "sss_internal.h"
#include "test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define VIEW 0.2 /* metres the orthographic camera sees across */

enum shape { WEDGE, PLANE, SPHERE };

/* A frame n x n: the lower face (the edge is the middle row boundary) lit
 * by 1, the upper one unlit, DiffCol `albedo`; `face` metres of each face
 * seen from the edge (beyond: background). */
typedef struct frame {
	int n;
	float *dd, *col, *z, *idx, *out;
	double *pt; /* each pixel's view-space point */
	sss_passes ps;
	sss_camera cam;
	sss_options opt;
} frame;

/* Orthographic VIEW metres wide at depth 4, or (perspective) a 90 mm lens
 * seeing VIEW metres across at depth 0.5, the wedge's edge there. */
static void frame_make(frame *f, int n, enum shape s, float albedo,
                       double face, int perspective)
{
	f->n = n;
	f->pt = malloc(sizeof(double) * 3 * n * n);
	f->dd = malloc(sizeof(float) * 3 * n * n);
	f->col = malloc(sizeof(float) * 3 * n * n);
	f->z = malloc(sizeof(float) * n * n);
	f->idx = malloc(sizeof(float) * n * n);
	f->out = malloc(sizeof(float) * 3 * n * n);
	double pix = VIEW / n;
	for (int y = 0; y < n; y++)
		for (int x = 0; x < n; x++) {
			int i = y * n + x;
			double u = (x + 0.5) * pix - VIEW / 2,
			       v = VIEW / 2 - (y + 0.5) * pix;
			double z = 4.0 + fabs(v); /* both faces recede at 45 degrees */
			if (perspective) { /* the ray (u, v, 0.5) t/0.5 meets them */
				double t = 0.5 / (1.0 - fabs(v) / 0.5);
				u *= t / 0.5, v *= t / 0.5, z = t;
			}
			f->pt[3 * i] = u, f->pt[3 * i + 1] = v, f->pt[3 * i + 2] = z;
			int inside = fabs(v) * sqrt(2.0) < face;
			if (s == PLANE)
				z = 4.0 + 0.3 * v, inside = 1;
			if (s == SPHERE) { /* radius VIEW / 3 */
				double a = VIEW / 3, r2 = u * u + v * v;
				inside = r2 < a * a;
				z = inside ? 4.0 - sqrt(a * a - r2) : 0.0;
			}
			f->z[i] = inside ? (float)z : 1e10f;
			f->idx[i] = inside ? 1.0f : 0.0f;
			float light = s == WEDGE ? (v < 0.0 ? 1.0f : 0.0f)
			                         : (u < 0.0 ? 1.0f : 0.2f);
			for (int c = 0; c < 3; c++) {
				f->dd[3 * i + c] = light;
				f->col[3 * i + c] = albedo;
			}
		}
	memset(&f->ps, 0, sizeof f->ps);
	f->ps.diff_dir = (sss_image){f->dd, n, n, 3, 0};
	f->ps.diff_col = (sss_image){f->col, n, n, 3, 0};
	f->ps.depth = (sss_image){f->z, n, n, 1, 0};
	f->ps.index_ma = (sss_image){f->idx, n, n, 1, 0};
	sss_camera_default(&f->cam);
	f->cam.type = SSS_CAMERA_ORTHOGRAPHIC;
	f->cam.ortho_scale = VIEW;
	if (perspective) {
		f->cam.type = SSS_CAMERA_PERSPECTIVE;
		f->cam.lens_mm = 36.0 * 0.5 / VIEW;
		f->cam.sensor_width_mm = 36.0;
	}
	sss_options_default(&f->opt);
	f->opt.num_threads = 1;
	f->opt.method = SSS_METHOD_SEPARABLE;
}

static void frame_free(frame *f)
{
	free(f->dd);
	free(f->col);
	free(f->z);
	free(f->idx);
	free(f->out);
	free(f->pt);
}

/* Burley matched to one of 4.x's walks, radius r m. */
static sss_material walk(int32_t calibration, float r, float albedo)
{
	sss_material m;
	sss_material_default(&m, SSS_PROFILE_BURLEY);
	m.pass_index = 1;
	m.calibration = calibration;
	m.burley_mapping = SSS_BURLEY_CYCLES_RANDOM_WALK;
	for (int c = 0; c < 3; c++) {
		m.albedo[c] = albedo;
		m.radius[c] = r;
	}
	return m;
}

/* The scattered light with the crease term (crease 1), without it but
 * with the blur stopped at creases (2: what the term adds to), or with
 * neither (0), into out (3 x n x n). */
static sss_result run(frame *f, const sss_material *m, int crease,
                      float *out)
{
	f->opt.crease = crease;
	sss_image ol = {out, f->n, f->n, 3, 0};
	return sss_apply(&f->ps, &f->cam, m, 1, &f->opt, NULL, &ol, NULL, 0);
}

/* Per unit length of edge, in metres times light: what the crease term
 * added to the upper face (sum over its rows of a middle column, each row
 * the length of face it covers) and to the lower one; and the lower
 * face's light far from the edge. */
static void crease_sums(const frame *f, const float *with,
                        const float *without, double *upper, double *lower,
                        double *plateau)
{
	int n = f->n, x = n / 2;
	*upper = *lower = 0.0;
	for (int y = 1; y < n - 1; y++) {
		int i = 3 * (y * n + x);
		/* the next row further from the edge, on the same face */
		const double *a = f->pt + i, *b = f->pt + i + (y < n / 2 ? -3 * n
		                                                          : 3 * n);
		double step = sqrt((b[0] - a[0]) * (b[0] - a[0]) +
		                   (b[1] - a[1]) * (b[1] - a[1]) +
		                   (b[2] - a[2]) * (b[2] - a[2]));
		double d = (double)with[i] - without[i];
		if (y < n / 2)
			*upper += d * step;
		else
			*lower += fabs(d) * step;
	}
	*plateau = with[3 * ((n - 3) * n + x)];
}

/* The walks at 3 cm, but 4.x's plain Random Walk, whose light stays much
 * closer to the edge (d = 0.03 - 0.19 of the radius), at 7 cm and 128
 * pixels or more so that its d spans a pixel and its tail the face. */
/* The calibration's gain for the view angle at row y of the lit (lower)
 * face, whose normal is (0, -1, -1) / sqrt 2, in the frame's middle
 * column; the camera at the origin looking along +z. */
static double view_gain(const frame *f, const sss_material *m, int y)
{
	const double *p = f->pt + 3 * (y * f->n + f->n / 2);
	double len = f->cam.type == SSS_CAMERA_PERSPECTIVE
	             ? sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) : 1.0;
	double cosv = f->cam.type == SSS_CAMERA_PERSPECTIVE
	              ? (p[1] + p[2]) / sqrt(2.0) / len : sqrt(0.5);
	float g[3];
	sss_calibration_gain(m, m->albedo, (float)cosv, g);
	return g[0];
}

static void test_wedge(int32_t calibration, float radius, int small,
                       int perspective)
{
	const float albedos[] = {0.3f, 0.55f, 0.85f};
	const int sizes[] = {small, 192};
	for (int a = 0; a < 3; a++) {
		double per_d[2];
		for (int s = 0; s < 2; s++) {
			frame f;
			frame_make(&f, sizes[s], WEDGE, albedos[a], 1.0, perspective);
			sss_material m = walk(calibration, radius, albedos[a]);
			float *without = malloc(sizeof(float) * 3 * f.n * f.n);
			CHECK_STATUS("wedge-status", SSS_OK, run(&f, &m, 1, f.out));
			CHECK_STATUS("wedge-off-status", SSS_OK,
			             run(&f, &m, 2, without));
			double up, low, plateau;
			crease_sums(&f, f.out, without, &up, &low, &plateau);
			float kappa, gamma, lkappa, lgamma;
			sss__crease_params(m.calibration, albedos[a], &kappa, &gamma);
			sss__crease_loss_params(m.calibration, albedos[a], &lkappa,
			                        &lgamma);
			/* the integral of F over t is 0.7958 d, of the light at the
			 * edge: in perspective the lit face is seen there at another
			 * angle than at the far row, and the walk's energy follows
			 * the view (plain Random Walk's by 8 % here) */
			double at_edge = plateau * view_gain(&f, &m, f.n / 2 + 2) /
			                 view_gain(&f, &m, f.n - 3);
			double want = kappa * 0.7958 * gamma * radius * at_edge;
			double lost = lkappa * 0.7958 * lgamma * radius * at_edge;
			per_d[s] = up / want;
			CHECK("wedge-total", fabs(up / want - 1.0) < 0.05,
			      "calibration %d, albedo %g, %d px, perspective %d: the "
			      "unlit face gained %g, expected %g", (int)calibration,
			      (double)albedos[a], f.n, perspective, up, want);
			CHECK("wedge-lit-face", lost > 0.0 &&
			      fabs(low / lost - 1.0) < 0.1,
			      "calibration %d, albedo %g, %d px, perspective %d: the "
			      "lit face lost %g, expected %g", (int)calibration,
			      (double)albedos[a], f.n, perspective, low, lost);
			free(without);
			frame_free(&f);
		}
		CHECK("wedge-pixel-size", fabs(per_d[0] / per_d[1] - 1.0) < 0.05,
		      "calibration %d, albedo %g: %g at %d px, %g at 192 px",
		      (int)calibration, (double)albedos[a], per_d[0], small,
		      per_d[1]);
	}
}

/* Nothing where there is no crease, without a calibration, with the
 * option off; nothing left as the radius vanishes. */
static void test_none(void)
{
	const enum shape shapes[] = {PLANE, SPHERE};
	for (int s = 0; s < 2; s++) {
		frame f;
		frame_make(&f, 96, shapes[s], 0.6f, 1.0, 0);
		sss_material m = walk(SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN, 0.03f, 0.6f);
		float *without = malloc(sizeof(float) * 3 * 96 * 96);
		CHECK_STATUS("none-status", SSS_OK, run(&f, &m, 1, f.out));
		CHECK_STATUS("none-off-status", SSS_OK, run(&f, &m, 0, without));
		CHECK("none-smooth", !memcmp(f.out, without,
		                             sizeof(float) * 3 * 96 * 96),
		      "shape %d: the crease term changed a surface without one", s);
		free(without);
		frame_free(&f);
	}
	frame f;
	frame_make(&f, 96, WEDGE, 0.6f, 1.0, 0);
	float *without = malloc(sizeof(float) * 3 * 96 * 96);
	sss_material m = walk(SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN, 0.03f, 0.6f);
	m.calibration = SSS_CALIBRATION_NONE;
	CHECK_STATUS("none-cal-status", SSS_OK, run(&f, &m, 1, f.out));
	CHECK_STATUS("none-cal-off-status", SSS_OK, run(&f, &m, 0, without));
	CHECK("none-uncalibrated", !memcmp(f.out, without,
	                                   sizeof(float) * 3 * 96 * 96),
	      "a material without a calibration gained crease light");
	/* As the radius vanishes, so does what crosses the edge. */
	double last = INFINITY;
	int falls = 1;
	for (float r = 0.01f; r > 1e-7f; r *= 0.1f) {
		m = walk(SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN, r, 0.6f);
		run(&f, &m, 1, f.out);
		run(&f, &m, 2, without);
		double up, low, plateau;
		crease_sums(&f, f.out, without, &up, &low, &plateau);
		falls &= up <= last;
		last = up;
	}
	CHECK("none-vanishing", falls && last < 1e-9, "at 1e-7 m the unlit "
	      "face still gains %g", last);
	free(without);
	frame_free(&f);
}

/* A lit face 12 mm wide under a radius of 1 m: the walk spreads its light
 * over everything, and what crosses the edge is at most what entered
 * that face, not the measured half-space's kappa x 0.8 d. */
static void test_narrow(void)
{
	frame f;
	frame_make(&f, 96, WEDGE, 0.6f, 0.012, 0);
	float *without = malloc(sizeof(float) * 3 * 96 * 96);
	sss_material m = walk(SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN, 1.0f, 0.6f);
	CHECK_STATUS("narrow-status", SSS_OK, run(&f, &m, 1, f.out));
	CHECK_STATUS("narrow-off-status", SSS_OK, run(&f, &m, 2, without));
	double up, low, plateau;
	crease_sums(&f, f.out, without, &up, &low, &plateau);
	float kappa, gamma;
	sss__crease_params(m.calibration, 0.6f, &kappa, &gamma);
	double entered = 0.012 * without[3 * ((f.n / 2 + 1) * f.n + f.n / 2)];
	double half_space = kappa * 0.7958 * gamma * 1.0 * entered / 0.012;
	CHECK("narrow-bounded", up > 0.0 && up < 0.5 * entered &&
	      up < 0.01 * half_space, "gained %g: the face took in %g, a "
	      "half-space would give %g", up, entered, half_space);
	free(without);
	frame_free(&f);
}

/* A kept frame's workspace keeps the geometry (points, bends, normals,
 * creases) while the camera, the slot map and the materials taking the
 * term stay, and makes it again when one changes: every scatter through
 * it equals sss_apply's without one, bit for bit. */
static void test_kept_geometry(void)
{
	frame f;
	frame_make(&f, 64, WEDGE, 0.6f, 1.0, 0);
	size_t n = (size_t)3 * f.n * f.n;
	float *want = malloc(sizeof(float) * n), *off = malloc(sizeof(float) * n);
	sss__workspace *ws = sss__workspace_new();
	/* radius, the camera's width, the material's pass index, rows of
	 * the index pass cleared: the second reuses the first's geometry (and
	 * planes), the third needs them made again for the camera, the fourth
	 * for the slot map (the material off the table), the fifth again, the
	 * sixth for the slot map (a quarter of the rows no longer scatter),
	 * the seventh for it back */
	const struct { float radius; double view; int index, cut; } steps[] = {
		{0.03f, VIEW, 1, 0}, {0.05f, VIEW, 1, 0}, {0.05f, 1.5 * VIEW, 1, 0},
		{0.05f, 1.5 * VIEW, 2, 0}, {0.03f, VIEW, 1, 0}, {0.03f, VIEW, 1, 1},
		{0.03f, VIEW, 1, 0}};
	float *idx = malloc(sizeof(float) * f.n * f.n);
	if (idx)
		memcpy(idx, f.idx, sizeof(float) * f.n * f.n);
	for (int k = 0; ws && want && off && idx && k < 7; k++) {
		sss_material m = walk(SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN, steps[k].radius, 0.6f);
		m.pass_index = steps[k].index;
		f.cam.ortho_scale = steps[k].view;
		for (int i = 0; i < f.n * f.n; i++)
			f.idx[i] = steps[k].cut && i < f.n * f.n / 4 ? 0.0f : idx[i];
		CHECK_STATUS("kept-want", SSS_OK, run(&f, &m, 1, want));
		sss_image ol = {f.out, f.n, f.n, 3, 0};
		CHECK_STATUS("kept-status", SSS_OK,
		             sss__apply_report(&f.ps, &f.cam, &m, 1, &f.opt, NULL,
		                               &ol, NULL, ws, NULL, NULL, 0));
		CHECK("kept-same", memcmp(f.out, want, sizeof(float) * n) == 0,
		      "scatter %d through a kept workspace differs from sss_apply's",
		      k);
		if (k == 0) {
			CHECK_STATUS("kept-off", SSS_OK, run(&f, &m, 0, off));
			CHECK("kept-crease-counts",
			      memcmp(off, want, sizeof(float) * n) != 0,
			      "the crease term added nothing: the test cannot fail");
		}
	}
	sss__workspace_free(ws);
	free(idx);
	free(want);
	free(off);
	frame_free(&f);
}

int main(void)
{
	test_kept_geometry();
	for (int p = 0; p < 2; p++) {
		test_wedge(SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN, 0.03f, 64, p);
		test_wedge(SSS_CALIBRATION_CYCLES4_RANDOM_WALK, 0.07f, 128, p);
		test_wedge(SSS_CALIBRATION_CYCLES_RANDOM_WALK, 0.03f, 64, p);
	}
	test_none();
	test_narrow();
	return tu_finish("test_crease");
}
