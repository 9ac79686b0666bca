/* sss_blur1d_avx2.c - the separable method's inner loop on eight AVX2
 * lanes: one sample per lane, the same operations as sss_blur1d.c in the
 * same order and no fused multiply-adds, so the bits are the same. Built
 * for every x86-64 compiler that knows the target attribute; chosen at run
 * time only on CPUs that have AVX2. */
#include "sss_blur1d.h"

#if (defined(__x86_64__) || defined(__i386__)) && \
    (defined(__GNUC__) || defined(__clang__))

#include <cpuid.h>
#include <immintrin.h>

/* CPUID and XGETBV themselves rather than __builtin_cpu_supports: its
 * data (__cpu_model) comes from libgcc or compiler-rt, which not every
 * toolchain links into a shared library (Zig's, for the portable builds). */
int sss__blur1d_avx2_supported(void)
{
	unsigned a, b, c, d, lo, hi;
	if (!__get_cpuid(1, &a, &b, &c, &d) || !(c & bit_OSXSAVE) ||
	    !(c & bit_AVX))
		return 0;
	__asm__ volatile("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0));
	(void)hi;
	if ((lo & 6) != 6) /* the system saves the XMM and YMM registers */
		return 0;
	return __get_cpuid_count(7, 0, &a, &b, &c, &d) && (b & bit_AVX2);
}

#define AVX2 __attribute__((target("avx2")))

AVX2 static inline float lane_sum(__m256 v)
{
	__m128 r = _mm_add_ps(_mm256_castps256_ps128(v),
	                      _mm256_extractf128_ps(v, 1)); /* l0+l4 .. l3+l7 */
	__m128 u = _mm_add_ps(r, _mm_movehl_ps(r, r));     /* r0+r2, r1+r3 */
	return _mm_cvtss_f32(_mm_add_ss(u, _mm_shuffle_ps(u, u, 1)));
}

/* One vector of samples s .. s + 7 read from the given row pointers
 * (already offset to sample s), lanes outside `lanes` masked off. */
#define DENSE_STEP(rgb0, rgb1, rgb2, zp, sp, lanes)                           \
	do {                                                                      \
		__m256 sf = _mm256_cvtepi32_ps(_mm256_add_epi32(                      \
			_mm256_set1_epi32(s), iota));                                     \
		__m256 dz = _mm256_sub_ps(_mm256_loadu_ps(zp), zc);                   \
		__m256 xs = _mm256_add_ps(_mm256_cvtepi32_ps(_mm256_add_epi32(        \
			_mm256_set1_epi32(b->i + s), iota)), off);                        \
		__m256 e = _mm256_mul_ps(_mm256_mul_ps(dz, xs), ife);                 \
		__m256 xt2 = _mm256_mul_ps(sf, two_xt);                               \
		__m256 q = _mm256_add_ps(_mm256_mul_ps(e, _mm256_add_ps(e, xt2)),     \
		                         _mm256_mul_ps(_mm256_mul_ps(dz, dz), cz));   \
		q = _mm256_max_ps(q, zero); /* NaN -> 0, as in sss__blur1d_q */       \
		__m256i slots = _mm256_loadu_si256(                                   \
			(const __m256i *)(const void *)(sp));                             \
		__m256 valid = _mm256_and_ps(                                         \
			_mm256_castsi256_ps(_mm256_and_si256(                             \
				_mm256_cmpeq_epi32(slots, slot_c), (lanes))),                  \
			_mm256_cmp_ps(q, cut, _CMP_LT_OQ));                               \
		CHANNEL(0, rgb0, acc0, ws0);                                          \
		CHANNEL(1, rgb1, acc1, ws1);                                          \
		CHANNEL(2, rgb2, acc2, ws2);                                          \
	} while (0)

/* One channel's share of a vector of samples. */
#define CHANNEL(c, rgb, acc, ws)                                              \
	do {                                                                      \
		__m256 w0 = _mm256_loadu_ps(b->row0 + (c) * b->stride + s);          \
		__m256 w1 = _mm256_loadu_ps(b->row1 + (c) * b->stride + s);          \
		__m256 w = _mm256_and_ps(                                             \
			_mm256_add_ps(w0, _mm256_mul_ps(f, _mm256_sub_ps(w1, w0))), valid); \
		__m256 a = _mm256_loadu_ps(b->row0 + (3 + (c)) * b->stride + s);    \
		__m256 t = _mm256_max_ps(_mm256_sub_ps(one, _mm256_mul_ps(q, a)),  \
		                         zero);                                      \
		__m256 t2 = _mm256_mul_ps(t, t);                                      \
		__m256 t4 = _mm256_mul_ps(t2, t2);                                    \
		__m256 wgt = _mm256_mul_ps(w, _mm256_mul_ps(t4, t4));                 \
		acc = _mm256_add_ps(acc, _mm256_mul_ps(wgt, _mm256_loadu_ps(rgb)));   \
		ws = _mm256_add_ps(ws, wgt);                                          \
	} while (0)

AVX2 void sss__blur1d_avx2(sss__blur1d *b)
{
	const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
	const __m256 f = _mm256_set1_ps(b->f), cut = _mm256_set1_ps(b->cut_q);
	const __m256i slot_c = _mm256_set1_epi32(b->slot_c);
	const __m256i iota = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
	const __m256i all = _mm256_set1_epi32(-1);
	const __m256 zc = _mm256_set1_ps(b->zc), off = _mm256_set1_ps(b->off_axis);
	const __m256 ife = _mm256_set1_ps(b->ife), two_xt = _mm256_set1_ps(b->two_xt);
	const __m256 cz = _mm256_set1_ps(b->cz);
	const float *r0 = b->rgb[0] + b->i, *r1 = b->rgb[1] + b->i,
	            *r2 = b->rgb[2] + b->i, *zr = b->z + b->i;
	const int32_t *sr = b->slot + b->i;
	__m256 acc0 = zero, acc1 = zero, acc2 = zero;
	__m256 ws0 = zero, ws1 = zero, ws2 = zero;
	int32_t s = b->s_lo;
	for (; s + SSS__LANES - 1 <= b->s_hi; s += SSS__LANES)
		DENSE_STEP(r0 + s, r1 + s, r2 + s, zr + s, sr + s, all);
	if (s <= b->s_hi) {
		/* A short last vector reads on past the row where the arrays
		 * allow (the lanes are masked off) and otherwise goes through a
		 * padded copy: no light, another material. */
		int32_t n = b->s_hi - s + 1, j = b->i + s;
		__m256i lanes = _mm256_cmpgt_epi32(_mm256_set1_epi32(n), iota);
		if (j + SSS__LANES <= b->readable) {
			DENSE_STEP(r0 + s, r1 + s, r2 + s, zr + s, sr + s, lanes);
		} else {
			float st[4][SSS__LANES];
			int32_t slot_t[SSS__LANES];
			for (int l = 0; l < SSS__LANES; l++) {
				int in = l < n;
				for (int c = 0; c < 3; c++)
					st[c][l] = in ? b->rgb[c][j + l] : 0.0f;
				st[3][l] = in ? b->z[j + l] : b->zc;
				slot_t[l] = in ? b->slot[j + l] : -2;
			}
			DENSE_STEP(st[0], st[1], st[2], st[3], slot_t, lanes);
		}
	}
	b->acc[0] = lane_sum(acc0);
	b->acc[1] = lane_sum(acc1);
	b->acc[2] = lane_sum(acc2);
	b->wsum[0] = lane_sum(ws0);
	b->wsum[1] = lane_sum(ws1);
	b->wsum[2] = lane_sum(ws2);
}

/* Sparse taps: the same arithmetic on gathered pixels, each tap's two
 * pixels in turn (sss__blur1d_taps_scalar's order). */
AVX2 void sss__blur1d_taps_avx2(sss__blur1d *b, const sss__taps *t,
                                int32_t v0, int32_t v1)
{
	const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
	const __m256 cut = _mm256_set1_ps(b->cut_q), r = _mm256_set1_ps(b->r);
	const int lerp = t->w1[0] != NULL;
	const __m256 f_rows = _mm256_set1_ps(t->f);
	const __m256i centre = _mm256_set1_epi32(b->i);
	const __m256i len = _mm256_set1_epi32(b->len);
	const __m256i last = _mm256_set1_epi32(b->len - 1);
	const __m256i none = _mm256_set1_epi32(-1);
	const __m256i slot_c = _mm256_set1_epi32(b->slot_c);
	const __m256 zc = _mm256_set1_ps(b->zc), off = _mm256_set1_ps(b->off_axis);
	const __m256 ife = _mm256_set1_ps(b->ife), two_xt = _mm256_set1_ps(b->two_xt);
	const __m256 cz = _mm256_set1_ps(b->cz);
	__m256 acc[3] = {zero, zero, zero}, ws[3] = {zero, zero, zero};
	for (int32_t k = v0 * SSS__LANES; k < v1 * SSS__LANES; k += SSS__LANES) {
		__m256 o = _mm256_mul_ps(_mm256_loadu_ps(t->at + k), r);
		__m256 fl = _mm256_floor_ps(o);
		__m256 f = _mm256_sub_ps(o, fl);
		__m256i j0 = _mm256_add_epi32(centre, _mm256_cvttps_epi32(fl));
		for (int e = 0; e < 2; e++) {
			__m256 share = e ? f : _mm256_sub_ps(one, f);
			__m256i j = e ? _mm256_sub_epi32(j0, none) : j0;
			/* in the row: j > -1 and j < len */
			__m256i in = _mm256_and_si256(_mm256_cmpgt_epi32(j, none),
			                              _mm256_cmpgt_epi32(len, j));
			j = _mm256_min_epi32(_mm256_max_epi32(j, _mm256_setzero_si256()),
			                     last);
			__m256 sf = _mm256_cvtepi32_ps(_mm256_sub_epi32(j, centre));
			__m256 dz = _mm256_sub_ps(_mm256_i32gather_ps(b->z, j, 4), zc);
			__m256 xs = _mm256_add_ps(_mm256_cvtepi32_ps(j), off);
			__m256 ee = _mm256_mul_ps(_mm256_mul_ps(dz, xs), ife);
			__m256 xt2 = _mm256_mul_ps(sf, two_xt);
			__m256 q = _mm256_add_ps(_mm256_mul_ps(ee, _mm256_add_ps(ee, xt2)),
			                         _mm256_mul_ps(_mm256_mul_ps(dz, dz), cz));
			q = _mm256_max_ps(q, zero);
			__m256i same = _mm256_cmpeq_epi32(
				_mm256_i32gather_epi32((const int *)(const void *)b->slot, j, 4),
				slot_c);
			__m256 valid = _mm256_and_ps(
				_mm256_castsi256_ps(_mm256_and_si256(in, same)),
				_mm256_cmp_ps(q, cut, _CMP_LT_OQ));
			for (int c = 0; c < 3; c++) {
				__m256 wk = _mm256_loadu_ps(t->w[c] + k);
				__m256 a = _mm256_loadu_ps(t->a8[c] + k);
				if (lerp) {
					wk = _mm256_add_ps(wk, _mm256_mul_ps(f_rows, _mm256_sub_ps(
						_mm256_loadu_ps(t->w1[c] + k), wk)));
					a = _mm256_add_ps(a, _mm256_mul_ps(f_rows, _mm256_sub_ps(
						_mm256_loadu_ps(t->a81[c] + k), a)));
				}
				__m256 w = _mm256_and_ps(_mm256_mul_ps(share, wk), valid);
				__m256 tt = _mm256_max_ps(
					_mm256_sub_ps(one, _mm256_mul_ps(q, a)), zero);
				__m256 t2 = _mm256_mul_ps(tt, tt);
				__m256 t4 = _mm256_mul_ps(t2, t2);
				__m256 wgt = _mm256_mul_ps(w, _mm256_mul_ps(t4, t4));
				acc[c] = _mm256_add_ps(acc[c], _mm256_mul_ps(wgt,
					_mm256_i32gather_ps(b->rgb[c], j, 4)));
				ws[c] = _mm256_add_ps(ws[c], wgt);
			}
		}
	}
	for (int c = 0; c < 3; c++) {
		b->acc[c] = lane_sum(acc[c]);
		b->wsum[c] = lane_sum(ws[c]);
	}
}

#else

int sss__blur1d_avx2_supported(void)
{
	return 0;
}

void sss__blur1d_avx2(sss__blur1d *b)
{
	sss__blur1d_scalar(b);
}

void sss__blur1d_taps_avx2(sss__blur1d *b, const sss__taps *t, int32_t v0,
                           int32_t v1)
{
	sss__blur1d_taps_scalar(b, t, v0, v1);
}

#endif
