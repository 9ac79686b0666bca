/* sss_exr_decode.c - a multilayer EXR decoded straight into float
 * passes: header checks, limits, chunks decoded by threads (ZIP through
 * libdeflate); sss_exr_read. */
#include "sss_exr_internal.h"

#include <libdeflate.h>

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* ------------------------------------------------------------- decoding */

typedef struct read_job {
	exr_context_t ctxt;
	int part;
	const sss_exr *exr;
	const chan_ref *ref;     /* per source channel */
	int tiled;
	int b44;                 /* B44 or B44A: see raw_chunk */
	int zip;                 /* ZIP or ZIPS: see zip_decompress */
	int32_t lines;           /* scanlines per chunk */
	int32_t tile_w, tile_h, tiles_x;
	xio *io;
	exr_result_t rv;         /* first failure (under io->lock) */
	int32_t bad_x, bad_y;    /* its chunk, in pixels from the data window */
} read_job;

static int job_failed(read_job *job)
{
	pthread_mutex_lock(&job->io->lock);
	int failed = job->rv != EXR_ERR_SUCCESS;
	pthread_mutex_unlock(&job->io->lock);
	return failed;
}

static void job_fail(read_job *job, exr_result_t rv, int32_t x, int32_t y)
{
	pthread_mutex_lock(&job->io->lock);
	if (job->rv == EXR_ERR_SUCCESS) {
		job->rv = rv;
		job->bad_x = x;
		job->bad_y = y;
	}
	pthread_mutex_unlock(&job->io->lock);
}

/* Chunk i's info and its top-left pixel relative to the data window. */
static exr_result_t chunk_at(const read_job *job, int32_t i,
                             exr_chunk_info_t *ci, int32_t *x0, int32_t *y0)
{
	const sss_exr *exr = job->exr;
	exr_result_t rv;
	if (job->tiled) {
		int32_t tx = i % job->tiles_x, ty = i / job->tiles_x;
		*x0 = tx * job->tile_w;
		*y0 = ty * job->tile_h;
		rv = exr_read_tile_chunk_info(job->ctxt, job->part, tx, ty, 0, 0,
		                              ci);
	} else {
		*x0 = 0;
		*y0 = i * job->lines;
		rv = exr_read_scanline_chunk_info(
			job->ctxt, job->part, exr->data_window.min.y + *y0, ci);
		if (rv == EXR_ERR_SUCCESS)
			*y0 = ci->start_y - exr->data_window.min.y;
	}
	/* The buffers are ours: never trust a chunk to stay inside them. */
	if (rv == EXR_ERR_SUCCESS &&
	    (*y0 < 0 || *x0 < 0 || ci->width < 0 || ci->height < 0 ||
	     ci->width > exr->width - *x0 || ci->height > exr->height - *y0))
		rv = EXR_ERR_CORRUPT_CHUNK;
	return rv;
}

/* Every channel of the chunk at (x0, y0) straight to its place in its
 * pass: interleaved floats, halves and uints converted on the way. */
static void point_channels(const read_job *job, exr_decode_pipeline_t *dec,
                           int32_t x0, int32_t y0)
{
	const sss_exr *exr = job->exr;
	for (int c = 0; c < dec->channel_count; c++) {
		exr_coding_channel_info_t *ch = &dec->channels[c];
		const chan_ref *r = &job->ref[c];
		if (r->raw) {
			ch->decode_to_ptr = (uint8_t *)(r->raw + (size_t)y0 *
			                    (size_t)exr->width + (size_t)x0);
			ch->user_pixel_stride = (int32_t)sizeof *r->raw;
			ch->user_line_stride = exr->width * (int32_t)sizeof *r->raw;
			ch->user_bytes_per_element = (int16_t)sizeof *r->raw;
			ch->user_data_type = EXR_PIXEL_UINT;
			continue;
		}
		size_t at = ((size_t)y0 * (size_t)exr->width + (size_t)x0) *
		            (size_t)r->count + (size_t)r->k;
		ch->decode_to_ptr = (uint8_t *)(r->data + at);
		ch->user_pixel_stride = r->count * (int32_t)sizeof(float);
		ch->user_line_stride = exr->width * r->count * (int32_t)sizeof(float);
		ch->user_bytes_per_element = (int16_t)sizeof(float);
		ch->user_data_type = EXR_PIXEL_FLOAT;
	}
}

