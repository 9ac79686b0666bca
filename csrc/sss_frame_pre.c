/* sss_frame_pre.c - what a frame's passes give every scatter alike, made
 * once when a kept frame is read (sss_frame.c) instead of at every
 * re-tune: the light of the passes that do not scatter, summed, and the
 * depth range of each material index on screen. sss_apply without a
 * frame computes the same per call, through the same functions, so both
 * give the same bits. */
#include "sss_internal.h"

#include <stdlib.h>
#include <string.h>

/* (dir + ind) x col of one pass family, added to acc; nothing without the
 * colour or without both lights. */
static void add_scaled(float acc[3], const sss_image *light_a,
                       const sss_image *light_b, const sss_image *colour,
                       int32_t x, int32_t y)
{
	if (!colour->data || (!light_a->data && !light_b->data))
		return;
	const float *c = sss__at(colour, x, y);
	for (int k = 0; k < 3; k++) {
		float l = 0.0f;
		if (light_a->data)
			l += sss__at(light_a, x, y)[k];
		if (light_b->data)
			l += sss__at(light_b, x, y)[k];
		acc[k] += l * c[k];
	}
}

static void add_plain(float acc[3], const sss_image *im, int32_t x, int32_t y)
{
	if (!im->data)
		return;
	const float *v = sss__at(im, x, y);
	for (int k = 0; k < 3; k++)
		acc[k] += v[k];
}

void sss__rest_light(const sss_passes *p, int32_t x, int32_t y, float out[3])
{
	out[0] = out[1] = out[2] = 0.0f;
	add_scaled(out, &p->gloss_dir, &p->gloss_ind, &p->gloss_col, x, y);
	add_scaled(out, &p->trans_dir, &p->trans_ind, &p->trans_col, x, y);
	add_plain(out, &p->emit, x, y);
	add_plain(out, &p->env, x, y);
}

typedef struct rest_ctx {
	const sss_passes *p;
	float *rest;
} rest_ctx;

static void rest_rows(void *vctx, int32_t y0, int32_t y1)
{
	const rest_ctx *ctx = vctx;
	int32_t w = ctx->p->diff_dir.width;
	for (int32_t y = y0; y < y1; y++)
		for (int32_t x = 0; x < w; x++)
			sss__rest_light(ctx->p, x, y,
			                ctx->rest + 3 * ((size_t)y * w + x));
}

void sss__index_zrange_scan(const sss_passes *p, float *zrange)
{
	for (int32_t i = 0; i < 65536; i++)
		zrange[2 * i] = INFINITY, zrange[2 * i + 1] = -INFINITY;
	for (int32_t y = 0; y < p->diff_dir.height; y++)
		for (int32_t x = 0; x < p->diff_dir.width; x++) {
			float index = sss__at(&p->index_ma, x, y)[0];
			if (!(index >= 0.5f && index < 65535.5f))
				continue;
			int32_t k = (int32_t)(index + 0.5f);
			float z = sss__at(&p->depth, x, y)[0];
			if (!isfinite(z))
				continue;
			zrange[2 * k] = fminf(zrange[2 * k], z);
			zrange[2 * k + 1] = fmaxf(zrange[2 * k + 1], z);
		}
}

sss_result sss__frame_pre_make(const sss_passes *p, int32_t num_threads,
                               sss__frame_pre *pre)
{
	int32_t w = p->diff_dir.width, h = p->diff_dir.height;
	memset(pre, 0, sizeof *pre);
	pre->rest = malloc((size_t)w * h * 3 * sizeof *pre->rest);
	pre->zrange = malloc(65536 * 2 * sizeof *pre->zrange);
	if (!pre->rest || !pre->zrange) {
		sss__frame_pre_free(pre);
		return SSS_ERR_OUT_OF_MEMORY;
	}
	rest_ctx ctx = {p, pre->rest};
	sss__parallel_rows(h, num_threads, rest_rows, &ctx);
	sss__index_zrange_scan(p, pre->zrange);
	return SSS_OK;
}

void sss__frame_pre_free(sss__frame_pre *pre)
{
	free(pre->rest);
	free(pre->zrange);
	memset(pre, 0, sizeof *pre);
}
