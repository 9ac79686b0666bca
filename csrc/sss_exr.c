/* sss_exr.c - multilayer EXR files through OpenEXR's C API (OpenEXRCore):
 * channels decoded straight into float passes, written back losslessly
 * through a temporary file. The only file of libsss that sees openexr.h. */
#define _DEFAULT_SOURCE /* flock */
#include "sss_internal.h"

#include <libdeflate.h>
#include <openexr.h>

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <dirent.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <time.h>
#include <unistd.h>

#define FAILX(code, ...) sss__fail(errbuf, errbuf_len, code, __VA_ARGS__)

/* EXR allows 255-byte names once long names are switched on. */
#define MAX_NAME 255
#define SHORT_NAME 31

/* ---------------------------------------------------------------- types */

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

/* --------------------------------------------------------- I/O, errors */

static void xio_init(xio *io, int fd)
{
	memset(io, 0, sizeof *io);
	io->fd = fd;
	pthread_mutex_init(&io->lock, NULL);
}

static void xio_note(xio *io, const char *msg)
{
	pthread_mutex_lock(&io->lock);
	if (!io->quiet && !io->msg[0] && msg)
		snprintf(io->msg, sizeof io->msg, "%s", msg);
	pthread_mutex_unlock(&io->lock);
}

/* Read contexts only: exr_get_user_data locks a write context, and the
 * library may report while holding that lock. */
static void on_read_error(exr_const_context_t ctxt, exr_result_t code,
                          const char *msg)
{
	void *ud = NULL;
	(void)code;
	if (ctxt && exr_get_user_data(ctxt, &ud) == EXR_ERR_SUCCESS && ud)
		xio_note(ud, msg);
}

/* Write contexts: silent; our write callback records I/O errors itself,
 * and everything else the library could say there is our own misuse. */
static void on_write_error(exr_const_context_t ctxt, exr_result_t code,
                           const char *msg)
{
	(void)ctxt;
	(void)code;
	(void)msg;
}

static int64_t io_read(exr_const_context_t ctxt, void *ud, void *buffer,
                       uint64_t sz, uint64_t offset,
                       exr_stream_error_func_ptr_t error_cb)
{
	xio *io = ud;
	uint8_t *p = buffer;
	uint64_t done = 0;
	if (io->fd < 0 || offset > (uint64_t)INT64_MAX - sz) {
		if (error_cb)
			error_cb(ctxt, EXR_ERR_READ_IO, "read outside the file");
		return -1;
	}
	while (done < sz) {
		uint64_t left = sz - done;
		ssize_t n = pread(io->fd, p + done,
		                  (size_t)(left > (1u << 30) ? (1u << 30) : left),
		                  (off_t)(offset + done));
		if (n < 0 && errno == EINTR)
			continue;
		if (n < 0) {
			if (error_cb)
				error_cb(ctxt, EXR_ERR_READ_IO, "read error: %s",
				         strerror(errno));
			return -1;
		}
		if (n == 0)
			break; /* end of file: the library reports the short read */
		done += (uint64_t)n;
	}
	return (int64_t)done;
}

static int64_t io_size(exr_const_context_t ctxt, void *ud)
{
	(void)ctxt;
	return ((xio *)ud)->size;
}

static int64_t io_write(exr_const_context_t ctxt, void *ud, const void *buffer,
                        uint64_t sz, uint64_t offset,
                        exr_stream_error_func_ptr_t error_cb)
{
	xio *io = ud;
	const uint8_t *p = buffer;
	uint64_t done = 0;
	(void)error_cb;
	(void)ctxt;
	while (done < sz) {
		uint64_t left = sz - done;
		ssize_t n = pwrite(io->fd, p + done,
		                   (size_t)(left > (1u << 30) ? (1u << 30) : left),
		                   (off_t)(offset + done));
		if (n < 0 && errno == EINTR)
			continue;
		if (n <= 0) {
			char m[128];
			snprintf(m, sizeof m, "write error: %s",
			         n < 0 ? strerror(errno) : "no progress");
			xio_note(io, m);
			return -1;
		}
		done += (uint64_t)n;
	}
	return (int64_t)done;
}

/* "PATH: WHAT: <library's sentence> (<its detail>)". What the library
 * has not implemented (OpenEXRCore 3.1 neither decodes nor encodes DWAA
 * and DWAB) is SSS_ERR_UNSUPPORTED and names the library's version. */
static sss_result exr_fail(char *errbuf, size_t errbuf_len, const char *path,
                           const char *what, exr_result_t rv, xio *io)
{
	char detail[256], version[64] = "";
	pthread_mutex_lock(&io->lock);
	memcpy(detail, io->msg, sizeof detail);
	pthread_mutex_unlock(&io->lock);
	sss_result code = SSS_ERR_EXR;
	if (rv == EXR_ERR_OUT_OF_MEMORY)
		code = SSS_ERR_OUT_OF_MEMORY;
	if (rv == EXR_ERR_FEATURE_NOT_IMPLEMENTED) {
		int maj = 0, min = 0, patch = 0;
		const char *extra = NULL;
		exr_get_library_version(&maj, &min, &patch, &extra);
		snprintf(version, sizeof version, " [OpenEXRCore %d.%d.%d]", maj,
		         min, patch);
		code = SSS_ERR_UNSUPPORTED;
	}
	return FAILX(code, "%s: %s: %s%s%s%s%s", path, what,
	             exr_get_default_error_message(rv), detail[0] ? " (" : "",
	             detail, detail[0] ? ")" : "", version);
}

/* -------------------------------------------------------------- options */

void sss_exr_options_default(sss_exr_options *opt)
{
	if (!opt)
		return;
	memset(opt, 0, sizeof *opt);
	opt->struct_size = sizeof *opt;
	opt->max_width = 32768;
	opt->max_height = 32768;
	opt->max_pixels = (int64_t)1 << 28;
	opt->compression = SSS_EXR_ZIP;
	opt->num_threads = 0;
	opt->max_channels = 4096;
	opt->max_bytes = 0;
}

