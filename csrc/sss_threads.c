/* sss_threads.c - parallel loop over rows. The rows are cut into chunks
 * that the threads take in turn from a shared counter, so a frame whose
 * scattering object fills only part of it keeps every core busy. Every
 * row's arithmetic is independent of who computes it, so results are
 * identical for any thread count. */
#define _GNU_SOURCE /* sched_getaffinity, CPU_COUNT */
#include "sss_internal.h"

#include <pthread.h>
#ifdef __linux__
#include <sched.h>
#endif
#include <stdatomic.h>
#include <unistd.h>

#define MAX_THREADS 256
/* Chunks per thread: enough to even out uneven rows, few enough that
 * per-chunk set-up (scratch, table rows) stays negligible. */
#define CHUNKS_PER_THREAD 8

typedef struct shared {
	sss__rows_fn fn;
	void *ctx;
	int32_t height, chunk;
	atomic_int next;
} shared;

static void *worker(void *arg)
{
	shared *s = arg;
	for (;;) {
		int32_t c = atomic_fetch_add(&s->next, 1);
		int64_t y0 = (int64_t)c * s->chunk;
		if (y0 >= s->height)
			return NULL;
		int64_t y1 = y0 + s->chunk < s->height ? y0 + s->chunk : s->height;
		s->fn(s->ctx, (int32_t)y0, (int32_t)y1);
	}
}

/* The CPUs this process may run on: its affinity mask where the system
 * has one (Linux: taskset, a farm's cpuset), else every online CPU. */
int32_t sss__cpu_count(void)
{
#ifdef __linux__
	cpu_set_t set;
	CPU_ZERO(&set);
	if (sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0)
		return CPU_COUNT(&set);
#endif
	long cores = sysconf(_SC_NPROCESSORS_ONLN);
	return cores > 0 ? (int32_t)(cores < MAX_THREADS ? cores : MAX_THREADS)
	                 : 1;
}

void sss__parallel_rows(int32_t height, int32_t num_threads, sss__rows_fn fn,
                        void *ctx)
{
	int32_t n = num_threads > 0 ? num_threads : sss__cpu_count();
	if (n > MAX_THREADS)
		n = MAX_THREADS;
	if (n > height)
		n = height;
	if (n <= 1) {
		if (height > 0)
			fn(ctx, 0, height);
		return;
	}
	int32_t chunk = (int32_t)(((int64_t)height + (int64_t)n *
	                           CHUNKS_PER_THREAD - 1) /
	                          ((int64_t)n * CHUNKS_PER_THREAD));
	shared s = {fn, ctx, height, chunk, 0};
	pthread_t threads[MAX_THREADS];
	int started[MAX_THREADS] = {0};
	/* The calling thread works too; a thread that cannot be started
	 * leaves its share to the others, so the result never depends on it. */
	for (int32_t t = 1; t < n; t++)
		started[t] = pthread_create(&threads[t], NULL, worker, &s) == 0;
	worker(&s);
	for (int32_t t = 1; t < n; t++)
		if (started[t])
			pthread_join(threads[t], NULL);
}
