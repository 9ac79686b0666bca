/* sss_glow.c - the transmitted light one visible part of an object sends
 * to another.
 *
 * A back-lit thin part glows, and where it faces another part of the same
 * material (the inside of an ear's cup, a fold) that part is lit by the
 * glow and reflects it. The render without SSS has no glow to bounce, and
 * the back-light layer gathers only what crosses the part at the pixel,
 * so the random walk's light there was missing: on a 1.5 cm skin cup of
 * 6 cm radius lit from behind and seen from inside, ours was 0.72 / 0.67
 * / 0.77 of the walk, on the flat slab of the same skin 1.03 / 1.04 / 1.1
 * (docs/transmission.md, "Glow between facing parts").
 *
 * One bounce, between visible pixels only (no occlusion test): the light
 * leaving each pixel of a transmitting material through transmission,
 * G (radiance, DiffCol applied), reaches every other pixel p of the same
 * slot with the form factor
 *
 *     E(p) = sum_q G(q) A(q) cos_p cos_q / max(r^2, r_min^2),
 *
 * A(q) the surface area q stands for, r the distance between the two
 * surface points (view space, from the Depth pass), cos_p and cos_q the
 * angles between their normals and the line joining them (0 when a point
 * faces away), r_min 1.5 grid steps at p's depth (so that a neighbour on
 * a nearly flat surface does not blow up). The receiver reflects E / pi
 * times its DiffCol, as diffuse light. Points sample a grid of at most
 * GLOW_GRID columns (every pixel up to that width), each standing for its
 * cell's pixels of its slot with the glow of its own pixel. The points of the 3 x 3 cells of GLOW_CELL^2 points
 * around a point's own cell count one by one; the cells beyond, through
 * their sums, as one vector per channel at the middle of the point's cell
 * (the cup's far side: within 8 points the bundled head lost nothing, a
 * cup seen from inside most of its gain). E is interpolated bilinearly
 * between the grid points of the pixel's slot. Flat and convex surfaces
 * exchange nothing (cos_p or cos_q <= 0). */
#include "sss_internal.h"

#include <stdlib.h>
#include <string.h>

/* Grid columns at most, and the grid points a side of a far cell. */
#define GLOW_GRID 240
#define GLOW_CELL 4
/* Smallest view cosine a source's area is divided by. */
#define GLOW_MIN_VIEW 0.05

typedef struct point {
	int16_t slot;  /* -1: none */
	float pos[3];  /* view space */
	float nrm[3];  /* towards the camera; 0 when not told */
	float area;    /* surface area the point stands for */
	float r_min2;  /* squared nearest distance counted */
	float glow[3]; /* G at the point's pixel */
} point;

typedef struct glow_ctx {
	const float *glow;   /* G at the grid points, gw x gh x 3 */
	const sss_image *depth;
	const int16_t *slot;
	const sss__projection *proj;
	const uint8_t *receives; /* per slot: transmission on */
	int32_t w, h, step, gw, gh;
	point *pts;
	float *e;            /* gw x gh x 3 */
	int32_t cw, ch;      /* far cells: GLOW_CELL^2 grid points each */
	struct cell *cells;
	int32_t *sources;    /* the cells that send light, in order */
	int32_t nsources;
} glow_ctx;

/* A far cell: its points of one slot summed, and the light the cells
 * outside its 3 x 3 neighbourhood send to its middle, as a vector per
 * channel (dotted with a receiver's normal: the sources in front of it). */
typedef struct cell {
	int16_t slot;      /* -1: none */
	float pos[3];      /* area-weighted mean position */
	float nrm_area[3]; /* sum of area x normal */
	float area;
	float flux[3];     /* sum of area x glow */
	float in[3][3];    /* [channel][axis] */
} cell;

static float depth_at(const glow_ctx *c, int32_t x, int32_t y)
{
	return sss__at(c->depth, x, y)[0];
}

/* Pixels between grid points for an image w pixels wide. */
static int32_t grid_step(int32_t w)
{
	int32_t step = (w + GLOW_GRID - 1) / GLOW_GRID;
	return step > 1 ? step : 1;
}

/* The grid point (i, j) sits at pixel (i step + step / 2, ...), clamped
 * into the image. */
static int32_t grid_coord(int32_t i, int32_t step, int32_t len)
{
	int32_t p = i * step + step / 2;
	return p < len ? p : len - 1;
}

