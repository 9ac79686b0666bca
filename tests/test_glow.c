/* test_glow.c - the glow facing parts of a back-lit material send each
 * other (sss_glow.c). On the inside of a sphere every two points see each
 * other with cos_p cos_q / r^2 = 1 / (4 R^2), so a bowl (a hemisphere
 * opening towards an orthographic camera) glowing with radiance L sends
 * its bottom L A / (4 pi R^2) to add to its diffuse light, A the area that
 * glows: L / 2 for the whole bowl. A flat plane and a dome send
 * themselves nothing; light does not pass between slots, or to a slot
 * that does not receive; and a bowl three times as many pixels across,
 * on a grid coarser than its pixels, gets about the same. */
#include "sss_internal.h"
#include "test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define N 120 /* image side, pixels */

enum surface { BOWL, DOME, PLANE };

/* Depth of a unit-radius surface centred at depth 4 through pixel (x, y)
 * of an orthographic view 2.4 radii wide, or 0 where it misses. */
static double depth_at(enum surface s, int x, int y, int n)
{
	double u = ((x + 0.5) / n - 0.5) * 2.4, v = ((y + 0.5) / n - 0.5) * 2.4;
	double r2 = u * u + v * v;
	if (s == PLANE)
		return 4.0;
	if (r2 >= 1.0)
		return 0.0;
	return s == BOWL ? 4.0 + sqrt(1.0 - r2) : 4.0 - sqrt(1.0 - r2);
}

typedef struct frame {
	int n;
	float *depth, *glow, *out;
	int16_t *slot;
	sss_image dimg;
	sss__projection proj;
} frame;

static void frame_make(frame *f, enum surface s, int n, int16_t (*slot_of)(
	                       int x, int y))
{
	f->n = n;
	f->depth = calloc((size_t)n * n, sizeof *f->depth);
	f->glow = calloc((size_t)sss__glow_points(n, n) * 3, sizeof *f->glow);
	f->out = calloc((size_t)n * 3, sizeof *f->out);
	f->slot = malloc((size_t)n * n * sizeof *f->slot);
	for (int y = 0; y < n; y++)
		for (int x = 0; x < n; x++) {
			size_t i = (size_t)y * n + x;
			double z = depth_at(s, x, y, n);
			f->depth[i] = (float)z;
			f->slot[i] = z > 0.0 ? (slot_of ? slot_of(x, y) : 0) : -1;
			int64_t g = sss__glow_point_of(n, n, x, y);
			for (int c = 0; g >= 0 && c < 3; c++)
				f->glow[3 * g + c] = f->slot[i] >= 0 ? 1.0f + c : 0.0f;
		}
	f->dimg = (sss_image){f->depth, n, n, 1, 0};
	f->proj = (sss__projection){1, n / 2.4, n / 2.4, n / 2.0, n / 2.0};
}

static void frame_free(frame *f)
{
	free(f->depth);
	free(f->glow);
	free(f->out);
	free(f->slot);
}

/* What pixel (x, y) receives, channel c. */
static float received(const frame *f, const uint8_t *receives, int x, int y,
                      int c)
{
	sss__glow *g = NULL;
	sss_result r = sss__glow_make(f->glow, &f->dimg, f->slot, receives,
	                              &f->proj, f->n, f->n, 2, &g);
	CHECK("make", r == SSS_OK, "%s", sss_status_name(r));
	if (r)
		return NAN;
	sss__glow_row(g, y, f->slot + (size_t)y * f->n, f->out);
	float v = f->out[3 * x + c];
	sss__glow_free(g);
	return v;
}

static int16_t halves(int x, int y)
{
	(void)y;
	return x < N / 2 ? 0 : 1;
}

int main(void)
{
	uint8_t both[2] = {1, 1}, first[2] = {1, 0};
	frame f;

	/* The bowl's bottom: the whole bowl glows, L / 2 (the pixels next
	 * to the receiver count from 1.5 grid steps on, and the outline's
	 * pixels stand for less than their share: 0.46 at 120 x 120). */
	frame_make(&f, BOWL, N, NULL);
	for (int c = 0; c < 3; c++) {
		float v = received(&f, both, N / 2, N / 2, c);
		CHECK("bowl.bottom", fabsf(v / ((1.0f + c) * 0.5f) - 1.0f) < 0.1f,
		      "channel %d: %g, expected about %g", c, v, (1.0 + c) * 0.5);
	}
	/* halfway up the wall it is the same on a sphere */
	float mid = received(&f, both, N / 2 + 30, N / 2, 0);
	CHECK("bowl.wall", fabsf(mid / 0.5f - 1.0f) < 0.1f, "%g", mid);
	/* a slot that does not receive gets nothing */
	f.slot[(size_t)(N / 2) * N + N / 2] = 0;
	uint8_t none[1] = {0};
	CHECK("bowl.not-receiving", received(&f, none, N / 2, N / 2, 0) == 0.0f,
	      "something came");
	frame_free(&f);

	/* Split into two slots down the middle: the left half's bottom
	 * receives only from the left half, about half as much; the right
	 * half, not receiving, gets nothing. */
	frame_make(&f, BOWL, N, halves);
	float left = received(&f, both, N / 2 - 2, N / 2, 0);
	CHECK("bowl.slots", left > 0.18f && left < 0.28f, "%g", left);
	CHECK("bowl.slot-off", received(&f, first, N / 2 + 2, N / 2, 0) == 0.0f,
	      "the right half received");
	frame_free(&f);

	/* Nothing between the points of a plane or of a dome. */
	enum surface flat[2] = {PLANE, DOME};
	const char *ids[2] = {"plane", "dome"};
	for (int k = 0; k < 2; k++) {
		frame_make(&f, flat[k], N, NULL);
		float worst = 0.0f;
		for (int y = 10; y < N - 10; y += 7)
			for (int x = 10; x < N - 10; x += 7)
				if (f.slot[(size_t)y * N + x] >= 0) {
					float v = received(&f, both, x, y, 2);
					worst = v > worst ? v : worst;
				}
		CHECK(ids[k], worst < 1e-4f, "received %g", worst);
		frame_free(&f);
	}

	/* A larger image takes a coarser grid (at most GLOW_GRID points
	 * across) and gets about the same. */
	frame_make(&f, BOWL, 3 * N, NULL);
	float big = received(&f, both, 3 * N / 2, 3 * N / 2, 0);
	CHECK("bowl.coarse-grid", fabsf(big / 0.5f - 1.0f) < 0.1f, "%g", big);
	frame_free(&f);

	return tu_finish("test_glow");
}
