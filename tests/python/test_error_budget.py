"""The error budget's split by cause (blender_scripts/error_budget.py) on
synthetic frames whose error has one known cause."""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..",
                                "blender_scripts"))
import error_budget as eb  # noqa: E402


def frame(h=32, w=48):
    """Two materials side by side on one plane (a silhouette between
    them), no back light, flat; the reference's halves equal (no noise)."""
    rng = np.random.default_rng(1)
    ref = rng.uniform(0.2, 1.0, (h, w, 3))
    idx = np.ones((h, w))
    idx[:, w // 2:] = 2
    depth = np.full((h, w), 5.0)
    mask = np.ones((h, w), bool)
    flat = np.zeros((h, w))
    return ref, idx, depth, mask, flat


def split(ours, ref, idx, depth, mask, back=None, curv=None):
    flat = np.zeros(mask.shape)
    rows, cause, _ = eb.budget([ours], ref, (ref, ref), mask, idx, depth,
                               flat if back is None else back,
                               flat if curv is None else curv)
    return rows, cause


def test_a_gain_per_material_is_calibration():
    ref, idx, depth, mask, _ = frame()
    ours = ref.copy()
    ours[idx == 2] *= 1.2
    rows, _ = split(ours, ref, idx, depth, mask)
    assert abs(rows["calibration"]["share"] - 1.0) < 1e-9
    assert all(abs(rows[k]["share"]) < 1e-9 for k in eb.CAUSES)
    assert abs(rows["calibration"]["gains"][2][0] - 1 / 1.2) < 1e-9


def test_an_error_along_the_silhouette_is_the_silhouettes():
    ref, idx, depth, mask, _ = frame()
    ours = ref.copy()
    w = ref.shape[1]
    rng = np.random.default_rng(2)
    ours[:, w // 2 - 1:w // 2 + 1] += rng.normal(0, 0.1, (ref.shape[0], 2,
                                                          3))
    rows, cause = split(ours, ref, idx, depth, mask)
    assert rows["silhouettes"]["share"] > 0.95
    assert rows["rest"]["share"] < 0.05
    assert (cause == 0).sum() == ref.shape[0] // 4 * 2


def test_back_light_and_concave_blocks_are_told_apart():
    ref, idx, depth, mask, _ = frame()
    back = np.zeros(mask.shape)
    back[:8, :16] = 0.5           # transmission: a corner, away from edges
    curv = np.zeros(mask.shape)
    curv[24:, :16] = -1.0         # a groove at the scale of the radius
    ours = ref.copy()
    ours[:8, :16] += 0.05
    ours[24:, :16] -= 0.05
    rows, _ = split(ours, ref, idx, depth, mask, back, curv)
    assert abs(rows["transmission"]["share"] - 0.5) < 0.05
    assert abs(rows["crevices"]["share"] - 0.5) < 0.05
    assert rows["transmission"]["blocks"] == rows["crevices"]["blocks"] > 0


def test_a_sharp_convex_edge_is_an_edge_not_a_crevice():
    ref, idx, depth, mask, _ = frame()
    idx[:] = 1                    # one material: no silhouette
    curv = np.zeros(mask.shape)
    curv[:, 10:12] = 50.0         # a sharp edge across the frame
    ours = ref.copy()
    rng = np.random.default_rng(3)   # in the blocks holding it
    ours[:, 8:12] += rng.normal(0, 0.05, (ref.shape[0], 4, 3))
    rows, _ = split(ours, ref, idx, depth, mask, curv=curv)
    assert rows["edges"]["share"] > 0.95
    assert rows["crevices"]["share"] == 0.0


def test_a_pixel_over_two_faces_marks_an_edge():
    """The curvature misses the edge (flat); the averaged normal of the
    pixels on it, shorter than one, tells."""
    ref, idx, depth, mask, flat = frame()
    idx[:] = 1
    normal = np.zeros(ref.shape)
    normal[..., 2] = 1.0
    # one column half on a face turned 90 degrees: length 0.707
    normal[:, 21] = [0.5, 0.0, 0.5]
    ours = ref.copy()
    rng = np.random.default_rng(4)   # in the blocks holding it
    ours[:, 20:24] += rng.normal(0, 0.05, (ref.shape[0], 4, 3))
    faces = eb.two_faces(normal, mask)
    assert faces.sum() == ref.shape[0] and faces[:, 21].all()
    rows, cause, _ = eb.budget([ours], ref, (ref, ref), mask, idx, depth,
                               flat, flat, None, faces)
    assert rows["edges"]["share"] > 0.95
    assert (cause == eb.CAUSES.index("edges")).sum() == ref.shape[0] // 4
    rows, _, _ = eb.budget([ours], ref, (ref, ref), mask, idx, depth, flat,
                           flat)
    assert rows["rest"]["share"] > 0.95