static void grid_pixel(const glow_ctx *c, int32_t i, int32_t j, int32_t *x,
                       int32_t *y)
{
	*x = grid_coord(i, c->step, c->w);
	*y = grid_coord(j, c->step, c->h);
}

int64_t sss__glow_points(int32_t w, int32_t h)
{
	int32_t step = grid_step(w);
	return (int64_t)((w + step - 1) / step) * ((h + step - 1) / step);
}

int sss__glow_on_row(int32_t w, int32_t h, int32_t y)
{
	int32_t step = grid_step(w);
	return grid_coord(y / step, step, h) == y;
}

int64_t sss__glow_point_of(int32_t w, int32_t h, int32_t x, int32_t y)
{
	int32_t step = grid_step(w), gw = (w + step - 1) / step;
	int32_t i = x / step, j = y / step;
	if (grid_coord(i, step, w) != x || grid_coord(j, step, h) != y)
		return -1;
	return (int64_t)j * gw + i;
}

static void view_point(const glow_ctx *c, int32_t x, int32_t y, float out[3])
{
	double p[3];
	sss__view_point(c->proj, x, y, depth_at(c, x, y), p);
	for (int k = 0; k < 3; k++)
		out[k] = (float)p[k];
}

/* The surface normal at pixel (x, y) from its neighbours `step` pixels
 * away on its slot (central where both are, else one-sided), turned
 * towards the camera; 0 when an axis has neither. */
static void normal_at(const glow_ctx *c, int32_t x, int32_t y, int16_t s,
                      const float here[3], float n[3])
{
	float t[2][3];
	for (int a = 0; a < 2; a++) {
		float lo[3], hi[3];
		int32_t d = c->step;
		int32_t x0 = a ? x : x - d, y0 = a ? y - d : y;
		int32_t x1 = a ? x : x + d, y1 = a ? y + d : y;
		int have0 = x0 >= 0 && y0 >= 0 && c->slot[(size_t)y0 * c->w + x0] == s;
		int have1 = x1 < c->w && y1 < c->h &&
		            c->slot[(size_t)y1 * c->w + x1] == s;
		if (!have0 && !have1) {
			n[0] = n[1] = n[2] = 0.0f;
			return;
		}
		if (have0)
			view_point(c, x0, y0, lo);
		else
			memcpy(lo, here, sizeof lo);
		if (have1)
			view_point(c, x1, y1, hi);
		else
			memcpy(hi, here, sizeof hi);
		for (int k = 0; k < 3; k++)
			t[a][k] = hi[k] - lo[k];
	}
	float cx = t[0][1] * t[1][2] - t[0][2] * t[1][1];
	float cy = t[0][2] * t[1][0] - t[0][0] * t[1][2];
	float cz = t[0][0] * t[1][1] - t[0][1] * t[1][0];
	float len = sqrtf(cx * cx + cy * cy + cz * cz);
	if (!(len > 0.0f) || !isfinite(len)) {
		n[0] = n[1] = n[2] = 0.0f;
		return;
	}
	/* towards the camera: against the ray from it (view space looks
	 * along +Z; the ray to a perspective point is the point itself) */
	float v[3] = {c->proj->ortho ? 0.0f : here[0],
	              c->proj->ortho ? 0.0f : here[1],
	              c->proj->ortho ? 1.0f : here[2]};
	float sign = cx * v[0] + cy * v[1] + cz * v[2] > 0.0f ? -1.0f : 1.0f;
	n[0] = sign * cx / len;
	n[1] = sign * cy / len;
	n[2] = sign * cz / len;
}

