#!/bin/sh
# Builds the libFuzzer harness (tests/fuzz/fuzz_exr.c: EXR reader and
# scene parser) with ASan + UBSan and fuzzes it for SECONDS in all (default
# 60; 3/4 on EXR files, 1/4 on scene descriptions), on one core.
#
#   sh scripts/fuzz.sh [SECONDS] [all|exr|scene]
#
# Environment: BUILD (default build), FUZZ_CC (default clang),
# FUZZ_MERGE=0 to leave tests/fuzz/corpus alone.
#
# New inputs go to $BUILD/fuzz/work-TARGET, never into the repository.
# Afterwards the ones that add coverage over the committed corpus are
# found with -merge=1 and at most 50 small ones (<= 4 KiB) copied into
# tests/fuzz/corpus/TARGET. Crashes, leaks and timeouts are left in
# $BUILD/fuzz/artifacts; the exit status is then 1: minimise the input
# (the fuzzer with -minimize_crash=1), fix the bug, and add the input to
# tests/fuzz/corpus/regressions so that `make test` replays it.
set -eu
seconds=${1:-60}
which=${2:-all}
root=$(cd "$(dirname "$0")/.." && pwd)
build=${BUILD:-build}
case $build in /*) ;; *) build=$root/$build ;; esac
cc=${FUZZ_CC:-clang}
out=$build/fuzz
fuzz_dir=$root/tests/fuzz
corpus=$fuzz_dir/corpus
mkdir -p "$out/artifacts"

case $seconds in '' | *[!0-9]*)
	echo "fuzz.sh: SECONDS must be a whole number, got '$seconds'" >&2
	exit 2 ;;
esac
case $which in all | exr | scene) ;; *)
	echo "fuzz.sh: target must be all, exr or scene, got '$which'" >&2
	exit 2 ;;
esac

# ------------------------------------------------------------------ build
exr_inc=$(pkg-config --cflags-only-I OpenEXR 2>/dev/null ||
	echo -I/usr/include/OpenEXR)
lib_src=$(ls "$root"/csrc/sss_*.c | grep -v '/sss_main\.c$')
bin=$out/fuzz_exr
# shellcheck disable=SC2086
if ! "$cc" -O1 -g -fno-omit-frame-pointer \
	-fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all \
	-std=c11 -Wall -Wextra -Wpedantic -Wshadow -Wstrict-prototypes \
	-Wmissing-prototypes -ffp-contract=off -D_POSIX_C_SOURCE=200809L \
	-pthread $exr_inc -I/usr/include/cjson -I"$root/csrc" -o "$bin" \
	"$fuzz_dir/fuzz_exr.c" $lib_src -lOpenEXRCore -lcjson -lm -pthread; then
	echo "fuzz.sh: cannot build with $cc -fsanitize=fuzzer (Debian:" \
		"apt-get install clang libclang-rt-dev)" >&2
	exit 2
fi
echo "fuzz.sh: built $bin"

# -------------------------------------------------------------------- run
status=0
# run TARGET SECONDS DICT: one libFuzzer job on one core (-jobs=1
# -workers=1: its log is $out/fuzz-0.log, shown at the end).
run() {
	target=$1 secs=$2 dict=$3
	work=$out/work-$target
	mkdir -p "$work"
	[ "$secs" -gt 0 ] || return 0
	echo "fuzz.sh: fuzzing $target for ${secs}s"
	rm -f "$out/fuzz-0.log"
	rc=0
	(cd "$out" && ASAN_OPTIONS=detect_leaks=1 \
		UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
		"$bin" -jobs=1 -workers=1 -max_total_time="$secs" -max_len=65536 \
		-timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
		-dict="$fuzz_dir/$dict" -artifact_prefix="$out/artifacts/" \
		"$work" "$corpus/$target" "$corpus/regressions") >/dev/null 2>&1 ||
		rc=$?
	log=$out/fuzz-$target.log
	[ -f "$out/fuzz-0.log" ] && mv "$out/fuzz-0.log" "$log"
	grep -E '^#[0-9]+.*(DONE|pulse|NEW)' "$log" 2>/dev/null | tail -n 1 || true
	grep -E '^stat::(number_of_executed_units|average_exec_per_sec|peak_rss)' \
		"$log" 2>/dev/null || true
	if [ "$rc" -ne 0 ] ||
		grep -qE 'ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer)|runtime error|ALARM|fuzz_exr: ' "$log"; then
		echo "fuzz.sh: $target: FAILED (exit $rc); see $log and $out/artifacts"
		grep -E 'ERROR:|SUMMARY|runtime error|fuzz_exr: |Test unit written' \
			"$log" | head -n 20 || true
		status=1
	fi
	merge "$target"
}

# merge TARGET: new coverage over the committed corpus, small files only.
merge() {
	target=$1
	[ "${FUZZ_MERGE:-1}" != 0 ] || return 0
	[ "$status" -eq 0 ] || return 0
	m=$out/merge-$target
	rm -rf "$m" && mkdir -p "$m"
	cp "$corpus/$target"/* "$m"/ 2>/dev/null || true
	cp "$corpus/regressions"/* "$m"/ 2>/dev/null || true
	ls "$m" | sort >"$out/before-$target"
	(cd "$out" && "$bin" -merge=1 -max_len=65536 -timeout=10 \
		-rss_limit_mb=2048 "$m" "$out/work-$target") >"$out/merge-$target.log" 2>&1 ||
		{ echo "fuzz.sh: merge failed, see $out/merge-$target.log"; return 0; }
	n=0
	# smallest first, at most 50, each at most 4 KiB
	for f in $(cd "$m" && ls -Sr); do
		grep -qxF "$f" "$out/before-$target" && continue
		[ "$(wc -c <"$m/$f")" -le 4096 ] || continue
		[ "$n" -lt 50 ] || break
		cp "$m/$f" "$corpus/$target/fuzz-$f"
		n=$((n + 1))
	done
	echo "fuzz.sh: $target: $n new small inputs added to tests/fuzz/corpus/$target"
}

case $which in
all)
	exr_s=$((seconds * 3 / 4))
	run exr "$exr_s" exr.dict
	run scene $((seconds - exr_s)) scene.dict ;;
exr) run exr "$seconds" exr.dict ;;
scene) run scene "$seconds" scene.dict ;;
esac
exit $status
