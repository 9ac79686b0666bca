/* sss_apply.c - the public entry point: validates the passes, builds one
 * kernel per material, prepares the light to scatter, runs the method and
 * recombines the passes as Blender does. */
#include "sss_internal.h"
#include "sss_transmission.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>


/* Indexed by sss_method: the one place the methods are named. */
static const struct {
	const char *name, *summary;
} methods[] = {
	[SSS_METHOD_AUTO] = {"auto", "Per material: separable, or disk where "
		"the radius passes the curvature's"},
	[SSS_METHOD_SEPARABLE] = {"separable", "Fastest: two 1-D passes"},
	[SSS_METHOD_SEPARABLE_EXACT] = {"separable-exact", "Slower, exact for "
		"Gaussian sums: two 1-D passes per lobe"},
	[SSS_METHOD_DISK] = {"disk", "Sampled disk: grainy on fine detail at "
		"few samples"},
	[SSS_METHOD_REFERENCE] = {"reference", "Slowest, exact in screen "
		"space: brute-force 2-D"},
};

const char *sss_method_name(int32_t method)
{
	if (method < 0 || method >= (int32_t)(sizeof methods / sizeof *methods))
		return NULL;
	return methods[method].name;
}

const char *sss_method_summary(int32_t method)
{
	return sss_method_name(method) ? methods[method].summary : NULL;
}

static sss_result check_output(const char *name, const sss_image *out,
                               const sss_passes *p, int32_t w, int32_t h,
                               char *errbuf, size_t errbuf_len)
{
	if (!out)
		return SSS_OK;
	if (!out->data)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "output %s has no data", name);
	sss_result r = sss__check_image(name, out, 3, 1, w, h, errbuf, errbuf_len);
	if (r)
		return r;
	const char *olo, *ohi;
	sss__span(out, &olo, &ohi);
	for (int32_t i = 0; i < sss__render_pass_count; i++) {
		const sss_image *in = (const sss_image *)(const void *)(
			(const char *)p + sss__render_passes[i].offset);
		if (!in->data)
			continue;
		const char *lo, *hi;
		sss__span(in, &lo, &hi);
		if (olo < hi && lo < ohi)
			return FAILX(SSS_ERR_INVALID_ARGUMENT, "output %s overlaps an "
			             "input pass; inputs are never overwritten", name);
	}
	return SSS_OK;
}

/* The first output whose floats are packed (no row padding, which may
 * belong to a larger image): 3 floats a pixel of working memory, free
 * until the recombination writes it. NULL if neither is. */
static float *packed_output(const sss_image *a, const sss_image *b)
{
	const sss_image *outs[] = {a, b};
	for (int k = 0; k < 2; k++)
		if (outs[k] && outs[k]->channels >= 3 &&
		    sss__stride(outs[k]) == (int64_t)outs[k]->width *
		                            outs[k]->channels)
			return outs[k]->data;
	return NULL;
}

/* The per-pixel work before and after the blur, on row chunks in
 * parallel (sss__parallel_rows): every pixel only reads the passes and
 * writes its own outputs. */
typedef struct rows_ctx {
	const sss_passes *p;
	const sss_material *materials;
	const sss__kernel *kernels;
	const int16_t *by_index;
	const sss__transmission *transmission;
	const sss__thin *thin; /* thin parts lit from the front, or NULL */
	double background_depth;
	int32_t w, h;
	const sss__projection *proj; /* for the view cosine of calibrations */
	float *signal;
	int64_t signal_px, signal_ch; /* layout, as in sss__job */
	float *curvature;   /* the surface's mean curvature at the first pixel
	                       of each CURVATURE_BLOCK^2 block, NaN where not
	                       read (or NULL: no material follows the shape) */
	int16_t *slot;
	const float *median_x; /* per material, the median over its pixels
	                          of the widest walk radius x the mean
	                          curvature (sss_auto.c), or NULL */
	const float *crease; /* what sharp edges carried (sss_crease.c), 3 a
	                        pixel in the signal's units, or NULL */
	const sss_image *out_combined, *out_diffuse_light;
	const float *rest;   /* the frame's sss__rest_light, or NULL */
	float *view;         /* the view cosine of every scattering pixel
	                        (view_plane), or NULL: made pixel by pixel */
	float *glow;         /* the transmitted light the glow's grid points
	                        send out, 3 a point (sss_glow.c), or NULL */
	const sss__glow *glow_in; /* what facing parts send it, or NULL */
	atomic_int *glow_failed;  /* glow_rows could not allocate a row */
} rows_ctx;

/* Which pixels scatter, and the signal: L, or L sqrt(DiffCol) for
 * pre-and-post texturing. Anything non-finite is left out. */
