/* sss_exr_encode.c - the passes encoded losslessly into one scanline
 * part, the source's attributes copied (Blender's metadata), chunks
 * compressed by threads (ZIP through libdeflate). */
#include "sss_exr_internal.h"

#include <libdeflate.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------- write */

/* Required and structural attributes: set by us for a single-part
 * scanline file, never copied from the source (which may be tiled, deep
 * or multi-part). Everything else (Blender's metadata) is copied. */
static int is_structural(const char *name)
{
	static const char *const names[] = {
		"channels", "compression", "dataWindow", "displayWindow",
		"lineOrder", "pixelAspectRatio", "screenWindowCenter",
		"screenWindowWidth", "tiles", "type", "name", "version",
		"chunkCount", "maxSamplesPerPixel",
	};
	for (size_t i = 0; i < sizeof names / sizeof *names; i++)
		if (strcmp(name, names[i]) == 0)
			return 1;
	return 0;
}


/* One attribute through the typed setter for its type. */
static exr_result_t copy_attribute(exr_context_t c, int part,
                                   const exr_attribute_t *a)
{
	const char *n = a->name;
	switch (a->type) {
	case EXR_ATTR_BOX2I: return exr_attr_set_box2i(c, part, n, a->box2i);
	case EXR_ATTR_BOX2F: return exr_attr_set_box2f(c, part, n, a->box2f);
	case EXR_ATTR_CHLIST:
		return exr_attr_set_channels(c, part, n, a->chlist);
	case EXR_ATTR_CHROMATICITIES:
		return exr_attr_set_chromaticities(c, part, n, a->chromaticities);
	case EXR_ATTR_COMPRESSION:
		return exr_attr_set_compression(c, part, n,
		                                (exr_compression_t)a->uc);
	case EXR_ATTR_DOUBLE: return exr_attr_set_double(c, part, n, a->d);
	case EXR_ATTR_ENVMAP:
		return exr_attr_set_envmap(c, part, n, (exr_envmap_t)a->uc);
	case EXR_ATTR_FLOAT: return exr_attr_set_float(c, part, n, a->f);
	case EXR_ATTR_FLOAT_VECTOR:
		return exr_attr_set_float_vector(c, part, n,
		                                 a->floatvector->length,
		                                 a->floatvector->arr);
	case EXR_ATTR_INT: return exr_attr_set_int(c, part, n, a->i);
	case EXR_ATTR_KEYCODE:
		return exr_attr_set_keycode(c, part, n, a->keycode);
	case EXR_ATTR_LINEORDER:
		return exr_attr_set_lineorder(c, part, n, (exr_lineorder_t)a->uc);
	case EXR_ATTR_M33F: return exr_attr_set_m33f(c, part, n, a->m33f);
	case EXR_ATTR_M33D: return exr_attr_set_m33d(c, part, n, a->m33d);
	case EXR_ATTR_M44F: return exr_attr_set_m44f(c, part, n, a->m44f);
	case EXR_ATTR_M44D: return exr_attr_set_m44d(c, part, n, a->m44d);
	case EXR_ATTR_PREVIEW:
		return exr_attr_set_preview(c, part, n, a->preview);
	case EXR_ATTR_RATIONAL:
		return exr_attr_set_rational(c, part, n, a->rational);
	case EXR_ATTR_STRING:
		return exr_attr_set_string(c, part, n, a->string->str);
	case EXR_ATTR_STRING_VECTOR: {
		const exr_attr_string_vector_t *sv = a->stringvector;
		const char **s = malloc((size_t)(sv->n_strings > 0 ? sv->n_strings
		                                                   : 1) *
		                        sizeof *s);
		if (!s)
			return EXR_ERR_OUT_OF_MEMORY;
		for (int32_t i = 0; i < sv->n_strings; i++)
			s[i] = sv->strings[i].str;
		exr_result_t rv = exr_attr_set_string_vector(c, part, n,
		                                             sv->n_strings, s);
		free(s);
		return rv;
	}
	case EXR_ATTR_TILEDESC:
		return exr_attr_set_tiledesc(c, part, n, a->tiledesc);
	case EXR_ATTR_TIMECODE:
		return exr_attr_set_timecode(c, part, n, a->timecode);
	case EXR_ATTR_V2I: return exr_attr_set_v2i(c, part, n, a->v2i);
	case EXR_ATTR_V2F: return exr_attr_set_v2f(c, part, n, a->v2f);
	case EXR_ATTR_V2D: return exr_attr_set_v2d(c, part, n, a->v2d);
	case EXR_ATTR_V3I: return exr_attr_set_v3i(c, part, n, a->v3i);
	case EXR_ATTR_V3F: return exr_attr_set_v3f(c, part, n, a->v3f);
	case EXR_ATTR_V3D: return exr_attr_set_v3d(c, part, n, a->v3d);
	case EXR_ATTR_OPAQUE:
		/* (size 0: see write_alloc, why this does not leak) */
		return exr_attr_set_user(c, part, n, a->type_name, a->opaque->size,
		                         a->opaque->packed_data);
	default:
		return EXR_ERR_INVALID_ATTR;
	}
}

