#!/bin/sh
# Installs Blender as a Python module (PyPI's bpy, pinned) into a virtual
# environment and writes DIR/bin/blender, a `blender` command line for it
# (scripts/bpy_blender.py). The environment sees Debian's packages (pytest,
# OpenImageIO, matplotlib), as Debian's Blender does. Idempotent.
# Usage: scripts/install-bpy.sh VERSION DIR [PYTHON]
set -eu
version=$1 dir=$2 python=${3:-/usr/bin/python3}
here=$(cd "$(dirname "$0")" && pwd)
if ! "$dir/bin/python" -c "import importlib.metadata as m, sys; \
sys.exit(m.version('bpy') != '$version')" 2>/dev/null; then
	echo "installing bpy $version into $dir (Blender as a Python module)"
	rm -rf "$dir"
	"$python" -m venv --system-site-packages "$dir"
	"$dir/bin/python" -m pip install -q --disable-pip-version-check \
		"bpy==$version" 2>&1 | grep -v "^WARNING: Location" || true
	"$dir/bin/python" -c "import bpy" >/dev/null ||
		{ echo "bpy $version did not install into $dir" >&2; exit 1; }
fi
cat >"$dir/bin/blender.tmp" <<WRAPPER
#!/bin/sh
# Blender $version as a Python module, with Blender's command line.
exec "$dir/bin/python" "$here/bpy_blender.py" "\$@"
WRAPPER
chmod +x "$dir/bin/blender.tmp"
mv "$dir/bin/blender.tmp" "$dir/bin/blender"
