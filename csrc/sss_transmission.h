/* sss_transmission.h - private interface of sss_transmission.c: back-lit
 * transmission added to the diffuse light before the blur. */
#ifndef SSS_TRANSMISSION_H
#define SSS_TRANSMISSION_H

#include "sss.h"

typedef struct sss__transmission sss__transmission;

/* Checks the back-light passes against the image size and the outputs,
 * and prepares every transmitting material in scene units. *out is NULL
 * (and nothing is transmitted) when there is no back light or no material
 * transmits. materials must already be valid. */
sss_result sss__transmission_prepare(const sss_passes *p,
                                     const sss_material *materials,
                                     int32_t material_count,
                                     const sss_options *opt,
                                     double unit_scale, int32_t width,
                                     int32_t height,
                                     const sss_image *out_a,
                                     const sss_image *out_b,
                                     sss__transmission **out,
                                     char *errbuf, size_t errbuf_len);

/* Adds material m's transmitted light at pixel (x, y) to light[3]. A
 * non-finite back light or a NaN or negative thickness adds nothing. */
void sss__transmission_add(const sss__transmission *t, int32_t m, int32_t x,
                           int32_t y, float light[3]);

/* Whether material m takes back-lit light in this frame (t may be NULL). */
int sss__transmission_active(const sss__transmission *t, int32_t m);

void sss__transmission_free(sss__transmission *t); /* NULL is fine */

#endif /* SSS_TRANSMISSION_H */
