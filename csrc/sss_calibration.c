/* sss_calibration.c - what Cycles' random-walk SSS does that a blur of
 * the SSS-off render does not, measured on flat slabs
 * (blender_scripts/calibrate.py, Cycles CPU, denoising, adaptive sampling
 * and clamping off): Blender 3.4.1 in sections 1 and 2, 4.5.15 and 5.0.1
 * (4.0 rewrote the random walk) in section 3.
 *
 * 1. Energy. A box 6 x 6 m wide and 4 m deep (2 x 2 x 1 m for the world
 *    runs), Principled BSDF with Specular 0 and Roughness 0.5, Base Color =
 *    Subsurface Color = A per channel, Subsurface 1 with the radius r per
 *    channel (Subsurface Method Random Walk, IOR 1.4), faces an orthographic
 *    camera that sees 0.2 m of its middle at 64 x 64; the mean Combined
 *    over the central 32 x 32 pixels of the random walk over that of the
 *    same material with Subsurface 0 (the add-on's SSS-off render) is g(A).
 *    Three lightings: a uniform white world (r = 0.05 m and 0.2 m, 256
 *    samples), and a sun at 0 and at 60 degrees from the normal (r = 0.05 m,
 *    128 samples). All agree within their standard errors (0.001 - 0.003):
 *
 *      A      world   sun 0   sun 60   table
 *      0.05   1.0106  1.0100  1.0098   1.010
 *      0.1    1.0113  1.0122  1.0119   1.012
 *      0.2    1.0099  1.0119  1.0116   1.011
 *      0.3    1.0112  1.0146  1.0143   1.013
 *      0.4    1.0114                   1.011
 *      0.5    1.0091  1.0136  1.0133   1.012
 *      0.6    1.0103                   1.010
 *      0.7    1.0111  1.0078  1.0076   1.009
 *      0.8    1.0104  1.0135  1.0132   1.012
 *      0.85   1.0110                   1.011
 *      0.9    1.0060  1.0067  1.0065   1.006
 *      0.95   0.9684  0.9679  0.9687   0.968
 *      0.98   0.9401  0.9385  0.9399   0.9405
 *      0.99   0.9309  0.9290  0.9307   0.9315
 *      1.0    0.9197  0.9167  0.9186   0.9225
 *
 *    On a thick slab the random walk returns the diffuse lobe's energy to
 *    about 1 % up to A = 0.9; above it loses light (its walks are cut off
 *    after a fixed number of steps), and the reflectance A g(A) levels off
 *    at about 0.92. The last three entries are moved within their errors
 *    so that A g(A) never decreases. With r = 0.2 m the ratio grows at
 *    A <= 0.1 (1.11 at 0.1, 1.36 at 0.05); such dark channels are rare and
 *    keep the 0.05 m value. The ratio does not depend on the light's
 *    direction, so it is a property of the albedo. Where it goes: a slab
 *    with 2.5 cm stripes of Base Color (0.9, 0.8, 0.7) / (0.3, 0.15, 0.1)
 *    under the sun (r = 0.02 and 0.1 m) renders with the random walk as
 *    crisp as with SSS off (RMSE 0.044 between them, the noise): Cycles'
 *    random walk takes the colour where light leaves, i.e. post-scatter
 *    texturing (pre-and-post: RMSE 0.080 and 0.134). So the gain acts as a
 *    brighter diffuse colour at the exit pixel: the scattered light of a
 *    pixel is scaled by g(DiffCol) there, after the blur, in both
 *    texturing modes (the blend with strength m: 1 + m (g - 1)).
 *
 * 2. Shape. The same box under a sun at normal incidence, the left half in
 *    the shadow of a plate that only casts shadows (5 cm in front of the
 *    face), r = 0.3 m, 0.4 m seen at 128 x 128, pixel filter 0.01 px, 128
 *    samples: the edge profile of the random walk (averaged along the
 *    edge) is fitted with Burley's edge response (least squares in d and
 *    an energy factor). Fitted d / r (r = 0.05 m at 0.2 m gave the same to
 *    4 %) against Cycles' own radius conversion for the random walk
 *    followed by Christensen-Burley's searchlight fit:
 *
 *      A      d/r fit  this mapping  random-walk (C&B dmfp)
 *      0.1    0.316    0.313         0.265
 *      0.2    0.261    0.253         0.283
 *      0.3    0.210    0.209         0.286
 *      0.4    0.178    0.177         0.286
 *      0.5    0.145    0.151         0.279
 *      0.6    0.121    0.126         0.248
 *      0.7    0.098    0.099         0.186
 *      0.8    0.067    0.067         0.119
 *      0.85   0.046    0.050         0.092
 *      0.9    0.034    0.033         0.071
 *      0.93   0.032    0.032 (floor) 0.061
 *      0.95   0.034    0.032 (floor) 0.055
 *      0.99   0.032    0.032 (floor) 0.044
 *    (cycles: 0.0796 and eevee: 0.0459 for every A.) A = 1 fits below
 *    0.01 (Cycles takes a' = 0.999999 from A = 0.995 on), as here.
 *
 *    This mapping is within 4 % of the fit up to A = 0.9 (8 % at 0.85); below
 *    d = 0.032 r the measured profile stops narrowing, and this mapping
 *    keeps that floor. Every older mapping is off by up to 4x somewhere.
 *    Edge-profile RMSE (profiles over the SSS-off lit plateau; libsss,
 *    separable-exact, on the SSS-off render of the same slab), per mapping
 *    cycles / eevee / random-walk: A 0.3: 0.107 / 0.146 / 0.019; 0.5:
 *    0.063 / 0.103 / 0.040; 0.7: 0.021 / 0.061 / 0.051; 0.8: 0.018 /
 *    0.028 / 0.048; 0.9: 0.064 / 0.026 / 0.056; 0.95: 0.054 / 0.027 /
 *    0.033 - each older mapping wins only where its d crosses the fit.
 *
 * 3. Blender 4.5.15 and 5.0.1 (Principled v2, Subsurface Weight 1, Scale
 *    x Radius = r, IOR Level 0, default Subsurface IOR and Anisotropy),
 *    the same protocols. 5.0.1 measures as 4.5.15 within the errors
 *    (0.003 at most apart), so one table serves 4.x and 5.x. On the
 *    infinite slab the ratio is now the same to 4 digits for the white
 *    world, a sun at 0 and at 60 degrees and r = 0.05, 0.2 and 0.3 m
 *    (standard errors 0.0005 - 0.003):
 *
 *      A      Skin 4.5  Skin 5.0  RW 4.5  RW 5.0
 *      0.05   0.9036    0.9031    0.7686  0.7703
 *      0.1    0.9087    0.9079    0.7808  0.7827
 *      0.2    0.9196    0.9199    0.8054  0.8080
 *      0.3    0.9317    0.9297    0.8328  0.8293
 *      0.4    0.9436    0.9415    0.8575  0.8558
 *      0.5    0.9545    0.9535    0.8819  0.8815
 *      0.6    0.9646    0.9633    0.9059  0.9055
 *      0.7    0.9763    0.9753    0.9318  0.9323
 *      0.8    0.9889    0.9896    0.9609  0.9616
 *      0.85   0.9951    0.9975    0.9722  0.9737
 *      0.9    0.9916    0.9921    0.9763  0.9782
 *      0.95   0.9546    0.9552    0.9416  0.9435
 *      0.98   0.9262    0.9282    0.9128  0.9147
 *      0.99   0.9168    0.9189    0.9036  0.9054
 *      1.0    0.9055    0.9062    0.8945  0.8964
 *
 *    (the tables: 4.5's, A = 0 as at 0.05, A = 0.99 and 1 moved within
 *    their errors so that A g(A) never decreases; between the points
 *    the reflectance A g(A) is interpolated, not g). Random Walk (Skin), the
 *    3.x walk, now loses up to 10 % at low albedo where 3.4's kept 1 %
 *    more than the diffuse lobe; Random Walk loses up to 23 %; both level
 *    off at a reflectance of about 0.90.
 *
 *    Shape (r = 0.3 m, 0.4 m at 128 x 128): Random Walk (Skin) fits d / r
 *    = 0.316 0.293 0.242 0.207 0.171 0.147 0.121 0.100 0.068 0.052 0.032
 *    0.033 at A = 0.05 0.1 0.2 ... 0.8 0.85 0.9 0.95, 3.4's mapping
 *    within 5 % (8 % at 0.85): it keeps SSS_BURLEY_CYCLES_RANDOM_WALK.
 *    Random Walk widens the other way, with the albedo:
 *
 *      A      0.05   0.1    0.2    0.3    0.4    0.5    0.6    0.7
 *      d/r    0.0171 0.0192 0.0251 0.0304 0.0369 0.0447 0.0541 0.0656
 *      A      0.8    0.85   0.9    0.95 .. 1
 *      d/r    0.0825 0.0891 0.100  0.1039
 *
 *    (r = 0.05 m at 64 x 64 gave the same within 10 %, below a pixel at
 *    low A), and SSS_BURLEY_CYCLES4_RANDOM_WALK interpolates it. 5.0.1:
 *    the same fits within 4 % (one step of the fit's grid), for both walks.
 */