static void signal_rows(void *vctx, int32_t y0, int32_t y1)
{
	const rows_ctx *ctx = vctx;
	const sss_passes *p = ctx->p;
	const sss__kernel *kernels = ctx->kernels;
	const int16_t *by_index = ctx->by_index;
	int16_t *slot = ctx->slot;
	int32_t w = ctx->w;
	for (int32_t y = y0; y < y1; y++) {
		for (int32_t x = 0; x < w; x++) {
			size_t i = (size_t)y * w + x;
			float *out = ctx->signal + (int64_t)i * ctx->signal_px;
			float index = sss__at(&p->index_ma, x, y)[0];
			float z = sss__at(&p->depth, x, y)[0];
			int16_t k = -1;
			if (index >= 0.5f && index < 65535.5f)
				k = by_index[(int32_t)(index + 0.5f)];
			if (!(z > 0.0f && z < ctx->background_depth))
				k = -1;
			if (k >= 0 && p->position.data &&
			    !sss__isfinite3(sss__at(&p->position, x, y)))
				k = -1;
			if (k < 0) {
				/* 0: the methods weigh other pixels by 0, and 0 x a
				 * non-finite light would spoil the sum */
				slot[i] = -1;
				for (int c = 0; c < 3; c++)
					out[c * ctx->signal_ch] = 0.0f;
				continue;
			}
			float s[3];
			const float *dd = sss__at(&p->diff_dir, x, y);
			const float *di = p->diff_ind.data ? sss__at(&p->diff_ind, x, y)
			                                   : NULL;
			for (int c = 0; c < 3; c++)
				s[c] = di ? dd[c] + di[c] : dd[c];
			if (kernels[k].texturing == SSS_TEXTURING_PRE_AND_POST) {
				const float *col = sss__at(&p->diff_col, x, y);
				for (int c = 0; c < 3; c++)
					s[c] *= sqrtf(fmaxf(col[c], 0.0f));
			}
			/* a thin part lets some of it out at the back */
			if (ctx->thin)
				sss__thin_apply(ctx->thin, k, x, y, s);
			if (!sss__isfinite3(s))
				k = -1;
			slot[i] = k;
			for (int c = 0; c < 3; c++)
				out[c * ctx->signal_ch] = k >= 0 ? s[c] : 0.0f;
		}
	}
}

/* Whether slot k's calibration follows the surface's shape: its table
 * was measured with light from the front only. Where light also comes
 * from behind, the walk carries it across the object too, and the
 * back-lit transmission stands for what a finite object adds: both
 * together counted that light twice (calibration.md). */
static int shape_follows(const rows_ctx *ctx, int16_t k)
{
	return sss__calibration_needs_shape(&ctx->materials[k],
	                                    ctx->kernels[k].calibration_fade) &&
	       !sss__transmission_active(ctx->transmission, k);
}

/* The mean curvature under pixel (x, y) of slot k, over the largest
 * radius the material's walk sees. */
static double pixel_curvature(const rows_ctx *ctx, int16_t k, int32_t x,
                              int32_t y)
{
	const float *r = ctx->kernels[k].walk_radius;
	return sss__mean_curvature(&ctx->p->depth, ctx->slot, ctx->proj, ctx->w,
	                           ctx->h, x, y, fmax(r[0], fmax(r[1], r[2])));
}

/* The curvature, read over circles of 2 px and more, changes little
 * from pixel to pixel: it is read once per block of CURVATURE_BLOCK^2
 * pixels, at its first pixel, and the block's pixels of the same slot
 * share it (the others read their own): at 4 x 4 the shape term adds
 * 6 - 26 % to a calibrated frame (1080p, 16 px, one thread), at 2 x 2 it
 * added about 45 %. Rows of blocks. */
#define CURVATURE_BLOCK 4

static void curvature_rows(void *vctx, int32_t by0, int32_t by1)
{
	const rows_ctx *ctx = vctx;
	int32_t bw = (ctx->w + CURVATURE_BLOCK - 1) / CURVATURE_BLOCK;
	for (int32_t by = by0; by < by1; by++)
		for (int32_t bx = 0; bx < bw; bx++) {
			int32_t x = CURVATURE_BLOCK * bx, y = CURVATURE_BLOCK * by;
			int16_t k = ctx->slot[(size_t)y * ctx->w + x];
			ctx->curvature[(size_t)by * bw + bx] =
			        k >= 0 && shape_follows(ctx, k)
			        ? (float)pixel_curvature(ctx, k, x, y) : NAN;
		}
}

/* What sharp edges carried to pixel i, measured over the flat face's
 * light: the flat gain, not the shape's (whose rise at the edge the
 * measurement held). */
static void add_crease(const rows_ctx *ctx, size_t i, float mu,
                       const float *col, float *light)
{
	const float *e = ctx->crease + 3 * i;
	if (!(e[0] != 0.0f || e[1] != 0.0f || e[2] != 0.0f))
		return;
	int16_t k = ctx->slot[i];
	float extra[3];
	for (int c = 0; c < 3; c++) {
		extra[c] = e[c];
		if (ctx->kernels[k].texturing == SSS_TEXTURING_PRE_AND_POST) {
			float root = sqrtf(fmaxf(col[c], 0.0f));
			extra[c] = root > 0.0f ? extra[c] / root : 0.0f;
		}
	}
	sss__calibration_apply(&ctx->materials[k],
	                       ctx->kernels[k].calibration_gain,
	                       ctx->kernels[k].calibration_fade, mu, NULL, NULL,
	                       col, extra);
	for (int c = 0; c < 3; c++)
		light[c] += extra[c];
}

