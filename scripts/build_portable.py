"""Builds libsss self-contained for every platform Blender runs on, by
cross-compiling on this Linux machine with Zig's C compiler:

    build_portable.py [--build build] [--platforms linux-x64,windows-x64,...]

- fetches, once, pinned and hash-checked: OpenEXR's sources (PyPI's
  `openexr` source distribution; only its C library OpenEXRCore is built,
  which needs nothing but libdeflate), and Debian's source packages of
  libdeflate and cJSON (`apt-get source`, Debian's patches applied), into
  BUILD/portable/src; and `ziglang` from PyPI (pinned, hashes) into the
  virtual environment BUILD/zig-VERSION;
- compiles OpenEXRCore, libdeflate, cJSON and the library's own sources
  for each platform into BUILD/portable/PLATFORM/obj (only what changed is
  compiled again), and links the library (libsss.so, libsss.dll or
  libsss.dylib) and the `sss` command with all of them inside;
- checks what each one needs from the system, with the platform's own
  format (readelf and objdump for ELF and PE, the Mach-O load commands read
  here), and fails if it needs more than the operating system: Linux libc,
  libm, libpthread and glibc symbol versions up to 2.28 (Blender's
  baseline); Windows system DLLs; macOS libSystem. What it found goes to
  BUILD/portable/PLATFORM/deps.txt.

Each output is written under a temporary name and renamed into place.
"""
import argparse
import concurrent.futures
import glob
import hashlib
import os
import re
import shutil
import struct
import subprocess
import sys
import tarfile
import tempfile
import urllib.request

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, ".."))
CSRC = os.path.join(ROOT, "csrc")

ZIG_VERSION = "0.14.1"
# ziglang's wheels for the machines that build (pip checks the hash).
ZIG_HASHES = {
    "x86_64": "6eb9d4d759b292c83810dbee2e9e8e3fbfbf01d864e6e9811bae711fd74e1c2f",
    "aarch64": "7994b27f3cbfcedea43f9b7552e38b45857bdf0e9a45065474092dd74e7048cf",
}

# OpenEXR 3.3: its C library is C only and needs libdeflate alone (3.4
# adds HTJ2K through OpenJPH, C++); the source distribution on PyPI
# carries the whole source tree.
OPENEXR = {
    "version": "3.3.6",
    "url": "https://files.pythonhosted.org/packages/fb/7c/"
           "4ad0e22fc5df76e037166115ed3aebd2500e6abb769287e6bc239549bc09/"
           "openexr-3.3.6.tar.gz",
    "sha256": "ed9bdca815bcfd5514a8ead36f0733c5fa96998914d77ac9eb58406db3ad4626",
}
# Debian 12's source packages: the versions the Debian-linked build uses.
DEBIAN_SOURCES = {
    "libdeflate": ("1.14-1", "libdeflate-1.14", {
        "libdeflate_1.14-1.dsc":
            "1f82791c5ac5623ed110e09cc991471deebfe4c419414392d1242e122c6f4c19",
        "libdeflate_1.14.orig.tar.gz":
            "89e7df898c37c3427b0f39aadcf733731321a278771d20fc553f92da8d4808ac",
        "libdeflate_1.14-1.debian.tar.xz":
            "4794c379cc4e77eaeb283620bd80a7ce57b858af508f80ba6d5efbc4bcb10434",
    }),
    "cjson": ("1.7.15-1+deb12u4", "cJSON-1.7.15", {
        "cjson_1.7.15-1+deb12u4.dsc":
            "764c2de141d680f4fb4cada30c526dacaa30ead061b9b9c34f2b81e2df0f8439",
        "cjson_1.7.15.orig.tar.gz":
            "5308fd4bd90cef7aa060558514de6a1a4a0819974a26e6ed13973c5f624c24b2",
        "cjson_1.7.15-1+deb12u4.debian.tar.xz":
            "afd19a970966cf534ff1e9ec077d710a5e7e78eb4ec9b499c8bdc32e55da12cb",
    }),
}
# Each library's licence file in its sources, shipped with every package.
LICENCES = {
    "OpenEXR (BSD-3-Clause)": ("openexr-3.3.6", "LICENSE.md"),
    "libdeflate (MIT)": ("libdeflate-1.14", "COPYING"),
    "cJSON (MIT)": ("cJSON-1.7.15", "LICENSE"),
}

