# libsss - screen-space subsurface scattering for Blender render passes.
#
#   make          the library build/libsss.so and the command build/sss
#   make test     everything CI runs: installs missing packages (as root) and
#                 Blender 4.5/5.0 (bpy, in build/), builds, then the C tests,
#                 the sss command on real Blender renders (pytest), the
#                 add-on's tests inside every supported Blender on the
#                 self-contained library (make portable), the C tests
#                 under valgrind, and make check
#   make check    the C tests and the command's tests again under ASan +
#                 UBSan, warnings as errors
#   make valgrind the quick C tests under valgrind memcheck
#   make fuzz     coverage-guided fuzzing of the EXR and scene readers
#                 (clang's libFuzzer, FUZZ_SECONDS per target)
#   make deps     install the missing Debian packages (as root)
#   make bpy      install Blender 4.5 and 5.0 as Python modules into build/
#   make addon    the add-on: build/separable_sss.zip (3.4) and the
#                 extension build/separable_sss-VERSION-PLATFORM.zip (4.2+)
#   make portable the library and sss for linux-x64, windows-x64,
#                 macos-arm64 and macos-x64, self-contained (OpenEXR,
#                 libdeflate, cJSON linked in), cross-compiled with Zig:
#                 build/portable/PLATFORM
#   make portable-test  their C tests and sss runs: Linux natively,
#                 Windows under Wine; every build's dependencies checked
#   make dist     build/dist: one extension zip per platform, the 3.4 zip
#                 and the sss command per platform (sss-VERSION-PLATFORM.zip)
#   make blender-test  the add-on's tests in every supported Blender
#   make farm-test the OpenJD template (openjd run) and the Flamenco job type
#                 (compiled under Node) on 3 frames in Blender 3.4, 4.5, 5.0
#   make demo     render the bundled head-sized skin scene headlessly with
#                 the add-on: out/demo.exr and out/demo.png (before | after)
#   make demo-c   the library on synthetic passes, no Blender
#   make report   separable against the brute-force reference at 512x512
#   make bench    speed: cost per scattering pixel and the ratios that
#                 matter, into out/bench
#   make compare  libsss against Cycles random walk and EEVEE on the three
#                 bundled scenes: out/compare/SCENE/{sheet,plot}.png, results.*
#   make sweep    never worse than no SSS: every bundled scene and a
#                 sharp-edged one, radius 1e-6x to 1e3x, against Cycles 4.5's
#                 random walk: out/compare/sweep/SCENE/sweep.{png,md,csv}
#                 and out/compare/sweep/summary.{png,md}
#   make figures  the README's picture docs/images/head.png (compare on
#                 head: ours and the random walk at equal time, denoised)
#   make screenshots  the add-on's panels, docs/images/ui-*.png, and a live
#                 re-tune in a window, docs/images/live.png (Xvfb, 3.4)
#   make clean    remove build/
#
# Results must not depend on the compiler contracting a*b+c into an FMA:
# -ffp-contract=off, and never -ffast-math (see docs/library.md, Determinism).

CC      ?= cc
CFLAGS  ?= -O2 -g
BUILD   ?= build
WARN    := -std=c11 -Wall -Wextra -Wpedantic -Wshadow -Wstrict-prototypes \
           -Wmissing-prototypes
BASE    := $(WARN) -fPIC -fvisibility=hidden -ffp-contract=off \
           -D_POSIX_C_SOURCE=200809L -pthread
# OpenEXR's C API (OpenEXRCore), libdeflate (its ZIP chunks, faster than
# the zlib OpenEXRCore calls) and cJSON, all from Debian.
EXR_INC := $(shell pkg-config --cflags-only-I OpenEXR 2>/dev/null || echo -I/usr/include/OpenEXR)
LIB_INC := $(EXR_INC) -I/usr/include/cjson
LDLIBS  := -lOpenEXRCore -ldeflate -lcjson -lm -pthread

LIB_SRC   := $(sort $(filter-out csrc/sss_main.c,$(wildcard csrc/sss_*.c)))
LIB_HDR   := $(sort $(wildcard csrc/sss*.h))
TEST_SRC  := $(sort $(wildcard tests/test_*.c))
TESTS     := $(patsubst tests/%.c,$(BUILD)/tests/%,$(TEST_SRC)) \
             $(BUILD)/tests/fuzz_replay