/* Back to light (contribution = light x DiffCol) and recombine. */
static void composite_rows(void *vctx, int32_t y0, int32_t y1)
{
	const rows_ctx *ctx = vctx;
	const sss_passes *p = ctx->p;
	const sss_material *materials = ctx->materials;
	const sss__kernel *kernels = ctx->kernels;
	const int16_t *slot = ctx->slot;
	const sss_image *out_combined = ctx->out_combined;
	const sss_image *out_diffuse_light = ctx->out_diffuse_light;
	int32_t w = ctx->w;
	for (int32_t y = y0; y < y1; y++) {
		/* rows without grid points of the glow skip its test */
		int glow_row = ctx->glow && sss__glow_on_row(w, ctx->h, y);
		for (int32_t x = 0; x < w; x++) {
			size_t i = (size_t)y * w + x;
			const float *dd = sss__at(&p->diff_dir, x, y);
			const float *di = p->diff_ind.data ? sss__at(&p->diff_ind, x, y)
			                                   : NULL;
			const float *col = sss__at(&p->diff_col, x, y);
			float light[3];
			for (int c = 0; c < 3; c++) {
				float l = di ? dd[c] + di[c] : dd[c];
				if (slot[i] >= 0 && kernels[slot[i]].mix[c] > 0.0f) {
					l = ctx->signal[(int64_t)i * ctx->signal_px +
					                c * ctx->signal_ch];
					if (kernels[slot[i]].texturing ==
					    SSS_TEXTURING_PRE_AND_POST) {
						float root = sqrtf(fmaxf(col[c], 0.0f));
						l = root > 0.0f ? l / root : (di ? dd[c] + di[c]
						                                 : dd[c]);
					}
				}
				light[c] = l;
			}
			float sent[3] = {0.0f, 0.0f, 0.0f};
			if (slot[i] >= 0 && ctx->transmission) {
				/* back-lit light, after the blur: it crossed the part
				 * and spread over its thickness, not over the radius
				 * (transmission.md, "Not blurred") */
				float t[3] = {0.0f, 0.0f, 0.0f};
				sss__transmission_add(ctx->transmission, slot[i], x, y, t);
				for (int c = 0; c < 3; c++)
					if (kernels[slot[i]].mix[c] > 0.0f) {
						light[c] += t[c];
						sent[c] = t[c];
					}
			}
			if (slot[i] >= 0) { /* energy calibration, at the exit
			                       pixel's colour and view
			                       (sss_calibration.c) */
				const sss_material *m = &materials[slot[i]];
				const float *fade = kernels[slot[i]].calibration_fade;
				float mu = sss__calibration_needs_view(m, fade)
				           ? ctx->view ? ctx->view[i]
				             : sss__view_cosine(&p->depth, slot, ctx->proj,
				                                w, ctx->h, x, y)
				           : 1.0f;
				/* and at the surface's curvature over the distance
				   the walk travels */
				float shape[3], far[3];
				int shaped = ctx->curvature &&
				             shape_follows(ctx, slot[i]);
				int whole = 0;
				if (shaped) {
					const float *r = kernels[slot[i]].walk_radius;
					float rmax = fmaxf(r[0], fmaxf(r[1], r[2]));
					float mx = ctx->median_x ? ctx->median_x[slot[i]]
					                         : NAN;
					whole = isfinite(mx) && rmax > 0.0f;
					for (int c = 0; c < 3 && whole; c++)
						far[c] = mx * r[c] / rmax;
					int32_t b = CURVATURE_BLOCK;
					size_t first = (size_t)(y - y % b) * w + (x - x % b);
					float H = slot[first] == slot[i]
					          ? ctx->curvature[(size_t)(y / b) *
					                           ((w + b - 1) / b) + x / b]
					          : NAN;
					if (!isfinite(H))
						H = (float)pixel_curvature(ctx, slot[i], x, y);
					for (int c = 0; c < 3; c++)
						shape[c] = H * r[c];
				}
				float gain[3];
				sss__calibration_factors(m,
				                         kernels[slot[i]].calibration_gain,
				                         fade, mu, shaped ? shape : NULL,
				                         whole ? far : NULL, col, gain);
				for (int c = 0; c < 3; c++) {
					light[c] *= gain[c];
					sent[c] *= gain[c]; /* the transmitted part as it
					                       leaves */
				}
				if (ctx->crease)
					add_crease(ctx, i, mu, col, light);
			}
			int64_t g = glow_row && slot[i] >= 0
			            ? sss__glow_point_of(w, ctx->h, x, y) : -1;
			for (int c = 0; g >= 0 && c < 3; c++)
				ctx->glow[3 * g + c] = isfinite(sent[c]) && sent[c] > 0.0f
				                       ? sent[c] * col[c] : 0.0f;
			if (out_diffuse_light) {
				float *o = out_diffuse_light->data +
				           y * sss__stride(out_diffuse_light) +
				           (int64_t)x * out_diffuse_light->channels;
				memcpy(o, light, sizeof light);
			}
			if (out_combined) {
				float acc[3], own[3];
				const float *rest = ctx->rest ? ctx->rest + 3 * i : own;
				if (!ctx->rest)
					sss__rest_light(p, x, y, own);
				for (int c = 0; c < 3; c++)
					acc[c] = light[c] * col[c] + rest[c];
				float *o = out_combined->data + y * sss__stride(out_combined) +
				           (int64_t)x * out_combined->channels;
				memcpy(o, acc, sizeof acc);
				if (out_combined->channels >= 4)
					o[3] = p->combined.data ? sss__at(&p->combined, x, y)[3]
					                        : 1.0f;
			}
		}
	}
}

