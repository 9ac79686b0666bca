/* sss_transmission.c - back-lit transmission: light that reaches the back
 * of a thin part and crosses it, added to the diffuse light after the
 * blur: across a part of thickness t the light spreads sideways over
 * about t, and where T(t) matters t is below the profile's reach, so the
 * radius-wide blur would smear it (transmission.md, "Not blurred").
 *
 * Inputs per pixel: B, the light arriving from behind (the DiffDir and
 * DiffInd of a view layer whose material override is a white Translucent
 * BSDF: Cycles shades the visible point with the light that reaches it
 * through the object, shadows included), and t, the object's local
 * thickness there. The added light is strength x T(t) x B with T <= 1; the
 * diffuse colour (the albedo A) multiplies it like all diffuse light, so
 * T(0) = 1 here is A in the final image: the albedo-consistent maximum of
 * the models below.
 *
 * Models (sss_transmission in sss.h):
 *  - burley: for a Burley profile, the share of the light entering the
 *    back face of a slab of thickness t that leaves by the front, from
 *    steady-state 1-D diffusion in the slab with the medium Cycles' random
 *    walk itself uses (see slab_make below); for Blender 4.x's Random
 *    Walk (Skin) that walk's own, measured (walk4_make below). For a sum
 *    of 2-D Gaussians sum w_i G(v_i) (d'Eon, Jimenez, near/far profiles:
 *    no medium behind them) the profile's own mass beyond a plane at
 *    distance t, sum w_i e^{-t^2 / 2 v_i} (Golubev 2018, UE4, HDRP).
 *  - jimenez: Jimenez et al. 2010 (SeparableSSS.h SSSSTransmittance):
 *    d'Eon's skin sum w_i e^{-s^2 / v_i} with s = t 8.25 (1 - translucency)
 *    / sssWidth (sssWidth = the material's jimenez_width).
 *  - beer-lambert: colour^(t / distance), the artist-friendly form of
 *    e^{-c t} (seed 001, SetTransmittanceCoefficientByDistance).
 *  - fast: Barre-Brisebois & Bouchard, GDC 2011:
 *    (saturate(V . -(L + N delta))^p scale + ambient) x thinness. Cycles
 *    gives no per-pixel light direction (many lights, area lights,
 *    the world), but B already holds the light's intensity, distance and
 *    shadowing (their fLightAttenuation); the light that crossed the part
 *    leaves it along its normal, so L = -N and V . -(L + N delta) =
 *    (1 - delta) N . V (the facing pass; 1 when absent). Thinness is
 *    max(0, 1 - t / distance) in place of their baked local-thickness
 *    map. Capped at 1 so that no more light leaves than arrived.
 */
#include "sss_internal.h"
#include "sss_transmission.h"

#include <stdlib.h>
#include <string.h>

#define FAIL(...) sss__fail(errbuf, errbuf_len, SSS_ERR_INVALID_ARGUMENT, \
                            __VA_ARGS__)

/* One material, in scene units. */
typedef struct tmat {
	int32_t model;          /* sss_transmission; OFF = nothing */
	double gain[3];         /* strength x colour (Beer-Lambert: strength) */
	double thickness_scale;
	/* burley: per channel, the slab's diffusion (Burley profile, n = 0)
	 * or a Gaussian sum (n > 0) */
	int n[3];
	double d[3];
	double mfp[3];                   /* the slab's mean free path */
	double sigma_tr[3], a[3], zb[3]; /* slab_make */
	double edge[3];                  /* slab_edge */
	/* Blender 4.x's walk (walk4_make): its table (NULL: the slab), the
	 * table's albedo row below the channel's, the blend towards the next,
	 * each row's slab with l = 1 (sigma_tr, a, zb) for beyond the table,
	 * and the cap on T */
	const sss__walk4_table *walk4[3];
	int w4row[3];
	double w4f[3], w4unit[3][2][3], cap[3];
	double var[3][SSS_MAX_GAUSSIANS], w[3][SSS_MAX_GAUSSIANS];
	/* jimenez: s (mm of d'Eon's profile) per scene unit of thickness */
	double s_per_unit;
	/* beer-lambert and fast: scene units; colour for Beer-Lambert */
	double distance;
	double colour[3];
	/* fast */
	double distortion, power, scale, ambient;
	/* T at thickness 0, made once: a baked back light (the slab's
	 * attenuation in the light already) reads 0 at every pixel. Not for
	 * the fast model, whose T follows the facing pass. */
	int has_T0;
	double T0[3];
	int baked; /* transmission_baked_scale > 0 */
} tmat;