#include "sss_internal.h"

/* Reflectance of the random walk over the Principled diffuse lobe's, at
 * the albedos of cal_albedo, per calibration (section 1 and 3). */
static const float cal_albedo[] = {0.0f, 0.05f, 0.1f, 0.2f, 0.3f, 0.4f, 0.5f,
                                   0.6f, 0.7f, 0.8f, 0.85f, 0.9f, 0.95f,
                                   0.98f, 0.99f, 1.0f};
#define CAL_N ((int)(sizeof cal_albedo / sizeof *cal_albedo))
static const float cal_gain[][CAL_N] = {
	[SSS_CALIBRATION_CYCLES_RANDOM_WALK] = {
		1.010f, 1.010f, 1.012f, 1.011f, 1.013f, 1.011f, 1.012f, 1.010f,
		1.009f, 1.012f, 1.011f, 1.006f, 0.968f, 0.9405f, 0.9315f,
		0.9225f},
	[SSS_CALIBRATION_CYCLES4_RANDOM_WALK_SKIN] = {
		0.9036f, 0.9036f, 0.9087f, 0.9196f, 0.9317f, 0.9436f, 0.9545f,
		0.9646f, 0.9763f, 0.9889f, 0.9951f, 0.9916f, 0.9546f, 0.9262f,
		0.9170f, 0.9080f},
	[SSS_CALIBRATION_CYCLES4_RANDOM_WALK] = {
		0.7686f, 0.7686f, 0.7808f, 0.8054f, 0.8328f, 0.8575f, 0.8819f,
		0.9059f, 0.9318f, 0.9609f, 0.9722f, 0.9763f, 0.9416f, 0.9128f,
		0.9036f, 0.8946f},
};

