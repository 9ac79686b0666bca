#!/bin/bash
# Runs each tests/blender/test_*.py in its own headless Blender with an
# empty user folder (scripts, and from 4.2 extensions); Blender's per-frame
# chatter is filtered out. BLENDER may be a `blender` binary or the command
# line for the bpy module (scripts/install-bpy.sh); tests that start
# Blender themselves run the same one ($SSS_BLENDER).
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
	mkdir "$scripts/scripts" "$scripts/resources"
	BLENDER_USER_SCRIPTS=$scripts/scripts \
	BLENDER_USER_RESOURCES=$scripts/resources \
	SSS_BLENDER=$blender SSS_BUILD=$build \
	SSS_ADDON_ZIP=$build/separable_sss.zip \
	SSS_EXTENSION_ZIP=$(ls "$build"/separable_sss-*-linux-*.zip | head -n 1) \
		"$blender" -b --factory-startup --python-exit-code 1 \
		--python tests/blender/run.py -- "$t" 2>&1 |
		grep -v -E '^(Fra:|Blender quit|Read blend|Saved |Time:|Writing:|Error: Not freed|Warning: Unable|$)'
	rc=${PIPESTATUS[0]}
	rm -rf "$scripts"
	[ "$rc" -eq 0 ] || { echo "FAIL $t on $blender (exit $rc)"; status=1; }
done
exit $status
