"""The `sss` command against hostile input: the file system's odd corners
(devices, FIFOs, sockets, links, read-only and missing folders), numbers
at and past their limits, signals and other writers mid-write, --resume
over broken outputs, silent physics and messages that must name what is
wrong. Every case: a clear message, nothing destroyed, no hang. make check
runs them again against the ASan + UBSan build."""
import fcntl
import json
import os
import shutil
import signal
import socket
import stat
import subprocess
import time

import numpy as np
import pytest

from conftest import run
from exr import pass_rgb, read_channels, write_channels

HANG = 30  # seconds: anything slower is a hang


def args_for(blender_render, src, out, *extra):
    return [src, "-o", out, "--scene", blender_render / "scene.json", *extra]


def temp_name(output_name, pid=999999999, ident=1):
    """The name a writer gives its temporary for output_name (cut to 128
    bytes): ".NAME.tmp-PID-IDENT" + FNV-1a of all before it, so that only
    a file the writer named is ever taken for a stale temporary."""
    name = "." + output_name[:128] + ".tmp-"
    head = f"{pid}-{ident:08x}"
    h = 2166136261
    for b in (name + head).encode():
        h = ((h ^ b) * 16777619) & 0xFFFFFFFF
    return f"{name}{head}{h:08x}"


def only(tmp_path, *names):
    """The folder holds exactly these names (no output, no temporary)."""
    assert sorted(os.listdir(tmp_path)) == sorted(names)


# ------------------------------------------------- files it must not write

