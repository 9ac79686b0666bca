/* sss_separable.c - the separable method: a horizontal then a vertical 1-D
 * pass, each depth-aware and renormalised per channel.
 *
 * At every scattering pixel the kernel's support (scene units) is projected
 * through the camera at that pixel's depth, giving a half-width R in pixels.
 * If the whole kernel fits in the tap budget (2 floor(R) + 1 <= taps) every
 * pixel under it is a tap ("dense"); otherwise `taps` taps are spread with
 * Jimenez's quadratic spacing o_i = R (i/h)^2 and midpoint footprints, and
 * read with linear interpolation ("sparse"). A tap weighs the profile's
 * 1-D mass over its footprint on a plane facing the camera (so Burley's
 * singular centre is exact), times a falloff in how far the sample lies off
 * that plane (sss_blur1d.h): foreshortened surfaces blur less on screen and
 * a sample across a depth step weighs nothing.
 *
 * Speed: dense weights are tabulated once per material over the kernel
 * half-widths that occur (every 1/32 pixel, interpolated), sparse weights do
 * not depend on the half-width at all, so the per-sample work is a handful
 * of multiplications that run on eight AVX2 lanes where the CPU has them.
 * Sparse taps are read by the vector loop itself (both sides' offsets and
 * weights made once per material), and their far part is summed at every
 * STRIDE-th pixel and interpolated between (blur_pixel). The vertical pass
 * runs as a horizontal one over a transposed copy, so both read memory in
 * order.
 */
#include "sss_internal.h"
#include "sss_blur1d.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

/* Dense tables: half-widths every 1/R_STEPS pixel up to DENSE_MAX_HALF,
 * every pixel a tap, for tap budgets up to 2 DENSE_MAX_HALF + 1 (larger
 * budgets compute their weights per pixel). A kernel that fits is read
 * densely whatever its budget: every pixel in the vector loop costs less
 * than a sparse budget's gathered pairs (about a fifth at 24-32 px,
 * sss-bench --taps) and follows the profile at least as closely, so the
 * budget only thins kernels wider than this. */
#define R_STEPS 32
#define DENSE_MAX_HALF 64
#define PARAMS 6 /* W_r W_g W_b, A_r/8 A_g/8 A_b/8 */

/* Rows handled together, so that the transposed reads and writes fill
 * whole cache lines instead of touching one page per pixel. */
#define BLOCK 16

/* The falloff is matched to the profile's mass at this off-plane distance,
 * as a fraction of the support. */
#define MATCH_OFFSET 0.1

typedef struct table {
	int32_t half;     /* taps right of the centre, (taps - 1) / 2 */
	int32_t dense_half; /* widest dense row: DENSE_MAX_HALF, or half if
	                       that is 0 (the identity) or beyond tables */
	int32_t stride;   /* floats per parameter in a row, padded */
	float cut_q;      /* squared support */
	/* Dense rows j0 .. j0 + rows - 1 for half-widths 1 + j / R_STEPS. */
	int32_t j0, rows;
	float *dense;
	/* Sparse: taps 0..half at offsets r * sparse_at[t], with W and A/8. */
	float *sparse_at, *sparse_w; /* sparse_w: [t * PARAMS + p] */
	sss__taps sparse;            /* the same taps, both sides */
	/* Half-widths of the pixels that use dense rows, both axes. */
	double r_min, r_max;
	/* Per axis, pixels whose kernel a limit cut (max_support_px): one
	 * half-width, weights depending on the scene units per pixel only,
	 * tabulated over its logarithm (CAP_STEPS rows a unit, interpolated)
	 * for the depths those pixels have. */
	struct capped {
		double r;          /* the cut half-width, pixels; 0 = no table */
		double lu0;        /* log(units per pixel) of row 0 */
		int32_t n, rows;   /* taps right of the centre; rows */
		float *at;         /* n + 1 offsets in units of r */
		sss__taps layout;  /* both sides' offsets and cells (its own
		                      w and a8 unused) */
		size_t size;       /* floats per array of the layout */
		size_t row_floats; /* a row of sides: 6 x size, then 3 */
		float *sides;      /* rows x row_floats: W_c, then A_c/8, of
		                      every tap on both sides, then the centre's
		                      W_c */
		double z_lo, z_hi; /* the depths to cover (scan_half_widths) */
	} cap[2];
} table;

/* Rows a unit of log(units per pixel) in a cut kernel's table (steps of
 * 0.1 %: on a 1080p head at twice its radius the result moves by at most
 * 5e-6, against the weights made per pixel), and the most rows one may
 * have (depths up to e^8 apart; farther ranges make them per pixel). */
#define CAP_STEPS 1024.0
#define CAP_MAX_ROWS 8192

/* The taps' weights W (mass over the cell [x - below, x + above] pixels on
 * a plane facing the camera) and falloff coefficients A / 8, for upp scene
 * units per pixel. A is chosen so that rho(q A) equals the mass the cell
 * has when moved MATCH_OFFSET * support off the plane, its distance
 * becoming the true 3-D one; rho then follows the profile from the plane
 * out to there (exactly so for a Gaussian's first order). */
static void tap_weights(const sss__kernel *k, double x, double below,
                        double above, double upp, float *w, float *a8)
{
	double planar[3], moved[3];
	sss__line_mass3(k, (x - below) * upp, (x + above) * upp, planar);
	double off = MATCH_OFFSET * k->support;
	double d = sqrt(x * upp * x * upp + off * off);
	sss__line_mass3(k, d - below * upp, d + above * upp, moved);
	for (int c = 0; c < 3; c++) {
		w[c] = (float)planar[c];
		double rho = planar[c] > 0.0 ? moved[c] / planar[c] : 0.0;
		rho = rho < 0.0 ? 0.0 : rho > 1.0 ? 1.0 : rho;
		/* rho = (1 - off^2 a8)^8; the eighth root as three square
		 * roots (correctly rounded each: the float result is pow's,
		 * at a tenth of its cost on pixels whose weights are made
		 * one by one) */
		a8[c] = (float)((1.0 - sqrt(sqrt(sqrt(rho)))) / (off * off));
	}
}

