"""Image error metrics for compare.py, numpy only (no bpy), so that plain
pytest can check them (tests/python/test_compare_metrics.py).

All images are linear scene-referred float RGB arrays (h, w, 3) and the
error is measured against a reference image over a boolean mask (h, w) of
the scattering pixels (material index of a scattering material, not
background).

- rmse: sqrt(mean over mask pixels and RGB of (img - ref)^2).
- rel_mae: sum |img - ref| / sum |ref| over mask pixels and RGB (so 0.05
  reads "5 % of the reference's light is wrong").
- quarter resolution: both images are box-filtered over 4x4 pixel blocks
  (all pixels of the block, so the light just outside the mask is included
  as a display at that size would); a block counts when at least 75 % of
  its pixels are in the mask. This separates noise (which averages away)
  from bias (which does not).
- rmse_c, rmse_q_c: the RMSE against the noise-free image the reference
  estimates. The reference is the mean of two renders with independent
  seeds, A and B; its own noise variance per pixel and channel is
  E[(A - B)^2] / 4, and since the image's noise is independent of the
  reference's, E[MSE(img, ref)] = MSE(img, truth) + that variance. So
  rmse_c = sqrt(max(0, MSE(img, ref) - mean((A - B)^2) / 4)) (at quarter
  resolution from the downsampled halves). Without it a noisy reference
  adds the same floor to every error and shrinks every ratio of errors.
- rmse_in_c: rmse_c over the scattering pixels away from silhouettes (no
  4-neighbour with another material index or a depth more than 5 %
  nearer or farther). Silhouette pixels are few but hold the render's
  noisiest light (specular at grazing angles) and the mixed pixels of
  anti-aliased edges, which can dominate an RMSE.
- max_err: the largest per-pixel max-over-RGB |img - ref| over the mask.
- ssim: Wang et al. 2004 structural similarity with an 11x11 Gaussian
  window (sigma 1.5, truncated at 5 pixels and renormalised at the image
  border), K1 = 0.01, K2 = 0.03, on display-referred luminance: Rec.709
  luminance of the image times the shared exposure, clipped to [0, 1] and
  raised to 1/2.2, so L = 1. The SSIM map is averaged over the mask.
"""
import numpy as np

QUARTER = 4
QUARTER_COVERAGE = 0.75
LUMA = np.array([0.2126, 0.7152, 0.0722], dtype=np.float64)


def _check(img, ref, mask):
    if img.shape != ref.shape or img.shape[:2] != mask.shape:
        raise ValueError(f"shapes differ: {img.shape} {ref.shape} "
                         f"{mask.shape}")
    if not mask.any():
        raise ValueError("the mask is empty: nothing scatters on screen")


def rmse(img, ref, mask):
    _check(img, ref, mask)
    d = (img[mask] - ref[mask]).astype(np.float64)
    return float(np.sqrt(np.mean(d * d)))


def rel_mae(img, ref, mask):
    _check(img, ref, mask)
    den = float(np.sum(np.abs(ref[mask].astype(np.float64))))
    num = float(np.sum(np.abs((img[mask] - ref[mask]).astype(np.float64))))
    return num / den if den > 0 else float("inf") if num > 0 else 0.0


def max_err(img, ref, mask):
    _check(img, ref, mask)
    return float(np.max(np.abs(img[mask] - ref[mask])))


