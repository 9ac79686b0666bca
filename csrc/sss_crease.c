/* sss_crease.c - the light a sharp convex edge carries from one face to
 * the next.
 *
 * Where two faces meet at a convex edge, the random walk sends the light
 * that enters one face within a few mean free paths of the edge out
 * through the other face: a flux through the other face's plane, which no
 * exit profile of a flat half-space has and which a depth-aware blur,
 * whatever its distances, does not give (comparison.md: on a 90-degree
 * edge the walk's first unlit pixel was 2.5 times what a sum over the true
 * surface gives). Measured on such an edge (calibrate.py --part crease),
 * what the walk adds on the unlit face at distance t from the edge, over
 * the lit face's scattered light, is kappa F(t), F the tail beyond t of
 * Burley's 1-D marginal with d = gamma r (r the walk's radius), kappa and
 * gamma by albedo (sss__crease_params).
 *
 * In screen space, from the Depth pass: every pixel's view-space point
 * and normal (the slope on the side where its face goes on straightest);
 * the pixels next to a crease (a neighbour of the material whose normal
 * is more than 45 degrees away, each below the other's tangent plane,
 * each face flat a pixel further: a crease, not a smooth bend such as a
 * sphere's limb), listed by tile with the light two pixels inside their
 * face and how far that face goes on. Each pixel within reach of such
 * sources on another face, whose edge is the receiver's own (the source
 * lies on the line where the two tangent planes meet), takes their light
 * weighted by Burley's profile over the distance along the surface
 * through the edge, and its own distance t to the edge; it gains kappa x
 * that light x the mean of F(t) - F(t + w) over its extent across the
 * edge, w the lit face's width (a face narrower than the radius sends at
 * most what entered it). For a lit face the sum is the measured profile
 * whatever the pixel size.
 *
 * For the calibrations whose lit face has a measured loss
 * (sss__crease_loss_params: every walk's), the separable blur
 * stops at each crease (breaks: the pixel pairs it parts) and each pixel
 * also loses the loss's kappa F(t) of its own light, F with the loss's
 * d: the light that leaves through the other face. Then the result is
 * the same from any view (the blur's own share across an edge was not).
 */
#include "sss_internal.h"

#include <stdlib.h>
#include <string.h>

#define CREASE_MIN_COS 0.7071068 /* 45 degrees between the two normals */
#define CREASE_REACH 10.0        /* in d: F(10 d) < 2 % of F(0) */
#define CREASE_TABLE 256
#define CREASE_SOURCES 16       /* most sources read per receiver, about */
#define CREASE_U_MAX 60.0        /* F(60) for d = 1: about 1e-10 */

/* A pixel next to a crease, on its own face: where the light that crosses
 * the edge comes from. */
typedef struct crease_source {
	int32_t x, y;
	double pos[3], nrm[3];
	double pix;      /* its size (scene units) */
	double s_limit;  /* how far from the edge its pixel reaches */
	double extent;   /* how far its face goes on away from the edge */
	float light[3];  /* the signal a little inside its face */
} crease_source;

typedef struct crease_ctx {
	const sss__job *job;
	const sss_image *diff_col;
	const uint8_t *enabled;       /* per kernel */
	const int32_t *calibration;   /* per kernel */
	const double *reach;          /* per kernel: the widest reach over
	                                 albedos and channels, scene units */
	const float *pos, *nrm;       /* 3 per pixel; nrm NaN: unknown */
	uint8_t *near;                /* per pixel: BENT, NEAR_BENT */
	int8_t *across;               /* per pixel: the neighbour (0..7) over a
	                                 crease, or -1 */
	int32_t tiles_x, tiles_y;
	const int32_t *tile_first;    /* tiles_x * tiles_y + 1 offsets */
	const int32_t *tile_sat;      /* (tiles_y + 1) x (tiles_x + 1): the
	                                 sources in the tiles above and left */
	const crease_source *sources; /* by tile */
	float *extra;                 /* 3 per pixel, packed */
	uint8_t *breaks;              /* per pixel: SSS__BREAK_*, or NULL */
	const uint8_t *stops;         /* per kernel: the blur stops at its
	                                 creases (it takes the term and its
	                                 calibration has a loss) */
	int term;                     /* 0: the light over the edges left out */
	int receive_known;            /* near[] holds CAN_RECEIVE */
	double u_node[CREASE_TABLE];  /* Burley d = 1 */
	double G[CREASE_TABLE];       /* integral of F over [0, u] */
} crease_ctx;

#define CREASE_TILE 8
static const int8_t step_x[8] = {1, 1, 0, -1, -1, -1, 0, 1};
static const int8_t step_y[8] = {0, 1, 1, 1, 0, -1, -1, -1};

/* The unit vector from the point towards the camera. */
static void to_camera(const sss__projection *p, const float *pt,
                      double v[3])
{
	if (p->ortho) {
		v[0] = v[1] = 0.0, v[2] = -1.0;
		return;
	}
	double n = sqrt((double)pt[0] * pt[0] + (double)pt[1] * pt[1] +
	                (double)pt[2] * pt[2]);
	for (int c = 0; c < 3; c++)
		v[c] = n > 0.0 ? -pt[c] / n : (c == 2 ? -1.0 : 0.0);
}

static double dot3(const double *a, const double *b)
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double *a, const double *b, double *out)
{
	out[0] = a[1] * b[2] - a[2] * b[1];
	out[1] = a[2] * b[0] - a[0] * b[2];
	out[2] = a[0] * b[1] - a[1] * b[0];
}

