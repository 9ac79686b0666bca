/* test_exr.c - EXR reading and writing (sss_exr*.c). Input files are made
 * here with raw OpenEXRCore calls (planar buffers, the stored types), and
 * outputs are checked by decoding them the same way, so the library's
 * reader and writer are never their own oracle. */
#include "sss.h"
#include "test_util.h"

#include <openexr.h>

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

static char tmpdir[64];
static char errbuf[2048];

static void tpath(char *out, size_t len, const char *name)
{
	snprintf(out, len, "%s/%s", tmpdir, name);
}

/* ------------------------------------------------------------ helpers */

static uint32_t rng_state = 12345;

static uint32_t rnd(void)
{
	uint32_t x = rng_state;
	x ^= x << 13;
	x ^= x >> 17;
	x ^= x << 5;
	return rng_state = x;
}

/* Half to float written out independently of OpenEXR (and of libsss). */
static float half_to_float(uint16_t h)
{
	uint32_t s = (uint32_t)(h >> 15) << 31, e = (h >> 10) & 31u,
	         m = h & 1023u, bits;
	if (e == 0 && m == 0) {
		bits = s;
	} else if (e == 0) {
		float f = ldexpf((float)m, -24);
		memcpy(&bits, &f, 4);
		bits |= s;
	} else if (e == 31) {
		bits = s | 0x7f800000u | (m << 13);
	} else {
		bits = s | ((e + 112u) << 23) | (m << 13);
	}
	float f;
	memcpy(&f, &bits, 4);
	return f;
}

static uint32_t fbits(float f)
{
	uint32_t u;
	memcpy(&u, &f, 4);
	return u;
}

/* Same value, bit for bit (NaN payloads and signed zeros included). */
static int same_float(float a, float b)
{
	return fbits(a) == fbits(b);
}

static int file_contains(const char *hay, const char *needle)
{
	return strstr(hay, needle) != NULL;
}

static long file_size(const char *path)
{
	struct stat st;
	return stat(path, &st) ? -1 : (long)st.st_size;
}

static unsigned char *slurp(const char *path, long *len)
{
	FILE *f = fopen(path, "rb");
	if (!f)
		return NULL;
	fseek(f, 0, SEEK_END);
	*len = ftell(f);
	fseek(f, 0, SEEK_SET);
	unsigned char *b = malloc((size_t)*len + 1);
	if (b && fread(b, 1, (size_t)*len, f) != (size_t)*len) {
		free(b);
		b = NULL;
	}
	fclose(f);
	return b;
}

static void spit(const char *path, const unsigned char *b, long len)
{
	FILE *f = fopen(path, "wb");
	if (!f)
		abort();
	if (len > 0 && fwrite(b, 1, (size_t)len, f) != (size_t)len)
		abort();
	fclose(f);
}

/* Names in tmpdir (or a subdirectory) other than the expected ones. */
static int stray_files(const char *dir, const char *const *expected, int n)
{
	DIR *d = opendir(dir);
	int stray = 0;
	struct dirent *e;
	if (!d)
		return -1;
	while ((e = readdir(d))) {
		int ok = !strcmp(e->d_name, ".") || !strcmp(e->d_name, "..");
		for (int i = 0; i < n && !ok; i++)
			ok = !strcmp(e->d_name, expected[i]);
		if (!ok) {
			printf("  stray file: %s/%s\n", dir, e->d_name);
			stray++;
		}
	}
	closedir(d);
	return stray;
}

/* ------------------------------------------------- synthetic EXR files */

typedef struct tchan {
	const char *name;
	exr_pixel_type_t type;
	void *data; /* planar w x h: uint16 half bits, float or uint32 */
} tchan;

typedef struct tfile {
	int w, h, x0, y0;            /* data window size and origin */
	exr_compression_t comp;
	int tile;                    /* 0: scanline; else square tiles */
	int mip;                     /* tiled: write MIPMAP levels */
	int multipart;               /* 1: a part per pass, named as the pass
	                              * (Blender 5.0); 2: the same with channels
	                              * named by their component only */
	int nchan;
	tchan ch[64];
} tfile;

static int bpe(exr_pixel_type_t t)
{
	return t == EXR_PIXEL_HALF ? 2 : 4;
}

static void silent(exr_const_context_t c, exr_result_t code, const char *m)
{
	(void)c;
	(void)code;
	(void)m;
}

static const tchan *tfind(const tfile *f, const char *name)
{
	for (int i = 0; i < f->nchan; i++)
		if (!strcmp(f->ch[i].name, name))
			return &f->ch[i];
	return NULL;
}

/* The part (0 unless f->multipart) of channel i and, in *name, what the
 * channel is called inside it. */
static int tpart_of(const tfile *f, int i, char parts[][128], int *nparts,
                    const char **name)
{
	const char *full = f->ch[i].name, *dot = strrchr(full, '.');
	*name = full;
	if (!f->multipart)
		return 0;
	size_t n = dot ? (size_t)(dot - full) : 0;
	if (f->multipart == 2 && dot)
		*name = dot + 1;
	for (int p = 0; p < *nparts; p++)
		if (strlen(parts[p]) == n && !strncmp(parts[p], full, n))
			return p;
	snprintf(parts[*nparts], 128, "%.*s", (int)n, full);
	return (*nparts)++;
}