static sss_result get_options(const sss_exr_options *user, sss_exr_options *o,
                              char *errbuf, size_t errbuf_len)
{
	sss_exr_options_default(o);
	if (!user)
		return SSS_OK;
	/* ABI 8's struct ended before max_channels: its fields are read,
	 * the newer ones keep their defaults. */
	size_t old = offsetof(sss_exr_options, max_channels);
	if (user->struct_size != sizeof *user && user->struct_size != old)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "EXR options: struct_size "
		             "%u, expected %zu (use sss_exr_options_default)",
		             user->struct_size, sizeof *user);
	memcpy(o, user, user->struct_size);
	o->struct_size = sizeof *o;
	if (o->max_width < 1 || o->max_height < 1 || o->max_pixels < 1)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "EXR options: max_width %d, "
		             "max_height %d and max_pixels %lld must be >= 1",
		             o->max_width, o->max_height, (long long)o->max_pixels);
	if (o->compression < SSS_EXR_NONE || o->compression > SSS_EXR_DWAB)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "EXR options: unknown "
		             "compression %d", o->compression);
	if (o->num_threads < 0 || o->num_threads > 256)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "EXR options: num_threads "
		             "%d must be 0 (all cores) .. 256", o->num_threads);
	if (o->max_channels < 1 || o->max_bytes < 0)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "EXR options: max_channels "
		             "%d must be >= 1 and max_bytes %lld >= 0 (0: the "
		             "machine's memory)", o->max_channels,
		             (long long)o->max_bytes);
	return SSS_OK;
}

/* --------------------------------------------------------------- passes */

/* Canonical component order: R G B A X Y Z W U V, then by name. */
static int comp_rank(const char *c)
{
	static const char order[] = "RGBAXYZWUV";
	const char *p = c[0] && !c[1] ? strchr(order, c[0]) : NULL;
	return p ? (int)(p - order) : 10;
}

static int comp_cmp(const char *a, const char *b)
{
	int ra = comp_rank(a), rb = comp_rank(b);
	if (ra != rb)
		return ra < rb ? -1 : 1;
	return ra == 10 ? strcmp(a, b) : 0;
}

static char *dup_n(const char *s, size_t n)
{
	char *d = malloc(n + 1);
	if (d) {
		memcpy(d, s, n);
		d[n] = '\0';
	}
	return d;
}

static void pass_free(xpass *p)
{
	for (int32_t k = 0; k < p->count; k++) {
		free(p->chan[k].name);
		free(p->chan[k].raw);
	}
	free(p->chan);
	free(p->components);
	free(p->data);
	p->chan = NULL;
	p->components = NULL;
	p->data = NULL;
	p->count = 0;
}

void sss_exr_free(sss_exr *exr)
{
	if (!exr)
		return;
	for (int32_t i = 0; i < exr->pass_count; i++) {
		pass_free(&exr->passes[i]);
		free(exr->passes[i].layer);
		free(exr->passes[i].pass);
	}
	free(exr->passes);
	if (exr->header)
		exr_finish(&exr->header);
	pthread_mutex_destroy(&exr->io.lock);
	free(exr->path);
	free(exr);
}

static xpass *find_pass(const sss_exr *exr, const char *layer,
                        const char *pass)
{
	for (int32_t i = 0; i < exr->pass_count; i++)
		if (strcmp(exr->passes[i].layer, layer) == 0 &&
		    strcmp(exr->passes[i].pass, pass) == 0)
			return &exr->passes[i];
	return NULL;
}

/* Blender 5.0 names render passes in full ("Diffuse Direct" where 3.x and
 * 4.x write "DiffDir"); the library asks by the short names and reads
 * either. */
static const char *const full_pass_names[][2] = {
	{"DiffDir", "Diffuse Direct"},        {"DiffInd", "Diffuse Indirect"},
	{"DiffCol", "Diffuse Color"},         {"GlossDir", "Glossy Direct"},
	{"GlossInd", "Glossy Indirect"},      {"GlossCol", "Glossy Color"},
	{"TransDir", "Transmission Direct"},  {"TransInd", "Transmission Indirect"},
	{"TransCol", "Transmission Color"},   {"Emit", "Emission"},
	{"Env", "Environment"},               {"IndexMA", "Material Index"},
};

static const char *full_pass_name(const char *pass)
{
	for (size_t i = 0; i < sizeof full_pass_names / sizeof *full_pass_names;
	     i++)
		if (strcmp(full_pass_names[i][0], pass) == 0)
			return full_pass_names[i][1];
	return NULL;
}

/* A render pass by its short name, or by Blender 5.0's full name. */
static const xpass *find_render_pass(const sss_exr *exr, const char *layer,
                                     const char *pass)
{
	const xpass *p = find_pass(exr, layer, pass);
	const char *full = p ? NULL : full_pass_name(pass);
	return full ? find_pass(exr, layer, full) : p;
}

/* A new, empty pass at the end (names copied); NULL when out of memory. */
static xpass *append_pass(sss_exr *exr, const char *layer, size_t layer_len,
                          const char *pass, size_t pass_len)
{
	if (exr->pass_count == exr->pass_cap) {
		int32_t cap = exr->pass_cap ? 2 * exr->pass_cap : 16;
		xpass *grown = realloc(exr->passes, (size_t)cap * sizeof *grown);
		if (!grown)
			return NULL;
		exr->passes = grown;
		exr->pass_cap = cap;
	}
	xpass *p = &exr->passes[exr->pass_count];
	memset(p, 0, sizeof *p);
	p->layer = dup_n(layer, layer_len);
	p->pass = dup_n(pass, pass_len);
	if (!p->layer || !p->pass) {
		free(p->layer);
		free(p->pass);
		return NULL;
	}
	exr->pass_count++;
	return p;
}

