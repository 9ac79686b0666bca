"""Packages the add-on for Blender, from one code base:

    build_addon.py --library build/libsss.so --out build
    build_addon.py --library build/portable/windows-x64/libsss.dll \
        --platform windows-x64 --command build/portable/windows-x64/sss.exe \
        --licences build/portable/THIRD_PARTY_LICENSES.txt --out build/dist

- build/separable_sss.zip: the legacy add-on (Blender 3.4: Preferences >
  Add-ons > Install), the library beside the code;
- build/separable_sss-VERSION-PLATFORM.zip: the extension (Blender 4.2 and
  later: Preferences > Get Extensions > Install from Disk), the library in
  a platform wheel under wheels/, as the extension rules ask for compiled
  code; Blender installs it into the extensions' site-packages.
- with --command: build/sss-VERSION-PLATFORM.zip, the `sss` command for
  render farms.

--platform (default: this machine's) names the Blender platform the
library is for; the legacy zip is written only for a Linux library (Blender
3.4 on Debian). --licences adds the notices of the libraries linked into
the library to every package.

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
# This machine's Blender platform, for the Debian-linked library.
MACHINES = {"x86_64": "linux-x64", "aarch64": "linux-arm64"}
# Blender's platform names: the wheel's tag and the library's file name.
# The portable Linux builds need glibc 2.28 (manylinux_2_28), the macOS
# ones macOS 11.
PLATFORMS = {
    "linux-x64": ("manylinux_2_28_x86_64", "libsss.so"),
    "linux-arm64": ("manylinux_2_28_aarch64", "libsss.so"),
    "windows-x64": ("win_amd64", "libsss.dll"),
    "macos-arm64": ("macosx_11_0_arm64", "libsss.dylib"),
    "macos-x64": ("macosx_11_0_x86_64", "libsss.dylib"),
}


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


def wheel(library, version, tag, name, licences):
    """The wheel's file name and bytes: package libsss_native holding
    the library (name: libsss.so, .dll or .dylib), with the metadata a
    wheel needs (PEP 427)."""
    info = f"{WHEEL_PACKAGE}-{version}.dist-info"
    files = [
        (f"{WHEEL_PACKAGE}/__init__.py", (
            '"""libsss, the screen-space SSS library, for the Separable SSS'
            '\nadd-on: LIBRARY is its path."""\nimport os\n\nLIBRARY = '
            'os.path.join(os.path.dirname(os.path.abspath(__file__)),\n'
            f'                       "{name}")\n').encode()),
        (f"{WHEEL_PACKAGE}/{name}", open(library, "rb").read()),
        (f"{info}/METADATA", (
            f"Metadata-Version: 2.1\nName: {WHEEL_PACKAGE}\nVersion: "
            f"{version}\nSummary: libsss for the Separable SSS add-on\n"
            "License: GPL-3.0-or-later\n").encode()),
        (f"{info}/WHEEL", (
            "Wheel-Version: 1.0\nGenerator: build_addon.py\n"
            f"Root-Is-Purelib: false\nTag: py3-none-{tag}\n").encode()),
    ] + ([(f"{info}/THIRD_PARTY_LICENSES.txt", licences)] if licences
         else [])
    record = "\n".join([record_line(n, d) for n, d in files] +
                       [f"{info}/RECORD,,", ""])
    files.append((f"{info}/RECORD", record.encode()))
    return f"{WHEEL_PACKAGE}-{version}-py3-none-{tag}.whl", files


def main():
    p = argparse.ArgumentParser(prog="build_addon.py")
    p.add_argument("--library", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--platform", choices=sorted(PLATFORMS),
                   help="the Blender platform of --library (default: this "
                   "machine's)")
    p.add_argument("--command", help="the sss command built for it: also "
                   "write sss-VERSION-PLATFORM.zip")
    p.add_argument("--licences", help="notices of the libraries linked in")
    args = p.parse_args()
    if not os.path.isfile(args.library):
        sys.exit(f"build_addon: {args.library}: no such library (run make)")
    blender_platform = args.platform or MACHINES.get(platform.machine())
    if not blender_platform:
        sys.exit(f"build_addon: no Blender platform for {platform.machine()}"
                 " (give --platform)")
    tag, lib_name = PLATFORMS[blender_platform]
    if not args.platform and os.path.basename(args.library) == "libsss.so":
        # The Debian-linked library: Debian's glibc, a plain Linux tag.
        tag = "linux_" + platform.machine()
    licences = open(args.licences, "rb").read() if args.licences else None
    for path in (args.command, args.licences):
        if path and not os.path.isfile(path):
            sys.exit(f"build_addon: {path}: no such file")
    manifest = open(os.path.join(ADDON, "blender_manifest.toml")).read()
    version = manifest_version(manifest)
    if version != bl_info_version():
        sys.exit(f"build_addon: blender_manifest.toml says {version}, "
                 f"bl_info says {bl_info_version()}: make them agree")
    sources = [(rel, open(path, "rb").read()) for path, rel in addon_files()]
    library = open(args.library, "rb").read()
    os.makedirs(args.out, exist_ok=True)

    notices = [("THIRD_PARTY_LICENSES.txt", licences)] if licences else []
    legacy = None
    if blender_platform.startswith("linux"):
        legacy = os.path.join(args.out, "separable_sss.zip")
        write_zip(legacy, [("separable_sss/" + rel, data)
                           for rel, data in sources] +
                  [("separable_sss/" + lib_name, library)] +
                  [("separable_sss/" + n, d) for n, d in notices])

    wheel_name, wheel_files = wheel(args.library, version, tag, lib_name,
                                    licences)
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
              [("wheels/" + wheel_name, open(wheel_path, "rb").read())] +
              notices)
    os.remove(wheel_path)
    if legacy:
        print(f"add-on: {legacy} (Blender 3.4)")
    print(f"add-on: {extension} (extension, Blender 4.2 and later)")
    if args.command:
        farm = os.path.join(args.out, f"sss-{version}-{blender_platform}.zip")
        top = f"sss-{version}-{blender_platform}/"
        name = os.path.basename(args.command)
        info = zipfile.ZipInfo(top + name)
        info.external_attr = 0o100755 << 16  # executable when unpacked
        tmp = farm + ".tmp"
        with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr(info, open(args.command, "rb").read(),
                       zipfile.ZIP_DEFLATED)
            for n, d in notices:
                z.writestr(top + n, d)
        os.replace(tmp, farm)
        print(f"command: {farm} (sss for {blender_platform})")


if __name__ == "__main__":
    main()