/* The glow that facing parts of a back-lit material send each other
 * (sss_glow.c), added to the outputs' diffuse light. */
static void glow_rows(void *vctx, int32_t y0, int32_t y1)
{
	const rows_ctx *ctx = vctx;
	const sss_passes *p = ctx->p;
	float *row = malloc((size_t)ctx->w * 3 * sizeof *row);
	if (!row) {
		atomic_store(ctx->glow_failed, 1);
		return;
	}
	for (int32_t y = y0; y < y1; y++) {
		sss__glow_row(ctx->glow_in, y, ctx->slot + (size_t)y * ctx->w, row);
		for (int32_t x = 0; x < ctx->w; x++) {
			const float *g = row + 3 * x;
			if (!(g[0] > 0.0f || g[1] > 0.0f || g[2] > 0.0f))
				continue;
			const float *col = sss__at(&p->diff_col, x, y);
			if (ctx->out_diffuse_light) {
				float *o = ctx->out_diffuse_light->data +
				           y * sss__stride(ctx->out_diffuse_light) +
				           (int64_t)x * ctx->out_diffuse_light->channels;
				for (int c = 0; c < 3; c++)
					o[c] += g[c];
			}
			if (ctx->out_combined) {
				float *o = ctx->out_combined->data +
				           y * sss__stride(ctx->out_combined) +
				           (int64_t)x * ctx->out_combined->channels;
				for (int c = 0; c < 3; c++)
					o[c] += g[c] * col[c];
			}
		}
	}
	free(row);
}

static void view_rows(void *vctx, int32_t y0, int32_t y1)
{
	const rows_ctx *ctx = vctx;
	for (int32_t y = y0; y < y1; y++)
		for (int32_t x = 0; x < ctx->w; x++) {
			size_t i = (size_t)y * ctx->w + x;
			ctx->view[i] = ctx->slot[i] >= 0
			               ? sss__view_cosine(&ctx->p->depth, ctx->slot,
			                                  ctx->proj, ctx->w, ctx->h, x, y)
			               : 1.0f;
		}
}

/* What a kept view cosine was made for, beside the slot map. */
typedef struct view_key {
	int made;
	int32_t w, h;
	sss__projection proj;
} view_key;

/* rc->view: the view cosine of every scattering pixel, from the Depth
 * pass, the slot map and the camera, kept in the workspace with the slot
 * map and camera it was made for, and made again only when either changed
 * (a re-tune of radius or colour changes neither: 18 ms of a 1080p
 * scatter on two threads). Without a workspace the recombination makes
 * each pixel's as it goes (the same bits, no plane). */
static sss_result view_plane(rows_ctx *rc, sss__workspace *ws,
                             int32_t num_threads)
{
	size_t npix = (size_t)rc->w * rc->h;
	view_key *key = sss__ws_kept(ws, SSS__WS_VIEW_KEY, sizeof *key);
	float *view = sss__ws_kept(ws, SSS__WS_VIEW, npix * sizeof *view);
	if (key && view && key->made && key->w == rc->w && key->h == rc->h &&
	    sss__same_projection(&key->proj, rc->proj) &&
	    sss__ws_same_slots(ws, SSS__WS_VIEW_SLOT, rc->slot, npix)) {
		rc->view = view;
		return SSS_OK;
	}
	key = sss__ws_get(ws, SSS__WS_VIEW_KEY, sizeof *key, 1);
	rc->view = sss__ws_get(ws, SSS__WS_VIEW, npix * sizeof *view, 0);
	if (!key || !rc->view)
		return SSS_ERR_OUT_OF_MEMORY;
	sss__parallel_rows(rc->h, num_threads, view_rows, rc);
	sss_result r = sss__ws_note_slots(ws, SSS__WS_VIEW_SLOT, rc->slot, npix);
	if (!r)
		*key = (view_key){1, rc->w, rc->h, *rc->proj};
	return r;
}

/* The crease term (sss_crease.c) for the materials whose calibration
 * has one and follows the shape (not with back-lit transmission, which
 * stands for what crosses a finite object), from the light before the
 * blur: *out is NULL when no material takes it. */