# Blender's platform name: Zig's target, the library's and command's names.
PLATFORMS = {
    "linux-x64": ("x86_64-linux-gnu.2.28", "libsss.so", "sss"),
    "linux-arm64": ("aarch64-linux-gnu.2.28", "libsss.so", "sss"),
    "windows-x64": ("x86_64-windows-gnu", "libsss.dll", "sss.exe"),
    "macos-arm64": ("aarch64-macos.11.0", "libsss.dylib", "sss"),
    "macos-x64": ("x86_64-macos.11.0", "libsss.dylib", "sss"),
}
DEFAULT_PLATFORMS = "linux-x64,windows-x64,macos-arm64,macos-x64"

GLIBC_BASELINE = (2, 28)
LINUX_LIBS = {"libc.so.6", "libm.so.6", "libpthread.so.0", "libdl.so.2",
              "ld-linux-x86-64.so.2", "ld-linux-aarch64.so.1"}
# Windows' own DLLs (the Universal C Runtime through its api sets).
WINDOWS_DLLS = {"kernel32.dll", "ntdll.dll", "advapi32.dll", "bcrypt.dll",
                "ucrtbase.dll", "msvcrt.dll", "user32.dll", "shell32.dll"}
MACOS_LIBS = {"/usr/lib/libSystem.B.dylib"}

# The same language, warnings-as-they-are and floating-point rules as the
# Makefile: no contraction into FMAs (docs/library.md, Determinism).
CFLAGS = ["-O2", "-fPIC", "-fvisibility=hidden", "-ffp-contract=off"]
SSS_FLAGS = ["-std=c11", "-Wall", "-Wextra", "-Wno-missing-field-initializers",
             "-D_POSIX_C_SOURCE=200809L", "-pthread"]


def say(*a):
    print("build_portable:", *a, flush=True)


def fail(msg):
    sys.exit(f"build_portable: {msg}")


def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def checked(path, want):
    got = sha256(path)
    if got != want:
        os.remove(path)
        fail(f"{path}: sha256 {got}, expected {want}; removed it")


def download(url, path, want):
    if os.path.exists(path) and sha256(path) == want:
        return
    say(f"fetching {url}")
    tmp = path + ".tmp"
    with urllib.request.urlopen(url, timeout=300) as r, open(tmp, "wb") as f:
        shutil.copyfileobj(r, f)
    os.replace(tmp, path)
    checked(path, want)


def safe_extract(archive, dest, members=None):
    with tarfile.open(archive) as t:
        names = [m for m in t.getmembers()
                 if members is None or any(m.name == p or
                                           m.name.startswith(p + "/")
                                           for p in members)]
        for m in names:
            if m.name.startswith("/") or ".." in m.name.split("/") or \
                    not (m.isfile() or m.isdir()):
                continue
            t.extract(m, dest)


def fetch_openexr(src):
    archive = os.path.join(src, f"openexr-{OPENEXR['version']}.tar.gz")
    top = f"openexr-{OPENEXR['version']}"
    if os.path.isfile(os.path.join(src, top, ".complete")):
        return
    download(OPENEXR["url"], archive, OPENEXR["sha256"])
    shutil.rmtree(os.path.join(src, top), ignore_errors=True)
    safe_extract(archive, src, [f"{top}/src/lib/OpenEXRCore",
                                f"{top}/LICENSE.md"])
    open(os.path.join(src, top, ".complete"), "w").close()


