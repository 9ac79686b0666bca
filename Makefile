# libsss - screen-space subsurface scattering for Blender render passes.
#
#   make          build build/libsss.so
#   make test     install missing build packages (as root), build, run every test
#   make check    the C tests again under ASan + UBSan with -Werror
#   make demo     render a small synthetic scene with SSS and write a PNG
#   make clean
#
# Results must not depend on the compiler contracting a*b+c into an FMA:
# -ffp-contract=off, and never -ffast-math (see README, Determinism).

CC      ?= cc
CFLAGS  ?= -O2 -g
BUILD   ?= build
WARN    := -std=c11 -Wall -Wextra -Wpedantic -Wshadow -Wstrict-prototypes \
           -Wmissing-prototypes
BASE    := $(WARN) -fPIC -fvisibility=hidden -ffp-contract=off \
           -D_POSIX_C_SOURCE=200809L -pthread
LDLIBS  := -lm -pthread

LIB_SRC   := $(sort $(wildcard csrc/sss_*.c))
LIB_HDR   := csrc/sss.h csrc/sss_internal.h
TEST_SRC  := $(sort $(wildcard tests/test_*.c))
TESTS     := $(patsubst tests/%.c,$(BUILD)/tests/%,$(TEST_SRC))

.PHONY: all deps test check demo report clean

all: $(BUILD)/libsss.so

$(BUILD)/libsss.so: $(LIB_SRC) $(LIB_HDR) Makefile
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) $(BASE) -shared -o $@ $(LIB_SRC) $(LDLIBS)

# Tests link the library's objects statically so that they can also reach
# internal helpers; the shared library is what ships and what nm checks.
$(BUILD)/tests/%: tests/%.c tests/test_util.h tests/synth.h $(LIB_SRC) $(LIB_HDR) Makefile
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) $(BASE) -Icsrc -o $@ $< $(LIB_SRC) $(LDLIBS)

deps:
	@sh scripts/install-deps.sh

test: deps all $(TESTS)
	@sh tests/run_c_tests.sh $(BUILD) $(TESTS)
	@if sh scripts/sanitizers-supported.sh "$(CC)"; then \
		$(MAKE) --no-print-directory check; \
	else echo "make check: skipped ($(CC) cannot build with ASan+UBSan here)"; fi

# Sanitizer build: every C test again with ASan + UBSan, warnings as errors.
SAN := -O1 -g -fsanitize=address,undefined -fno-omit-frame-pointer \
       -fno-sanitize-recover=all -Werror
check:
	@$(MAKE) --no-print-directory BUILD=$(BUILD)/check CFLAGS="$(SAN)" \
		$(patsubst $(BUILD)/%,$(BUILD)/check/%,$(TESTS)) $(BUILD)/check/libsss.so
	@ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
		sh tests/run_c_tests.sh $(BUILD)/check \
		$(patsubst $(BUILD)/%,$(BUILD)/check/%,$(TESTS))

$(BUILD)/sss-demo: examples/demo.c tests/synth.h $(BUILD)/libsss.so
	$(CC) $(CFLAGS) $(WARN) -D_POSIX_C_SOURCE=200809L -Icsrc -Itests -o $@ \
		examples/demo.c -L$(BUILD) -lsss -Wl,-rpath,'$$ORIGIN' -lpng $(LDLIBS)

demo: deps $(BUILD)/sss-demo
	@$(BUILD)/sss-demo $(BUILD)/demo

$(BUILD)/sss-report: examples/method_report.c tests/synth.h $(BUILD)/libsss.so
	$(CC) $(CFLAGS) $(WARN) -D_POSIX_C_SOURCE=200809L -Icsrc -Itests -o $@ \
		examples/method_report.c -L$(BUILD) -lsss -Wl,-rpath,'$$ORIGIN' $(LDLIBS)

# Separable against reference for Burley at three radii, with timings.
report: $(BUILD)/sss-report
	@$(BUILD)/sss-report 512

clean:
	rm -rf $(BUILD)