/* The centre tap and the taps right of it for a kernel of half-width r
 * pixels, as offsets and cells (pixels). If every pixel under the kernel
 * fits in the tap budget, each is a tap with a one-pixel cell ("dense");
 * otherwise `taps` taps follow Jimenez's quadratic spacing o_i = r (i/h)^2
 * and each cell reaches halfway to the neighbouring taps, the midpoint rule
 * of his "area" weights. Returns the number of taps right of the centre. */
int32_t sss__tap_layout(int32_t taps, double r, sss__tap *tap)
{
	int32_t half_taps = (taps - 1) / 2;
	/* Every pixel whose cell reaches into the support. */
	int32_t dense = (int32_t)(r + 0.5);
	tap[0] = (sss__tap){0.0, -0.5, 0.5};
	if (half_taps == 0)
		return 0; /* one tap: the centre alone, the identity */
	if (dense <= half_taps) {
		for (int32_t t = 1; t <= dense; t++)
			tap[t] = (sss__tap){t, t - 0.5, t + 0.5};
		return dense;
	}
	double inv_h = 1.0 / half_taps;
	for (int32_t t = 0; t <= half_taps; t++)
		tap[t].offset = r * (t * inv_h) * (t * inv_h);
	for (int32_t t = 0; t <= half_taps; t++) {
		double prev = t ? tap[t - 1].offset : -tap[1].offset;
		double next = t < half_taps ? tap[t + 1].offset : tap[t].offset;
		tap[t].lo = 0.5 * (prev + tap[t].offset);
		tap[t].hi = 0.5 * (tap[t].offset + next);
	}
	return half_taps;
}

static int32_t dense_half(int32_t half)
{
	return half > 0 && half < DENSE_MAX_HALF ? DENSE_MAX_HALF : half;
}

static float *dense_row(const table *t, int32_t j)
{
	return t->dense + (size_t)(j - t->j0) * PARAMS * t->stride +
	       t->dense_half;
}

/* Floats per array of an sss__taps for taps 1..n, both sides (the centre
 * is kept apart); at least one vector. */
static size_t taps_size(int32_t n)
{
	size_t size = ((size_t)2 * n + SSS__LANES - 1) / SSS__LANES * SSS__LANES;
	return size ? size : SSS__LANES;
}

/* Floats an sss__taps for taps 0..n takes. */
#define TAPS_FLOATS(n) (7 * taps_size(n) + taps_size(n) / SSS__LANES)

/* Points l's arrays into m (TAPS_FLOATS(n) floats). */
static void taps_point(sss__taps *l, float *m, int32_t n)
{
	size_t size = taps_size(n);
	l->at = m;
	for (int c = 0; c < 3; c++) {
		l->w[c] = m + (1 + c) * size;
		l->a8[c] = m + (4 + c) * size;
	}
	l->cell = m + 7 * size;
	for (int c = 0; c < 3; c++)
		l->w1[c] = l->a81[c] = NULL;
	l->f = 0.0f;
}

/* Taps 0..n at offsets at[t] (units of the half-width) with weights
 * wa[t * PARAMS + p] as both sides' taps: the centre's W apart, then each
 * tap left and right of it, padded with zero weights. */
static void both_sides(int32_t n, const float *at, const float *wa,
                       sss__taps *l)
{
	int32_t m = 0;
	for (int c = 0; c < 3; c++)
		l->centre[c] = wa[c];
	for (int32_t t = 1; t <= n; t++) {
		const float *p = wa + (size_t)t * PARAMS;
		/* the cell reaches halfway to the neighbouring taps */
		float cell = 0.5f * (at[t < n ? t + 1 : t] - at[t - 1]);
		for (int sign = -1; sign <= 1; sign += 2) {
			int32_t v = m / SSS__LANES;
			if (m % SSS__LANES == 0 || cell < l->cell[v])
				l->cell[v] = cell;
			l->at[m] = sign * at[t];
			for (int c = 0; c < 3; c++) {
				l->w[c][m] = p[c];
				l->a8[c][m] = p[3 + c];
			}
			m++;
		}
	}
	for (; m % SSS__LANES; m++) {
		l->at[m] = 0.0f;
		for (int c = 0; c < 3; c++)
			l->w[c][m] = l->a8[c][m] = 0.0f;
	}
	l->count = m;
}

/* Rows for every half-width in [r_min, r_max] and the sparse taps. */
static sss_result table_build(const sss__kernel *k, table *t)
{
	int32_t half = (k->taps - 1) / 2;
	t->half = half;
	t->dense_half = dense_half(half);
	t->stride = (2 * t->dense_half + 1 + SSS__LANES - 1 + SSS__LANES - 1) /
	            SSS__LANES * SSS__LANES;
	t->cut_q = (float)(k->support * k->support);
	t->sparse_at = malloc((size_t)(half + 1) * sizeof *t->sparse_at);
	t->sparse_w = malloc((size_t)(half + 1) * PARAMS * sizeof *t->sparse_w);
	if (!t->sparse_at || !t->sparse_w)
		return SSS_ERR_OUT_OF_MEMORY;
	if (half > 0) {
		/* Any half-width past the dense range gives the same layout in
		 * units of itself. */
		sss__tap tap[SSS__MAX_HALF_TAPS + 1];
		double r = half + 1.0;
		sss__tap_layout(k->taps, r, tap);
		for (int32_t i = 0; i <= half; i++) {
			t->sparse_at[i] = (float)(tap[i].offset / r);
			float *p = t->sparse_w + (size_t)i * PARAMS;
			tap_weights(k, tap[i].offset, tap[i].offset - tap[i].lo,
			            tap[i].hi - tap[i].offset, k->support / r, p, p + 3);
		}
	}
	t->sparse.at = malloc(TAPS_FLOATS(half) * sizeof(float));
	if (!t->sparse.at)
		return SSS_ERR_OUT_OF_MEMORY;
	taps_point(&t->sparse, t->sparse.at, half);
	both_sides(half, t->sparse_at, t->sparse_w, &t->sparse);
	if (!(t->r_max >= t->r_min) || half > DENSE_MAX_HALF)
		return SSS_OK;
	t->j0 = (int32_t)((t->r_min - 1.0) * R_STEPS);
	t->rows = (int32_t)((t->r_max - 1.0) * R_STEPS) + 2 - t->j0;
	t->dense = calloc((size_t)t->rows * PARAMS * t->stride, sizeof *t->dense);
	if (!t->dense)
		return SSS_ERR_OUT_OF_MEMORY;
	for (int32_t j = t->j0; j < t->j0 + t->rows; j++) {
		double r = 1.0 + (double)j / R_STEPS;
		int32_t n = (int32_t)(r + 0.5);
		if (n > t->dense_half)
			n = t->dense_half;
		float *row = dense_row(t, j);
		for (int32_t s = 0; s <= n; s++) {
			float w[3], a8[3];
			tap_weights(k, s, 0.5, 0.5, k->support / r, w, a8);
			for (int c = 0; c < 3; c++) {
				row[c * t->stride + s] = row[c * t->stride - s] = w[c];
				row[(3 + c) * t->stride + s] = a8[c];
				row[(3 + c) * t->stride - s] = a8[c];
			}
		}
	}
	return SSS_OK;
}

