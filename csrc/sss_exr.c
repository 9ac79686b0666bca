/* sss_exr.c - the in-memory pass model of a multilayer EXR: its
 * options, the passes grouped from the channels' names, lookups, added and
 * removed passes and the header's attributes. Decoding is
 * sss_exr_decode.c, encoding sss_exr_encode.c, where the file goes
 * sss_exr_output.c. */
#include "sss_exr_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

sss_result sss__exr_get_options(const sss_exr_options *user,
                                sss_exr_options *o, char *errbuf,
                                size_t errbuf_len)
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

char *sss__exr_dup_n(const char *s, size_t n)
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
	p->layer = sss__exr_dup_n(layer, layer_len);
	p->pass = sss__exr_dup_n(pass, pass_len);
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
		return sss__exr_dup_n(name, strlen(name));
	size_t n = strlen(part_name), len = strlen(name);
	if (len > n && memcmp(name, part_name, n) == 0 && name[n] == '.')
		return sss__exr_dup_n(name, len);
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
sss_result sss__exr_group_channels(sss_exr *exr, int32_t max_channels,
                                   char *errbuf, size_t errbuf_len)
{
	int32_t index = 0;
	int64_t total = 0;
	for (int part = 0; part < exr->part_count; part++) {
		const exr_attr_chlist_t *cl = NULL;
		exr_result_t rv = exr_get_channels(exr->header, part, &cl);
		if (rv != EXR_ERR_SUCCESS)
			return sss__exr_fail(errbuf, errbuf_len, exr->path, "reading the "
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

/* The source's attributes, file order; *list is malloc'ed. */
exr_result_t sss__exr_source_attributes(const sss_exr *exr,
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

const char *sss__exr_path(const sss_exr *exr)
{
	return exr->path;
}

int sss__exr_has_attribute_prefix(const sss_exr *exr, const char *prefix)
{
	const exr_attribute_t **attrs = NULL;
	int32_t n = 0, found = 0;
	if (sss__exr_source_attributes(exr, &attrs, &n) == EXR_ERR_SUCCESS)
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