def fetch_debian(src, package):
    version, top, files = DEBIAN_SOURCES[package]
    if os.path.isfile(os.path.join(src, top, ".complete")):
        return
    debian = os.path.join(src, "debian")
    os.makedirs(debian, exist_ok=True)
    if not all(os.path.exists(os.path.join(debian, f)) and
               sha256(os.path.join(debian, f)) == h for f, h in files.items()):
        say(f"apt-get source {package}={version}")
        r = subprocess.run(["apt-get", "source", "--download-only", "-qq",
                            f"{package}={version}"], cwd=debian,
                           capture_output=True, text=True)
        if r.returncode != 0:
            fail(f"apt-get source {package}={version} failed (Debian's "
                 "source lists: scripts/install-deps.sh enables them, as "
                 f"root): {r.stderr.strip()}")
    for f, h in files.items():
        checked(os.path.join(debian, f), h)
    orig = next(f for f in files if ".orig." in f)
    deb = next(f for f in files if ".debian." in f)
    shutil.rmtree(os.path.join(src, top), ignore_errors=True)
    safe_extract(os.path.join(debian, orig), src)
    safe_extract(os.path.join(debian, deb), os.path.join(src, top))
    # Debian's patches, in Debian's order (security fixes among them).
    series = os.path.join(src, top, "debian", "patches", "series")
    if os.path.exists(series):
        for line in open(series):
            name = line.split("#")[0].strip()
            if not name:
                continue
            patch = os.path.join(src, top, "debian", "patches", name)
            r = subprocess.run(["patch", "-p1", "-s", "-N", "-i", patch],
                               cwd=os.path.join(src, top),
                               capture_output=True, text=True)
            if r.returncode != 0:
                fail(f"{package}: Debian's patch {name} does not apply: "
                     f"{r.stdout}{r.stderr}")
    open(os.path.join(src, top, ".complete"), "w").close()


def write_if_changed(path, text):
    if os.path.exists(path) and open(path).read() == text:
        return
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def openexr_config(src):
    """The four headers OpenEXR's CMake would generate for OpenEXRCore:
    no exported symbols (it is linked in, hidden), threads on, no Imath
    (the Core has its own half conversion)."""
    d = os.path.join(src, "openexr-config")
    os.makedirs(d, exist_ok=True)
    major, minor, patch = OPENEXR["version"].split(".")
    write_if_changed(os.path.join(d, "OpenEXRConfig.h"), f"""\
/* Written by scripts/build_portable.py for OpenEXRCore linked into libsss. */
#ifndef INCLUDED_OPENEXR_CONFIG_H
#define INCLUDED_OPENEXR_CONFIG_H 1
#define OPENEXR_VERSION_MAJOR {major}
#define OPENEXR_VERSION_MINOR {minor}
#define OPENEXR_VERSION_PATCH {patch}
#define OPENEXR_VERSION_STRING "{OPENEXR['version']}"
#define OPENEXR_PACKAGE_STRING "OpenEXR {OPENEXR['version']}"
#define OPENEXR_VERSION_RELEASE_TYPE ""
#define OPENEXR_VERSION_EXTRA ""
#define OPENEXR_LIB_VERSION_STRING "{OPENEXR['version']}"
#define OPENEXR_VERSION_HEX (({major} << 24) | ({minor} << 16) | ({patch} << 8))
#define OPENEXR_EXPORT
#define OPENEXR_HIDDEN
#endif
""")
    write_if_changed(os.path.join(d, "OpenEXRConfigInternal.h"), """\
#if defined(__x86_64__)
#define OPENEXR_IMF_HAVE_GCC_INLINE_ASM_AVX 1
#endif
""")
    write_if_changed(os.path.join(d, "IlmThreadConfig.h"),
                     "#define ILMTHREAD_THREADING_ENABLED 1\n")
    write_if_changed(os.path.join(d, "ImathConfig.h"), "/* no Imath */\n")
    return d


