/* sss_render_passes.c - Blender's render passes in a multilayer EXR: which
 * view layer holds the render, which of its passes libsss reads and what
 * to tell the artist when one is missing. Works on the sss_exr public API
 * (sss_exr*.c do the file format); sss_process.c runs it per frame. */
#include "sss_internal.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>


/* Appends printf output to a fixed buffer, truncating quietly. */
static void append(char *buf, size_t cap, const char *fmt, ...)
	__attribute__((format(printf, 3, 4)));
static void append(char *buf, size_t cap, const char *fmt, ...)
{
	size_t len = strlen(buf);
	if (len + 1 >= cap)
		return;
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(buf + len, cap - len, fmt, ap);
	va_end(ap);
}

/* "'ViewLayer' (Combined, DiffDir), 'Other' (Depth)": every layer in file
 * order with its passes. */
static void describe_layers(const sss_exr *exr, char *buf, size_t cap)
{
	int32_t n = sss_exr_pass_count(exr);
	for (int32_t i = 0; i < n && strlen(buf) + 1 < cap; i++) {
		const char *layer, *other, *pass;
		sss_exr_pass(exr, i, &layer, NULL, NULL, NULL);
		int seen = 0;
		for (int32_t j = 0; j < i && !seen; j++) {
			sss_exr_pass(exr, j, &other, NULL, NULL, NULL);
			seen = strcmp(other, layer) == 0;
		}
		if (seen)
			continue;
		append(buf, cap, "%s'%s' (", buf[0] ? ", " : "", layer);
		int first = 1;
		for (int32_t j = i; j < n; j++) {
			sss_exr_pass(exr, j, &other, &pass, NULL, NULL);
			if (strcmp(other, layer) == 0) {
				append(buf, cap, "%s%s", first ? "" : ", ",
				       pass[0] ? pass : "<no pass name>");
				first = 0;
			}
		}
		append(buf, cap, ")");
	}
	if (!buf[0])
		append(buf, cap, "none (the file has no channels)");
}

/* The render pass `name` of `layer` (by its short name or Blender 5.0's
 * full one, as sss_exr_find reads it) with its component letters; 0 when
 * the layer has no such pass. */
static int find_pass(const sss_exr *exr, const char *layer, const char *name,
                     const char **components, sss_image *view)
{
	if (sss_exr_find(exr, layer, name, view) != SSS_OK)
		return 0;
	for (int32_t i = 0; i < sss_exr_pass_count(exr); i++) {
		sss_image v;
		sss_exr_pass(exr, i, NULL, NULL, components, &v);
		if (v.data == view->data)
			return 1;
	}
	return 0;
}

/* Where the run of one-letter components `run` ("RGB") starts among a
 * pass's components ("RGBA", or "R,G,B,AO" when one name is longer than a
 * letter), or -1. */
static int32_t find_run(const char *components, const char *run)
{
	char comp[64][2];
	int32_t count = 0;
	for (const char *s = components; *s && count < 64; count++) {
		size_t len = strchr(components, ',') ? strcspn(s, ",") : 1;
		comp[count][0] = len == 1 ? s[0] : '\0'; /* longer: never a run */
		comp[count][1] = '\0';
		s += len;
		s += *s == ',';
	}
	int32_t n = (int32_t)strlen(run);
	for (int32_t at = 0; at + n <= count; at++) {
		int32_t j = 0;
		while (j < n && comp[at + j][0] == run[j])
			j++;
		if (j == n)
			return at;
	}
	return -1;
}

/* "in Blender enable View Layer Properties > Passes > Light > Diffuse:
 * Direct; ...": where each pass of the given need is turned on. */
static void blender_hint(int32_t need, char *buf, size_t cap)
{
	buf[0] = '\0';
	append(buf, cap, "in Blender enable View Layer Properties > Passes > ");
	int first = 1;
	for (int32_t t = 0; t < sss__render_pass_count; t++) {
		if (sss__render_passes[t].need != need)
			continue;
		append(buf, cap, "%s%s", first ? "" : "; ",
		       sss__render_passes[t].hint);
		first = 0;
	}
}

/* The layer to read: as named, or the first (in file order) with DiffDir
 * that is not the back-light layer (transmission's, SSS_BACKLIGHT_LAYER);
 * NULL when there is none. */