static void table_free(table *t)
{
	free(t->dense);
	free(t->sparse_at);
	free(t->sparse_w);
	free(t->sparse.at);
	for (int a = 0; a < 2; a++) {
		free(t->cap[a].at);
		free(t->cap[a].layout.at);
		free(t->cap[a].sides);
	}
}

/* One orientation of the working data: rows run along the pass axis. */
typedef struct plane {
	int32_t len, rows;
	float *rgb[3];         /* planar light, 0 where nothing scatters */
	float *z;              /* depth */
	int32_t *slot;         /* the job's, widened for the vector loop */
} plane;

/* The projection along and across the rows. */
typedef struct axis {
	int ortho;
	double f, c;           /* pixels per unit at depth 1, principal point */
	double f_perp, c_perp;
} axis;

typedef struct pass_ctx {
	const sss__job *job;
	const table *tables;
	plane in, out;         /* first pass: out is the transposed plane */
	axis ax;
	int first;
	int avx2;
	int32_t half_max;      /* largest tap count right of the centre */
	atomic_int *failed;    /* a band could not allocate its scratch */
	int planes_kept;       /* depth and slots laid out already */
} pass_ctx;

/* Half-width in pixels of kernel k at depth z along the axis, and whether
 * a limit cut it. */
static double half_width(const sss__job *job, const sss__kernel *k,
                         const axis *ax, int32_t len, double z, int *capped)
{
	double r = k->support * (ax->ortho ? ax->f : ax->f / z);
	*capped = 0;
	if (r > job->max_support_px || r > len) {
		r = fmin(job->max_support_px, len);
		*capped = 1;
	}
	return r;
}

/* The table of a kernel's cut pixels along one axis (tables[].cap[a]):
 * the layout of the cut half-width r and, for units per pixel from the
 * nearest such pixel's to the farthest's, every tap's weights. Nothing
 * when no pixel is cut, when the budget is too large to tabulate, or when
 * the depths are not usable (those pixels make their weights one by
 * one). */
static sss_result cap_build(const sss__job *job, const sss__kernel *k,
                            const axis *ax, int32_t len, struct capped *c)
{
	double r = fmin(job->max_support_px, len);
	double z_lo = c->z_lo, z_hi = c->z_hi;
	c->r = 0.0;
	if (!(z_lo > 0.0 && z_lo <= z_hi && isfinite(z_hi)) ||
	    (k->taps - 1) / 2 > SSS__MAX_HALF_TAPS)
		return SSS_OK;
	double u_lo = ax->ortho ? 1.0 / ax->f : z_lo / ax->f;
	double u_hi = ax->ortho ? 1.0 / ax->f : z_hi / ax->f;
	double span = log(u_hi) - log(u_lo);
	if (!(u_lo > 0.0) || !isfinite(span))
		return SSS_OK;
	int32_t rows = (int32_t)ceil(span * CAP_STEPS) + 2;
	if (rows > CAP_MAX_ROWS)
		return SSS_OK;
	sss__tap tap[SSS__MAX_HALF_TAPS + 1];
	float wa[(SSS__MAX_HALF_TAPS + 1) * PARAMS];
	int32_t n = sss__tap_layout(k->taps, r, tap);
	size_t size = taps_size(n);
	c->at = malloc((size_t)(n + 1) * sizeof *c->at);
	c->layout.at = malloc(TAPS_FLOATS(n) * sizeof(float));
	c->size = size;
	c->row_floats = 6 * size + 3;
	c->sides = malloc((size_t)rows * c->row_floats * sizeof *c->sides);
	if (!c->at || !c->layout.at || !c->sides)
		return SSS_ERR_OUT_OF_MEMORY;
	taps_point(&c->layout, c->layout.at, n);
	for (int32_t t = 0; t <= n; t++)
		c->at[t] = (float)(tap[t].offset / r);
	c->lu0 = log(u_lo);
	for (int32_t j = 0; j < rows; j++) {
		double upp = exp(c->lu0 + j / CAP_STEPS);
		for (int32_t t = 0; t <= n; t++) {
			float *p = wa + (size_t)t * PARAMS;
			tap_weights(k, tap[t].offset, tap[t].offset - tap[t].lo,
			            tap[t].hi - tap[t].offset, upp, p, p + 3);
		}
		/* this row's weights, both sides, in the layout's order */
		sss__taps row = c->layout;
		float *at_row = c->sides + (size_t)j * c->row_floats;
		for (int p = 0; p < 3; p++) {
			row.w[p] = at_row + p * size;
			row.a8[p] = at_row + (3 + p) * size;
		}
		both_sides(n, c->at, wa, &row);
		for (int p = 0; p < 3; p++)
			at_row[6 * size + p] = row.centre[p];
		c->layout.count = row.count;
	}
	c->n = n;
	c->rows = rows;
	c->r = r;
	return SSS_OK;
}

/* Where a cut pixel's weights lie in its table: rows r0 and r0 +
 * row_floats, interpolated by f at upp units per pixel; 0 if upp lies
 * outside the table. */
static int cap_row(const struct capped *c, double upp, float **r0, float *f)
{
	double x = (log(upp) - c->lu0) * CAP_STEPS;
	if (!(x >= 0.0 && x <= c->rows - 1))
		return 0;
	int32_t j = (int32_t)x;
	if (j > c->rows - 2)
		j = c->rows - 2;
	*f = (float)(x - j);
	*r0 = c->sides + (size_t)j * c->row_floats;
	return 1;
}