.PHONY: all deps bpy farm-test portable portable-test dist test check valgrind fuzz demo demo-c report bench addon blender-test compare sweep error-budget figures screenshots clean

all: $(BUILD)/libsss.so $(BUILD)/sss

# Each library source is compiled once, position-independent, into
# $(BUILD)/obj; the shared library, the command and every test link those
# objects (the tests and the command through the static archive).
LIB_OBJ := $(patsubst csrc/%.c,$(BUILD)/obj/%.o,$(LIB_SRC))
$(BUILD)/obj/%.o: csrc/%.c $(LIB_HDR) Makefile
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) $(BASE) $(LIB_INC) -c -o $@ $<

$(BUILD)/libsss.a: $(LIB_OBJ)
	@rm -f $@
	$(AR) rcs $@ $(LIB_OBJ)

$(BUILD)/libsss.so: $(LIB_OBJ)
	$(CC) $(CFLAGS) $(BASE) -shared -o $@ $(LIB_OBJ) $(LDLIBS)

# The command links the library's objects in, so it runs from anywhere.
$(BUILD)/sss: csrc/sss_main.c csrc/sss.h $(BUILD)/libsss.a Makefile
	$(CC) $(CFLAGS) $(BASE) $(LIB_INC) -o $@ csrc/sss_main.c \
		$(BUILD)/libsss.a $(LDLIBS)

# Tests link the static archive so that they can also reach internal
# helpers; the shared library is what ships and what nm checks.
$(BUILD)/tests/%: tests/%.c tests/test_util.h tests/synth.h $(BUILD)/libsss.a $(LIB_HDR) Makefile
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) $(BASE) $(LIB_INC) -Icsrc -o $@ $< $(BUILD)/libsss.a \
		$(LDLIBS) $(if $(findstring test_oom,$@),$(WRAP_ALLOC))
# (the measured points test_transmission checks the library against)
$(BUILD)/tests/test_transmission: $(wildcard tests/transmission4_*_measured.h)

# The fuzz harness without libFuzzer: replays tests/fuzz/corpus (seeds and
# every input the fuzzer ever failed on) in make test and make check.
$(BUILD)/tests/fuzz_replay: tests/fuzz/replay.c tests/fuzz/fuzz_exr.c $(BUILD)/libsss.a $(LIB_HDR) Makefile
	@mkdir -p $(@D)
	$(CC) $(CFLAGS) $(BASE) $(LIB_INC) -D_GNU_SOURCE -Icsrc \
		-DFUZZ_CORPUS='"$(abspath tests/fuzz/corpus)"' -o $@ \
		tests/fuzz/replay.c tests/fuzz/fuzz_exr.c $(BUILD)/libsss.a $(LDLIBS)

# Coverage-guided fuzzing with libFuzzer (clang): FUZZ_SECONDS per run.
FUZZ_SECONDS ?= 60
fuzz: all
	@BUILD=$(BUILD) sh scripts/fuzz.sh $(FUZZ_SECONDS)

# test_oom sees every allocation the library's own code makes.
WRAP_ALLOC := -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc

deps:
	@sh scripts/install-deps.sh

# Debian's interpreter: it has numpy, pytest and OpenImageIO (the first
# python3 on PATH may be another one without them).
PYTHON ?= /usr/bin/python3

test: deps all $(TESTS) addon $(BUILD)/sss-bench $(BUILD)/sss-retune
	@sh tests/run_c_tests.sh $(BUILD) $(TESTS)
	@SSS_BUILD=$(abspath $(BUILD)) $(PYTHON) -m pytest -q -p no:cacheprovider \
		--ignore=tests/python/test_portable.py tests/python
	@$(MAKE) --no-print-directory portable
	@lib=$(abspath $(BUILD))/portable/$(ADDON_PLATFORM)/libsss.so; \
	[ -f "$$lib" ] || lib=$(abspath $(BUILD))/libsss.so; \
	echo "blender-test: the add-on on $$lib"; \
	SSS_LIB=$$lib $(MAKE) --no-print-directory blender-test
	@$(MAKE) --no-print-directory farm-test
	@$(MAKE) --no-print-directory portable-test
	@if command -v valgrind >/dev/null; then \
		$(MAKE) --no-print-directory valgrind; \
	else echo "make valgrind: skipped (valgrind is not installed)"; fi
	@if sh scripts/sanitizers-supported.sh "$(CC)"; then \
		$(MAKE) --no-print-directory check; \
	else echo "make check: skipped ($(CC) cannot build with ASan+UBSan here)"; fi