static const char *render_layer(const sss_exr *exr, const char *layer)
{
	/* One look at each pass (a find per pass was quadratic). */
	for (int32_t i = 0; i < sss_exr_pass_count(exr); i++) {
		const char *l, *p;
		sss_exr_pass(exr, i, &l, &p, NULL, NULL);
		if (layer ? strcmp(l, layer) == 0
		          : (strcmp(p, "DiffDir") == 0 ||
		             strcmp(p, "Diffuse Direct") == 0) &&
		            strcmp(l, SSS_BACKLIGHT_LAYER) != 0)
			return l;
	}
	return NULL;
}

sss_result sss_exr_render_passes(const sss_exr *exr, const char *layer,
                                 sss_passes *passes, const char **layer_used,
                                 char *errbuf, size_t errbuf_len)
{
	char hint[400];
	blender_hint(SSS_PASS_REQUIRED, hint, sizeof hint);
	char layers[1024] = "";
	if (errbuf && errbuf_len)
		errbuf[0] = '\0';
	if (layer_used)
		*layer_used = NULL;
	if (!exr || !passes)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "sss_exr_render_passes: %s "
		             "is NULL", exr ? "passes" : "exr");
	memset(passes, 0, sizeof *passes);
	const char *path = sss__exr_path(exr);

	const char *use = render_layer(exr, layer);
	if (!use) {
		describe_layers(exr, layers, sizeof layers);
		if (layer)
			return FAILX(SSS_ERR_MISSING_PASS, "%s: no layer '%s'; layers "
			             "in the file: %s", path, layer, layers);
		return FAILX(SSS_ERR_MISSING_PASS, "%s: no layer has a DiffDir "
		             "pass; layers in the file: %s; %s", path, layers, hint);
	}

	char missing[256] = "";
	for (int32_t t = 0; t < sss__render_pass_count; t++) {
		const sss__pass_row *row = &sss__render_passes[t];
		const char *components;
		sss_image view;
		if (!find_pass(exr, use, row->name, &components, &view)) {
			if (row->need == SSS_PASS_REQUIRED)
				append(missing, sizeof missing, "%s%s",
				       missing[0] ? ", " : "", row->name);
			continue;
		}
		int32_t at = find_run(components, row->components);
		if (at < 0 && row->alt)
			at = find_run(components, row->alt);
		if (at < 0 && strcmp(row->name, "Combined") == 0)
			continue; /* RGB only: its alpha is what libsss would use */
		if (at < 0) {
			memset(passes, 0, sizeof *passes);
			return FAILX(SSS_ERR_MISSING_PASS, "%s: layer '%s': pass %s "
			             "has components '%s' but needs %s%s%s", path, use,
			             row->name, components, row->components,
			             row->alt ? " or " : "", row->alt ? row->alt : "");
		}
		view.data += at;
		*(sss_image *)(void *)((char *)passes + row->offset) = view;
	}
	if (missing[0]) {
		memset(passes, 0, sizeof *passes);
		describe_layers(exr, layers, sizeof layers);
		return FAILX(SSS_ERR_MISSING_PASS, "%s: layer '%s' has no %s pass%s"
		             "; layers in the file: %s; %s", path, use, missing,
		             strchr(missing, ',') ? "es" : "", layers, hint);
	}
	/* Blender stamps a Cycles render's header with "cycles.<layer>.samples"
	 * and the like (EEVEE has no DiffInd pass, Cycles always can). */
	char cycles[300];
	snprintf(cycles, sizeof cycles, "cycles.%s.", use);
	for (int32_t t = 0; t < sss__render_pass_count; t++) {
		const sss__pass_row *row = &sss__render_passes[t];
		if (row->need != SSS_PASS_CYCLES ||
		    ((sss_image *)(void *)((char *)passes + row->offset))->data ||
		    !sss__exr_has_attribute_prefix(exr, cycles))
			continue;
		memset(passes, 0, sizeof *passes);
		return FAILX(SSS_ERR_MISSING_PASS, "%s: layer '%s' is a Cycles "
		             "render without a %s pass: its light would be lost; "
		             "in Blender enable View Layer Properties > Passes > %s",
		             path, use, row->name, row->hint);
	}
	if (layer_used)
		*layer_used = use;
	return SSS_OK;
}