def zig_python(build):
    venv = os.path.join(build, f"zig-{ZIG_VERSION}")
    python = os.path.join(venv, "bin", "python")
    probe = [python, "-c", "import importlib.metadata as m, sys; "
             f"sys.exit(m.version('ziglang') != '{ZIG_VERSION}')"]
    if os.path.exists(python) and \
            subprocess.run(probe, capture_output=True).returncode == 0:
        return python
    machine = os.uname().machine
    if machine not in ZIG_HASHES:
        fail(f"no pinned ziglang wheel for a {machine} build machine")
    say(f"installing ziglang {ZIG_VERSION} into {venv}")
    shutil.rmtree(venv, ignore_errors=True)
    subprocess.run([sys.executable, "-m", "venv", venv], check=True)
    with tempfile.NamedTemporaryFile("w", suffix=".txt", delete=False) as f:
        f.write(f"ziglang=={ZIG_VERSION} "
                f"--hash=sha256:{ZIG_HASHES[machine]}\n")
        req = f.name
    try:
        r = subprocess.run([python, "-m", "pip", "install", "-q",
                            "--disable-pip-version-check", "--no-deps",
                            "--only-binary", ":all:", "--require-hashes",
                            "-r", req], capture_output=True, text=True)
    finally:
        os.remove(req)
    if r.returncode != 0 or subprocess.run(probe).returncode != 0:
        fail(f"ziglang {ZIG_VERSION} did not install into {venv}: "
             f"{r.stderr.strip()}")
    return python


class Compiler:
    def __init__(self, python, build, target):
        self.cc = [python, "-m", "ziglang", "cc", "-target", target]
        cache = os.path.join(build, "zig-cache")
        self.env = dict(os.environ, ZIG_GLOBAL_CACHE_DIR=cache,
                        ZIG_LOCAL_CACHE_DIR=cache)

    def run(self, args, what):
        r = subprocess.run(self.cc + args, env=self.env,
                           capture_output=True, text=True)
        if r.returncode != 0:
            fail(f"{what}:\n{r.stdout}{r.stderr}")
        return r.stderr

    def compile(self, source, obj, flags):
        """Compiles source unless obj is newer than it and every header it
        read, built with the same command."""
        cmd = flags + ["-MMD", "-MF", obj + ".d", "-c", "-o", obj, source]
        stamp = obj + ".cmd"
        if up_to_date(obj, stamp, " ".join(cmd)):
            return None
        os.makedirs(os.path.dirname(obj), exist_ok=True)
        warnings = self.run(cmd, f"compiling {source}")
        write_if_changed(stamp, " ".join(cmd))
        return warnings


def up_to_date(obj, stamp, cmd):
    if not (os.path.exists(obj) and os.path.exists(stamp) and
            open(stamp).read() == cmd and os.path.exists(obj + ".d")):
        return False
    t = os.path.getmtime(obj)
    deps = open(obj + ".d").read().replace("\\\n", " ").split(":", 1)[-1]
    return all(os.path.exists(p) and os.path.getmtime(p) <= t
               for p in deps.split())