# Valgrind memcheck on the C tests whose run stays short under it (the
# blur and extreme-value tests run under ASan instead: too slow here).
VALGRIND_TESTS := $(filter-out %/test_blur %/test_extremes %/test_methods,$(TESTS))
valgrind: $(VALGRIND_TESTS)
	@TEST_RUNNER="valgrind -q --error-exitcode=99 --leak-check=full \
		--errors-for-leak-kinds=definite" \
		sh tests/run_c_tests.sh $(BUILD) $(VALGRIND_TESTS)

# Sanitizer build: every C test and the command's tests again with ASan +
# UBSan, warnings as errors.
SAN := -O1 -g -fsanitize=address,undefined -fno-omit-frame-pointer \
       -fno-sanitize-recover=all -Werror
check:
	@$(MAKE) --no-print-directory BUILD=$(BUILD)/check CFLAGS="$(SAN)" \
		$(patsubst $(BUILD)/%,$(BUILD)/check/%,$(TESTS)) $(BUILD)/check/libsss.so \
		$(BUILD)/check/sss $(BUILD)/check/sss-bench $(BUILD)/check/sss-retune
	@ASAN_OPTIONS=detect_leaks=1:exitcode=86 UBSAN_OPTIONS=print_stacktrace=1:exitcode=87 \
		SSS_BUILD=$(abspath $(BUILD))/check $(PYTHON) -m pytest -q \
		-p no:cacheprovider --ignore=tests/python/test_portable.py tests/python
	@ASAN_OPTIONS=detect_leaks=1:exitcode=86 UBSAN_OPTIONS=print_stacktrace=1:exitcode=87 \
		sh tests/run_c_tests.sh $(BUILD)/check \
		$(patsubst $(BUILD)/%,$(BUILD)/check/%,$(TESTS))

# The add-on as Blender installs it, from one code base: the legacy zip
# (3.4: Preferences > Add-ons > Install, the library beside the code) and
# the extension (4.2+: Get Extensions > Install from Disk, the library in a
# platform wheel under wheels/).
ADDON_FILES := $(sort $(wildcard addon/separable_sss/*.py addon/separable_sss/*.toml addon/separable_sss/presets/*/*.py))
ADDON_VERSION := $(shell sed -n 's/^version = "\(.*\)"/\1/p' addon/separable_sss/blender_manifest.toml)
ADDON_PLATFORM := $(if $(filter aarch64,$(shell uname -m)),linux-arm64,linux-x64)
EXTENSION_ZIP := $(BUILD)/separable_sss-$(ADDON_VERSION)-$(ADDON_PLATFORM).zip
addon: $(BUILD)/separable_sss.zip
$(BUILD)/separable_sss.zip: $(ADDON_FILES) $(BUILD)/libsss.so scripts/build_addon.py
	@$(PYTHON) scripts/build_addon.py --library $(BUILD)/libsss.so --out $(BUILD)

# Self-contained builds for every platform Blender runs on, cross-compiled
# with Zig (PyPI's ziglang, pinned) from pinned, hash-checked sources
# (scripts/build_portable.py); objects are kept, so a second run only
# checks. The C tests are built for each platform too, except test_exr (its
# own EXR writer calls OpenEXR 3.1's API in a way 3.3 refuses) and test_oom
# (ld's --wrap, which Zig's linker lacks); the Debian build runs those.
PORTABLE_PLATFORMS ?= linux-x64,windows-x64,macos-arm64,macos-x64
PORTABLE_TESTS := $(filter-out test_exr test_oom,$(patsubst tests/%.c,%,$(TEST_SRC)))
portable:
	@$(PYTHON) scripts/build_portable.py --build $(BUILD) \
		--platforms $(PORTABLE_PLATFORMS) \
		--tests $(shell echo $(PORTABLE_TESTS) | tr ' ' ,)

