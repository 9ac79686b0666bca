"""scripts/sweep_summary.py (the end of make sweep): one table and one
picture of every scene's sweep, and a verdict that a single scale worse
than no SSS turns to "no"."""
import csv
import subprocess
import sys

from conftest import ROOT

COLUMNS = ("scene", "scale", "radius_m", "kernel_px", "samples",
           "rmse_no_sss", "rmse_ours", "cut", "rmse_q_no_sss",
           "rmse_q_ours", "cut_q", "ratio_q", "ours_vs_plain",
           "rw_over_plain", "render_s", "post_s")


def write_sweep(folder, name, ratios):
    folder.mkdir(parents=True)
    with open(folder / "sweep.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(COLUMNS)
        for scale, ratio in ratios:
            w.writerow([name, scale, 0.01 * scale, 4 * scale, 64, 0.1,
                        0.1 * ratio, 100 * (1 - ratio), 0.05, 0.05 * ratio,
                        100 * (1 - ratio), ratio, 0.1, "1.0/1.0/1.0", 1, 0.1])


def run(folder, *extra):
    return subprocess.run([sys.executable, str(ROOT / "scripts" /
                                               "sweep_summary.py"),
                           str(folder), *extra], capture_output=True,
                          text=True)


def test_summary_table_picture_and_verdict(tmp_path):
    write_sweep(tmp_path / "a", "a", [(1e-6, 1.0), (1.0, 0.6), (1e3, 0.8)])
    write_sweep(tmp_path / "b", "b", [(1e-6, 1.0004), (1.0, 0.7)])
    proc = run(tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "never worse than no SSS: yes" in proc.stdout
    md = (tmp_path / "summary.md").read_text()
    assert "| a | 1.000 | 0.600 | 0.800 | yes |" in md
    assert "| b | 1.000 | 0.700 |  | yes |" in md
    assert (tmp_path / "summary.png").stat().st_size > 1000

    write_sweep(tmp_path / "c", "c", [(1e-4, 1.2), (1.0, 0.5)])
    proc = run(tmp_path, "--scenes", "a,c")
    assert proc.returncode == 0, proc.stderr
    assert "never worse than no SSS: no (largest ratio 1.200: c at x0.0001)" \
        in proc.stdout
    assert "| c |  | 1.200 | 0.500 |  | no |" in \
        (tmp_path / "summary.md").read_text()


def test_missing_scene_is_named(tmp_path):
    write_sweep(tmp_path / "a", "a", [(1.0, 0.6)])
    proc = run(tmp_path, "--scenes", "a,nowhere")
    assert proc.returncode != 0
    assert "nowhere" in proc.stderr and "sweep.csv" in proc.stderr


def test_bad_csv_is_named(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "sweep.csv").write_text("scene,scale\na,x\n")
    proc = run(tmp_path, "--scenes", "a")
    assert proc.returncode != 0
    assert "a/sweep.csv" in proc.stderr and "line 2" in proc.stderr
    assert not (tmp_path / "summary.md").exists()