def special_file(kind, path):
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "socket":
        sock = socket.socket(socket.AF_UNIX)
        sock.bind(str(path))
        return sock
    elif kind == "device":
        try:  # /dev/null's numbers, in our folder: never the real one
            os.mknod(path, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
        except PermissionError:
            pytest.skip("creating a device node needs root")
    elif kind == "directory":
        path.mkdir()
    return None


@pytest.mark.parametrize("kind,needle", [
    ("fifo", "is a FIFO"), ("socket", "is a socket"),
    ("device", "is a character device"), ("directory", "is a directory")])
def test_output_never_replaces_a_special_file(sss_cmd, blender_render,
                                              tmp_path, kind, needle):
    out = tmp_path / "out.exr"
    keep = special_file(kind, out)
    before = os.lstat(out)
    proc = run(sss_cmd, *args_for(blender_render, blender_render /
                                  "render.exr", out), check=1)
    assert needle in proc.stderr and "out.exr" in proc.stderr, proc.stderr
    after = os.lstat(out)
    assert stat.S_IFMT(after.st_mode) == stat.S_IFMT(before.st_mode)
    assert after.st_ino == before.st_ino
    only(tmp_path, "out.exr")
    if keep:
        keep.close()


def test_output_is_not_the_scene(sss_cmd, blender_render, tmp_path):
    scene = tmp_path / "s.json"
    shutil.copy(blender_render / "scene.json", scene)
    before = scene.read_bytes()
    proc = run(sss_cmd, blender_render / "render.exr", "-o", scene,
               "--scene", scene, check=1)
    assert "scene description" in proc.stderr and "s.json" in proc.stderr
    assert scene.read_bytes() == before
    only(tmp_path, "s.json")


def test_symbolic_link_is_refused_and_kept(sss_cmd, blender_render,
                                           tmp_path):
    """Policy: an output that is a symbolic link is refused (neither
    replaced by a file nor written through); the message says so."""
    target = tmp_path / "target.exr"
    target.write_bytes(b"someone's file")
    link = tmp_path / "out.exr"
    link.symlink_to(target)
    proc = run(sss_cmd, *args_for(blender_render, blender_render /
                                  "render.exr", link), check=1)
    assert "symbolic link" in proc.stderr and "target.exr" in proc.stderr
    assert link.is_symlink() and target.read_bytes() == b"someone's file"
    only(tmp_path, "out.exr", "target.exr")


def test_read_only_output_is_kept(sss_cmd, blender_render, tmp_path):
    out = tmp_path / "out.exr"
    out.write_bytes(b"an earlier result")
    out.chmod(0o444)
    proc = run(sss_cmd, *args_for(blender_render, blender_render /
                                  "render.exr", out), check=1)
    assert "read-only" in proc.stderr and "0444" in proc.stderr
    assert out.read_bytes() == b"an earlier result"
    only(tmp_path, "out.exr")


def test_missing_folder_is_said_before_the_work(sss_cmd, blender_render,
                                                tmp_path):
    out = tmp_path / "no" / "such" / "out.exr"
    proc = run(sss_cmd, *args_for(blender_render, blender_render /
                                  "render.exr", out), check=1)
    assert "its folder" in proc.stderr and "no/such" in proc.stderr
    assert "->" not in proc.stdout  # no frame was processed


# --------------------------------------------------------------- no hangs

def test_fifo_input_and_scene_do_not_hang(sss_cmd, blender_render,
                                          tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    out = tmp_path / "out.exr"
    proc = subprocess.run([sss_cmd, str(fifo), "-o", str(out), "--scene",
                           str(blender_render / "scene.json")],
                          capture_output=True, text=True, timeout=HANG)
    assert proc.returncode == 1 and "is a FIFO" in proc.stderr, proc.stderr
    proc = subprocess.run([sss_cmd, str(blender_render / "render.exr"),
                           "-o", str(out), "--scene", str(fifo)],
                          capture_output=True, text=True, timeout=HANG)
    assert proc.returncode == 2 and "pipe" in proc.stderr, proc.stderr
    only(tmp_path, "pipe")


def test_scene_from_a_pipe_and_not_from_a_device(sss_cmd, blender_render,
                                                 tmp_path):
    out = tmp_path / "out.exr"
    scene = (blender_render / "scene.json").read_bytes()
    proc = subprocess.run([sss_cmd, str(blender_render / "render.exr"), "-o",
                           str(out), "--scene", "/dev/stdin"], input=scene,
                          capture_output=True, timeout=HANG)
    assert proc.returncode == 0, proc.stderr
    proc = run(sss_cmd, blender_render / "render.exr", "-o",
               tmp_path / "o2.exr", "--scene", "/dev/zero", check=2)
    assert "/dev/zero: is a character device" in proc.stderr


# ------------------------------------------------------------- numbers

# Every number is the whole argument, range checked before it is narrowed:
# no wrap-around (2^32 + 1 threads was 1), no trailing text, and --frames
# names the limit it hits (a huge step overflowed and leaked).
@pytest.mark.parametrize("option,value,needle", [
    ("--threads", "4294967297", "must be 0..256"),
    ("--threads", "4294967296", "must be 0..256"),
    ("--threads", " 4", "must be 0..256"),
    ("--threads", "4x", "must be 0..256"),
    ("--threads", "", "must be 0..256"),
    ("--samples", "4294967297", "must be 1..4096"),
    ("--samples", "0x10", "must be 1..4096"),
    ("--radius-scale", " 1", "must be a number"),
    ("--max-size", "100x100junk", "each 1..1048576"),
    ("--max-size", "100x", "each 1..1048576"),
    ("--max-size", "x100", "each 1..1048576"),
    ("--max-size", "-5x10", "each 1..1048576"),
    ("--max-size", "2000000x10", "each 1..1048576"),
    ("--max-size", "4294967297x4294967297", "each 1..1048576"),
    ("--frames", "1-10x9223372036854775807", "0..99999999"),
    ("--frames", "1-99999999999", "0..99999999"),
    ("--frames", "1-2000000", "at most 1000000 frames"),
    ("--frames", "1-600000,1-600000", "at most 1000000 frames"),
    ("--frames", "5-1", "must not run backwards"),
    ("--frames", "1-3x0", "step must be at least 1"),
    ("--frames", "1,2,", "like 1-240"),
    ("--frames", "-3", "like 1-240"),
])
def test_strict_numbers(sss_cmd, blender_render, tmp_path, option, value,
                        needle):
    scene = str(blender_render / "scene.json")
    pattern = option == "--frames"
    proc = run(sss_cmd, str(tmp_path / ("in_####.exr" if pattern else
                                        "in.exr")),
               "-o", str(tmp_path / ("out_####.exr" if pattern else
                                     "out.exr")),
               "--scene", scene, option, value, check=2)
    assert needle in proc.stderr and value in proc.stderr, proc.stderr
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("option,value", [
    ("--threads", "0"), ("--threads", "256"), ("--samples", "4096"),
    ("--max-size", "1048576x1048576"), ("--frames", "0-99999999x99999999"),
    ("--frames", "7,9,12-20x4")])
def test_numbers_at_their_limits(sss_cmd, blender_render, tmp_path, option,
                                 value):
    """Accepted: the run goes on to the (missing) input, exit status 1."""
    pattern = option == "--frames"
    proc = run(sss_cmd, str(tmp_path / ("in_####.exr" if pattern else
                                        "in.exr")),
               "-o", str(tmp_path / "out_####.exr" if pattern else
                         tmp_path / "out.exr"),
               "--scene", str(blender_render / "scene.json"), option, value,
               check=1)
    assert "cannot open" in proc.stderr, proc.stderr


def test_resume_after_a_killed_run(sss_cmd, blender_render, tmp_path):
    """Killed mid-sequence: only complete frames exist (outputs appear by
    rename), and --resume does the rest without redoing them."""
    import signal
    import time
    src = blender_render / "render.exr"
    for f in range(1, 41):
        os.symlink(src, tmp_path / f"in_{f:04d}.exr")
    args = [sss_cmd, tmp_path / "in_####.exr", "--frames", "1-40", "-o",
            tmp_path / "out_####.exr", "--scene",
            blender_render / "scene.json", "--method", "reference", "-q"]
    proc = subprocess.Popen([str(a) for a in args])
    deadline = time.monotonic() + 60
    while not (tmp_path / "out_0002.exr").exists():
        assert time.monotonic() < deadline and proc.poll() is None
        time.sleep(0.01)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    done = sorted(p.name for p in tmp_path.glob("out_*.exr"))
    assert 2 <= len(done) < 40
    for name in done:  # every output that exists is complete
        ch, _ = read_channels(tmp_path / name)
        assert "SSS.Combined.R" in ch
    stamps = {n: (tmp_path / n).stat().st_mtime_ns for n in done}
    # A temporary file of a process that is gone, as a kill can leave.
    (tmp_path / temp_name("out_0040.exr")).write_bytes(b"partial")
    proc = run(*args[:-1], "--resume", check=0)
    assert not list(tmp_path.glob(".*tmp*")), "stale temporary kept"
    assert f"{len(done)} skipped" in proc.stdout
    assert len(list(tmp_path.glob("out_*.exr"))) == 40
    for name, stamp in stamps.items():
        assert (tmp_path / name).stat().st_mtime_ns == stamp


def test_unwritable_output_and_full_disk(sss_cmd, blender_render, tmp_path):
    """Output where nothing can be written, and a disk that fills up
    mid-write (a file size limit): a clear error naming the output, no
    partial file, the input untouched."""
    import resource
    src = tmp_path / "in.exr"
    shutil.copy(blender_render / "render.exr", src)
    before = src.read_bytes()
    blocker = tmp_path / "not_a_dir"
    blocker.write_text("x")
    proc = run(sss_cmd, src, "-o", blocker / "out.exr", "--scene",
               blender_render / "scene.json", check=1)
    assert "out.exr" in proc.stderr
    limit = 20000  # bytes: the output is larger, the write fails midway

    def small_disk():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
        import signal
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)

    out = tmp_path / "out.exr"
    proc = subprocess.run([sss_cmd, str(src), "-o", str(out), "--scene",
                           str(blender_render / "scene.json")],
                          capture_output=True, text=True,
                          preexec_fn=small_disk)
    assert proc.returncode == 1, proc.stderr
    assert "out.exr" in proc.stderr
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "in.exr", "not_a_dir"]
    assert src.read_bytes() == before