/* Per band of rows: room for one pixel's per-pixel taps, both sides. */
typedef struct scratch {
	sss__tap *tap;
	float *at, *wa;
	sss__taps taps;
	sss__taps cut;  /* a cut kernel's: offsets, cells and two rows of
	                   weights its table's, interpolated in the loop */
} scratch;

static void *scratch_new(scratch *sc, int32_t half)
{
	size_t taps = (size_t)half + 1;
	char *m = malloc(taps * sizeof *sc->tap +
	                 (taps * (1 + PARAMS) + TAPS_FLOATS(half)) * sizeof(float));
	if (!m)
		return NULL;
	sc->tap = (sss__tap *)(void *)m;
	sc->at = (float *)(void *)(sc->tap + taps);
	sc->wa = sc->at + taps;
	taps_point(&sc->taps, sc->wa + taps * PARAMS, half);
	return m;
}

/* What every pixel of row `row` of ctx->in shares; for a perspective
 * camera two_xt and upp are per unit depth. */
static void row_template(const pass_ctx *ctx, int32_t row, sss__blur1d *b)
{
	const plane *pl = &ctx->in;
	const axis *ax = &ctx->ax;
	size_t base = (size_t)row * pl->len;
	double perp = (row + 0.5 - ax->c_perp) / ax->f_perp;
	memset(b, 0, sizeof *b);
	for (int c = 0; c < 3; c++)
		b->rgb[c] = pl->rgb[c] + base;
	b->z = pl->z + base;
	b->slot = pl->slot + base;
	b->readable = (int64_t)pl->len * (pl->rows - row);
	b->len = pl->len;
	b->off_axis = (float)(0.5 - ax->c);
	b->ife = ax->ortho ? 0.0f : (float)(1.0 / ax->f);
	b->two_xt = (float)(2.0 / ax->f);
	b->cz = ax->ortho ? 1.0f : (float)(1.0 + perp * perp);
}

/* How a pixel's 1-D blur is made. */
enum { IDENTITY, DENSE, SPARSE };

/* Sparse taps are summed in two parts: the first NEAR_VECTORS vectors
 * (the centre and the taps next to it) at every pixel, the rest (the far
 * taps, cells of STRIDE pixels or more) at every STRIDE-th pixel of a row
 * (the anchors) and interpolated linearly between two anchors. Their sum
 * changes as slowly along the row as their cells are wide: interpolating
 * over a cell moves each far sample by less than the cell its one point
 * already stands for. A pixel takes its own far sum instead where either
 * anchor is on another material, is cut by a limit where it is not (or
 * the reverse), has no far taps that wide, or where the depth does not run
 * straight between them: off the line by more than DEPTH_BEND, or rising
 * by more than DEPTH_SPAN, of the support (a step, a crease, a grazing
 * surface). */
#define NEAR_VECTORS 1
#define STRIDE 4
#define DEPTH_BEND 0.002
#define DEPTH_SPAN 0.05

typedef struct anchor {
	int32_t pos;     /* position along the row; -1: none */
	int ok;          /* far sums usable */
	int32_t slot;
	int capped;
	float z;
	float acc[3], ws[3];
} anchor;

/* A plane's slot holds the kernel in its low 16 bits and, above, which
 * face of the row (between creases, sss__job.breaks) the pixel is on:
 * samples count only on the centre's kernel and face. */
#define FACE_SHIFT 16
static int32_t kernel_of(int32_t slot)
{
	return slot & ((1 << FACE_SHIFT) - 1);
}

/* The kind of blur pixel i of the row needs, with its half-width. */
static int pixel_kind(const pass_ctx *ctx, const sss__blur1d *row,
                      int32_t i, double *r, int *capped)
{
	int32_t slot = kernel_of(row->slot[i]);
	const table *t = &ctx->tables[slot];
	*r = half_width(ctx->job, &ctx->job->kernels[slot], &ctx->ax,
	                ctx->in.len, row->z[i], capped);
	if (!(*r >= 1.0) || t->half == 0)
		return IDENTITY; /* nothing but the centre within reach */
	if (!*capped && t->dense && *r < t->dense_half + 0.5)
		return DENSE;
	return SPARSE;
}

/* b for pixel i of the row, of the given kind and half-width; for SPARSE,
 * its taps (the table's, or made in sc). */
static const sss__taps *pixel_setup(const pass_ctx *ctx,
                                    const sss__blur1d *row, int32_t i,
                                    int kind, double r, int capped,
                                    scratch *sc, sss__blur1d *b)
{
	const sss__job *job = ctx->job;
	const plane *pl = &ctx->in;
	const axis *ax = &ctx->ax;
	int32_t slot = kernel_of(row->slot[i]);
	const sss__kernel *k = &job->kernels[slot];
	const table *t = &ctx->tables[slot];
	float zc = row->z[i];
	*b = *row;
	b->i = i;
	b->slot_c = row->slot[i];
	b->r = (float)r;
	b->zc = zc;
	b->cut_q = t->cut_q;
	if (!ax->ortho)
		b->two_xt = zc * row->two_xt;

	if (kind == DENSE) {
		double fj = (r - 1.0) * R_STEPS;
		int32_t j = (int32_t)fj;
		int32_t n = (int32_t)(1.0 + (double)(j + 1) / R_STEPS + 0.5);
		if (n > t->dense_half)
			n = t->dense_half;
		b->f = (float)(fj - j);
		b->row0 = dense_row(t, j);
		b->row1 = dense_row(t, j + 1);
		b->stride = t->stride;
		b->s_lo = i < n ? -i : -n;
		b->s_hi = pl->len - 1 - i < n ? pl->len - 1 - i : n;
		return NULL;
	}
	if (!capped && r >= t->half + 0.5)
		return &t->sparse;
	const struct capped *cut = &t->cap[!ctx->first];
	float *r0, f;
	if (capped && cut->r == r &&
	    cap_row(cut, ax->ortho ? 1.0 / ax->f : zc / ax->f, &r0, &f)) {
		/* a limit cut the kernel: its table's taps, the weights
		 * interpolated between two rows as they are read */
		size_t size = cut->size, next = cut->row_floats;
		sss__taps *l = &sc->cut;
		l->count = cut->layout.count;
		l->at = cut->layout.at;
		l->cell = cut->layout.cell;
		for (int c = 0; c < 3; c++) {
			l->w[c] = r0 + c * size;
			l->a8[c] = r0 + (3 + c) * size;
			l->w1[c] = l->w[c] + next;
			l->a81[c] = l->a8[c] + next;
			/* as the loop interpolates its taps' W */
			float w0 = r0[6 * size + c], w1 = r0[next + 6 * size + c];
			l->centre[c] = w0 + f * (w1 - w0);
		}
		l->f = f;
		return l;
	}
	/* Weights for this pixel alone: the tap budget is too large to
	 * tabulate, or the depth lies outside the table. */
	double ppu = ax->ortho ? ax->f : ax->f / zc;
	int32_t n = sss__tap_layout(k->taps, r, sc->tap);
	for (int32_t s = 0; s <= n; s++) {
		const sss__tap *tp = &sc->tap[s];
		float *p = sc->wa + (size_t)s * PARAMS;
		sc->at[s] = (float)(tp->offset / r);
		tap_weights(k, tp->offset, tp->offset - tp->lo, tp->hi - tp->offset,
		            1.0 / ppu, p, p + 3);
	}
	both_sides(n, sc->at, sc->wa, &sc->taps);
	return &sc->taps;
}