def units(src, platform, config):
    """(source, object name, flags) of everything in the library."""
    exr = os.path.join(src, f"openexr-{OPENEXR['version']}", "src", "lib",
                       "OpenEXRCore")
    deflate = os.path.join(src, "libdeflate-1.14")
    cjson = os.path.join(src, "cJSON-1.7.15")
    windows = platform.startswith("windows")
    port = ["-include", os.path.join(CSRC, "port", "win32_posix.h"),
            "-D_FILE_OFFSET_BITS=64"] if windows else []
    if platform.startswith("macos"):
        # flock beside POSIX; NAME_MAX is in limits.h there, which
        # glibc's dirent.h includes.
        port = ["-D_DARWIN_C_SOURCE", "-include", "limits.h"]
    # cJSON.h marks its functions dllexport on Windows unless told not to.
    inc = ["-I" + exr, "-I" + config, "-I" + deflate, "-I" + cjson,
           "-DCJSON_HIDE_SYMBOLS"]
    out = []
    for f in sorted(glob.glob(os.path.join(exr, "*.c"))):
        out.append((f, "openexr/" + os.path.basename(f),
                    CFLAGS + ["-std=gnu11", "-w", "-I" + exr, "-I" + config,
                              "-I" + deflate]))
    for f in sorted(glob.glob(os.path.join(deflate, "lib", "*.c")) +
                    glob.glob(os.path.join(deflate, "lib", "*", "*.c"))):
        rel = os.path.relpath(f, os.path.join(deflate, "lib"))
        out.append((f, "deflate/" + rel.replace("/", "_"),
                    CFLAGS + ["-std=gnu11", "-w", "-I" + deflate]))
    out.append((os.path.join(cjson, "cJSON.c"), "cjson/cJSON.c",
                CFLAGS + ["-std=c89", "-w", "-DCJSON_HIDE_SYMBOLS"]))
    lib = sorted(f for f in glob.glob(os.path.join(CSRC, "sss_*.c"))
                 if not f.endswith("sss_main.c"))
    if windows:
        lib.append(os.path.join(CSRC, "port", "win32_posix.c"))
    for f in lib:
        out.append((f, "sss/" + os.path.basename(f),
                    CFLAGS + SSS_FLAGS + port + inc))
    return out, CFLAGS + SSS_FLAGS + port + inc


def build_platform(python, build, src, config, platform, jobs):
    target, lib_name, exe_name = PLATFORMS[platform]
    out = os.path.join(build, "portable", platform)
    cc = Compiler(python, build, target)
    todo, sss_flags = units(src, platform, config)
    objs = []
    with concurrent.futures.ThreadPoolExecutor(jobs) as pool:
        futures = []
        for source, name, flags in todo:
            obj = os.path.join(out, "obj", name[:-2] + ".o")
            objs.append(obj)
            futures.append((source, pool.submit(cc.compile, source, obj,
                                                flags)))
        for source, f in futures:
            warnings = f.result()
            if warnings and source.startswith(CSRC):
                print(warnings, end="", file=sys.stderr)
    main_obj = os.path.join(out, "obj", "main", "sss_main.o")
    cc.compile(os.path.join(CSRC, "sss_main.c"), main_obj, sss_flags)

    libs = [] if platform.startswith(("windows", "macos")) else ["-lm"]
    lib = os.path.join(out, lib_name)
    exe = os.path.join(out, exe_name)
    newest = max(os.path.getmtime(o) for o in objs + [main_obj])
    shared = ["-shared", "-s"]
    if platform.startswith("linux"):
        # Only sss_ symbols leave the library: the runtime's own (the CPU
        # model AVX2 dispatch reads) bind inside it.
        exports = os.path.join(out, "exports.map")
        write_if_changed(exports, "{ global: sss_*; local: *; };\n")
        shared.append("-Wl,--version-script=" + exports)
    if not (os.path.exists(lib) and os.path.getmtime(lib) >= newest):
        link(cc, shared + objs + libs + ["-pthread"], lib)
    if not (os.path.exists(exe) and os.path.getmtime(exe) >= newest):
        link(cc, ["-s", main_obj] + objs + libs + ["-pthread"], exe)
    # The objects as an archive, for the C tests built for this platform.
    archive = os.path.join(out, "libsss.a")
    if not (os.path.exists(archive) and os.path.getmtime(archive) >= newest):
        tmp = archive + ".tmp"
        if os.path.exists(tmp):
            os.remove(tmp)
        r = subprocess.run([python, "-m", "ziglang", "ar", "rcs", tmp] + objs,
                           env=cc.env, capture_output=True, text=True)
        if r.returncode != 0:
            fail(f"archiving {archive}: {r.stderr}")
        os.replace(tmp, archive)
    return lib, exe, cc, sss_flags, archive