/* Tabulates G(u) = integral over [0, u] of F, F(u) = the mass of Burley's
 * (d = 1) 1-D marginal beyond u, at u = U_MAX (k / (N-1))^2. */
static void tabulate(crease_ctx *ctx)
{
	double F[CREASE_TABLE];
	for (int k = 0; k < CREASE_TABLE; k++) {
		double s = (double)k / (CREASE_TABLE - 1);
		ctx->u_node[k] = CREASE_U_MAX * s * s;
	}
	F[CREASE_TABLE - 1] = 0.0;
	for (int k = CREASE_TABLE - 2; k >= 0; k--)
		F[k] = F[k + 1] + sss__burley_line_mass(ctx->u_node[k],
		                                        ctx->u_node[k + 1], 1.0);
	/* F(0) is 1/2 exactly; what the quadrature missed is spread evenly */
	double fix = 0.5 / F[0];
	ctx->G[0] = 0.0;
	for (int k = 1; k < CREASE_TABLE; k++)
		ctx->G[k] = ctx->G[k - 1] + 0.5 * fix * (F[k] + F[k - 1]) *
		            (ctx->u_node[k] - ctx->u_node[k - 1]);
}

static double G_at(const crease_ctx *ctx, double u)
{
	if (!(u > 0.0))
		return 0.0;
	double s = sqrt(u / CREASE_U_MAX) * (CREASE_TABLE - 1);
	if (s >= CREASE_TABLE - 1)
		return ctx->G[CREASE_TABLE - 1];
	int k = (int)s;
	double t = (u - ctx->u_node[k]) / (ctx->u_node[k + 1] - ctx->u_node[k]);
	return ctx->G[k] + t * (ctx->G[k + 1] - ctx->G[k]);
}

/* Step from pixel (x, y) to its neighbour along one axis, on the side
 * where the surface goes on straightest (the smaller second difference
 * with the next pixel), so that a pixel next to an edge takes its own
 * face's slope; 0 when no neighbour of its slot is there. */
static int face_step(const crease_ctx *ctx, int32_t x, int32_t y, int dx,
                     int dy, double step[3])
{
	const sss__job *job = ctx->job;
	int32_t w = job->width, h = job->height;
	int16_t own = job->slot[(size_t)y * w + x];
	const float *here = ctx->pos + 3 * ((size_t)y * w + x);
	double best = INFINITY;
	int found = 0;
	for (int side = -1; side <= 1; side += 2) {
		int32_t x1 = x + side * dx, y1 = y + side * dy;
		if (x1 < 0 || y1 < 0 || x1 >= w || y1 >= h ||
		    job->slot[(size_t)y1 * w + x1] != own)
			continue;
		const float *p1 = ctx->pos + 3 * ((size_t)y1 * w + x1);
		int32_t x2 = x1 + side * dx, y2 = y1 + side * dy;
		double bend;
		if (x2 >= 0 && y2 >= 0 && x2 < w && y2 < h &&
		    job->slot[(size_t)y2 * w + x2] == own) {
			const float *p2 = ctx->pos + 3 * ((size_t)y2 * w + x2);
			bend = 0.0;
			for (int c = 0; c < 3; c++) {
				double b = (double)p2[c] - 2.0 * p1[c] + here[c];
				bend += b * b;
			}
		} else {
			bend = 1e30 + fabs((double)p1[2] - here[2]);
		}
		if (!(bend < best))
			continue;
		best = bend;
		for (int c = 0; c < 3; c++)
			step[c] = side * ((double)p1[c] - here[c]);
		found = 1;
	}
	return found;
}

/* The unit normal at pixel (x, y), towards the camera; 0 where its
 * neighbours do not tell. */
static int pixel_normal(const crease_ctx *ctx, int32_t x, int32_t y,
                        double n[3])
{
	double sx[3], sy[3], c[3], v[3];
	size_t i = (size_t)y * ctx->job->width + x;
	if (!face_step(ctx, x, y, 1, 0, sx) || !face_step(ctx, x, y, 0, 1, sy))
		return 0;
	cross3(sx, sy, c);
	double len = sqrt(dot3(c, c));
	if (!(len > 0.0) || !isfinite(len))
		return 0;
	to_camera(&ctx->job->proj, ctx->pos + 3 * i, v);
	double sign = dot3(c, v) < 0.0 ? -1.0 : 1.0;
	for (int k = 0; k < 3; k++)
		n[k] = sign * c[k] / len;
	return 1;
}

/* Pixel size (scene units) at depth z. */
static double pixel_size(const sss__projection *p, double z)
{
	return 1.0 / sqrt(sss__pixels_per_unit_x(p, z) *
	                  sss__pixels_per_unit_y(p, z));
}

/* A crease bends the depth: where the second difference along a row or a
 * column passes BEND_SLOPE times the pixel's size (two faces at 45
 * degrees to the view give 2, normals 45 degrees apart at least 0.8; a
 * sphere of radius R pixels seen head-on 1/R, more only near its limb),
 * the pixel is BENT; pixels within 2 of one are NEAR_BENT and get
 * normals (detection reads a pixel beyond each side), as do the pixels of
 * the term's materials (the receivers read theirs; made once, a kept
 * workspace keeps them). */
#define BEND_SLOPE 0.4
#define BENT 2u
#define NEAR_BENT 1u