struct sss__transmission {
	sss_image back_dir, back_ind, thickness, facing;
	tmat *mats; /* material_count entries */
};

/* ----------------------------------------------------------------- models */

/* ------------------------------------------- the slab (burley model)
 *
 * The medium: Cycles 3.4's random walk (kernel/integrator/
 * subsurface_random_walk.h, subsurface_random_walk_remap with g = 0, and
 * kernel/closure/bssrdf.h, bssrdf_setup_radius) turns the surface albedo
 * A and the radius r of a channel into a homogeneous isotropic medium with
 * mean free path l = 1 / sigma_t = r sqrt(3 (1 - a')) (a' inverts Jensen's
 * dipole reflectance at IOR 1.4, as in sss_calibration.c) and
 * single-scattering albedo alpha(A) (Chiang, Kutz & Burley 2016, the g = 0
 * coefficients of Cycles' fit). The library's Burley d for that mapping is
 * l / s(A) (s = 1.9 - A + 3.5 (A - 0.8)^2, Cycles' searchlight fit); for
 * the other mappings l = d s(A) is the medium with the same d.
 *
 * Light that enters the back face is first scattered at depth
 * z0 = 2 l / 3 (the mean depth of a cosine-distributed first flight) and
 * diffuses with Grosjean's coefficient D = (2 sigma_a + sigma_s) /
 * (3 sigma_t^2) = (2 - alpha) l / 3 (as in photon beam diffusion, Habel
 * et al. 2013), transport coefficient sigma_tr = sqrt(sigma_a / D), and a
 * matched boundary (the walk leaves wherever it reaches the surface: no
 * internal reflection) extrapolated by zb = 2 D. The 1-D steady-state
 * diffusion equation between the extrapolated boundaries, distance
 * L = t + 2 zb apart, with the source at a = z0 + zb from the entry's,
 * has the Green's function sinh(sigma_tr x) sinh(sigma_tr (L - a)) /
 * (sigma_tr D sinh(sigma_tr L)) (x <= a), so of the light that enters, the
 * front face lets out sinh(sigma_tr a) / sinh(sigma_tr L) and the back face
 * sinh(sigma_tr (L - a)) / sinh(sigma_tr L) (Ishimaru 1978, ch. 9; the
 * slab form of Contini et al. 1997). A semi-infinite medium (L -> inf)
 * returns e^{-sigma_tr a} by the face it entered: that is what the albedo
 * A stands for once DiffCol multiplies the light, so
 *
 *   T(t) = sinh(sigma_tr a) / sinh(sigma_tr L) / e^{-sigma_tr a}
 *        = (1 - e^{-2 sigma_tr a}) e^{-sigma_tr (L - 2 a)}
 *          / (1 - e^{-2 sigma_tr L}),          L = max(t + 2 zb, 2 a),
 *
 * and a / L without absorption. L >= 2 a (a slab thinner than the source
 * depth is read as that thick) keeps T <= 1 and non-increasing in t; T(0)
 * = 1 / (1 + e^{-2 sigma_tr a}) is about 1/2: about half of what enters a
 * thin part leaves by the face it entered. Against Cycles 3.4's random
 * walk on a skin slab lit only from behind (measure_transmission.py
 * --slab-sweep; docs/transmission.md) this T is within about 10 %
 * for every channel from 0.5 to 4 cm and two radii; the profile's mass
 * beyond t (this model before) was 3-6 times too low. */

/* Cycles' single-scattering albedo for surface albedo A, g = 0. */
static double rw_alpha(double A)
{
	const double ca = 1.8260523782, cb = 4.98511194385 + 0.127355959438,
	             cc = 1.09686102424, cd = 0.496310210422,
	             ce = 4.23190299701 + 0.00310603949088,
	             cf = 2.40602999408;
	if (!(A > 0.0))
		return 0.0;
	if (A > 1.0)
		A = 1.0;
	double blend = pow(A, 0.25);
	double a = (1.0 - blend) * ca * pow(atan(cb * A), cc) +
	           blend * cd * pow(atan(ce * A), cf);
	return a < 0.0 ? 0.0 : a > 0.999999 ? 0.999999 : a;
}

