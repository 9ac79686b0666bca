/* sss_exr_internal.h - what the EXR files share: the in-memory pass model
 * (sss_exr.c), the OpenEXRCore stream callbacks (sss_exr_stream.c), and
 * the entry points of decoding (sss_exr_decode.c) and encoding
 * (sss_exr_encode.c) that the model and the output policy
 * (sss_exr_output.c) call. Only these files see openexr.h. */
#ifndef SSS_EXR_INTERNAL_H
#define SSS_EXR_INTERNAL_H

#include "sss_internal.h"

#include <openexr.h>

#include <pthread.h>
#include <sys/types.h>


/* EXR allows 255-byte names once long names are switched on. */
#define MAX_NAME 255
#define SHORT_NAME 31

typedef struct xchan {
	char *name;       /* full channel name, as in the file (or rebuilt) */
	const char *comp; /* the component: name after its last dot */
	int32_t type;     /* exr_pixel_type_t on disk, restored on writing */
	uint8_t p_linear; /* perceptual hint, kept for lossy codecs */
	int32_t index;    /* position among the source's channels, counted
	                   * over its parts in order; -1: added */
	uint32_t *raw;    /* a uint channel's own values (width x height),
	                   * which a float holds exactly only up to 2^24:
	                   * written back while the float view still reads
	                   * the same; NULL for other types */
} xchan;

typedef struct xpass {
	char *layer, *pass;
	char *components; /* "RGB"; names joined by ',' if one is not 1 char */
	int32_t count;    /* components, in canonical order */
	xchan *chan;
	float *data;      /* width x height x count floats, interleaved */
} xpass;

/* One context's file and error detail. OpenEXRCore hands it back to our
 * read/write callbacks and (read contexts) to the error handler through
 * user_data, so there is no global state and nothing is printed. */
typedef struct xio {
	int fd;
	int64_t size;           /* file size, lets the library reject offsets */
	int quiet;              /* set once decoded: later messages dropped */
	pthread_mutex_t lock;   /* decoding threads report concurrently */
	char msg[256];          /* the first detail message */
} xio;

struct sss_exr {
	int32_t width, height;
	exr_attr_box2i_t data_window, display_window;
	float pixel_aspect, screen_width;
	exr_attr_v2f_t screen_center;
	char *path;             /* as given, for messages */
	dev_t dev;              /* identity of the source file: never */
	ino_t ino;              /* written over */
	int32_t pass_count, pass_cap;
	xpass *passes;
	int part_count;         /* parts read: all share one data window */
	exr_context_t header;   /* the source header, kept for its metadata */
	xio io;                 /* header's callbacks' state (quiet by now) */
};

/* Where one source channel lands: its pass's buffer and component, and
 * a uint channel's own plane (decoded there, then converted;
 * written back from it). */
typedef struct chan_ref {
	float *data;
	int32_t count, k;
	uint32_t *raw;
} chan_ref;

/* ----------------------------------------------- sss_exr_stream.c */

/* io's state for descriptor fd (its size read when it is a file). */
void sss__xio_init(xio *io, int fd);

/* OpenEXRCore's callbacks: the error handlers keep the first detail
 * message in the context's xio; the streams read and write its fd. */
void sss__exr_on_read_error(exr_const_context_t ctxt, exr_result_t code,
                            const char *msg);
void sss__exr_on_write_error(exr_const_context_t ctxt, exr_result_t code,
                             const char *msg);
int64_t sss__exr_io_read(exr_const_context_t ctxt, void *ud, void *buffer,
                         uint64_t sz, uint64_t offset,
                         exr_stream_error_func_ptr_t error_cb);
int64_t sss__exr_io_size(exr_const_context_t ctxt, void *ud);
int64_t sss__exr_io_write(exr_const_context_t ctxt, void *ud,
                          const void *buffer, uint64_t sz, uint64_t offset,
                          exr_stream_error_func_ptr_t error_cb);

/* "path: what: detail" for an OpenEXRCore failure, with the status its
 * code maps to. */
sss_result sss__exr_fail(char *errbuf, size_t errbuf_len, const char *path,
                         const char *what, exr_result_t rv, xio *io);

/* ------------------------------------------------------ sss_exr.c */

/* A NUL-terminated copy of s's first n bytes, or NULL. */
char *sss__exr_dup_n(const char *s, size_t n);

/* The caller's options (NULL: the defaults) checked into *o. */
sss_result sss__exr_get_options(const sss_exr_options *user,
                                sss_exr_options *o, char *errbuf,
                                size_t errbuf_len);

/* The header's channels grouped into passes (layer, pass, components). */
sss_result sss__exr_group_channels(sss_exr *exr, int32_t max_channels,
                                   char *errbuf, size_t errbuf_len);

/* The source's attributes, file order; *list is malloc'ed. */
exr_result_t sss__exr_source_attributes(const sss_exr *exr,
                                        const exr_attribute_t ***list,
                                        int32_t *count);

/* ----------------------------------------------- sss_exr_decode.c */

/* Grows *buf (capacity *cap) to hold n bytes; 0 when out of memory. */
int sss__exr_grow(uint8_t **buf, size_t *cap, size_t n);

/* ----------------------------------------------- sss_exr_encode.c */

/* Writes the whole file to io (the temporary file tmp for path). */
sss_result sss__exr_encode(const sss_exr *exr, const sss_exr_options *o,
                           const char *path, const char *tmp, xio *io,
                           char *errbuf, size_t errbuf_len);

#endif