/* A chunk stored raw: its data is as long as its unpacked size, which
 * the file format (and the C++ library, so Blender) reads as "stored
 * uncompressed" whatever the codec. OpenEXRCore 3.1 does so for every
 * codec but B44 and B44A, which it runs through the B44 decoder anyway,
 * in place: a raw B44 chunk (an all-float file, a 1-line last chunk)
 * read as garbage or failed (found by tests/fuzz). The library has put
 * the raw bytes in the unpacked buffer already; nothing to undo. */
static exr_result_t raw_chunk(exr_decode_pipeline_t *dec)
{
	if (dec->unpacked_buffer != dec->packed_buffer)
		memcpy(dec->unpacked_buffer, dec->packed_buffer,
		       (size_t)dec->chunk.unpacked_size);
	return EXR_ERR_SUCCESS;
}

/* *buf holds at least n bytes (its contents are not kept); 0 when out of
 * memory, with *buf freed and *cap 0. */
int sss__exr_grow(uint8_t **buf, size_t *cap, size_t n)
{
	if (*cap >= n)
		return 1;
	free(*buf);
	*cap = 0;
	if (!(*buf = malloc(n)))
		return 0;
	*cap = n;
	return 1;
}

/* ZIP and ZIPS chunks are inflated by libdeflate (sss_zip.c); the
 * pipeline's decoding_user_data is the band's unzip_state. A chunk stored
 * raw (as long as its pixels) is used as it is. */
typedef struct unzip_state {
	struct libdeflate_decompressor *inflate;
	uint8_t *scratch;
	size_t cap;
} unzip_state;

static exr_result_t zip_decompress(exr_decode_pipeline_t *dec)
{
	unzip_state *z = dec->decoding_user_data;
	size_t n = (size_t)dec->chunk.unpacked_size;
	size_t packed = (size_t)dec->chunk.packed_size;
	if (packed == n) {
		if (dec->unpacked_buffer != dec->packed_buffer)
			memcpy(dec->unpacked_buffer, dec->packed_buffer, n);
		return EXR_ERR_SUCCESS;
	}
	if (!dec->unpacked_buffer)
		return EXR_ERR_CORRUPT_CHUNK;
	if (!sss__exr_grow(&z->scratch, &z->cap, n))
		return EXR_ERR_OUT_OF_MEMORY;
	return sss__zip_inflate(z->inflate, dec->packed_buffer, packed,
	                        z->scratch, dec->unpacked_buffer, n)
	       ? EXR_ERR_SUCCESS : EXR_ERR_CORRUPT_CHUNK;
}

/* Decodes chunks [c0, c1) with one pipeline; every channel goes straight
 * to its place in its pass (interleaved), halves and uints converted. */
