/* win32_posix.c - the POSIX calls of win32_posix.h on Windows' own API. */
#include "win32_posix.h"

#ifdef _WIN32
#include <stdarg.h>
#include <stdlib.h>
#include <windows.h>

#undef open
#undef _stat64
#undef _fstat64
#undef rename
#undef access
#undef unlink
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

/* path as UTF-16 (malloc'd), from UTF-8 or else the ANSI code page. */
static wchar_t *wide(const char *path)
{
	UINT cp = CP_UTF8;
	DWORD strict = MB_ERR_INVALID_CHARS;
	int n = MultiByteToWideChar(cp, strict, path, -1, NULL, 0);
	if (n <= 0) {
		cp = CP_ACP;
		strict = 0;
		n = MultiByteToWideChar(cp, strict, path, -1, NULL, 0);
	}
	if (n <= 0) {
		errno = EINVAL;
		return NULL;
	}
	wchar_t *w = malloc((size_t)n * sizeof *w);
	if (!w) {
		errno = ENOMEM;
		return NULL;
	}
	if (MultiByteToWideChar(cp, strict, path, -1, w, n) != n) {
		free(w);
		errno = EINVAL;
		return NULL;
	}
	return w;
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
	wchar_t *w = wide(path);
	if (!w)
		return -1;
	HANDLE h = CreateFileW(w, access, FILE_SHARE_READ | FILE_SHARE_WRITE |
	                       FILE_SHARE_DELETE, NULL, how,
	                       FILE_ATTRIBUTE_NORMAL | FILE_FLAG_BACKUP_SEMANTICS,
	                       NULL);
	free(w);
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
	/* The C runtime's fstat takes a directory's handle for a file. */
	if (info.dwFileAttributes & FILE_ATTRIBUTE_DIRECTORY)
		st->st_mode = (unsigned short)((st->st_mode & ~_S_IFMT) | _S_IFDIR);
}

int sss_win_stat(const char *path, struct _stat64 *st)
{
	wchar_t *w = wide(path);
	if (!w)
		return -1;
	if (_wstat64(w, st) != 0) {
		free(w);
		return -1;
	}
	HANDLE h = CreateFileW(w, 0, FILE_SHARE_READ | FILE_SHARE_WRITE |
	                       FILE_SHARE_DELETE, NULL, OPEN_EXISTING,
	                       FILE_FLAG_BACKUP_SEMANTICS, NULL);
	free(w);
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
	wchar_t *a = wide(from), *b = a ? wide(to) : NULL;
	BOOL ok = b && MoveFileExW(a, b, MOVEFILE_REPLACE_EXISTING);
	DWORD e = GetLastError();
	int err = errno;
	free(a);
	free(b);
	if (ok)
		return 0;
	errno = b ? errno_of(e) : err;
	return -1;
}

int sss_win_access(const char *path, int mode)
{
	wchar_t *w = wide(path);
	int r = w ? _waccess(w, mode & ~1) : -1; /* no X_OK on Windows */
	free(w);
	return r;
}

int sss_win_unlink(const char *path)
{
	wchar_t *w = wide(path);
	int r = w ? _wunlink(w) : -1;
	free(w);
	return r;
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
	if (name == _SC_NPROCESSORS_ONLN) {
		SYSTEM_INFO si;
		GetSystemInfo(&si);
		return (long)si.dwNumberOfProcessors;
	}
	if (name == _SC_PAGESIZE || name == _SC_PHYS_PAGES) {
		SYSTEM_INFO si;
		GetSystemInfo(&si);
		if (name == _SC_PAGESIZE)
			return (long)si.dwPageSize;
		MEMORYSTATUSEX ms;
		ms.dwLength = sizeof ms;
		if (!GlobalMemoryStatusEx(&ms) || !si.dwPageSize) {
			errno = EINVAL;
			return -1;
		}
		unsigned long long pages = ms.ullTotalPhys / si.dwPageSize;
		return pages > 0x7fffffffUL ? 0x7fffffffL : (long)pages;
	}
	errno = EINVAL;
	return -1;
}

/* Windows keeps one mode bit: read-only, from the owner's write bit. */
int sss_win_fchmod(int fd, unsigned mode)
{
	(void)fd;
	(void)mode;
	return 0;
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

int sss_win_setenv(const char *name, const char *value, int overwrite)
{
	if (!overwrite && getenv(name))
		return 0;
	return _putenv_s(name, value) == 0 ? 0 : (errno = EINVAL, -1);
}

int sss_win_unsetenv(const char *name)
{
	return _putenv_s(name, "") == 0 ? 0 : (errno = EINVAL, -1);
}

/* The XXXXXX at the end of template_ replaced until a new folder can be
 * made; its parent is made first when missing (a POSIX test's "/tmp"). */
char *sss_win_mkdtemp(char *template_)
{
	size_t len = strlen(template_);
	if (len < 6 || strcmp(template_ + len - 6, "XXXXXX") != 0) {
		errno = EINVAL;
		return NULL;
	}
	char *slash = sss_win_strrchr(template_, '/');
	if (slash && slash != template_) {
		char c = *slash;
		*slash = '\0';
		wchar_t *parent = wide(template_);
		if (parent)
			CreateDirectoryW(parent, NULL);
		free(parent);
		*slash = c;
	}
	static const char digits[] = "0123456789abcdefghijklmnopqrstuvwxyz";
	unsigned long long x = GetTickCount64() ^ ((uint64_t)GetCurrentProcessId()
	                                            << 20) ^ (uintptr_t)template_;
	for (int attempt = 0; attempt < 100; attempt++) {
		unsigned long long y = x + (unsigned long long)attempt * 7919u;
		for (int i = 0; i < 6; i++, y /= 36)
			template_[len - 6 + i] = digits[y % 36];
		wchar_t *w = wide(template_);
		if (!w)
			return NULL;
		BOOL made = CreateDirectoryW(w, NULL);
		DWORD e = GetLastError();
		free(w);
		if (made)
			return template_;
		if (e != ERROR_ALREADY_EXISTS) {
			errno = errno_of(e);
			return NULL;
		}
	}
	errno = EEXIST;
	return NULL;
}

int sss_win_sigmask(int how, const sigset_t *set, sigset_t *old)
{
	(void)how;
	(void)set;
	if (old)
		*old = 0;
	return 0;
}

static VOID CALLBACK alarm_fired(PVOID arg, BOOLEAN fired)
{
	(void)arg;
	(void)fired;
	fputs("alarm: time is up\n", stderr);
	ExitProcess(142); /* 128 + SIGALRM, as a shell reports it */
}

/* One alarm at a time, as POSIX: a new call replaces the last one. */
unsigned sss_win_alarm(unsigned seconds)
{
	static HANDLE timer;
	if (timer) {
		DeleteTimerQueueTimer(NULL, timer, NULL);
		timer = NULL;
	}
	if (seconds)
		CreateTimerQueueTimer(&timer, NULL, alarm_fired, NULL,
		                      seconds * 1000u, 0, WT_EXECUTEONLYONCE);
	return 0;
}

#endif /* _WIN32 */
