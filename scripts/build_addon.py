"""Packages the add-on for Blender, from one code base:

    build_addon.py --library build/libsss.so --out build

- build/separable_sss.zip: the legacy add-on (Blender 3.4: Preferences >
  Add-ons > Install), the library beside the code;
- build/separable_sss-VERSION-PLATFORM.zip: the extension (Blender 4.2 and
  later: Preferences > Get Extensions > Install from Disk), the library in
  a platform wheel under wheels/, as the extension rules ask for compiled
  code; Blender installs it into the extensions' site-packages.

Both are written to a temporary name and renamed into place.
"""
import argparse
import ast
import base64
import hashlib
import os
import platform
import re
import sys
import zipfile

HERE = os.path.dirname(os.path.abspath(__file__))
ADDON = os.path.join(HERE, "..", "addon", "separable_sss")
WHEEL_PACKAGE = "libsss_native"
# Blender's platform names and the wheel tags that go with them.
PLATFORMS = {"x86_64": ("linux-x64", "linux_x86_64"),
             "aarch64": ("linux-arm64", "linux_aarch64")}


def addon_files():
    for root, dirs, files in os.walk(ADDON):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__")
        for name in sorted(files):
            if name.endswith((".py", ".toml")):
                path = os.path.join(root, name)
                yield path, os.path.relpath(path, ADDON)


def bl_info_version():
    tree = ast.parse(open(os.path.join(ADDON, "__init__.py")).read())
    for node in tree.body:
        if isinstance(node, ast.Assign) and \
                getattr(node.targets[0], "id", "") == "bl_info":
            info = ast.literal_eval(node.value)
            return ".".join(str(v) for v in info["version"])
    sys.exit("build_addon: __init__.py has no bl_info")


def manifest_version(text):
    m = re.search(r'^version\s*=\s*"([^"]+)"', text, re.M)
    if not m:
        sys.exit("build_addon: blender_manifest.toml has no version")
    return m.group(1)


def write_zip(path, entries):
    """entries: (name in the zip, bytes); written atomically."""
    tmp = path + ".tmp"
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in entries:
            z.writestr(name, data)
    os.replace(tmp, path)


def record_line(name, data):
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest())
    return f"{name},sha256={digest.rstrip(b'=').decode()},{len(data)}"


def wheel(library, version, tag):
    """The wheel's file name and bytes: package libsss_native holding
    libsss.so, with the metadata a wheel needs (PEP 427)."""
    info = f"{WHEEL_PACKAGE}-{version}.dist-info"
    files = [
        (f"{WHEEL_PACKAGE}/__init__.py", (
            '"""libsss, the screen-space SSS library, for the Separable SSS'
            '\nadd-on: LIBRARY is its path."""\nimport os\n\nLIBRARY = '
            'os.path.join(os.path.dirname(os.path.abspath(__file__)),\n'
            '                       "libsss.so")\n').encode()),
        (f"{WHEEL_PACKAGE}/libsss.so", open(library, "rb").read()),
        (f"{info}/METADATA", (
            f"Metadata-Version: 2.1\nName: {WHEEL_PACKAGE}\nVersion: "
            f"{version}\nSummary: libsss for the Separable SSS add-on\n"
            "License: GPL-3.0-or-later\n").encode()),
        (f"{info}/WHEEL", (
            "Wheel-Version: 1.0\nGenerator: build_addon.py\n"
            f"Root-Is-Purelib: false\nTag: py3-none-{tag}\n").encode()),
    ]
    record = "\n".join([record_line(n, d) for n, d in files] +
                       [f"{info}/RECORD,,", ""])
    files.append((f"{info}/RECORD", record.encode()))
    return f"{WHEEL_PACKAGE}-{version}-py3-none-{tag}.whl", files


def main():
    p = argparse.ArgumentParser(prog="build_addon.py")
    p.add_argument("--library", required=True)
    p.add_argument("--out", required=True)
    args = p.parse_args()
    if not os.path.isfile(args.library):
        sys.exit(f"build_addon: {args.library}: no such library (run make)")
    machine = platform.machine()
    if machine not in PLATFORMS:
        sys.exit(f"build_addon: no Blender platform for {machine}")
    blender_platform, tag = PLATFORMS[machine]
    manifest = open(os.path.join(ADDON, "blender_manifest.toml")).read()
    version = manifest_version(manifest)
    if version != bl_info_version():
        sys.exit(f"build_addon: blender_manifest.toml says {version}, "
                 f"bl_info says {bl_info_version()}: make them agree")
    sources = [(rel, open(path, "rb").read()) for path, rel in addon_files()]
    library = open(args.library, "rb").read()
    os.makedirs(args.out, exist_ok=True)

    legacy = os.path.join(args.out, "separable_sss.zip")
    write_zip(legacy, [("separable_sss/" + rel, data)
                       for rel, data in sources] +
              [("separable_sss/libsss.so", library)])

    wheel_name, wheel_files = wheel(args.library, version, tag)
    wheel_path = os.path.join(args.out, wheel_name)
    write_zip(wheel_path, wheel_files)
    # Keys after a [table] header belong to it: these go before it.
    head, sep, tail = manifest.partition("\n[permissions]")
    manifest = head.rstrip("\n") + (f'\n\nplatforms = ["{blender_platform}"]'
                                    f'\nwheels = ["./wheels/{wheel_name}"]\n'
                                    ) + sep + tail if sep else manifest
    extension = os.path.join(
        args.out, f"separable_sss-{version}-{blender_platform}.zip")
    write_zip(extension, [(rel, manifest.encode() if rel ==
                           "blender_manifest.toml" else data)
                          for rel, data in sources] +
              [("wheels/" + wheel_name, open(wheel_path, "rb").read())])
    os.remove(wheel_path)
    print(f"add-on: {legacy} (Blender 3.4)")
    print(f"add-on: {extension} (extension, Blender 4.2 and later)")


if __name__ == "__main__":
    main()
