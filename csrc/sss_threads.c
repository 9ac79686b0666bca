/* sss_threads.c - row-band parallel loop. Each band writes disjoint rows
 * and every pixel's arithmetic is independent of the banding, so results
 * are identical for any thread count. */
#include "sss_internal.h"

#include <pthread.h>
#include <unistd.h>

#define MAX_THREADS 256

typedef struct band {
	sss__rows_fn fn;
	void *ctx;
	int32_t y0, y1;
} band;

static void *band_main(void *arg)
{
	band *b = arg;
	b->fn(b->ctx, b->y0, b->y1);
	return NULL;
}

void sss__parallel_rows(int32_t height, int32_t num_threads, sss__rows_fn fn,
                        void *ctx)
{
	int32_t n = num_threads;
	if (n <= 0) {
		long cores = sysconf(_SC_NPROCESSORS_ONLN);
		n = cores > 0 ? (int32_t)cores : 1;
	}
	if (n > MAX_THREADS)
		n = MAX_THREADS;
	if (n > height)
		n = height;
	if (n <= 1) {
		fn(ctx, 0, height);
		return;
	}
	band bands[MAX_THREADS];
	pthread_t threads[MAX_THREADS];
	int started[MAX_THREADS] = {0};
	for (int32_t t = 0; t < n; t++) {
		bands[t] = (band){fn, ctx, (int32_t)((int64_t)height * t / n),
		                  (int32_t)((int64_t)height * (t + 1) / n)};
		/* Band 0 runs on the calling thread; a band whose thread cannot
		 * be started runs there too, so the result never depends on it. */
		if (t > 0)
			started[t] = pthread_create(&threads[t], NULL, band_main,
			                            &bands[t]) == 0;
	}
	fn(ctx, bands[0].y0, bands[0].y1);
	for (int32_t t = 1; t < n; t++) {
		if (started[t])
			pthread_join(threads[t], NULL);
		else
			fn(ctx, bands[t].y0, bands[t].y1);
	}
}