def build_tests(cc, flags, archive, out, platform, names):
    """tests/NAME.c for this platform, linked with the portable objects,
    into out/tests (NAME.exe on Windows)."""
    suffix = ".exe" if platform.startswith("windows") else ""
    tests = os.path.join(ROOT, "tests")
    libs = [] if platform.startswith(("windows", "macos")) else ["-lm"]
    built = []
    for name in names:
        source = os.path.join(tests, name + ".c")
        if not os.path.isfile(source):
            fail(f"--tests: no test {source}")
        exe = os.path.join(out, "tests", name + suffix)
        deps = [source, archive] + glob.glob(os.path.join(tests, "*.h"))
        extra = (["-Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc"]
                 if name == "test_oom" else [])
        if not (os.path.exists(exe) and os.path.getmtime(exe) >=
                max(os.path.getmtime(d) for d in deps)):
            os.makedirs(os.path.dirname(exe), exist_ok=True)
            link(cc, flags + ["-I" + CSRC, "-I" + tests, source, archive] +
                 libs + extra + ["-pthread"], exe)
        built.append(exe)
    return built


def link(cc, args, path):
    """Links into a temporary folder and renames the result into place
    (Zig writes import libraries and debug files beside a Windows DLL)."""
    d = tempfile.mkdtemp(dir=os.path.dirname(path))
    try:
        tmp = os.path.join(d, os.path.basename(path))
        cc.run(args + ["-o", tmp], f"linking {path}")
        os.replace(tmp, path)
    finally:
        shutil.rmtree(d)


# ------------------------------------------------------------ the checks

def tool(args):
    r = subprocess.run(args, capture_output=True, text=True)
    if r.returncode != 0:
        fail(f"{' '.join(args)}: {r.stderr.strip()}")
    return r.stdout


ELF_MACHINES = {"linux-x64": "Advanced Micro Devices X86-64",
                "linux-arm64": "AArch64"}


def check_elf(path, platform):
    machine = re.search(r"Machine:\s+(.+)", tool(["readelf", "-h", path]))
    machine = machine.group(1).strip() if machine else "?"
    needed = re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]",
                        tool(["readelf", "-d", path]))
    versions = sorted({tuple(int(x) for x in v.split("."))
                       for v in re.findall(r"GLIBC_([0-9.]+)",
                                           tool(["objdump", "-T", path]))})
    newest = ".".join(map(str, versions[-1])) if versions else "none"
    problems = [f"needs {n}, not part of the system" for n in needed
                if n not in LINUX_LIBS]
    if versions and versions[-1] > GLIBC_BASELINE:
        problems.append(f"needs glibc {newest}, newer than the baseline "
                        f"{'.'.join(map(str, GLIBC_BASELINE))}")
    if machine != ELF_MACHINES[platform]:
        problems.append(f"is for {machine}, not {ELF_MACHINES[platform]}")
    return needed, f"ELF {machine}, newest glibc symbol version {newest}", \
        problems


def check_pe(path):
    text = tool(["objdump", "-p", path])
    dlls = re.findall(r"DLL Name: (\S+)", text)
    problems = [f"needs {d}, not a Windows system DLL" for d in dlls
                if d.lower() not in WINDOWS_DLLS and
                not d.lower().startswith("api-ms-win-")]
    fmt = re.search(r"file format (\S+)", text)
    return dlls, f"format {fmt.group(1) if fmt else '?'}", problems


MACHO_CPU = {0x01000007: "x86_64", 0x0100000c: "arm64"}
LC_DYLIBS = {0xc: "LC_LOAD_DYLIB", 0x80000018: "LC_LOAD_WEAK_DYLIB",
             0x8000001f: "LC_REEXPORT_DYLIB", 0x80000023: "LC_LOAD_UPWARD_DYLIB",
             0x20: "LC_LAZY_LOAD_DYLIB"}