/* The sums of vectors v0 .. v1 - 1 of taps at b's pixel. */
static void taps_sum(const pass_ctx *ctx, sss__blur1d *b, const sss__taps *t,
                     int32_t v0, int32_t v1)
{
	if (ctx->avx2)
		sss__blur1d_taps_avx2(b, t, v0, v1);
	else
		sss__blur1d_taps_scalar(b, t, v0, v1);
}

/* Whether b's far taps (past NEAR_VECTORS) have cells of STRIDE pixels. */
static int far_is_wide(const sss__blur1d *b, const sss__taps *t)
{
	return t->count / SSS__LANES > NEAR_VECTORS &&
	       t->cell[NEAR_VECTORS] * b->r >= (float)STRIDE;
}

/* The far sums of pixel pos of the row, where it can be an anchor. */
static void anchor_at(const pass_ctx *ctx, const sss__blur1d *row,
                      int32_t pos, scratch *sc, anchor *a)
{
	a->pos = pos;
	a->ok = 0;
	if (pos >= ctx->in.len || row->slot[pos] < 0)
		return;
	double r;
	int capped;
	if (pixel_kind(ctx, row, pos, &r, &capped) != SPARSE)
		return;
	sss__blur1d b;
	const sss__taps *t = pixel_setup(ctx, row, pos, SPARSE, r, capped, sc,
	                                 &b);
	if (!far_is_wide(&b, t))
		return;
	taps_sum(ctx, &b, t, NEAR_VECTORS, t->count / SSS__LANES);
	a->ok = 1;
	a->slot = row->slot[pos];
	a->capped = capped;
	a->z = b.zc;
	for (int c = 0; c < 3; c++) {
		a->acc[c] = b.acc[c];
		a->ws[c] = b.wsum[c];
	}
}

/* The 1-D blur of row `row` of ctx->in at pixel i into out; 0 if it is
 * the identity there (kernel narrower than a pixel at this depth). anc:
 * the row's last two anchors, kept from pixel to pixel. */
static int blur_pixel(const pass_ctx *ctx, const sss__blur1d *row,
                      int32_t i, scratch *sc, anchor anc[2], float out[3])
{
	double r;
	int capped;
	int kind = pixel_kind(ctx, row, i, &r, &capped);
	if (kind == IDENTITY)
		return 0;
	int32_t d = i % STRIDE;
	if (kind == SPARSE && d != 0) {
		/* the anchors left and right of i, first (their taps may use
		 * sc, which the pixel's own then replace) */
		int32_t a = i - d;
		if (anc[0].pos != a) {
			if (anc[1].pos == a)
				anc[0] = anc[1];
			else
				anchor_at(ctx, row, a, sc, &anc[0]);
		}
		if (anc[1].pos != a + STRIDE)
			anchor_at(ctx, row, a + STRIDE, sc, &anc[1]);
	}
	sss__blur1d b;
	const sss__taps *t = pixel_setup(ctx, row, i, kind, r, capped, sc, &b);
	if (kind == DENSE) {
		if (ctx->avx2)
			sss__blur1d_avx2(&b);
		else
			sss__blur1d_scalar(&b);
	} else {
		int32_t nv = t->count / SSS__LANES;
		int32_t near = nv < NEAR_VECTORS ? nv : NEAR_VECTORS;
		float acc[3], ws[3];
		taps_sum(ctx, &b, t, 0, near);
		for (int c = 0; c < 3; c++) { /* and the centre's own light */
			acc[c] = b.acc[c] + t->centre[c] * row->rgb[c][i];
			ws[c] = b.wsum[c] + t->centre[c];
		}
		const anchor *lo = &anc[0], *hi = &anc[1];
		double support = ctx->job->kernels[kernel_of(b.slot_c)].support;
		float u = (float)d / STRIDE;
		int between = d != 0 && lo->ok && hi->ok && lo->slot == b.slot_c &&
		              hi->slot == b.slot_c && lo->capped == capped &&
		              hi->capped == capped && far_is_wide(&b, t) &&
		              fabs((double)hi->z - lo->z) <= DEPTH_SPAN * support &&
		              fabs(b.zc - (lo->z + u * (hi->z - lo->z))) <=
		                      DEPTH_BEND * support;
		if (between) {
			for (int c = 0; c < 3; c++) {
				b.acc[c] = lo->acc[c] + u * (hi->acc[c] - lo->acc[c]);
				b.wsum[c] = lo->ws[c] + u * (hi->ws[c] - lo->ws[c]);
			}
		} else if (d == 0 && anc[1].pos == i && anc[1].ok) {
			/* this pixel is the anchor the last one read: its far
			 * sums are made */
			anc[0] = anc[1];
			for (int c = 0; c < 3; c++) {
				b.acc[c] = anc[0].acc[c];
				b.wsum[c] = anc[0].ws[c];
			}
		} else if (nv > near) {
			taps_sum(ctx, &b, t, near, nv);
			if (d == 0) { /* the next pixels' left anchor */
				anchor *a = &anc[0];
				a->pos = i;
				a->ok = far_is_wide(&b, t);
				a->slot = b.slot_c;
				a->capped = capped;
				a->z = b.zc;
				for (int c = 0; c < 3; c++) {
					a->acc[c] = b.acc[c];
					a->ws[c] = b.wsum[c];
				}
			}
		} else {
			for (int c = 0; c < 3; c++)
				b.acc[c] = b.wsum[c] = 0.0f;
		}
		for (int c = 0; c < 3; c++) {
			b.acc[c] += acc[c];
			b.wsum[c] += ws[c];
		}
	}
	for (int c = 0; c < 3; c++)
		out[c] = b.wsum[c] > 0.0f ? b.acc[c] / b.wsum[c] : row->rgb[c][i];
	return 1;
}