/* Writes f with raw OpenEXRCore calls; 0 on success. */
static int write_test_exr(const char *path, const tfile *f)
{
	exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
	init.error_handler_fn = silent;
	exr_context_t c;
	char parts[64][128];
	const char *inner[64];
	int part_of[64], nparts = f->multipart ? 0 : 1;
	for (int i = 0; i < f->nchan; i++)
		part_of[i] = tpart_of(f, i, parts, &nparts, &inner[i]);
	exr_result_t rv = exr_start_write(&c, path, EXR_WRITE_FILE_DIRECTLY,
	                                  &init);
	if (rv)
		return rv;
	for (int part = 0; !rv && part < nparts; part++) {
		int added;
		rv = exr_add_part(c, f->multipart ? parts[part] : NULL,
		                  f->tile ? EXR_STORAGE_TILED : EXR_STORAGE_SCANLINE,
		                  &added);
		if (!rv && added != part)
			rv = EXR_ERR_INVALID_ARGUMENT;
		if (!rv)
			rv = exr_initialize_required_attr_simple(c, part, f->w, f->h,
			                                         f->comp);
		exr_attr_box2i_t dw = {{{{f->x0, f->y0}}},
		                       {{{f->x0 + f->w - 1, f->y0 + f->h - 1}}}};
		exr_attr_box2i_t disp = {{{{0, 0}}}, {{{63, 47}}}};
		if (!rv)
			rv = exr_set_data_window(c, part, &dw);
		if (!rv)
			rv = exr_set_display_window(c, part, &disp);
		if (!rv)
			rv = exr_set_pixel_aspect_ratio(c, part, 1.25f);
		if (!rv && f->tile)
			rv = exr_set_tile_descriptor(c, part, (uint32_t)f->tile,
			                             (uint32_t)f->tile,
			                             f->mip ? EXR_TILE_MIPMAP_LEVELS
			                                    : EXR_TILE_ONE_LEVEL,
			                             EXR_TILE_ROUND_DOWN);
		/* Given order, not sorted: the library must sort the list. */
		for (int i = 0; !rv && i < f->nchan; i++)
			if (part_of[i] == part)
				rv = exr_add_channel(c, part, inner[i], f->ch[i].type,
				                     EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
		if (part > 0)
			continue;
		/* Blender-like metadata that must survive a round trip (5.0 puts
		 * it in the first part only). */
		exr_attr_m44f_t m = {{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 2, 3, 4,
		                      1}};
		if (!rv)
			rv = exr_attr_set_string(c, part, "BlenderMultiChannel",
			                         "Blender V2.55.1 and newer");
		if (!rv)
			rv = exr_attr_set_string(c, part, "RenderTime", "00:01.25");
		if (!rv)
			rv = exr_attr_set_m44f(c, part, "worldToCamera", &m);
		if (!rv)
			rv = exr_attr_set_int(c, part, "Frame", 42);
	}
	if (!rv)
		rv = exr_write_header(c);

	for (int part = 0; !rv && part < nparts; part++) {
		exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
		int started = 0;
		int levels = 1;
		if (f->tile && f->mip)
			rv = exr_get_tile_levels(c, part, &levels, NULL);
		for (int lv = 0; !rv && lv < levels; lv++) {
			int32_t lw = f->w, lh = f->h, step = f->tile;
			if (f->tile)
				rv = exr_get_level_sizes(c, part, lv, lv, &lw, &lh);
			else
				rv = exr_get_scanlines_per_chunk(c, part, &step);
			int nx = f->tile ? (lw + step - 1) / step : 1;
			int ny = (lh + step - 1) / step;
			for (int ty = 0; !rv && ty < ny; ty++)
				for (int tx = 0; !rv && tx < nx; tx++) {
					exr_chunk_info_t ci;
					if (f->tile)
						rv = exr_write_tile_chunk_info(c, part, tx, ty, lv,
						                               lv, &ci);
					else
						rv = exr_write_scanline_chunk_info(
							c, part, f->y0 + ty * step, &ci);
					if (!rv)
						rv = started
						     ? exr_encoding_update(c, part, &ci, &enc)
						     : exr_encoding_initialize(c, part, &ci, &enc);
					for (int k = 0; !rv && k < enc.channel_count; k++) {
						exr_coding_channel_info_t *ch = &enc.channels[k];
						const tchan *t = NULL;
						for (int i = 0; i < f->nchan && !t; i++)
							if (part_of[i] == part &&
							    !strcmp(inner[i], ch->channel_name))
								t = &f->ch[i];
						int b = bpe(t->type);
						/* level > 0 takes any pixels: only level 0 is
						 * read */
						size_t at = ((size_t)ty * step * f->w +
						             (size_t)(f->tile ? tx * step : 0)) * b;
						ch->encode_from_ptr = (const uint8_t *)t->data + at;
						ch->user_pixel_stride = b;
						ch->user_line_stride = f->w * b;
						ch->user_bytes_per_element = (int16_t)b;
						ch->user_data_type = (uint16_t)t->type;
					}
					if (!rv && !started)
						rv = exr_encoding_choose_default_routines(c, part,
						                                          &enc);
					started = 1;
					if (!rv)
						rv = exr_encoding_run(c, part, &enc);
				}
		}
		if (started)
			exr_encoding_destroy(c, &enc);
	}
	exr_result_t fr = exr_finish(&c);
	return rv ? rv : fr;
}

/* A scanline file decoded with raw OpenEXRCore into planar buffers of
 * each channel's stored type (no conversion at all). */
typedef struct rawimg {
	exr_attr_box2i_t dw, disp;
	int w, h, n;
	char name[64][128];
	exr_pixel_type_t type[64];
	void *data[64];
	exr_context_t c;
} rawimg;

static void raw_free(rawimg *r)
{
	for (int i = 0; i < r->n; i++)
		free(r->data[i]);
	if (r->c)
		exr_finish(&r->c);
	memset(r, 0, sizeof *r);
}

static int raw_read(const char *path, rawimg *r)
{
	exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
	init.error_handler_fn = silent;
	const exr_attr_chlist_t *cl;
	int32_t lines;
	memset(r, 0, sizeof *r);
	exr_result_t rv = exr_start_read(&r->c, path, &init);
	if (!rv)
		rv = exr_get_data_window(r->c, 0, &r->dw);
	if (!rv)
		rv = exr_get_display_window(r->c, 0, &r->disp);
	if (!rv)
		rv = exr_get_channels(r->c, 0, &cl);
	if (!rv)
		rv = exr_get_scanlines_per_chunk(r->c, 0, &lines);
	if (rv)
		return rv;
	r->w = r->dw.max.x - r->dw.min.x + 1;
	r->h = r->dw.max.y - r->dw.min.y + 1;
	r->n = cl->num_channels;
	for (int i = 0; i < r->n; i++) {
		snprintf(r->name[i], sizeof r->name[i], "%s",
		         cl->entries[i].name.str);
		r->type[i] = cl->entries[i].pixel_type;
		r->data[i] = calloc((size_t)r->w * r->h, 4);
	}
	exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
	int started = 0;
	for (int y = r->dw.min.y; !rv && y <= r->dw.max.y; y += lines) {
		exr_chunk_info_t ci;
		rv = exr_read_scanline_chunk_info(r->c, 0, y, &ci);
		if (!rv)
			rv = started ? exr_decoding_update(r->c, 0, &ci, &dec)
			             : exr_decoding_initialize(r->c, 0, &ci, &dec);
		for (int k = 0; !rv && k < dec.channel_count; k++) {
			exr_coding_channel_info_t *ch = &dec.channels[k];
			int b = ch->bytes_per_element;
			ch->decode_to_ptr = (uint8_t *)r->data[k] +
			                    (size_t)(ci.start_y - r->dw.min.y) * r->w * b;
			ch->user_pixel_stride = b;
			ch->user_line_stride = r->w * b;
			ch->user_bytes_per_element = (int16_t)b;
			ch->user_data_type = ch->data_type;
		}
		if (!rv && !started)
			rv = exr_decoding_choose_default_routines(r->c, 0, &dec);
		started = 1;
		if (!rv)
			rv = exr_decoding_run(r->c, 0, &dec);
	}
	if (started)
		exr_decoding_destroy(r->c, &dec);
	return rv;
}

static int raw_index(const rawimg *r, const char *name)
{
	for (int i = 0; i < r->n; i++)
		if (!strcmp(r->name[i], name))
			return i;
	return -1;
}

/* Stored value i of raw channel k as float. */
static float raw_value(const rawimg *r, int k, size_t i)
{
	if (r->type[k] == EXR_PIXEL_HALF)
		return half_to_float(((const uint16_t *)r->data[k])[i]);
	if (r->type[k] == EXR_PIXEL_UINT)
		return (float)((const uint32_t *)r->data[k])[i];
	return ((const float *)r->data[k])[i];
}

/* ----------------------------------------------- the Blender-like file */

static const struct {
	const char *name;
	exr_pixel_type_t type;
} blender_channels[] = {
	{"ViewLayer.Combined.A", EXR_PIXEL_HALF},
	{"ViewLayer.Combined.B", EXR_PIXEL_HALF},
	{"ViewLayer.Combined.G", EXR_PIXEL_HALF},
	{"ViewLayer.Combined.R", EXR_PIXEL_HALF},
	{"ViewLayer.DiffDir.R", EXR_PIXEL_FLOAT},
	{"ViewLayer.DiffDir.G", EXR_PIXEL_FLOAT},
	{"ViewLayer.DiffDir.B", EXR_PIXEL_FLOAT},
	{"ViewLayer.DiffInd.B", EXR_PIXEL_HALF},
	{"ViewLayer.DiffInd.G", EXR_PIXEL_HALF},
	{"ViewLayer.DiffInd.R", EXR_PIXEL_HALF},
	{"ViewLayer.DiffCol.R", EXR_PIXEL_HALF},
	{"ViewLayer.DiffCol.G", EXR_PIXEL_HALF},
	{"ViewLayer.DiffCol.B", EXR_PIXEL_HALF},
	{"ViewLayer.GlossDir.R", EXR_PIXEL_HALF},
	{"ViewLayer.GlossDir.G", EXR_PIXEL_HALF},
	{"ViewLayer.GlossDir.B", EXR_PIXEL_HALF},
	{"ViewLayer.Depth.Z", EXR_PIXEL_FLOAT},
	{"ViewLayer.IndexMA.X", EXR_PIXEL_FLOAT},
	{"ViewLayer.Position.Z", EXR_PIXEL_FLOAT},
	{"ViewLayer.Position.Y", EXR_PIXEL_FLOAT},
	{"ViewLayer.Position.X", EXR_PIXEL_FLOAT},
	{"ViewLayer.Vector.W", EXR_PIXEL_HALF},
	{"ViewLayer.Vector.Z", EXR_PIXEL_HALF},
	{"ViewLayer.Vector.Y", EXR_PIXEL_HALF},
	{"ViewLayer.Vector.X", EXR_PIXEL_HALF},
	{"ViewLayer.UV.U", EXR_PIXEL_HALF},
	{"ViewLayer.UV.V", EXR_PIXEL_HALF},
	{"ViewLayer.UV.A", EXR_PIXEL_HALF},
	{"ViewLayer.Denoising Normal.X", EXR_PIXEL_HALF},
	{"ViewLayer.Crypto.r", EXR_PIXEL_FLOAT},
	{"ViewLayer.Crypto.g", EXR_PIXEL_FLOAT},
	{"ViewLayer.Crypto.b", EXR_PIXEL_FLOAT},
	{"ViewLayer.Crypto.a", EXR_PIXEL_FLOAT},
	{"ViewLayer.Deep.Pass.R", EXR_PIXEL_HALF},
	{"ViewLayer.ObjectID.X", EXR_PIXEL_UINT},
	{"Wall.DiffDir.R", EXR_PIXEL_FLOAT},
	{"Wall.DiffDir.G", EXR_PIXEL_FLOAT},
	{"Wall.DiffDir.B", EXR_PIXEL_FLOAT},
	{"Wall.DiffCol.R", EXR_PIXEL_HALF},
	{"Wall.DiffCol.G", EXR_PIXEL_HALF},
	{"Wall.DiffCol.B", EXR_PIXEL_HALF},
	{"Wall.Depth.Z", EXR_PIXEL_FLOAT},
	{"Wall.IndexMA.X", EXR_PIXEL_FLOAT},
	{"Wall.Combined.R", EXR_PIXEL_HALF},
	{"Wall.Combined.G", EXR_PIXEL_HALF},
	{"Wall.Combined.B", EXR_PIXEL_HALF},
};

/* The passes sss_exr_read must form, in file (sorted channel) order. */
static const struct {
	const char *layer, *pass, *components;
} blender_passes[] = {
	{"ViewLayer", "Combined", "RGBA"},
	{"ViewLayer", "Crypto", "abgr"},
	{"ViewLayer.Deep", "Pass", "R"},
	{"ViewLayer", "Denoising Normal", "X"},
	{"ViewLayer", "Depth", "Z"},
	{"ViewLayer", "DiffCol", "RGB"},
	{"ViewLayer", "DiffDir", "RGB"},
	{"ViewLayer", "DiffInd", "RGB"},
	{"ViewLayer", "GlossDir", "RGB"},
	{"ViewLayer", "IndexMA", "X"},
	{"ViewLayer", "ObjectID", "X"},
	{"ViewLayer", "Position", "XYZ"},
	{"ViewLayer", "UV", "AUV"},
	{"ViewLayer", "Vector", "XYZW"},
	{"Wall", "Combined", "RGB"},
	{"Wall", "Depth", "Z"},
	{"Wall", "DiffCol", "RGB"},
	{"Wall", "DiffDir", "RGB"},
	{"Wall", "IndexMA", "X"},
};

#define NPASSES ((int)(sizeof blender_passes / sizeof *blender_passes))

/* Half bit patterns that must survive exactly: signed zeros, smallest
 * and largest subnormals, the largest finite, infinities, NaNs. */
static const uint16_t half_specials[] = {0x0000, 0x8000, 0x0001, 0x03ff,
                                         0x0400, 0x7bff, 0xfbff, 0x7c00,
                                         0xfc00, 0x3c00, 0x7e00, 0xfe00};

static void fill_channel(tchan *t, int w, int h)
{
	size_t n = (size_t)w * h;
	if (t->type == EXR_PIXEL_HALF) {
		uint16_t *d = malloc(n * 2);
		for (size_t i = 0; i < n; i++) {
			uint16_t v = (uint16_t)(rnd() & 0x7bff); /* finite, +/- */
			if (rnd() & 1)
				v |= 0x8000;
			if (i % 97 == 0)
				v = half_specials[(i / 97) % (sizeof half_specials / 2)];
			d[i] = v;
		}
		t->data = d;
	} else if (t->type == EXR_PIXEL_FLOAT) {
		float *d = malloc(n * 4);
		for (size_t i = 0; i < n; i++) {
			d[i] = ((float)(rnd() >> 8) / 16777216.0f - 0.3f) * 100.0f;
			if (i % 89 == 0)
				d[i] = -0.0f;
			if (i % 89 == 1)
				d[i] = 1e-42f; /* subnormal */
			if (i % 89 == 2)
				d[i] = INFINITY;
		}
		t->data = d;
	} else {
		uint32_t *d = malloc(n * 4);
		for (size_t i = 0; i < n; i++)
			d[i] = rnd() & 0xffffff; /* exact in float */
		t->data = d;
	}
}

/* f: n channels named names, all of one pixel type, w x h, codec comp,
 * each filled by fill_channel. */
static void tfile_named(tfile *f, const char *const *names, int n, int w,
                        int h, exr_compression_t comp, exr_pixel_type_t type)
{
	memset(f, 0, sizeof *f);
	f->w = w;
	f->h = h;
	f->comp = comp;
	f->nchan = n;
	for (int i = 0; i < n; i++) {
		f->ch[i].name = names[i];
		f->ch[i].type = type;
		fill_channel(&f->ch[i], w, h);
	}
}

static void make_blender(tfile *f, int w, int h, exr_compression_t comp)
{
	memset(f, 0, sizeof *f);
	f->w = w;
	f->h = h;
	f->x0 = -3;
	f->y0 = 5;
	f->comp = comp;
	f->nchan = (int)(sizeof blender_channels / sizeof *blender_channels);
	for (int i = 0; i < f->nchan; i++) {
		f->ch[i].name = blender_channels[i].name;
		f->ch[i].type = blender_channels[i].type;
		fill_channel(&f->ch[i], w, h);
	}
	/* Depth and IndexMA plausible (not that reading cares). */
	float *idx = (float *)tfind(f, "ViewLayer.IndexMA.X")->data;
	for (int i = 0; i < w * h; i++)
		idx[i] = (float)(i % 3);
}

static void tfile_free(tfile *f)
{
	for (int i = 0; i < f->nchan; i++)
		free(f->ch[i].data);
	f->nchan = 0;
}

static float tvalue(const tchan *t, size_t i)
{
	if (t->type == EXR_PIXEL_HALF)
		return half_to_float(((const uint16_t *)t->data)[i]);
	if (t->type == EXR_PIXEL_UINT)
		return (float)((const uint32_t *)t->data)[i];
	return ((const float *)t->data)[i];
}

/* Every channel of f, read through libsss, equals the expected value:
 * the original (lossless) or, if raw is given, what raw OpenEXRCore
 * decodes from the same file (lossy codecs). Returns mismatches. */
static long check_values(const sss_exr *exr, const tfile *f,
                         const rawimg *raw)
{
	long bad = 0;
	for (int c = 0; c < f->nchan; c++) {
		const char *name = f->ch[c].name;
		const char *last = strrchr(name, '.'), *first = last;
		while (first && first > name && first[-1] != '.')
			first--; /* from the end, as Blender splits */
		first = first && first > name ? first - 1 : last;
		char layer[64] = "", pass[64] = "";
		if (first != last) {
			snprintf(layer, sizeof layer, "%.*s", (int)(first - name), name);
			snprintf(pass, sizeof pass, "%.*s", (int)(last - first - 1),
			         first + 1);
		} else if (last) {
			snprintf(pass, sizeof pass, "%.*s", (int)(last - name), name);
		}
		const char *comp = last ? last + 1 : name;
		int found = 0;
		for (int32_t i = 0; i < sss_exr_pass_count(exr) && !found; i++) {
			const char *l, *p, *cs;
			sss_image v;
			sss_exr_pass(exr, i, &l, &p, &cs, &v);
			if (strcmp(l, layer) || strcmp(p, pass))
				continue;
			int k = (int)(strchr(cs, comp[0]) - cs);
			int rk = raw ? raw_index(raw, name) : -1;
			found = 1;
			for (size_t px = 0; px < (size_t)f->w * f->h; px++) {
				float want = raw && rk >= 0 ? raw_value(raw, rk, px)
				                            : tvalue(&f->ch[c], px);
				float got = v.data[px * v.channels + k];
				if (!same_float(want, got) && bad++ < 5)
					printf("  %s pixel %zu: got %a want %a\n", name, px,
					       (double)got, (double)want);
			}
		}
		if (!found && bad++ < 5)
			printf("  channel %s: no pass\n", name);
	}
	return bad;
}

/* ------------------------------------------------------------- tests */

static void test_options(void)
{
	sss_exr_options o;
	sss_exr_options_default(&o);
	CHECK("exr.opt.defaults", o.struct_size == sizeof o &&
	      o.max_width == 32768 && o.max_height == 32768 &&
	      o.max_pixels == ((int64_t)1 << 28) &&
	      o.compression == SSS_EXR_ZIP && o.num_threads == 0,
	      "defaults wrong");
	sss_exr_options_default(NULL); /* no crash */

	sss_exr *exr = (sss_exr *)1;
	char p[256];
	tpath(p, sizeof p, "none.exr");
	o.struct_size = 3;
	CHECK_STATUS("exr.opt.struct_size", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_read(p, &o, &exr, errbuf, sizeof errbuf));
	CHECK("exr.opt.struct_size.out", exr == NULL, "out not cleared");
	sss_exr_options_default(&o);
	o.compression = 42;
	CHECK_STATUS("exr.opt.compression", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_read(p, &o, &exr, errbuf, sizeof errbuf));
	sss_exr_options_default(&o);
	o.num_threads = -1;
	CHECK_STATUS("exr.opt.threads", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_read(p, &o, &exr, errbuf, sizeof errbuf));
	sss_exr_options_default(&o);
	o.max_channels = 0;
	CHECK_STATUS("exr.opt.max_channels", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_read(p, &o, &exr, errbuf, sizeof errbuf));
	/* ABI 8's struct, without max_channels and max_bytes: still read,
	 * with their defaults (a missing file is then the error). */
	sss_exr_options_default(&o);
	o.struct_size = (uint32_t)offsetof(sss_exr_options, max_channels);
	o.max_channels = 0; /* past ABI 8's end: not read */
	CHECK_STATUS("exr.opt.abi8", SSS_ERR_IO,
	             sss_exr_read(p, &o, &exr, errbuf, sizeof errbuf));
	CHECK_STATUS("exr.arg.path", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_read(NULL, NULL, &exr, errbuf, sizeof errbuf));
	CHECK_STATUS("exr.arg.out", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_read(p, NULL, NULL, errbuf, sizeof errbuf));
	CHECK_STATUS("exr.arg.write", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_write(NULL, p, NULL, errbuf, sizeof errbuf));
	CHECK_STATUS("exr.arg.pass", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_pass(NULL, 0, NULL, NULL, NULL, NULL));
	CHECK_STATUS("exr.arg.find", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_find(NULL, "", "", NULL));
	CHECK("exr.arg.size", sss_exr_width(NULL) == 0 &&
	      sss_exr_height(NULL) == 0 && sss_exr_pass_count(NULL) == 0,
	      "NULL sizes");
	sss_exr_free(NULL);
}

/* (1) A Blender-style file: grouping, values, passes, round trip. */
static void test_round_trip(void)
{
	char in[256], out[256];
	tfile f;
	make_blender(&f, 37, 41, EXR_COMPRESSION_ZIP);
	tpath(in, sizeof in, "blender.exr");
	tpath(out, sizeof out, "blender_sss.exr");
	CHECK("exr.rt.write_input", write_test_exr(in, &f) == 0, "raw write");

	sss_exr *exr = NULL;
	CHECK_STATUS("exr.rt.read", SSS_OK,
	             sss_exr_read(in, NULL, &exr, errbuf, sizeof errbuf));
	if (!exr) {
		printf("  %s\n", errbuf);
		tfile_free(&f);
		return;
	}
	CHECK("exr.rt.size", sss_exr_width(exr) == 37 &&
	      sss_exr_height(exr) == 41, "%dx%d", sss_exr_width(exr),
	      sss_exr_height(exr));
	CHECK("exr.rt.pass_count", sss_exr_pass_count(exr) == NPASSES,
	      "%d passes, expected %d", sss_exr_pass_count(exr), NPASSES);
	int order_ok = 1;
	for (int i = 0; i < NPASSES && i < sss_exr_pass_count(exr); i++) {
		const char *l, *p, *cs;
		sss_image v;
		sss_exr_pass(exr, i, &l, &p, &cs, &v);
		if (strcmp(l, blender_passes[i].layer) ||
		    strcmp(p, blender_passes[i].pass) ||
		    strcmp(cs, blender_passes[i].components) ||
		    v.channels != (int)strlen(cs) || v.width != 37 ||
		    v.height != 41 || v.row_stride != 0) {
			printf("  pass %d: '%s' '%s' '%s' (expected '%s' '%s' '%s')\n",
			       i, l, p, cs, blender_passes[i].layer,
			       blender_passes[i].pass, blender_passes[i].components);
			order_ok = 0;
		}
	}
	CHECK("exr.rt.grouping", order_ok, "grouping or canonical order");
	CHECK_STATUS("exr.rt.pass_range", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_pass(exr, NPASSES, NULL, NULL, NULL, NULL));
	long bad = check_values(exr, &f, NULL);
	CHECK("exr.rt.values", bad == 0, "%ld values differ", bad);

	/* Render passes of the first layer with DiffDir: ViewLayer. */
	sss_passes ps;
	const char *used = NULL;
	sss_image dd, dc, z, ix, comb, pos, gd;
	CHECK_STATUS("exr.rt.render", SSS_OK,
	             sss_exr_render_passes(exr, NULL, &ps, &used, errbuf,
	                                   sizeof errbuf));
	sss_exr_find(exr, "ViewLayer", "DiffDir", &dd);
	sss_exr_find(exr, "ViewLayer", "DiffCol", &dc);
	sss_exr_find(exr, "ViewLayer", "Depth", &z);
	sss_exr_find(exr, "ViewLayer", "IndexMA", &ix);
	sss_exr_find(exr, "ViewLayer", "Combined", &comb);
	sss_exr_find(exr, "ViewLayer", "Position", &pos);
	sss_exr_find(exr, "ViewLayer", "GlossDir", &gd);
	CHECK("exr.rt.render.layer", used && !strcmp(used, "ViewLayer"),
	      "layer %s", used ? used : "(null)");
	CHECK("exr.rt.render.views",
	      ps.diff_dir.data == dd.data && ps.diff_dir.channels == 3 &&
	      ps.diff_col.data == dc.data && ps.depth.data == z.data &&
	      ps.depth.channels == 1 && ps.index_ma.data == ix.data &&
	      ps.combined.data == comb.data && ps.combined.channels == 4 &&
	      ps.position.data == pos.data && ps.position.channels == 3 &&
	      ps.gloss_dir.data == gd.data && ps.diff_ind.data != NULL &&
	      ps.gloss_ind.data == NULL && ps.emit.data == NULL &&
	      ps.diff_dir.width == 37 && ps.diff_dir.height == 41,
	      "views wrong");
	CHECK("exr.rt.render.value", ps.index_ma.data[5] == 2.0f &&
	      ps.depth.data[7] == ((float *)tfind(&f, "ViewLayer.Depth.Z")
	                           ->data)[7], "values");

	/* The second layer by name; its Combined is RGB only: absent. */
	CHECK_STATUS("exr.rt.render.wall", SSS_OK,
	             sss_exr_render_passes(exr, "Wall", &ps, &used, errbuf,
	                                   sizeof errbuf));
	sss_exr_find(exr, "Wall", "DiffDir", &dd);
	CHECK("exr.rt.render.wall.views", used && !strcmp(used, "Wall") &&
	      ps.diff_dir.data == dd.data && ps.combined.data == NULL &&
	      ps.diff_ind.data == NULL && ps.position.data == NULL,
	      "Wall views");
	CHECK_STATUS("exr.rt.render.nolayer", SSS_ERR_MISSING_PASS,
	             sss_exr_render_passes(exr, "Nope", &ps, &used, errbuf,
	                                   sizeof errbuf));
	CHECK("exr.rt.render.nolayer.msg", file_contains(errbuf, "Nope") &&
	      file_contains(errbuf, "ViewLayer") &&
	      file_contains(errbuf, "Wall") && ps.diff_dir.data == NULL &&
	      used == NULL, "%s", errbuf);

	/* Add SSS.Combined (given ABGR: stored canonically as RGBA). */
	size_t n = (size_t)37 * 41;
	float *sss = malloc(n * 4 * sizeof *sss);
	for (size_t i = 0; i < n * 4; i++)
		sss[i] = (float)i * 0.25f - 100.0f;
	CHECK_STATUS("exr.rt.add", SSS_OK,
	             sss_exr_add_pass(exr, "SSS", "Combined", "ABGR", sss, errbuf,
	                              sizeof errbuf));
	const char *cs = NULL;
	sss_image v = {0};
	int32_t np = sss_exr_pass_count(exr);
	sss_exr_pass(exr, np - 1, NULL, NULL, &cs, &v);
	int perm = np == NPASSES + 1 && cs && !strcmp(cs, "RGBA") &&
	           v.channels == 4;
	for (size_t i = 0; perm && i < n; i++)
		perm = v.data[4 * i + 0] == sss[4 * i + 3] &&
		       v.data[4 * i + 1] == sss[4 * i + 2] &&
		       v.data[4 * i + 2] == sss[4 * i + 1] &&
		       v.data[4 * i + 3] == sss[4 * i + 0];
	CHECK("exr.rt.add.canonical", perm, "ABGR not stored as RGBA");
	/* Replacing: same count, new data (now RGBA = sss as given). */
	CHECK_STATUS("exr.rt.replace", SSS_OK,
	             sss_exr_add_pass(exr, "SSS", "Combined", "RGBA", sss, errbuf,
	                              sizeof errbuf));
	sss_exr_find(exr, "SSS", "Combined", &v);
	CHECK("exr.rt.replace.data", sss_exr_pass_count(exr) == NPASSES + 1 &&
	      v.data[0] == sss[0] && v.data[4 * n - 1] == sss[4 * n - 1],
	      "replace");
	CHECK_STATUS("exr.add.dot", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_add_pass(exr, "SSS", "Com.bined", "RGB", sss, errbuf,
	                              sizeof errbuf));
	CHECK_STATUS("exr.add.dotpass", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_add_pass(exr, "", "a.b", "RGB", sss, errbuf,
	                              sizeof errbuf));
	CHECK_STATUS("exr.add.repeat", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_add_pass(exr, "SSS", "X", "RGR", sss, errbuf,
	                              sizeof errbuf));
	CHECK_STATUS("exr.add.null", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_add_pass(exr, "SSS", "X", "RGB", NULL, errbuf,
	                              sizeof errbuf));
	CHECK_STATUS("exr.add.empty", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_add_pass(exr, "SSS", "X", "", sss, errbuf,
	                              sizeof errbuf));
	CHECK("exr.add.unchanged", sss_exr_pass_count(exr) == NPASSES + 1,
	      "failed adds changed the image");

	/* Write, then decode the output with raw OpenEXRCore. */
	CHECK_STATUS("exr.rt.write", SSS_OK,
	             sss_exr_write(exr, out, NULL, errbuf, sizeof errbuf));
	rawimg r;
	int rrv = raw_read(out, &r);
	CHECK("exr.rt.raw", rrv == 0, "raw read of output: %d", rrv);
	if (!rrv) {
		long diff = 0, type = 0, missing = 0;
		for (int c = 0; c < f.nchan; c++) {
			int k = raw_index(&r, f.ch[c].name);
			if (k < 0) {
				missing++;
				continue;
			}
			if (r.type[k] != f.ch[c].type) {
				type++;
				continue;
			}
			size_t b = (size_t)bpe(f.ch[c].type);
			if (memcmp(r.data[k], f.ch[c].data, n * b))
				diff++;
		}
		CHECK("exr.rt.bits", diff == 0 && type == 0 && missing == 0 &&
		      r.n == f.nchan + 4, "%ld differ, %ld types, %ld missing, "
		      "%d channels", diff, type, missing, r.n);
		static const char comps[] = "RGBA";
		long sbad = 0;
		for (int k = 0; k < 4; k++) {
			char name[32];
			snprintf(name, sizeof name, "SSS.Combined.%c", comps[k]);
			int rk = raw_index(&r, name);
			if (rk < 0 || r.type[rk] != EXR_PIXEL_FLOAT) {
				sbad++;
				continue;
			}
			for (size_t i = 0; i < n; i++)
				if (((float *)r.data[rk])[i] != sss[4 * i + k])
					sbad++;
		}
		CHECK("exr.rt.new_pass", sbad == 0, "%ld SSS values wrong", sbad);
		int sorted = 1;
		for (int k = 1; k < r.n; k++)
			sorted = sorted && strcmp(r.name[k - 1], r.name[k]) < 0;
		CHECK("exr.rt.sorted", sorted, "channel list not sorted");
		CHECK("exr.rt.windows", r.dw.min.x == -3 && r.dw.min.y == 5 &&
		      r.dw.max.x == 33 && r.dw.max.y == 45 && r.disp.max.x == 63 &&
		      r.disp.max.y == 47, "windows");
		const char *s = NULL;
		exr_attr_m44f_t m = {{0}};
		int32_t frame = 0;
		float par = 0;
		exr_compression_t comp = EXR_COMPRESSION_LAST_TYPE;
		int attrs = exr_attr_get_string(r.c, 0, "BlenderMultiChannel", NULL,
		                                &s) == 0 &&
		            s && !strcmp(s, "Blender V2.55.1 and newer") &&
		            exr_attr_get_m44f(r.c, 0, "worldToCamera", &m) == 0 &&
		            m.m[13] == 3.0f &&
		            exr_attr_get_int(r.c, 0, "Frame", &frame) == 0 &&
		            frame == 42 &&
		            exr_get_pixel_aspect_ratio(r.c, 0, &par) == 0 &&
		            par == 1.25f &&
		            exr_get_compression(r.c, 0, &comp) == 0 &&
		            comp == EXR_COMPRESSION_ZIP;
		CHECK("exr.rt.attributes", attrs, "header attributes lost");
	}
	raw_free(&r);

	/* And libsss reads its own output back the same way. */
	sss_exr *back = NULL;
	CHECK_STATUS("exr.rt.reread", SSS_OK,
	             sss_exr_read(out, NULL, &back, errbuf, sizeof errbuf));
	if (back) {
		bad = check_values(back, &f, NULL);
		CHECK("exr.rt.reread.values", bad == 0 &&
		      sss_exr_pass_count(back) == NPASSES + 1, "%ld differ", bad);
		CHECK_STATUS("exr.rt.reread.find", SSS_OK,
		             sss_exr_find(back, "SSS", "Combined", &v));
		CHECK("exr.rt.reread.sss", v.channels == 4 && v.data[1] == sss[1],
		      "SSS pass");
		sss_exr_free(back);
	}

	/* The file does not depend on the number of encoding threads. */
	{
		char o1[300], o4[300];
		tpath(o1, sizeof o1, "t1.exr");
		tpath(o4, sizeof o4, "t4.exr");
		sss_exr_options o;
		sss_exr_options_default(&o);
		o.num_threads = 1;
		sss_result w1 = sss_exr_write(exr, o1, &o, errbuf, sizeof errbuf);
		o.num_threads = 4;
		sss_result w4 = sss_exr_write(exr, o4, &o, errbuf, sizeof errbuf);
		long l1 = 0, l4 = 0;
		unsigned char *b1 = slurp(o1, &l1), *b4 = slurp(o4, &l4);
		CHECK("exr.rt.threads.identical", w1 == SSS_OK && w4 == SSS_OK &&
		      b1 && b4 && l1 == l4 && !memcmp(b1, b4, (size_t)l1),
		      "1 and 4 threads wrote different files");
		free(b1);
		free(b4);
		unlink(o1);
		unlink(o4);
	}

	/* Every output compression reads back; lossless ones exactly. */
	static const int comps_out[] = {SSS_EXR_NONE, SSS_EXR_RLE, SSS_EXR_ZIPS,
	                                SSS_EXR_PIZ, SSS_EXR_PXR24, SSS_EXR_B44,
	                                SSS_EXR_B44A, SSS_EXR_DWAA,
	                                SSS_EXR_DWAB};
	for (size_t i = 0; i < sizeof comps_out / sizeof *comps_out; i++) {
		sss_exr_options o;
		sss_exr_options_default(&o);
		o.compression = comps_out[i];
		char id[64];
		sss_result wr = sss_exr_write(exr, out, &o, errbuf, sizeof errbuf);
		snprintf(id, sizeof id, "exr.rt.write.comp%d", comps_out[i]);
		if (comps_out[i] >= SSS_EXR_DWAA && wr == SSS_ERR_UNSUPPORTED) {
			/* OpenEXRCore 3.1 cannot encode DWA: said so, cleanly */
			CHECK(id, file_contains(errbuf, out) &&
			      file_contains(errbuf, "OpenEXRCore"), "%s", errbuf);
			continue;
		}
		CHECK(id, wr == SSS_OK, "%s", errbuf);
		back = NULL;
		wr = sss_exr_read(out, NULL, &back, errbuf, sizeof errbuf);
		snprintf(id, sizeof id, "exr.rt.reread.comp%d", comps_out[i]);
		CHECK(id, wr == SSS_OK && sss_exr_pass_count(back) == NPASSES + 1,
		      "%s", errbuf);
		int lossless = comps_out[i] <= SSS_EXR_PIZ;
		if (back && lossless) {
			bad = check_values(back, &f, NULL);
			snprintf(id, sizeof id, "exr.rt.lossless.comp%d", comps_out[i]);
			CHECK(id, bad == 0, "%ld differ", bad);
		}
		sss_exr_free(back);
	}
	free(sss);
	sss_exr_free(exr);
	tfile_free(&f);
}

/* Input compressions: libsss agrees with raw OpenEXRCore on every value,
 * and lossless ones equal the originals. Also thread counts. */
static void test_compressions(void)
{
	/* DWAA and DWAB: OpenEXRCore 3.1 cannot write them; see test_dwa. */
	static const exr_compression_t comps[] = {
		EXR_COMPRESSION_NONE, EXR_COMPRESSION_RLE, EXR_COMPRESSION_ZIPS,
		EXR_COMPRESSION_ZIP, EXR_COMPRESSION_PIZ, EXR_COMPRESSION_PXR24,
		EXR_COMPRESSION_B44, EXR_COMPRESSION_B44A};
	for (size_t i = 0; i < sizeof comps / sizeof *comps; i++) {
		char in[256], id[64];
		tfile f;
		make_blender(&f, 53, 70, comps[i]);
		snprintf(in, sizeof in, "%s/comp%d.exr", tmpdir, (int)comps[i]);
		int wr = write_test_exr(in, &f);
		snprintf(id, sizeof id, "exr.comp%d.write", (int)comps[i]);
		CHECK(id, wr == 0, "raw write %d", wr);
		rawimg r;
		int rr = raw_read(in, &r);
		for (int threads = 0; threads <= 1; threads++) {
			sss_exr_options o;
			sss_exr_options_default(&o);
			o.num_threads = threads;
			sss_exr *exr = NULL;
			snprintf(id, sizeof id, "exr.comp%d.read.t%d", (int)comps[i],
			         threads);
			CHECK_STATUS(id, SSS_OK,
			             sss_exr_read(in, &o, &exr, errbuf, sizeof errbuf));
			if (!exr) {
				printf("  %s\n", errbuf);
				continue;
			}
			long bad = rr == 0 ? check_values(exr, &f, &r) : -1;
			snprintf(id, sizeof id, "exr.comp%d.vs_raw.t%d", (int)comps[i],
			         threads);
			CHECK(id, bad == 0, "%ld differ from raw OpenEXRCore", bad);
			if (comps[i] <= EXR_COMPRESSION_PIZ) {
				bad = check_values(exr, &f, NULL);
				snprintf(id, sizeof id, "exr.comp%d.exact.t%d",
				         (int)comps[i], threads);
				CHECK(id, bad == 0, "%ld differ from the originals", bad);
			}
			sss_exr_free(exr);
		}
		raw_free(&r);
		tfile_free(&f);
	}
}

/* File Output node naming (no layer), plain RGB, longer components. */
/* Blender 5.0 names its passes in full: the same render passes are found
 * under "Diffuse Direct", "Material Index" and so on, and the short names
 * still win where both are present. */
/* "exr.b5.<layout>.<name>": one case id per file layout. */
static const char *b5_id(int multipart, const char *name)
{
	static char id[64];
	static const char *const layout[] = {"single", "parts", "short"};
	snprintf(id, sizeof id, "exr.b5.%s.%s", layout[multipart], name);
	return id;
}

/* Blender 5.0's names, in one part (as 4.x lays a file out), a part per
 * pass (as 5.0 saves a multilayer EXR) and a part per pass with channels
 * named by component (as the multi-part convention allows). */
static void test_blender5_pass_names(int multipart)
{
	static const char *names[] = {
		"ViewLayer.Combined.R", "ViewLayer.Combined.G",
		"ViewLayer.Combined.B", "ViewLayer.Combined.A",
		"ViewLayer.Depth.Z", "ViewLayer.Diffuse Color.R",
		"ViewLayer.Diffuse Color.G", "ViewLayer.Diffuse Color.B",
		"ViewLayer.Diffuse Direct.R", "ViewLayer.Diffuse Direct.G",
		"ViewLayer.Diffuse Direct.B", "ViewLayer.Diffuse Indirect.R",
		"ViewLayer.Diffuse Indirect.G", "ViewLayer.Diffuse Indirect.B",
		"ViewLayer.Emission.R", "ViewLayer.Emission.G",
		"ViewLayer.Emission.B", "ViewLayer.Glossy Direct.R",
		"ViewLayer.Glossy Direct.G", "ViewLayer.Glossy Direct.B",
		"ViewLayer.Material Index.X", "ViewLayer.Transmission Color.R",
		"ViewLayer.Transmission Color.G", "ViewLayer.Transmission Color.B",
		"SSSBackLight.Diffuse Direct.R", "SSSBackLight.Diffuse Direct.G",
		"SSSBackLight.Diffuse Direct.B", "Zlayer.DiffDir.R",
		"Zlayer.DiffDir.G", "Zlayer.DiffDir.B", "Zlayer.Diffuse Direct.R",
		"Zlayer.Diffuse Direct.G", "Zlayer.Diffuse Direct.B",
		"Zlayer.DiffCol.R", "Zlayer.DiffCol.G", "Zlayer.DiffCol.B",
		"Zlayer.Depth.Z", "Zlayer.IndexMA.X"};
	tfile f;
	tfile_named(&f, names, (int)(sizeof names / sizeof *names), 6, 5,
	            EXR_COMPRESSION_ZIP, EXR_PIXEL_FLOAT);
	f.multipart = multipart;
	char in[256];
	tpath(in, sizeof in, "blender5.exr");
	char out[256];
	tpath(out, sizeof out, "blender5_out.exr");
	CHECK(b5_id(multipart, "raw_write"), write_test_exr(in, &f) == 0,
	      "raw write");
	sss_exr *exr = NULL;
	CHECK_STATUS(b5_id(multipart, "read"), SSS_OK,
	             sss_exr_read(in, NULL, &exr, errbuf, sizeof errbuf));
	if (exr) {
		sss_passes ps;
		const char *used = NULL;
		sss_image dd, dc, di, ix, em, tc, bl, shortdd;
		CHECK_STATUS(b5_id(multipart, "render"), SSS_OK,
		             sss_exr_render_passes(exr, NULL, &ps, &used, errbuf,
		                                   sizeof errbuf));
		sss_exr_find(exr, "ViewLayer", "Diffuse Direct", &dd);
		sss_exr_find(exr, "ViewLayer", "Diffuse Color", &dc);
		sss_exr_find(exr, "ViewLayer", "Diffuse Indirect", &di);
		sss_exr_find(exr, "ViewLayer", "Material Index", &ix);
		sss_exr_find(exr, "ViewLayer", "Emission", &em);
		sss_exr_find(exr, "ViewLayer", "Transmission Color", &tc);
		if (!used)
			printf("  %s\n", errbuf);
		CHECK(b5_id(multipart, "layer"), used && !strcmp(used, "ViewLayer"),
		      "layer %s", used ? used : "(null)");
		CHECK(b5_id(multipart, "views"), ps.diff_dir.data == dd.data &&
		      ps.diff_col.data == dc.data && ps.diff_ind.data == di.data &&
		      ps.index_ma.data == ix.data && ps.emit.data == em.data &&
		      ps.trans_col.data == tc.data && ps.gloss_ind.data == NULL &&
		      ps.depth.data != NULL, "5.0 names not read");
		CHECK_STATUS(b5_id(multipart, "find_short"), SSS_OK,
		             sss_exr_find(exr, "SSSBackLight", "DiffDir", &bl));
		CHECK_STATUS(b5_id(multipart, "render_short"), SSS_OK,
		             sss_exr_render_passes(exr, "Zlayer", &ps, &used,
		                                   errbuf, sizeof errbuf));
		sss_exr_find(exr, "Zlayer", "Diffuse Direct", &shortdd);
		CHECK(b5_id(multipart, "short_wins"),
		      ps.diff_dir.data != shortdd.data && ps.diff_dir.data != NULL,
		      "the short name must win");
		CHECK(b5_id(multipart, "passes"), sss_exr_pass_count(exr) == 15,
		      "%d passes", sss_exr_pass_count(exr));
		CHECK(b5_id(multipart, "values"), check_values(exr, &f, NULL) == 0,
		      "values differ");
		/* Written back as one part with every channel's full name. */
		CHECK_STATUS(b5_id(multipart, "write"), SSS_OK,
		             sss_exr_write(exr, out, NULL, errbuf, sizeof errbuf));
		sss_exr *back = NULL;
		CHECK_STATUS(b5_id(multipart, "reread"), SSS_OK,
		             sss_exr_read(out, NULL, &back, errbuf, sizeof errbuf));
		CHECK(b5_id(multipart, "round_trip"), back &&
		      sss_exr_pass_count(back) == 15 &&
		      check_values(back, &f, NULL) == 0, "round trip differs");
		sss_exr_free(back);
		sss_exr_free(exr);
	}
	tfile_free(&f);
}

static void test_file_output_names(void)
{
	static const char *names[] = {"DiffDir.R", "DiffDir.G", "DiffDir.B",
	                              "DiffCol.R", "DiffCol.G", "DiffCol.B",
	                              "Depth.Z", "IndexMA.X", "B", "G", "R",
	                              "A", "Extra.red", "Extra.green"};
	tfile f;
	memset(&f, 0, sizeof f);
	f.w = 20;
	f.h = 9;
	f.comp = EXR_COMPRESSION_PIZ;
	f.nchan = (int)(sizeof names / sizeof *names);
	for (int i = 0; i < f.nchan; i++) {
		f.ch[i].name = names[i];
		f.ch[i].type = i % 2 ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
		fill_channel(&f.ch[i], f.w, f.h);
	}
	char in[256], out[256];
	tpath(in, sizeof in, "fileout.exr");
	tpath(out, sizeof out, "fileout_sss.exr");
	CHECK("exr.fo.write", write_test_exr(in, &f) == 0, "raw write");
	sss_exr *exr = NULL;
	CHECK_STATUS("exr.fo.read", SSS_OK,
	             sss_exr_read(in, NULL, &exr, errbuf, sizeof errbuf));
	if (exr) {
		const char *l, *p, *cs;
		int ok = sss_exr_pass_count(exr) == 6;
		static const char *const want[][2] = {
			{"", "RGBA"}, {"Depth", "Z"}, {"DiffCol", "RGB"},
			{"DiffDir", "RGB"}, {"Extra", "green,red"}, {"IndexMA", "X"}};
		for (int i = 0; ok && i < 6; i++) {
			sss_exr_pass(exr, i, &l, &p, &cs, NULL);
			ok = !strcmp(l, "") && !strcmp(p, want[i][0]) &&
			     !strcmp(cs, want[i][1]);
			if (!ok)
				printf("  pass %d: '%s' '%s' '%s'\n", i, l, p, cs);
		}
		CHECK("exr.fo.grouping", ok, "File Output grouping");
		CHECK("exr.fo.values", check_values(exr, &f, NULL) == 0, "values");
		sss_passes ps;
		const char *used = NULL;
		CHECK_STATUS("exr.fo.render", SSS_OK,
		             sss_exr_render_passes(exr, NULL, &ps, &used, errbuf,
		                                   sizeof errbuf));
		CHECK("exr.fo.render.layer", used && used[0] == '\0' &&
		      ps.diff_dir.data && ps.combined.data == NULL,
		      "layer '' expected");
		/* A plain-RGB pass without layer or pass name round-trips. */
		float *rgb = calloc((size_t)f.w * f.h * 3, sizeof *rgb);
		rgb[3] = 7.0f;
		CHECK_STATUS("exr.fo.add", SSS_OK,
		             sss_exr_add_pass(exr, "", "Light", "RGB", rgb, errbuf,
		                              sizeof errbuf));
		CHECK_STATUS("exr.fo.write_out", SSS_OK,
		             sss_exr_write(exr, out, NULL, errbuf, sizeof errbuf));
		rawimg r;
		int rr = raw_read(out, &r);
		int k = rr ? -1 : raw_index(&r, "Light.R");
		CHECK("exr.fo.light", k >= 0 && ((float *)r.data[k])[1] == 7.0f &&
		      raw_index(&r, "Extra.green") >= 0 && raw_index(&r, "A") >= 0,
		      "names rebuilt wrong");
		raw_free(&r);
		free(rgb);
		sss_exr_free(exr);
	}
	tfile_free(&f);
}

/* Single-pass files, where OpenEXRCore may pick its specialised
 * interleaving and direct-read routines: RGBA, RGB, one channel; half
 * and float; stored and compressed. */
static void test_single_pass(void)
{
	static const char *sets[][4] = {{"R", "G", "B", "A"},
	                                {"B", "G", "R", NULL},
	                                {"Z", NULL, NULL, NULL}};
	static const char *want[] = {"RGBA", "RGB", "Z"};
	for (int set = 0; set < 3; set++)
		for (int type = 0; type < 2; type++)
			for (int comp = 0; comp < 2; comp++) {
				tfile f;
				memset(&f, 0, sizeof f);
				f.w = 19;
				f.h = 35;
				f.comp = comp ? EXR_COMPRESSION_ZIP : EXR_COMPRESSION_NONE;
				for (int i = 0; i < 4 && sets[set][i]; i++) {
					f.ch[i].name = sets[set][i];
					f.ch[i].type = type ? EXR_PIXEL_FLOAT : EXR_PIXEL_HALF;
					fill_channel(&f.ch[i], f.w, f.h);
					f.nchan++;
				}
				char p[300], id[64];
				snprintf(p, sizeof p, "%s/single%d%d%d.exr", tmpdir, set,
				         type, comp);
				snprintf(id, sizeof id, "exr.single.%d%d%d", set, type,
				         comp);
				sss_exr *exr = NULL;
				int ok = write_test_exr(p, &f) == 0 &&
				         sss_exr_read(p, NULL, &exr, errbuf,
				                      sizeof errbuf) == SSS_OK;
				const char *cs = "";
				if (ok)
					sss_exr_pass(exr, 0, NULL, NULL, &cs, NULL);
				CHECK(id, ok && sss_exr_pass_count(exr) == 1 &&
				      !strcmp(cs, want[set]) &&
				      check_values(exr, &f, NULL) == 0, "%s", errbuf);
				/* and written back bit for bit (the encoder's paths) */
				char out[300];
				rawimg r;
				memset(&r, 0, sizeof r);
				snprintf(out, sizeof out, "%s/single_out.exr", tmpdir);
				long diff = 0;
				ok = ok && sss_exr_write(exr, out, NULL, errbuf,
				                         sizeof errbuf) == SSS_OK &&
				     raw_read(out, &r) == 0 && r.n == f.nchan;
				for (int i = 0; ok && i < f.nchan; i++) {
					int k = raw_index(&r, f.ch[i].name);
					diff += k < 0 || r.type[k] != f.ch[i].type ||
					        memcmp(r.data[k], f.ch[i].data,
					               (size_t)f.w * f.h * bpe(f.ch[i].type));
				}
				snprintf(id, sizeof id, "exr.single.%d%d%d.write", set,
				         type, comp);
				CHECK(id, ok && diff == 0, "%ld channels differ: %s", diff,
				      errbuf);
				raw_free(&r);
				sss_exr_free(exr);
				tfile_free(&f);
			}
}

/* (2) Tiled input (partial edge tiles, ONE_LEVEL and MIPMAP) reads like
 * the scanline file. */
static void test_tiled(void)
{
	for (int mip = 0; mip <= 1; mip++) {
		tfile f;
		make_blender(&f, 37, 41, EXR_COMPRESSION_ZIP);
		f.tile = 16;
		f.mip = mip;
		char in[256], id[64];
		snprintf(in, sizeof in, "%s/tiled%d.exr", tmpdir, mip);
		int wr = write_test_exr(in, &f);
		snprintf(id, sizeof id, "exr.tiled%d.write", mip);
		CHECK(id, wr == 0, "raw tiled write %d", wr);
		sss_exr *exr = NULL;
		snprintf(id, sizeof id, "exr.tiled%d.read", mip);
		CHECK_STATUS(id, SSS_OK,
		             sss_exr_read(in, NULL, &exr, errbuf, sizeof errbuf));
		if (exr) {
			long bad = check_values(exr, &f, NULL);
			snprintf(id, sizeof id, "exr.tiled%d.values", mip);
			CHECK(id, bad == 0 && sss_exr_width(exr) == 37 &&
			      sss_exr_pass_count(exr) == NPASSES, "%ld differ", bad);
			/* Written back as scanlines, still exact. */
			char out[256];
			tpath(out, sizeof out, "tiled_out.exr");
			snprintf(id, sizeof id, "exr.tiled%d.write_out", mip);
			CHECK_STATUS(id, SSS_OK,
			             sss_exr_write(exr, out, NULL, errbuf,
			                           sizeof errbuf));
			sss_exr *back = NULL;
			sss_exr_read(out, NULL, &back, errbuf, sizeof errbuf);
			snprintf(id, sizeof id, "exr.tiled%d.reread", mip);
			CHECK(id, back && check_values(back, &f, NULL) == 0, "%s",
			      errbuf);
			sss_exr_free(back);
			sss_exr_free(exr);
		} else {
			printf("  %s\n", errbuf);
		}
		tfile_free(&f);
	}
}

/* Offset of the first chunk's data, the chunk count and file size. */
static int layout(const char *path, uint64_t *table, int32_t *chunks)
{
	exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
	init.error_handler_fn = silent;
	exr_context_t c;
	exr_chunk_info_t ci;
	exr_attr_box2i_t dw;
	if (exr_start_read(&c, path, &init))
		return -1;
	int rv = exr_get_data_window(c, 0, &dw) ||
	         exr_get_chunk_count(c, 0, chunks) ||
	         exr_read_scanline_chunk_info(c, 0, dw.min.y, &ci);
	/* chunk = int y, int size, data; the offset table precedes chunk 0 */
	*table = ci.data_offset - 8 - 8 * (uint64_t)*chunks;
	exr_finish(&c);
	return rv ? -1 : 0;
}

static void expect_bad(const char *id, const char *path, sss_result code,
                       const char *also)
{
	sss_exr *exr = (sss_exr *)1;
	errbuf[0] = '\0';
	sss_result r = sss_exr_read(path, NULL, &exr, errbuf, sizeof errbuf);
	CHECK(id, r == code && exr == NULL && file_contains(errbuf, path) &&
	      (!also || file_contains(errbuf, also)),
	      "got %s, expected %s: %s", sss_status_name(r),
	      sss_status_name(code), errbuf);
	if (getenv("TEST_EXR_VERBOSE"))
		printf("  [%s] %s\n", id, errbuf);
	if (r == SSS_OK)
		sss_exr_free(exr);
}

/* (3) Bad files: the documented code, the file named, never a crash. */
static void test_bad_files(void)
{
	char p[256], good[256];
	tpath(p, sizeof p, "missing.exr");
	expect_bad("exr.bad.missing", p, SSS_ERR_IO, "No such file");
	expect_bad("exr.bad.directory", tmpdir, SSS_ERR_IO, "directory");
	tpath(p, sizeof p, "empty.exr");
	spit(p, (const unsigned char *)"", 0);
	expect_bad("exr.bad.empty", p, SSS_ERR_EXR, "empty");
	tpath(p, sizeof p, "magic.exr");
	unsigned char junk[200];
	for (size_t i = 0; i < sizeof junk; i++)
		junk[i] = (unsigned char)(i * 7 + 1);
	spit(p, junk, sizeof junk);
	expect_bad("exr.bad.magic", p, SSS_ERR_EXR, NULL);

	tfile f;
	make_blender(&f, 37, 41, EXR_COMPRESSION_ZIP);
	tpath(good, sizeof good, "good.exr");
	CHECK("exr.bad.write_good", write_test_exr(good, &f) == 0, "raw write");
	long len = 0;
	unsigned char *bytes = slurp(good, &len);
	uint64_t table = 0;
	int32_t chunks = 0;
	CHECK("exr.bad.layout", bytes && layout(good, &table, &chunks) == 0 &&
	      table > 100 && (long)table < len, "layout");
	if (!bytes) {
		tfile_free(&f);
		return;
	}
	long cuts[] = {4, 8, 100, (long)table, (long)table + 8 * chunks,
	               (long)table + 8 * chunks + 13,
	               (long)table + 8 * chunks + (len - (long)table) / 2,
	               len - 1};
	for (size_t i = 0; i < sizeof cuts / sizeof *cuts; i++) {
		char id[64];
		tpath(p, sizeof p, "truncated.exr");
		spit(p, bytes, cuts[i]);
		snprintf(id, sizeof id, "exr.bad.truncated.%ld", cuts[i]);
		expect_bad(id, p, SSS_ERR_EXR, cuts[i] > (long)table
		                               ? "truncated or corrupt" : NULL);
	}

	/* The dataWindow attribute patched to 1000000x1000000. */
	static const char key[] = "dataWindow\0box2i";
	unsigned char *patched = malloc((size_t)len);
	memcpy(patched, bytes, (size_t)len);
	unsigned char *at = NULL;
	for (long i = 0; i + (long)sizeof key < len && !at; i++)
		if (!memcmp(patched + i, key, sizeof key))
			at = patched + i + sizeof key + 4; /* after the size */
	CHECK("exr.bad.dw.found", at != NULL, "no dataWindow attribute");
	if (at) {
		int32_t box[4] = {0, 0, 999999, 999999};
		memcpy(at, box, sizeof box); /* little-endian host, as EXR */
		tpath(p, sizeof p, "huge.exr");
		spit(p, patched, len);
		expect_bad("exr.bad.huge", p, SSS_ERR_INVALID_ARGUMENT,
		           "1000000x1000000 exceeds the 32768x32768 limit");
		int32_t inverted[4] = {10, 10, 0, 0};
		memcpy(at, inverted, sizeof inverted);
		tpath(p, sizeof p, "inverted.exr");
		spit(p, patched, len);
		expect_bad("exr.bad.inverted", p, SSS_ERR_EXR, NULL);
	}
	/* A chunk offset pointing far outside the file: OpenEXRCore rebuilds
	 * the table from the chunks themselves (the data is intact), or the
	 * read fails; never wrong pixels. */
	memcpy(patched, bytes, (size_t)len);
	uint64_t far = (uint64_t)1 << 40;
	memcpy(patched + table + 8, &far, 8);
	tpath(p, sizeof p, "badoffset.exr");
	spit(p, patched, len);
	sss_exr *rebuilt = NULL;
	sss_result rr = sss_exr_read(p, NULL, &rebuilt, errbuf, sizeof errbuf);
	CHECK("exr.bad.offset", rr == SSS_ERR_EXR ||
	      (rr == SSS_OK && check_values(rebuilt, &f, NULL) == 0),
	      "got %s: %s", sss_status_name(rr), errbuf);
	sss_exr_free(rebuilt);
	/* Garbage inside compressed chunk data: an error, or other pixels. */
	memcpy(patched, bytes, (size_t)len);
	for (long i = (long)table + 8 * chunks + 8; i < len; i += 5)
		patched[i] ^= 0x5a;
	tpath(p, sizeof p, "garbage.exr");
	spit(p, patched, len);
	expect_bad("exr.bad.garbage", p, SSS_ERR_EXR, NULL);
	free(patched);
	free(bytes);

	/* Limits from the options. */
	sss_exr_options o;
	sss_exr *exr = NULL;
	sss_exr_options_default(&o);
	o.max_width = 20;
	CHECK_STATUS("exr.bad.max_width", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_read(good, &o, &exr, errbuf, sizeof errbuf));
	CHECK("exr.bad.max_width.msg", file_contains(errbuf, good) &&
	      file_contains(errbuf, "37x41 exceeds the 20x32768 limit"), "%s",
	      errbuf);
	sss_exr_options_default(&o);
	o.max_pixels = 1000;
	CHECK_STATUS("exr.bad.max_pixels", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_read(good, &o, &exr, errbuf, sizeof errbuf));
	CHECK("exr.bad.max_pixels.msg", file_contains(errbuf, "1517 pixels"),
	      "%s", errbuf);
	tfile_free(&f);
}

/* Writes through our descriptor: the library deletes an incomplete file
 * it opened itself, and a header alone is all these tests need. */
static int64_t keep_write(exr_const_context_t c, void *ud, const void *buf,
                          uint64_t sz, uint64_t off,
                          exr_stream_error_func_ptr_t cb)
{
	(void)c;
	(void)cb;
	return pwrite(*(int *)ud, buf, (size_t)sz, (off_t)off);
}

/* DWAA/DWAB inputs (tiny files made by oiiotool, in tests/data): read,
 * or with OpenEXRCore 3.1 refused as unsupported, naming the library. */
static void test_dwa(void)
{
	static const char *files[] = {"tests/data/dwaa_32x32.exr",
	                              "tests/data/dwab_32x32.exr"};
	for (int i = 0; i < 2; i++) {
		sss_exr *exr = NULL;
		char id[64];
		sss_result r = sss_exr_read(files[i], NULL, &exr, errbuf,
		                            sizeof errbuf);
		sss_image v = {0};
		snprintf(id, sizeof id, "exr.dwa%d", i);
		if (r == SSS_OK)
			CHECK(id, sss_exr_find(exr, "", "", &v) == SSS_OK &&
			      v.channels == 3 && v.data[0] > 0.9f && v.data[1] < 0.1f,
			      "values");
		else
			CHECK(id, r == SSS_ERR_UNSUPPORTED &&
			      file_contains(errbuf, files[i]) &&
			      file_contains(errbuf, "DWA") &&
			      file_contains(errbuf, "OpenEXRCore"), "%s: %s",
			      sss_status_name(r), errbuf);
		sss_exr_free(exr);
	}
}

/* Files valid as EXR that libsss refuses or reads partly. */
/* Two 2-row half parts, "first" (Y, 2 wide) and "second" (Z, second_w
 * wide), both 1 2 3 4 ... row by row; 0 on success. */
static int write_two_parts(const char *path, int second_w)
{
	exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
	init.error_handler_fn = silent;
	exr_context_t c;
	int part;
	uint16_t px[6] = {0x3c00, 0x4000, 0x4200, 0x4400, 0x4500, 0x4600};
	int rv = exr_start_write(&c, path, EXR_WRITE_FILE_DIRECTLY, &init);
	for (int i = 0; !rv && i < 2; i++)
		rv = exr_add_part(c, i ? "second" : "first", EXR_STORAGE_SCANLINE,
		                  &part) ||
		     exr_initialize_required_attr_simple(c, part, i ? second_w : 2,
		                                         2, EXR_COMPRESSION_NONE) ||
		     exr_add_channel(c, part, i ? "Z" : "Y", EXR_PIXEL_HALF,
		                     EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
	if (!rv)
		rv = exr_write_header(c);
	for (int i = 0; !rv && i < 2; i++)
		for (int y = 0; !rv && y < 2; y++) {
			int w = i ? second_w : 2;
			exr_chunk_info_t ci;
			exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
			rv = exr_write_scanline_chunk_info(c, i, y, &ci) ||
			     exr_encoding_initialize(c, i, &ci, &enc);
			if (!rv) {
				enc.channels[0].encode_from_ptr =
					(const uint8_t *)(px + w * y);
				enc.channels[0].user_pixel_stride = 2;
				enc.channels[0].user_line_stride = 2 * w;
				rv = exr_encoding_choose_default_routines(c, i, &enc) ||
				     exr_encoding_run(c, i, &enc);
			}
			exr_encoding_destroy(c, &enc);
		}
	return exr_finish(&c) || rv;
}

static void test_unsupported(void)
{
	exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
	init.error_handler_fn = silent;
	exr_context_t c;
	int part, fd;
	char p[256];

	/* Deep scanline header: refused before any chunk is read. */
	tpath(p, sizeof p, "deep.exr");
	exr_context_initializer_t keep = init;
	keep.write_fn = keep_write;
	keep.user_data = &fd;
	fd = open(p, O_WRONLY | O_CREAT | O_TRUNC, 0666);
	int rv = exr_start_write(&c, p, EXR_WRITE_FILE_DIRECTLY, &keep);
	if (!rv)
		rv = exr_add_part(c, NULL, EXR_STORAGE_DEEP_SCANLINE, &part) ||
		     exr_initialize_required_attr_simple(c, part, 8, 8,
		                                         EXR_COMPRESSION_ZIPS) ||
		     exr_add_channel(c, part, "Z", EXR_PIXEL_FLOAT,
		                     EXR_PERCEPTUALLY_LINEAR, 1, 1) ||
		     exr_write_header(c);
	exr_finish(&c);
	close(fd);
	CHECK("exr.deep.write", rv == 0, "deep header %d", rv);
	expect_bad("exr.deep", p, SSS_ERR_UNSUPPORTED, "deep");

	/* A 2x2-subsampled channel: refused, naming it. */
	tpath(p, sizeof p, "sampled.exr");
	fd = open(p, O_WRONLY | O_CREAT | O_TRUNC, 0666);
	rv = exr_start_write(&c, p, EXR_WRITE_FILE_DIRECTLY, &keep);
	if (!rv)
		rv = exr_add_part(c, NULL, EXR_STORAGE_SCANLINE, &part) ||
		     exr_initialize_required_attr_simple(c, part, 8, 8,
		                                         EXR_COMPRESSION_NONE) ||
		     exr_add_channel(c, part, "Y", EXR_PIXEL_HALF,
		                     EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1) ||
		     exr_add_channel(c, part, "RY", EXR_PIXEL_HALF,
		                     EXR_PERCEPTUALLY_LOGARITHMIC, 2, 2) ||
		     exr_write_header(c);
	exr_finish(&c);
	close(fd);
	CHECK("exr.sampled.write", rv == 0, "sampled header %d", rv);
	expect_bad("exr.sampled", p, SSS_ERR_UNSUPPORTED, "'RY'");

	/* Two parts: both are read, each channel under its part's name. */
	tpath(p, sizeof p, "multipart.exr");
	CHECK("exr.multipart.write", write_two_parts(p, 2) == 0, "multipart");
	sss_exr *exr = NULL;
	CHECK_STATUS("exr.multipart.read", SSS_OK,
	             sss_exr_read(p, NULL, &exr, errbuf, sizeof errbuf));
	sss_image y = {0}, z = {0};
	CHECK("exr.multipart.both", exr && sss_exr_pass_count(exr) == 2 &&
	      sss_exr_find(exr, "", "first", &y) == SSS_OK &&
	      sss_exr_find(exr, "", "second", &z) == SSS_OK &&
	      y.data[3] == 4.0f && z.data[0] == 1.0f && z.data[3] == 4.0f,
	      "parts not read: %s", errbuf);
	if (exr) {
		char out[256];
		tpath(out, sizeof out, "multipart_out.exr");
		CHECK_STATUS("exr.multipart.write_out", SSS_OK,
		             sss_exr_write(exr, out, NULL, errbuf, sizeof errbuf));
	}
	sss_exr_free(exr);

	/* Parts of different sizes: refused, naming the part. */
	tpath(p, sizeof p, "multipart_sizes.exr");
	CHECK("exr.multipart_sizes.write", write_two_parts(p, 3) == 0,
	      "multipart sizes");
	expect_bad("exr.multipart_sizes", p, SSS_ERR_UNSUPPORTED,
	           "part 1 ('second')");
}

/* Passes missing for libsss, and the hints. */
static void test_missing_passes(void)
{
	static const char *names[] = {"ViewLayer.Combined.R",
	                              "ViewLayer.Combined.G",
	                              "ViewLayer.Combined.B",
	                              "ViewLayer.DiffCol.R",
	                              "ViewLayer.DiffCol.G",
	                              "ViewLayer.DiffCol.B",
	                              "ViewLayer.Depth.Z"};
	tfile f;
	tfile_named(&f, names, (int)(sizeof names / sizeof *names), 4, 3,
	            EXR_COMPRESSION_ZIP, EXR_PIXEL_HALF);
	char p[256];
	tpath(p, sizeof p, "nodiffdir.exr");
	CHECK("exr.missing.write", write_test_exr(p, &f) == 0, "raw write");
	sss_exr *exr = NULL;
	CHECK_STATUS("exr.missing.read", SSS_OK,
	             sss_exr_read(p, NULL, &exr, errbuf, sizeof errbuf));
	sss_passes ps;
	const char *used = (const char *)1;
	if (exr) {
		CHECK_STATUS("exr.missing.auto", SSS_ERR_MISSING_PASS,
		             sss_exr_render_passes(exr, NULL, &ps, &used, errbuf,
		                                   sizeof errbuf));
		CHECK("exr.missing.auto.msg", file_contains(errbuf, "DiffDir") &&
		      file_contains(errbuf, p) &&
		      file_contains(errbuf, "'ViewLayer' (Combined, Depth, "
		                            "DiffCol)") &&
		      file_contains(errbuf, "View Layer Properties > Passes") &&
		      used == NULL, "%s", errbuf);
		CHECK_STATUS("exr.missing.named", SSS_ERR_MISSING_PASS,
		             sss_exr_render_passes(exr, "ViewLayer", &ps, NULL,
		                                   errbuf, sizeof errbuf));
		CHECK("exr.missing.named.msg",
		      file_contains(errbuf, "no DiffDir, IndexMA passes") &&
		      file_contains(errbuf, "Material Index") &&
		      ps.diff_col.data == NULL, "%s", errbuf);
		sss_exr_free(exr);
	}
	tfile_free(&f);

	/* A DiffDir without R, G, B components. */
	static const char *odd[] = {"L.DiffDir.X", "L.DiffDir.Y", "L.DiffDir.Z",
	                            "L.DiffCol.R", "L.DiffCol.G", "L.DiffCol.B",
	                            "L.Depth.Z", "L.IndexMA.X"};
	tfile_named(&f, odd, (int)(sizeof odd / sizeof *odd), 2, 2,
	            EXR_COMPRESSION_NONE, EXR_PIXEL_FLOAT);
	tpath(p, sizeof p, "xyzdiff.exr");
	CHECK("exr.components.write", write_test_exr(p, &f) == 0, "raw write");
	exr = NULL;
	sss_exr_read(p, NULL, &exr, errbuf, sizeof errbuf);
	CHECK_STATUS("exr.components", SSS_ERR_MISSING_PASS,
	             sss_exr_render_passes(exr, NULL, &ps, NULL, errbuf,
	                                   sizeof errbuf));
	CHECK("exr.components.msg", file_contains(errbuf, "DiffDir") &&
	      file_contains(errbuf, "'XYZ'"), "%s", errbuf);
	sss_exr_free(exr);
	tfile_free(&f);
}


/* A view layer named as Blender names a copy ("ViewLayer.001"): names are
 * split from the end, so the layer is found by itself and by name. */
static void test_dotted_layer(void)
{
	static const char *names[] = {"ViewLayer.001.DiffDir.R",
	                              "ViewLayer.001.DiffDir.G",
	                              "ViewLayer.001.DiffDir.B",
	                              "ViewLayer.001.DiffCol.R",
	                              "ViewLayer.001.DiffCol.G",
	                              "ViewLayer.001.DiffCol.B",
	                              "ViewLayer.001.Depth.Z",
	                              "ViewLayer.001.IndexMA.X"};
	tfile f;
	tfile_named(&f, names, (int)(sizeof names / sizeof *names), 3, 2,
	            EXR_COMPRESSION_ZIP, EXR_PIXEL_FLOAT);
	char p[256];
	tpath(p, sizeof p, "dotted.exr");
	CHECK("exr.dotted.write", write_test_exr(p, &f) == 0, "raw write");
	sss_exr *exr = NULL;
	CHECK_STATUS("exr.dotted.read", SSS_OK,
	             sss_exr_read(p, NULL, &exr, errbuf, sizeof errbuf));
	sss_passes ps;
	const char *used = NULL;
	if (exr) {
		const char *l = NULL, *pass = NULL;
		int32_t np = sss_exr_pass_count(exr), same = 0;
		for (int32_t i = 0; i < np; i++) {
			sss_exr_pass(exr, i, &l, &pass, NULL, NULL);
			same += !strcmp(l, "ViewLayer.001") && strchr(pass, '.') == NULL;
		}
		CHECK("exr.dotted.split", np == 4 && same == 4, "%d passes", np);
		CHECK_STATUS("exr.dotted.auto", SSS_OK,
		             sss_exr_render_passes(exr, NULL, &ps, &used, errbuf,
		                                   sizeof errbuf));
		CHECK("exr.dotted.used", used && !strcmp(used, "ViewLayer.001"),
		      "%s", used ? used : "(none)");
		CHECK_STATUS("exr.dotted.named", SSS_OK,
		             sss_exr_render_passes(exr, "ViewLayer.001", &ps, NULL,
		                                   errbuf, sizeof errbuf));
		CHECK("exr.dotted.values", check_values(exr, &f, NULL) == 0,
		      "values");
		/* Added under a dotted layer, read back as that layer. */
		float one[6] = {1, 2, 3, 4, 5, 6};
		CHECK_STATUS("exr.dotted.add", SSS_OK,
		             sss_exr_add_pass(exr, "SSS-ViewLayer.001", "X", "V",
		                              one, errbuf, sizeof errbuf));
		CHECK_STATUS("exr.dotted.add.pass_dot", SSS_ERR_INVALID_ARGUMENT,
		             sss_exr_add_pass(exr, "L", "a.b", "V", one, errbuf,
		                              sizeof errbuf));
		char o[256];
		tpath(o, sizeof o, "dotted_out.exr");
		CHECK_STATUS("exr.dotted.save", SSS_OK,
		             sss_exr_write(exr, o, NULL, errbuf, sizeof errbuf));
		sss_exr *back = NULL;
		sss_image v;
		CHECK_STATUS("exr.dotted.reread", SSS_OK,
		             sss_exr_read(o, NULL, &back, errbuf, sizeof errbuf));
		CHECK_STATUS("exr.dotted.find", SSS_OK,
		             sss_exr_find(back, "SSS-ViewLayer.001", "X", &v));
		sss_exr_free(back);
		sss_exr_free(exr);
	}
	tfile_free(&f);
}

/* uint channels (object or cryptomatte-like IDs) come back bit for bit,
 * also above 2^24 where a float rounds them; a float view changed by
 * the caller is written as changed. */
static void test_uint_exact(void)
{
	static const char *names[] = {"L.ID.X", "L.Depth.Z"};
	tfile f;
	tfile_named(&f, names, 1, 4, 4, EXR_COMPRESSION_ZIP, EXR_PIXEL_UINT);
	f.nchan = 2;
	f.ch[1].name = names[1];
	f.ch[1].type = EXR_PIXEL_FLOAT;
	fill_channel(&f.ch[1], 4, 4);
	uint32_t *id = f.ch[0].data;
	static const uint32_t big[] = {16777217u, 16777219u, 0xFFFFFFFFu,
	                               0x80000001u, 0xFFFFFF81u, 123456789u};
	for (size_t i = 0; i < sizeof big / sizeof *big; i++)
		id[i] = big[i];
	char p[256], o[256];
	tpath(p, sizeof p, "uint.exr");
	tpath(o, sizeof o, "uint_out.exr");
	CHECK("exr.uint.write", write_test_exr(p, &f) == 0, "raw write");
	sss_exr *exr = NULL;
	CHECK_STATUS("exr.uint.read", SSS_OK,
	             sss_exr_read(p, NULL, &exr, errbuf, sizeof errbuf));
	CHECK_STATUS("exr.uint.save", SSS_OK,
	             sss_exr_write(exr, o, NULL, errbuf, sizeof errbuf));
	rawimg r;
	long bad = 0;
	if (raw_read(o, &r) == 0) {
		int k = raw_index(&r, "L.ID.X");
		for (int i = 0; k >= 0 && i < 16; i++)
			bad += ((uint32_t *)r.data[k])[i] != id[i];
		CHECK("exr.uint.bits", k >= 0 && r.type[k] == EXR_PIXEL_UINT &&
		      bad == 0, "%ld values changed", bad);
	} else {
		CHECK("exr.uint.raw", 0, "cannot read %s", o);
	}
	raw_free(&r);
	/* Changed through the view: the new value is written. */
	sss_image v;
	if (exr && sss_exr_find(exr, "L", "ID", &v) == SSS_OK) {
		v.data[0] = 7.0f;
		CHECK_STATUS("exr.uint.save2", SSS_OK,
		             sss_exr_write(exr, o, NULL, errbuf, sizeof errbuf));
		if (raw_read(o, &r) == 0) {
			int k = raw_index(&r, "L.ID.X");
			CHECK("exr.uint.changed", k >= 0 &&
			      ((uint32_t *)r.data[k])[0] == 7 &&
			      ((uint32_t *)r.data[k])[1] == id[1], "not kept");
		}
		raw_free(&r);
	}
	sss_exr_free(exr);
	tfile_free(&f);
}

/* (4) Writing: never over the source, atomic, no temporary left. */
static void test_write_safety(void)
{
	char dir[256], src[512], p[512];
	tpath(dir, sizeof dir, "w");
	mkdir(dir, 0777);
	snprintf(src, sizeof src, "%s/src.exr", dir);
	tfile f;
	make_blender(&f, 37, 41, EXR_COMPRESSION_ZIP);
	CHECK("exr.ws.write_src", write_test_exr(src, &f) == 0, "raw write");
	long len0 = 0, len1 = 0;
	unsigned char *before = slurp(src, &len0);
	sss_exr *exr = NULL;
	CHECK_STATUS("exr.ws.read", SSS_OK,
	             sss_exr_read(src, NULL, &exr, errbuf, sizeof errbuf));
	if (!exr) {
		free(before);
		tfile_free(&f);
		return;
	}

	/* The source itself, a hard link and a symlink to it: refused. */
	CHECK_STATUS("exr.ws.self", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_write(exr, src, NULL, errbuf, sizeof errbuf));
	CHECK("exr.ws.self.msg", file_contains(errbuf, src) &&
	      file_contains(errbuf, "refusing"), "%s", errbuf);
	char hard[512], soft[512];
	snprintf(hard, sizeof hard, "%s/hard.exr", dir);
	snprintf(soft, sizeof soft, "%s/soft.exr", dir);
	CHECK("exr.ws.links", link(src, hard) == 0 && symlink(src, soft) == 0,
	      "links: %s", strerror(errno));
	CHECK_STATUS("exr.ws.hardlink", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_write(exr, hard, NULL, errbuf, sizeof errbuf));
	CHECK_STATUS("exr.ws.symlink", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_write(exr, soft, NULL, errbuf, sizeof errbuf));
	unsigned char *after = slurp(src, &len1);
	CHECK("exr.ws.intact", before && after && len0 == len1 &&
	      !memcmp(before, after, (size_t)len0), "source changed");
	free(after);
	const char *const listed[] = {"src.exr", "hard.exr", "soft.exr"};
	CHECK("exr.ws.no_temp.refused", stray_files(dir, listed, 3) == 0,
	      "stray files");

	/* A directory that does not exist, and a path that is a directory. */
	snprintf(p, sizeof p, "%s/nodir/out.exr", dir);
	CHECK_STATUS("exr.ws.nodir", SSS_ERR_IO,
	             sss_exr_write(exr, p, NULL, errbuf, sizeof errbuf));
	CHECK("exr.ws.nodir.msg", file_contains(errbuf, p), "%s", errbuf);
	CHECK_STATUS("exr.ws.isdir", SSS_ERR_IO,
	             sss_exr_write(exr, dir, NULL, errbuf, sizeof errbuf));
	if (geteuid() != 0) { /* root ignores directory permissions */
		char ro[300];
		snprintf(ro, sizeof ro, "%s/ro", dir);
		mkdir(ro, 0555);
		snprintf(p, sizeof p, "%s/out.exr", ro);
		CHECK_STATUS("exr.ws.readonly", SSS_ERR_IO,
		             sss_exr_write(exr, p, NULL, errbuf, sizeof errbuf));
		CHECK("exr.ws.readonly.empty", stray_files(ro, NULL, 0) == 0,
		      "files left in a read-only directory");
		rmdir(ro);
	}

	/* A write that fails midway (file size limit): the old output stays
	 * as it was and no temporary file is left. */
	char out[512];
	snprintf(out, sizeof out, "%s/out.exr", dir);
	spit(out, (const unsigned char *)"old contents", 12);
	struct rlimit old, lim;
	struct sigaction ign, prev;
	memset(&ign, 0, sizeof ign);
	ign.sa_handler = SIG_IGN;
	sigaction(SIGXFSZ, &ign, &prev);
	getrlimit(RLIMIT_FSIZE, &old);
	lim = old;
	lim.rlim_cur = 20000;
	setrlimit(RLIMIT_FSIZE, &lim);
	sss_result r = sss_exr_write(exr, out, NULL, errbuf, sizeof errbuf);
	setrlimit(RLIMIT_FSIZE, &old);
	sigaction(SIGXFSZ, &prev, NULL);
	CHECK("exr.ws.fsize", r == SSS_ERR_EXR || r == SSS_ERR_IO,
	      "got %s: %s", sss_status_name(r), errbuf);
	CHECK("exr.ws.fsize.msg", file_contains(errbuf, out), "%s", errbuf);
	after = slurp(out, &len1);
	CHECK("exr.ws.fsize.old", after && len1 == 12 &&
	      !memcmp(after, "old contents", 12), "old output changed");
	free(after);
	const char *const listed2[] = {"src.exr", "hard.exr", "soft.exr",
	                               "out.exr"};
	CHECK("exr.ws.fsize.no_temp", stray_files(dir, listed2, 4) == 0,
	      "temporary file left behind");

	/* A successful write replaces the old output, nothing else left. */
	CHECK_STATUS("exr.ws.ok", SSS_OK,
	             sss_exr_write(exr, out, NULL, errbuf, sizeof errbuf));
	CHECK("exr.ws.ok.replaced", file_size(out) > 1000, "not replaced");
	CHECK("exr.ws.ok.no_temp", stray_files(dir, listed2, 4) == 0,
	      "temporary file left behind");
	/* The source may even be gone: metadata comes from memory. */
	unlink(hard);
	unlink(soft);
	unlink(src);
	CHECK_STATUS("exr.ws.src_gone", SSS_OK,
	             sss_exr_write(exr, out, NULL, errbuf, sizeof errbuf));
	rawimg rr;
	const char *s = NULL;
	CHECK("exr.ws.src_gone.attrs", raw_read(out, &rr) == 0 &&
	      exr_attr_get_string(rr.c, 0, "RenderTime", NULL, &s) == 0 && s &&
	      !strcmp(s, "00:01.25"), "metadata lost");
	raw_free(&rr);
	/* Bad write arguments. */
	sss_exr_options o;
	sss_exr_options_default(&o);
	o.compression = -1;
	CHECK_STATUS("exr.ws.badcomp", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_write(exr, out, &o, errbuf, sizeof errbuf));
	CHECK_STATUS("exr.ws.nopath", SSS_ERR_INVALID_ARGUMENT,
	             sss_exr_write(exr, "", NULL, errbuf, sizeof errbuf));
	unlink(out);
	free(before);
	sss_exr_free(exr);
	tfile_free(&f);
	rmdir(dir);
}

/* Removes what the tests made (flat files and the w/ directory). */
static void cleanup(const char *dir)
{
	DIR *d = opendir(dir);
	struct dirent *e;
	char p[512];
	if (!d)
		return;
	while ((e = readdir(d))) {
		if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
			continue;
		snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
		struct stat st;
		if (lstat(p, &st) == 0 && S_ISDIR(st.st_mode))
			cleanup(p);
		else
			unlink(p);
	}
	closedir(d);
	rmdir(dir);
}

/* sss_process_exr says where it is: read, scatter and write in order,
 * each from 0 to 1, the write in rounds of chunks, all on this thread. */
static struct {
	char stage[16][16];
	double done[16];
	int n;
} seen;

static void on_progress(const char *stage, double done, void *user)
{
	(void)user;
	if (seen.n < 16) {
		snprintf(seen.stage[seen.n], sizeof seen.stage[0], "%s", stage);
		seen.done[seen.n] = done;
	}
	seen.n++;
}

static void test_progress(void)
{
	char err[512], out[128];
	sss_scene *scene = NULL;
	tpath(out, sizeof out, "progress.exr");
	CHECK_STATUS("progress.scene", SSS_OK,
	             sss_scene_load("tests/data/blender_8x8.json", &scene, NULL,
	                            0, err, sizeof err));
	sss_process_options opt;
	sss_process_options_default(&opt);
	opt.progress_fn = on_progress;
	CHECK_STATUS("progress.run", SSS_OK,
	             sss_process_exr("tests/data/blender_8x8.exr", out, scene,
	                             &opt, NULL, err, sizeof err));
	sss_scene_free(scene);
	static const char *order[] = {"read", "scatter", "write"};
	int stage = 0, ok = seen.n >= 6 && seen.n <= 16;
	double last = -1.0;
	for (int i = 0; ok && i < seen.n; i++) {
		if (strcmp(seen.stage[i], order[stage]) != 0) {
			ok = last == 1.0 && stage < 2 &&
			     strcmp(seen.stage[i], order[stage + 1]) == 0;
			stage++;
			last = -1.0;
		}
		ok = ok && seen.done[i] >= last && seen.done[i] <= 1.0 &&
		     (last >= 0.0 || seen.done[i] == 0.0);
		last = seen.done[i];
	}
	CHECK("progress.order", ok && stage == 2 && last == 1.0,
	      "%d calls, stage %d, last %g", seen.n, stage, last);
}

/* An output folder that takes no new file is said before the frame is
 * read or scattered (procfs: not even root creates a file there). */
static void test_unwritable_folder_first(void)
{
	char err[512];
	sss_scene *scene = NULL;
	sss_scene_load("tests/data/blender_8x8.json", &scene, NULL, 0, err,
	               sizeof err);
	sss_process_options opt;
	sss_process_options_default(&opt);
	opt.progress_fn = on_progress;
	seen.n = 0;
	CHECK_STATUS("process.folder", SSS_ERR_IO,
	             sss_process_exr("tests/data/blender_8x8.exr",
	                             "/proc/sss_out.exr", scene, &opt, NULL, err,
	                             sizeof err));
	CHECK("process.folder.first", seen.n == 0 &&
	      file_contains(err, "its folder /proc is not writable"),
	      "%d progress calls; %s", seen.n, err);
	sss_scene_free(scene);
}

int main(void)
{
	snprintf(tmpdir, sizeof tmpdir, "/tmp/sss_exr_XXXXXX");
	if (!mkdtemp(tmpdir)) {
		perror("mkdtemp");
		return 1;
	}
	test_options();
	test_round_trip();
	test_compressions();
	test_file_output_names();
	for (int multipart = 0; multipart <= 2; multipart++)
		test_blender5_pass_names(multipart);
	test_single_pass();
	test_tiled();
	test_bad_files();
	test_unsupported();
	test_dwa();
	test_missing_passes();
	test_dotted_layer();
	test_uint_exact();
	test_write_safety();
	test_progress();
	test_unwritable_folder_first();
	cleanup(tmpdir);
	return tu_finish("test_exr");
}