/* ZIP and ZIPS chunks are deflated by libdeflate (sss_zip.c); the slot's
 * zip_slot travels in encoding_user_data. */
typedef struct zip_slot {
	struct libdeflate_compressor *deflate;
	uint8_t *scratch;
	size_t cap;
} zip_slot;

/* Measured on make compare's head render (49 channels, 320x240): level 4
 * writes 0.3 % more bytes than 6 in 5 % less time; on the benchmark's
 * noisy 1080p frame 10 % less time (the level is not stored in the
 * file; any reader inflates any level). */
#define ZIP_LEVEL 4

static void *write_alloc(size_t size);
static void write_free(void *p);

static exr_result_t zip_compress(exr_encode_pipeline_t *enc)
{
	zip_slot *z = enc->encoding_user_data;
	size_t n = enc->packed_bytes;
	if (!sss__exr_grow(&z->scratch, &z->cap, n))
		return EXR_ERR_OUT_OF_MEMORY;
	/* The pipeline frees this buffer with the context's free function,
	 * which is write_free. */
	size_t bound = libdeflate_zlib_compress_bound(z->deflate, n);
	if (!enc->compressed_buffer || enc->compressed_alloc_size < bound) {
		if (enc->compressed_buffer &&
		    enc->compressed_buffer != enc->packed_buffer)
			write_free(enc->compressed_buffer);
		enc->compressed_alloc_size = 0;
		if (!(enc->compressed_buffer = write_alloc(bound)))
			return EXR_ERR_OUT_OF_MEMORY;
		enc->compressed_alloc_size = bound;
	}
	enc->compressed_bytes = sss__zip_deflate(z->deflate, enc->packed_buffer,
	                                         n, z->scratch,
	                                         enc->compressed_buffer, bound);
	return EXR_ERR_SUCCESS;
}

/* Chunk encoding: a round of up to `slots` chunks is packed and
 * compressed in parallel (one pipeline per slot, kept across rounds),
 * then written in scanline order by the calling thread, since an
 * INCREASING_Y file takes its chunks in order. */
typedef struct write_job {
	exr_context_t ctxt;
	int part;
	const sss_exr *exr;
	const chan_ref *ref;         /* per channel of the (sorted) list */
	const exr_chunk_info_t *info; /* per chunk */
	exr_encode_pipeline_t *pipe; /* per slot */
	uint8_t *started;            /* per slot */
	exr_result_t *rv;            /* per slot, this round */
	zip_slot *zip;               /* per slot; NULL unless ZIP or ZIPS */
	int32_t first;               /* chunk of slot 0 in this round */
} write_job;

/* Float to uint as OpenEXRCore 3.1 converts when packing, but saturating
 * at the top: its own conversion tests f > (float)UINT32_MAX, which is
 * 2^32 itself, so 2^32 (what uint values from 0xFFFFFF80 up read as)
 * went through an out-of-range cast and came back as 0 (found by
 * tests/fuzz: a uint channel did not survive a round trip). */