static int bent_along(const crease_ctx *ctx, int32_t x, int32_t y, int dx,
                      int dy, double pix)
{
	const sss__job *job = ctx->job;
	int32_t w = job->width, h = job->height;
	int32_t xa = x - dx, ya = y - dy, xb = x + dx, yb = y + dy;
	if (xa < 0 || ya < 0 || xb >= w || yb >= h)
		return 0;
	int16_t k = job->slot[(size_t)y * w + x];
	size_t a = (size_t)ya * w + xa, b = (size_t)yb * w + xb;
	if (job->slot[a] != k || job->slot[b] != k)
		return 0;
	double z = ctx->pos[3 * ((size_t)y * w + x) + 2];
	return fabs((double)ctx->pos[3 * a + 2] - 2.0 * z + ctx->pos[3 * b + 2]) >
	       BEND_SLOPE * pix;
}

static void bend_rows(void *vctx, int32_t y0, int32_t y1)
{
	crease_ctx *ctx = vctx;
	const sss__job *job = ctx->job;
	int32_t w = job->width;
	for (int32_t y = y0; y < y1; y++)
		for (int32_t x = 0; x < w; x++) {
			size_t i = (size_t)y * w + x;
			ctx->near[i] = 0;
			if (job->slot[i] < 0 || !ctx->enabled[job->slot[i]])
				continue;
			double pix = pixel_size(&job->proj, ctx->pos[3 * i + 2]);
			if (bent_along(ctx, x, y, 1, 0, pix) ||
			    bent_along(ctx, x, y, 0, 1, pix))
				ctx->near[i] = BENT;
		}
}

/* NEAR_BENT around every BENT pixel (serial: a pixel's neighbours). */
static void mark_near(crease_ctx *ctx)
{
	int32_t w = ctx->job->width, h = ctx->job->height;
	for (int32_t y = 0; y < h; y++)
		for (int32_t x = 0; x < w; x++) {
			if (!(ctx->near[(size_t)y * w + x] & BENT))
				continue;
			for (int32_t v = y - 2; v <= y + 2; v++)
				for (int32_t u = x - 2; u <= x + 2; u++)
					if (u >= 0 && v >= 0 && u < w && v < h)
						ctx->near[(size_t)v * w + u] |= NEAR_BENT;
		}
}

static void normal_rows(void *vctx, int32_t y0, int32_t y1)
{
	crease_ctx *ctx = vctx;
	const sss__job *job = ctx->job;
	int32_t w = job->width;
	for (int32_t y = y0; y < y1; y++)
		for (int32_t x = 0; x < w; x++) {
			size_t i = (size_t)y * w + x;
			int16_t slot = job->slot[i];
			if (!(ctx->near[i] & NEAR_BENT) &&
			    !(slot >= 0 && ctx->enabled[slot]))
				continue; /* never read */
			float *n = (float *)ctx->nrm + 3 * i;
			double m[3];
			n[0] = n[1] = n[2] = NAN;
			if (pixel_normal(ctx, x, y, m))
				for (int k = 0; k < 3; k++)
					n[k] = (float)m[k];
		}
}

/* |cos| between normal n at pixel i and the ray to it, kept from
 * grazing. */
static double facing(const crease_ctx *ctx, size_t i, const double n[3])
{
	double v[3];
	to_camera(&ctx->job->proj, ctx->pos + 3 * i, v);
	return fmax(fabs(dot3(n, v)), 0.2);
}

static void load3(const float *v, double out[3])
{
	out[0] = v[0], out[1] = v[1], out[2] = v[2];
}

/* Whether pixel j has a known normal within FLAT_COS of n and the slot k:
 * the face goes on flat there. */
#define FLAT_COS 0.95
static int flat_at(const crease_ctx *ctx, int16_t k, int32_t x, int32_t y,
                   const double n[3])
{
	const sss__job *job = ctx->job;
	if (x < 0 || y < 0 || x >= job->width || y >= job->height)
		return 0;
	size_t j = (size_t)y * job->width + x;
	if (job->slot[j] != k || !(ctx->near[j] & NEAR_BENT) ||
	    isnan(ctx->nrm[3 * j]))
		return 0;
	double m[3];
	load3(ctx->nrm + 3 * j, m);
	return dot3(n, m) > FLAT_COS;
}

/* Pixels next to a crease: a neighbour of the same slot whose normal is
 * more than 45 degrees from its own, each below the other's tangent plane
 * (convex), and each face flat for a pixel beyond them (a crease, not a
 * smooth bend such as a sphere's limb seen at grazing angles). */
static int convex_pair(const crease_ctx *ctx, int16_t k, int32_t x,
                       int32_t y, int dir, const double P[3],
                       const double n[3], const double Q[3],
                       const double m[3], double max_cos)
{
	double D[3];
	if (!(dot3(n, m) < max_cos))
		return 0;
	for (int c = 0; c < 3; c++)
		D[c] = Q[c] - P[c];
	if (!(dot3(D, n) < 0.0 && dot3(D, m) > 0.0))
		return 0;
	return flat_at(ctx, k, x - step_x[dir], y - step_y[dir], n) &&
	       flat_at(ctx, k, x + 2 * step_x[dir], y + 2 * step_y[dir], m);
}