/* The slab's sigma_tr, a and zb for one channel: mean free path l (scene
 * units, > 0) and surface albedo A. */
static void slab_make(double l, double A, double *sigma_tr, double *a,
                      double *zb)
{
	double alpha = rw_alpha(A);
	double D = (2.0 - alpha) * l / 3.0;
	*sigma_tr = sqrt(3.0 * (1.0 - alpha) / (2.0 - alpha)) / l;
	*zb = 2.0 * D;
	*a = 2.0 * l / 3.0 + *zb;
}

/* T(t) of the slab above, t >= 0 (+Inf allowed). */
static double slab_eval_c(double sigma_tr, double a, double zb,
                          double edge, double t)
{
	double L = t + 2.0 * zb;
	if (!(L > 2.0 * a))
		L = 2.0 * a;
	if (isinf(L))
		return 0.0;
	double x = sigma_tr * L;
	if (x < 1e-6)
		return a / L; /* no absorption: the linear flux profile */
	double y = sigma_tr * a;
	/* Past x = 20, 1 - e^-2x is 1 in doubles (e^-40 is far below half
	 * the spacing below 1): the same value without its exponential. */
	double below = x > 20.0 ? 1.0 : -expm1(-2.0 * x);
	double T = edge * exp(-(x - 2.0 * y)) / below;
	return T < 1.0 ? T : 1.0;
}

/* The slab's edge factor 1 - e^-2y, y = sigma_tr a: one per channel. */
static double slab_edge(double sigma_tr, double a)
{
	return -expm1(-2.0 * (sigma_tr * a));
}

static double slab_eval(double sigma_tr, double a, double zb, double t)
{
	return slab_eval_c(sigma_tr, a, zb, slab_edge(sigma_tr, a), t);
}

/* ------------------------------------------- Blender 4.x's walk
 *
 * Blender 4.x's Random Walk (Skin) is 3.4's Random Walk with the same
 * radius mapping (sss_calibration.c, section 3) but carries more light
 * through a thin slab than the slab above: the walk's light that crosses
 * after few scatterings is not multiplied by the albedo, as this model's
 * (times DiffCol) is, so the walk over the slab is 1.1 - 1.9 at A 0.6 -
 * 0.95 and up to 16 at A 0.05 where the slab is a quarter of a mean free
 * path. Measured on Blender 4.5.15 over t / l = 0.25 .. 90 and A = 0.05 ..
 * 0.95 (scripts/measure_transmission4.sh, docs/transmission.md) and
 * tabulated as ln T (sss_walk4_skin_table.c, scripts/fit_transmission4.py):
 * T is read linearly in x = t / l along the table's two albedo rows
 * around A and blended linearly in A (in ln T), each row non-increasing,
 * so T is too. Beyond the last column each row follows its slab's decay
 * (T over the slab held); outside the rows' albedos the nearest row. T
 * is the light the library multiplies by the albedo (and the
 * calibration's gain) afterwards, so it exceeds 1 where the walk lets
 * more through than A: it is capped at 1 / A (A T <= 1, no more light
 * leaves than arrived). Materials whose calibration is
 * SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN with the cycles-random-walk
 * mapping use it. 4.x's plain Random Walk (the method of a new material)
 * has its own table, measured the same way (sss_walk4_rw_table.c, where
 * the slab was up to 245 times off), for the calibration and mapping
 * SSS_CALIBRATION_CYCLES4_RANDOM_WALK / SSS_BURLEY_CYCLES4_RANDOM_WALK.
 * 3.x's (SSS_CALIBRATION_CYCLES_RANDOM_WALK) and every other material
 * keep the slab above. */

/* The measured table of mat's walk, or NULL: the slab. */
static const sss__walk4_table *walk4_table(const sss_material *mat)
{
	if (mat->calibration == SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN &&
	    mat->burley_mapping == SSS_BURLEY_CYCLES_RANDOM_WALK)
		return &sss__walk4_skin;
	if (mat->calibration == SSS_CALIBRATION_CYCLES4_RANDOM_WALK &&
	    mat->burley_mapping == SSS_BURLEY_CYCLES4_RANDOM_WALK)
		return &sss__walk4_rw;
	return NULL;
}

