/* sss_curvature.c - the mean curvature of the visible surface at a pixel,
 * from the Depth pass, at a chosen scale.
 *
 * A random walk in a convex object leaves it sooner than in a flat
 * half-space, so less of its light is absorbed (sss_calibration.c, shape):
 * the calibration needs to know how curved the surface is over the
 * distance the light travels. Eight points on a circle of radius rho
 * around the pixel (on screen; the circle shrinks where it leaves the
 * surface) give the tangent plane, from two crossing chords, and how far
 * the midpoints of the four opposite pairs drop below it: on a circle of
 * radius a through the pixel a point at distance s drops s^2 / (2 a), so
 * 2 drop / s^2 over a pair is the surface's curvature along it (exactly,
 * on a sphere), and the mean curvature H follows from three or four
 * directions (1/a on a sphere, 1/(2a) on a cylinder), averaged over the
 * circle, which on a faceted mesh seen from a circle wider than its
 * facets is the smooth surface's. Positive is convex. */
#include "sss_internal.h"

#include <string.h>

#define RING 8
/* Circles from 2 px (a narrower one reads the depth's rounding and the
 * facets) to 48 px (a wider one costs no more but leaves most objects). */
#define RING_MIN_PX 2.0
#define RING_MAX_PX 48.0
/* A point farther than this many radii away lies on another surface. */
#define RING_REACH 3.0

/* Points of the circle of radius rho (scene units, r_px on screen) that
 * lie on the surface of pixel (x, y); returns how many. */
static int ring_points(const sss_image *depth, const int16_t *slot,
                       const sss__projection *p, int32_t w, int32_t h,
                       int32_t x, int32_t y, const double here[3],
                       double rho, double r_px, double q[RING][3],
                       int ok[RING])
{
	static const double cs[RING][2] = {
		{1, 0}, {0.70710678, 0.70710678}, {0, 1}, {-0.70710678, 0.70710678},
		{-1, 0}, {-0.70710678, -0.70710678}, {0, -1}, {0.70710678, -0.70710678}};
	int16_t own = slot[(size_t)y * w + x];
	int n = 0;
	for (int i = 0; i < RING; i++) {
		int32_t qx = x + (int32_t)floor(r_px * cs[i][0] + 0.5);
		int32_t qy = y - (int32_t)floor(r_px * cs[i][1] + 0.5);
		ok[i] = 0;
		if (qx < 0 || qy < 0 || qx >= w || qy >= h ||
		    slot[(size_t)qy * w + qx] != own)
			continue;
		double z = sss__at(depth, qx, qy)[0];
		if (!(z > 0.0) || !isfinite(z))
			continue;
		sss__view_point(p, qx, qy, z, q[i]);
		double d2 = 0.0;
		for (int c = 0; c < 3; c++)
			d2 += (q[i][c] - here[c]) * (q[i][c] - here[c]);
		if (d2 < RING_REACH * RING_REACH * rho * rho && d2 > 0.0) {
			ok[i] = 1;
			n++;
		}
	}
	return n;
}

/* The tangent from opposite points i and i + 4, if both are there. */
static int chord(double q[RING][3], const int ok[RING], int i, double t[3])
{
	if (!ok[i] || !ok[i + RING / 2])
		return 0;
	for (int c = 0; c < 3; c++)
		t[c] = q[i][c] - q[i + RING / 2][c];
	return 1;
}

/* The normal from two crossing chords, turned towards the camera. */
static int ring_normal(const sss__projection *p, double q[RING][3],
                       const int ok[RING], const double here[3],
                       double n[3])
{
	double a[3], b[3];
	if (!((chord(q, ok, 0, a) && chord(q, ok, 2, b)) ||
	      (chord(q, ok, 1, a) && chord(q, ok, 3, b))))
		return 0;
	n[0] = a[1] * b[2] - a[2] * b[1];
	n[1] = a[2] * b[0] - a[0] * b[2];
	n[2] = a[0] * b[1] - a[1] * b[0];
	double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
	if (!(len > 0.0) || !isfinite(len))
		return 0;
	/* The camera looks along +Z: from a point, it lies along -here
	 * (perspective) or -Z (orthographic). */
	double towards = p->ortho ? -n[2]
	                          : -(n[0] * here[0] + n[1] * here[1] +
	                              n[2] * here[2]);
	double sign = towards < 0.0 ? -1.0 : 1.0;
	for (int c = 0; c < 3; c++)
		n[c] *= sign / len;
	return 1;
}

static double dot3(const double a[3], const double b[3])
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Two unit tangents, e1 along the screen's x as far as the normal
 * allows. */
static int tangent_basis(const double n[3], double e1[3], double e2[3])
{
	double x[3] = {1.0, 0.0, 0.0};
	double along = dot3(x, n), len = 0.0;
	for (int c = 0; c < 3; c++) {
		e1[c] = x[c] - along * n[c];
		len += e1[c] * e1[c];
	}
	if (!(len > 1e-12))
		return 0;
	len = sqrt(len);
	for (int c = 0; c < 3; c++)
		e1[c] /= len;
	e2[0] = n[1] * e1[2] - n[2] * e1[1];
	e2[1] = n[2] * e1[0] - n[0] * e1[2];
	e2[2] = n[0] * e1[1] - n[1] * e1[0];
	return 1;
}

