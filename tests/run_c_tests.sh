#!/bin/sh
# Runs each C test program, then checks the shared library's exported
# symbols; prints one closing "N passed, N failed" line over everything.
set -u
build=$1
shift
passed=0
failed=0
for t in "$@"; do
	out=$(${TEST_RUNNER:-} "$t" 2>&1)
	rc=$?
	printf '%s\n' "$out" | grep -v -E '^(ok |[0-9]+ passed, [0-9]+ failed)'
	line=$(printf '%s\n' "$out" | grep -E '^[0-9]+ passed, [0-9]+ failed' | tail -n 1)
	p=$(printf '%s' "$line" | sed -E 's/^([0-9]+) passed.*/\1/')
	f=$(printf '%s' "$line" | sed -E 's/^[0-9]+ passed, ([0-9]+) failed.*/\1/')
	if [ -z "$line" ]; then p=0; f=1; echo "FAIL $(basename "$t"): no summary (exit $rc)"; fi
	if [ "$rc" -ne 0 ] && [ "$f" -eq 0 ]; then f=1; echo "FAIL $(basename "$t"): exit $rc"; fi
	passed=$((passed + p))
	failed=$((failed + f))
done
# Only the public sss_ symbols may be exported from the shared library,
# not the internal sss__ ones.
lib="$build/libsss.so"
if [ -f "$lib" ]; then
	bad=$(nm -D --defined-only "$lib" | awk '{print $NF}' |
		grep -v -E '^sss_[a-z0-9]')
	if [ -n "$bad" ]; then
		echo "FAIL exported symbols that are not public sss_ ones: $bad"
		failed=$((failed + 1))
	else
		echo "exports: only sss_ symbols ($(nm -D --defined-only "$lib" | grep -c ' sss_'))"
		passed=$((passed + 1))
	fi
fi
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