static sss_result crease_before(const rows_ctx *rc, const sss__job *job,
                                int32_t material_count,
                                const sss_options *opt, float **out,
                                uint8_t **breaks)
{
	*out = NULL;
	*breaks = NULL;
	uint8_t *enabled = calloc(material_count, 1);
	int32_t *calibration = malloc(material_count * sizeof *calibration);
	sss_result r = enabled && calibration ? SSS_OK : SSS_ERR_OUT_OF_MEMORY;
	int any = 0;
	for (int32_t m = 0; !r && m < material_count; m++) {
		float kappa, gamma;
		calibration[m] = rc->materials[m].calibration;
		sss__crease_params(calibration[m], 0.5f, &kappa, &gamma);
		enabled[m] = rc->kernels[m].support > 0.0 && kappa > 0.0f &&
		             shape_follows(rc, (int16_t)m);
		any |= enabled[m];
	}
	size_t npix = (size_t)job->width * job->height;
	if (!r && any) {
		*out = sss__ws_get(job->ws, SSS__WS_CREASE, npix * 3 * sizeof **out,
		                   0);
		*breaks = sss__ws_get(job->ws, SSS__WS_BREAKS, npix, 0);
		if (!*out || !*breaks)
			r = SSS_ERR_OUT_OF_MEMORY;
		else
			r = sss__crease(job, material_count, &rc->p->diff_col,
			                enabled, calibration, opt->num_threads, *out,
			                *breaks, opt->crease == 1);
		if (r) {
			sss__ws_put(job->ws, *out);
			sss__ws_put(job->ws, *breaks);
			*out = NULL;
			*breaks = NULL;
		}
	}
	free(enabled);
	free(calibration);
	return r;
}

/* The auto method: the choice per material (sss_auto.c), then each
 * method over its materials' pixels (the methods read only pixels of the
 * slot they scatter, so the two runs do not meet). The signal is planar,
 * as the separable method reads it, and packed before the disk method
 * runs. */
static sss_result run_auto(sss__job *job, rows_ctx *rc,
                           const sss_image *depth, int32_t material_count,
                           const sss_options *opt, int32_t *chosen)
{
	size_t npix = (size_t)job->width * job->height;
	const int16_t *slot = job->slot;
	sss_result r = sss__auto_methods(depth, slot, &job->proj, job->width,
	                                 job->height, job->kernels,
	                                 material_count, chosen, NULL);
	if (r)
		return r;
	int uses[2] = {0, 0}; /* separable, disk */
	for (size_t i = 0; i < npix; i++)
		if (slot[i] >= 0)
			uses[chosen[slot[i]] == SSS_METHOD_DISK] = 1;
	int16_t *own = NULL;
	if (uses[0] && uses[1] && !(own = malloc(npix * sizeof *own)))
		return SSS_ERR_OUT_OF_MEMORY;
	for (int d = 0; d < 2 && !r; d++) {
		if (!uses[d])
			continue;
		if (own) {
			int32_t method = d ? SSS_METHOD_DISK : SSS_METHOD_SEPARABLE;
			for (size_t i = 0; i < npix; i++)
				own[i] = slot[i] >= 0 && chosen[slot[i]] == method ? slot[i]
				                                                   : -1;
			job->slot = own;
		}
		if (!d) {
			r = sss__separable(job, opt->num_threads);
			continue;
		}
		/* Packed for the disk method, through the scratch buffer, which
		 * nothing holds between the methods. */
		for (size_t i = 0; i < npix; i++)
			for (int c = 0; c < 3; c++)
				job->scratch[3 * i + c] = job->signal[i + c * npix];
		memcpy(job->signal, job->scratch, 3 * npix * sizeof *job->signal);
		job->signal_px = rc->signal_px = 3;
		job->signal_ch = rc->signal_ch = 1;
		/* Per source where the light enters only from the front: with
		 * back-lit transmission it overshot (marble at x100: 0.66 ->
		 * 0.71 of the error without SSS), as the shape term does. */
		uint8_t *per_source = malloc(material_count ? material_count : 1);
		if (!per_source) {
			r = SSS_ERR_OUT_OF_MEMORY;
			break;
		}
		for (int32_t m = 0; m < material_count; m++)
			per_source[m] = !sss__transmission_active(rc->transmission, m);
		r = sss__disk(job, opt->samples, opt->num_threads, per_source);
		free(per_source);
	}
	job->slot = slot;
	free(own);
	return r;
}

/* Everything sss_apply checks before any work: the arguments, the
 * options (into *opt, the defaults when user_opt is NULL), every pass and
 * output, the camera and the material table. */