/* Rows y0..y1 of both planes from the job, scattering pixels only: planar
 * light and depth, and their transposes for the second pass. */
static void fill_rows(void *vctx, int32_t y0, int32_t y1)
{
	const pass_ctx *ctx = vctx;
	const sss__job *job = ctx->job;
	const plane *in = &ctx->in, *out = &ctx->out;
	int32_t w = job->width, h = job->height;
	/* This chunk's rows are a segment of every transposed row: no light,
	 * no material until a scattering pixel says otherwise. */
	for (int32_t x = 0; x < w; x++) {
		size_t o = (size_t)x * h + y0, n = (size_t)(y1 - y0);
		for (int c = 0; c < 3; c++)
			memset(out->rgb[c] + o, 0, n * sizeof(float));
		if (!ctx->planes_kept)
			memset(out->slot + o, 0xff, n * sizeof *out->slot); /* -1 */
	}
	if (ctx->planes_kept)
		return; /* a kept workspace's, for this slot map */
	for (size_t i = (size_t)y0 * w; i < (size_t)y1 * w; i++)
		in->slot[i] = job->slot[i];
	for (int32_t yb = y0; yb < y1; yb += BLOCK) {
		int32_t ye = yb + BLOCK < y1 ? yb + BLOCK : y1;
		for (int32_t x = 0; x < w; x++)
			for (int32_t y = yb; y < ye; y++) {
				size_t i = (size_t)y * w + x, o = (size_t)x * h + y;
				int16_t slot = job->slot[i];
				if (slot < 0)
					continue;
				if (in->z != job->depth)
					in->z[i] = job->depth[y * job->depth_stride +
					                      (int64_t)x * job->depth_channels];
				out->z[o] = in->z[i];
				out->slot[o] = slot;
			}
	}
}

/* Each plane's slots marked with the face of its row they lie on: the
 * count of creases crossed from the row's start (rows: SSS__BREAK_RIGHT,
 * columns: SSS__BREAK_DOWN). Planes so marked are not kept for a
 * re-tune (the breaks follow the materials' settings too). */
static void faces(const sss__job *job, const plane *hp, const plane *vp)
{
	int32_t w = job->width, h = job->height;
	for (int32_t y = 0; y < h; y++) {
		int32_t face = 0;
		for (int32_t x = 0; x < w; x++) {
			size_t i = (size_t)y * w + x;
			if (x > 0 && (job->breaks[i - 1] & SSS__BREAK_RIGHT) &&
			    face < 0x7fff)
				face++;
			if (hp->slot[i] >= 0)
				hp->slot[i] |= face << FACE_SHIFT;
		}
	}
	for (int32_t x = 0; x < w; x++) {
		int32_t face = 0;
		for (int32_t y = 0; y < h; y++) {
			size_t o = (size_t)x * h + y;
			if (y > 0 && (job->breaks[(size_t)(y - 1) * w + x] &
			              SSS__BREAK_DOWN) && face < 0x7fff)
				face++;
			if (vp->slot[o] >= 0)
				vp->slot[o] |= face << FACE_SHIFT;
		}
	}
}

/* One pass over rows r0..r1 of ctx->in, in blocks of BLOCK rows. The pixel
 * at position p of row r sits at p * rows + r in the other orientation:
 * the first pass stores its result there (the transposed plane), the
 * second blends it into the job's signal (back in image order). */
static void pass_rows(void *vctx, int32_t r0, int32_t r1)
{
	const pass_ctx *ctx = vctx;
	const sss__job *job = ctx->job;
	const plane *in = &ctx->in;
	int32_t len = in->len, rows = in->rows;
	scratch sc;
	void *mem = scratch_new(&sc, ctx->half_max);
	if (!mem) {
		atomic_store(ctx->failed, 1);
		return;
	}
	for (int32_t rb = r0; rb < r1; rb += BLOCK) {
		int32_t re = rb + BLOCK < r1 ? rb + BLOCK : r1;
		sss__blur1d tpl[BLOCK];
		anchor anc[BLOCK][2];
		for (int32_t r = 0; r < BLOCK; r++)
			anc[r][0].pos = anc[r][1].pos = -1;
		/* Only the span where the block's rows scatter: a sequential
		 * scan here, so that the strided walk below (and the work)
		 * follows the coverage. */
		int32_t first = len, last = -1;
		for (int32_t r = rb; r < re; r++) {
			row_template(ctx, r, &tpl[r - rb]);
			const int32_t *sl = in->slot + (size_t)r * len;
			int32_t a = 0, b = len - 1;
			while (a < first && sl[a] < 0)
				a++;
			while (b > last && sl[b] < 0)
				b--;
			first = a < first ? a : first;
			last = b > last ? b : last;
		}
		for (int32_t pos = first; pos <= last; pos++)
			for (int32_t r = rb; r < re; r++) {
				size_t i = (size_t)r * len + pos, o = (size_t)pos * rows + r;
				int32_t slot = in->slot[i];
				if (slot < 0)
					continue;
				float b[3];
				if (!blur_pixel(ctx, &tpl[r - rb], pos, &sc, anc[r - rb], b))
					for (int c = 0; c < 3; c++)
						b[c] = in->rgb[c][i];
				if (ctx->first)
					for (int c = 0; c < 3; c++)
						ctx->out.rgb[c][o] = b[c];
				else {
					/* back into the light's planes, in place:
					 * this pass's pixel is at o in image order */
					float v[3];
					for (int c = 0; c < 3; c++)
						v[c] = ctx->out.rgb[c][o];
					sss__blend_pixel(&job->kernels[kernel_of(slot)], b, v);
					for (int c = 0; c < 3; c++)
						ctx->out.rgb[c][o] = v[c];
				}
			}
	}
	free(mem);
}