static void detect_rows(void *vctx, int32_t y0, int32_t y1)
{
	crease_ctx *ctx = vctx;
	const sss__job *job = ctx->job;
	int32_t w = job->width, h = job->height;
	for (int32_t y = y0; y < y1; y++)
		for (int32_t x = 0; x < w; x++) {
			size_t i = (size_t)y * w + x;
			ctx->across[i] = -1;
			int16_t k = job->slot[i];
			if (k < 0 || !(ctx->near[i] & BENT) || isnan(ctx->nrm[3 * i]))
				continue;
			double P[3], n[3], best = CREASE_MIN_COS;
			load3(ctx->pos + 3 * i, P);
			load3(ctx->nrm + 3 * i, n);
			for (int dir = 0; dir < 8; dir++) {
				int32_t qx = x + step_x[dir], qy = y + step_y[dir];
				if (qx < 0 || qy < 0 || qx >= w || qy >= h)
					continue;
				size_t j = (size_t)qy * w + qx;
				if (job->slot[j] != k || !(ctx->near[j] & NEAR_BENT) ||
				    isnan(ctx->nrm[3 * j]))
					continue;
				double Q[3], m[3];
				load3(ctx->pos + 3 * j, Q);
				load3(ctx->nrm + 3 * j, m);
				if (!convex_pair(ctx, k, x, y, dir, P, n, Q, m, best))
					continue;
				best = dot3(n, m);
				ctx->across[i] = (int8_t)dir;
			}
		}
}

static double face_extent(const crease_ctx *ctx, int32_t x, int32_t y,
                          int dir, const double P[3], const double n[3]);

/* Whether a crease parts pixel i from its neighbour j (dir) for the blur:
 * the test detect_rows makes, for the pair itself, either of them bent,
 * and both faces going on from the edge at least as far as the
 * material's widest radius (with a radius larger than the faces the walk
 * carries light round the whole object, as the blur does). */
static int parted(const crease_ctx *ctx, size_t i, int32_t x, int32_t y,
                  int dir)
{
	const sss__job *job = ctx->job;
	int32_t w = job->width, h = job->height;
	int32_t qx = x + step_x[dir], qy = y + step_y[dir];
	if (qx >= w || qy >= h)
		return 0;
	size_t j = (size_t)qy * w + qx;
	int16_t k = job->slot[i];
	if (job->slot[j] != k || !((ctx->near[i] | ctx->near[j]) & BENT) ||
	    !(ctx->near[i] & NEAR_BENT) || !(ctx->near[j] & NEAR_BENT) ||
	    isnan(ctx->nrm[3 * i]) || isnan(ctx->nrm[3 * j]))
		return 0;
	double P[3], Q[3], n[3], m[3];
	load3(ctx->pos + 3 * i, P);
	load3(ctx->pos + 3 * j, Q);
	load3(ctx->nrm + 3 * i, n);
	load3(ctx->nrm + 3 * j, m);
	if (!convex_pair(ctx, k, x, y, dir, P, n, Q, m, CREASE_MIN_COS))
		return 0;
	const float *wr = job->kernels[k].walk_radius;
	double widest = fmax(wr[0], fmax(wr[1], wr[2]));
	return face_extent(ctx, x, y, dir, P, n) >= widest &&
	       face_extent(ctx, qx, qy, (dir + 4) % 8, Q, m) >= widest;
}

static void break_rows(void *vctx, int32_t y0, int32_t y1)
{
	crease_ctx *ctx = vctx;
	const sss__job *job = ctx->job;
	int32_t w = job->width;
	for (int32_t y = y0; y < y1; y++)
		for (int32_t x = 0; x < w; x++) {
			size_t i = (size_t)y * w + x;
			uint8_t b = 0;
			int16_t k = job->slot[i];
			if (k >= 0 && ctx->stops[k] && (ctx->near[i] & NEAR_BENT)) {
				if (parted(ctx, i, x, y, 0))
					b |= SSS__BREAK_RIGHT;
				if (parted(ctx, i, x, y, 2))
					b |= SSS__BREAK_DOWN;
			}
			ctx->breaks[i] = b;
		}
}

/* The signal of pixel j, channel c. */
static float signal_at(const sss__job *job, size_t j, int c)
{
	return job->signal[(int64_t)j * job->signal_px + c * job->signal_ch];
}

/* A reach in scene units as a window's half-size in pixels. */
static int32_t reach_px(const crease_ctx *ctx, double reach, double pix)
{
	double most = (double)ctx->job->width + ctx->job->height;
	return (int32_t)ceil(fmax(fmin(reach / pix, most), 2.0));
}

/* How far the face of pixel (x, y) goes on away from the neighbour dir
 * across its crease, along the screen line through both, while its
 * points stay on the pixel's tangent plane: light can only cross the edge
 * from where the face is. Past the material's reach F has no mass left,
 * so the march stops there. */
static double face_extent(const crease_ctx *ctx, int32_t x, int32_t y,
                          int dir, const double P[3], const double n[3])
{
	const sss__job *job = ctx->job;
	int16_t k = job->slot[(size_t)y * job->width + x];
	double far = 0.0;
	int32_t steps = reach_px(ctx, ctx->reach[k],
	                         pixel_size(&job->proj, P[2])) + 1;
	for (int32_t s = 1; s <= steps; s++) {
		int32_t u = x - s * step_x[dir], v = y - s * step_y[dir];
		if (u < 0 || v < 0 || u >= job->width || v >= job->height)
			break;
		size_t j = (size_t)v * job->width + u;
		if (job->slot[j] != k)
			break;
		double Q[3], D[3];
		load3(ctx->pos + 3 * j, Q);
		for (int c = 0; c < 3; c++)
			D[c] = Q[c] - P[c];
		double along = sqrt(dot3(D, D));
		if (fabs(dot3(D, n)) > 0.02 * along +
		                       0.5 * pixel_size(&job->proj, Q[2]))
			break;
		far = along;
	}
	return far;
}