void sss__walk4_albedo_row(const float *an, double A, int *row, double *f)
{
	double a = A < an[0] ? an[0] : A > an[SSS__WALK4_NA - 1]
	           ? an[SSS__WALK4_NA - 1] : A;
	int i = 0;
	while (i < SSS__WALK4_NA - 2 && a >= an[i + 1])
		i++;
	*row = i;
	*f = (a - an[i]) / (an[i + 1] - an[i]);
}

static void walk4_make(tmat *m, int c, double A,
                       const sss__walk4_table *table)
{
	const float *an = table->albedo;
	int i;
	sss__walk4_albedo_row(an, A, &i, &m->w4f[c]);
	m->walk4[c] = table;
	m->w4row[c] = i;
	for (int k = 0; k < 2; k++) {
		double *u = m->w4unit[c][k];
		slab_make(1.0, an[i + k], &u[0], &u[1], &u[2]);
	}
	m->cap[c] = 1.0 / (A > an[0] ? A : an[0]);
}

/* ln T of the table's row k at x = t / l >= 0 (+Inf allowed). */
static double walk4_row(const sss__walk4_table *table, int k,
                        const double unit[3], double x)
{
	const float *xs = table->x, *r = table->ln_t[k];
	const int n = SSS__WALK4_NX;
	if (x >= xs[n - 1])
		return r[n - 1] + log(slab_eval(unit[0], unit[1], unit[2], x)) -
		       log(slab_eval(unit[0], unit[1], unit[2], xs[n - 1]));
	int j = 0;
	while (j < n - 2 && x >= xs[j + 1])
		j++;
	double f = (x - xs[j]) / (xs[j + 1] - xs[j]);
	return r[j] + f * (r[j + 1] - r[j]);
}

static double walk4_eval(const tmat *m, int c, double t)
{
	double x = t / m->mfp[c], f = m->w4f[c];
	int i = m->w4row[c];
	const sss__walk4_table *tb = m->walk4[c];
	double v = f < 1.0 ? walk4_row(tb, i, m->w4unit[c][0], x)
	                   : walk4_row(tb, i + 1, m->w4unit[c][1], x);
	if (f > 0.0 && f < 1.0)
		v = (1.0 - f) * v + f * walk4_row(tb, i + 1, m->w4unit[c][1], x);
	double T = exp(v);
	return T < m->cap[c] ? T : m->cap[c];
}

/* T(t) of channel c's medium: the slab, or Blender 4.x's walk. */
static double medium_eval(const tmat *m, int c, double t)
{
	return m->walk4[c] ? walk4_eval(m, c, t)
	                   : slab_eval_c(m->sigma_tr[c], m->a[c], m->zb[c],
	                                 m->edge[c], t);
}

/* len: scene units per metre of profile length (radius_scale/unit_scale). */
static void tmat_make(const sss_material *mat, const sss_options *opt,
                      double unit_scale, tmat *m)
{
	memset(m, 0, sizeof *m);
	m->model = mat->kind == SSS_PROFILE_NONE ? SSS_TRANSMISSION_OFF
	                                         : mat->transmission;
	if (m->model == SSS_TRANSMISSION_OFF)
		return;
	double len = (double)opt->radius_scale / unit_scale;
	for (int c = 0; c < 3; c++) {
		m->cap[c] = 1.0;
		m->gain[c] = mat->transmission_strength;
		if (m->model != SSS_TRANSMISSION_BEER_LAMBERT)
			m->gain[c] *= mat->transmission_color[c];
		m->colour[c] = mat->transmission_color[c];
	}
	m->thickness_scale = mat->thickness_scale;
	m->baked = mat->transmission_baked_scale > 0.0f;
	m->distance = (double)mat->transmission_distance * len;
	m->distortion = mat->transmission_distortion;
	m->power = mat->transmission_power;
	m->scale = mat->transmission_scale;
	m->ambient = mat->transmission_ambient;
	switch (m->model) {
	case SSS_TRANSMISSION_BURLEY:
		for (int c = 0; c < 3; c++) {
			m->n[c] = sss__profile_gaussians(mat, opt, len, c,
			                                 m->var[c], m->w[c], &m->d[c]);
			if (m->n[c] != 0 || !(m->d[c] > 0.0))
				continue;
			double A = mat->albedo[c];
			double l = mat->burley_mapping ==
			           SSS_BURLEY_CYCLES_RANDOM_WALK
			           ? (double)mat->radius[c] * len *
			             sss__cycles_rw_mfp_over_radius(A)
			           : m->d[c] * (1.9 - A + 3.5 * (A - 0.8) * (A - 0.8));
			if (!(l > 0.0) || !isfinite(l)) {
				m->d[c] = 0.0;
				continue;
			}
			m->mfp[c] = l;
			slab_make(l, A, &m->sigma_tr[c], &m->a[c], &m->zb[c]);
			m->edge[c] = slab_edge(m->sigma_tr[c], m->a[c]);
			const sss__walk4_table *table = walk4_table(mat);
			if (table)
				walk4_make(m, c, A, table);
		}
		break;
	case SSS_TRANSMISSION_JIMENEZ: {
		/* s = t 8.25 (1 - translucency) / sssWidth, both lengths in the
		 * same unit; s is then in mm of d'Eon's profile. */
		double width = (double)mat->jimenez_width * len;
		double k = 8.25 * (1.0 - (double)mat->transmission_translucency);
		m->s_per_unit = k == 0.0 ? 0.0 : width > 0.0 ? k / width
		                                              : INFINITY;
		break;
	}
	default:
		break;
	}
}