static void points_rows(void *vctx, int32_t j0, int32_t j1)
{
	const glow_ctx *c = vctx;
	for (int32_t j = j0; j < j1; j++)
		for (int32_t i = 0; i < c->gw; i++) {
			point *pt = &c->pts[(size_t)j * c->gw + i];
			int32_t x, y;
			grid_pixel(c, i, j, &x, &y);
			int16_t s = c->slot[(size_t)y * c->w + x];
			float z = depth_at(c, x, y);
			pt->slot = -1;
			if (s < 0 || !c->receives[s] || !(z > 0.0f) || !isfinite(z))
				continue;
			view_point(c, x, y, pt->pos);
			normal_at(c, x, y, s, pt->pos, pt->nrm);
			if (pt->nrm[0] == 0.0f && pt->nrm[1] == 0.0f &&
			    pt->nrm[2] == 0.0f)
				continue;
			/* the cell's pixels of this slot: the area it stands for */
			int32_t n = 0;
			int32_t xa = i * c->step, ya = j * c->step;
			int32_t xb = xa + c->step < c->w ? xa + c->step : c->w;
			int32_t yb = ya + c->step < c->h ? ya + c->step : c->h;
			for (int32_t yy = ya; yy < yb; yy++)
				for (int32_t xx = xa; xx < xb; xx++)
					n += c->slot[(size_t)yy * c->w + xx] == s;
			double px_x = c->proj->ortho ? 1.0 / c->proj->fx : z / c->proj->fx;
			double px_y = c->proj->ortho ? 1.0 / c->proj->fy : z / c->proj->fy;
			float len = c->proj->ortho ? 1.0f
			            : sqrtf(pt->pos[0] * pt->pos[0] +
			                    pt->pos[1] * pt->pos[1] +
			                    pt->pos[2] * pt->pos[2]);
			float view = c->proj->ortho ? fabsf(pt->nrm[2])
			             : fabsf(pt->nrm[0] * pt->pos[0] +
			                     pt->nrm[1] * pt->pos[1] +
			                     pt->nrm[2] * pt->pos[2]) / len;
			pt->area = (float)(n * px_x * px_y /
			                   (view > GLOW_MIN_VIEW ? view : GLOW_MIN_VIEW));
			double step = 1.5 * c->step * (px_x > px_y ? px_x : px_y);
			pt->r_min2 = (float)(step * step);
			for (int ch = 0; ch < 3; ch++) {
				float v = c->glow[3 * ((size_t)j * c->gw + i) + ch];
				pt->glow[ch] = isfinite(v) && v > 0.0f ? v : 0.0f;
			}
			pt->slot = s;
		}
}

/* d = to - from, its squared length and length; 0 when they coincide. */
static inline int separation(const float from[3], const float to[3],
                             float d[3], float *r2, float *r)
{
	for (int a = 0; a < 3; a++)
		d[a] = to[a] - from[a];
	*r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
	*r = sqrtf(*r2);
	return *r > 0.0f;
}

static void cells_rows(void *vctx, int32_t cj0, int32_t cj1)
{
	const glow_ctx *c = vctx;
	for (int32_t cj = cj0; cj < cj1; cj++)
		for (int32_t ci = 0; ci < c->cw; ci++) {
			cell *k = &c->cells[(size_t)cj * c->cw + ci];
			memset(k, 0, sizeof *k);
			k->slot = -1;
			double pos[3] = {0.0, 0.0, 0.0};
			for (int32_t j = cj * GLOW_CELL;
			     j < (cj + 1) * GLOW_CELL && j < c->gh; j++)
				for (int32_t i = ci * GLOW_CELL;
				     i < (ci + 1) * GLOW_CELL && i < c->gw; i++) {
					const point *p = &c->pts[(size_t)j * c->gw + i];
					if (p->slot < 0 || (k->slot >= 0 && p->slot != k->slot))
						continue;
					k->slot = p->slot;
					k->area += p->area;
					for (int a = 0; a < 3; a++) {
						pos[a] += (double)p->area * p->pos[a];
						k->nrm_area[a] += p->area * p->nrm[a];
						k->flux[a] += p->area * p->glow[a];
					}
				}
			if (k->slot >= 0 && k->area > 0.0f)
				for (int a = 0; a < 3; a++)
					k->pos[a] = (float)(pos[a] / k->area);
			else
				k->slot = -1;
		}
}

/* What the cells beyond each cell's 3 x 3 neighbourhood send to it. */
static void far_rows(void *vctx, int32_t cj0, int32_t cj1)
{
	const glow_ctx *c = vctx;
	for (int32_t cj = cj0; cj < cj1; cj++)
		for (int32_t ci = 0; ci < c->cw; ci++) {
			cell *k = &c->cells[(size_t)cj * c->cw + ci];
			double in[3][3] = {{0.0}};
			for (int32_t n = 0; k->slot >= 0 && n < c->nsources; n++) {
				int32_t si = c->sources[n] % c->cw;
				int32_t sj = c->sources[n] / c->cw;
				const cell *q = &c->cells[c->sources[n]];
				float d[3], r2, r;
				if ((si >= ci - 1 && si <= ci + 1 && sj >= cj - 1 &&
				     sj <= cj + 1) || q->slot != k->slot ||
				    !separation(k->pos, q->pos, d, &r2, &r))
					continue;
				/* the sources' cosine: their summed area x normal */
				float cq = -(q->nrm_area[0] * d[0] + q->nrm_area[1] * d[1] +
				             q->nrm_area[2] * d[2]) / (r * q->area);
				if (!(cq > 0.0f))
					continue;
				double wgt = cq / ((double)r2 * r);
				for (int ch = 0; ch < 3; ch++)
					for (int a = 0; a < 3; a++)
						in[ch][a] += wgt * q->flux[ch] * d[a];
			}
			for (int ch = 0; ch < 3; ch++)
				for (int a = 0; a < 3; a++)
					k->in[ch][a] = (float)in[ch][a];
		}
}