def macho_dylibs(path):
    """The architecture, file type and every dylib a 64-bit Mach-O file
    loads, read from its load commands."""
    data = open(path, "rb").read()
    magic, cpu, _, filetype, ncmds, _, _, _ = struct.unpack_from("<8I", data)
    if magic != 0xfeedfacf:
        fail(f"{path}: not a 64-bit little-endian Mach-O file")
    off, dylibs = 32, []
    for _ in range(ncmds):
        cmd, size = struct.unpack_from("<2I", data, off)
        if cmd in LC_DYLIBS:
            name_off = struct.unpack_from("<I", data, off + 8)[0]
            name = data[off + name_off:off + size].split(b"\0")[0].decode()
            dylibs.append(name)
        off += size
    kind = {6: "dylib", 2: "executable"}.get(filetype, f"type {filetype}")
    return MACHO_CPU.get(cpu, hex(cpu)), kind, dylibs


def check_macho(path, platform):
    arch, kind, dylibs = macho_dylibs(path)
    want = "arm64" if platform.endswith("arm64") else "x86_64"
    problems = [f"needs {d}, not libSystem" for d in dylibs
                if d not in MACOS_LIBS]
    if arch != want:
        problems.append(f"is {arch}, not {want}")
    return dylibs, f"Mach-O {arch} {kind}", problems


def check(path, platform):
    if platform.startswith("linux"):
        deps, note, problems = check_elf(path, platform)
    elif platform.startswith("windows"):
        deps, note, problems = check_pe(path)
    else:
        deps, note, problems = check_macho(path, platform)
    line = (f"{os.path.basename(path)}: {os.path.getsize(path)} bytes, "
            f"{note}, needs {', '.join(deps) or 'nothing'}")
    return line, [f"{path}: {p}" for p in problems]


def licences(src, out):
    """THIRD_PARTY_LICENSES.txt: the notices of what is linked in."""
    parts = ["libsss links these libraries in; their licences follow.\n"]
    for name, (top, rel) in LICENCES.items():
        text = open(os.path.join(src, top, rel), encoding="utf-8").read()
        parts.append(f"{'=' * 72}\n{name}: {top}\n{'=' * 72}\n{text}\n")
    write_if_changed(os.path.join(out, "THIRD_PARTY_LICENSES.txt"),
                     "\n".join(parts))


def main():
    p = argparse.ArgumentParser(prog="build_portable.py")
    p.add_argument("--build", default=os.path.join(ROOT, "build"))
    p.add_argument("--platforms", default=DEFAULT_PLATFORMS,
                   help=f"comma-separated, of {', '.join(PLATFORMS)}")
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    p.add_argument("--tests", default="",
                   help="comma-separated C tests (tests/NAME.c) to build "
                   "for each platform, into BUILD/portable/PLATFORM/tests")
    args = p.parse_args()
    platforms = [x for x in args.platforms.split(",") if x]
    for x in platforms:
        if x not in PLATFORMS:
            fail(f"--platforms: unknown platform {x!r} "
                 f"(known: {', '.join(PLATFORMS)})")
    build = os.path.abspath(args.build)
    src = os.path.join(build, "portable", "src")
    os.makedirs(src, exist_ok=True)
    fetch_openexr(src)
    for package in DEBIAN_SOURCES:
        fetch_debian(src, package)
    config = openexr_config(src)
    python = zig_python(build)
    licences(src, os.path.join(build, "portable"))
    problems = []
    for platform in platforms:
        lib, exe, cc, flags, archive = build_platform(
            python, build, src, config, platform, args.jobs)
        if args.tests:
            build_tests(cc, flags, archive, os.path.dirname(lib), platform,
                        [t for t in args.tests.split(",") if t])
        lines = []
        for path in (lib, exe):
            line, bad = check(path, platform)
            lines.append(line)
            problems += bad
        write_if_changed(os.path.join(os.path.dirname(lib), "deps.txt"),
                         "\n".join(lines) + "\n")
        for line in lines:
            say(f"{platform}: {line}")
    if problems:
        fail("not self-contained:\n  " + "\n  ".join(problems))


if __name__ == "__main__":
    main()
