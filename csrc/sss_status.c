/* sss_status.c - status names and messages, version, struct defaults. */
#include "sss_internal.h"

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

void sss_options_default(sss_options *opt)
{
	if (!opt)
		return;
	memset(opt, 0, sizeof *opt);
	opt->struct_size = sizeof *opt;
	opt->method = SSS_METHOD_AUTO;
	opt->radius_scale = 1.0f;
	opt->taps = SSS_DEFAULT_TAPS;
	opt->num_threads = 0;
	opt->background_depth = 1e9;
	opt->max_support_px = 256;
	opt->samples = 64;
	opt->crease = 1;
}

void sss_camera_default(sss_camera *cam)
{
	if (!cam)
		return;
	/* Blender's default camera: 50 mm lens on a 36 mm sensor. */
	memset(cam, 0, sizeof *cam);
	cam->struct_size = sizeof *cam;
	cam->type = SSS_CAMERA_PERSPECTIVE;
	cam->lens_mm = 50.0;
	cam->sensor_width_mm = 36.0;
	cam->sensor_height_mm = 24.0;
	cam->sensor_fit = SSS_SENSOR_FIT_AUTO;
	cam->ortho_scale = 6.0;
	cam->pixel_aspect_x = 1.0;
	cam->pixel_aspect_y = 1.0;
	cam->unit_scale = 1.0;
}

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