static uint32_t float_to_uint_sat(float f)
{
	if (!(f > 0.0f)) /* negative, zero or NaN */
		return 0;
	if (f >= 4294967296.0f)
		return UINT32_MAX;
	return (uint32_t)f;
}

static void encode_slots(void *arg, int32_t s0, int32_t s1)
{
	write_job *job = arg;
	const sss_exr *exr = job->exr;
	for (int32_t s = s0; s < s1; s++) {
		const exr_chunk_info_t *ci = &job->info[job->first + s];
		exr_encode_pipeline_t *enc = &job->pipe[s];
		exr_result_t rv = job->started[s]
		                  ? exr_encoding_update(job->ctxt, job->part, ci, enc)
		                  : exr_encoding_initialize(job->ctxt, job->part, ci,
		                                            enc);
		size_t y0 = (size_t)(ci->start_y - exr->data_window.min.y);
		/* uint channels are converted here (float_to_uint_sat) into one
		 * staging block per chunk, a plane per uint channel. */
		size_t plane = (size_t)exr->width * (size_t)(ci->height > 0
		                                             ? ci->height : 0);
		int nuint = 0;
		for (int k = 0; rv == EXR_ERR_SUCCESS && k < enc->channel_count; k++)
			nuint += enc->channels[k].data_type == EXR_PIXEL_UINT;
		uint32_t *stage = NULL;
		if (nuint > 0 && plane > 0 &&
		    !(stage = malloc((size_t)nuint * plane * sizeof *stage)))
			rv = EXR_ERR_OUT_OF_MEMORY;
		for (int k = 0, u = 0; rv == EXR_ERR_SUCCESS &&
		                       k < enc->channel_count; k++) {
			exr_coding_channel_info_t *ch = &enc->channels[k];
			const chan_ref *r = &job->ref[k];
			size_t at = y0 * (size_t)exr->width * (size_t)r->count +
			            (size_t)r->k;
			if (ch->data_type == EXR_PIXEL_UINT && stage) {
				uint32_t *dst = stage + (size_t)u++ * plane;
				const uint32_t *raw = r->raw ? r->raw + y0 *
				                      (size_t)exr->width : NULL;
				/* The channel's own value while its float view still
				 * reads as it did: above 2^24 a float is not exact. */
				for (size_t i = 0; i < plane; i++) {
					float f = r->data[at + i * (size_t)r->count];
					dst[i] = raw && f == (float)raw[i]
					         ? raw[i] : float_to_uint_sat(f);
				}
				ch->encode_from_ptr = (const uint8_t *)dst;
				ch->user_pixel_stride = (int32_t)sizeof *dst;
				ch->user_line_stride = exr->width * (int32_t)sizeof *dst;
				ch->user_bytes_per_element = (int16_t)sizeof *dst;
				ch->user_data_type = EXR_PIXEL_UINT;
				continue;
			}
			ch->encode_from_ptr = (const uint8_t *)(r->data + at);
			ch->user_pixel_stride = r->count * (int32_t)sizeof(float);
			ch->user_line_stride = exr->width * r->count *
			                       (int32_t)sizeof(float);
			ch->user_bytes_per_element = (int16_t)sizeof(float);
			ch->user_data_type = EXR_PIXEL_FLOAT;
		}
		if (rv == EXR_ERR_SUCCESS && !job->started[s]) {
			rv = exr_encoding_choose_default_routines(job->ctxt, job->part,
			                                          enc);
			if (job->zip) {
				enc->compress_fn = zip_compress;
				enc->encoding_user_data = &job->zip[s];
			}
		}
		job->started[s] = 1;
		/* Pack and compress only; the caller writes, in order. */
		enc->yield_until_ready_fn = NULL;
		enc->write_fn = NULL;
		if (rv == EXR_ERR_SUCCESS)
			rv = exr_encoding_run(job->ctxt, job->part, enc);
		free(stage); /* packed by now */
		job->rv[s] = rv;
	}
}

