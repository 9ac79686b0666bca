#!/bin/bash
# Runs each tests/blender/test_*.py in its own headless Blender with an
# empty user scripts folder; Blender's per-frame chatter is filtered out.
# Usage: scripts/blender-tests.sh BLENDER BUILD_DIR TEST...
set -u
blender=$1 build=$2
shift 2
if ! command -v "$blender" >/dev/null; then
	echo "blender-test: skipped (no $blender on PATH)"
	exit 0
fi
status=0
for t in "$@"; do
	scripts=$(mktemp -d)
	BLENDER_USER_SCRIPTS=$scripts SSS_BUILD=$build \
	SSS_ADDON_ZIP=$build/separable_sss.zip \
		"$blender" -b --factory-startup --python-exit-code 1 \
		--python tests/blender/run.py -- "$t" 2>&1 |
		grep -v -E '^(Fra:|Blender quit|Read blend|Saved |Time:|Writing:|Error: Not freed|Warning: Unable|$)'
	rc=${PIPESTATUS[0]}
	rm -rf "$scripts"
	[ "$rc" -eq 0 ] || { echo "FAIL $t (exit $rc)"; status=1; }
done
exit $status