# The portable builds' C tests: linux-x64 natively, windows-x64 under Wine
# (skipped with a message where wine64 is missing); then the sss commands
# against the Debian build's output, bit for bit, and every build's
# dependencies (tests/python/test_portable.py); then build/dist's Linux
# zips (the portable library) installed into every supported Blender.
# macOS builds are checked, not run.
WINE ?= $(firstword $(wildcard /usr/lib/wine/wine64) $(shell command -v wine64 2>/dev/null))
portable-test: dist all
	@sh tests/run_c_tests.sh $(BUILD)/portable/linux-x64 \
		$(patsubst %,$(BUILD)/portable/linux-x64/tests/%,$(PORTABLE_TESTS))
	@if [ -n "$(WINE)" ]; then \
		WINEDEBUG=-all WINEPREFIX=$(abspath $(BUILD))/wine \
		TEST_RUNNER="$(WINE)" sh tests/run_c_tests.sh \
		$(BUILD)/portable/windows-x64 \
		$(patsubst %,$(BUILD)/portable/windows-x64/tests/%.exe,$(PORTABLE_TESTS)); \
	else echo "portable-test: Windows C tests skipped (wine64 is not installed)"; fi
	@SSS_BUILD=$(abspath $(BUILD)) SSS_WINE="$(WINE)" $(PYTHON) -m pytest -q \
		-p no:cacheprovider tests/python/test_portable.py
	@status=0; for b in $(BLENDERS); do \
		bash scripts/blender-tests.sh $$b $(abspath $(BUILD))/dist \
			tests/blender/test_install.py tests/blender/test_extension.py \
			|| status=1; \
	done; exit $$status

# What to download for each machine, in build/dist: the extension per
# platform, the legacy 3.4 zip (with the portable Linux library) and the
# sss command per platform, each with the licences of what is linked in.
comma := ,
DIST_PLATFORMS := $(subst $(comma), ,$(PORTABLE_PLATFORMS))
dist: portable
	@mkdir -p $(BUILD)/dist
	@for p in $(DIST_PLATFORMS); do \
		d=$(BUILD)/portable/$$p; \
		lib=$$(ls $$d/libsss.so $$d/libsss.dll $$d/libsss.dylib 2>/dev/null); \
		exe=$$(ls $$d/sss $$d/sss.exe 2>/dev/null); \
		$(PYTHON) scripts/build_addon.py --library $$lib --platform $$p \
			--command $$exe --out $(BUILD)/dist \
			--licences $(BUILD)/portable/THIRD_PARTY_LICENSES.txt || exit 1; \
	done

# Supported Blenders: Debian's blender (3.4) and, from PyPI, Blender as a
# Python module (bpy, pinned), each in a virtual environment under the
# build folder with a `blender` command line (scripts/bpy_blender.py):
# BLENDER=$(BUILD)/bpy-4.5.15/bin/blender runs demo or compare on 4.5.
BLENDER ?= blender
BPY_VERSIONS ?= 4.5.15 5.0.1
BPY_BLENDERS := $(patsubst %,$(BUILD)/bpy-%/bin/blender,$(BPY_VERSIONS))
BLENDERS ?= $(BLENDER) $(BPY_BLENDERS)
bpy: $(BPY_BLENDERS)
$(BUILD)/bpy-%/bin/blender: scripts/install-bpy.sh scripts/bpy_blender.py
	@sh scripts/install-bpy.sh $* $(abspath $(BUILD))/bpy-$*

# Blender's own Python runs these (they import bpy); each file in its own
# Blender process, with an empty user folder, on every supported Blender.
BLENDER_TESTS := $(sort $(wildcard tests/blender/test_*.py))
blender-test: all addon $(filter $(BUILD)/%,$(BLENDERS))
	@status=0; for b in $(BLENDERS); do \
		bash scripts/blender-tests.sh $$b $(abspath $(BUILD)) \
			$(BLENDER_TESTS) || status=1; \
	done; exit $$status

