"""The `sss` command on real Blender renders and on bad input."""
import json
import os
import re
import shutil
import subprocess

import numpy as np
import pytest

from conftest import run
from exr import pass_rgb, read_channels, read_raw, write_channels


def relative_error(got, want):
    """Per-value |got - want| / max(|want|, 1e-2): relative where it
    matters, absolute on near-black values."""
    return np.abs(got - want) / np.maximum(np.abs(want), 1e-2)


@pytest.mark.parametrize("name,prefix", [("render.exr", "ViewLayer."),
                                         ("fileout.exr", "")])
def test_radius_zero_equals_blender_combined(sss_cmd, blender_render,
                                             tmp_path, name, prefix):
    """With scattering off, SSS.Combined is Blender's own Combined: the
    recombination of the passes is exactly Blender's (both naming styles)."""
    out = tmp_path / "out.exr"
    run(sss_cmd, blender_render / name, "-o", out, "--scene",
        blender_render / "scene.json", "--radius-scale", "0", check=0)
    ch, _ = read_channels(out)
    want = np.stack([ch[f"{prefix}Combined.{c}"] for c in "RGBA"], axis=-1)
    got = np.stack([ch[f"SSS.Combined.{c}"] for c in "RGBA"], axis=-1)
    err = relative_error(got, want)
    assert err.max() < 1e-4, f"max relative error {err.max():.2e}"
    # Without scattering the light is DiffDir + DiffInd.
    light = pass_rgb(ch, "SSS.DiffLight")
    diffuse = pass_rgb(ch, f"{prefix}DiffDir") + pass_rgb(ch, f"{prefix}DiffInd")
    assert np.array_equal(light, diffuse)


def test_every_input_channel_kept(sss_cmd, blender_render, tmp_path):
    for name in ("render.exr", "render_half.exr"):
        src = blender_render / name
        out = tmp_path / ("out_" + name)
        run(sss_cmd, src, "-o", out, "--scene", blender_render / "scene.json",
            check=0)
        before, after = read_raw(src), read_raw(out)
        assert set(before) <= set(after)
        for ch, data in before.items():
            assert after[ch].dtype == data.dtype, ch
            assert np.array_equal(after[ch], data, equal_nan=True), ch
        added = sorted(set(after) - set(before))
        assert added == sorted(
            [f"SSS.Combined.{c}" for c in "RGBA"] +
            [f"SSS.DiffLight.{c}" for c in "RGB"])


def test_scattering_stays_on_its_material(sss_cmd, blender_render, tmp_path):
    """Only the subsurface material's pixels change, and its energy is kept
    (the blur conserves light; only the colour of edges moves)."""
    out = tmp_path / "out.exr"
    run(sss_cmd, blender_render / "render.exr", "-o", out, "--scene",
        blender_render / "scene.json", check=0)
    ch, _ = read_channels(out)
    index = ch["ViewLayer.IndexMA.X"]
    before = pass_rgb(ch, "ViewLayer.Combined")
    after = pass_rgb(ch, "SSS.Combined")
    changed = np.abs(after - before).max(axis=-1) > 1e-4
    assert changed.any(), "nothing scattered"
    assert np.all(index[changed] == 1), "pixels of other materials changed"
    light = pass_rgb(ch, "SSS.DiffLight")
    diffuse = (pass_rgb(ch, "ViewLayer.DiffDir") +
               pass_rgb(ch, "ViewLayer.DiffInd"))
    skin = index == 1
    ratio = light[skin].sum(axis=0) / diffuse[skin].sum(axis=0)
    assert np.all(np.abs(ratio - 1) < 0.05), ratio


def test_half_piz_input(sss_cmd, blender_render, tmp_path):
    out = tmp_path / "out.exr"
    run(sss_cmd, blender_render / "render_half.exr", "-o", out, "--scene",
        blender_render / "scene.json", "--radius-scale", "0", check=0)
    ch, _ = read_channels(out)
    want = pass_rgb(ch, "ViewLayer.Combined")
    got = pass_rgb(ch, "SSS.Combined")
    # Each half pass carries ~5e-4 relative rounding.
    assert relative_error(got, want).max() < 1e-2