/* exp(-a * t) for a, t >= 0 with 0 * inf read as 0 (no attenuation). */
static double decay(double a, double t)
{
	if (a == 0.0 || t == 0.0)
		return 1.0;
	return exp(-a * t);
}

/* T per channel at thickness t >= 0 (scene units, +Inf allowed). */
static void tmat_eval(const tmat *m, double t, double facing, double out[3])
{
	for (int c = 0; c < 3; c++) {
		double T = 0.0;
		switch (m->model) {
		case SSS_TRANSMISSION_BURLEY:
			if (m->n[c] == 0) {
				if (m->d[c] > 0.0)
					T = medium_eval(m, c, t);
				else
					T = t == 0.0 ? 1.0 : 0.0;
			} else {
				for (int i = 0; i < m->n[c]; i++)
					T += m->w[c][i] * (m->var[c][i] > 0.0
					     ? decay(1.0 / (2.0 * m->var[c][i]), t * t)
					     : (t == 0.0 ? 1.0 : 0.0));
			}
			break;
		case SSS_TRANSMISSION_JIMENEZ: {
			double s = m->s_per_unit == 0.0 || t == 0.0
			           ? 0.0 : m->s_per_unit * t;
			double sum = 0.0; /* the weights' sum, 1 up to rounding */
			for (int i = 0; i < 6; i++) {
				double wi = (double)sss__deon_weight[i][c];
				sum += wi;
				T += wi * decay(1.0 / (double)sss__deon_variance[i], s * s);
			}
			T /= sum;
			break;
		}
		case SSS_TRANSMISSION_BEER_LAMBERT: {
			double col = m->colour[c];
			if (t == 0.0 || col >= 1.0)
				T = 1.0;
			else if (col <= 0.0 || !(m->distance > 0.0))
				T = 0.0;
			else
				T = decay(-log(col) / m->distance, t);
			break;
		}
		case SSS_TRANSMISSION_FAST: {
			double thin = m->distance > 0.0 ? 1.0 - t / m->distance
			                                : (t == 0.0 ? 1.0 : 0.0);
			if (!(thin > 0.0))
				break;
			double f = isfinite(facing) ? facing : 1.0;
			f = (1.0 - m->distortion) * f;
			f = f < 0.0 ? 0.0 : f > 1.0 ? 1.0 : f;
			double v = (pow(f, m->power) * m->scale + m->ambient) * thin;
			T = v < 1.0 ? v : 1.0;
			break;
		}
		default:
			break;
		}
		/* Rounding must not let more light out than came in. */
		out[c] = m->gain[c] * (T < m->cap[c] ? T : m->cap[c]);
	}
}

/* A valid copy of mat (any table key) made into a tmat in metres. */
static sss_result tmat_in_metres(const sss_material *mat, sss_material *v,
                                 tmat *m)
{
	if (!mat)
		return SSS_ERR_INVALID_ARGUMENT;
	*v = *mat;
	v->pass_index = 1; /* the table key plays no part */
	sss_result r = sss_material_validate(v, NULL, 0);
	if (r)
		return r;
	sss_options opt;
	sss_options_default(&opt);
	tmat_make(v, &opt, 1.0, m);
	return SSS_OK;
}