typedef struct named_chan {
	const char *name;
	chan_ref ref;
} named_chan;

static int named_cmp(const void *a, const void *b)
{
	return strcmp(((const named_chan *)a)->name,
	              ((const named_chan *)b)->name);
}

static exr_result_t encode_chunks(exr_context_t c, int part,
                                  const sss_exr *exr,
                                  const sss_exr_options *o, int32_t *bad_y)
{
	int32_t threads = o->num_threads;
	const exr_attr_chlist_t *cl = NULL;
	int32_t lines = 0;
	exr_result_t rv = exr_get_channels(c, part, &cl);
	if (rv == EXR_ERR_SUCCESS)
		rv = exr_get_scanlines_per_chunk(c, part, &lines);
	if (rv != EXR_ERR_SUCCESS)
		return rv;
	if (lines < 1 || cl->num_channels < 1)
		return EXR_ERR_INVALID_ARGUMENT;
	int32_t chunks = (int32_t)(((int64_t)exr->height + lines - 1) / lines);
	int32_t slots = threads > 0 ? threads : sss__cpu_count();
	slots = slots < 1 ? 1 : slots > chunks ? chunks : slots;

	write_job job = {.ctxt = c, .part = part, .exr = exr};
	chan_ref *ref = calloc((size_t)cl->num_channels, sizeof *ref);
	exr_chunk_info_t *info = calloc((size_t)chunks, sizeof *info);
	job.pipe = calloc((size_t)slots, sizeof *job.pipe);
	job.started = calloc((size_t)slots, 1);
	job.rv = calloc((size_t)slots, sizeof *job.rv);
	if (!ref || !info || !job.pipe || !job.started || !job.rv)
		rv = EXR_ERR_OUT_OF_MEMORY;
	if (rv == EXR_ERR_SUCCESS && (o->compression == SSS_EXR_ZIP ||
	                              o->compression == SSS_EXR_ZIPS)) {
		job.zip = calloc((size_t)slots, sizeof *job.zip);
		for (int32_t s = 0; job.zip && s < slots; s++)
			if (!(job.zip[s].deflate =
			      libdeflate_alloc_compressor(ZIP_LEVEL)))
				rv = EXR_ERR_OUT_OF_MEMORY;
		if (!job.zip)
			rv = EXR_ERR_OUT_OF_MEMORY;
	}

	/* The library sorted the channel list; find each one's pass, by
	 * binary search over our channels sorted the same way (a scan per
	 * channel was quadratic in the channel count). */
	named_chan *by_name = rv == EXR_ERR_SUCCESS
	                      ? malloc((size_t)cl->num_channels * sizeof *by_name)
	                      : NULL;
	int32_t nb = 0;
	if (rv == EXR_ERR_SUCCESS && !by_name)
		rv = EXR_ERR_OUT_OF_MEMORY;
	for (int32_t j = 0; by_name && j < exr->pass_count; j++)
		for (int32_t k = 0; k < exr->passes[j].count &&
		                    nb < cl->num_channels; k++)
			by_name[nb++] = (named_chan){exr->passes[j].chan[k].name,
			                             {exr->passes[j].data,
			                              exr->passes[j].count, k,
			                              exr->passes[j].chan[k].raw}};
	if (by_name)
		qsort(by_name, (size_t)nb, sizeof *by_name, named_cmp);
	for (int i = 0; rv == EXR_ERR_SUCCESS && i < cl->num_channels; i++) {
		named_chan key = {cl->entries[i].name.str, {NULL, 0, 0, NULL}};
		const named_chan *hit = bsearch(&key, by_name, (size_t)nb,
		                                sizeof *by_name, named_cmp);
		if (!hit)
			rv = EXR_ERR_INVALID_ARGUMENT;
		else
			ref[i] = hit->ref;
	}
	free(by_name);
	for (int32_t i = 0; rv == EXR_ERR_SUCCESS && i < chunks; i++)
		rv = exr_write_scanline_chunk_info(
			c, part, exr->data_window.min.y + i * lines, &info[i]);
	job.ref = ref;
	job.info = info;

	for (int32_t first = 0; rv == EXR_ERR_SUCCESS && first < chunks;
	     first += slots) {
		int32_t n = chunks - first < slots ? chunks - first : slots;
		job.first = first;
		sss__parallel_rows(n, n, encode_slots, &job);
		for (int32_t s = 0; rv == EXR_ERR_SUCCESS && s < n; s++) {
			*bad_y = info[first + s].start_y;
			rv = job.rv[s];
			/* A chunk whose data is as long as its unpacked size is
			 * stored raw: readers take that length to mean "not
			 * compressed". OpenEXRCore 3.1's ZIP and RLE encoders fall
			 * back to the raw bytes only when the compressed ones are
			 * longer, so a chunk that compressed to exactly its own
			 * size was written compressed and read back as garbage
			 * (found by tests/fuzz). The packed bytes are written then. */
			const exr_encode_pipeline_t *e = &job.pipe[s];
			int raw = e->compressed_bytes >= e->packed_bytes;
			if (rv == EXR_ERR_SUCCESS)
				rv = exr_write_scanline_chunk(
					c, part, info[first + s].start_y,
					raw ? e->packed_buffer : e->compressed_buffer,
					raw ? e->packed_bytes : e->compressed_bytes);
		}
		if (rv == EXR_ERR_SUCCESS && o->progress_fn)
			o->progress_fn((double)(first + n) / chunks, o->progress_user);
	}
	for (int32_t s = 0; job.started && s < slots; s++)
		if (job.started[s])
			exr_encoding_destroy(c, &job.pipe[s]);
	for (int32_t s = 0; job.zip && s < slots; s++) {
		libdeflate_free_compressor(job.zip[s].deflate);
		free(job.zip[s].scratch);
	}
	free(job.zip);
	free(job.pipe);
	free(job.started);
	free(job.rv);
	free(info);
	free(ref);
	return rv;
}