/* The interval [cal_albedo[i - 1], cal_albedo[i]] holding a (searched from
 * i = first; a in (cal_albedo[first - 1], 1)) and a's place t in it. */
static int interval(float a, int first, float *t)
{
	int i = first;
	while (i < CAL_N - 1 && cal_albedo[i] < a)
		i++;
	*t = (a - cal_albedo[i - 1]) / (cal_albedo[i] - cal_albedo[i - 1]);
	return i;
}

/* Piecewise linear in cal_albedo, clamped at both ends; 1 for NaN. */
static float lerp_table(const float *table, float a)
{
	if (!isfinite(a))
		return 1.0f;
	if (a <= 0.0f)
		return table[0];
	if (a >= 1.0f)
		return table[CAL_N - 1];
	float t;
	int i = interval(a, 1, &t);
	return table[i - 1] + t * (table[i] - table[i - 1]);
}

/* g(A) with the reflectance A g(A), not g, interpolated linearly: where
 * the walk's reflectance levels off (g ~ 1/A) a linear g would overshoot
 * between the points and A g(A) would fall again. Below the first
 * point g is its value; NaN gives 1. */
static float gain_at(const float *table, float a)
{
	if (!isfinite(a))
		return 1.0f;
	if (a <= cal_albedo[1])
		return table[1];
	if (a >= 1.0f)
		return table[CAL_N - 1];
	float t;
	int i = interval(a, 2, &t);
	float r0 = cal_albedo[i - 1] * table[i - 1], r1 = cal_albedo[i] * table[i];
	return (r0 + t * (r1 - r0)) / a;
}