static sss_result check_call(const sss_passes *p, const sss_camera *cam,
                             const sss_material *materials,
                             int32_t material_count,
                             const sss_options *user_opt,
                             const sss_image *out_combined,
                             const sss_image *out_diffuse_light,
                             sss_options *opt, char *errbuf,
                             size_t errbuf_len)
{
	sss_result r;
	if (errbuf && errbuf_len)
		errbuf[0] = '\0';
	if (!p || !cam)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "%s is NULL",
		             p ? "camera" : "passes");
	if (material_count < 0 || material_count > 32767 ||
	    (material_count > 0 && !materials))
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "material_count %d must be "
		             "0..32767 with a table", material_count);
	if (!out_combined && !out_diffuse_light)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "no output image given");

	sss_options_default(opt);
	if (user_opt)
		*opt = *user_opt;
	if ((r = sss__options_check(opt, errbuf, errbuf_len)))
		return r;

	if ((r = sss__check_image("DiffDir", &p->diff_dir, 3, 1, p->diff_dir.width,
	                     p->diff_dir.height, errbuf, errbuf_len)))
		return r;
	int32_t w = p->diff_dir.width, h = p->diff_dir.height;
	if ((uint64_t)w * (uint64_t)h > SIZE_MAX / (3 * sizeof(float)) / 2)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "image %dx%d is too large",
		             w, h);
	/* Every pass of the table (DiffDir again: at its own size). */
	for (int32_t i = 0; i < sss__render_pass_count; i++) {
		const sss__pass_row *row = &sss__render_passes[i];
		if ((r = sss__check_image(
		         row->name,
		         (const sss_image *)(const void *)((const char *)p +
		                                           row->offset),
		         (int32_t)strlen(row->components),
		         row->need == SSS_PASS_REQUIRED, w, h, errbuf, errbuf_len)))
			return r;
	}
	if ((r = check_output("combined", out_combined, p, w, h, errbuf,
	                      errbuf_len)) ||
	    (r = check_output("diffuse light", out_diffuse_light, p, w, h,
	                      errbuf, errbuf_len)))
		return r;
	if (out_combined && out_diffuse_light) {
		const char *alo, *ahi, *blo, *bhi;
		sss__span(out_combined, &alo, &ahi);
		sss__span(out_diffuse_light, &blo, &bhi);
		if (alo < bhi && blo < ahi)
			return FAILX(SSS_ERR_INVALID_ARGUMENT, "outputs combined and "
			             "diffuse light share memory; each needs its own");
	}
	if ((r = sss__projection_make(cam, w, h, &(sss__projection){0}, errbuf,
	                              errbuf_len)))
		return r;
	uint8_t seen[65536 / 8] = {0}; /* pass indices already in the table */
	for (int32_t m = 0; m < material_count; m++) {
		if ((r = sss_material_validate(&materials[m], errbuf, errbuf_len)))
			return r;
		int32_t idx = materials[m].pass_index;
		if (seen[idx / 8] & (1u << (idx % 8)))
			return FAILX(SSS_ERR_INVALID_ARGUMENT, "material pass_index "
			             "%d appears twice in the table", idx);
		seen[idx / 8] |= (uint8_t)(1u << (idx % 8));
	}
	return SSS_OK;
}

/* The kernels of the table's materials: by_index (65536 entries) maps a
 * pass index to its material's row where it scatters, else -1; zrange
 * (2 per material) is scratch; *proj the camera's projection. */
static void build_kernels(const sss_passes *p, const sss_camera *cam,
                          const sss_material *materials,
                          int32_t material_count, const sss_options *opt,
                          const float *index_zrange, int16_t *by_index,
                          double *zrange, sss__kernel *kernels,
                          sss__projection *proj)
{
	int32_t w = p->diff_dir.width, h = p->diff_dir.height;
	/* Kernels only for the table's materials that are on screen (a big
	 * scene-wide table costs nothing for the materials this frame lacks),
	 * each limited by how far its pixels can reach. */
	for (int i = 0; i < 65536; i++)
		by_index[i] = -1;
	for (int32_t m = 0; m < material_count; m++)
		by_index[materials[m].pass_index] = (int16_t)m;
	for (int32_t m = 0; m < material_count; m++) {
		const float *zr = index_zrange + 2 * materials[m].pass_index;
		zrange[2 * m] = zr[0];
		zrange[2 * m + 1] = zr[1];
	}
	sss__projection_make(cam, w, h, proj, NULL, 0);
	for (int32_t m = 0; m < material_count; m++) {
		int32_t idx = materials[m].pass_index;
		by_index[idx] = -1;
		if (!(zrange[2 * m] <= zrange[2 * m + 1]))
			continue; /* not on screen */
		double limit = sss__reach_limit(proj, opt->max_support_px, w, h,
		                                zrange[2 * m], zrange[2 * m + 1]);
		sss__kernel_build(&materials[m], opt, cam->unit_scale, limit,
		                  &kernels[m]);
		if (kernels[m].support > 0.0)
			by_index[idx] = (int16_t)m;
	}
}

/* The chosen method over the signal; method_of[m]: what ran for each
 * material (auto chooses per material). */
static sss_result run_method(sss__job *job, rows_ctx *rc,
                             const sss_passes *p,
                             const sss_material *materials,
                             int32_t material_count, const sss_options *opt,
                             int32_t *method_of)
{
	for (int32_t m = 0; m < material_count; m++)
		method_of[m] = opt->method;
	switch (opt->method) {
	case SSS_METHOD_AUTO:
		return run_auto(job, rc, &p->depth, material_count, opt, method_of);
	case SSS_METHOD_REFERENCE:
		return sss__reference(job, opt->num_threads);
	case SSS_METHOD_SEPARABLE_EXACT:
		return sss__separable_exact(job, materials, material_count, opt);
	case SSS_METHOD_DISK:
		return sss__disk(job, opt->samples, opt->num_threads, NULL);
	default:
		return sss__separable(job, opt->num_threads);
	}
}