/* Long (up to 255 byte) names are an EXR 2 feature, switched on only when
 * a channel or copied attribute needs one, for older readers' sake. */
static int needs_long_names(const sss_exr *exr,
                            const exr_attribute_t *const *attrs,
                            int32_t count)
{
	for (int32_t j = 0; j < exr->pass_count; j++)
		for (int32_t k = 0; k < exr->passes[j].count; k++)
			if (strlen(exr->passes[j].chan[k].name) > SHORT_NAME)
				return 1;
	for (int32_t i = 0; i < count; i++) {
		if (is_structural(attrs[i]->name))
			continue;
		if (attrs[i]->name_length > SHORT_NAME ||
		    attrs[i]->type_name_length > SHORT_NAME)
			return 1;
		/* A copied channel list's own names count too: without the flag
		 * the library refused a long one ("Text too long for file
		 * flags") and the whole write failed (found by tests/fuzz). */
		if (attrs[i]->type == EXR_ATTR_CHLIST)
			for (int k = 0; k < attrs[i]->chlist->num_channels; k++)
				if (attrs[i]->chlist->entries[k].name.length > SHORT_NAME)
					return 1;
	}
	return 0;
}

/* The write context's allocator. OpenEXRCore 3.1 copies an opaque
 * attribute of size 0 (a user attribute with no bytes, which a file may
 * hold and sss_exr_write copies) into alloc_fn(0) but records an
 * allocation size of 0, so it never frees that block: with malloc, a
 * leak per write (found by tests/fuzz). Size 0 gets one static block
 * instead, which free ignores. (Declaring the attribute without data is
 * no way out: the header then fails with "no pack provider".) */
static max_align_t zero_block;

static void *write_alloc(size_t size)
{
	return size ? malloc(size) : (void *)&zero_block;
}

static void write_free(void *p)
{
	if (p != (void *)&zero_block)
		free(p);
}