/* The API's component string: "RGB", or "red,green" for longer names. */
static int make_components(xpass *p)
{
	size_t len = 1;
	int single = 1;
	for (int32_t k = 0; k < p->count; k++) {
		len += strlen(p->chan[k].comp) + 1;
		if (strlen(p->chan[k].comp) != 1)
			single = 0;
	}
	free(p->components);
	p->components = malloc(len);
	if (!p->components)
		return -1;
	char *o = p->components;
	for (int32_t k = 0; k < p->count; k++) {
		if (!single && k > 0)
			*o++ = ',';
		size_t n = strlen(p->chan[k].comp);
		memcpy(o, p->chan[k].comp, n);
		o += n;
	}
	*o = '\0';
	return 0;
}

/* Splits a channel name from the end, as Blender does: the component
 * after the last dot, the pass between the dot before it and that one,
 * and the layer is all before (Blender's own copies of a view layer are
 * "ViewLayer.001": "ViewLayer.001.DiffDir.R" is that layer's DiffDir.R).
 * One dot: just the pass ("DiffDir.R", File Output node naming). */
static void split_name(const char *name, const char **layer, size_t *layer_len,
                       const char **pass, size_t *pass_len, const char **comp)
{
	const char *last = strrchr(name, '.');
	*layer = *pass = "";
	*layer_len = *pass_len = 0;
	if (!last) {
		*comp = name;
		return;
	}
	*comp = last + 1;
	const char *mid = last;
	while (mid > name && mid[-1] != '.')
		mid--;
	if (mid > name) {
		*layer = name;
		*layer_len = (size_t)(mid - 1 - name);
		*pass = mid;
		*pass_len = (size_t)(last - mid);
	} else {
		*pass = name;
		*pass_len = (size_t)(last - name);
	}
}

/* A channel's name as the library names it: in a multi-part file (Blender
 * 5.0 writes one part per pass, named "ViewLayer.Combined"), a channel
 * not already under its part's name is put under it ("R" in part
 * "ViewLayer.Combined" is "ViewLayer.Combined.R"), so that names stay
 * unique across parts. Malloc'ed; NULL when out of memory. */
static char *qualified_name(const sss_exr *exr, int part, const char *name)
{
	const char *part_name = NULL;
	if (exr->part_count < 2 ||
	    exr_get_name(exr->header, part, &part_name) != EXR_ERR_SUCCESS ||
	    !part_name || !part_name[0])
		return dup_n(name, strlen(name));
	size_t n = strlen(part_name), len = strlen(name);
	if (len > n && memcmp(name, part_name, n) == 0 && name[n] == '.')
		return dup_n(name, len);
	char *q = malloc(n + 1 + len + 1);
	if (q)
		snprintf(q, n + 1 + len + 1, "%s.%s", part_name, name);
	return q;
}

/* The passes by (layer, pass) while channels are grouped: open
 * addressing over pass numbers, so that grouping stays linear in the
 * channel count (a scan per channel took 32 s for 65k channels). */
typedef struct pass_index {
	int32_t *slot; /* pass number, -1 empty */
	size_t mask;   /* slots - 1, slots a power of two */
} pass_index;

static size_t pass_hash(const char *layer, size_t layer_len, const char *pass,
                        size_t pass_len)
{
	size_t h = 1469598103934665603u & SIZE_MAX;
	for (size_t i = 0; i < layer_len; i++)
		h = (h ^ (unsigned char)layer[i]) * 1099511628211u;
	h = (h ^ 0xff) * 1099511628211u; /* "a.b" + "c" is not "a" + "b.c" */
	for (size_t i = 0; i < pass_len; i++)
		h = (h ^ (unsigned char)pass[i]) * 1099511628211u;
	return h;
}

/* The slot of (layer, pass): its pass, or the empty slot it would take. */
static size_t pass_slot(const sss_exr *exr, const pass_index *ix,
                        const char *layer, size_t layer_len,
                        const char *pass, size_t pass_len)
{
	size_t i = pass_hash(layer, layer_len, pass, pass_len) & ix->mask;
	for (;; i = (i + 1) & ix->mask) {
		int32_t j = ix->slot[i];
		if (j < 0)
			return i;
		const xpass *q = &exr->passes[j];
		if (strlen(q->layer) == layer_len &&
		    memcmp(q->layer, layer, layer_len) == 0 &&
		    strlen(q->pass) == pass_len &&
		    memcmp(q->pass, pass, pass_len) == 0)
			return i;
	}
}

