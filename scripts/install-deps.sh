#!/bin/sh
# Installs the Debian packages the build and tests need, when they are
# missing and we are root; otherwise says what to install. Idempotent.
set -u
# Build: compiler, OpenEXR's C API, cJSON, libpng (demo). Tests: Blender
# renders real scenes; Debian's python3 with numpy, pytest and OpenImageIO
# checks the results independently of the code under test. The comparison
# (make compare) plots with matplotlib and renders EEVEE under Xvfb with
# Mesa's software OpenGL. make bench times oiiotool (openimageio-tools).
# python3-venv: the virtual environments for Blender 4.5 and 5.0 (bpy) and
# openjd-cli. nodejs: the Flamenco job type's compile test (tests/farm/).
# The portable builds (scripts/build_portable.py): Debian's source
# packages of libdeflate and cJSON (the deb-src list below) with Debian's
# patches (patch); the Windows build's tests run under Wine (wine64).
PACKAGES="gcc make libc6-dev pkg-config binutils libpng-dev libopenexr-dev
libcjson-dev libdeflate-dev blender python3 python3-venv python3-numpy python3-pytest python3-openimageio
valgrind python3-matplotlib xvfb xauth libgl1-mesa-dri openimageio-tools nodejs patch wine64"
# The source lists are the machine's own binary ones, as deb-src.
SOURCES=/etc/apt/sources.list.d/libsss-src
update=""
if [ ! -e "$SOURCES.sources" ] && [ ! -e "$SOURCES.list" ] &&
	[ "$(id -u)" = 0 ] && [ -d /etc/apt/sources.list.d ] &&
	! grep -rqs "^Types:.*deb-src\|^deb-src" /etc/apt/sources.list /etc/apt/sources.list.d; then
	if [ -f /etc/apt/sources.list.d/debian.sources ]; then
		sed 's/^Types: deb$/Types: deb-src/' \
			/etc/apt/sources.list.d/debian.sources >"$SOURCES.sources"
	elif [ -f /etc/apt/sources.list ]; then
		sed -n 's/^deb /deb-src /p' /etc/apt/sources.list >"$SOURCES.list"
	fi
	update=yes
fi
missing=""
for p in $PACKAGES; do
	dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" \
		|| missing="$missing $p"
done
if [ -z "$missing" ]; then
	[ -z "$update" ] || apt-get update -qq
	exit 0
fi
if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
	echo "installing:$missing"
	export DEBIAN_FRONTEND=noninteractive
	apt-get update -qq && apt-get install -y -qq --no-install-recommends $missing \
		>/dev/null || { echo "apt-get install failed for:$missing" >&2; exit 1; }
else
	echo "missing Debian packages:$missing (run as root, or: sudo apt-get install$missing)" >&2
	exit 1
fi
