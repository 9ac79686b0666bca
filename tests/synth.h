/* synth.h - synthetic render passes for tests, the demo and reports:
 * owned buffers for every pass Blender writes, and views of them. */
#ifndef SYNTH_H
#define SYNTH_H

#include "sss.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct synth {
	int w, h;
	float *diff_dir, *diff_ind, *diff_col;
	float *gloss_dir, *gloss_ind, *gloss_col;
	float *trans_dir, *trans_ind, *trans_col;
	float *emit, *env, *combined; /* combined: RGBA */
	float *depth, *index, *position;
} synth;

static inline float *synth_buf_(size_t n, float v)
{
	float *p = malloc(n * sizeof *p);
	if (!p)
		abort();
	for (size_t i = 0; i < n; i++)
		p[i] = v;
	return p;
}

/* Background everywhere (depth 1e10, index 0), white DiffCol, no light. */
static inline synth *synth_new(int w, int h)
{
	synth *s = calloc(1, sizeof *s);
	if (!s)
		abort();
	size_t n = (size_t)w * h;
	s->w = w;
	s->h = h;
	s->diff_dir = synth_buf_(3 * n, 0);
	s->diff_ind = synth_buf_(3 * n, 0);
	s->diff_col = synth_buf_(3 * n, 1);
	s->gloss_dir = synth_buf_(3 * n, 0);
	s->gloss_ind = synth_buf_(3 * n, 0);
	s->gloss_col = synth_buf_(3 * n, 0);
	s->trans_dir = synth_buf_(3 * n, 0);
	s->trans_ind = synth_buf_(3 * n, 0);
	s->trans_col = synth_buf_(3 * n, 0);
	s->emit = synth_buf_(3 * n, 0);
	s->env = synth_buf_(3 * n, 0);
	s->combined = synth_buf_(4 * n, 1);
	s->depth = synth_buf_(n, 1e10f);
	s->index = synth_buf_(n, 0);
	s->position = NULL;
	return s;
}

static inline void synth_free(synth *s)
{
	if (!s)
		return;
	float *all[] = {s->diff_dir, s->diff_ind, s->diff_col, s->gloss_dir,
	                s->gloss_ind, s->gloss_col, s->trans_dir, s->trans_ind,
	                s->trans_col, s->emit, s->env, s->combined, s->depth,
	                s->index, s->position};
	for (size_t i = 0; i < sizeof all / sizeof *all; i++)
		free(all[i]);
	free(s);
}

static inline sss_image synth_view(float *data, int w, int h, int channels)
{
	sss_image im = {data, w, h, channels, 0};
	return im;
}

static inline sss_passes synth_passes(const synth *s)
{
	sss_passes p;
	memset(&p, 0, sizeof p);
	int w = s->w, h = s->h;
	p.diff_dir = synth_view(s->diff_dir, w, h, 3);
	p.diff_ind = synth_view(s->diff_ind, w, h, 3);
	p.diff_col = synth_view(s->diff_col, w, h, 3);
	p.gloss_dir = synth_view(s->gloss_dir, w, h, 3);
	p.gloss_ind = synth_view(s->gloss_ind, w, h, 3);
	p.gloss_col = synth_view(s->gloss_col, w, h, 3);
	p.trans_dir = synth_view(s->trans_dir, w, h, 3);
	p.trans_ind = synth_view(s->trans_ind, w, h, 3);
	p.trans_col = synth_view(s->trans_col, w, h, 3);
	p.emit = synth_view(s->emit, w, h, 3);
	p.env = synth_view(s->env, w, h, 3);
	p.combined = synth_view(s->combined, w, h, 4);
	p.depth = synth_view(s->depth, w, h, 1);
	p.index_ma = synth_view(s->index, w, h, 1);
	if (s->position)
		p.position = synth_view(s->position, w, h, 3);
	return p;
}

/* Deterministic xorshift32 in [0, 1). */
static inline float synth_rand(uint32_t *state)
{
	uint32_t x = *state;
	x ^= x << 13;
	x ^= x >> 17;
	x ^= x << 5;
	*state = x;
	return (float)(x >> 8) / 16777216.0f;
}

/* A fronto-parallel plane at depth z with material index m over the
 * rectangle [x0, x1) x [y0, y1). */
static inline void synth_plane(synth *s, int x0, int y0, int x1, int y1,
                               float z, float m)
{
	for (int y = y0; y < y1; y++)
		for (int x = x0; x < x1; x++) {
			size_t i = (size_t)y * s->w + x;
			s->depth[i] = z;
			s->index[i] = m;
		}
}

/* A sphere of radius `radius` centred on the view axis at depth `zc`, seen
 * by the default camera (50 mm lens, 36 mm sensor fit to the width), with
 * material index m: planar depth where the ray hits, background elsewhere. */
static inline void synth_sphere(synth *s, float zc, float radius, float m)
{
	double f = s->w * 50.0 / 36.0;
	for (int y = 0; y < s->h; y++)
		for (int x = 0; x < s->w; x++) {
			double dx = (x + 0.5 - s->w / 2.0) / f;
			double dy = (s->h / 2.0 - (y + 0.5)) / f;
			/* |t (dx, dy, 1) - (0, 0, zc)|^2 = radius^2, nearest t. */
			double a = dx * dx + dy * dy + 1.0, b = -2.0 * zc;
			double c = (double)zc * zc - (double)radius * radius;
			double disc = b * b - 4.0 * a * c;
			if (disc < 0.0)
				continue;
			size_t i = (size_t)y * s->w + x;
			s->depth[i] = (float)((-b - sqrt(disc)) / (2.0 * a));
			s->index[i] = m;
		}
}

/* Random diffuse light in [lo, hi) on every channel. */
static inline void synth_noise(synth *s, float lo, float hi, uint32_t seed)
{
	uint32_t st = seed ? seed : 1;
	for (size_t i = 0; i < (size_t)3 * s->w * s->h; i++)
		s->diff_dir[i] = lo + (hi - lo) * synth_rand(&st);
}

#endif