/* Source channel `index` (entry e of part `part`) into its pass. */
static sss_result add_channel(sss_exr *exr, pass_index *ix,
                              const exr_attr_chlist_entry_t *e, int part,
                              int32_t index, char *errbuf, size_t errbuf_len)
{
	const char *source = e->name.str;
	if (e->x_sampling != 1 || e->y_sampling != 1)
		return FAILX(SSS_ERR_UNSUPPORTED, "%s: channel '%s' is subsampled "
		             "(%dx%d); only full-resolution channels are supported",
		             exr->path, source, e->x_sampling, e->y_sampling);
	if (e->pixel_type != EXR_PIXEL_UINT && e->pixel_type != EXR_PIXEL_HALF &&
	    e->pixel_type != EXR_PIXEL_FLOAT)
		return FAILX(SSS_ERR_EXR, "%s: channel '%s' has unknown pixel type "
		             "%d", exr->path, source, (int)e->pixel_type);
	char *name = qualified_name(exr, part, source);
	if (!name)
		return FAILX(SSS_ERR_OUT_OF_MEMORY, "%s: out of memory", exr->path);
	const char *layer, *pass, *comp;
	size_t layer_len, pass_len;
	split_name(name, &layer, &layer_len, &pass, &pass_len, &comp);

	size_t slot = pass_slot(exr, ix, layer, layer_len, pass, pass_len);
	xpass *p = ix->slot[slot] >= 0 ? &exr->passes[ix->slot[slot]] : NULL;
	if (!p && !(p = append_pass(exr, layer, layer_len, pass, pass_len))) {
		free(name);
		return FAILX(SSS_ERR_OUT_OF_MEMORY, "%s: out of memory", exr->path);
	}
	ix->slot[slot] = (int32_t)(p - exr->passes);

	/* Insertion in canonical order; names map to (layer, pass, component)
	 * one way only except for odd leading dots, so a clash (also of two
	 * parts' channels) is refused rather than one channel silently lost. */
	int32_t at = p->count;
	while (at > 0 && comp_cmp(comp, p->chan[at - 1].comp) < 0)
		at--;
	if (at > 0 && comp_cmp(comp, p->chan[at - 1].comp) == 0) {
		sss_result r = FAILX(SSS_ERR_UNSUPPORTED, "%s: channels '%s' and "
		                     "'%s' are the same component of one pass",
		                     exr->path, p->chan[at - 1].name, name);
		free(name);
		return r;
	}
	xchan *grown = realloc(p->chan, (size_t)(p->count + 1) * sizeof *grown);
	if (!grown) {
		free(name);
		return FAILX(SSS_ERR_OUT_OF_MEMORY, "%s: out of memory", exr->path);
	}
	p->chan = grown;
	memmove(&p->chan[at + 1], &p->chan[at],
	        (size_t)(p->count - at) * sizeof *p->chan);
	p->chan[at] = (xchan){name, comp, (int32_t)e->pixel_type, e->p_linear,
	                      index, NULL};
	p->count++;
	return SSS_OK;
}

/* Groups the source's channels, part by part, into passes (in
 * channel-list order), components sorted canonically. Pixel buffers are
 * allocated later. */
static sss_result group_channels(sss_exr *exr, int32_t max_channels,
                                 char *errbuf, size_t errbuf_len)
{
	int32_t index = 0;
	int64_t total = 0;
	for (int part = 0; part < exr->part_count; part++) {
		const exr_attr_chlist_t *cl = NULL;
		exr_result_t rv = exr_get_channels(exr->header, part, &cl);
		if (rv != EXR_ERR_SUCCESS)
			return exr_fail(errbuf, errbuf_len, exr->path, "reading the "
			                "channel list", rv, &exr->io);
		/* Decoding counts a part's channels in 16 bits too. */
		if (cl->num_channels > sss__exr_max_channels())
			return FAILX(SSS_ERR_UNSUPPORTED, "%s: part %d has %d "
			             "channels, more than the %d the OpenEXR in use "
			             "decodes in one part", exr->path, part,
			             cl->num_channels, sss__exr_max_channels());
		total += cl->num_channels;
	}
	/* From the header, before anything is allocated per channel. */
	if (total > max_channels)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "%s: %lld channels, more "
		             "than the limit of %d (raise it with sss "
		             "--max-channels, or sss_exr_options.max_channels)",
		             exr->path, (long long)total, max_channels);
	pass_index ix = {NULL, 0};
	size_t slots = 16;
	while (slots < 2 * (size_t)total)
		slots *= 2;
	if (!(ix.slot = malloc(slots * sizeof *ix.slot)))
		return FAILX(SSS_ERR_OUT_OF_MEMORY, "%s: out of memory", exr->path);
	memset(ix.slot, 0xff, slots * sizeof *ix.slot);
	ix.mask = slots - 1;
	sss_result r = SSS_OK;
	for (int part = 0; part < exr->part_count && !r; part++) {
		const exr_attr_chlist_t *cl = NULL;
		exr_get_channels(exr->header, part, &cl);
		for (int i = 0; i < cl->num_channels && !r; i++, index++)
			r = add_channel(exr, &ix, &cl->entries[i], part, index, errbuf,
			                errbuf_len);
	}
	free(ix.slot);
	if (r)
		return r;
	for (int32_t j = 0; j < exr->pass_count; j++)
		if (make_components(&exr->passes[j]))
			return FAILX(SSS_ERR_OUT_OF_MEMORY, "%s: out of memory",
			             exr->path);
	return SSS_OK;
}

/* ------------------------------------------------------------- decoding */

/* Where one source channel lands: its pass's buffer and component, and
 * a uint channel's own plane (decoded there, then converted). */