static void decode_chunks(void *arg, int32_t c0, int32_t c1)
{
	read_job *job = arg;
	exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
	exr_result_t (*decompress)(exr_decode_pipeline_t *) = NULL;
	unzip_state unzip = {NULL, NULL, 0};
	int started = 0;
	if (job->zip && !(unzip.inflate = libdeflate_alloc_decompressor())) {
		job_fail(job, EXR_ERR_OUT_OF_MEMORY, 0, 0);
		return;
	}
	for (int32_t i = c0; i < c1 && !job_failed(job); i++) {
		exr_chunk_info_t ci;
		int32_t x0 = 0, y0 = 0;
		exr_result_t rv = chunk_at(job, i, &ci, &x0, &y0);
		if (rv == EXR_ERR_SUCCESS) {
			rv = started ? exr_decoding_update(job->ctxt, job->part, &ci,
			                                   &dec)
			             : exr_decoding_initialize(job->ctxt, job->part, &ci,
			                                       &dec);
			started = 1;
		}
		if (rv == EXR_ERR_SUCCESS && !dec.read_fn) {
			/* OpenEXRCore 3.1's fast path for 4 halves interleaved in
			 * reverse (a file's A B G R into our R G B A floats) writes
			 * them in the wrong order. The routine is picked from the
			 * pointers alone, so it is chosen with the channels pointing
			 * at one place (no interleave: a general routine, which
			 * reads the real pointers and strides on every run). */
			point_channels(job, &dec, x0, y0);
			for (int c = 1; c < dec.channel_count; c++)
				dec.channels[c].decode_to_ptr =
					dec.channels[0].decode_to_ptr;
			rv = exr_decoding_choose_default_routines(job->ctxt,
			                                          job->part, &dec);
			decompress = dec.decompress_fn;
			if (job->zip && dec.decompress_fn) {
				dec.decompress_fn = zip_decompress;
				dec.decoding_user_data = &unzip;
			}
		}
		if (rv == EXR_ERR_SUCCESS && job->b44)
			dec.decompress_fn = ci.packed_size == ci.unpacked_size
			                    ? raw_chunk : decompress;
		if (rv == EXR_ERR_SUCCESS)
			point_channels(job, &dec, x0, y0);
		if (rv == EXR_ERR_SUCCESS)
			rv = exr_decoding_run(job->ctxt, job->part, &dec);
		if (rv != EXR_ERR_SUCCESS)
			job_fail(job, rv, x0, y0);
	}
	if (started)
		exr_decoding_destroy(job->ctxt, &dec);
	libdeflate_free_decompressor(unzip.inflate);
	free(unzip.scratch);
}

/* decode_chunks over chunks 1.. (chunk 0 is decoded first, alone). */
static void decode_rest(void *arg, int32_t c0, int32_t c1)
{
	decode_chunks(arg, c0 + 1, c1 + 1);
}

/* Opens a read context on io's file; library size limits as given. */
static exr_result_t start_read(exr_context_t *ctxt, const char *path, xio *io,
                               int max_w, int max_h)
{
	exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
	init.error_handler_fn = sss__exr_on_read_error;
	init.user_data = io;
	init.read_fn = sss__exr_io_read;
	init.size_fn = sss__exr_io_size;
	init.max_image_width = max_w;
	init.max_image_height = max_h;
	return exr_start_read(ctxt, path, &init);
}

/* exr_start_read refused the header. If only because of our size limits,
 * say so (SSS_ERR_INVALID_ARGUMENT), by parsing it again without them. */
static int too_large(const char *path, xio *io, const sss_exr_options *o,
                     char *errbuf, size_t errbuf_len)
{
	exr_context_t c = NULL;
	exr_attr_box2i_t dw;
	int hit = 0;
	pthread_mutex_lock(&io->lock);
	io->quiet = 1;
	pthread_mutex_unlock(&io->lock);
	if (start_read(&c, path, io, 0, 0) == EXR_ERR_SUCCESS &&
	    exr_get_data_window(c, 0, &dw) == EXR_ERR_SUCCESS) {
		long long w = (long long)dw.max.x - dw.min.x + 1;
		long long h = (long long)dw.max.y - dw.min.y + 1;
		if (w > o->max_width || h > o->max_height) {
			FAILX(SSS_ERR_INVALID_ARGUMENT, "%s: data window %lldx%lld "
			      "exceeds the %dx%d limit", path, w, h, o->max_width,
			      o->max_height);
			hit = 1;
		}
	}
	if (c)
		exr_finish(&c);
	pthread_mutex_lock(&io->lock);
	io->quiet = 0;
	pthread_mutex_unlock(&io->lock);
	return hit;
}