sss_result sss_transmittance(const sss_material *mat, double thickness,
                             double facing, double out[3])
{
	sss_material v;
	tmat m;
	sss_result r = out ? tmat_in_metres(mat, &v, &m)
	                   : SSS_ERR_INVALID_ARGUMENT;
	if (r)
		return r;
	out[0] = out[1] = out[2] = 0.0;
	if (!(thickness >= 0.0))
		return SSS_OK; /* NaN or negative: unknown, nothing crosses */
	double t = m.thickness_scale == 0.0 ? 0.0 : thickness * m.thickness_scale;
	tmat_eval(&m, t, facing, out);
	return SSS_OK;
}

/* The thickness where the slab lets less than `level` through: at most
 * `mfps` mean free paths (without absorption it falls only as a / L). */
static double slab_reach(const tmat *m, int c, double level, double mfps)
{
	double hi = mfps * m->mfp[c];
	if (medium_eval(m, c, hi) >= level)
		return hi;
	double lo = 0.0;
	for (int i = 0; i < 60; i++) {
		double mid = 0.5 * (lo + hi);
		if (medium_eval(m, c, mid) >= level)
			lo = mid;
		else
			hi = mid;
	}
	return hi;
}

sss_result sss_transmission_reach(const sss_material *mat, double *metres)
{
	sss_material v;
	tmat m;
	sss_result r = metres ? tmat_in_metres(mat, &v, &m)
	                      : SSS_ERR_INVALID_ARGUMENT;
	if (r)
		return r;
	double reach = 0.0;
	switch (m.model) {
	case SSS_TRANSMISSION_BURLEY:
		if (v.kind != SSS_PROFILE_BURLEY) /* Gaussian sums: 1e-5 left */
			return sss_material_support(&v, metres);
		for (int c = 0; c < 3; c++)
			if (m.n[c] == 0 && m.d[c] > 0.0) {
				double s = slab_reach(&m, c, 0.01, 100.0);
				reach = s > reach ? s : reach;
			}
		break;
	case SSS_TRANSMISSION_JIMENEZ: {
		/* d'Eon's sum w e^{-s^2/v} is below 1 % at s = 5 mm. */
		double k = 8.25 * (1.0 - (double)v.transmission_translucency);
		if (!(k > 0.0))
			return sss_material_support(&v, metres);
		reach = 5.0 * (double)v.jimenez_width / k;
		break;
	}
	case SSS_TRANSMISSION_BEER_LAMBERT: {
		double c = v.transmission_color[0];
		for (int i = 1; i < 3; i++)
			c = v.transmission_color[i] > c ? v.transmission_color[i] : c;
		c = c < 1e-3 ? 1e-3 : c > 0.999 ? 0.999 : c;
		reach = m.distance * log(0.01) / log(c);
		break;
	}
	case SSS_TRANSMISSION_FAST: /* gone at the distance */
		reach = m.distance;
		break;
	default:
		break;
	}
	*metres = reach;
	return SSS_OK;
}

sss_result sss_transmission_slab(const sss_material *mat, double sigma_tr[3],
                                 double a[3], double zb[3])
{
	sss_material v;
	tmat m;
	sss_result r = sigma_tr && a && zb ? tmat_in_metres(mat, &v, &m)
	                                   : SSS_ERR_INVALID_ARGUMENT;
	if (r)
		return r;
	if (m.model != SSS_TRANSMISSION_BURLEY || v.kind != SSS_PROFILE_BURLEY)
		return SSS_ERR_UNSUPPORTED;
	for (int c = 0; c < 3; c++) {
		int slab = m.n[c] == 0 && m.d[c] > 0.0;
		sigma_tr[c] = slab ? m.sigma_tr[c] : 0.0;
		a[c] = slab ? m.a[c] : 0.0;
		zb[c] = slab ? m.zb[c] : 0.0;
	}
	return SSS_OK;
}

/* sss_transmission_table: where its samples end, relative to T(0), and
 * in mean free paths at most; the evenly spaced samples' spacing near 0,
 * in mean free paths. */
#define TABLE_FLOOR 1e-6
#define TABLE_MFPS 1e6
#define TABLE_STEP_MFPS 0.25

