"""The benchmark's parts, on tiny sizes, so that `make bench` does not rot:
the C driver prints its CSV line for every method, dumps what the
end-to-end and Blender comparisons read, and the frame it makes from that
dump is one the `sss` command processes. No timing is asserted."""
import csv
import importlib.util
import io
import json
import subprocess

import numpy as np
import pytest

from conftest import BUILD, ROOT, run

BENCH = BUILD / "sss-bench"


def load_driver():
    spec = importlib.util.spec_from_file_location(
        "run_bench", ROOT / "bench" / "run_bench.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def bench():
    if not BENCH.exists():
        pytest.fail(f"{BENCH} is missing: run make first")
    return str(BENCH)


@pytest.mark.parametrize("method", ["separable", "separable-exact", "disk",
                                    "reference"])
def test_csv_line(bench, method):
    out = subprocess.run([bench, "--size", "40", "30", "--radius", "4",
                          "--coverage", "0.5", "--method", method,
                          "--repeat", "1", "--header"],
                         capture_output=True, text=True, check=True).stdout
    rows = list(csv.DictReader(io.StringIO(out)))
    assert len(rows) == 1
    row = rows[0]
    assert row["method"] == method
    assert (int(row["width"]), int(row["height"])) == (40, 30)
    assert 0.3 < float(row["coverage"]) < 0.7
    assert float(row["seconds"]) > 0
    assert float(row["rss_peak_mib"]) >= float(row["rss_inputs_mib"]) > 0


def test_bad_arguments(bench):
    proc = subprocess.run([bench, "--method", "nonsense"], capture_output=True,
                          text=True)
    assert proc.returncode == 2 and "nonsense" in proc.stderr
    proc = subprocess.run([bench, "--coverage", "0"], capture_output=True,
                          text=True)
    assert proc.returncode == 2 and "usage" in proc.stderr


def test_dump_makes_a_frame_sss_processes(bench, sss_cmd, tmp_path):
    w, h = 48, 32
    prefix = str(tmp_path / "f")
    subprocess.run([bench, "--size", str(w), str(h), "--radius", "6",
                    "--repeat", "1", "--dump", prefix], check=True,
                   capture_output=True)
    light = np.fromfile(prefix + "_light.f32", np.float32)
    assert light.size == 3 * w * h and np.isfinite(light).all()
    depth = np.fromfile(prefix + "_depth.f32", np.float32)
    assert depth.size == w * h and (depth > 0).all()
    driver = load_driver()
    frame = tmp_path / "frame.exr"
    channels = driver.frame_from_dump(prefix, w, h, str(frame))
    assert channels == 39
    out = tmp_path / "out.exr"
    proc = run(sss_cmd, frame, "-o", out, "--scene", prefix + "_scene.json",
               check=0)
    assert "sss" in proc.stdout and out.exists()


def test_no_scatter_is_the_frame_floor(bench):
    """--no-scatter: the material matches no pixel, so only the passes are
    read and recombined (what the bench subtracts for coverage)."""
    out = subprocess.run([bench, "--size", "40", "30", "--radius", "4",
                          "--repeat", "1", "--no-scatter", "--header"],
                         capture_output=True, text=True, check=True).stdout
    row = next(csv.DictReader(io.StringIO(out)))
    assert float(row["coverage"]) == 0.0 and float(row["seconds"]) > 0


def test_cpu_flags_named():
    flags = load_driver().cpu_flags()
    assert isinstance(flags, str) and flags


def test_calibrated_runs_and_dumps_its_scene(bench, tmp_path):
    """--calibrated: the energy matched to Random Walk (Skin), which reads
    the view and the curvature at every pixel; the dumped scene says so."""
    prefix = str(tmp_path / "f")
    out = subprocess.run([bench, "--size", "48", "32", "--radius", "6",
                          "--repeat", "1", "--calibrated", "--dump",
                          prefix], capture_output=True, text=True,
                         check=True).stdout
    assert float(out.split(",")[8]) > 0
    with open(prefix + "_scene.json") as f:
        material = json.load(f)["materials"][0]
    assert material["calibration"] == "cycles4-random-walk-skin"
    assert material["mapping"] == "cycles-random-walk"


def test_retune_driver_on_a_real_frame():
    """sss-retune: one frame read, scattered again per radius scale; the
    figures make bench reports for a live re-tune."""
    exe = BUILD / "sss-retune"
    if not exe.exists():
        pytest.fail(f"{exe} is missing: run make first")
    out = subprocess.run([str(exe), str(ROOT / "tests/data/blender_8x8.exr"),
                          str(ROOT / "tests/data/blender_8x8.json"),
                          "--threads", "1", "--repeat", "2",
                          "--radius-scale", "1", "--radius-scale", "100"],
                         capture_output=True, text=True, check=True).stdout
    rows = [line.split(",") for line in out.splitlines()]
    assert [r[0] for r in rows] == ["1", "100"]
    for r in rows:
        assert r[1:4] == ["8", "8", "1"] and float(r[4]) >= 0.0
        assert float(r[5]) >= float(r[4])
    bad = subprocess.run([str(exe), str(ROOT / "tests/data/missing.exr"),
                          str(ROOT / "tests/data/blender_8x8.json")],
                         capture_output=True, text=True)
    assert bad.returncode == 1 and "missing.exr" in bad.stderr