# ---------------------------------------------- signals and temporaries

@pytest.fixture(scope="module")
def big_render(blender_render, tmp_path_factory):
    """The test render tiled to 512x512: a write that lasts long enough
    to be interrupted."""
    ch, spec = read_channels(blender_render / "render.exr")
    tiled = {k: np.tile(v, (8, 8)) for k, v in ch.items()}
    path = tmp_path_factory.mktemp("big") / "big.exr"
    write_channels(path, tiled, spec.width * 8, spec.height * 8,
                   attributes={"cycles.ViewLayer.samples": "4"})
    return path


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM,
                                 signal.SIGHUP])
def test_signal_mid_write_leaves_no_temporary(sss_cmd, blender_render,
                                              big_render, tmp_path, sig):
    out = tmp_path / "out.exr"
    # sss leaves a signal its parent ignores ignored (nohup's SIGHUP):
    # the command gets the default disposition, as from a terminal.
    proc = subprocess.Popen([sss_cmd, *map(str, args_for(
        blender_render, big_render, out, "--threads", "1", "-q"))],
        preexec_fn=lambda: signal.signal(sig, signal.SIG_DFL))
    deadline = time.monotonic() + HANG
    while not list(tmp_path.glob(".out.exr.tmp-*")):
        assert proc.poll() is None, "finished before its write was seen"
        assert time.monotonic() < deadline
        time.sleep(0.001)
    proc.send_signal(sig)
    assert proc.wait(timeout=HANG) == -sig
    only(tmp_path)


def test_long_output_name_cleans_its_own_stale_temporary(
        sss_cmd, blender_render, tmp_path):
    """Over 128 bytes the temporary's name is cut; the clean-up matches
    the same cut name."""
    name = "n" * 200 + ".exr"
    stale = tmp_path / temp_name(name)
    stale.write_bytes(b"partial")
    run(sss_cmd, *args_for(blender_render, blender_render / "render.exr",
                           tmp_path / name), check=0)
    only(tmp_path, name)


