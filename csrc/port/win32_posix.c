/* win32_posix.c - the POSIX calls of win32_posix.h on Windows' own API. */
#include "win32_posix.h"

#ifdef _WIN32
#include <stdarg.h>
#include <windows.h>

#undef open
#undef _stat64
#undef _fstat64
#undef rename
#undef strrchr

static int errno_of(DWORD e)
{
	switch (e) {
	case ERROR_FILE_NOT_FOUND:
	case ERROR_PATH_NOT_FOUND:
	case ERROR_INVALID_NAME:
		return ENOENT;
	case ERROR_FILE_EXISTS:
	case ERROR_ALREADY_EXISTS:
		return EEXIST;
	case ERROR_ACCESS_DENIED:
	case ERROR_SHARING_VIOLATION:
		return EACCES;
	case ERROR_LOCK_VIOLATION:
		return EWOULDBLOCK;
	case ERROR_NOT_ENOUGH_MEMORY:
	case ERROR_OUTOFMEMORY:
		return ENOMEM;
	case ERROR_DISK_FULL:
	case ERROR_HANDLE_DISK_FULL:
		return ENOSPC;
	case ERROR_DIRECTORY:
		return ENOTDIR;
	default:
		return EIO;
	}
}

int sss_win_open(const char *path, int flags, ...)
{
	DWORD access = (flags & O_WRONLY) ? GENERIC_WRITE
	               : (flags & O_RDWR) ? GENERIC_READ | GENERIC_WRITE
	                                  : GENERIC_READ;
	DWORD how = (flags & O_CREAT) && (flags & O_EXCL) ? CREATE_NEW
	            : (flags & O_CREAT) && (flags & O_TRUNC) ? CREATE_ALWAYS
	            : (flags & O_CREAT) ? OPEN_ALWAYS
	            : (flags & O_TRUNC) ? TRUNCATE_EXISTING : OPEN_EXISTING;
	HANDLE h = CreateFileA(path, access, FILE_SHARE_READ | FILE_SHARE_WRITE |
	                       FILE_SHARE_DELETE, NULL, how,
	                       FILE_ATTRIBUTE_NORMAL | FILE_FLAG_BACKUP_SEMANTICS,
	                       NULL);
	if (h == INVALID_HANDLE_VALUE) {
		errno = errno_of(GetLastError());
		return -1;
	}
	int fd = _open_osfhandle((intptr_t)h, O_BINARY |
	                         (flags & (O_WRONLY | O_RDWR | O_APPEND)));
	if (fd < 0)
		CloseHandle(h);
	return fd;
}

/* Volume serial number and 64-bit file index, folded into the C runtime's
 * 32-bit st_dev and 16-bit st_ino. */
static void identify(HANDLE h, struct _stat64 *st)
{
	BY_HANDLE_FILE_INFORMATION info;
	if (h == INVALID_HANDLE_VALUE || !GetFileInformationByHandle(h, &info))
		return;
	uint64_t index = ((uint64_t)info.nFileIndexHigh << 32) |
	                 info.nFileIndexLow;
	st->st_dev = (_dev_t)(info.dwVolumeSerialNumber ^
	                      (uint32_t)(index >> 16) ^ (uint32_t)(index >> 48));
	st->st_ino = (_ino_t)(index & 0xffff);
}

int sss_win_stat(const char *path, struct _stat64 *st)
{
	if (_stat64(path, st) != 0)
		return -1;
	HANDLE h = CreateFileA(path, 0, FILE_SHARE_READ | FILE_SHARE_WRITE |
	                       FILE_SHARE_DELETE, NULL, OPEN_EXISTING,
	                       FILE_FLAG_BACKUP_SEMANTICS, NULL);
	identify(h, st);
	if (h != INVALID_HANDLE_VALUE)
		CloseHandle(h);
	return 0;
}

int sss_win_fstat(int fd, struct _stat64 *st)
{
	if (_fstat64(fd, st) != 0)
		return -1;
	identify((HANDLE)_get_osfhandle(fd), st);
	return 0;
}

