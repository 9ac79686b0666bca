"""The comparison's metrics (blender_scripts/compare_metrics.py) on
synthetic images with known answers."""
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..",
                                "blender_scripts"))
import compare_metrics as cm  # noqa: E402


def images(seed=0, h=32, w=40):
    rng = np.random.default_rng(seed)
    ref = rng.uniform(0.1, 1.0, (h, w, 3)).astype(np.float32)
    mask = np.zeros((h, w), bool)
    mask[4:28, 8:36] = True
    return ref, mask


def test_identical_images_have_no_error():
    ref, mask = images()
    m = cm.all_metrics(ref, ref, mask, 1.0)
    assert m["rmse"] == m["rel_mae"] == m["max_err"] == 0
    assert m["rmse_q"] == 0
    assert m["ssim"] == pytest.approx(1.0)


def test_known_offsets():
    ref, mask = images()
    img = ref + 0.1
    assert cm.rmse(img, ref, mask) == pytest.approx(0.1, rel=1e-5)
    assert cm.max_err(img, ref, mask) == pytest.approx(0.1, rel=1e-5)
    expect = 0.1 * mask.sum() * 3 / ref[mask].sum()
    assert cm.rel_mae(img, ref, mask) == pytest.approx(expect, rel=1e-5)
    # Outside the mask nothing counts.
    img = ref.copy()
    img[~mask] += 5
    assert cm.rmse(img, ref, mask) == 0


