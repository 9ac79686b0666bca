/* sss_calibration.c - what Cycles 3.4's random-walk SSS does that a blur of
 * the SSS-off render does not, measured once on flat slabs
 * (blender_scripts/calibrate.py, Blender 3.4.1, Cycles CPU, denoising,
 * adaptive sampling and clamping off).
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
 */
#include "sss_internal.h"

/* Reflectance of the random walk over the Principled diffuse lobe's. */
static const float cal_albedo[] = {0.0f, 0.05f, 0.1f, 0.2f, 0.3f, 0.4f, 0.5f,
                                   0.6f, 0.7f, 0.8f, 0.85f, 0.9f, 0.95f,
                                   0.98f, 0.99f, 1.0f};
static const float cal_gain[] = {1.010f, 1.010f, 1.012f, 1.011f, 1.013f,
                                 1.011f, 1.012f, 1.010f, 1.009f, 1.012f,
                                 1.011f, 1.006f, 0.968f, 0.9405f, 0.9315f,
                                 0.9225f};
#define CAL_N ((int)(sizeof cal_albedo / sizeof *cal_albedo))

static float rw_gain(float a)
{
	if (!isfinite(a))
		return 1.0f;
	if (a <= 0.0f)
		return cal_gain[0];
	if (a >= 1.0f)
		return cal_gain[CAL_N - 1];
	int i = 1;
	while (i < CAL_N - 1 && cal_albedo[i] < a)
		i++;
	float t = (a - cal_albedo[i - 1]) / (cal_albedo[i] - cal_albedo[i - 1]);
	return cal_gain[i - 1] + t * (cal_gain[i] - cal_gain[i - 1]);
}

sss_result sss_calibration_gain(int32_t calibration, const float albedo[3],
                                float gain[3])
{
	if (!albedo || !gain)
		return SSS_ERR_INVALID_ARGUMENT;
	if (calibration != SSS_CALIBRATION_NONE &&
	    calibration != SSS_CALIBRATION_CYCLES_RANDOM_WALK)
		return SSS_ERR_INVALID_ARGUMENT;
	for (int c = 0; c < 3; c++)
		gain[c] = calibration == SSS_CALIBRATION_CYCLES_RANDOM_WALK
		          ? rw_gain(albedo[c]) : 1.0f;
	return SSS_OK;
}

void sss__calibration_apply(const sss_material *mat, const float *diff_col,
                            float *light)
{
	if (mat->calibration != SSS_CALIBRATION_CYCLES_RANDOM_WALK)
		return;
	float s = mat->strength;
	for (int c = 0; c < 3; c++) {
		float m = mat->kind == SSS_PROFILE_JIMENEZ
		          ? s * mat->jimenez_strength[c] : s;
		if (m > 0.0f)
			light[c] *= 1.0f + m * (rw_gain(diff_col[c]) - 1.0f);
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

double sss__cycles_rw_d_over_radius(double albedo)
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
	double mfp = sqrt(3.0 * (1.0 - alpha)); /* mean free path / radius */
	double s = 1.9 - a + 3.5 * (a - 0.8) * (a - 0.8);
	double d = mfp / s;
	if (a < 0.995 && d < CYCLES_RW_MIN_D)
		d = CYCLES_RW_MIN_D;
	return d;
}