/* sss_apply, and the method each material ran (chosen: one per material,
 * -1 for one not on screen or that does not scatter; may be NULL). */
sss_result sss__apply_report(const sss_passes *p, const sss_camera *cam,
                             const sss_material *materials,
                             int32_t material_count,
                             const sss_options *user_opt,
                             const sss_image *out_combined,
                             const sss_image *out_diffuse_light,
                             const sss__frame_pre *pre, sss__workspace *ws,
                             int32_t *chosen, char *errbuf,
                             size_t errbuf_len)
{
	sss_result r;
	sss_options opt;
	if ((r = check_call(p, cam, materials, material_count, user_opt,
	                    out_combined, out_diffuse_light, &opt, errbuf,
	                    errbuf_len)))
		return r;
	int32_t w = p->diff_dir.width, h = p->diff_dir.height;
	/* Transmission (sss_transmission.c): back-lit light joins the
	 * diffuse light after the blur; NULL when nothing transmits. */
	sss__transmission *transmission = NULL;
	if ((r = sss__transmission_prepare(p, materials, material_count, &opt,
	                                   cam->unit_scale, w, h, out_combined,
	                                   out_diffuse_light, &transmission,
	                                   errbuf, errbuf_len)))
		return r;
	/* Thin parts lit from the front (sss_thin.c): less of the light
	 * entering them is reflected; NULL when no material asks. */
	sss__thin *thin = NULL;
	if ((r = sss__thin_prepare(p, materials, material_count, &opt,
	                           cam->unit_scale, &thin, errbuf,
	                           errbuf_len))) {
		sss__transmission_free(transmission);
		return r;
	}

	/* All allocations up front, one error path. */
	size_t npix = (size_t)w * (size_t)h;
	sss__kernel *kernels = calloc(material_count ? material_count : 1,
	                              sizeof *kernels);
	int16_t *by_index = malloc(65536 * sizeof *by_index);
	int16_t *slot = sss__ws_get(ws, SSS__WS_SLOT, npix * sizeof *slot, 0);
	int32_t *method_of = malloc((material_count ? material_count : 1) *
	                            sizeof *method_of);
	float *signal = sss__ws_get(ws, SSS__WS_SIGNAL, npix * 3 * sizeof *signal,
	                            0);
	float *scratch = packed_output(out_combined, out_diffuse_light);
	float *own_scratch = NULL;
	float *curvature = NULL; /* allocated below, once kernels tell */
	float *crease = NULL;    /* likewise */
	uint8_t *breaks = NULL;  /* where creases part the faces */
	float *median_x = NULL;  /* likewise */
	if (!scratch)
		scratch = own_scratch = sss__ws_get(ws, SSS__WS_SCRATCH,
		                                    npix * 3 * sizeof *scratch, 0);
	double *zrange = malloc(2 * (material_count ? material_count : 1) *
	                        sizeof *zrange);
	float *own_index_zrange = pre ? NULL
	                          : malloc(65536 * 2 * sizeof *own_index_zrange);
	if (!kernels || !by_index || !slot || !signal || !scratch || !zrange ||
	    !method_of || (!pre && !own_index_zrange)) {
		r = FAILX(SSS_ERR_OUT_OF_MEMORY, "cannot allocate working memory "
		          "for a %dx%d image", w, h);
		goto done;
	}

	sss__projection proj;
	if (!pre)
		sss__index_zrange_scan(p, own_index_zrange);
	build_kernels(p, cam, materials, material_count, &opt,
	              pre ? pre->zrange : own_index_zrange, by_index, zrange,
	              kernels, &proj);

	sss__job job = {
		.width = w, .height = h, .kernels = kernels, .slot = slot,
		.depth = p->depth.data, .depth_stride = sss__stride(&p->depth),
		.depth_channels = p->depth.channels,
		.position = p->position.data,
		.position_stride = p->position.data ? sss__stride(&p->position) : 0,
		.position_channels = p->position.channels,
		.proj = proj, .max_support_px = opt.max_support_px,
		.signal = signal, .signal_px = 3, .signal_ch = 1,
		.scratch = scratch, .ws = ws,
	};
	if (opt.method == SSS_METHOD_SEPARABLE ||
	    opt.method == SSS_METHOD_AUTO) /* reads colour planes */
		job.signal_px = 1, job.signal_ch = (int64_t)npix;

	rows_ctx rc = {
		.p = p, .materials = materials, .kernels = kernels,
		.by_index = by_index, .transmission = transmission,
		.thin = thin, .background_depth = opt.background_depth, .w = w, .h = h,
		.proj = &job.proj, .signal = signal, .signal_px = job.signal_px,
		.signal_ch = job.signal_ch, .slot = slot,
		.out_combined = out_combined, .out_diffuse_light = out_diffuse_light,
		.rest = pre ? pre->rest : NULL,
	};
	/* Materials whose calibration follows the shape need the curvature
	 * map. */
	for (int32_t m = 0; m < material_count; m++)
		if (kernels[m].support > 0.0 && shape_follows(&rc, (int16_t)m)) {
			curvature = malloc((size_t)((w + CURVATURE_BLOCK - 1) /
			                            CURVATURE_BLOCK) *
			                   ((h + CURVATURE_BLOCK - 1) / CURVATURE_BLOCK) *
			                   sizeof *curvature);
			if (!curvature) {
				r = FAILX(SSS_ERR_OUT_OF_MEMORY, "cannot allocate working "
				          "memory for a %dx%d image", w, h);
				goto done;
			}
			break;
		}
	rc.curvature = curvature;
	sss__parallel_rows(h, opt.num_threads, signal_rows, &rc);
	if (opt.crease && material_count > 0 &&
	    (r = crease_before(&rc, &job, material_count, &opt, &crease,
	                       &breaks))) {
		FAILX(r, "cannot allocate working memory for a %dx%d image", w, h);
		goto done;
	}

	job.breaks = breaks;
	if (material_count > 0) {
		r = run_method(&job, &rc, p, materials, material_count, &opt,
		               method_of);
		if (r == SSS_ERR_OUT_OF_MEMORY)
			FAILX(r, "cannot allocate working memory for a %dx%d image",
			      w, h);
		if (r)
			goto done;
	}

	rc.crease = crease;
	if (curvature) {
		sss__parallel_rows((h + CURVATURE_BLOCK - 1) / CURVATURE_BLOCK,
		                   opt.num_threads, curvature_rows, &rc);
		/* The objects' scale against the radius, for the far term: the
		 * median x auto reads (its choice is not used here). */
		median_x = malloc(material_count * sizeof *median_x);
		int32_t *unused = malloc(material_count * sizeof *unused);
		r = median_x && unused
		    ? sss__auto_methods(&p->depth, slot, &job.proj, w, h, kernels,
		                        material_count, unused, median_x)
		    : SSS_ERR_OUT_OF_MEMORY;
		free(unused);
		if (r) {
			FAILX(r, "cannot allocate working memory for a %dx%d image",
			      w, h);
			goto done;
		}
		rc.median_x = median_x;
	}
	int needs_view = 0;
	for (int32_t m = 0; m < material_count; m++)
		needs_view |= kernels[m].support > 0.0 &&
		              sss__calibration_needs_view(&materials[m],
		                                          kernels[m].calibration_fade);
	if (needs_view && ws && (r = view_plane(&rc, ws, opt.num_threads))) {
		FAILX(r, "cannot allocate working memory for a %dx%d image", w, h);
		goto done;
	}
	/* Back-lit parts that face each other light each other with their
	 * glow (sss_glow.c). */
	float *glow = NULL;
	uint8_t *receives = NULL;
	if (transmission && material_count > 0) {
		receives = calloc((size_t)material_count, 1);
		int any = 0;
		for (int32_t m = 0; receives && m < material_count; m++)
			any |= receives[m] = kernels[m].support > 0.0 &&
			                     sss__transmission_active(transmission, m);
		if (any) /* zeros where no grid point's pixel scatters */
			glow = calloc((size_t)sss__glow_points(w, h) * 3, sizeof *glow);
		if (!receives || (any && !glow)) {
			free(receives);
			r = FAILX(SSS_ERR_OUT_OF_MEMORY, "cannot allocate working "
			          "memory for a %dx%d image", w, h);
			goto done;
		}
	}
	rc.glow = glow;
	sss__parallel_rows(h, opt.num_threads, composite_rows, &rc);
	if (glow) {
		sss__glow *bounce = NULL;
		r = sss__glow_make(glow, &p->depth, slot, receives, &job.proj, w, h,
		                   opt.num_threads, &bounce);
		if (!r) {
			atomic_int failed = 0;
			rc.glow_in = bounce;
			rc.glow_failed = &failed;
			sss__parallel_rows(h, opt.num_threads, glow_rows, &rc);
			if (atomic_load(&failed))
				r = SSS_ERR_OUT_OF_MEMORY;
		}
		sss__glow_free(bounce);
	}
	free(receives);
	free(glow);
	if (r) {
		FAILX(r, "cannot allocate working memory for a %dx%d image", w, h);
		goto done;
	}
	if (chosen)
		for (int32_t m = 0; m < material_count; m++)
			chosen[m] = by_index[materials[m].pass_index] == m
			            ? method_of[m] : -1;
	r = SSS_OK;
done:
	sss__transmission_free(transmission);
	sss__thin_free(thin);
	free(kernels);
	free(by_index);
	sss__ws_put(ws, slot);
	sss__ws_put(ws, signal);
	free(curvature);
	sss__ws_put(ws, crease);
	sss__ws_put(ws, breaks);
	free(median_x);
	sss__ws_put(ws, own_scratch);
	free(zrange);
	free(own_index_zrange);
	free(method_of);
	return r;
}

sss_result sss_apply(const sss_passes *p, const sss_camera *cam,
                     const sss_material *materials, int32_t material_count,
                     const sss_options *opt, const sss_image *out_combined,
                     const sss_image *out_diffuse_light, char *errbuf,
                     size_t errbuf_len)
{
	return sss__apply_report(p, cam, materials, material_count, opt,
	                         out_combined, out_diffuse_light, NULL, NULL,
	                         NULL, errbuf, errbuf_len);
}
