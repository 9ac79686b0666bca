/* sss_exr_stream.c - OpenEXRCore's read and write callbacks on our own
 * file descriptors, and its error messages kept per context (no global
 * state, nothing printed). */
#include "sss_exr_internal.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* --------------------------------------------------------- I/O, errors */

void sss__xio_init(xio *io, int fd)
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
void sss__exr_on_read_error(exr_const_context_t ctxt, exr_result_t code,
                            const char *msg)
{
	void *ud = NULL;
	(void)code;
	if (ctxt && exr_get_user_data(ctxt, &ud) == EXR_ERR_SUCCESS && ud)
		xio_note(ud, msg);
}

/* Write contexts: silent; our write callback records I/O errors itself,
 * and everything else the library could say there is our own misuse. */
void sss__exr_on_write_error(exr_const_context_t ctxt, exr_result_t code,
                             const char *msg)
{
	(void)ctxt;
	(void)code;
	(void)msg;
}

int64_t sss__exr_io_read(exr_const_context_t ctxt, void *ud, void *buffer,
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

int64_t sss__exr_io_size(exr_const_context_t ctxt, void *ud)
{
	(void)ctxt;
	return ((xio *)ud)->size;
}

int64_t sss__exr_io_write(exr_const_context_t ctxt, void *ud,
                          const void *buffer, uint64_t sz, uint64_t offset,
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
sss_result sss__exr_fail(char *errbuf, size_t errbuf_len, const char *path,
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
