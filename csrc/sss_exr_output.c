/* sss_exr_output.c - where a written EXR goes: the output path's checks,
 * a locked temporary file beside it (stale ones of dead writers removed),
 * the atomic rename; sss_exr_check_output and sss_exr_write. */
#define _DEFAULT_SOURCE /* flock */
#include "sss_exr_internal.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

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
		size_t dir_len = slash == path ? 1 : (size_t)(slash - path);
		char *dir = sss__exr_dup_n(path, dir_len);
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
	if ((r = sss__exr_get_options(opt, &o, errbuf, errbuf_len)))
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
	sss__xio_init(&io, fd);
	r = sss__exr_encode(exr, &o, path, tmp, &io, errbuf, errbuf_len);
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