/* a x = b by Cramer's rule; 0 when a is (nearly) singular. */
static int solve3(double a[3][3], const double b[3], double x[3])
{
#define DET(m) ((m)[0][0] * ((m)[1][1] * (m)[2][2] - (m)[1][2] * (m)[2][1]) - \
                (m)[0][1] * ((m)[1][0] * (m)[2][2] - (m)[1][2] * (m)[2][0]) + \
                (m)[0][2] * ((m)[1][0] * (m)[2][1] - (m)[1][1] * (m)[2][0]))
	double det = DET(a);
	if (!(fabs(det) > 1e-9))
		return 0;
	for (int k = 0; k < 3; k++) {
		double m[3][3];
		memcpy(m, a, sizeof m);
		for (int r = 0; r < 3; r++)
			m[r][k] = b[r];
		x[k] = DET(m) / det;
	}
	return 1;
#undef DET
}

double sss__mean_curvature(const sss_image *depth, const int16_t *slot,
                           const sss__projection *p, int32_t w, int32_t h,
                           int32_t x, int32_t y, double rho)
{
	double z = sss__at(depth, x, y)[0];
	if (!(z > 0.0) || !isfinite(z) || !(rho > 0.0) || !isfinite(rho))
		return 0.0;
	double here[3];
	sss__view_point(p, x, y, z, here);
	double px_per_unit = fmin(sss__pixels_per_unit_x(p, z),
	                          sss__pixels_per_unit_y(p, z));
	if (!(px_per_unit > 0.0) || !isfinite(px_per_unit))
		return 0.0;
	double r_px = rho * px_per_unit;
	if (r_px > RING_MAX_PX)
		r_px = RING_MAX_PX;
	if (r_px < RING_MIN_PX)
		r_px = RING_MIN_PX;
	/* The widest circle, up to rho, that stays on the surface. */
	for (; r_px >= RING_MIN_PX; r_px *= 0.5) {
		double q[RING][3], n[3];
		int ok[RING];
		double radius = r_px / px_per_unit;
		if (ring_points(depth, slot, p, w, h, x, y, here, radius, r_px, q,
		                ok) < RING - 2)
			continue;
		/* The normal from a circle a quarter as wide: a secant's slope
		 * is the mean slope under it, which near a silhouette differs
		 * from the pixel's; narrower than 2 px it would read a facet. */
		double nq[RING][3], n_px = fmax(0.25 * r_px, RING_MIN_PX);
		int nok[RING];
		if (n_px < r_px) {
			ring_points(depth, slot, p, w, h, x, y, here,
			            n_px / px_per_unit, n_px, nq, nok);
			if (!ring_normal(p, nq, nok, here, n) &&
			    !ring_normal(p, q, ok, here, n))
				continue;
		} else if (!ring_normal(p, q, ok, here, n))
			continue;
		/* Each opposite pair's midpoint lies below the pixel by the
		 * drop over its chord: the tangent components, which a normal
		 * read from secants gets slightly wrong, cancel in it. On a
		 * surface seen at an angle the screen's directions are not the
		 * surface's, so the pairs' curvatures are fitted by Euler's
		 * k(psi) = kxx c^2 + 2 kxy c s + kyy s^2 in the tangent plane
		 * (c, s: cos and sin of the chord's direction there), whose
		 * mean (kxx + kyy) / 2 is H. */
		double e1[3], e2[3];
		if (!tangent_basis(n, e1, e2))
			continue;
		double ata[3][3] = {{0}}, atb[3] = {0};
		int pairs = 0;
		for (int i = 0; i < RING / 2; i++) {
			const double *a = q[i], *b = q[i + RING / 2];
			if (!ok[i] || !ok[i + RING / 2])
				continue;
			double d[3], t[3], s2 = 0.0;
			for (int c = 0; c < 3; c++) {
				d[c] = here[c] - 0.5 * (a[c] + b[c]);
				t[c] = a[c] - b[c];
				s2 += 0.5 * ((here[c] - a[c]) * (here[c] - a[c]) +
				             (here[c] - b[c]) * (here[c] - b[c]));
			}
			double tc = dot3(t, e1), ts = dot3(t, e2);
			double tl = tc * tc + ts * ts;
			if (!(s2 > 0.0) || !(tl > 0.0))
				continue;
			double row[3] = {tc * tc / tl, 2.0 * tc * ts / tl, ts * ts / tl};
			double kappa = 2.0 * dot3(d, n) / s2;
			for (int r = 0; r < 3; r++) {
				for (int c = 0; c < 3; c++)
					ata[r][c] += row[r] * row[c];
				atb[r] += row[r] * kappa;
			}
			pairs++;
		}
		double k[3];
		if (pairs < 3 || !solve3(ata, atb, k))
			continue;
		double curvature = 0.5 * (k[0] + k[2]);
		return isfinite(curvature) ? curvature : 0.0;
	}
	return 0.0;
}