sss_result sss_transmission_table(const sss_material *mat, int32_t n,
                                  float *table, double *step, double *span)
{
	sss_material v;
	tmat m;
	sss_result r = table && step && span && n >= 2
	               ? tmat_in_metres(mat, &v, &m) : SSS_ERR_INVALID_ARGUMENT;
	if (r)
		return r;
	if (m.model != SSS_TRANSMISSION_BURLEY || v.kind != SSS_PROFILE_BURLEY)
		return SSS_ERR_UNSUPPORTED;
	int medium[3];
	double T0[3], end = 0.0, l = INFINITY;
	for (int c = 0; c < 3; c++) {
		medium[c] = m.n[c] == 0 && m.d[c] > 0.0;
		if (!medium[c])
			continue;
		T0[c] = medium_eval(&m, c, 0.0);
		double e = slab_reach(&m, c, TABLE_FLOOR * T0[c], TABLE_MFPS);
		end = e > end ? e : end;
		l = m.mfp[c] < l ? m.mfp[c] : l;
	}
	/* Slab thicknesses; the table's are the pass's. With no medium at all
	 * any lengths do: 1 mm. */
	double k = m.thickness_scale;
	if (!(end > 0.0))
		end = l = 1e-3;
	double per = k > 0.0 ? 1.0 / k : 1.0;
	*step = TABLE_STEP_MFPS * l * per;
	*span = end * per;
	double g = log1p(*span / *step) / (n - 1);
	for (int32_t i = 0; i < n; i++) {
		double t = k == 0.0 ? 0.0
		         : i == n - 1 ? end : expm1(g * (double)i) * *step * k;
		for (int c = 0; c < 3; c++) {
			double T = !medium[c] ? (t == 0.0 ? 1.0 : 0.0)
			         : medium_eval(&m, c, t) / T0[c];
			if (i == n - 1 && k != 0.0)
				T = 0.0; /* nothing beyond the table */
			table[3 * (size_t)i + (size_t)c] = (float)(T < 1.0 ? T : 1.0);
		}
	}
	return SSS_OK;
}

/* ---------------------------------------------------------------- passes */

static sss_result check_pass(const char *name, const sss_image *im,
                             int32_t channels, int32_t w, int32_t h,
                             const sss_image *outs[2], char *errbuf,
                             size_t errbuf_len)
{
	sss_result r = sss__check_image(name, im, channels, 0, w, h, errbuf,
	                                errbuf_len);
	if (r || !im->data)
		return r;
	const char *lo, *hi;
	sss__span(im, &lo, &hi);
	for (int i = 0; i < 2; i++) {
		const sss_image *o = outs[i];
		if (!o || !o->data || o->width <= 0 || o->height <= 0)
			continue;
		const char *olo, *ohi;
		sss__span(o, &olo, &ohi);
		if (olo < hi && lo < ohi)
			return FAIL("an output overlaps pass %s; inputs are never "
			            "overwritten", name);
	}
	return SSS_OK;
}