def test_sequence_reports_bad_frame_and_continues(sss_cmd, blender_render,
                                                  tmp_path):
    src = blender_render / "render.exr"
    for f in (1, 3):
        shutil.copy(src, tmp_path / f"in_{f:04d}.exr")
    data = src.read_bytes()
    (tmp_path / "in_0002.exr").write_bytes(data[: len(data) // 3])
    proc = run(sss_cmd, tmp_path / "in_####.exr", "--frames", "1-3", "-o",
               tmp_path / "out_####.exr", "--scene",
               blender_render / "scene.json", check=1)
    assert "in_0002.exr" in proc.stderr
    assert (tmp_path / "out_0001.exr").exists()
    assert not (tmp_path / "out_0002.exr").exists()
    assert (tmp_path / "out_0003.exr").exists()
    assert "3 frames: 2 written, 0 skipped, 1 failed" in proc.stdout
    leftovers = [p for p in os.listdir(tmp_path) if "tmp" in p]
    assert leftovers == []
    # Timing per frame is reported.
    assert re.search(r"in_0001\.exr -> .*out_0001\.exr: read [0-9.]+ s, "
                     r"sss [0-9.]+ s, write [0-9.]+ s", proc.stdout)


def test_refuses_to_overwrite_input(sss_cmd, blender_render, tmp_path):
    src = tmp_path / "in.exr"
    shutil.copy(blender_render / "render.exr", src)
    before = src.read_bytes()
    proc = run(sss_cmd, src, "-o", src, "--scene",
               blender_render / "scene.json", check=1)
    assert "overwrite" in proc.stderr
    link = tmp_path / "same.exr"
    os.link(src, link)
    proc = run(sss_cmd, src, "-o", link, "--scene",
               blender_render / "scene.json", check=1)
    assert src.read_bytes() == before


@pytest.mark.parametrize("content,needle", [
    (b"", "in.exr"),
    (b"not an exr file at all, just text", "in.exr"),
])
def test_bad_files(sss_cmd, blender_render, tmp_path, content, needle):
    src = tmp_path / "in.exr"
    src.write_bytes(content)
    proc = run(sss_cmd, src, "-o", tmp_path / "out.exr", "--scene",
               blender_render / "scene.json", check=1)
    assert needle in proc.stderr
    assert not (tmp_path / "out.exr").exists()


def test_truncated_at_several_offsets(sss_cmd, blender_render, tmp_path):
    data = (blender_render / "render.exr").read_bytes()
    for cut in (4, 100, 2000, len(data) // 2, len(data) - 1):
        src = tmp_path / f"cut_{cut}.exr"
        src.write_bytes(data[:cut])
        proc = run(sss_cmd, src, "-o", tmp_path / "out.exr", "--scene",
                   blender_render / "scene.json")
        assert proc.returncode == 1, (cut, proc.stderr)
        assert f"cut_{cut}.exr" in proc.stderr
        assert "Traceback" not in proc.stderr and "Sanitizer" not in proc.stderr
        assert not (tmp_path / "out.exr").exists()


def test_missing_pass_and_nan_depth(sss_cmd, blender_render, tmp_path):
    ch, spec = read_channels(blender_render / "fileout.exr")
    without = {k: v for k, v in ch.items() if not k.startswith("DiffDir.")}
    src = tmp_path / "nodiff.exr"
    write_channels(src, without, spec.width, spec.height)
    proc = run(sss_cmd, src, "-o", tmp_path / "out.exr", "--scene",
               blender_render / "scene.json", check=1)
    assert "DiffDir" in proc.stderr

    nan_depth = dict(ch)
    nan_depth["Depth.V"] = np.full_like(ch["Depth.V"], np.nan)
    src = tmp_path / "nandepth.exr"
    write_channels(src, nan_depth, spec.width, spec.height)
    proc = run(sss_cmd, src, "-o", tmp_path / "out2.exr", "--scene",
               blender_render / "scene.json", check=1)
    assert "Depth" in proc.stderr and "nandepth.exr" in proc.stderr


def test_bad_scene(sss_cmd, blender_render, tmp_path):
    scene = json.loads((blender_render / "scene.json").read_text())
    scene["materials"][0]["radius"] = [1, 2]
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(scene))
    proc = run(sss_cmd, blender_render / "render.exr", "-o",
               tmp_path / "out.exr", "--scene", path, check=2)
    assert "materials[0].radius" in proc.stderr
    proc = run(sss_cmd, blender_render / "render.exr", "-o",
               tmp_path / "out.exr", "--scene", tmp_path / "missing.json",
               check=2)
    assert "missing.json" in proc.stderr


def test_usage(sss_cmd, tmp_path):
    proc = run(sss_cmd, "--help", check=0)
    source = open(os.path.join(os.path.dirname(__file__), "..", "..", "csrc",
                               "sss_main.c")).read()
    for option in set(re.findall(r'\{"([a-z-]+)", (?:required|no)_argument',
                                 source)):
        assert f"--{option}" in proc.stdout, option
    assert "example" in proc.stdout
    assert re.match(r"sss \d+\.\d+\.\d+", run(sss_cmd, "--version",
                                               check=0).stdout)
    run(sss_cmd, check=2)
    run(sss_cmd, "a.exr", "-o", "b.exr", check=2)          # no scene
    run(sss_cmd, "a_####.exr", "-o", "b.exr", "--scene", "s.json",
        "--frames", "1-3", check=2)                       # patterns differ
    run(sss_cmd, "a.exr", "-o", "b.exr", "--scene", "s.json",
        "--radius-scale", "-1", check=2)
    run(sss_cmd, "a.exr", "-o", "b.exr", "--scene", "s.json",
        "--method", "magic", check=2)


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
    (tmp_path / ".out_0040.exr.tmp-999999999-1").write_bytes(b"partial")
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