def test_quarter_resolution_averages_noise_away_but_not_bias():
    ref, mask = images()
    ref[:] = 0.5
    rng = np.random.default_rng(1)
    noisy = ref + rng.choice([-0.1, 0.1], ref.shape).astype(np.float32)
    biased = ref + 0.1
    assert cm.rmse(noisy, ref, mask) == pytest.approx(0.1, rel=1e-4)
    qi, qr, qm = cm.quarter(noisy, ref, mask)
    assert qm.sum() == (24 // 4) * (28 // 4)
    assert cm.rmse(qi, qr, qm) < 0.05
    qi, qr, qm = cm.quarter(biased, ref, mask)
    assert cm.rmse(qi, qr, qm) == pytest.approx(0.1, rel=1e-4)


def test_noise_corrected_rmse_removes_the_reference_noise():
    """A noisy reference inflates every error by its own variance; the
    corrected RMSE recovers the error against the noise-free truth."""
    truth, mask = images(h=256, w=320)
    mask[:] = True
    rng = np.random.default_rng(2)
    half_a = truth + rng.normal(0, 0.1, truth.shape)
    half_b = truth + rng.normal(0, 0.1, truth.shape)
    ref = (half_a + half_b) / 2
    biased = truth + 0.05
    raw = cm.rmse(biased, ref, mask)
    assert raw == pytest.approx(np.hypot(0.05, 0.1 / np.sqrt(2)), rel=0.02)
    fixed = cm.noise_corrected_rmse(biased, ref, mask, half_a, half_b)
    assert fixed == pytest.approx(0.05, rel=0.05)
    # The image's own noise stays an error; only the reference's goes.
    noisy = truth + rng.normal(0, 0.08, truth.shape)
    assert cm.noise_corrected_rmse(noisy, ref, mask, half_a, half_b) == \
        pytest.approx(0.08, rel=0.05)
    # Never negative: the truth itself measures (about) zero.
    assert cm.noise_corrected_rmse(truth, ref, mask, half_a, half_b) < 0.01
    m = cm.all_metrics(biased, ref, mask, 1.0, halves=(half_a, half_b))
    assert m["rmse_c"] == pytest.approx(fixed)
    assert m["rmse_q_c"] == pytest.approx(0.05, rel=0.05)
    assert np.isnan(cm.all_metrics(biased, ref, mask, 1.0)["rmse_c"])


def test_silhouettes_and_the_error_away_from_them():
    index = np.zeros((12, 14))
    index[3:9, 4:10] = 1
    depth = np.full((12, 14), 10.0)
    depth[3:9, 4:10] = 2.0
    depth[5, 6] = 2.05  # a 2.5 % step: still the same surface
    depth[5:7, 8:10] = 3.0  # a 50 % step inside the square
    e = cm.silhouettes(index, depth)
    ring = np.zeros_like(e)
    ring[2:10, 3:11] = True
    ring[4:8, 5:9] = False  # one pixel either side of the square's border
    ring[2, 3] = ring[2, 10] = ring[9, 3] = ring[9, 10] = False  # corners
    step = np.zeros_like(e)
    step[4:8, 7:11] = True  # around the deeper 2x2 block
    step[4, 7] = step[4, 10] = step[7, 7] = step[7, 10] = False
    step[5:7, 8:10] = True
    assert np.array_equal(e, ring | step)
    assert not e[5, 6] and not e[0, 0]

    truth = np.full((12, 14, 3), 0.5)
    mask = index > 0
    img = truth + 0.3 * e[..., None]  # wrong only on silhouettes
    m = cm.all_metrics(img, truth, mask, 1.0, halves=(truth, truth),
                       edges=e)
    assert m["rmse_in_c"] == pytest.approx(0.0, abs=1e-12)
    assert m["rmse_c"] > 0.1
    assert np.isnan(cm.all_metrics(img, truth, mask, 1.0)["rmse_in_c"])


def test_render_noise_from_two_sample_counts():
    bias, sigma = 0.03, 0.4  # noise RMSE sigma / sqrt(samples)

    def error(n):
        return float(np.hypot(bias, sigma / np.sqrt(n)))
    assert cm.render_noise(error(64), 64, error(256), 256) == \
        pytest.approx(sigma / 8)
    assert cm.render_noise(error(16), 16, error(64), 64) == \
        pytest.approx(sigma / 4)
    # Errors that do not fall, or counts in the wrong order: unknown.
    assert np.isnan(cm.render_noise(0.05, 16, 0.05, 64))
    assert np.isnan(cm.render_noise(error(64), 64, error(16), 16))


def test_ssim_properties():
    ref, mask = images()
    x = cm.display_luma(ref, 1.0)
    # A constant image stays constant through the renormalised window.
    blurred = cm.gaussian_blur(np.full((9, 7), 0.3))
    assert np.allclose(blurred, 0.3)
    assert cm.gaussian_kernel().sum() == pytest.approx(1.0)
    noisy = ref + np.random.default_rng(2).normal(0, 0.05, ref.shape)
    worse = ref + np.random.default_rng(2).normal(0, 0.2, ref.shape)
    s1 = cm.ssim(noisy.astype(np.float32), ref, mask, 1.0)
    s2 = cm.ssim(worse.astype(np.float32), ref, mask, 1.0)
    assert 1 > s1 > s2 > 0
    assert np.all(cm.ssim_map(x, x) == pytest.approx(1.0))


def test_interp_samples():
    s = [16, 64, 256]
    e = [0.4, 0.2, 0.1]  # 1/sqrt(n)
    assert cm.interp_samples(s, e, 0.2) == (pytest.approx(64), "interpolated")
    assert cm.interp_samples(s, e, 0.2828)[0] == pytest.approx(32, rel=1e-3)
    assert cm.interp_samples(s, e, 0.5) == (16, "below")
    n, how = cm.interp_samples(s, e, 0.05)
    assert how == "extrapolated" and n == pytest.approx(1024, rel=1e-6)
    assert cm.time_at([16, 64], [1.0, 4.0], 32) == pytest.approx(2.0)


def walk_curve(counts=(1, 2, 4, 8, 16, 32, 64, 128, 256)):
    """A made-up denoised walk: error 0.4 / sqrt(n) in 0.5 n seconds, a
    power law, so the curve in log time is exact between its points."""
    return [(0.5 * n, 0.4 / np.sqrt(n), n) for n in counts]


def test_equal_time_ahead_up_to_where_the_walk_catches_up():
    walk = walk_curve()
    ours = [(2.0, 0.1, 16), (5.0, 0.08, 64), (20.0, 0.075, 256)]
    r = cm.equal_time(ours, walk)
    # The walk reaches 0.1 at 16 spp (8 s), 0.08 at 25 spp (12.5 s) and
    # 0.075 at 28.4 spp (14.2 s), before ours' 20 s.
    assert [p["ahead"] for p in r["points"]] == [True, True, False]
    assert r["points"][0]["reach"] == pytest.approx(8.0)
    assert r["points"][1]["reach"] == pytest.approx(12.5)
    assert r["points"][1]["reach_samples"] == pytest.approx(25.0)
    assert r["points"][2]["reach"] == pytest.approx(0.5 * (0.4 / 0.075) ** 2)
    assert r["intervals"] == [(2.0, pytest.approx(12.5))]
    line = cm.equal_time_line("head", r, walk)
    assert line.startswith("head: ours+OIDN ahead of walk+OIDN from 2.0 s "
                           "up to 12.5 s (walk needs 25 spp to match")
    assert "0.0800 at 64 spp, 5.0 s" in line


def test_equal_time_never_ahead():
    walk = walk_curve()
    # The walk's fewest samples are already closer than anything of ours.
    r = cm.equal_time([(3.0, 0.5, 16), (9.0, 0.45, 64)], walk)
    assert r["intervals"] == [] and not any(p["ahead"] for p in r["points"])
    line = cm.equal_time_line("marble", r, walk)
    assert line.startswith("marble: never ahead: walk+OIDN at 1 spp (0.5 s) "
                           "is already closer (0.4000 against")
    assert "best 0.4500 at 64 spp, 9.0 s" in line
    # The walk catches ours' error (0.1, its 16 spp) at 8 s, before ours'
    # 10 s.
    r = cm.equal_time([(10.0, 0.1, 16)], walk)
    assert r["intervals"] == []
    assert r["points"][0]["reach"] == pytest.approx(8.0)
    assert cm.equal_time_line("x", r, walk) == (
        "x: never ahead: walk+OIDN reaches ours+OIDN's best (0.1000 at 16 "
        "spp, 10.0 s) in 8.0 s (about 16 spp)")


def test_equal_time_always_ahead():
    walk = walk_curve()
    # 0.01 is below the walk's 256 spp (0.025): no measured count reaches
    # it, and the extrapolation is not trusted.
    r = cm.equal_time([(1.0, 0.03, 16), (4.0, 0.01, 64)], walk)
    assert r["intervals"] == [(1.0, float("inf"))]
    line = cm.equal_time_line("mixed", r, walk)
    assert line.startswith("mixed: ours+OIDN ahead of walk+OIDN from 1.0 s "
                           "on, past the walk's largest count: at 256 spp "
                           "(128.0 s) it has 0.0250, ours+OIDN 0.0100")


def test_equal_time_gaps_dominated_points_and_the_fewest_walk():
    walk = walk_curve()
    # Ahead from 1 to 2 s (the walk reaches 0.2 at 4 spp), behind until
    # ours' 256 spp at 20 s, ahead again until the walk's 64 spp (32 s);
    # the 64-spp point is no better than the 16-spp one: not counted.
    ours = [(1.0, 0.2, 16), (4.0, 0.2, 64), (20.0, 0.05, 256)]
    r = cm.equal_time(ours, walk)
    assert [p["samples"] for p in r["points"]] == [16, 256]
    assert r["intervals"] == [(1.0, pytest.approx(2.0)),
                              (20.0, pytest.approx(32.0))]
    line = cm.equal_time_line("s", r, walk)
    assert "up to 32.0 s (walk needs 64 spp to match" in line
    assert line.endswith("; not from 2.0 to 20.0 s")
    # Faster than the walk's fewest samples, which are already closer:
    # ahead only until that render is done.
    r = cm.equal_time([(0.3, 0.45, 16)], walk)
    assert r["intervals"] == [(0.3, 0.5)]
    assert "up to 0.5 s (walk needs 1 spp (its fewest) to match" in \
        cm.equal_time_line("s", r, walk)
    # Too little to compare.
    assert "no equal-time comparison" in cm.equal_time_line(
        "s", cm.equal_time([], walk), walk)