/* Deep or unknown storage is refused; scanline and tiled parts are read. */
static sss_result check_storage(sss_exr *exr, int part, char *errbuf,
                                size_t errbuf_len)
{
	exr_storage_t storage;
	exr_result_t rv = exr_get_storage(exr->header, part, &storage);
	if (rv != EXR_ERR_SUCCESS)
		return sss__exr_fail(errbuf, errbuf_len, exr->path,
		                     "reading the header", rv, &exr->io);
	if (storage == EXR_STORAGE_DEEP_SCANLINE ||
	    storage == EXR_STORAGE_DEEP_TILED)
		return FAILX(SSS_ERR_UNSUPPORTED, "%s: deep image data is not "
		             "supported (render without deep output)", exr->path);
	if (storage != EXR_STORAGE_SCANLINE && storage != EXR_STORAGE_TILED)
		return FAILX(SSS_ERR_EXR, "%s: unknown storage type %d", exr->path,
		             (int)storage);
	return SSS_OK;
}

/* Every part: its storage, and one data window for all (a pass is one
 * image); the image's size and the part-0 windows kept for writing. */
static sss_result read_header(sss_exr *exr, const sss_exr_options *o,
                              char *errbuf, size_t errbuf_len)
{
	exr_context_t c = exr->header;
	const char *path = exr->path;
	int parts = 0;
	exr_result_t rv = exr_get_count(c, &parts);
	if (rv == EXR_ERR_SUCCESS && parts < 1)
		rv = EXR_ERR_FILE_BAD_HEADER;
	if (rv != EXR_ERR_SUCCESS)
		return sss__exr_fail(errbuf, errbuf_len, path, "reading the header", rv,
		                     &exr->io);
	exr->part_count = parts;
	sss_result r;
	exr_attr_box2i_t dw;
	for (int part = 0; part < parts; part++) {
		exr_attr_box2i_t pw;
		if ((r = check_storage(exr, part, errbuf, errbuf_len)))
			return r;
		if ((rv = exr_get_data_window(c, part, &pw)) != EXR_ERR_SUCCESS)
			return sss__exr_fail(errbuf, errbuf_len, path, "reading the data "
			                     "window", rv, &exr->io);
		if (part == 0) {
			dw = pw;
		} else if (memcmp(&pw, &dw, sizeof dw) != 0) {
			const char *name = NULL;
			exr_get_name(c, part, &name);
			return FAILX(SSS_ERR_UNSUPPORTED, "%s: part %d ('%s') has data "
			             "window (%d,%d)-(%d,%d), part 0 (%d,%d)-(%d,%d); "
			             "parts of different sizes are not supported", path,
			             part, name ? name : "", pw.min.x, pw.min.y,
			             pw.max.x, pw.max.y, dw.min.x, dw.min.y, dw.max.x,
			             dw.max.y);
		}
	}
	/* Sizes checked before anything is allocated. */
	long long w = (long long)dw.max.x - dw.min.x + 1;
	long long h = (long long)dw.max.y - dw.min.y + 1;
	if (w < 1 || h < 1)
		return FAILX(SSS_ERR_EXR, "%s: empty data window (%d,%d)-(%d,%d)",
		             path, dw.min.x, dw.min.y, dw.max.x, dw.max.y);
	if (w > o->max_width || h > o->max_height)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "%s: data window %lldx%lld "
		             "exceeds the %dx%d limit", path, w, h, o->max_width,
		             o->max_height);
	if (w * h > o->max_pixels)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "%s: data window %lldx%lld "
		             "has %lld pixels, more than the limit of %lld", path, w,
		             h, w * h, (long long)o->max_pixels);
	exr->width = (int32_t)w;
	exr->height = (int32_t)h;
	exr->data_window = dw;

	/* Kept for writing; a file that lacks them gets the defaults. */
	exr->display_window = dw;
	exr->pixel_aspect = 1.0f;
	exr->screen_width = 1.0f;
	exr_get_display_window(c, 0, &exr->display_window);
	exr_get_pixel_aspect_ratio(c, 0, &exr->pixel_aspect);
	exr_get_screen_window_center(c, 0, &exr->screen_center);
	exr_get_screen_window_width(c, 0, &exr->screen_width);
	return SSS_OK;
}

/* Decodes every chunk of one part, each channel straight into its pass
 * (ref: the part's channels, in its channel-list order). */
