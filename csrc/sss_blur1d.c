/* sss_blur1d.c - the separable method's inner loop in portable C: eight
 * lanes emulated in the order the vector implementation uses, so that both
 * give the same bits (see sss_blur1d.h). */
#include "sss_blur1d.h"

#include <math.h>

/* Lanes summed as the vector code does: ((l0+l4)+(l2+l6))+((l1+l5)+(l3+l7)). */
static inline float lane_sum(const float l[SSS__LANES])
{
	float r0 = l[0] + l[4], r1 = l[1] + l[5], r2 = l[2] + l[6],
	      r3 = l[3] + l[7];
	return (r0 + r2) + (r1 + r3);
}

void sss__blur1d_scalar(sss__blur1d *b)
{
	float acc[3][SSS__LANES] = {{0}}, ws[3][SSS__LANES] = {{0}};
	for (int32_t s = b->s_lo; s <= b->s_hi; s++) {
		int lane = (int)((s - b->s_lo) % SSS__LANES);
		int32_t j = b->i + s;
		float q = sss__blur1d_q(b, j, s);
		int valid = b->slot[j] == b->slot_c && q < b->cut_q;
		for (int c = 0; c < 3; c++) {
			float w0 = b->row0[c * b->stride + s];
			float w1 = b->row1[c * b->stride + s];
			float w = w0 + b->f * (w1 - w0);
			w = valid ? w : 0.0f;
			float wgt = w * sss__blur1d_rho(q, b->row0[(3 + c) * b->stride + s]);
			acc[c][lane] += wgt * b->rgb[c][j];
			ws[c][lane] += wgt;
		}
	}
	for (int c = 0; c < 3; c++) {
		b->acc[c] = lane_sum(acc[c]);
		b->wsum[c] = lane_sum(ws[c]);
	}
}

void sss__blur1d_taps_scalar(sss__blur1d *b, const sss__taps *t, int32_t v0,
                             int32_t v1)
{
	float acc[3][SSS__LANES] = {{0}}, ws[3][SSS__LANES] = {{0}};
	for (int32_t k0 = v0 * SSS__LANES; k0 < v1 * SSS__LANES; k0 += SSS__LANES)
		for (int e = 0; e < 2; e++)
			for (int lane = 0; lane < SSS__LANES; lane++) {
				int32_t k = k0 + lane;
				float o = t->at[k] * b->r;
				float fl = floorf(o);
				float f = o - fl;
				float share = e ? f : 1.0f - f;
				int32_t j = b->i + (int32_t)fl + e;
				int in = j >= 0 && j < b->len;
				j = j < 0 ? 0 : j >= b->len ? b->len - 1 : j;
				float q = sss__blur1d_q(b, j, j - b->i);
				int valid = in && b->slot[j] == b->slot_c && q < b->cut_q;
				for (int c = 0; c < 3; c++) {
					float wk = t->w[c][k], ak = t->a8[c][k];
					if (t->w1[0]) {
						wk = wk + t->f * (t->w1[c][k] - wk);
						ak = ak + t->f * (t->a81[c][k] - ak);
					}
					float w = valid ? share * wk : 0.0f;
					float wgt = w * sss__blur1d_rho(q, ak);
					acc[c][lane] += wgt * b->rgb[c][j];
					ws[c][lane] += wgt;
				}
			}
	for (int c = 0; c < 3; c++) {
		b->acc[c] = lane_sum(acc[c]);
		b->wsum[c] = lane_sum(ws[c]);
	}
}
