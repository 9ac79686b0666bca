/* test_util.h - tiny assertion helpers shared by the C tests.
 * Every failure prints a stable case id, the expression, file and line;
 * tu_finish() prints the closing "N passed, N failed" line. */
#ifndef TEST_UTIL_H
#define TEST_UTIL_H

#include "sss.h"

#include <stdio.h>

static int tu_passed, tu_failed;

#define CHECK(id, cond, ...)                                               \
	do {                                                                   \
		if (cond) {                                                        \
			tu_passed++;                                                   \
		} else {                                                           \
			tu_failed++;                                                   \
			printf("FAIL [%s] %s:%d: %s: ", (id), __FILE__, __LINE__,      \
			       #cond);                                                 \
			printf(__VA_ARGS__);                                           \
			printf("\n");                                                  \
		}                                                                  \
	} while (0)

/* Expects `expr` to return status `code`; prints both names otherwise. */
#define CHECK_STATUS(id, code, expr)                                       \
	do {                                                                   \
		sss_result tu_r_ = (expr);                                         \
		CHECK(id, tu_r_ == (code), "got %s, expected %s",                  \
		      sss_status_name(tu_r_), sss_status_name(code));              \
	} while (0)

static inline int tu_finish(const char *name)
{
	printf("%s: %d passed, %d failed\n", name, tu_passed, tu_failed);
	printf("%d passed, %d failed\n", tu_passed, tu_failed);
	return tu_failed ? 1 : 0;
}

#endif