/* Each grid point: the points of the 3 x 3 cells around its own one by
 * one, the rest through its cell's vector. */
static void gather_rows(void *vctx, int32_t j0, int32_t j1)
{
	const glow_ctx *c = vctx;
	for (int32_t j = j0; j < j1; j++)
		for (int32_t i = 0; i < c->gw; i++) {
			const point *p = &c->pts[(size_t)j * c->gw + i];
			float *e = c->e + 3 * ((size_t)j * c->gw + i);
			e[0] = e[1] = e[2] = 0.0f;
			if (p->slot < 0)
				continue;
			int32_t ci = i / GLOW_CELL, cj = j / GLOW_CELL;
			int32_t ja = (cj - 1) * GLOW_CELL, jb = (cj + 2) * GLOW_CELL;
			int32_t ia = (ci - 1) * GLOW_CELL, ib = (ci + 2) * GLOW_CELL;
			ja = ja > 0 ? ja : 0;
			jb = jb < c->gh ? jb : c->gh;
			ia = ia > 0 ? ia : 0;
			ib = ib < c->gw ? ib : c->gw;
			double acc[3] = {0.0, 0.0, 0.0};
			for (int32_t jj = ja; jj < jb; jj++)
				for (int32_t ii = ia; ii < ib; ii++) {
					const point *q = &c->pts[(size_t)jj * c->gw + ii];
					float d[3], r2, r;
					if (q == p || q->slot != p->slot ||
					    !(q->glow[0] > 0.0f || q->glow[1] > 0.0f ||
					      q->glow[2] > 0.0f) ||
					    !separation(p->pos, q->pos, d, &r2, &r))
						continue;
					float cp = (p->nrm[0] * d[0] + p->nrm[1] * d[1] +
					            p->nrm[2] * d[2]) / r;
					float cq = -(q->nrm[0] * d[0] + q->nrm[1] * d[1] +
					             q->nrm[2] * d[2]) / r;
					if (!(cp > 0.0f) || !(cq > 0.0f))
						continue;
					double wgt = (double)cp * cq * q->area /
					             (r2 > p->r_min2 ? r2 : p->r_min2);
					for (int ch = 0; ch < 3; ch++)
						acc[ch] += wgt * q->glow[ch];
				}
			const cell *k = &c->cells[(size_t)cj * c->cw + ci];
			if (k->slot == p->slot)
				for (int ch = 0; ch < 3; ch++) {
					float far = p->nrm[0] * k->in[ch][0] +
					            p->nrm[1] * k->in[ch][1] +
					            p->nrm[2] * k->in[ch][2];
					if (far > 0.0f)
						acc[ch] += far;
				}
			for (int ch = 0; ch < 3; ch++)
				e[ch] = (float)(acc[ch] / SSS__PI);
		}
}

struct sss__glow {
	glow_ctx c;
};

