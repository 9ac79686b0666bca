/* sss_auto.c - what SSS_METHOD_AUTO runs for each material.
 *
 * The separable method tests depth one axis at a time, so where its kernel
 * is wide against the surface's curvature radius it carries light around
 * the object that the 2-D methods hold back (on a front-lit sphere, from
 * the lit middle to the rim). That is where it errs most against the
 * reference, and where it becomes worse than no SSS against Cycles'
 * random walk (docs/comparison.md); the disk method tests the true 3-D
 * distance of every sample. auto reads, per material, the median over a
 * grid of its pixels of x = the widest walk radius x the mean curvature
 * there (sss__mean_curvature: flat and concave read 0), and runs the disk
 * method where x reaches AUTO_DISK_X, the separable method elsewhere
 * (sss_apply.c runs them, the disk method normalised per source where
 * no back-lit transmission carries that light already).
 */
#include "sss_internal.h"

#include <stdlib.h>

/* Probes per material: a grid about this dense over its pixels. */
#define AUTO_PROBES 256

static int by_value(const void *a, const void *b)
{
	float x = *(const float *)a, y = *(const float *)b;
	return (x > y) - (x < y);
}

sss_result sss__auto_methods(const sss_image *depth, const int16_t *slot,
                             const sss__projection *proj, int32_t w,
                             int32_t h, const sss__kernel *kernels,
                             int32_t count, int32_t *method, float *median_x)
{
	size_t npix = (size_t)w * (size_t)h;
	size_t *pixels = calloc(count ? (size_t)count : 1, sizeof *pixels);
	int32_t *step = malloc((count ? (size_t)count : 1) * sizeof *step);
	size_t *start = malloc((count ? (size_t)count + 1 : 1) * sizeof *start);
	size_t *filled = calloc(count ? (size_t)count : 1, sizeof *filled);
	float *x_at = NULL;
	sss_result r = SSS_ERR_OUT_OF_MEMORY;
	if (!pixels || !step || !start || !filled)
		goto done;
	for (size_t i = 0; i < npix; i++)
		if (slot[i] >= 0)
			pixels[slot[i]]++;
	/* A grid step per material for about AUTO_PROBES probes; a material
	 * has at most as many probes as pixels. */
	start[0] = 0;
	for (int32_t m = 0; m < count; m++) {
		int32_t s = 1;
		while ((size_t)(s + 1) * (s + 1) * AUTO_PROBES <= pixels[m])
			s++;
		step[m] = s;
		size_t grid = (size_t)((w + s - 1) / s) * (size_t)((h + s - 1) / s);
		start[m + 1] = start[m] + (grid < pixels[m] ? grid : pixels[m]);
	}
	x_at = malloc((start[count] ? start[count] : 1) * sizeof *x_at);
	if (!x_at)
		goto done;
	/* Each material's own grid, in raster order: only its points are
	 * visited (a scan of every pixel with a division each cost more than
	 * the probes). */
	for (int32_t m = 0; m < count; m++) {
		if (!pixels[m])
			continue;
		const float *rad = kernels[m].walk_radius;
		double rho = fmax(rad[0], fmax(rad[1], rad[2]));
		for (int32_t y = 0; y < h; y += step[m])
			for (int32_t x = 0; x < w; x += step[m]) {
				if (slot[(size_t)y * w + x] != m)
					continue;
				double H = sss__mean_curvature(depth, slot, proj, w, h, x,
				                               y, rho);
				x_at[start[m] + filled[m]++] =
					(float)(H > 0.0 ? rho * H : 0.0);
			}
	}
	for (int32_t m = 0; m < count; m++) {
		float *v = x_at + start[m];
		size_t n = filled[m];
		float med = 0.0f;
		if (n) {
			qsort(v, n, sizeof *v, by_value);
			med = n % 2 ? v[n / 2] : 0.5f * (v[n / 2 - 1] + v[n / 2]);
		}
		if (median_x)
			median_x[m] = med;
		method[m] = n && med >= AUTO_DISK_X ? SSS_METHOD_DISK
		                                     : SSS_METHOD_SEPARABLE;
	}
	r = SSS_OK;
done:
	free(pixels);
	free(step);
	free(start);
	free(filled);
	free(x_at);
	return r;
}
