/* replay.c - runs files through LLVMFuzzerTestOneInput without libFuzzer
 * (the idea of stb's fuzz_main.c), so that the fuzz corpus and every
 * regression input are replayed by `make test` with any C compiler, and
 * under ASan + UBSan by `make check`.
 *
 *   fuzz_replay [FILE|DIR]...   (default: FUZZ_CORPUS, tests/fuzz/corpus)
 *
 * Directories are walked recursively in name order; names starting with a
 * dot are skipped. A crash or a sanitizer report kills the process (a
 * failure to the test runner; the file is named); a leak is a failed
 * file. The closing line is "N passed, M failed", N the files replayed
 * cleanly. */
#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#ifndef FUZZ_CORPUS
#define FUZZ_CORPUS "tests/fuzz/corpus"
#endif

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int replayed, failed;

/* The file being replayed, named when the process dies on it: by a
 * sanitizer (its death callback; a weak reference, so that plain builds
 * link too) or by a signal (abort() from a broken contract, a crash). */
static const char *current;

void __sanitizer_set_death_callback(void (*callback)(void))
	__attribute__((weak));
/* LeakSanitizer, when linked in: a leak check after every file names the
 * file that leaked (at exit it could not say which). */
int __lsan_do_recoverable_leak_check(void) __attribute__((weak));

static void say_current(void)
{
	static const char head[] = "FAIL fuzz_replay: died on ";
	if (!current)
		return;
	/* async-signal-safe: write(2) only */
	if (write(STDOUT_FILENO, head, sizeof head - 1) < 0 ||
	    write(STDOUT_FILENO, current, strlen(current)) < 0 ||
	    write(STDOUT_FILENO, "\n", 1) < 0)
		return;
}

static void on_signal(int sig)
{
	say_current();
	signal(sig, SIG_DFL);
	raise(sig);
}

/* The whole file in a buffer of exactly its size, so that ASan sees any
 * read past the input's end, as under libFuzzer. */
static void replay_file(const char *path)
{
	FILE *fp = fopen(path, "rb");
	if (!fp) {
		printf("FAIL %s: cannot open: %s\n", path, strerror(errno));
		failed++;
		return;
	}
	size_t cap = 4096, n = 0;
	uint8_t *buf = malloc(cap);
	for (;;) {
		if (!buf)
			break;
		n += fread(buf + n, 1, cap - n, fp);
		if (n < cap)
			break;
		uint8_t *grown = realloc(buf, cap * 2);
		if (!grown) {
			free(buf);
			buf = NULL;
			break;
		}
		buf = grown;
		cap *= 2;
	}
	int bad = !buf || ferror(fp);
	fclose(fp);
	if (bad) {
		printf("FAIL %s: cannot read\n", path);
		free(buf);
		failed++;
		return;
	}
	uint8_t *exact = malloc(n ? n : 1);
	if (!exact) {
		printf("FAIL %s: out of memory\n", path);
		free(buf);
		failed++;
		return;
	}
	memcpy(exact, buf, n);
	free(buf);
	fflush(stdout);
	current = path;
	LLVMFuzzerTestOneInput(exact, n);
	current = NULL;
	free(exact);
	if (__lsan_do_recoverable_leak_check &&
	    __lsan_do_recoverable_leak_check()) {
		printf("FAIL %s: memory leaked (report above)\n", path);
		failed++;
		return;
	}
	replayed++;
}

static int by_name(const void *a, const void *b)
{
	return strcmp(*(char *const *)a, *(char *const *)b);
}

static void replay_path(const char *path, int depth)
{
	struct stat st;
	if (stat(path, &st)) {
		printf("FAIL %s: %s\n", path, strerror(errno));
		failed++;
		return;
	}
	if (!S_ISDIR(st.st_mode)) {
		replay_file(path);
		return;
	}
	if (depth > 16) {
		printf("FAIL %s: directories nested too deep\n", path);
		failed++;
		return;
	}
	DIR *d = opendir(path);
	if (!d) {
		printf("FAIL %s: cannot open: %s\n", path, strerror(errno));
		failed++;
		return;
	}
	/* Names first, then sorted: the order is the same on every machine. */
	char **names = NULL;
	size_t count = 0, cap = 0;
	struct dirent *e;
	while ((e = readdir(d)) != NULL) {
		if (e->d_name[0] == '.')
			continue;
		if (count == cap) {
			size_t ncap = cap ? 2 * cap : 64;
			char **grown = realloc(names, ncap * sizeof *grown);
			if (!grown)
				break;
			names = grown;
			cap = ncap;
		}
		size_t len = strlen(path) + strlen(e->d_name) + 2;
		if (!(names[count] = malloc(len)))
			break;
		size_t plen = strlen(path);
		snprintf(names[count], len, "%s%s%s", path,
		         plen && path[plen - 1] == '/' ? "" : "/", e->d_name);
		count++;
	}
	closedir(d);
	if (count)
		qsort(names, count, sizeof *names, by_name);
	for (size_t i = 0; i < count; i++) {
		replay_path(names[i], depth + 1);
		free(names[i]);
	}
	free(names);
}

int main(int argc, char **argv)
{
	if (__sanitizer_set_death_callback)
		__sanitizer_set_death_callback(say_current);
	signal(SIGABRT, on_signal);
	signal(SIGSEGV, on_signal);
	signal(SIGBUS, on_signal);
	signal(SIGFPE, on_signal);
	if (argc < 2)
		replay_path(FUZZ_CORPUS, 0);
	for (int i = 1; i < argc; i++)
		replay_path(argv[i], 0);
	if (replayed == 0 && failed == 0) {
		printf("FAIL fuzz_replay: no input files\n");
		failed++;
	}
	printf("fuzz_replay: %d passed, %d failed\n", replayed, failed);
	printf("%d passed, %d failed\n", replayed, failed);
	return failed ? 1 : 0;
}