/* Lists the crease pixels by tile, each with the light two pixels inside
 * its face (a pixel filter blends the crease pixel itself with the other
 * face). */
static sss_result list_sources(crease_ctx *ctx, int32_t **first_out,
                               int32_t **sat_out,
                               crease_source **sources_out)
{
	const sss__job *job = ctx->job;
	int32_t w = job->width, h = job->height;
	ctx->tiles_x = (w + CREASE_TILE - 1) / CREASE_TILE;
	ctx->tiles_y = (h + CREASE_TILE - 1) / CREASE_TILE;
	size_t tiles = (size_t)ctx->tiles_x * ctx->tiles_y;
	int32_t *first = calloc(tiles + 1, sizeof *first);
	int32_t *sat = calloc((size_t)(ctx->tiles_x + 1) * (ctx->tiles_y + 1),
	                      sizeof *sat);
	if (!first || !sat) {
		free(first);
		free(sat);
		return SSS_ERR_OUT_OF_MEMORY;
	}
	size_t count = 0;
	for (int32_t y = 0; y < h; y++)
		for (int32_t x = 0; x < w; x++)
			if (ctx->across[(size_t)y * w + x] >= 0) {
				first[(size_t)(y / CREASE_TILE) * ctx->tiles_x +
				      x / CREASE_TILE + 1]++;
				count++;
			}
	size_t sw = (size_t)ctx->tiles_x + 1;
	for (int32_t ty = 0; ty < ctx->tiles_y; ty++)
		for (int32_t tx = 0; tx < ctx->tiles_x; tx++)
			sat[(ty + 1) * sw + tx + 1] =
			        first[(size_t)ty * ctx->tiles_x + tx + 1] +
			        sat[ty * sw + tx + 1] + sat[(ty + 1) * sw + tx] -
			        sat[ty * sw + tx];
	for (size_t t = 0; t < tiles; t++)
		first[t + 1] += first[t];
	crease_source *src = malloc((count ? count : 1) * sizeof *src);
	int32_t *fill = malloc((tiles ? tiles : 1) * sizeof *fill);
	if (!src || !fill) {
		free(first);
		free(sat);
		free(src);
		free(fill);
		return SSS_ERR_OUT_OF_MEMORY;
	}
	memcpy(fill, first, tiles * sizeof *fill);
	for (int32_t y = 0; y < h; y++)
		for (int32_t x = 0; x < w; x++) {
			size_t i = (size_t)y * w + x;
			int dir = ctx->across[i];
			if (dir < 0)
				continue;
			double n[3];
			load3(ctx->nrm + 3 * i, n);
			size_t from = i;
			for (int back = 2; back >= 1; back--) {
				int32_t ix = x - back * step_x[dir],
				        iy = y - back * step_y[dir];
				if (flat_at(ctx, job->slot[i], ix, iy, n)) {
					from = (size_t)iy * w + ix;
					break;
				}
			}
			crease_source *e = &src[fill[(size_t)(y / CREASE_TILE) *
			                             ctx->tiles_x + x / CREASE_TILE]++];
			e->x = x, e->y = y;
			load3(ctx->pos + 3 * i, e->pos);
			load3(ctx->nrm + 3 * i, e->nrm);
			e->pix = pixel_size(&job->proj, e->pos[2]);
			e->s_limit = 1.5 * e->pix / facing(ctx, i, n);
			e->extent = face_extent(ctx, x, y, dir, e->pos, n) +
			            0.5 * e->pix / facing(ctx, i, n);
			for (int c = 0; c < 3; c++)
				e->light[c] = signal_at(job, from, c);
		}
	free(fill);
	*first_out = first;
	*sat_out = sat;
	*sources_out = src;
	return SSS_OK;
}

static void window_tiles(const crease_ctx *ctx, int32_t x, int32_t y,
                         int32_t r, int32_t *tx0, int32_t *ty0, int32_t *tx1,
                         int32_t *ty1)
{
	*tx0 = (x > r ? x - r : 0) / CREASE_TILE;
	*ty0 = (y > r ? y - r : 0) / CREASE_TILE;
	*tx1 = (x + r) / CREASE_TILE;
	*ty1 = (y + r) / CREASE_TILE;
	if (*tx1 >= ctx->tiles_x)
		*tx1 = ctx->tiles_x - 1;
	if (*ty1 >= ctx->tiles_y)
		*ty1 = ctx->tiles_y - 1;
}

/* How many sources the tiles under a window of half-size r hold. */
static int32_t sources_near(const crease_ctx *ctx, int32_t x, int32_t y,
                            int32_t r)
{
	int32_t tx0, ty0, tx1, ty1;
	window_tiles(ctx, x, y, r, &tx0, &ty0, &tx1, &ty1);
	const int32_t *sat = ctx->tile_sat;
	size_t sw = (size_t)ctx->tiles_x + 1;
	return sat[(ty1 + 1) * sw + tx1 + 1] - sat[ty0 * sw + tx1 + 1] -
	       sat[(ty1 + 1) * sw + tx0] + sat[ty0 * sw + tx0];
}

/* Whether source src can send light to the receiver at P, normal n, of
 * slot k: not its own face, a convex crease between them, and the source
 * at the edge of the receiver's face (else another face's edge); then
 * the receiver's distance tq from the edge, the source's s from the
 * receiver's plane and how far along the edge they lie apart. */
