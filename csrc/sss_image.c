/* sss_image.c - the render passes' table and the checks of the caller's
 * image views, shared by every stage that reads a pass. */
#include "sss_internal.h"
#include "sss_pass_table.h"

#include <stddef.h>
#include <string.h>

#define ROW(name, member, components, alt, need, blender, hint) \
	{name, offsetof(sss_passes, member), components, alt, need, blender, \
	 hint},
const sss__pass_row sss__render_passes[] = {SSS_RENDER_PASSES(ROW)};
#undef ROW
const int32_t sss__render_pass_count =
	(int32_t)(sizeof sss__render_passes / sizeof *sss__render_passes);

sss_result sss_render_pass(int32_t i, sss_pass_info *info)
{
	if (!info || i < 0 || i >= sss__render_pass_count)
		return SSS_ERR_INVALID_ARGUMENT;
	const sss__pass_row *p = &sss__render_passes[i];
	memset(info, 0, sizeof *info);
	info->name = p->name;
	info->components = p->components;
	info->alt = p->alt;
	info->need = p->need;
	info->blender = p->blender;
	info->hint = p->hint;
	return SSS_OK;
}


sss_result sss__check_image(const char *name, const sss_image *im,
                            int32_t min_channels, int required, int32_t w,
                            int32_t h, char *errbuf, size_t errbuf_len)
{
	if (!im->data) {
		if (required)
			return FAILX(SSS_ERR_MISSING_PASS, "pass %s is required but "
			             "absent", name);
		return SSS_OK;
	}
	if (im->width <= 0 || im->height <= 0)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "pass %s: image size %dx%d "
		             "must be at least 1x1", name, im->width, im->height);
	if (im->channels < min_channels)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "pass %s has %d channel(s), "
		             "needs %d", name, im->channels, min_channels);
	if (im->row_stride != 0 &&
	    im->row_stride < (int64_t)im->width * im->channels)
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "pass %s: row_stride %lld "
		             "is smaller than width x channels", name,
		             (long long)im->row_stride);
	/* Its last float must be addressable: a stride near 2^60 made the
	 * span of the image overflow (found by the second hostile round). */
	int64_t row = (int64_t)im->width * im->channels;
	int64_t stride = im->row_stride ? im->row_stride : row;
	uint64_t left = (uint64_t)(UINTPTR_MAX - (uintptr_t)im->data) /
	                sizeof(float);
	if (im->height > 1 &&
	    ((uint64_t)stride > (uint64_t)(INT64_MAX - row) /
	                        (uint64_t)(im->height - 1) ||
	     (uint64_t)(stride * (im->height - 1) + row) > left))
		return FAILX(SSS_ERR_INVALID_ARGUMENT, "pass %s: row_stride %lld "
		             "for %d rows reaches past the address space", name,
		             (long long)im->row_stride, im->height);
	if (im->width != w || im->height != h)
		return FAILX(SSS_ERR_SIZE_MISMATCH, "pass %s is %dx%d but DiffDir "
		             "is %dx%d", name, im->width, im->height, w, h);
	return SSS_OK;
}
