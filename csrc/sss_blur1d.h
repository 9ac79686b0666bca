/* sss_blur1d.h - the separable method's inner loop, shared by its scalar
 * and vector implementations (sss_blur1d.c, sss_blur1d_avx2.c).
 *
 * One call blurs one pixel along one row of a working plane over every
 * pixel within [s_lo, s_hi] of it. A sample at offset s weighs
 *
 *     W_c(s) * rho(q * A_c(s)) * [same material] * [q < cut_q]
 *
 * W_c(s): the profile's 1-D mass over the sample's cell on a flat plane
 * facing the camera, linearly interpolated between two tabulated kernel
 * half-widths (row0, row1, weight f). q: the squared 3-D distance between
 * the two surface points minus the squared in-plane distance, that is how
 * far the sample lies off the plane (0 on a plane facing the camera). rho(u) = max(0, 1 - u/8)^8: 1 at u = 0, smooth, exactly 0 for
 * u >= 8 (a sample across a depth step weighs nothing); A_c(s) is fitted
 * per tap so that rho matches the profile's mass at the true distance (see
 * sss_separable.c). The result is sum(w v) / sum(w) per channel.
 *
 * Both implementations run the same operations in the same order on eight
 * lanes (sample s goes to lane (s - s_lo) mod 8, lanes are summed as
 * ((l0+l4)+(l2+l6)) + ((l1+l5)+(l3+l7))), without fused multiply-adds, so
 * their results are identical bit for bit. */
#ifndef SSS_BLUR1D_H
#define SSS_BLUR1D_H

#include <stdint.h>

#define SSS__LANES 8

typedef struct sss__blur1d {
	/* The row, every array indexed by the position along it. */
	const float *rgb[3];   /* light, planar; 0 where nothing scatters */
	const float *z;        /* depth */
	const int32_t *slot;   /* kernel per pixel (and, above bit 16, its
	                          face between creases), -1 = does not scatter */
	int32_t i;             /* the centre pixel */
	int32_t len;           /* pixels in the row */
	int64_t readable;      /* elements every array holds from the row start */
	int32_t s_lo, s_hi;    /* sample offsets from the centre, inclusive */
	int32_t slot_c;
	float zc;              /* centre depth */
	/* The sample's position along the axis relative to the principal
	 * point is (i + s) + off_axis pixels; ife = 1/f_axis for a perspective
	 * camera, 0 for an orthographic one; two_xt = 2 zc / f_axis
	 * (perspective) or 2 / f_axis, so that |s| two_xt / 2 is the in-plane
	 * distance; cz = 1 + (perpendicular position / f_perp)^2 (perspective)
	 * or 1. */
	float off_axis, ife, two_xt, cz;
	float cut_q;           /* squared support */
	float f;               /* interpolation between row0 and row1 */
	float r;               /* sparse taps: the half-width, pixels */
	/* Table rows, indexed by s: W_c at [c * stride + s], A_c / 8 at
	 * [(3 + c) * stride + s]; readable over [s_lo, s_hi + 7]. */
	const float *row0, *row1;
	int32_t stride;
	/* Out: per channel, sum(w v) and sum(w). */
	float acc[3], wsum[3];
} sss__blur1d;

/* How far sample j (offset s from the centre) lies off the plane through
 * the centre facing the camera: squared 3-D distance minus squared
 * in-plane distance, clamped at 0 (NaN gives 0; such samples are rejected
 * by their material). From depth alone, with no square root and no
 * difference of large numbers: with dz the depth difference,
 * dx - xt = dz (x_j - c) / f and dy = dz (y - c') / f'. (Blender's
 * Position pass gives the same distances: on the 1080p demo the result
 * from positions was within 1.7e-5 of this, at 13 % more time and three
 * more planes each way.) */
static inline float sss__blur1d_q(const sss__blur1d *b, int32_t j, int32_t s)
{
	float dz = b->z[j] - b->zc;
	float xs = (float)j + b->off_axis;
	float e = (dz * xs) * b->ife;
	float xt2 = (float)s * b->two_xt;
	float q = e * (e + xt2) + (dz * dz) * b->cz;
	return q > 0.0f ? q : 0.0f; /* as the vector max: NaN and -0 give 0 */
}

/* rho(u) for u = q A_c / 8 as stored: max(0, 1 - u)^8. */
static inline float sss__blur1d_rho(float q, float a8)
{
	float t = 1.0f - q * a8;
	t = t > 0.0f ? t : 0.0f;
	float t2 = t * t, t4 = t2 * t2;
	return t4 * t4;
}

/* Taps anywhere along the row (sparse layouts): tap k lies at at[k] r
 * pixels from the centre (signed; r = the sss__blur1d's) and weighs w_c[k]
 * (W over its cell), with A_c/8 in a8_c[k]. It is read by linear
 * interpolation (the centre tap aside: sss__taps.centre): with
 * o = at[k] r, the pixels i + floor(o) and one right of
 * it take the shares 1 - frac(o) and frac(o) of w_c[k], each with its own
 * falloff rho, and only where it lies in the row on the centre's material.
 * The arrays are padded with zero weights to a multiple of SSS__LANES; tap
 * k goes to lane k mod 8, its left pixel before its right one. The row
 * fields of the sss__blur1d are used, not the table rows. cell[v]: the
 * narrowest cell of vector v's taps, in units of r. */
typedef struct sss__taps {
	/* The centre tap's W per channel: not in the lanes, since it reads
	 * the pixel itself, on its own material and plane (falloff 1), and
	 * leaving it out makes the default 33 taps four vectors, not five. */
	float centre[3];
	int32_t count;         /* a multiple of SSS__LANES */
	float *at;
	float *w[3], *a8[3];
	float *cell;           /* count / SSS__LANES */
	/* Or weights interpolated between two rows, w + f (w1 - w) and
	 * a8 + f (a81 - a8) (a cut kernel's table); w1[0] NULL: none. */
	float *w1[3], *a81[3];
	float f;
} sss__taps;

void sss__blur1d_scalar(sss__blur1d *b);
/* Taps of vectors v0 .. v1 - 1 (taps 8 v0 .. 8 v1 - 1) only. */
void sss__blur1d_taps_scalar(sss__blur1d *b, const sss__taps *t, int32_t v0,
                             int32_t v1);
void sss__blur1d_taps_avx2(sss__blur1d *b, const sss__taps *t, int32_t v0,
                           int32_t v1);
/* Same result, AVX2; only call when sss__blur1d_avx2_supported(). */
void sss__blur1d_avx2(sss__blur1d *b);
int sss__blur1d_avx2_supported(void);

#endif /* SSS_BLUR1D_H */