/* The depth range of each kernel's pixels, over STRIPES stripes of rows
 * in parallel; a kernel's half-width falls as depth grows, so this bounds
 * the half-widths its dense rows must cover. */
#define STRIPES 32

typedef struct scan_ctx {
	const sss__job *job;
	int32_t count;
	float *zr; /* [stripe][kernel][min, max] */
} scan_ctx;

static void scan_stripes(void *vctx, int32_t s0, int32_t s1)
{
	const scan_ctx *ctx = vctx;
	const sss__job *job = ctx->job;
	for (int32_t st = s0; st < s1; st++) {
		float *zr = ctx->zr + (size_t)st * ctx->count * 2;
		for (int32_t m = 0; m < ctx->count; m++) {
			zr[2 * m] = INFINITY;
			zr[2 * m + 1] = -INFINITY;
		}
		int32_t y0 = (int32_t)((int64_t)job->height * st / STRIPES);
		int32_t y1 = (int32_t)((int64_t)job->height * (st + 1) / STRIPES);
		for (int32_t y = y0; y < y1; y++)
			for (int32_t x = 0; x < job->width; x++) {
				int16_t slot = job->slot[(size_t)y * job->width + x];
				if (slot < 0)
					continue;
				float z = job->depth[y * job->depth_stride +
				                     (int64_t)x * job->depth_channels];
				zr[2 * slot] = z < zr[2 * slot] ? z : zr[2 * slot];
				zr[2 * slot + 1] = z > zr[2 * slot + 1] ? z : zr[2 * slot + 1];
			}
	}
}

/* The half-widths that dense rows must cover, per kernel, both axes. */
static sss_result scan_half_widths(const sss__job *job, const axis ax[2],
                                   table *tables, int32_t count,
                                   int32_t num_threads)
{
	scan_ctx ctx = {job, count, malloc((size_t)STRIPES * count * 2 *
	                                   sizeof(float))};
	if (!ctx.zr)
		return SSS_ERR_OUT_OF_MEMORY;
	sss__parallel_rows(STRIPES, num_threads, scan_stripes, &ctx);
	for (int32_t m = 0; m < count; m++) {
		table *t = &tables[m];
		const sss__kernel *k = &job->kernels[m];
		float zmin = INFINITY, zmax = -INFINITY;
		for (int32_t st = 0; st < STRIPES; st++) {
			const float *zr = ctx.zr + ((size_t)st * count + m) * 2;
			zmin = zr[0] < zmin ? zr[0] : zmin;
			zmax = zr[1] > zmax ? zr[1] : zmax;
		}
		t->r_min = INFINITY;
		t->r_max = -INFINITY;
		if (!(zmin <= zmax) || !(k->support > 0.0))
			continue;
		int32_t half = dense_half((k->taps - 1) / 2);
		for (int a = 0; a < 2; a++) {
			int32_t len = a ? job->height : job->width;
			int capped_near, capped_far;
			double r_near = half_width(job, k, &ax[a], len, zmin, &capped_near);
			double r_far = half_width(job, k, &ax[a], len, zmax, &capped_far);
			/* Dense pixels are the uncapped ones in [1, half + 0.5). */
			double hi = capped_near ? fmin(job->max_support_px, len) : r_near;
			double lo = r_far < 1.0 ? 1.0 : r_far;
			/* Cut pixels: from the nearest to where the cut ends. */
			t->cap[a].z_lo = t->cap[a].z_hi = 0.0;
			if (capped_near) {
				t->cap[a].z_lo = zmin;
				t->cap[a].z_hi = capped_far || ax[a].ortho ? zmax
				                 : fmin(zmax, k->support * ax[a].f /
				                                  fmin(job->max_support_px,
				                                       len));
			}
			hi = hi < half + 0.5 ? hi : half + 0.5;
			if (!(lo <= hi))
				continue;
			t->r_min = fmin(t->r_min, lo);
			t->r_max = fmax(t->r_max, hi);
		}
	}
	free(ctx.zr);
	return SSS_OK;
}

