"""The self-contained builds (make portable, build/portable/PLATFORM): what
each needs from the system, as the platform's own format says, and the sss
command of the Linux and Windows builds (the latter under Wine) against
the Debian build, bit for bit, on a real Blender render."""
import os
import re
import shutil
import struct
import subprocess

import pytest

from exr import read_raw

BUILD = os.environ.get("SSS_BUILD", os.path.join(
    os.path.dirname(__file__), "..", "..", "build"))
PORTABLE = os.path.join(BUILD, "portable")
DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data")
WINE = os.environ.get("SSS_WINE") or shutil.which("wine64") or (
    "/usr/lib/wine/wine64" if os.path.exists("/usr/lib/wine/wine64") else "")
METHODS = ["separable", "separable-exact", "disk", "reference", "auto"]


def built(platform, name):
    path = os.path.join(PORTABLE, platform, name)
    if not os.path.exists(path):
        pytest.skip(f"{path} is not built (make portable)")
    return path


def run(args):
    r = subprocess.run(args, capture_output=True, text=True)
    assert r.returncode == 0, f"{args}: {r.stderr}"
    return r.stdout


@pytest.mark.parametrize("name", ["libsss.so", "sss"])
def test_linux_needs_only_libc_libm_libpthread_glibc_2_28(name):
    path = built("linux-x64", name)
    needed = re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]",
                        run(["readelf", "-d", path]))
    assert needed and set(needed) <= {"libc.so.6", "libm.so.6",
                                      "libpthread.so.0"}, needed
    versions = {tuple(int(x) for x in v.split("."))
                for v in re.findall(r"GLIBC_([0-9.]+)",
                                    run(["objdump", "-T", path]))}
    assert versions and max(versions) <= (2, 28), sorted(versions)


def test_linux_library_exports_only_sss_symbols():
    path = built("linux-x64", "libsss.so")
    names = [line.split()[-1] for line in
             run(["nm", "-D", "--defined-only", path]).splitlines()]
    assert names and all(n.startswith("sss_") for n in names), names


@pytest.mark.parametrize("name", ["libsss.dll", "sss.exe"])
def test_windows_needs_only_system_dlls(name):
    path = built("windows-x64", name)
    text = run(["objdump", "-p", path])
    assert "pei-x86-64" in text
    dlls = [d.lower() for d in re.findall(r"DLL Name: (\S+)", text)]
    assert "kernel32.dll" in dlls
    assert all(d == "kernel32.dll" or d.startswith("api-ms-win-crt-")
               for d in dlls), dlls
    if name == "libsss.dll":
        table = text.split("[Ordinal/Name Pointer] Table", 1)[1]
        exports = re.findall(r"^\s*\[\s*\d+\] (\S+)$", table, re.M)
        assert "sss_process_exr" in exports, exports
        assert all(e.startswith("sss_") for e in exports), exports


def macho(path):
    """(cpu type, file type, dylibs) from a 64-bit Mach-O's load
    commands."""
    data = open(path, "rb").read()
    magic, cpu, _, filetype, ncmds = struct.unpack_from("<5I", data)
    assert magic == 0xfeedfacf, f"{path}: not a 64-bit Mach-O file"
    off, dylibs = 32, []
    for _ in range(ncmds):
        cmd, size = struct.unpack_from("<2I", data, off)
        if cmd in (0xc, 0x80000018, 0x8000001f, 0x80000023, 0x20):
            name_off = struct.unpack_from("<I", data, off + 8)[0]
            dylibs.append(data[off + name_off:off + size].split(b"\0")[0]
                          .decode())
        off += size
    return cpu, filetype, dylibs


@pytest.mark.parametrize("platform,cpu", [("macos-arm64", 0x0100000c),
                                          ("macos-x64", 0x01000007)])
@pytest.mark.parametrize("name,filetype", [("libsss.dylib", 6), ("sss", 2)])
def test_macos_is_the_right_architecture_and_needs_only_libsystem(
        platform, cpu, name, filetype):
    got_cpu, got_type, dylibs = macho(built(platform, name))
    assert (got_cpu, got_type) == (cpu, filetype)
    assert dylibs == ["/usr/lib/libSystem.B.dylib"], dylibs


@pytest.fixture(scope="module")
def debian_outputs(tmp_path_factory):
    sss = os.path.join(BUILD, "sss")
    if not os.path.exists(sss):
        pytest.skip(f"{sss} is not built (make)")
    out = tmp_path_factory.mktemp("debian")
    for m in METHODS:
        run([sss, os.path.join(DATA, "blender_8x8.exr"), "-o",
             str(out / f"{m}.exr"), "--scene",
             os.path.join(DATA, "blender_8x8.json"), "-m", m, "-q"])
    return out