def test_live_writers_temporary_is_never_deleted(sss_cmd, blender_render,
                                                 tmp_path):
    """Another writer (another host or PID namespace: its PID means
    nothing here) holds the lock on its temporary; it is kept. An unlocked
    one is stale and goes."""
    live = tmp_path / temp_name("out.exr", ident=0xa1)
    stale = tmp_path / temp_name("out.exr", ident=0xb2)
    stale.write_bytes(b"left by a killed run")
    with open(live, "wb") as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        run(sss_cmd, *args_for(blender_render, blender_render / "render.exr",
                               tmp_path / "out.exr"), check=0)
        assert live.exists()
    assert not stale.exists()
    only(tmp_path, "out.exr", live.name)


def test_resume_redoes_broken_outputs(sss_cmd, blender_render, tmp_path):
    src = blender_render / "render.exr"
    for f in range(1, 5):
        os.symlink(src, tmp_path / f"in_{f:04d}.exr")
    base = [sss_cmd, tmp_path / "in_####.exr", "-o", tmp_path / "out_####.exr",
            "--scene", blender_render / "scene.json", "--frames", "1-4"]
    run(*base, check=0)
    good = (tmp_path / "out_0004.exr").read_bytes()
    stamp = (tmp_path / "out_0004.exr").stat().st_mtime_ns
    (tmp_path / "out_0001.exr").write_bytes(b"")
    (tmp_path / "out_0002.exr").write_bytes(good[:len(good) // 2])
    shutil.copy(src, tmp_path / "out_0003.exr")  # an EXR, not an output
    proc = run(*base, "--resume", check=0)
    assert "1 skipped" in proc.stdout, proc.stdout
    for f in (1, 2, 3):
        assert f"out_{f:04d}.exr: exists but is not a complete output" in \
            proc.stderr, proc.stderr
        ch, _ = read_channels(tmp_path / f"out_{f:04d}.exr")
        assert "SSS.Combined.R" in ch
    assert (tmp_path / "out_0004.exr").stat().st_mtime_ns == stamp


def test_report_to_a_full_device_fails(sss_cmd, blender_render, tmp_path):
    with open("/dev/full", "w") as full:
        proc = subprocess.run([sss_cmd, *map(str, args_for(
            blender_render, blender_render / "render.exr",
            tmp_path / "out.exr"))], stdout=full, stderr=subprocess.PIPE,
            text=True, timeout=HANG)
    assert proc.returncode == 1 and "standard output" in proc.stderr


# ------------------------------------------------------- silent physics

def test_cycles_render_without_diffind_is_refused(sss_cmd, blender_render,
                                                  tmp_path):
    """Cycles always can write DiffInd; without it the indirect diffuse
    light would vanish from the result. EEVEE has no such pass: fine."""
    ch, spec = read_channels(blender_render / "render.exr")
    without = {k: v for k, v in ch.items() if ".DiffInd." not in k}
    cycles = tmp_path / "cycles.exr"
    write_channels(cycles, without, spec.width, spec.height,
                   attributes={"cycles.ViewLayer.samples": "4"})
    proc = run(sss_cmd, *args_for(blender_render, cycles,
                                  tmp_path / "o1.exr"), check=1)
    assert "Cycles render without a DiffInd pass" in proc.stderr
    assert "cycles.exr" in proc.stderr
    eevee = tmp_path / "eevee.exr"
    write_channels(eevee, without, spec.width, spec.height)
    run(sss_cmd, *args_for(blender_render, eevee, tmp_path / "o2.exr"),
        check=0)


def scattered_change(path):
    ch, _ = read_channels(path)
    light = pass_rgb(ch, "SSS.DiffLight")
    return light, np.abs(light - pass_rgb(ch, "ViewLayer.DiffDir") -
                         pass_rgb(ch, "ViewLayer.DiffInd")).max()


@pytest.mark.parametrize("method", ["separable", "separable-exact", "disk",
                                    "reference"])
def test_absurd_radii_follow_one_rule(sss_cmd, blender_render, tmp_path,
                                      method):
    """Every method scatters at absurd radii and reaches its limit: the
    result no longer changes (some returned the input before)."""
    lights = []
    for scale in ("1e12", "1e30"):
        out = tmp_path / f"out_{scale}.exr"
        run(sss_cmd, *args_for(blender_render, blender_render / "render.exr",
                               out, "--method", method, "--radius-scale",
                               scale), check=0)
        light, change = scattered_change(out)
        assert change > 0.05, (scale, change)
        lights.append(light)
    assert np.array_equal(lights[0], lights[1])
    scene = json.loads((blender_render / "scene.json").read_text())
    scene["materials"][0]["radius"] = [1e30, 1e30, 1e30]
    (tmp_path / "huge.json").write_text(json.dumps(scene))
    out = tmp_path / "scene_huge.exr"
    run(sss_cmd, blender_render / "render.exr", "-o", out, "--scene",
        tmp_path / "huge.json", "--method", method, check=0)
    assert scattered_change(out)[1] > 0.05


# -------------------------------------------------------------- messages

def test_empty_output_is_a_usage_error(sss_cmd, blender_render, tmp_path):
    proc = run(sss_cmd, blender_render / "render.exr", "-o", "", "--scene",
               blender_render / "scene.json", check=2)
    assert "-o OUTPUT is empty" in proc.stderr


def test_too_long_path_is_named(sss_cmd, blender_render, tmp_path):
    out = str(tmp_path) + "/" + "d" * 5000 + ".exr"
    proc = run(sss_cmd, blender_render / "render.exr", "-o", out, "--scene",
               blender_render / "scene.json", check=1)
    assert "longer than 4095 bytes" in proc.stderr
    assert out[:80] in proc.stderr


def test_blender5_multi_part_render(sss_cmd, tmp_path):
    """Blender 5.0 writes a part per pass; every part is read."""
    src = os.path.join(os.path.dirname(__file__), "..", "fuzz", "corpus",
                       "exr", "blender5_render_float_zip.exr")
    scene = tmp_path / "s.json"
    scene.write_text(json.dumps({"version": 1, "materials": [
        {"pass_index": 1, "profile": "burley", "radius": [1, 0.5, 0.25]}]}))
    out = tmp_path / "out.exr"
    run(sss_cmd, src, "-o", out, "--scene", scene, check=0)
    assert "SSS.Combined.R" in read_channels(out)[0]


# ------------------------------------------- second round: names, data loss

def dotted_copy(blender_render, path):
    """The render with a second view layer as Blender names a copy,
    ViewLayer.001, whose diffuse light is half the first's."""
    ch, spec = read_channels(blender_render / "render.exr")
    both = dict(ch)
    for name, value in ch.items():
        if name.startswith("ViewLayer."):
            half = ".DiffDir." in name or ".DiffInd." in name
            both["ViewLayer.001." + name[len("ViewLayer."):]] = \
                value * 0.5 if half else value
    write_channels(path, both, spec.width, spec.height,
                   attributes={"cycles.ViewLayer.samples": "4",
                               "cycles.ViewLayer.001.samples": "4"})


def test_view_layer_named_with_a_dot(sss_cmd, blender_render, tmp_path):
    """Names split from the end, as Blender splits them: ViewLayer.001's
    passes are its own, found by name (-l) and by the first-layer rule."""
    src = tmp_path / "two.exr"
    dotted_copy(blender_render, src)
    lights = {}
    for layer in ("ViewLayer.001", "ViewLayer", None):
        out = tmp_path / f"out_{layer}.exr"
        extra = ["-l", layer] if layer else []
        run(sss_cmd, *args_for(blender_render, src, out, "--radius-scale",
                               "0", *extra), check=0)
        ch, _ = read_channels(out)
        lights[layer] = pass_rgb(ch, "SSS.DiffLight")
        assert "ViewLayer.001.DiffDir.R" in ch and "ViewLayer.DiffDir.R" in ch
    one = pass_rgb(read_channels(src)[0], "ViewLayer.001.DiffDir")
    assert np.array_equal(lights["ViewLayer.001"],
                          one + pass_rgb(read_channels(src)[0],
                                         "ViewLayer.001.DiffInd"))
    assert np.allclose(lights["ViewLayer"], 2 * lights["ViewLayer.001"])
    # the first layer with DiffDir, in file order (sorted names)
    assert np.array_equal(lights[None], lights["ViewLayer.001"])
    proc = run(sss_cmd, *args_for(blender_render, src, tmp_path / "x.exr",
                                  "-l", "ViewLayer.002"), check=1)
    assert "'ViewLayer.001' (" in proc.stderr, proc.stderr


def test_input_layer_named_sss_is_never_replaced(sss_cmd, blender_render,
                                                 tmp_path):
    """The result layer is SSS: an input layer of that name (a view layer
    called SSS, or an output given again) is refused, not replaced."""
    ch, spec = read_channels(blender_render / "render.exr")
    renamed = {("SSS." + k[len("ViewLayer."):] if k.startswith("ViewLayer.")
                else k): v for k, v in ch.items()}
    src = tmp_path / "sss_layer.exr"
    write_channels(src, renamed, spec.width, spec.height)
    out = tmp_path / "out.exr"
    proc = run(sss_cmd, *args_for(blender_render, src, out), check=1)
    assert "has a layer 'SSS'" in proc.stderr, proc.stderr
    assert "rename that view layer" in proc.stderr
    only(tmp_path, "sss_layer.exr")
    # an output given again as the input: refused the same way
    run(sss_cmd, *args_for(blender_render, blender_render / "render.exr",
                           out), check=0)
    proc = run(sss_cmd, *args_for(blender_render, out, tmp_path / "o2.exr"),
               check=1)
    assert "has a layer 'SSS'" in proc.stderr, proc.stderr


def test_clean_up_deletes_only_what_a_writer_named(sss_cmd, blender_render,
                                                   tmp_path):
    """An input and a scene whose names merely look like the output's
    temporaries are never deleted by the stale-temporary clean-up; nor is
    the input even when its name is one a writer could have made."""
    src = tmp_path / ".o.exr.tmp-1-ab"
    scene = tmp_path / ".o.exr.tmp-2-cd"
    shutil.copy(blender_render / "render.exr", src)
    shutil.copy(blender_render / "scene.json", scene)
    run(sss_cmd, src, "-o", tmp_path / "o.exr", "--scene", scene, check=0)
    only(tmp_path, src.name, scene.name, "o.exr")
    named = tmp_path / temp_name("p.exr", pid=1, ident=2)
    shutil.copy(blender_render / "render.exr", named)
    run(sss_cmd, named, "-o", tmp_path / "p.exr", "--scene", scene, check=0)
    assert named.exists()


# ------------------------------------------- second round: farms, limits

def test_file_size_limit_signal_removes_the_temporary(sss_cmd, blender_render,
                                                      tmp_path):
    """ulimit -f as a farm sets it, SIGXFSZ at its default: the command
    says so, removes its temporary and dies of the signal."""
    import resource

    def small_disk():
        resource.setrlimit(resource.RLIMIT_FSIZE, (20000, 20000))

    out = tmp_path / "out.exr"
    proc = subprocess.run([sss_cmd, *map(str, args_for(
        blender_render, blender_render / "render.exr", out))],
        capture_output=True, text=True, preexec_fn=small_disk, timeout=HANG)
    assert proc.returncode == -signal.SIGXFSZ, (proc.returncode, proc.stderr)
    assert "stopped by SIGXFSZ" in proc.stderr and "ulimit -f" in \
        proc.stderr, proc.stderr
    assert "removed the unfinished" in proc.stderr
    only(tmp_path)


def test_cpu_time_limit_signal_is_said(sss_cmd, blender_render, big_render,
                                       tmp_path):
    """ulimit -t: SIGXCPU at the soft limit is reported, nothing is left."""
    import resource

    def one_second():
        resource.setrlimit(resource.RLIMIT_CPU, (1, 60))

    proc = subprocess.run([sss_cmd, *map(str, args_for(
        blender_render, big_render, tmp_path / "out.exr", "--method",
        "reference", "--threads", "1", "--radius-scale", "30"))], capture_output=True, text=True,
        preexec_fn=one_second, timeout=120)
    assert proc.returncode == -signal.SIGXCPU, (proc.returncode, proc.stderr)
    assert "stopped by SIGXCPU" in proc.stderr and "ulimit -t" in proc.stderr
    only(tmp_path)


def test_replaced_output_keeps_its_mode(sss_cmd, blender_render, tmp_path):
    out = tmp_path / "out.exr"
    out.write_bytes(b"an earlier result")
    out.chmod(0o640)
    run(sss_cmd, *args_for(blender_render, blender_render / "render.exr",
                           out), check=0)
    assert stat.S_IMODE(out.stat().st_mode) == 0o640
    assert "SSS.Combined.R" in read_channels(out)[0]


def test_unwritable_folder_is_said_before_the_work(sss_cmd, blender_render,
                                                   tmp_path):
    """A folder that takes no new file (procfs: not even root may create
    one there; a 0555 folder for other users) is said before the frame is
    read or scattered."""
    folders = ["/proc"]
    if os.geteuid() != 0:
        locked = tmp_path / "locked"
        locked.mkdir(mode=0o555)
        folders.append(str(locked))
    for folder in folders:
        proc = run(sss_cmd, *args_for(blender_render, blender_render /
                                      "render.exr", folder + "/out.exr"),
                   check=1)
        assert f"its folder {folder} is not writable" in proc.stderr, \
            proc.stderr
        assert "->" not in proc.stdout


COUNT_THREADS = r"""
#define _GNU_SOURCE
#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
static int started;
int pthread_create(pthread_t *t, const pthread_attr_t *a,
                   void *(*fn)(void *), void *arg)
{
    int (*real)(pthread_t *, const pthread_attr_t *, void *(*)(void *),
                void *) = dlsym(RTLD_NEXT, "pthread_create");
    __atomic_add_fetch(&started, 1, __ATOMIC_SEQ_CST);
    return real(t, a, fn, arg);
}
__attribute__((destructor)) static void report(void)
{
    FILE *f = fopen(getenv("THREADS_REPORT"), "w");
    if (f) { fprintf(f, "%d\n", started); fclose(f); }
}
"""


def threads_started(sss_cmd, args, tmp_path, shim, cpus=None):
    report = tmp_path / "threads.txt"
    env = dict(os.environ, LD_PRELOAD=str(shim), THREADS_REPORT=str(report),
               ASAN_OPTIONS=os.environ.get("ASAN_OPTIONS", "") +
               ":verify_asan_link_order=0")
    proc = subprocess.run([sss_cmd, *map(str, args)], env=env,
                          capture_output=True, text=True, timeout=HANG,
                          preexec_fn=(lambda: os.sched_setaffinity(0, cpus))
                          if cpus else None)
    assert proc.returncode == 0, proc.stderr
    return int(report.read_text())


def test_threads_hold_for_the_exr_coder(sss_cmd, blender_render, big_render,
                                        tmp_path):
    """--threads 1 runs everything on one thread, the EXR decode and
    encode included; "all cores" is the CPUs of the affinity mask."""
    if not shutil.which("cc"):
        pytest.skip("no C compiler for the pthread_create counter")
    shim = tmp_path / "count.so"
    (tmp_path / "count.c").write_text(COUNT_THREADS)
    subprocess.run(["cc", "-shared", "-fPIC", "-o", str(shim),
                    str(tmp_path / "count.c"), "-ldl"], check=True)
    args = args_for(blender_render, big_render, tmp_path / "out.exr", "-q")
    assert threads_started(sss_cmd, [*args, "--threads", "1"], tmp_path,
                           shim) == 0
    assert threads_started(sss_cmd, [*args, "--threads", "2"], tmp_path,
                           shim) > 0  # the counter counts
    assert threads_started(sss_cmd, [*args, "--threads", "0"], tmp_path,
                           shim, cpus={0}) == 0


# ------------------------------------------- second round: memory bombs

def with_extra_channels(blender_render, path, extra, size=None):
    """The render (cropped to size x size around its middle) with `extra`
    more one-component passes in a layer of their own."""
    ch, spec = read_channels(blender_render / "render.exr")
    w, h = spec.width, spec.height
    if size:
        y0, x0 = (h - size) // 2, (w - size) // 2
        ch = {k: v[y0:y0 + size, x0:x0 + size] for k, v in ch.items()}
        w = h = size
    zero = np.zeros((h, w), np.float32)
    for i in range(extra):
        ch[f"Extra.P{i:05d}.V"] = zero
    write_channels(path, ch, w, h)
    return len(ch)


def test_channel_and_memory_limits_from_the_header(sss_cmd, blender_render,
                                                   tmp_path):
    src = tmp_path / "many.exr"
    total = with_extra_channels(blender_render, src, 4100, size=4)
    proc = run(sss_cmd, *args_for(blender_render, src, tmp_path / "o.exr"),
               check=1)
    assert f"{total} channels, more than the limit of 4096" in proc.stderr
    assert "--max-channels" in proc.stderr, proc.stderr
    run(sss_cmd, *args_for(blender_render, src, tmp_path / "o.exr",
                           "--max-channels", str(total)), check=0)
    # memory: the 64x64 render's channels at 4 bytes, against 64 KiB
    proc = run(sss_cmd, *args_for(blender_render, blender_render /
                                  "render.exr", tmp_path / "o2.exr",
                                  "--max-memory", "64K"), check=1)
    ch, spec = read_channels(blender_render / "render.exr")
    mib = spec.width * spec.height * len(ch) * 4 / 2 ** 20
    assert f"{mib:.2f} MiB decoded, more than the limit of 0.06 MiB" in \
        proc.stderr, proc.stderr
    assert "--max-memory" in proc.stderr, proc.stderr
    assert not (tmp_path / "o2.exr").exists()
    for bad in ("12Q", "-1G", "", "G"):
        proc = run(sss_cmd, *args_for(blender_render, src, tmp_path /
                                      "o3.exr", "--max-memory", bad), check=2)
        assert "--max-memory" in proc.stderr


def test_openexr_channel_ceiling_refused_before_work(sss_cmd, blender_render,
                                                     tmp_path):
    """OpenEXRCore 3.1 counts a part's channels in 16 bits: an output
    past 32767 channels was written empty or scrambled with exit 0."""
    src = tmp_path / "ceiling.exr"
    base = len(read_channels(blender_render / "render.exr")[0])
    total = with_extra_channels(blender_render, src, 32765 - base, size=2)
    assert total == 32765
    proc = run(sss_cmd, *args_for(blender_render, src, tmp_path / "o.exr",
                                  "--max-channels", "40000"), check=1)
    assert f"{total + 7} channels with the result's 7, more than the " \
        "32767 one file can hold" in proc.stderr, proc.stderr
    assert "->" not in proc.stdout
    only(tmp_path, "ceiling.exr")


# ------------------------------------------- second round: messages

def scene_with(blender_render, tmp_path, name, change):
    scene = json.loads((blender_render / "scene.json").read_text())
    change(scene)
    path = tmp_path / name
    path.write_text(json.dumps(scene))
    return path


def test_support_cap_past_int32_names_its_range(sss_cmd, blender_render,
                                                tmp_path):
    scene = scene_with(blender_render, tmp_path, "s.json",
                       lambda s: s.update(max_support_px=2147483648))
    proc = run(sss_cmd, blender_render / "render.exr", "-o",
               tmp_path / "o.exr", "--scene", scene, check=2)
    assert "2.14748e+09 is out of range (must be 1..2147483647)" in \
        proc.stderr, proc.stderr


def test_json_keys_match_strictly(sss_cmd, blender_render, tmp_path):
    """"unit_scale\\u0000junk" is not unit_scale (cJSON's strings end at
    the NUL): refused, with where it is."""
    text = (blender_render / "scene.json").read_text()
    scene = tmp_path / "s.json"
    scene.write_text(text.replace("{", '{"unit_scale\\u0000junk": 1000, ',
                                  1))
    proc = run(sss_cmd, blender_render / "render.exr", "-o",
               tmp_path / "o.exr", "--scene", scene, check=2)
    assert "\\u0000" in proc.stderr and "line 1" in proc.stderr, proc.stderr


def test_json_values_are_bounded(sss_cmd, blender_render, tmp_path):
    """A 6 MB array took 248 MB in the parser; refused before parsing."""
    scene = tmp_path / "s.json"
    scene.write_text('{"junk": [' + "0," * 3000000 + '0]}')
    proc = run(sss_cmd, blender_render / "render.exr", "-o",
               tmp_path / "o.exr", "--scene", scene, check=2)
    assert "more than 2097152 JSON values" in proc.stderr, proc.stderr


def test_control_characters_in_names_are_shown_escaped(sss_cmd,
                                                       blender_render,
                                                       tmp_path):
    """A material or layer name with ESC, CR or LF: printed as \\xNN, so
    no terminal escape runs and no fake line can be made."""
    evil = "Skin\x1b[31m\r\nsss: error: fake"

    def rename(s):
        s["materials"][0]["name"] = evil
    scene = scene_with(blender_render, tmp_path, "s.json", rename)
    proc = run(sss_cmd, blender_render / "render.exr", "-o",
               tmp_path / "o.exr", "--scene", scene, check=0)
    assert "Skin\\x1b[31m\\x0d\\x0asss: error: fake" in proc.stdout, \
        proc.stdout
    proc = run(sss_cmd, blender_render / "render.exr", "-o",
               tmp_path / "o2.exr", "--scene", scene, "-l", evil, check=1)
    for text in (proc.stdout, proc.stderr):
        assert "\x1b" not in text and "\r" not in text
        assert not any(line.startswith("sss: error: fake")
                       for line in text.splitlines()), text
    assert "\\x1b" in proc.stderr


# ------------------------------------------- second round: frame patterns

def test_every_run_of_hashes_and_a_literal_hash(sss_cmd, blender_render,
                                                tmp_path):
    for f in (1, 2):
        os.symlink(blender_render / "render.exr", tmp_path / f"in_{f:02d}.exr")
    run(sss_cmd, tmp_path / "in_##.exr", "--frames", "1-2", "-o",
        str(tmp_path / "o_##_###") + "\\#.exr", "--scene",
        blender_render / "scene.json", "-q", check=0)
    assert sorted(p.name for p in tmp_path.glob("o_*")) == [
        "o_01_001#.exr", "o_02_002#.exr"]


def test_output_that_is_another_frames_input_is_refused_first(
        sss_cmd, blender_render, tmp_path):
    """-o in_1###.exr --frames 1,1001: frame 1's output is frame 1001's
    input; said before any frame is written."""
    for f in (1, 1001):
        shutil.copy(blender_render / "render.exr", tmp_path / f"in_{f:04d}.exr")
    before = (tmp_path / "in_1001.exr").read_bytes()
    proc = run(sss_cmd, tmp_path / "in_####.exr", "--frames", "1,1001", "-o",
               tmp_path / "in_1###.exr", "--scene",
               blender_render / "scene.json", check=2)
    assert "frame 1's output" in proc.stderr and "frame 1001's input" in \
        proc.stderr, proc.stderr
    assert (tmp_path / "in_1001.exr").read_bytes() == before
    only(tmp_path, "in_0001.exr", "in_1001.exr")