sss_result sss__glow_make(const float *glow, const sss_image *depth,
                          const int16_t *slot, const uint8_t *receives,
                          const sss__projection *proj, int32_t w, int32_t h,
                          int32_t num_threads, sss__glow **out)
{
	*out = NULL;
	sss__glow *g = calloc(1, sizeof *g);
	if (!g)
		return SSS_ERR_OUT_OF_MEMORY;
	glow_ctx *c = &g->c;
	*c = (glow_ctx){glow, depth, slot, proj, receives, w, h, 1, 0, 0, NULL,
	                NULL, 0, 0, NULL, NULL, 0};
	c->step = grid_step(w);
	c->gw = (w + c->step - 1) / c->step;
	c->gh = (h + c->step - 1) / c->step;
	size_t n = (size_t)c->gw * c->gh;
	c->cw = (c->gw + GLOW_CELL - 1) / GLOW_CELL;
	c->ch = (c->gh + GLOW_CELL - 1) / GLOW_CELL;
	c->pts = malloc(n * sizeof *c->pts);
	c->e = malloc(n * 3 * sizeof *c->e);
	c->cells = malloc((size_t)c->cw * c->ch * sizeof *c->cells);
	c->sources = malloc((size_t)c->cw * c->ch * sizeof *c->sources);
	if (!c->pts || !c->e || !c->cells || !c->sources) {
		sss__glow_free(g);
		return SSS_ERR_OUT_OF_MEMORY;
	}
	sss__parallel_rows(c->gh, num_threads, points_rows, c);
	sss__parallel_rows(c->ch, num_threads, cells_rows, c);
	for (int32_t k = 0; k < c->cw * c->ch; k++) {
		const cell *q = &c->cells[k];
		if (q->slot >= 0 && (q->flux[0] > 0.0f || q->flux[1] > 0.0f ||
		                     q->flux[2] > 0.0f))
			c->sources[c->nsources++] = k;
	}
	sss__parallel_rows(c->ch, num_threads, far_rows, c);
	sss__parallel_rows(c->gh, num_threads, gather_rows, c);
	/* only the points and what they receive are read from here on */
	free(c->cells);
	free(c->sources);
	c->cells = NULL;
	c->sources = NULL;
	*out = g;
	return SSS_OK;
}

/* Bilinear between the four grid points around each pixel, those of its
 * slot only (the point itself where the grid is every pixel). */
void sss__glow_row(const sss__glow *g, int32_t y, const int16_t *slot_row,
                   float *out)
{
	const glow_ctx *c = &g->c;
	memset(out, 0, (size_t)c->w * 3 * sizeof *out);
	if (c->step == 1) {
		const point *row = c->pts + (size_t)y * c->gw;
		const float *e = c->e + 3 * (size_t)y * c->gw;
		for (int32_t x = 0; x < c->w; x++)
			if (slot_row[x] >= 0 && row[x].slot == slot_row[x])
				memcpy(out + 3 * x, e + 3 * x, 3 * sizeof *out);
		return;
	}
	float gy = ((float)y - c->step / 2) / c->step;
	int32_t j0 = (int32_t)floorf(gy);
	float fy = gy - j0;
	const point *r0 = j0 >= 0 ? c->pts + (size_t)j0 * c->gw : NULL;
	const point *r1 = j0 + 1 < c->gh ? c->pts + (size_t)(j0 + 1) * c->gw
	                                 : NULL;
	for (int32_t x = 0; x < c->w; x++) {
		int16_t s = slot_row[x];
		if (s < 0)
			continue;
		float gx = ((float)x - c->step / 2) / c->step;
		int32_t i0 = (int32_t)floorf(gx);
		float fx = gx - i0, wsum = 0.0f, acc[3] = {0.0f, 0.0f, 0.0f};
		if (r0 && r1 && i0 >= 0 && i0 + 1 < c->gw && r0[i0].slot == s &&
		    r0[i0 + 1].slot == s && r1[i0].slot == s &&
		    r1[i0 + 1].slot == s) {
			/* inside the slot: plain bilinear */
			const float *e00 = c->e + 3 * ((size_t)j0 * c->gw + i0);
			const float *e10 = e00 + 3, *e01 = e00 + 3 * c->gw;
			const float *e11 = e01 + 3;
			for (int ch = 0; ch < 3; ch++) {
				float top = e00[ch] + fx * (e10[ch] - e00[ch]);
				float bottom = e01[ch] + fx * (e11[ch] - e01[ch]);
				out[3 * x + ch] = top + fy * (bottom - top);
			}
			continue;
		}
		for (int b = 0; b < 4; b++) {
			int32_t i = i0 + (b & 1), j = j0 + (b >> 1);
			if (i < 0 || j < 0 || i >= c->gw || j >= c->gh)
				continue;
			size_t k = (size_t)j * c->gw + i;
			if (c->pts[k].slot != s)
				continue;
			float wgt = ((b & 1) ? fx : 1.0f - fx) *
			            ((b >> 1) ? fy : 1.0f - fy);
			if (!(wgt > 0.0f))
				continue;
			for (int ch = 0; ch < 3; ch++)
				acc[ch] += wgt * c->e[3 * k + ch];
			wsum += wgt;
		}
		if (wsum > 0.0f)
			for (int ch = 0; ch < 3; ch++)
				out[3 * x + ch] = acc[ch] / wsum;
	}
}

void sss__glow_free(sss__glow *g)
{
	if (!g)
		return;
	free(g->c.pts);
	free(g->c.e);
	free(g->c.cells);
	free(g->c.sources);
	free(g);
}