def test_the_render_without_sss_is_measured_in_the_same_blocks():
    ref, idx, depth, mask, flat = frame()
    w = ref.shape[1]
    ours = ref.copy()
    ours[:, w // 2 - 1:w // 2 + 1] += 0.1
    plain = ours.copy()
    plain[:, :8] -= 0.2           # away from the silhouette
    rows, _, _ = eb.budget([ours], ref, (ref, ref), mask, idx, depth, flat,
                           flat, [plain])
    assert abs(rows["silhouettes"]["rmse_plain"] -
               rows["silhouettes"]["rmse"]) < 0.02
    assert rows["rest"]["rmse_plain"] > 0.05 > rows["rest"]["rmse"]


def test_seeds_pool_their_squared_errors():
    """Two seeds whose errors are +e and -e: the budget holds e^2 (not 0,
    as their mean image would), the calibration none of it (one gain
    cannot fit both), and each run's row the root of the mean square."""
    ref, idx, depth, mask, flat = frame()
    up, down = ref.copy(), ref.copy()
    up[idx == 2] += 0.1
    down[idx == 2] -= 0.1
    rows, _, _ = eb.budget([up, down], ref, (ref, ref), mask, idx, depth,
                           flat, flat)
    n = (idx == 2).sum() / idx.size
    assert abs(rows["total"]["rmse"] - 0.1 * np.sqrt(n)) < 1e-6
    assert abs(rows["calibration"]["share"]) < 0.05  # a gain under 1 helps a little
    pooled = eb.pool([dict(rmse_q_c=0.3, rmse_c=0.6, mean_ratio=1.1),
                      dict(rmse_q_c=0.4, rmse_c=0.8, mean_ratio=0.9)])
    assert abs(pooled["rmse_q_c"] - np.sqrt((0.09 + 0.16) / 2)) < 1e-12
    assert abs(pooled["rmse_c"] - np.sqrt((0.36 + 0.64) / 2)) < 1e-12
    assert abs(pooled["mean_ratio"] - 1.0) < 1e-12
    assert pooled["rmse_q_c_seeds"] == [0.3, 0.4]


def test_the_summary_says_up_to_what_time_ours_is_ahead():
    """budget.md's line on the trade at equal wall time, on made-up runs
    (compare_metrics.equal_time: the walk reaches ours' 0.05 at its 16
    spp, 8 s, after ours' 3 s)."""
    ref, idx, depth, mask, _ = frame()
    rows, _ = split(ref * 1.1, ref, idx, depth, mask)
    runs = [dict(what="ours + OIDN", samples=16, seconds=3.0,
                 rmse_q_c=0.05, mean_ratio=1.0)]
    runs += [dict(what="walk + OIDN", samples=n, seconds=0.5 * n,
                  rmse_q_c=0.2 / np.sqrt(n), mean_ratio=1.0)
             for n in (4, 8, 16, 64)]
    md = eb.markdown([dict(scene="head", runs=runs, budget=rows)])
    assert "\nhead: ours+OIDN ahead of walk+OIDN from 3.0 s up to 8.0 s " \
        "(walk needs 16 spp to match" in md


def test_the_summary_draws_each_scenes_trade(tmp_path):
    """--summary gathers every scene's budget.json into summary.md and
    draws each scene's time.png (make compare's plot) from it."""
    import json
    runs = [dict(what="ours + OIDN", samples=16, seconds=1.0,
                 rmse_q_c=0.02, rmse_c=0.03, mean_ratio=1.0),
            dict(what="walk + OIDN", samples=4, seconds=0.5,
                 rmse_q_c=0.05, rmse_c=0.06, mean_ratio=1.0),
            dict(what="walk + OIDN", samples=16, seconds=1.5,
                 rmse_q_c=0.03, rmse_c=0.04, mean_ratio=1.0),
            dict(what="walk + OIDN", samples=64, seconds=5.0,
                 rmse_q_c=0.01, rmse_c=0.02, mean_ratio=1.0)]
    budget = {k: dict(share=0.2, blocks=0.2, rmse=0.01)
              for k in eb.CAUSES + ("calibration", "total")}
    scene = tmp_path / "out_folder_named_otherwise"
    scene.mkdir()
    (scene / "budget.json").write_text(json.dumps(dict(
        scene="made", resolution=[8, 8], ref_samples=64, blender="x",
        seeds=8, runs=runs, budget=budget)))
    eb.summary(str(tmp_path))
    text = (tmp_path / "summary.md").read_text()
    assert "made: ours+OIDN ahead of walk+OIDN" in text
    png = scene / "time.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert png.stat().st_size > 5000