static int is_calibration(int32_t calibration)
{
	return calibration > SSS_CALIBRATION_NONE &&
	       calibration <= SSS_CALIBRATION_CYCLES4_RANDOM_WALK;
}

sss_result sss_calibration_gain(int32_t calibration, const float albedo[3],
                                float gain[3])
{
	if (!albedo || !gain)
		return SSS_ERR_INVALID_ARGUMENT;
	if (calibration != SSS_CALIBRATION_NONE && !is_calibration(calibration))
		return SSS_ERR_INVALID_ARGUMENT;
	for (int c = 0; c < 3; c++)
		gain[c] = is_calibration(calibration)
		          ? gain_at(cal_gain[calibration], albedo[c]) : 1.0f;
	return SSS_OK;
}

void sss__calibration_apply(const sss_material *mat, const float *diff_col,
                            float *light)
{
	if (!is_calibration(mat->calibration))
		return;
	const float *table = cal_gain[mat->calibration];
	float s = mat->strength;
	for (int c = 0; c < 3; c++) {
		float m = mat->kind == SSS_PROFILE_JIMENEZ
		          ? s * mat->jimenez_strength[c] : s;
		if (m > 0.0f)
			light[c] *= 1.0f + m * (gain_at(table, diff_col[c]) - 1.0f);
	}
}

/* Cycles 3.4, bssrdf.h: Jensen's dipole reflectance with a boundary of
 * relative index eta, inverted for a' (Cycles bisects 12 times; 48 steps
 * here: the measured widths follow the exact inverse better). */
static double dipole_rd(double a, double four_thirds_a)
{
	double s = sqrt(3.0 * (1.0 - a));
	return 0.5 * a * (1.0 + exp(-four_thirds_a * s)) * exp(-s);
}

/* Below this d / radius the measured random walk stops narrowing
 * (A = 0.9 .. 0.99: 0.032 - 0.034). */
#define CYCLES_RW_MIN_D 0.032

double sss__cycles_rw_mfp_over_radius(double albedo)
{
	const double eta = 1.4; /* Principled's default Subsurface IOR */
	double f_dr = -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
	double four_thirds_a = 4.0 / 3.0 * (1.0 + f_dr) / (1.0 - f_dr);
	double a = albedo, alpha;
	if (!(a >= 1e-4))
		alpha = 0.0; /* also NaN: validation refuses it before here */
	else if (a >= 0.995)
		alpha = 0.999999; /* Cycles' own limit */
	else {
		double lo = 0.0, hi = 1.0;
		for (int i = 0; i < 48; i++) {
			double mid = 0.5 * (lo + hi);
			if (dipole_rd(mid, four_thirds_a) < a)
				lo = mid;
			else
				hi = mid;
		}
		alpha = 0.5 * (lo + hi);
	}
	return sqrt(3.0 * (1.0 - alpha));
}

double sss__cycles_rw_d_over_radius(double albedo)
{
	double a = albedo;
	double s = 1.9 - a + 3.5 * (a - 0.8) * (a - 0.8);
	double d = sss__cycles_rw_mfp_over_radius(a) / s;
	if (a < 0.995 && d < CYCLES_RW_MIN_D)
		d = CYCLES_RW_MIN_D;
	return d;
}

/* Section 3: Cycles 4.x/5.x's Random Walk, d / radius at cal_albedo
 * (A = 0 as at 0.05: the fit cannot go below a pixel there). */
static const float cycles4_rw_d[CAL_N] = {
	0.0171f, 0.0171f, 0.0192f, 0.0251f, 0.0304f, 0.0369f, 0.0447f, 0.0541f,
	0.0656f, 0.0825f, 0.0891f, 0.100f, 0.1039f, 0.1039f, 0.1039f, 0.1039f};

double sss__cycles4_rw_d_over_radius(double albedo)
{
	return lerp_table(cycles4_rw_d, (float)albedo);
}