sss_result sss__transmission_prepare(const sss_passes *p,
                                     const sss_material *materials,
                                     int32_t count, const sss_options *opt,
                                     double unit_scale, int32_t w, int32_t h,
                                     const sss_image *out_a,
                                     const sss_image *out_b,
                                     sss__transmission **out, char *errbuf,
                                     size_t errbuf_len)
{
	*out = NULL;
	const sss_image *outs[2] = {out_a, out_b};
	const struct {
		const char *name;
		const sss_image *im;
		int32_t channels;
	} passes[] = {
		{"BackDir", &p->back_dir, 3}, {"BackInd", &p->back_ind, 3},
		{"Thickness", &p->thickness, 1}, {"Facing", &p->facing, 1},
	};
	sss_result r;
	for (size_t i = 0; i < sizeof passes / sizeof *passes; i++)
		if ((r = check_pass(passes[i].name, passes[i].im,
		                    passes[i].channels, w, h, outs, errbuf,
		                    errbuf_len)))
			return r;
	int32_t first = -1;
	for (int32_t m = 0; m < count && first < 0; m++)
		if (materials[m].transmission != SSS_TRANSMISSION_OFF &&
		    materials[m].kind != SSS_PROFILE_NONE)
			first = m;
	if (first < 0)
		return SSS_OK;
	if (!p->back_dir.data) {
		if (p->back_ind.data || p->thickness.data)
			return sss__fail(errbuf, errbuf_len, SSS_ERR_MISSING_PASS,
			                 "pass BackDir is required with BackInd or "
			                 "Thickness");
		return SSS_OK; /* no back light: nothing to transmit */
	}
	if (!p->thickness.data)
		return sss__fail(errbuf, errbuf_len, SSS_ERR_MISSING_PASS,
		                 "pass Thickness is required with BackDir: material "
		                 "%d transmits", materials[first].pass_index);
	/* A baked back light crossed the part at the radius scale it was
	 * rendered for: another scale would leave that light as it is (T(0)
	 * does not depend on the scale), so the combination is refused. 0
	 * turns scattering and transmission off, which is exact. */
	for (int32_t m = 0; m < count; m++) {
		float baked = materials[m].transmission_baked_scale;
		if (baked > 0.0f &&
		    materials[m].transmission != SSS_TRANSMISSION_OFF &&
		    materials[m].kind != SSS_PROFILE_NONE &&
		    opt->radius_scale != baked && opt->radius_scale != 0.0f)
			return sss__fail(errbuf, errbuf_len,
			                 SSS_ERR_INVALID_ARGUMENT, "radius_scale %g: "
			                 "material %d's back light crossed it at radius "
			                 "scale %g (transmission_baked_scale), which "
			                 "another scale cannot change: render it again "
			                 "at the new radius, or use 0 (no scattering)",
			                 (double)opt->radius_scale,
			                 materials[m].pass_index, (double)baked);
	}

	sss__transmission *t = calloc(1, sizeof *t);
	tmat *mats = t ? calloc((size_t)count, sizeof *mats) : NULL;
	if (!mats) {
		free(t);
		return sss__fail(errbuf, errbuf_len, SSS_ERR_OUT_OF_MEMORY,
		                 "cannot allocate the transmission table");
	}
	t->mats = mats;
	t->back_dir = p->back_dir;
	t->back_ind = p->back_ind;
	t->thickness = p->thickness;
	t->facing = p->facing;
	for (int32_t m = 0; m < count; m++) {
		tmat *mt = &mats[m];
		tmat_make(&materials[m], opt, unit_scale, mt);
		mt->has_T0 = mt->model != SSS_TRANSMISSION_OFF &&
		             mt->model != SSS_TRANSMISSION_FAST;
		if (mt->has_T0)
			tmat_eval(mt, 0.0, 1.0, mt->T0);
	}
	*out = t;
	return SSS_OK;
}

int sss__transmission_active(const sss__transmission *t, int32_t m)
{
	return t && t->mats[m].model != SSS_TRANSMISSION_OFF;
}

void sss__transmission_add(const sss__transmission *t, int32_t m, int32_t x,
                           int32_t y, float light[3])
{
	const tmat *mt = &t->mats[m];
	if (mt->model == SSS_TRANSMISSION_OFF)
		return;
	double thick = sss__at(&t->thickness, x, y)[0];
	if (!(thick >= 0.0))
		return; /* NaN or negative: no measurement here */
	const float *bd = sss__at(&t->back_dir, x, y);
	const float *bi = t->back_ind.data ? sss__at(&t->back_ind, x, y) : NULL;
	double b[3];
	for (int c = 0; c < 3; c++) {
		b[c] = (double)bd[c] + (bi ? (double)bi[c] : 0.0);
		if (!isfinite(b[c]))
			return; /* never spread a NaN or Inf */
		if (b[c] < 0.0)
			b[c] = 0.0; /* no negative light crosses */
	}
	if (b[0] == 0.0 && b[1] == 0.0 && b[2] == 0.0)
		return; /* no light from behind here: nothing to carry */
	double facing = t->facing.data ? sss__at(&t->facing, x, y)[0] : 1.0;
	/* a baked back light crossed the part already: T(0) whatever the
	 * pass says (the thickness is there for sss_thin.c) */
	double tt = mt->thickness_scale == 0.0 || mt->baked ? 0.0
	            : thick * mt->thickness_scale;
	double T[3];
	if (tt == 0.0 && mt->has_T0)
		memcpy(T, mt->T0, sizeof T);
	else
		tmat_eval(mt, tt, facing, T);
	for (int c = 0; c < 3; c++) {
		double v = (double)light[c] + T[c] * b[c];
		if (isfinite(v) && fabs(v) <= 3.0e38)
			light[c] = (float)v;
	}
}

void sss__transmission_free(sss__transmission *t)
{
	if (!t)
		return;
	free(t->mats);
	free(t);
}