# The farm integrations (farm/): the OpenJD template through a real
# `openjd run` (PyPI's openjd-cli, pinned with hashes, in a virtual
# environment under the build folder) and the Flamenco job type compiled
# under Node, each on a 3-frame job in Blender 3.4, 4.5 and 5.0 (tests/farm/).
OPENJD_VENV := $(BUILD)/openjd
$(OPENJD_VENV)/.installed: tests/farm/openjd-requirements.txt
	@echo "installing openjd-cli into $(OPENJD_VENV)"
	@rm -rf $(OPENJD_VENV)
	@$(PYTHON) -m venv $(OPENJD_VENV)
	@$(OPENJD_VENV)/bin/python -m pip install -q --disable-pip-version-check \
		--require-hashes --only-binary :all: \
		-r tests/farm/openjd-requirements.txt 2>&1 | grep -v "^WARNING: Location" || true
	@$(OPENJD_VENV)/bin/openjd --version >/dev/null || \
		{ echo "openjd-cli did not install into $(OPENJD_VENV)" >&2; exit 1; }
	@touch $@
farm-test: all addon $(OPENJD_VENV)/.installed $(BPY_BLENDERS)
	@SSS_BUILD=$(abspath $(BUILD)) $(PYTHON) -m pytest -q -p no:cacheprovider tests/farm

$(BUILD)/sss-demo: examples/demo.c tests/synth.h $(BUILD)/libsss.so
	$(CC) $(CFLAGS) $(WARN) -D_POSIX_C_SOURCE=200809L -Icsrc -Itests -o $@ \
		examples/demo.c -L$(BUILD) -lsss -Wl,-rpath,'$$ORIGIN' -lpng $(LDLIBS)

# The demo: a head-sized object with a skin material lit from the side and
# from behind, rendered headlessly with the add-on's pipeline.
DEMO_SIZE ?= 400
DEMO_SAMPLES ?= 32
demo: deps all
	@mkdir -p out $(BUILD)/demo
	@$(BLENDER) -b --factory-startup --python-exit-code 1 \
		--python blender_scripts/build_scene.py -- --kind demo \
		--out $(BUILD)/demo/demo.blend --size $(DEMO_SIZE) \
		--samples $(DEMO_SAMPLES) | grep build_scene
	@SSS_LIB=$(abspath $(BUILD))/libsss.so $(BLENDER) -b $(BUILD)/demo/demo.blend \
		--python-exit-code 1 --python blender_scripts/render_sss.py -- \
		--output $(abspath out)/demo.exr | grep render_sss
	@$(PYTHON) scripts/side_by_side.py out/demo.exr out/demo.png
	@echo "demo: wrote $(abspath out)/demo.exr (all passes + SSS layer)"
	@echo "demo: wrote $(abspath out)/demo.png (left: without SSS, right: with SSS)"

# The same idea without Blender: synthetic passes through the C API.
demo-c: $(BUILD)/sss-demo
	@$(BUILD)/sss-demo $(BUILD)/demo-c

$(BUILD)/sss-report: examples/method_report.c tests/synth.h $(BUILD)/libsss.so
	$(CC) $(CFLAGS) $(WARN) -D_POSIX_C_SOURCE=200809L -Icsrc -Itests -o $@ \
		examples/method_report.c -L$(BUILD) -lsss -Wl,-rpath,'$$ORIGIN' $(LDLIBS)

# The benchmark: cost per scattering pixel over sizes, coverage and radii
# for every method, and the ratios that matter (threads, AVX2, reference,
# Blender's Bilateral Blur, sss end to end vs oiiotool), into out/bench.
$(BUILD)/sss-bench: bench/sss_bench.c tests/synth.h $(BUILD)/libsss.so
	$(CC) $(CFLAGS) $(WARN) -D_POSIX_C_SOURCE=200809L -Icsrc -Itests -o $@ \
		bench/sss_bench.c -L$(BUILD) -lsss -Wl,-rpath,'$$ORIGIN' $(LDLIBS)

# A live re-tune's scatter on a real frame: one frame read, scattered again.
$(BUILD)/sss-retune: bench/sss_retune.c $(BUILD)/libsss.so
	$(CC) $(CFLAGS) $(WARN) -D_POSIX_C_SOURCE=200809L -Icsrc -o $@ \
		bench/sss_retune.c -L$(BUILD) -lsss -Wl,-rpath,'$$ORIGIN' $(LDLIBS)

bench: deps all $(BUILD)/sss-bench $(BUILD)/sss-retune
	@$(PYTHON) bench/run_bench.py --out out/bench --build $(BUILD)

# Separable against reference for Burley at three radii, with timings.
report: $(BUILD)/sss-report
	@$(BUILD)/sss-report 512