static int source_seen(const crease_ctx *ctx, const crease_source *src,
                       int16_t k, const double P[3], const double n[3],
                       double *tq, double *s, double *along)
{
	const double *m = src->nrm;
	double cs = dot3(n, m);
	if (cs > CREASE_MIN_COS)
		return 0; /* its own face */
	double D[3];
	for (int c = 0; c < 3; c++)
		D[c] = src->pos[c] - P[c];
	double hq = dot3(D, n), hp = -dot3(D, m);
	if (!(hq < 0.0 && hp < 0.0))
		return 0;
	if (ctx->job->slot[(size_t)src->y * ctx->job->width + src->x] != k)
		return 0;
	double sn = sqrt(fmax(1.0 - cs * cs, 1e-12));
	*tq = -hp / sn, *s = -hq / sn;
	if (*s > src->s_limit)
		return 0;
	double e3[3];
	cross3(n, m, e3);
	*along = dot3(D, e3) / sn;
	return 1;
}

/* Whether any source of the frame can send light to the pixel: all of
 * crease_rows' tests but the window's (which follows the radius), so it
 * holds whatever the radius and is kept with the geometry; crease_rows
 * skips a pixel without one (on the demo head lit from the front, 9 000
 * of the 612 000 pixels within reach of a source have one). Made only
 * for at most RECEIVE_SOURCES sources (each pixel tests all of them). */
#define CAN_RECEIVE 4u
#define RECEIVE_SOURCES 256

static void receive_rows(void *vctx, int32_t y0, int32_t y1)
{
	crease_ctx *ctx = vctx;
	const sss__job *job = ctx->job;
	int32_t w = job->width, count = ctx->tile_first[(size_t)ctx->tiles_x *
	                                                ctx->tiles_y];
	for (int32_t y = y0; y < y1; y++)
		for (int32_t x = 0; x < w; x++) {
			size_t i = (size_t)y * w + x;
			int16_t k = job->slot[i];
			ctx->near[i] &= (uint8_t)~CAN_RECEIVE;
			if (k < 0 || !ctx->enabled[k] || isnan(ctx->nrm[3 * i]))
				continue;
			double P[3], n[3], tq, s, along;
			load3(ctx->pos + 3 * i, P);
			load3(ctx->nrm + 3 * i, n);
			for (int32_t e = 0; e < count; e++) {
				const crease_source *src = &ctx->sources[e];
				if ((src->x != x || src->y != y) &&
				    source_seen(ctx, src, k, P, n, &tq, &s, &along)) {
					ctx->near[i] |= CAN_RECEIVE;
					break;
				}
			}
		}
}

/* The mean of F(t) - F(t + face) over t in [a, b] (extent b - a, the
 * pixel's across the edge), F for Burley's d. */
static double mean_tail(const crease_ctx *ctx, double d, double a, double b,
                        double face, double extent)
{
	double u = 1.0 / d, f = face * u;
	return d * (G_at(ctx, b * u) - G_at(ctx, a * u) - G_at(ctx, b * u + f) +
	            G_at(ctx, a * u + f)) / extent;
}