/* Writes the whole file to io (the temporary file). */
sss_result sss__exr_encode(const sss_exr *exr, const sss_exr_options *o,
                           const char *path, const char *tmp, xio *io,
                           char *errbuf, size_t errbuf_len)
{
	exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
	init.error_handler_fn = sss__exr_on_write_error;
	init.user_data = io;
	init.write_fn = sss__exr_io_write;
	init.alloc_fn = write_alloc;
	init.free_fn = write_free;
	exr_context_t c = NULL;
	const exr_attribute_t **attrs = NULL;
	int32_t nattrs = 0, bad_y = 0;
	int part = 0;
	char step[160] = "reading the source header";
	exr_result_t rv = sss__exr_source_attributes(exr, &attrs, &nattrs);

	if (rv == EXR_ERR_SUCCESS) {
		snprintf(step, sizeof step, "starting the file");
		rv = exr_start_write(&c, tmp, EXR_WRITE_FILE_DIRECTLY, &init);
	}
	if (rv == EXR_ERR_SUCCESS) {
		snprintf(step, sizeof step, "defining the header");
		rv = exr_add_part(c, NULL, EXR_STORAGE_SCANLINE, &part);
	}
	if (rv == EXR_ERR_SUCCESS && needs_long_names(exr, attrs, nattrs))
		rv = exr_set_longname_support(c, 1);
	if (rv == EXR_ERR_SUCCESS)
		rv = exr_initialize_required_attr_simple(
			c, part, exr->width, exr->height,
			(exr_compression_t)o->compression);
	/* The source's windows (a border render's data window is offset). */
	if (rv == EXR_ERR_SUCCESS)
		rv = exr_set_data_window(c, part, &exr->data_window);
	if (rv == EXR_ERR_SUCCESS)
		rv = exr_set_display_window(c, part, &exr->display_window);
	if (rv == EXR_ERR_SUCCESS)
		rv = exr_set_pixel_aspect_ratio(c, part, exr->pixel_aspect);
	if (rv == EXR_ERR_SUCCESS)
		rv = exr_set_screen_window_center(c, part, &exr->screen_center);
	if (rv == EXR_ERR_SUCCESS)
		rv = exr_set_screen_window_width(c, part, exr->screen_width);
	/* Original pixel types: half stays half, bit for bit. */
	for (int32_t j = 0; rv == EXR_ERR_SUCCESS && j < exr->pass_count; j++)
		for (int32_t k = 0; rv == EXR_ERR_SUCCESS &&
		                    k < exr->passes[j].count; k++) {
			const xchan *ch = &exr->passes[j].chan[k];
			snprintf(step, sizeof step, "adding channel '%s'", ch->name);
			rv = exr_add_channel(c, part, ch->name,
			                     (exr_pixel_type_t)ch->type,
			                     ch->p_linear ? EXR_PERCEPTUALLY_LINEAR
			                                  : EXR_PERCEPTUALLY_LOGARITHMIC,
			                     1, 1);
		}
	for (int32_t i = 0; rv == EXR_ERR_SUCCESS && i < nattrs; i++) {
		if (is_structural(attrs[i]->name))
			continue;
		snprintf(step, sizeof step, "copying header attribute '%s'",
		         attrs[i]->name);
		rv = copy_attribute(c, part, attrs[i]);
	}
	if (rv == EXR_ERR_SUCCESS) {
		snprintf(step, sizeof step, "writing the header");
		rv = exr_write_header(c);
	}
	if (rv == EXR_ERR_SUCCESS && exr->pass_count > 0) {
		rv = encode_chunks(c, part, exr, o, &bad_y);
		if (rv != EXR_ERR_SUCCESS)
			snprintf(step, sizeof step, "encoding the scanlines at y %d",
			         bad_y);
	}
	if (c) {
		/* Writes the chunk offset table; on failure the file is dropped
		 * by the caller anyway. */
		exr_result_t fr = exr_finish(&c);
		if (rv == EXR_ERR_SUCCESS && fr != EXR_ERR_SUCCESS) {
			snprintf(step, sizeof step, "finishing the file");
			rv = fr;
		}
	}
	free(attrs);
	if (rv != EXR_ERR_SUCCESS)
		return sss__exr_fail(errbuf, errbuf_len, path, step, rv, io);
	return SSS_OK;
}
