"""The `sss` command on real Blender renders and on bad input."""
import json
import os
import re
import shutil

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


def option_rows():
    """{key: (lo, hi, default, help)} of the bounded integer rows of the
    library's options schema, read from its table
    (csrc/sss_option_fields.h; the library itself is not loaded here, as
    under make check it is built with the sanitizers)."""
    text = open(os.path.join(os.path.dirname(__file__), "..", "..", "csrc",
                             "sss_option_fields.h")).read()
    text = re.sub(r"\s*\\\n\s*", " ", text)
    rows = {}
    for key, kind, default, lo, hi, help_text in re.findall(
            r'X\("(\w+)", \w+, (\w+), (\w+), (\w+), (\w+), \d,\s*"([^"]*)"\)',
            text):
        if kind == "INT" and (lo + hi + default).isdigit():
            rows[key] = (int(lo), int(hi), int(default), help_text)
    return rows


@pytest.mark.parametrize("option,key", [("--threads", "threads"),
                                        ("--samples", "samples")])
def test_option_ranges_are_the_librarys(sss_cmd, tmp_path, option, key):
    """The command's --threads and --samples take the library's option's
    range (sss_option_field): its help and its messages say it, its
    bounds are accepted and one past them refused."""
    lo, hi, default, help_line = option_rows()[key]
    span = f"{lo}..{hi}"
    help_text = run(sss_cmd, "--help", check=0).stdout
    assert f"{help_line}, {span}" in help_text
    assert f"else {default})" in help_text
    base = ("missing.exr", "-o", tmp_path / "o.exr", "--scene",
            tmp_path / "missing.json")
    for bad in (lo - 1, hi + 1):
        proc = run(sss_cmd, *base, option, bad, check=2)
        assert f"{option} '{bad}' must be {span}" in proc.stderr
    for good in (lo, hi):
        proc = run(sss_cmd, *base, option, good)
        assert option not in proc.stderr and "missing.json" in proc.stderr


def test_radius_scale_range_is_the_librarys(sss_cmd, tmp_path):
    assert 'X("radius_scale", radius_scale, F32, 1.0, 0, SSS__BIG, 0,' in \
        re.sub(r"\s*\\\n\s*", " ", open(os.path.join(
            os.path.dirname(__file__), "..", "..", "csrc",
            "sss_option_fields.h")).read())
    assert "by F >= 0 " in run(sss_cmd, "--help", check=0).stdout
    proc = run(sss_cmd, "missing.exr", "-o", tmp_path / "o.exr", "--scene",
               tmp_path / "s.json", "--radius-scale", "-0.5", check=2)
    assert "--radius-scale '-0.5' must be a number >= 0" in proc.stderr