static void crease_rows(void *vctx, int32_t y0, int32_t y1)
{
	const crease_ctx *ctx = vctx;
	const sss__job *job = ctx->job;
	const sss__projection *proj = &job->proj;
	int32_t w = job->width;
	for (int32_t y = y0; y < y1; y++)
		for (int32_t x = 0; x < w; x++) {
			size_t i = (size_t)y * w + x;
			int16_t k = job->slot[i];
			if (k < 0 || !ctx->enabled[k] ||
			    (ctx->receive_known && !(ctx->near[i] & CAN_RECEIVE)))
				continue;
			const sss__kernel *ker = &job->kernels[k];
			double P[3], n[3];
			load3(ctx->pos + 3 * i, P);
			double pix = pixel_size(proj, P[2]);
			/* no source within the widest reach: nothing to do */
			if (!sources_near(ctx, x, y, reach_px(ctx, ctx->reach[k], pix)))
				continue;
			const float *col = sss__at(ctx->diff_col, x, y);
			double kappa[3], d[3], lkappa[3], ld[3], dmax = 0.0;
			for (int c = 0; c < 3; c++) {
				float kap, gam;
				sss__crease_params(ctx->calibration[k], col[c], &kap,
				                   &gam);
				kappa[c] = (double)kap * ker->mix[c] *
				           ker->calibration_fade[c];
				d[c] = (double)gam * ker->walk_radius[c];
				if (kappa[c] > 0.0 && d[c] > dmax)
					dmax = d[c];
				sss__crease_loss_params(ctx->calibration[k], col[c], &kap,
				                        &gam);
				lkappa[c] = (double)kap * ker->mix[c] *
				            ker->calibration_fade[c];
				ld[c] = (double)gam * ker->walk_radius[c];
				if (lkappa[c] > 0.0 && ld[c] > dmax)
					dmax = ld[c];
			}
			if (!(dmax > 0.0))
				continue;
			int32_t r = reach_px(ctx, CREASE_REACH * dmax, pix);
			int32_t tx0, ty0, tx1, ty1;
			window_tiles(ctx, x, y, r, &tx0, &ty0, &tx1, &ty1);
			/* A window with many sources reads every thin-th of each
			 * tile's: an average along the edges over about
			 * CREASE_SOURCES of them. A row of tiles holds its sources in
			 * one run: its empty tiles cost nothing. */
			int32_t listed = sources_near(ctx, x, y, r);
			if (!listed)
				continue;
			if (isnan(ctx->nrm[3 * i]))
				continue; /* its neighbours do not tell */
			load3(ctx->nrm + 3 * i, n);
			int32_t thin = listed > 2 * CREASE_SOURCES
			               ? listed / CREASE_SOURCES : 1;
			double W = 0.0, WT = 0.0, WS = 0.0, WL[3] = {0};
			for (int32_t ty = ty0; ty <= ty1; ty++) {
				size_t t0 = (size_t)ty * ctx->tiles_x;
				int32_t run1 = ctx->tile_first[t0 + tx1 + 1];
				int32_t e = ctx->tile_first[t0 + tx0];
				while (e < run1) {
					int32_t end = ctx->tile_first[t0 + ctx->sources[e].x /
					                                   CREASE_TILE + 1];
					for (; e < end; e += thin) {
						const crease_source *src = &ctx->sources[e];
						if (abs(src->x - x) > r || abs(src->y - y) > r ||
						    (src->x == x && src->y == y))
							continue;
						double tq, s, along;
						if (!source_seen(ctx, src, k, P, n, &tq, &s, &along))
							continue;
						double g = sqrt((s + tq) * (s + tq) + along * along);
						/* Burley's profile, up to a constant: it only
						 * weighs the sources against each other */
						float u = (float)(fmax(g, 0.5 * src->pix) / dmax);
						double wgt = (expf(-u) + expf(-u / 3.0f)) / u;
						W += wgt;
						WT += wgt * tq;
						WS += wgt * src->extent;
						for (int c = 0; c < 3; c++)
							WL[c] += wgt * src->light[c];
					}
					e = end;
				}
			}
			if (!(W > 0.0) || !ctx->term)
				continue;
			double tm = WT / W, face = WS / W;
			double extent = pix / facing(ctx, i, n);
			float *out = ctx->extra + 3 * i;
			double a = fmax(tm - 0.5 * extent, 0.0), b = tm + 0.5 * extent;
			for (int c = 0; c < 3; c++) {
				double v = 0.0;
				/* from sources at [0, face] from the edge */
				if (kappa[c] > 0.0 && d[c] > 0.0)
					v += kappa[c] * mean_tail(ctx, d[c], a, b, face, extent) *
					     WL[c] / W;
				/* its own light that leaves through the other face */
				if (lkappa[c] > 0.0 && ld[c] > 0.0)
					v -= lkappa[c] *
					     mean_tail(ctx, ld[c], a, b, face, extent) *
					     signal_at(job, i, c);
				out[c] = (float)v;
			}
		}
}

static void point_rows(void *vctx, int32_t y0, int32_t y1)
{
	crease_ctx *ctx = vctx;
	const sss__job *job = ctx->job;
	for (int32_t y = y0; y < y1; y++)
		for (int32_t x = 0; x < job->width; x++) {
			size_t i = (size_t)y * job->width + x;
			double p[3] = {NAN, NAN, NAN};
			if (job->slot[i] >= 0)
				sss__view_point(&job->proj, x, y,
				           job->depth[y * job->depth_stride +
				                      (int64_t)x * job->depth_channels],
				           p);
			for (int c = 0; c < 3; c++)
				((float *)ctx->pos)[3 * i + c] = (float)p[c];
		}
}

/* What the geometry in a workspace (points, bends, normals, creases) was
 * made for: it depends only on the Depth pass (the frame's), the camera,
 * the slot map and which kernels take the term. Followed by the enabled
 * flags, one a kernel. */
typedef struct geometry_key {
	int made;
	int receive_known; /* near[] holds CAN_RECEIVE */
	int32_t w, h, kernel_count;
	sss__projection proj;
} geometry_key;

/* Whether job->ws holds the geometry for this job and enabled set. */
static int geometry_kept(const sss__job *job, int32_t kernel_count,
                         const uint8_t *enabled)
{
	size_t npix = (size_t)job->width * job->height;
	sss__workspace *ws = job->ws;
	const geometry_key *key = sss__ws_kept(ws, SSS__WS_EDGE_KEY,
	                                       sizeof *key + kernel_count);
	return key && key->made && key->w == job->width &&
	       key->h == job->height && key->kernel_count == kernel_count &&
	       sss__same_projection(&key->proj, &job->proj) &&
	       memcmp(key + 1, enabled, (size_t)kernel_count) == 0 &&
	       sss__ws_kept(ws, SSS__WS_EDGE_POS, npix * 3 * sizeof(float)) &&
	       sss__ws_kept(ws, SSS__WS_EDGE_NRM, npix * 3 * sizeof(float)) &&
	       sss__ws_kept(ws, SSS__WS_EDGE_SIDE, npix) &&
	       sss__ws_kept(ws, SSS__WS_EDGE_NEAR, npix) &&
	       sss__ws_same_slots(ws, SSS__WS_EDGE_SLOT, job->slot, npix);
}

/* Notes in job->ws what its geometry was made for. */
static sss_result geometry_keep(const sss__job *job, int32_t kernel_count,
                                const uint8_t *enabled)
{
	size_t npix = (size_t)job->width * job->height;
	geometry_key *key = sss__ws_get(job->ws, SSS__WS_EDGE_KEY,
	                                sizeof *key + kernel_count, 1);
	if (!key || sss__ws_note_slots(job->ws, SSS__WS_EDGE_SLOT, job->slot,
	                               npix))
		return SSS_ERR_OUT_OF_MEMORY;
	memcpy(key + 1, enabled, (size_t)kernel_count);
	*key = (geometry_key){1, 0, job->width, job->height, kernel_count,
	                      job->proj};
	return SSS_OK;
}

