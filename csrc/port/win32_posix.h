/* win32_posix.h - the POSIX calls libsss and sss make, on Windows
 * (MinGW-w64's C runtime and winpthreads). The Windows build includes this
 * before every source file (scripts/build_portable.py: -include), so the
 * library's own files stay POSIX only; the functions are in win32_posix.c.
 *
 * - open() opens binary files that can be renamed and removed while open
 *   (FILE_SHARE_DELETE), as POSIX files can: sss_exr_write renames its
 *   temporary before closing it. rename() replaces an existing file.
 * - stat() and fstat() give each file an identity (volume serial number and
 *   file index folded into st_dev and st_ino; the C runtime leaves st_ino
 *   0), so that "the input itself" is still recognised as an output.
 * - flock() is LockFileEx on the whole file; pread()/pwrite() are ReadFile
 *   and WriteFile at an offset.
 * - No symbolic links (lstat is stat), no signal masks (pthread_sigmask
 *   changes nothing and gives an empty old mask), sigaction() is signal().
 * - Paths are UTF-8 (as Blender and Python give them), opened through
 *   Windows' wide-character API: open, stat, rename, access, unlink and
 *   mkdtemp (a path that is not UTF-8 is taken in the ANSI code page).
 *   Listing a folder (opendir, for stale temporaries) stays ANSI.
 * - A path's last separator is '/' or '\\' (strrchr of '/').
 * - setenv, unsetenv and mkdtemp, which the C tests use; alarm() (a
 *   test's watchdog) ends the process after that many seconds. */
#ifndef SSS_WIN32_POSIX_H
#define SSS_WIN32_POSIX_H
#ifdef _WIN32

/* MinGW's io.h (which these include) declares tell(), a name the
 * library's files give their own functions: renamed out of the way. */
#define tell sss__win32_io_tell
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <time.h>
#include <unistd.h>
#undef tell

#ifndef NAME_MAX
#define NAME_MAX 255
#endif
#define O_NONBLOCK 0
#define O_CLOEXEC 0
#define O_NOFOLLOW 0
#define F_GETFL 3
#define F_SETFL 4
#define LOCK_SH 1
#define LOCK_EX 2
#define LOCK_NB 4
#define LOCK_UN 8
#ifndef S_ISLNK
#define S_ISLNK(m) 0
#endif
#ifndef S_ISSOCK
#define S_ISSOCK(m) 0
#endif
#ifndef S_ISFIFO
#define S_ISFIFO(m) (((m) & _S_IFMT) == _S_IFIFO)
#endif
#ifndef S_ISBLK
#define S_ISBLK(m) 0
#endif
#ifndef _SC_NPROCESSORS_ONLN
#define _SC_NPROCESSORS_ONLN 84
#endif
#ifndef _SC_PHYS_PAGES
#define _SC_PHYS_PAGES 85
#define _SC_PAGESIZE 30
#endif
#ifndef SIGHUP
#define SIGHUP 1
#endif
#ifndef SIGQUIT
#define SIGQUIT 3
#endif
#ifndef SIG_BLOCK
#define SIG_BLOCK 0
#define SIG_UNBLOCK 1
#define SIG_SETMASK 2
#endif

#ifndef _POSIX
typedef _sigset_t sigset_t;
#endif
#define sigfillset(s) (*(s) = ~(sigset_t)0, 0)
#define sigemptyset(s) (*(s) = 0, 0)

struct sigaction {
	void (*sa_handler)(int);
	sigset_t sa_mask;
	int sa_flags;
};

int sss_win_open(const char *path, int flags, ...);
/* Built with _FILE_OFFSET_BITS=64: MinGW's stat and fstat name _stat64 and
 * _fstat64 (struct stat is struct _stat64, with 64-bit sizes); those are
 * what is replaced here. */
int sss_win_stat(const char *path, struct _stat64 *st);
int sss_win_fstat(int fd, struct _stat64 *st);
int sss_win_rename(const char *from, const char *to);
int sss_win_access(const char *path, int mode);
int sss_win_unlink(const char *path);
int sss_win_flock(int fd, int op);
ssize_t sss_win_pread(int fd, void *buf, size_t n, int64_t offset);
ssize_t sss_win_pwrite(int fd, const void *buf, size_t n, int64_t offset);
ssize_t sss_win_readlink(const char *path, char *buf, size_t n);
long sss_win_sysconf(int name);
int sss_win_fcntl(int fd, int cmd, ...);
int sss_win_sigaction(int sig, const struct sigaction *sa,
                      struct sigaction *old);
int sss_win_strerror_r(int e, char *buf, size_t n);
char *sss_win_strrchr(const char *s, int c);
int sss_win_setenv(const char *name, const char *value, int overwrite);
int sss_win_unsetenv(const char *name);
char *sss_win_mkdtemp(char *template_);
int sss_win_sigmask(int how, const sigset_t *set, sigset_t *old);
/* A replaced output keeps its mode where Windows has one (read-only);
 * owners are not Windows' notion: these do nothing. */
int sss_win_fchmod(int fd, unsigned mode);
#define fchmod(f, m) sss_win_fchmod(f, m)
#define geteuid() 1
#define fchown(f, u, g) ((void)(f), (void)(u), (void)(g), 0)
unsigned sss_win_alarm(unsigned seconds);

#define open sss_win_open
#define _stat64(p, s) sss_win_stat(p, s)
#define lstat(p, s) sss_win_stat(p, s)
#define _fstat64(f, s) sss_win_fstat(f, s)
#define rename(a, b) sss_win_rename(a, b)
#define access(p, m) sss_win_access(p, m)
#define unlink(p) sss_win_unlink(p)
#define flock(f, o) sss_win_flock(f, o)
#define pread sss_win_pread
#define pwrite sss_win_pwrite
#define readlink sss_win_readlink
#define sysconf sss_win_sysconf
#define fcntl sss_win_fcntl
#define sigaction(s, a, o) sss_win_sigaction(s, a, o)
#define strerror_r sss_win_strerror_r
#define strrchr(s, c) sss_win_strrchr(s, c)
#define setenv sss_win_setenv
#define unsetenv sss_win_unsetenv
#define mkdtemp sss_win_mkdtemp
#undef pthread_sigmask
#define pthread_sigmask sss_win_sigmask
#define alarm sss_win_alarm

#endif /* _WIN32 */
#endif