typedef struct chan_ref {
	float *data;
	int32_t count, k;
	uint32_t *raw;
} chan_ref;

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
static int grow(uint8_t **buf, size_t *cap, size_t n)
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
	if (!grow(&z->scratch, &z->cap, n))
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
	init.error_handler_fn = on_read_error;
	init.user_data = io;
	init.read_fn = io_read;
	init.size_fn = io_size;
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
		return exr_fail(errbuf, errbuf_len, exr->path, "reading the header",
		                rv, &exr->io);
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
		return exr_fail(errbuf, errbuf_len, path, "reading the header", rv,
		                &exr->io);
	exr->part_count = parts;
	sss_result r;
	exr_attr_box2i_t dw;
	for (int part = 0; part < parts; part++) {
		exr_attr_box2i_t pw;
		if ((r = check_storage(exr, part, errbuf, errbuf_len)))
			return r;
		if ((rv = exr_get_data_window(c, part, &pw)) != EXR_ERR_SUCCESS)
			return exr_fail(errbuf, errbuf_len, path, "reading the data "
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
		return exr_fail(errbuf, errbuf_len, path, "reading the chunk "
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
	return exr_fail(errbuf, errbuf_len, path, what, job.rv, &exr->io);
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
			r = exr_fail(errbuf, errbuf_len, path, "reading the channel "
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
	if ((r = get_options(opt, &o, errbuf, errbuf_len)))
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
	if (!exr || !(exr->path = dup_n(path, strlen(path)))) {
		free(exr);
		close(fd);
		return FAILX(SSS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
	}
	xio_init(&exr->io, fd);
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
			r = exr_fail(errbuf, errbuf_len, path, "not a readable "
			             "OpenEXR file", rv, &exr->io);
	} else if (!(r = read_header(exr, &o, errbuf, errbuf_len)) &&
	           !(r = group_channels(exr, o.max_channels, errbuf,
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

int32_t sss_exr_width(const sss_exr *exr)
{
	return exr ? exr->width : 0;
}

int32_t sss_exr_height(const sss_exr *exr)
{
	return exr ? exr->height : 0;
}

int32_t sss_exr_pass_count(const sss_exr *exr)
{
	return exr ? exr->pass_count : 0;
}

static sss_image view_of(const sss_exr *exr, const xpass *p, int32_t first)
{
	sss_image v = {p->data + first, exr->width, exr->height, p->count, 0};
	return v;
}

sss_result sss_exr_pass(const sss_exr *exr, int32_t i, const char **layer,
                        const char **pass, const char **components,
                        sss_image *view)
{
	if (!exr || i < 0 || i >= exr->pass_count)
		return SSS_ERR_INVALID_ARGUMENT;
	const xpass *p = &exr->passes[i];
	if (layer)
		*layer = p->layer;
	if (pass)
		*pass = p->pass;
	if (components)
		*components = p->components;
	if (view)
		*view = view_of(exr, p, 0);
	return SSS_OK;
}

sss_result sss_exr_find(const sss_exr *exr, const char *layer,
                        const char *pass, sss_image *view)
{
	if (!exr)
		return SSS_ERR_INVALID_ARGUMENT;
	const xpass *p = find_render_pass(exr, layer ? layer : "",
	                                  pass ? pass : "");
	if (!p)
		return SSS_ERR_MISSING_PASS;
	if (view)
		*view = view_of(exr, p, 0);
	return SSS_OK;
}

/* ------------------------------------------- for sss_render_passes.c */

const char *sss__exr_path(const sss_exr *exr)
{
	return exr->path;
}

static exr_result_t source_attributes(const sss_exr *exr,
                                      const exr_attribute_t ***list,
                                      int32_t *count);

int sss__exr_has_attribute_prefix(const sss_exr *exr, const char *prefix)
{
	const exr_attribute_t **attrs = NULL;
	int32_t n = 0, found = 0;
	if (source_attributes(exr, &attrs, &n) == EXR_ERR_SUCCESS)
		for (int32_t i = 0; i < n && !found; i++)
			found = strncmp(attrs[i]->name, prefix, strlen(prefix)) == 0;
	free(attrs);
	return found;
}

int64_t sss__exr_channel_count(const sss_exr *exr)
{
	int64_t n = 0;
	for (int32_t j = 0; j < exr->pass_count; j++)
		n += exr->passes[j].count;
	return n;
}

/* OpenEXRCore 3.1 holds a part's channel count in the coding pipelines'
 * int16_t channel_count: past 32767 the chunks were written empty or
 * scrambled with exit 0. The type of that field says the ceiling. */
int32_t sss__exr_max_channels(void)
{
	exr_encode_pipeline_t e;
	(void)e;
	return sizeof e.channel_count >= 4 ? INT32_MAX
	       : (int32_t)((1L << (8 * sizeof e.channel_count - 1)) - 1);
}

/* ------------------------------------------------------------ add pass */

sss_result sss_exr_add_pass(sss_exr *exr, const char *layer, const char *pass,
                            const char *components, const float *data,
                            char *errbuf, size_t errbuf_len)
{
	if (errbuf && errbuf_len)
		errbuf[0] = '\0';
	if (!exr || !data || !components || !components[0])
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "sss_exr_add_pass: %s",
		             !exr ? "exr is NULL" : !data ? "data is NULL"
		                                          : "no components");
	layer = layer ? layer : "";
	pass = pass ? pass : "";
	/* Names must read back as the same layer and pass (split_name reads
	 * from the end: a layer may hold dots, a pass may not). */
	if (strchr(pass, '.'))
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "pass name '%s' must not "
		             "contain a dot", pass);
	size_t n = strlen(components);
	if (strlen(layer) + strlen(pass) + 3 > MAX_NAME)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "layer and pass names "
		             "'%s.%s' are too long for EXR channel names", layer,
		             pass);
	for (size_t i = 0; i < n; i++)
		if (components[i] == '.' || strchr(components + i + 1,
		                                   components[i]))
			return FAILX(SSS_ERR_INVALID_ARGUMENT, "components '%s': "
			             "'%c' is %s", components, components[i],
			             components[i] == '.' ? "not a component name"
			                                  : "repeated");
	if ((int64_t)exr->width * (int64_t)n * (int64_t)sizeof(float) >
	    INT32_MAX)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "components '%s': too many "
		             "for a %d pixel wide image", components, exr->width);

	/* Everything new is built first; exr changes only on success. */
	size_t npix = (size_t)exr->width * (size_t)exr->height;
	xpass np = {NULL, NULL, NULL, (int32_t)n, NULL, NULL};
	int32_t order[256];
	if (n > 256)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "components '%s': more "
		             "than 256", components);
	for (int32_t k = 0; k < (int32_t)n; k++) {
		/* canonical order, as for passes read from files */
		char a[2] = {components[k], '\0'};
		int32_t at = k;
		while (at > 0) {
			char b[2] = {components[order[at - 1]], '\0'};
			if (comp_cmp(a, b) >= 0)
				break;
			order[at] = order[at - 1];
			at--;
		}
		order[at] = k;
	}
	np.chan = calloc(n, sizeof *np.chan);
	np.data = npix <= SIZE_MAX / sizeof(float) / n
	          ? malloc(npix * n * sizeof(float)) : NULL;
	int ok = np.chan && np.data;
	for (size_t k = 0; ok && k < n; k++) {
		size_t len = strlen(layer) + strlen(pass) + 4;
		char *name = malloc(len);
		if (!(ok = name != NULL))
			break;
		char c = components[order[k]];
		if (layer[0])
			snprintf(name, len, "%s.%s.%c", layer, pass, c);
		else if (pass[0])
			snprintf(name, len, "%s.%c", pass, c);
		else
			snprintf(name, len, "%c", c);
		np.chan[k] = (xchan){name, name + strlen(name) - 1,
		                     EXR_PIXEL_FLOAT, 0, -1, NULL};
	}
	ok = ok && make_components(&np) == 0;
	xpass *slot = find_pass(exr, layer, pass);
	if (ok && !slot)
		ok = (slot = append_pass(exr, layer, strlen(layer), pass,
		                         strlen(pass))) != NULL;
	if (!ok) {
		if (!np.chan)
			np.count = 0;
		pass_free(&np);
		return FAILX(SSS_ERR_OUT_OF_MEMORY, "cannot add pass '%s.%s' "
		             "(%dx%d x %zu floats)", layer, pass, exr->width,
		             exr->height, n);
	}
	for (size_t i = 0; i < npix; i++)
		for (size_t k = 0; k < n; k++)
			np.data[i * n + k] = data[i * n + (size_t)order[k]];
	/* Replacing keeps the layer and pass strings, so names handed out
	 * by sss_exr_pass or sss_exr_render_passes stay valid. */
	pass_free(slot);
	slot->components = np.components;
	slot->count = np.count;
	slot->chan = np.chan;
	slot->data = np.data;
	return SSS_OK;
}

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

/* The source's attributes, file order; *list is malloc'ed. */
static exr_result_t source_attributes(const sss_exr *exr,
                                      const exr_attribute_t ***list,
                                      int32_t *count)
{
	*list = NULL;
	*count = 0;
	exr_result_t rv = exr_get_attribute_list(
		exr->header, 0, EXR_ATTR_LIST_FILE_ORDER, count, NULL);
	if (rv != EXR_ERR_SUCCESS || *count <= 0)
		return rv;
	*list = malloc((size_t)*count * sizeof **list);
	if (!*list)
		return EXR_ERR_OUT_OF_MEMORY;
	return exr_get_attribute_list(exr->header, 0, EXR_ATTR_LIST_FILE_ORDER,
	                              count, *list);
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
	if (!grow(&z->scratch, &z->cap, n))
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
static sss_result write_file(const sss_exr *exr, const sss_exr_options *o,
                             const char *path, const char *tmp, xio *io,
                             char *errbuf, size_t errbuf_len)
{
	exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
	init.error_handler_fn = on_write_error;
	init.user_data = io;
	init.write_fn = io_write;
	init.alloc_fn = write_alloc;
	init.free_fn = write_free;
	exr_context_t c = NULL;
	const exr_attribute_t **attrs = NULL;
	int32_t nattrs = 0, bad_y = 0;
	int part = 0;
	char step[160] = "reading the source header";
	exr_result_t rv = source_attributes(exr, &attrs, &nattrs);

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
		return exr_fail(errbuf, errbuf_len, path, step, rv, io);
	return SSS_OK;
}

/* ------------------------------------------------- output and temporary */

static int create_locked_temp(const char *path, char **out);

/* The output's folder takes a new file: a temporary is created there and
 * removed at once (signals wait meanwhile), so that a read-only folder,
 * file system or a full inode table is said before any work, for root
 * too (access() would let root through). */
static sss_result check_folder(const char *path, char *errbuf,
                               size_t errbuf_len)
{
	sigset_t all, old;
	char *t = NULL;
	sigfillset(&all);
	pthread_sigmask(SIG_BLOCK, &all, &old);
	int fd = create_locked_temp(path, &t);
	int e = errno;
	if (fd >= 0) {
		unlink(t);
		close(fd);
	}
	pthread_sigmask(SIG_SETMASK, &old, NULL);
	free(t);
	if (fd >= 0)
		return SSS_OK;
	const char *slash = strrchr(path, '/');
	int n = slash ? (slash == path ? 1 : (int)(slash - path)) : 1;
	return FAILX(e == ENOMEM ? SSS_ERR_OUT_OF_MEMORY : SSS_ERR_IO,
	             "%s: its folder %.*s is not writable: %s", path, n,
	             slash ? path : ".", strerror(e));
}

sss_result sss_exr_check_output(const char *path, char *errbuf,
                                size_t errbuf_len)
{
	if (errbuf && errbuf_len)
		errbuf[0] = '\0';
	if (!path || !path[0])
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "the output path is empty");
	size_t len = strlen(path);
	if (path[len - 1] == '/')
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "%s: names a directory",
		             path);
	struct stat st;
	if (lstat(path, &st) != 0) {
		int e = errno;
		if (e != ENOENT)
			return FAILX(SSS_ERR_IO, "%s: %s", path, strerror(e));
		/* Absent: its folder must exist (said now, not after the work). */
		const char *slash = strrchr(path, '/');
		if (!slash)
			return SSS_OK;
		char *dir = dup_n(path, slash == path ? 1 : (size_t)(slash - path));
		if (!dir)
			return FAILX(SSS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
		int bad = stat(dir, &st) != 0 ? errno
		          : S_ISDIR(st.st_mode) ? 0 : ENOTDIR;
		sss_result r = bad ? FAILX(SSS_ERR_IO, "%s: its folder %s: %s",
		                           path, dir, strerror(bad)) : SSS_OK;
		free(dir);
		return r ? r : check_folder(path, errbuf, errbuf_len);
	}
	if (S_ISLNK(st.st_mode)) {
		char target[512];
		ssize_t n = readlink(path, target, sizeof target - 1);
		target[n > 0 ? n : 0] = '\0';
		return FAILX(SSS_ERR_IO, "%s: is a symbolic link (to %s); outputs "
		             "replace regular files only and never write through a "
		             "link: give the path of the file itself", path,
		             n > 0 ? target : "?");
	}
	if (!S_ISREG(st.st_mode))
		return FAILX(SSS_ERR_IO, "%s: is %s, not a regular file; it is not "
		             "replaced", path, sss__file_kind(st.st_mode));
	/* The permission bits as well as access(): root may write anything. */
	if (!(st.st_mode & 0222) || access(path, W_OK) != 0)
		return FAILX(SSS_ERR_IO, "%s: is read-only (mode %04o); it is not "
		             "replaced", path, (unsigned)(st.st_mode & 07777));
	return check_folder(path, errbuf, errbuf_len);
}

/* Temporaries are "<dir>/.<name>.tmp-<pid>-<hex>" beside their output (so
 * the final rename is atomic), the name cut to 128 bytes to stay under
 * NAME_MAX; create_temp and remove_stale_temporaries both build the
 * prefix here. Returns the prefix's length, or -1 if it does not fit. */
#define TEMP_NAME_MAX 128
static int temp_prefix(const char *path, char *out, size_t cap,
                       size_t *dir_len)
{
	const char *slash = strrchr(path, '/');
	*dir_len = slash ? (size_t)(slash - path) + 1 : 0;
	size_t base_len = strlen(path + *dir_len);
	if (base_len > TEMP_NAME_MAX)
		base_len = TEMP_NAME_MAX;
	int n = snprintf(out, cap, "%.*s.%.*s.tmp-", (int)*dir_len, path,
	                 (int)base_len, path + *dir_len);
	return n >= 0 && (size_t)n < cap ? n : -1;
}

/* FNV-1a, 32 bits, over a then b. */
static uint32_t name_check(const char *a, size_t a_len, const char *b,
                           size_t b_len)
{
	uint32_t h = 2166136261u;
	for (size_t i = 0; i < a_len + b_len; i++) {
		h ^= (unsigned char)(i < a_len ? a[i] : b[i - a_len]);
		h *= 16777619u;
	}
	return h;
}

/* What create_temp appends to the name (its prefix without the folder):
 * "<pid>-<8 hex id><8 hex check>", the check being name_check of the
 * name up to the check. A file that merely looks like a temporary (an
 * input or scene someone named ".o.exr.tmp-1-ab") lacks it, and is never
 * taken for one. */
static void temp_suffix(const char *name, size_t name_len, long pid,
                        unsigned long id, char *out, size_t cap)
{
	char head[64];
	snprintf(head, sizeof head, "%ld-%08lx", pid, id & 0xffffffffUL);
	snprintf(out, cap, "%s%08lx", head,
	         (unsigned long)name_check(name, name_len, head, strlen(head)));
}

static int is_temp_suffix(const char *name, size_t name_len, const char *s)
{
	const char *p = s;
	while (*p >= '0' && *p <= '9')
		p++;
	if (p == s || p - s > 20 || *p++ != '-' || strlen(p) != 16)
		return 0;
	for (const char *q = p; *q; q++)
		if (!((*q >= '0' && *q <= '9') || (*q >= 'a' && *q <= 'f')))
			return 0;
	char want[64];
	temp_suffix(name, name_len, strtol(s, NULL, 10),
	            strtoul((char[9]){p[0], p[1], p[2], p[3], p[4], p[5], p[6],
	                              p[7], 0}, NULL, 16), want, sizeof want);
	return strcmp(want, s) == 0;
}

static int same_file(const struct stat *a, const struct stat *b)
{
	return a->st_dev == b->st_dev && a->st_ino == b->st_ino;
}

/* Removes the temporaries that stopped writers left for path. A writer
 * holds an exclusive flock on its temporary until it is renamed, so a
 * temporary whose lock can be taken has no live writer, whatever host or
 * PID namespace wrote it (a PID says nothing across those); it is
 * removed only while that lock is held and the name is still that file,
 * and only if its name carries create_temp's check (temp_suffix) and it
 * is not the file being written from. */
static void remove_stale_temporaries(const char *path, const sss_exr *exr)
{
	size_t cap = strlen(path) + 64, dir_len;
	char *prefix = malloc(cap), *full = malloc(cap + 256 + NAME_MAX);
	int n = prefix ? temp_prefix(path, prefix, cap, &dir_len) : -1;
	DIR *d = NULL;
	if (n >= 0 && full) {
		snprintf(full, cap, "%.*s", (int)(dir_len ? dir_len : 2),
		         dir_len ? prefix : "./");
		d = opendir(full);
	}
	const char *name = n >= 0 ? prefix + dir_len : NULL;
	size_t name_len = n >= 0 ? (size_t)n - dir_len : 0;
	struct dirent *e;
	while (d && (e = readdir(d))) {
		if (strncmp(e->d_name, name, name_len) != 0 ||
		    !is_temp_suffix(name, name_len, e->d_name + name_len))
			continue;
		snprintf(full, cap + 256 + NAME_MAX, "%.*s%s", (int)dir_len, path,
		         e->d_name);
		int fd = open(full, O_RDONLY | O_NONBLOCK | O_NOFOLLOW | O_CLOEXEC);
		if (fd < 0)
			continue;
		struct stat held, now;
		if (fstat(fd, &held) == 0 && S_ISREG(held.st_mode) &&
		    !(held.st_dev == exr->dev && held.st_ino == exr->ino) &&
		    flock(fd, LOCK_EX | LOCK_NB) == 0 && lstat(full, &now) == 0 &&
		    same_file(&held, &now))
			unlink(full);
		close(fd); /* releases the lock */
	}
	if (d)
		closedir(d);
	free(prefix);
	free(full);
}

/* create_temp's work: a unique name beside path, opened and locked. */
static int create_locked_temp(const char *path, char **out)
{
	size_t dir_len, cap = strlen(path) + 64;
	char *t = malloc(cap);
	int n = t ? temp_prefix(path, t, cap, &dir_len) : -1;
	if (n < 0) {
		free(t);
		errno = ENOMEM;
		return -1;
	}
	struct timespec ts;
	clock_gettime(CLOCK_REALTIME, &ts);
	/* Time and this call's buffer address: distinct across threads. */
	unsigned long id = (unsigned long)ts.tv_nsec ^ (unsigned long)(uintptr_t)t;
	for (int attempt = 0; attempt < 64; attempt++, id += 7919) {
		temp_suffix(t + dir_len, (size_t)n - dir_len, (long)getpid(), id,
		            t + n, cap - (size_t)n);
		int fd = open(t, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
		if (fd < 0 && errno == EEXIST)
			continue;
		if (fd < 0)
			break;
		/* A cleaner may have taken it between open and flock, to remove
		 * it: then it is not ours any more; take another name. A file
		 * system without locks keeps the file unlocked (and safe from
		 * cleaners, which need the lock). */
		struct stat mine, named;
		int locked = flock(fd, LOCK_EX | LOCK_NB) == 0;
		if ((!locked && errno == EWOULDBLOCK) || fstat(fd, &mine) != 0 ||
		    stat(t, &named) != 0 || !same_file(&mine, &named)) {
			close(fd);
			continue;
		}
		*out = t;
		return fd;
	}
	int e = errno;
	free(t);
	errno = e;
	return -1;
}

/* Creates a new, unique, empty temporary for path, takes its lock and
 * tells o->temporary_fn. O_EXCL makes it ours alone; mode 0666 less the
 * umask, as any new file. Signals wait while this runs (the calling
 * thread's mask, restored), so that a handler that removes the announced
 * temporary never finds one that exists but was not yet announced. */
static int create_temp(const char *path, const sss_exr_options *o,
                       char **out)
{
	sigset_t all, old;
	sigfillset(&all);
	pthread_sigmask(SIG_BLOCK, &all, &old);
	int fd = create_locked_temp(path, out);
	int e = errno;
	if (fd >= 0 && o->temporary_fn)
		o->temporary_fn(*out, o->temporary_user);
	pthread_sigmask(SIG_SETMASK, &old, NULL);
	errno = e;
	return fd;
}

sss_result sss_exr_write(const sss_exr *exr, const char *path,
                         const sss_exr_options *opt, char *errbuf,
                         size_t errbuf_len)
{
	sss_exr_options o;
	sss_result r;
	if (errbuf && errbuf_len)
		errbuf[0] = '\0';
	if (!exr)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "sss_exr_write: exr is NULL");
	if ((r = get_options(opt, &o, errbuf, errbuf_len)))
		return r;
	if (exr->pass_count == 0)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "%s: the image has no "
		             "channels to write", path && path[0] ? path : "output");
	int64_t channels = sss__exr_channel_count(exr);
	if (channels > sss__exr_max_channels())
		return FAILX(SSS_ERR_UNSUPPORTED, "%s: %lld channels, more than "
		             "the %d one file can hold with this OpenEXR; nothing "
		             "was written", path && path[0] ? path : "output",
		             (long long)channels, sss__exr_max_channels());

	/* Same device and inode as the source (any name or link to it):
	 * refused, so a failed or partial run never loses a render. */
	struct stat st;
	if (path && stat(path, &st) == 0 && st.st_dev == exr->dev &&
	    st.st_ino == exr->ino)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "%s: is the file this image "
		             "was read from (%s); refusing to overwrite it", path,
		             exr->path);
	if ((r = sss_exr_check_output(path, errbuf, errbuf_len)))
		return r;

	remove_stale_temporaries(path, exr);
	char *tmp = NULL;
	int fd = create_temp(path, &o, &tmp);
	if (fd < 0)
		return FAILX(errno == ENOMEM ? SSS_ERR_OUT_OF_MEMORY : SSS_ERR_IO,
		             "%s: cannot create a temporary file in its directory: "
		             "%s", path, strerror(errno));
	/* A replaced output keeps its permission bits (and, for root, its
	 * owner). Its hard links are not kept: the rename that makes the
	 * write atomic gives the name a new file. */
	struct stat old;
	if (lstat(path, &old) == 0 && S_ISREG(old.st_mode)) {
		fchmod(fd, old.st_mode & 07777);
		if (geteuid() == 0 && fchown(fd, old.st_uid, old.st_gid) == 0)
			fchmod(fd, old.st_mode & 07777); /* chown drops set-id */
	}
	xio io;
	xio_init(&io, fd);
	r = write_file(exr, &o, path, tmp, &io, errbuf, errbuf_len);
	/* Renamed before the close releases the lock, so that no cleaner
	 * takes a complete temporary for a stale one. */
	int renamed = !r && rename(tmp, path) == 0;
	if (!r && !renamed)
		r = FAILX(SSS_ERR_IO, "%s: cannot rename %s to it: %s", path, tmp,
		          strerror(errno));
	if (close(fd) && !r) { /* a late write error (network file systems) */
		r = FAILX(SSS_ERR_IO, "%s: writing: %s", path, strerror(errno));
		unlink(path);
	} else if (r && !renamed) {
		unlink(tmp); /* path itself was never touched */
	}
	if (o.temporary_fn)
		o.temporary_fn(NULL, o.temporary_user);
	pthread_mutex_destroy(&io.lock);
	free(tmp);
	return r;
}

/* Removes every pass of `layer` (what sss_frame_write added once the file
 * is written, so that a frame kept for re-tunes holds only the render's
 * passes). Views of other passes stay valid. */
void sss__exr_remove_layer(sss_exr *exr, const char *layer)
{
	int32_t kept = 0;
	for (int32_t i = 0; i < exr->pass_count; i++) {
		xpass *p = &exr->passes[i];
		if (strcmp(p->layer, layer) == 0) {
			pass_free(p);
			free(p->layer);
			free(p->pass);
			continue;
		}
		exr->passes[kept++] = *p;
	}
	exr->pass_count = kept;
}