sss_result sss__separable(const sss__job *job, int32_t num_threads)
{
	int32_t w = job->width, h = job->height, count = 0;
	size_t npix = (size_t)w * h;
	const sss__projection *pr = &job->proj;
	axis ax[2] = {{pr->ortho, pr->fx, pr->cx, pr->fy, pr->cy},
	              {pr->ortho, pr->fy, pr->cy, pr->fx, pr->cx}};
	for (size_t i = 0; i < npix; i++)
		if (job->slot[i] >= count)
			count = job->slot[i] + 1;
	if (count == 0)
		return SSS_OK;

	sss_result r = SSS_ERR_OUT_OF_MEMORY;
	int copy_z = !(job->depth_channels == 1 && job->depth_stride == w);
	/* The light's planes are the job's signal (planar for this method,
	 * 0 where nothing scatters); the depth planes start as zeros and
	 * only scattering pixels are written: the work follows the
	 * coverage. A sample on
	 * another material is masked off, but must be finite: 0 is. Distances
	 * come from depth (sss__blur1d_q), so a Position pass is not read. */
	table *tables = calloc((size_t)count, sizeof *tables);
	plane hp = {w, h, {NULL}, NULL, NULL};
	plane vp = {h, w, {NULL}, NULL, NULL};
	/* Depth and slots laid out both ways depend on the frame's depth and
	 * the slot map only: a kept workspace keeps them for a re-tune that
	 * leaves the slot map as it was (same bits). */
	int kept = !job->breaks &&
	           sss__ws_same_slots(job->ws, SSS__WS_PLANE_SLOT, job->slot,
	                              npix);
	sss__ws_forget(job->ws, SSS__WS_PLANE_SLOT); /* noted once laid out */
	float *hbuf = copy_z ? sss__ws_get(job->ws, SSS__WS_DEPTH_H,
	                                   npix * sizeof *hbuf, !kept) : NULL;
	float *vbuf = sss__ws_get(job->ws, SSS__WS_DEPTH_V, npix * sizeof *vbuf,
	                          !kept);
	int32_t *slots = sss__ws_get(job->ws, SSS__WS_SLOTS,
	                             2 * npix * sizeof *slots, 0);
	if (!tables || (copy_z && !hbuf) || !vbuf || !slots)
		goto done;
	/* The transposed light lives in the job's scratch image (fill_rows
	 * clears it). */
	for (int c = 0; c < 3; c++) {
		hp.rgb[c] = job->signal + c * npix;
		vp.rgb[c] = job->scratch + c * npix;
	}
	vp.z = vbuf;
	hp.slot = slots;
	vp.slot = slots + npix;
	hp.z = copy_z ? hbuf : (float *)job->depth;

	if ((r = scan_half_widths(job, ax, tables, count, num_threads)))
		goto done;
	r = SSS_ERR_OUT_OF_MEMORY;
	for (int32_t m = 0; m < count; m++) {
		if (!(job->kernels[m].support > 0.0))
			continue;
		if ((r = table_build(&job->kernels[m], &tables[m])))
			goto done;
		for (int a = 0; a < 2; a++)
			if ((r = cap_build(job, &job->kernels[m], &ax[a],
			                   a ? h : w, &tables[m].cap[a])))
				goto done;
	}

	const char *simd = getenv("SSS_SIMD");
	int avx2 = !(simd && strcmp(simd, "scalar") == 0) &&
	           sss__blur1d_avx2_supported();
	int32_t half_max = 0;
	for (int32_t m = 0; m < count; m++)
		if (tables[m].half > half_max)
			half_max = tables[m].half;
	atomic_int failed = 0;
	pass_ctx first = {job, tables, hp, vp, ax[0], 1, avx2, half_max, &failed,
	                  kept};
	sss__parallel_rows(h, num_threads, fill_rows, &first);
	if (job->breaks)
		faces(job, &hp, &vp);
	else if (job->ws && (r = sss__ws_note_slots(job->ws, SSS__WS_PLANE_SLOT,
	                                            job->slot, npix)))
		goto done;
	sss__parallel_rows(h, num_threads, pass_rows, &first);
	pass_ctx second = {job, tables, vp, hp, ax[1], 0, avx2, half_max, &failed,
	                   kept};
	if (!atomic_load(&failed))
		sss__parallel_rows(w, num_threads, pass_rows, &second);
	r = atomic_load(&failed) ? SSS_ERR_OUT_OF_MEMORY : SSS_OK;
done:
	if (tables)
		for (int32_t m = 0; m < count; m++)
			table_free(&tables[m]);
	free(tables);
	sss__ws_put(job->ws, vbuf);
	sss__ws_put(job->ws, hbuf);
	sss__ws_put(job->ws, slots);
	return r;
}

sss_result sss_kernel_1d(const sss_material *mat, double pixels_per_metre,
                         int32_t taps, float *offsets, float *weights,
                         int32_t *count)
{
	if (!mat || !offsets || !weights || !count || *count < 1)
		return SSS_ERR_INVALID_ARGUMENT;
	if (!(isfinite(pixels_per_metre) && pixels_per_metre > 0.0))
		return SSS_ERR_INVALID_ARGUMENT;
	sss_material m = *mat;
	m.pass_index = 1; /* the table key plays no part in the shape */
	if (taps > 4097 || sss_material_validate(&m, NULL, 0) != SSS_OK)
		return SSS_ERR_INVALID_ARGUMENT;
	sss_options opt;
	sss_options_default(&opt);
	if (taps > 0)
		m.taps = taps;
	sss__kernel *k = malloc(sizeof *k);
	sss__tap *tap = malloc((SSS__MAX_HALF_TAPS + 1) * sizeof *tap);
	if (!k || !tap) {
		free(k);
		free(tap);
		return SSS_ERR_OUT_OF_MEMORY;
	}
	sss__kernel_build(&m, &opt, 1.0, 0.0, k);

	/* On a flat fronto-parallel plane a tap's distance is its offset. As
	 * in blur_pixel, a kernel within the dense rows reads every pixel. */
	double r = k->support * pixels_per_metre;
	/* A kernel wider than any image (1e12 pixels per metre overflowed
	 * the tap layout's integer conversions) is the caller's error. */
	if (!(r <= (double)(1 << 24))) {
		free(k);
		free(tap);
		return SSS_ERR_INVALID_ARGUMENT;
	}
	int32_t budget = k->taps, dense = dense_half((budget - 1) / 2);
	if (r < dense + 0.5)
		budget = 2 * dense + 1;
	tap[0] = (sss__tap){0.0, -0.5, 0.5};
	int32_t n = r >= 1.0 ? sss__tap_layout(budget, r, tap) : 0;
	if (2 * n + 1 > *count) {
		free(k);
		free(tap);
		return SSS_ERR_INVALID_ARGUMENT;
	}
	double upm = 1.0 / pixels_per_metre;
	double mass[SSS__MAX_HALF_TAPS + 1][3], sum[3] = {0, 0, 0};
	for (int32_t t = 0; t <= n; t++) {
		if (k->support > 0.0)
			sss__line_mass3(k, tap[t].lo * upm, tap[t].hi * upm, mass[t]);
		else
			mass[t][0] = mass[t][1] = mass[t][2] = 1.0;
		for (int c = 0; c < 3; c++)
			sum[c] += (t ? 2.0 : 1.0) * mass[t][c];
	}
	for (int32_t t = -n; t <= n; t++) {
		int32_t at = t < 0 ? -t : t;
		offsets[t + n] = (float)(t < 0 ? -tap[at].offset : tap[at].offset);
		for (int c = 0; c < 3; c++)
			weights[3 * (t + n) + c] = (float)(mass[at][c] / sum[c]);
	}
	*count = 2 * n + 1;
	free(k);
	free(tap);
	return SSS_OK;
}