sss_result sss__crease(const sss__job *job, int32_t kernel_count,
                       const sss_image *diff_col, const uint8_t *enabled,
                       const int32_t *calibration, int32_t num_threads,
                       float *extra, uint8_t *breaks, int term)
{
	size_t npix = (size_t)job->width * job->height;
	double *reach = malloc((kernel_count ? kernel_count : 1) * sizeof *reach);
	uint8_t *stops = malloc(kernel_count ? kernel_count : 1);
	for (int32_t k = 0; reach && stops && k < kernel_count; k++) {
		float lk, lg;
		sss__crease_loss_params(calibration[k], 0.5f, &lk, &lg);
		/* 2 (no term) stops it for every walk: what a loss row is
		 * fitted against before it exists */
		stops[k] = enabled[k] && (lk > 0.0f || !term);
		/* the table's widest gamma, albedo by albedo */
		float widest = 0.0f, kappa, gamma;
		for (int a = 0; a <= 100; a++) {
			sss__crease_params(calibration[k], 0.01f * a, &kappa, &gamma);
			widest = fmaxf(widest, gamma);
			sss__crease_loss_params(calibration[k], 0.01f * a, &kappa,
			                        &gamma);
			widest = fmaxf(widest, gamma);
		}
		const float *wr = job->kernels[k].walk_radius;
		reach[k] = CREASE_REACH * widest * fmax(wr[0], fmax(wr[1], wr[2]));
	}
	/* A re-tune of radius or colour changes none of what the geometry
	 * depends on: a kept one is used as it is. */
	int kept = job->ws && geometry_kept(job, kernel_count, enabled);
	if (job->ws && !kept) { /* invalid until made again */
		geometry_key *key = sss__ws_kept(job->ws, SSS__WS_EDGE_KEY,
		                                 sizeof *key);
		if (key)
			key->made = 0;
	}
	crease_ctx *ctx = malloc(sizeof *ctx);
	float *pos = sss__ws_get(job->ws, SSS__WS_EDGE_POS,
	                         npix * 3 * sizeof *pos, 0);
	float *nrm = sss__ws_get(job->ws, SSS__WS_EDGE_NRM,
	                         npix * 3 * sizeof *nrm, 0);
	int8_t *across = sss__ws_get(job->ws, SSS__WS_EDGE_SIDE,
	                             npix * sizeof *across, 0);
	uint8_t *near = sss__ws_get(job->ws, SSS__WS_EDGE_NEAR, npix, 0);
	int32_t *first = NULL, *sat = NULL;
	crease_source *sources = NULL;
	sss_result r = ctx && pos && nrm && across && near && reach && stops
	               ? SSS_OK : SSS_ERR_OUT_OF_MEMORY;
	if (!r) {
		*ctx = (crease_ctx){.job = job, .diff_col = diff_col,
		                    .enabled = enabled, .calibration = calibration,
		                    .reach = reach, .pos = pos, .nrm = nrm,
		                    .near = near, .across = across, .extra = extra,
		                    .breaks = breaks, .stops = stops,
		                    .term = term};
		tabulate(ctx);
		memset(extra, 0, npix * 3 * sizeof *extra);
		if (!kept) {
			sss__parallel_rows(job->height, num_threads, point_rows, ctx);
			sss__parallel_rows(job->height, num_threads, bend_rows, ctx);
		}
	}
	int bent = 0;
	for (size_t i = 0; !r && !bent && i < npix; i++)
		bent = near[i] & BENT;
	if (bent && !kept) { /* else no crease: smooth, or only silhouettes */
		mark_near(ctx);
		sss__parallel_rows(job->height, num_threads, normal_rows, ctx);
		sss__parallel_rows(job->height, num_threads, detect_rows, ctx);
	}
	if (!r && breaks) {
		if (bent)
			sss__parallel_rows(job->height, num_threads, break_rows, ctx);
		else
			memset(breaks, 0, npix);
	}
	if (!r && job->ws && !kept)
		r = geometry_keep(job, kernel_count, enabled);
	if (!r && bent)
		r = list_sources(ctx, &first, &sat, &sources);
	if (!r && bent && first[(size_t)ctx->tiles_x * ctx->tiles_y] > 0) {
		ctx->tile_first = first;
		ctx->tile_sat = sat;
		ctx->sources = sources;
		if (job->ws) { /* kept: worth making once */
			geometry_key *key = sss__ws_kept(job->ws, SSS__WS_EDGE_KEY,
			                                 sizeof *key);
			if (key && !key->receive_known &&
			    first[(size_t)ctx->tiles_x * ctx->tiles_y] <=
			            RECEIVE_SOURCES) {
				sss__parallel_rows(job->height, num_threads, receive_rows,
				                   ctx);
				key->receive_known = 1;
			}
			ctx->receive_known = key && key->receive_known;
		}
		sss__parallel_rows(job->height, num_threads, crease_rows, ctx);
	}
	free(first);
	free(sat);
	free(sources);
	free(reach);
	free(stops);
	sss__ws_put(job->ws, near);
	sss__ws_put(job->ws, across);
	sss__ws_put(job->ws, pos);
	sss__ws_put(job->ws, nrm);
	free(ctx);
	return r;
}
