"""scripts/method_trade.py: each method's error against the reference per
material, and its time, on a real render's passes."""
import csv
import subprocess
import sys

from conftest import ROOT, SSS


def run(*args):
    return subprocess.run([sys.executable, str(ROOT / "scripts" /
                                               "method_trade.py"), *map(
                                                   str, args)],
                          capture_output=True, text=True, timeout=600)


def test_errors_against_the_reference(sss_cmd, blender_render, tmp_path):
    out = tmp_path / "trade"
    proc = run(blender_render / "render.exr", "--scene",
               blender_render / "scene.json", "--out", out, "--variants",
               "separable,separable:taps=65,disk:samples=8", "--repeat", "1",
               "--sss", SSS)
    assert proc.returncode == 0, proc.stderr
    with open(out / "method_trade.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    variants = {r["variant"] for r in rows}
    assert variants == {"reference", "separable", "separable:taps=65",
                        "disk:samples=8"}
    for r in rows:
        err = float(r["error"])
        if r["variant"] == "reference":
            assert err == 0.0
        else:
            # Every method approximates the same scattering: close to the
            # reference, and not identical to it.
            assert 0.0 < err < 0.2, r
        assert float(r["seconds"]) > 0.0 and int(r["pixels"]) > 0
    md = (out / "method_trade.md").read_text()
    assert "| separable |" in md and "| disk:samples=8 |" in md
    assert (out / "method_trade.png").stat().st_size > 1000


def test_bad_variant_named(tmp_path, blender_render):
    proc = run(blender_render / "render.exr", "--scene",
               blender_render / "scene.json", "--out", tmp_path,
               "--variants", "separable:taps=many")
    assert proc.returncode == 2
    assert "--variants" in proc.stderr and "taps=many" in proc.stderr
    assert not (tmp_path / "method_trade.csv").exists()


def test_unknown_method_named_before_any_run(tmp_path, blender_render):
    """An unknown method is refused at once, naming the methods there
    are, not after the reference's long run."""
    proc = run(blender_render / "render.exr", "--scene",
               blender_render / "scene.json", "--out", tmp_path,
               "--variants", "separable,gaussian-blur")
    assert proc.returncode == 2
    assert "gaussian-blur" in proc.stderr and "separable-exact" in proc.stderr
    assert not (tmp_path / "method_trade.csv").exists()