# The speed/accuracy trade: each bundled scene (blender_scripts/build_scene.py
# kinds head, marble, mixed) rendered with Cycles random walk, Cycles with SSS
# off plus every method the library accepts, EEVEE's own SSS and EEVEE plus
# our methods (blender_scripts/compare.py). COMPARE_ARGS=--quick for a fast run.
COMPARE_SCENES ?= head marble mixed
COMPARE_ARGS ?=
compare: deps all
	@mkdir -p out/compare $(BUILD)/compare
	@for kind in $(COMPARE_SCENES); do \
		log=$(BUILD)/compare/$$kind.log; \
		$(BLENDER) -b --factory-startup --python-exit-code 1 \
			--python blender_scripts/build_scene.py -- --kind $$kind \
			--out $(BUILD)/compare/$$kind.blend >$$log 2>&1 && \
		SSS_LIB=$(abspath $(BUILD))/libsss.so $(BLENDER) -b --factory-startup \
			--python-exit-code 1 --python blender_scripts/compare.py -- \
			--scene $(BUILD)/compare/$$kind.blend --out out/compare/$$kind \
			$(COMPARE_ARGS) >>$$log 2>&1 || { tail -n 40 $$log; exit 1; }; \
		grep -E "^(compare|scene|  |$$kind: )" $$log; \
	done
	@cat $(patsubst %,out/compare/%/summary.txt,$(COMPARE_SCENES)) \
		>out/compare/summary.txt
	@echo "compare: wrote out/compare/SCENE/{sheet.png,plot.png,time.png,results.csv,results.md} and out/compare/summary.txt"

# Never worse than no SSS: every bundled scene, the sharp-edged block and
# a small front-lit sphere seen orthographically, with every Subsurface
# scaled from 1e-6x to 1e3x, against the random walk of the Blender artists
# use (4.5 LTS; SWEEP_BLENDER=blender for 3.4)
# (blender_scripts/sweep_radius.py): out/compare/sweep/SCENE/sweep.{png,md,csv}.
SWEEP_SCENES ?= head marble mixed block sphere
SWEEP_ARGS ?=
SWEEP_BLENDER ?= $(word 1,$(BPY_BLENDERS))
sweep: deps all $(filter $(BUILD)/%,$(SWEEP_BLENDER))
	@mkdir -p out/compare/sweep $(BUILD)/compare
	@for kind in $(SWEEP_SCENES); do \
		log=$(BUILD)/compare/sweep_$$kind.log; \
		$(SWEEP_BLENDER) -b --factory-startup --python-exit-code 1 \
			--python blender_scripts/build_scene.py -- --kind $$kind \
			--out $(BUILD)/compare/sweep_$$kind.blend >$$log 2>&1 && \
		SSS_LIB=$(abspath $(BUILD))/libsss.so $(SWEEP_BLENDER) -b --factory-startup \
			--python-exit-code 1 --python blender_scripts/sweep_radius.py -- \
			--scene $(BUILD)/compare/sweep_$$kind.blend \
			--name $$kind --out out/compare/sweep/$$kind $(SWEEP_ARGS) \
			>>$$log 2>&1 \
			|| { tail -n 40 $$log; exit 1; }; \
		grep -E '^sweep' $$log; \
	done
	@$(PYTHON) scripts/sweep_summary.py out/compare/sweep \
		--scenes $(shell echo $(SWEEP_SCENES) | tr ' ' ,)

# Where our remaining error is, by cause (calibration, silhouettes,
# transmission, crevices, the rest), on every bundled scene with OIDN on
# both sides, and ours + OIDN against the denoised random walk at equal
# time (blender_scripts/error_budget.py): out/error_budget/SCENE/
# {budget.md,budget.json,errors.png,time.png} and out/error_budget/summary.md. The
# reference renders (random walk, BUDGET_ARGS' --ref-samples, default
# 1024) are kept in $(BUILD)/error_budget/cache/DIGEST/ and reused while
# the scripts that build the scenes and render them are unchanged (DIGEST:
# their SHA-1; a scene built otherwise gets new references). Ours (at 16, 32, 64
# spp) and the walk are rendered with eight seeds and their squared errors
# pooled: at 16 spp one seed's error is a draw (docs/comparison.md, over
# seeds).
BUDGET_SCENES ?= head marble mixed block sphere
BUDGET_ARGS ?= --seeds 8 --samples 16,32,64
BUDGET_BLENDER ?= $(word 1,$(BPY_BLENDERS))
BUDGET_CACHE = $(BUILD)/error_budget/cache/$(shell cat \
	blender_scripts/build_scene.py blender_scripts/compare_runs.py | \
	sha1sum | cut -c1-12)