static sss_result decode_part(sss_exr *exr, const sss_exr_options *o,
                              int part, const chan_ref *ref, char *errbuf,
                              size_t errbuf_len)
{
	exr_context_t c = exr->header;
	const char *path = exr->path;
	read_job job = {.ctxt = c, .part = part, .exr = exr, .ref = ref,
	                .io = &exr->io};
	exr_storage_t storage = EXR_STORAGE_SCANLINE;
	int32_t chunks = 0;
	exr_compression_t comp = EXR_COMPRESSION_NONE;
	exr_result_t rv = exr_get_storage(c, part, &storage);
	if (rv == EXR_ERR_SUCCESS)
		rv = exr_get_compression(c, part, &comp);
	job.tiled = storage == EXR_STORAGE_TILED;
	job.b44 = comp == EXR_COMPRESSION_B44 || comp == EXR_COMPRESSION_B44A;
	job.zip = comp == EXR_COMPRESSION_ZIP || comp == EXR_COMPRESSION_ZIPS;
	if (rv == EXR_ERR_SUCCESS && job.tiled) {
		/* Level 0 only: mip/rip levels below it are not needed. */
		int32_t lw = 0, lh = 0;
		rv = exr_get_tile_sizes(c, part, 0, 0, &job.tile_w, &job.tile_h);
		if (rv == EXR_ERR_SUCCESS)
			rv = exr_get_level_sizes(c, part, 0, 0, &lw, &lh);
		if (rv == EXR_ERR_SUCCESS &&
		    (job.tile_w < 1 || job.tile_h < 1 || lw != exr->width ||
		     lh != exr->height))
			rv = EXR_ERR_FILE_BAD_HEADER;
		if (rv == EXR_ERR_SUCCESS) {
			job.tiles_x = (int32_t)(((int64_t)lw + job.tile_w - 1) /
			                        job.tile_w);
			chunks = job.tiles_x *
			         (int32_t)(((int64_t)lh + job.tile_h - 1) / job.tile_h);
		}
	} else if (rv == EXR_ERR_SUCCESS) {
		rv = exr_get_scanlines_per_chunk(c, part, &job.lines);
		if (rv == EXR_ERR_SUCCESS && job.lines < 1)
			rv = EXR_ERR_FILE_BAD_HEADER;
		if (rv == EXR_ERR_SUCCESS)
			chunks = (int32_t)(((int64_t)exr->height + job.lines - 1) /
			                   job.lines);
	}
	if (rv != EXR_ERR_SUCCESS)
		return sss__exr_fail(errbuf, errbuf_len, path, "reading the chunk "
		                     "layout", rv, &exr->io);

	/* The first chunk on this thread loads the chunk offset table once;
	 * then the rest in parallel, one pipeline per band of chunks. */
	decode_chunks(&job, 0, 1);
	if (job.rv == EXR_ERR_SUCCESS && chunks > 1)
		sss__parallel_rows(chunks - 1, o->num_threads, decode_rest, &job);
	if (job.rv == EXR_ERR_SUCCESS)
		return SSS_OK;
	char what[160], where[48] = "";
	const char *name = NULL;
	if (exr->part_count > 1 &&
	    exr_get_name(c, part, &name) == EXR_ERR_SUCCESS && name)
		snprintf(where, sizeof where, "part '%.30s', ", name);
	if (job.rv == EXR_ERR_FEATURE_NOT_IMPLEMENTED)
		snprintf(what, sizeof what, "decoding the pixels");
	else if (job.rv == EXR_ERR_OUT_OF_MEMORY)
		snprintf(what, sizeof what, "out of memory while decoding (%sthe "
		         "%s at y %d)", where, job.tiled ? "tile" : "scanlines",
		         exr->data_window.min.y + job.bad_y);
	else if (job.tiled)
		snprintf(what, sizeof what, "truncated or corrupt (%sthe tile at "
		         "x %d, y %d)", where, exr->data_window.min.x + job.bad_x,
		         exr->data_window.min.y + job.bad_y);
	else
		snprintf(what, sizeof what, "truncated or corrupt (%sthe scanlines "
		         "from y %d)", where, exr->data_window.min.y + job.bad_y);
	return sss__exr_fail(errbuf, errbuf_len, path, what, job.rv, &exr->io);
}