int sss_win_rename(const char *from, const char *to)
{
	if (MoveFileExA(from, to, MOVEFILE_REPLACE_EXISTING))
		return 0;
	errno = errno_of(GetLastError());
	return -1;
}

int sss_win_flock(int fd, int op)
{
	HANDLE h = (HANDLE)_get_osfhandle(fd);
	OVERLAPPED o;
	memset(&o, 0, sizeof o);
	BOOL ok;
	if (op & LOCK_UN)
		ok = UnlockFileEx(h, 0, MAXDWORD, MAXDWORD, &o);
	else
		ok = LockFileEx(h, ((op & LOCK_EX) ? LOCKFILE_EXCLUSIVE_LOCK : 0) |
		                ((op & LOCK_NB) ? LOCKFILE_FAIL_IMMEDIATELY : 0), 0,
		                MAXDWORD, MAXDWORD, &o);
	if (ok)
		return 0;
	DWORD e = GetLastError();
	errno = e == ERROR_LOCK_VIOLATION || e == ERROR_IO_PENDING
	        ? EWOULDBLOCK : errno_of(e);
	return -1;
}

static ssize_t at_offset(int fd, void *buf, size_t n, int64_t offset,
                         int write)
{
	HANDLE h = (HANDLE)_get_osfhandle(fd);
	OVERLAPPED o;
	memset(&o, 0, sizeof o);
	o.Offset = (DWORD)((uint64_t)offset & 0xffffffffu);
	o.OffsetHigh = (DWORD)((uint64_t)offset >> 32);
	DWORD done = 0, len = n > 0x40000000u ? 0x40000000u : (DWORD)n;
	BOOL ok = write ? WriteFile(h, buf, len, &done, &o)
	                : ReadFile(h, buf, len, &done, &o);
	if (ok)
		return (ssize_t)done;
	DWORD e = GetLastError();
	if (!write && e == ERROR_HANDLE_EOF)
		return 0;
	errno = errno_of(e);
	return -1;
}

ssize_t sss_win_pread(int fd, void *buf, size_t n, int64_t offset)
{
	return at_offset(fd, buf, n, offset, 0);
}

ssize_t sss_win_pwrite(int fd, const void *buf, size_t n, int64_t offset)
{
	return at_offset(fd, (void *)buf, n, offset, 1);
}

ssize_t sss_win_readlink(const char *path, char *buf, size_t n)
{
	(void)path;
	(void)buf;
	(void)n;
	errno = EINVAL;
	return -1;
}

long sss_win_sysconf(int name)
{
	if (name != _SC_NPROCESSORS_ONLN) {
		errno = EINVAL;
		return -1;
	}
	SYSTEM_INFO si;
	GetSystemInfo(&si);
	return (long)si.dwNumberOfProcessors;
}

/* Only the file status flags, of which Windows files have none here. */
int sss_win_fcntl(int fd, int cmd, ...)
{
	(void)fd;
	return cmd == F_GETFL || cmd == F_SETFL ? 0 : (errno = EINVAL, -1);
}

int sss_win_sigaction(int sig, const struct sigaction *sa,
                      struct sigaction *old)
{
	void (*prev)(int) = signal(sig, sa ? sa->sa_handler : SIG_DFL);
	if (prev == SIG_ERR)
		return -1;
	if (!sa) /* only asked: put it back */
		signal(sig, prev);
	if (old) {
		memset(old, 0, sizeof *old);
		old->sa_handler = prev;
	}
	return 0;
}

int sss_win_strerror_r(int e, char *buf, size_t n)
{
	return strerror_s(buf, n, e);
}

char *sss_win_strrchr(const char *s, int c)
{
	char *last = strrchr(s, c);
	if (c == '/') {
		char *back = strrchr(s, '\\');
		if (back && (!last || back > last))
			last = back;
	}
	return last;
}

#endif /* _WIN32 */