error-budget: deps all $(filter $(BUILD)/%,$(BUDGET_BLENDER))
	@mkdir -p out/error_budget $(BUILD)/error_budget
	@for kind in $(BUDGET_SCENES); do \
		log=$(BUILD)/error_budget/$$kind.log; \
		$(BUDGET_BLENDER) -b --factory-startup --python-exit-code 1 \
			--python blender_scripts/build_scene.py -- --kind $$kind \
			--out $(BUILD)/error_budget/$$kind.blend >$$log 2>&1 && \
		SSS_LIB=$(abspath $(BUILD))/libsss.so $(BUDGET_BLENDER) -b \
			--factory-startup --python-exit-code 1 \
			--python blender_scripts/error_budget.py -- \
			--scene $(BUILD)/error_budget/$$kind.blend --name $$kind \
			--out out/error_budget/$$kind \
			--cache $(BUDGET_CACHE) $(BUDGET_ARGS) >>$$log 2>&1 \
			|| { tail -n 40 $$log; exit 1; }; \
		grep -E '^(budget|\|)' $$log; \
	done
	@$(BUDGET_BLENDER) -b --factory-startup --python-exit-code 1 \
		--python blender_scripts/error_budget.py -- --summary out/error_budget

# The README's picture at equal wall time, both sides denoised: the head
# scene without SSS, with the library, with Cycles' random walk at the
# count whose time is closest to ours, and the reference, each with its
# time and error, from a compare run on head that keeps its images
# (scripts/readme_figure.py): docs/images/head.png. FIGURE_ARGS are
# compare.py's options for that run; BLENDER=build/bpy-4.5.15/bin/blender
# for the committed picture.
FIGURE_ARGS ?= --samples 64 --rw-samples 1,2,4,8,16,32,64,128,1024 --no-eevee
figures:
	@SSS_COMPARE_KEEP_WORK=1 $(MAKE) --no-print-directory compare \
		COMPARE_SCENES=head COMPARE_ARGS="$(FIGURE_ARGS)"
	@$(PYTHON) scripts/readme_figure.py --compare out/compare/head \
		--out docs/images/head.png

# The add-on's panels in a real Blender window (Debian's 3.4 under Xvfb:
# the bpy builds have no windows), on the bundled head scene:
# docs/images/ui-*.png (scripts/ui_screenshots.py), each looked at before
# it is committed.
SHOT_RUN = xvfb-run -a -s "-screen 0 1920x1080x24" $(BLENDER) \
	--factory-startup --enable-event-simulate --python \
	scripts/ui_screenshots.py -- $(BUILD)/screenshots/head.blend docs/images
screenshots: deps all
	@mkdir -p $(BUILD)/screenshots
	@$(BLENDER) -b --factory-startup --python-exit-code 1 \
		--python blender_scripts/build_scene.py -- --kind head \
		--out $(BUILD)/screenshots/head.blend --size 320 --samples 16 \
		| grep build_scene
	@SSS_LIB=$(abspath $(BUILD))/libsss.so $(SHOT_RUN) | grep ui_screenshots
	@SSS_LIB=$(abspath $(BUILD))/libsss.so $(SHOT_RUN) --open \
		| grep ui_screenshots
	@SSS_LIB=$(abspath $(BUILD))/libsss.so xvfb-run -a -s "-screen 0 1280x720x24" \
		$(BLENDER) --factory-startup --enable-event-simulate --python \
		scripts/live_screenshot.py -- $(BUILD)/screenshots/head.blend \
		$(BUILD)/screenshots | grep live_screenshot
	@cp $(BUILD)/screenshots/live.png docs/images/live.png

# docs/scene.md's rows for material fields that have none yet, from the
# library's schema (scripts/scene_doc.py); test_scene checks every row.
scene-doc: all
	@SSS_LIB=$(abspath $(BUILD))/libsss.so $(PYTHON) scripts/scene_doc.py

clean:
	rm -rf $(BUILD)