/* The memory the decoded image takes, checked before it is allocated:
 * at most max_bytes, or the machine's physical memory (a 5 MB file of
 * 646 channels took 2.8 GB; at the default pixel cap, 700 GB). */
static sss_result check_memory(const sss_exr *exr, const sss_exr_options *o,
                               char *errbuf, size_t errbuf_len)
{
	double bytes = 0.0;
	int64_t channels = 0;
	for (int32_t j = 0; j < exr->pass_count; j++)
		for (int32_t k = 0; k < exr->passes[j].count; k++) {
			channels++;
			bytes += exr->passes[j].chan[k].type == EXR_PIXEL_UINT ? 8 : 4;
		}
	bytes *= (double)exr->width * (double)exr->height;
	double limit = (double)o->max_bytes;
	int machine = o->max_bytes == 0;
	if (machine) {
		long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGESIZE);
		limit = pages > 0 && size > 0 ? (double)pages * (double)size
		                              : 9.2e18;
	}
	if (bytes <= limit)
		return SSS_OK;
	int gib = limit >= 1073741824.0;
	double unit = gib ? 1073741824.0 : 1048576.0;
	return FAILX(SSS_ERR_INVALID_ARGUMENT, "%s: its %dx%d pixels x %lld "
	             "channels take %.2f %s decoded, more than the limit of "
	             "%.2f %s%s (raise it with sss --max-memory, or "
	             "sss_exr_options.max_bytes)", exr->path, exr->width,
	             exr->height, (long long)channels, bytes / unit,
	             gib ? "GiB" : "MiB", limit / unit, gib ? "GiB" : "MiB",
	             machine ? ", the machine's memory" : "");
}