@pytest.mark.parametrize("platform", ["linux-x64", "windows-x64"])
@pytest.mark.parametrize("method", METHODS)
def test_sss_gives_the_debian_builds_bits(platform, method, debian_outputs,
                                          tmp_path):
    if platform == "windows-x64":
        command = [WINE, built(platform, "sss.exe")]
        if not WINE:
            pytest.skip("wine64 is not installed")
    else:
        command = [built(platform, "sss")]
    out = tmp_path / "out.exr"
    env = dict(os.environ, WINEDEBUG="-all",
               WINEPREFIX=os.path.join(os.path.abspath(BUILD), "wine"))
    r = subprocess.run(command + [os.path.join(DATA, "blender_8x8.exr"),
                                  "-o", str(out), "--scene",
                                  os.path.join(DATA, "blender_8x8.json"),
                                  "-m", method, "-q"],
                       capture_output=True, text=True, env=env)
    assert r.returncode == 0, r.stderr
    want = read_raw(debian_outputs / f"{method}.exr")
    got = read_raw(out)
    assert sorted(got) == sorted(want)
    differ = [n for n in want if got[n].tobytes() != want[n].tobytes()]
    assert not differ, f"{platform} {method}: channels differ: {differ}"
    assert not [p for p in os.listdir(tmp_path) if ".tmp-" in p]


def wine_env():
    return dict(os.environ, WINEDEBUG="-all",
                WINEPREFIX=os.path.join(os.path.abspath(BUILD), "wine"))


def test_windows_sss_writes_non_ascii_paths_beside_its_input(tmp_path):
    """UTF-8 paths through Windows' wide API, the temporary renamed over
    a file that exists, nothing left behind."""
    if not WINE:
        pytest.skip("wine64 is not installed")
    sss = built("windows-x64", "sss.exe")
    folder = tmp_path / "Render \u00dcbung"
    folder.mkdir()
    src = folder / "frame.exr"
    shutil.copy(os.path.join(DATA, "blender_8x8.exr"), src)
    out = folder / "r\u00e9sultat.exr"
    for _ in range(2):  # the second run replaces the first's output
        r = subprocess.run([WINE, sss, str(src), "-o", str(out), "--scene",
                            os.path.join(DATA, "blender_8x8.json"), "-q"],
                           capture_output=True, text=True, env=wine_env())
        assert r.returncode == 0, r.stderr
        assert out.exists()
    assert sorted(os.listdir(folder)) == ["frame.exr", "r\u00e9sultat.exr"]
    assert "SSS.Combined.R" in read_raw(out)


def test_windows_sss_refuses_to_overwrite_its_input(tmp_path):
    """The same file under another spelling (backslashes, a drive letter)
    is still the input: refused, the input untouched."""
    if not WINE:
        pytest.skip("wine64 is not installed")
    sss = built("windows-x64", "sss.exe")
    src = tmp_path / "frame.exr"
    shutil.copy(os.path.join(DATA, "blender_8x8.exr"), src)
    before = src.read_bytes()
    other = "Z:" + str(src).replace("/", "\\")
    r = subprocess.run([WINE, sss, str(src), "-o", other, "--scene",
                        os.path.join(DATA, "blender_8x8.json"), "-q"],
                       capture_output=True, text=True, env=wine_env())
    assert r.returncode != 0
    assert "refusing to overwrite" in r.stderr, r.stderr
    assert src.read_bytes() == before
    assert os.listdir(tmp_path) == ["frame.exr"]


def test_linux_sss_runs_in_a_root_with_nothing_but_glibc(tmp_path,
                                                         debian_outputs):
    """The linux-x64 command in a chroot holding only glibc's libc, libm,
    libpthread and loader: no OpenEXR, libdeflate or cJSON anywhere."""
    if os.geteuid() != 0 or not hasattr(os, "chroot"):
        pytest.skip("a chroot needs root")
    sss = built("linux-x64", "sss")
    loader = "/lib64/ld-linux-x86-64.so.2"
    libdir = os.path.dirname(os.path.realpath("/lib/x86_64-linux-gnu/libc.so.6"))
    if not os.path.exists(loader) or not os.path.isdir(libdir):
        pytest.skip("not an x86-64 glibc system")
    root = tmp_path / "root"
    for d in ("lib64", "lib/x86_64-linux-gnu", "work"):
        (root / d).mkdir(parents=True)
    shutil.copy(os.path.realpath(loader), root / "lib64" /
                "ld-linux-x86-64.so.2")
    for lib in ("libc.so.6", "libm.so.6", "libpthread.so.0"):
        shutil.copy(os.path.join(libdir, lib),
                    root / "lib" / "x86_64-linux-gnu" / lib)
    shutil.copy(sss, root / "sss")
    shutil.copy(os.path.join(DATA, "blender_8x8.exr"), root / "work" / "in.exr")
    shutil.copy(os.path.join(DATA, "blender_8x8.json"),
                root / "work" / "in.json")
    r = subprocess.run(["chroot", str(root), "/sss", "/work/in.exr", "-o",
                        "/work/out.exr", "--scene", "/work/in.json", "-m",
                        "separable", "-q"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    want = read_raw(debian_outputs / "separable.exr")
    got = read_raw(root / "work" / "out.exr")
    assert all(got[n].tobytes() == want[n].tobytes() for n in want)
