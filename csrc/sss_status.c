/* sss_status.c - status names and messages, version, struct defaults. */
#include "sss_camera_fields.h"
#include "sss_internal.h"
#include "sss_option_fields.h"

#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

/* Parallel tables indexed by enum sss_status (the OpenEXRCore pattern);
 * test_api checks that every code has both. */
static const char *const status_names[] = {
	"SSS_OK",
	"SSS_ERR_INVALID_ARGUMENT",
	"SSS_ERR_SIZE_MISMATCH",
	"SSS_ERR_MISSING_PASS",
	"SSS_ERR_OUT_OF_MEMORY",
	"SSS_ERR_UNSUPPORTED",
	"SSS_ERR_IO",
	"SSS_ERR_EXR",
	"SSS_ERR_UNKNOWN",
};

static const char *const status_messages[] = {
	"success",
	"invalid argument",
	"pass buffers have different sizes",
	"a required render pass is missing",
	"out of memory",
	"not supported",
	"file could not be read or written",
	"EXR file error",
	"unknown error",
};

#define STATUS_COUNT ((int32_t)(sizeof status_names / sizeof *status_names))

const char *sss_status_name(sss_result code)
{
	if (code < 0 || code >= STATUS_COUNT)
		return status_names[SSS_ERR_UNKNOWN];
	return status_names[code];
}

const char *sss_status_string(sss_result code)
{
	if (code < 0 || code >= STATUS_COUNT)
		return status_messages[SSS_ERR_UNKNOWN];
	return status_messages[code];
}

uint32_t sss_abi_version(void)
{
	return SSS_ABI_VERSION;
}

const char *sss_version_string(void)
{
	return SSS_VERSION_STRING;
}

sss_result sss__fail(char *errbuf, size_t errbuf_len, sss_result code,
                     const char *fmt, ...)
{
	if (errbuf && errbuf_len > 0) {
		va_list ap;
		va_start(ap, fmt);
		vsnprintf(errbuf, errbuf_len, fmt, ap);
		va_end(ap);
	}
	return code;
}

int sss__in_range(double v, double lo, double hi, int lo_open)
{
	if (!(v >= lo) || (lo_open && !(v > lo)))
		return 0;
	if (hi == INFINITY)
		return 1;
	return hi >= SSS__BIG ? isfinite(v) : v <= hi;
}

const char *sss__range_text(double lo, double hi, int lo_open, int integer,
                            char *buf, size_t len)
{
	const char *op = lo_open ? ">" : ">=";
	if (integer && hi >= INT32_MAX)
		snprintf(buf, len, "%s %.0f", op, lo);
	else if (integer)
		snprintf(buf, len, "%.0f..%.0f", lo, hi);
	else if (lo <= -SSS__BIG && hi >= SSS__BIG)
		snprintf(buf, len, "finite");
	else if (hi == INFINITY)
		snprintf(buf, len, "%s %g", op, lo);
	else if (hi >= SSS__BIG)
		snprintf(buf, len, "finite and %s %g", op, lo);
	else
		snprintf(buf, len, "in %c%g, %g]", lo_open ? '(' : '[', lo, hi);
	return buf;
}

/* Each member's default from its schema row (sss_option_fields.h,
 * sss_camera_fields.h). */
#define DEFAULT(key, member, type, def, ...) opt->member = (def);
void sss_options_default(sss_options *opt)
{
	if (!opt)
		return;
	memset(opt, 0, sizeof *opt);
	opt->struct_size = sizeof *opt;
	SSS_OPTION_FIELDS(DEFAULT)
}
#undef DEFAULT

#define DEFAULT(key, member, type, place, when, def, ...) cam->member = (def);
void sss_camera_default(sss_camera *cam)
{
	if (!cam)
		return;
	memset(cam, 0, sizeof *cam);
	cam->struct_size = sizeof *cam;
	SSS_CAMERA_FIELDS(DEFAULT)
}
#undef DEFAULT

size_t sss_struct_size(const char *name)
{
	static const struct {
		const char *name;
		size_t size;
	} sizes[] = {
		{"sss_image", sizeof(sss_image)},
		{"sss_passes", sizeof(sss_passes)},
		{"sss_camera", sizeof(sss_camera)},
		{"sss_material", sizeof(sss_material)},
		{"sss_options", sizeof(sss_options)},
		{"sss_exr_options", sizeof(sss_exr_options)},
		{"sss_process_options", sizeof(sss_process_options)},
		{"sss_timings", sizeof(sss_timings)},
		{"sss_field_info", sizeof(sss_field_info)},
		{"sss_pass_info", sizeof(sss_pass_info)},
	};
	if (!name)
		return 0;
	for (size_t i = 0; i < sizeof sizes / sizeof *sizes; i++)
		if (strcmp(name, sizes[i].name) == 0)
			return sizes[i].size;
	return 0;
}

const char *sss__file_kind(unsigned mode)
{
	mode_t m = (mode_t)mode;
	return S_ISDIR(m) ? "a directory" : S_ISFIFO(m) ? "a FIFO (named pipe)"
	       : S_ISSOCK(m) ? "a socket" : S_ISCHR(m) ? "a character device"
	       : S_ISBLK(m) ? "a block device" : S_ISLNK(m) ? "a symbolic link"
	       : S_ISREG(m) ? "a regular file" : "not a regular file";
}