def downsample(img, f=QUARTER):
    """Box filter over f x f blocks (the image is cut to a multiple of f)."""
    h, w = img.shape[0] // f * f, img.shape[1] // f * f
    a = img[:h, :w].astype(np.float64)
    shape = (h // f, f, w // f, f) + a.shape[2:]
    return a.reshape(shape).mean(axis=(1, 3))


def quarter(img, ref, mask):
    """(img, ref, mask) at quarter resolution (see the module doc)."""
    m = downsample(mask.astype(np.float64)) >= QUARTER_COVERAGE
    return downsample(img), downsample(ref), m


def display_luma(img, exposure):
    y = np.tensordot(img.astype(np.float64), LUMA, axes=([2], [0]))
    return np.clip(y * exposure, 0.0, 1.0) ** (1 / 2.2)


def gaussian_kernel(sigma=1.5, radius=5):
    x = np.arange(-radius, radius + 1, dtype=np.float64)
    k = np.exp(-0.5 * (x / sigma) ** 2)
    return k / k.sum()


def gaussian_blur(a, sigma=1.5, radius=5):
    """Separable Gaussian, renormalised where the window leaves the image
    (so a constant stays constant up to the border)."""
    k = gaussian_kernel(sigma, radius)

    def blur(x, axis):
        x = np.moveaxis(x, axis, 0)
        n = x.shape[0]
        out = np.zeros_like(x)
        for i, w in enumerate(k):
            o = i - radius
            lo, hi = max(0, -o), min(n, n - o)
            if lo < hi:
                out[lo:hi] += w * x[lo + o:hi + o]
        return np.moveaxis(out, 0, axis)

    ones = np.ones_like(a)
    norm = blur(blur(ones, 0), 1)
    return blur(blur(a, 0), 1) / norm


def ssim_map(x, y, sigma=1.5, radius=5, k1=0.01, k2=0.03, L=1.0):
    x = x.astype(np.float64)
    y = y.astype(np.float64)
    c1, c2 = (k1 * L) ** 2, (k2 * L) ** 2
    mx, my = gaussian_blur(x, sigma, radius), gaussian_blur(y, sigma, radius)
    sxx = gaussian_blur(x * x, sigma, radius) - mx * mx
    syy = gaussian_blur(y * y, sigma, radius) - my * my
    sxy = gaussian_blur(x * y, sigma, radius) - mx * my
    return ((2 * mx * my + c1) * (2 * sxy + c2)) / \
        ((mx * mx + my * my + c1) * (sxx + syy + c2))


def ssim(img, ref, mask, exposure):
    _check(img, ref, mask)
    m = ssim_map(display_luma(img, exposure), display_luma(ref, exposure))
    return float(np.mean(m[mask]))


def exposure_for(ref, mask):
    """One exposure for every image of a scene: the reference's 99th
    percentile luminance over the mask maps to 0.85."""
    y = np.tensordot(ref[mask].astype(np.float64), LUMA, axes=([1], [0]))
    p = float(np.percentile(y, 99)) if y.size else 0.0
    return 0.85 / p if p > 0 else 1.0


def noise_corrected_rmse(img, ref, mask, half_a, half_b):
    """RMSE against the expectation of ref = (half_a + half_b) / 2, two
    independent renders (see the module doc)."""
    _check(img, ref, mask)
    d = (img[mask] - ref[mask]).astype(np.float64)
    h = (half_a[mask] - half_b[mask]).astype(np.float64)
    return float(np.sqrt(max(0.0, np.mean(d * d) - np.mean(h * h) / 4)))


def silhouettes(index, depth, rel_step=0.05):
    """Pixels with a 4-neighbour of another material index or a depth
    step of more than rel_step of the nearer depth."""
    out = np.zeros(index.shape, bool)
    for axis in (0, 1):
        n = index.shape[axis]
        a = [slice(None)] * 2
        b = [slice(None)] * 2
        a[axis], b[axis] = slice(1, n), slice(0, n - 1)
        a, b = tuple(a), tuple(b)
        near = np.minimum(depth[a], depth[b])
        step = (index[a] != index[b]) | \
            (np.abs(depth[a] - depth[b]) > rel_step * near)
        out[a] |= step
        out[b] |= step
    return out


def all_metrics(img, ref, mask, exposure, halves=None, edges=None):
    """halves: the reference's two independent halves, for rmse_c,
    rmse_q_c and, with edges (silhouettes()), rmse_in_c; nan without."""
    qi, qr, qm = quarter(img, ref, mask)
    have_q = bool(qm.any())
    nan = float("nan")
    corrected = {"rmse_c": nan, "rmse_q_c": nan, "rmse_in_c": nan}
    if halves is not None:
        a, b = halves
        corrected["rmse_c"] = noise_corrected_rmse(img, ref, mask, a, b)
        if have_q:
            corrected["rmse_q_c"] = noise_corrected_rmse(
                qi, qr, qm, downsample(a), downsample(b))
        inner = mask & ~edges if edges is not None else None
        if inner is not None and inner.any():
            corrected["rmse_in_c"] = noise_corrected_rmse(img, ref, inner,
                                                          a, b)
    return {**corrected,
        "rmse": rmse(img, ref, mask),
        "rel_mae": rel_mae(img, ref, mask),
        "rmse_q": rmse(qi, qr, qm) if have_q else float("nan"),
        "rel_mae_q": rel_mae(qi, qr, qm) if have_q else float("nan"),
        "ssim": ssim(img, ref, mask, exposure),
        "max_err": max_err(img, ref, mask),
    }


def render_noise(error_n, n, error_m, m):
    """The RMSE that a render's own noise contributes at n samples, from
    its errors against the (noise-free) reference at n and at m > n
    samples: bias is the same at both and noise variance goes as 1/samples,
    so error_n^2 - error_m^2 = noise_n^2 (1 - n/m). nan where the errors do
    not fall (noise too small to see against the bias)."""
    if not (m > n > 0) or not (error_n > error_m >= 0):
        return float("nan")
    return float(np.sqrt((error_n ** 2 - error_m ** 2) / (1.0 - n / m)))


def interp_samples(samples, errors, target):
    """The sample count at which a random-walk series (samples ascending,
    errors against the reference) reaches `target`, interpolating
    log(error) linearly in log(samples) between the bracketing points.
    Returns (samples, how): how is "interpolated", "below" (already reached
    at the lowest count: the lowest count is returned) or "extrapolated"
    (past the highest count, along the slope of the last two points, or
    1/sqrt(n) when there is only one)."""
    pts = [(float(s), float(e)) for s, e in zip(samples, errors)
           if e > 0 and np.isfinite(e)]
    if not pts or not (target > 0 and np.isfinite(target)):
        return float("nan"), "n/a"
    if target >= pts[0][1]:
        return pts[0][0], "below"
    for (s0, e0), (s1, e1) in zip(pts, pts[1:]):
        if e0 >= target >= e1 and e0 != e1:
            t = (np.log(target) - np.log(e0)) / (np.log(e1) - np.log(e0))
            return float(np.exp(np.log(s0) + t * (np.log(s1) -
                                                  np.log(s0)))), \
                "interpolated"
    if len(pts) >= 2 and pts[-1][1] < pts[-2][1]:
        (s0, e0), (s1, e1) = pts[-2], pts[-1]
        slope = (np.log(e1) - np.log(e0)) / (np.log(s1) - np.log(s0))
    else:
        slope = -0.5
        s1, e1 = pts[-1]
    return float(np.exp(np.log(s1) + (np.log(target) - np.log(e1)) /
                        slope)), "extrapolated"


def equal_time(ours, walk):
    """Where ours is ahead of the walk at equal wall time. ours and walk:
    [(seconds, error, samples)], one point per sample count (both
    denoised, say). The walk's error at any time is its curve: log(error)
    linear in log(seconds) between its measured points (interp_samples
    over seconds); it "reaches" an error at the first time its curve is
    at or below it, at its first point if that is already below, and not
    at all if only extrapolation would. Ours at a time budget is the best
    of its points that fit: a point with no less error than a cheaper one
    never counts. A point of ours at t with error e is ahead from t until
    the walk reaches e (if that is later than t).

    Returns a dict: "intervals", [(start, end)] in seconds where ours is
    ahead, merged, end inf where the walk never reaches that error within
    its measured counts; "points", per counted point of ours a dict:
    seconds, error, samples, reach (seconds when the walk reaches its
    error, inf: never within the measured ones; nan: no walk), reach_samples
    (the walk's samples there, log samples linear in log seconds),
    how (interp_samples's word), ahead (bool)."""
    ours = sorted((float(t), float(e), n) for t, e, n in ours
                  if np.isfinite(e) and e > 0 and t > 0)
    walk = sorted((float(t), float(e), float(n)) for t, e, n in walk
                  if np.isfinite(e) and e > 0 and t > 0)
    points, best = [], float("inf")
    for t, e, n in ours:
        if e >= best:
            continue
        best = e
        reach, how = interp_samples([w[0] for w in walk],
                                    [w[1] for w in walk], e)
        if how == "extrapolated":
            reach = float("inf")
        if np.isfinite(reach):
            reach_n = float(np.exp(np.interp(
                np.log(reach), [np.log(w[0]) for w in walk],
                [np.log(w[2]) for w in walk])))
        else:
            reach_n = reach
        points.append(dict(seconds=t, error=e, samples=n, reach=reach,
                           reach_samples=reach_n, how=how,
                           ahead=bool(reach > t)))
    intervals = []
    for p in points:
        if not p["ahead"]:
            continue
        if intervals and p["seconds"] <= intervals[-1][1]:
            intervals[-1] = (intervals[-1][0], max(intervals[-1][1],
                                                   p["reach"]))
        else:
            intervals.append((p["seconds"], p["reach"]))
    return dict(intervals=intervals, points=points)


def equal_time_line(name, result, walk, ours_label="ours+OIDN",
                    walk_label="walk+OIDN"):
    """One line on equal_time's result (walk: its input, for the walk's
    own points)."""
    points, intervals = result["points"], result["intervals"]
    walk = sorted((float(t), float(e), n) for t, e, n in walk
                  if np.isfinite(e) and e > 0 and t > 0)
    if not points or len(walk) < 2:
        return (f"{name}: no equal-time comparison ({ours_label} and "
                f"{walk_label} at two counts or more are needed)")
    if not intervals:
        best = points[-1]
        first = walk[0]
        if first[1] <= best["error"]:
            return (f"{name}: never ahead: {walk_label} at {first[2]:g} spp "
                    f"({first[0]:.1f} s) is already closer ({first[1]:.4f} "
                    f"against {ours_label}'s best {best['error']:.4f} at "
                    f"{best['samples']:g} spp, {best['seconds']:.1f} s)")
        return (f"{name}: never ahead: {walk_label} reaches "
                f"{ours_label}'s best ({best['error']:.4f} at "
                f"{best['samples']:g} spp, {best['seconds']:.1f} s) in "
                f"{best['reach']:.1f} s (about {best['reach_samples']:.0f} "
                "spp)")
    start, end = intervals[-1]
    last = max((p for p in points if p["ahead"]), key=lambda p: p["reach"])
    gaps = "".join(f"; not from {a:.1f} to {b:.1f} s" for (_, a), (b, _)
                   in zip(intervals, intervals[1:]))
    since = f"from {intervals[0][0]:.1f} s " if intervals[0][0] > 0 else ""
    if not np.isfinite(end):
        top = walk[-1]
        return (f"{name}: {ours_label} ahead of {walk_label} {since}on, "
                f"past the walk's largest count: at {top[2]:g} spp "
                f"({top[0]:.1f} s) it has {top[1]:.4f}, {ours_label} "
                f"{last['error']:.4f} at {last['samples']:g} spp "
                f"({last['seconds']:.1f} s){gaps}")
    fewest = " (its fewest)" if last["how"] == "below" else ""
    return (f"{name}: {ours_label} ahead of {walk_label} {since}up to "
            f"{end:.1f} s (walk needs {last['reach_samples']:.0f} spp"
            f"{fewest} to match {ours_label}'s {last['error']:.4f} at "
            f"{last['samples']:g} spp, {last['seconds']:.1f} s){gaps}")


def time_at(samples, seconds, n):
    """Render time at n samples: piecewise linear between the measured
    (samples, seconds), proportional to the nearest end outside them."""
    s = np.asarray(samples, dtype=np.float64)
    t = np.asarray(seconds, dtype=np.float64)
    order = np.argsort(s)
    s, t = s[order], t[order]
    if n < s[0]:
        return float(t[0] * n / s[0])
    if n > s[-1]:
        return float(t[-1] * n / s[-1])
    return float(np.interp(n, s, t))


def crop_box(mask, pad=0.12):
    """The box (y0, y1, x0, x1) around the mask's pixels, widened by pad
    of its size on each side (and 2 pixels): what the pictures show."""
    ys, xs = np.nonzero(mask)
    h, w = mask.shape
    y0, y1, x0, x1 = ys.min(), ys.max() + 1, xs.min(), xs.max() + 1
    py, px = int((y1 - y0) * pad) + 2, int((x1 - x0) * pad) + 2
    return (max(0, y0 - py), min(h, y1 + py), max(0, x0 - px),
            min(w, x1 + px))