/* Allocates every pass and decodes every part into them. */
static sss_result decode_image(sss_exr *exr, const sss_exr_options *o,
                               char *errbuf, size_t errbuf_len)
{
	const char *path = exr->path;
	size_t npix = (size_t)exr->width * (size_t)exr->height;
	int32_t channels = 0;
	sss_result mr = check_memory(exr, o, errbuf, errbuf_len);
	if (mr)
		return mr;
	for (int32_t j = 0; j < exr->pass_count; j++) {
		xpass *p = &exr->passes[j];
		channels += p->count;
		if ((int64_t)exr->width * p->count * (int64_t)sizeof(float) >
		    INT32_MAX)
			return FAILX(SSS_ERR_UNSUPPORTED, "%s: pass '%s' has too many "
			             "components (%d) for its width", path, p->pass,
			             p->count);
		if (npix > SIZE_MAX / sizeof(float) / (size_t)p->count ||
		    !(p->data = calloc(npix * (size_t)p->count, sizeof(float))))
			return FAILX(SSS_ERR_OUT_OF_MEMORY, "%s: cannot allocate pass "
			             "'%s' (%dx%d x %d)", path, p->pass, exr->width,
			             exr->height, p->count);
	}
	if (channels == 0)
		return SSS_OK;

	chan_ref *ref = calloc((size_t)channels, sizeof *ref);
	if (!ref)
		return FAILX(SSS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
	for (int32_t j = 0; j < exr->pass_count; j++)
		for (int32_t k = 0; k < exr->passes[j].count; k++) {
			xchan *ch = &exr->passes[j].chan[k];
			if (ch->type == EXR_PIXEL_UINT &&
			    !(ch->raw = calloc(npix, sizeof *ch->raw))) {
				free(ref);
				return FAILX(SSS_ERR_OUT_OF_MEMORY, "%s: out of memory "
				             "for channel '%s'", path, ch->name);
			}
			ref[ch->index] = (chan_ref){exr->passes[j].data,
			                            exr->passes[j].count, k, ch->raw};
		}
	sss_result r = SSS_OK;
	int32_t first = 0;
	for (int part = 0; part < exr->part_count && !r; part++) {
		const exr_attr_chlist_t *cl = NULL;
		exr_result_t rv = exr_get_channels(exr->header, part, &cl);
		if (rv != EXR_ERR_SUCCESS)
			r = sss__exr_fail(errbuf, errbuf_len, path, "reading the channel "
			                  "list", rv, &exr->io);
		else if (cl->num_channels > 0)
			r = decode_part(exr, o, part, ref + first, errbuf, errbuf_len);
		if (!r)
			first += cl->num_channels;
	}
	free(ref);
	/* uint channels into their float view (exact up to 2^24). */
	for (int32_t j = 0; j < exr->pass_count && !r; j++) {
		xpass *p = &exr->passes[j];
		for (int32_t k = 0; k < p->count; k++)
			if (p->chan[k].raw)
				for (size_t i = 0; i < npix; i++)
					p->data[i * (size_t)p->count + (size_t)k] =
						(float)p->chan[k].raw[i];
	}
	return r;
}

/* ----------------------------------------------------------------- read */

sss_result sss_exr_read(const char *path, const sss_exr_options *opt,
                        sss_exr **out, char *errbuf, size_t errbuf_len)
{
	sss_exr_options o;
	sss_result r;
	if (errbuf && errbuf_len)
		errbuf[0] = '\0';
	if (!out)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "sss_exr_read: out is NULL");
	*out = NULL;
	if (!path || !path[0])
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "sss_exr_read: no path");
	if ((r = sss__exr_get_options(opt, &o, errbuf, errbuf_len)))
		return r;

	/* Our own descriptor: a missing file is SSS_ERR_IO, and its device
	 * and inode identify the source for sss_exr_write's refusal. */
	int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC); /* a FIFO:
	                                   no wait for a writer, refused below */
	if (fd < 0)
		return FAILX(SSS_ERR_IO, "%s: cannot open: %s", path,
		             strerror(errno));
	struct stat st;
	if (fstat(fd, &st)) {
		int e = errno;
		close(fd);
		return FAILX(SSS_ERR_IO, "%s: %s", path, strerror(e));
	}
	if (!S_ISREG(st.st_mode)) {
		close(fd);
		return FAILX(SSS_ERR_IO, "%s: is %s; EXR files are read from "
		             "regular files only", path, sss__file_kind(st.st_mode));
	}
	sss_exr *exr = calloc(1, sizeof *exr);
	if (!exr || !(exr->path = sss__exr_dup_n(path, strlen(path)))) {
		free(exr);
		close(fd);
		return FAILX(SSS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
	}
	sss__xio_init(&exr->io, fd);
	exr->io.size = (int64_t)st.st_size;
	exr->dev = st.st_dev;
	exr->ino = st.st_ino;

	exr_result_t rv = start_read(&exr->header, path, &exr->io, o.max_width,
	                             o.max_height);
	if (rv != EXR_ERR_SUCCESS) {
		exr->header = NULL; /* the library has finished it */
		if (too_large(path, &exr->io, &o, errbuf, errbuf_len))
			r = SSS_ERR_INVALID_ARGUMENT;
		else if (st.st_size == 0)
			r = FAILX(SSS_ERR_EXR, "%s: not an OpenEXR file (it is empty)",
			          path);
		else
			r = sss__exr_fail(errbuf, errbuf_len, path, "not a readable "
			                  "OpenEXR file", rv, &exr->io);
	} else if (!(r = read_header(exr, &o, errbuf, errbuf_len)) &&
	           !(r = sss__exr_group_channels(exr, o.max_channels, errbuf,
	                                         errbuf_len))) {
		r = decode_image(exr, &o, errbuf, errbuf_len);
	}
	/* The header stays in memory for sss_exr_write; the file is done. */
	close(fd);
	pthread_mutex_lock(&exr->io.lock);
	exr->io.fd = -1;
	exr->io.quiet = 1;
	pthread_mutex_unlock(&exr->io.lock);
	if (r) {
		sss_exr_free(exr);
		return r;
	}
	*out = exr;
	if (o.progress_fn)
		o.progress_fn(1.0, o.progress_user);
	return SSS_OK;
}
