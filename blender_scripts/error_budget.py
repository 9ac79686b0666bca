"""Where our remaining error is, by cause, with OIDN on both sides, and the
trade at equal time against the denoised random walk, headless:

    blender -b --factory-startup --python-exit-code 1 \\
        --python blender_scripts/error_budget.py -- --scene SCENE.blend \\
        --out DIR [--name NAME] [--resolution 240x135] [--ref-samples 1024]
        [--rw-samples 4,8,16,64] [--samples 16[,64]] [--seeds 1] [--cache DIR]
    blender -b --python blender_scripts/error_budget.py -- --summary DIR

In one run: Cycles' random walk at --ref-samples (the reference: two
renders of half as many samples with two other seeds, so that its noise can
be taken out; kept in --cache and reused by later runs of the same scene,
size and count), the random walk at each --rw-samples count, the render
with material SSS off at each --samples count (the budget is the first's)
and our default method on its passes;
every one of them but the reference denoised by Blender's Denoise node
(OIDN, with the render's albedo and normal), as artists render. Times are
wall times of the render, the library's scatter and the denoise.

With --seeds N every run but the reference is rendered with N seeds (the
scene's and the next ones, SEED_STEP apart) and each row's error is the
root of the mean squared error over them, its time the mean: at 16
samples one seed's error is a draw, not the method's (on the mixed scene
ours + OIDN read 0.0117 - 0.0238 over eight seeds, the walk + OIDN
0.0154 - 0.0264, and one specular highlight's noise held 28 % of ours'
squared error at the first seed). budget.json keeps each seed's error
(rmse_q_c_seeds); the budget averages the seeds' squared errors per block.
Only the first seed's renders stay in DIR/work.

The budget is of ours + OIDN at quarter resolution (compare_metrics: 4 x 4
blocks at least 75 % scattering, where noise averages away and bias
stays), its squared error against the reference with the reference's own
noise taken out:
- calibration: what a per-material, per-channel gain fitted to the
  reference takes away (the energy the walk returns that ours does not);
  the shares below split what is left after that gain, by block, the
  first that applies:
- silhouettes: blocks touching a silhouette or a depth step (a pixel with
  a 4-neighbour of another material or a depth more than 5 % apart),
  where light leaves or enters through faces the camera does not see;
- transmission: blocks where the back-light layer's light is at least
  5 % of the front diffuse light (its scattering pixels);
- crevices: blocks whose surface is concave at the scale of the
  material's radius (the mean curvature from the Position pass times the
  largest radius below -0.05: grooves, sockets, the inside of a ring);
- edges: blocks with a sharp convex edge between faces the camera sees
  (that curvature times the radius above 2: far sharper than any
  rounded object at its own scale), or with a pixel that covers two such
  faces (its Denoising Normal, averaged over its samples, shorter than
  0.97; on the block scene the curvature alone found the edges in 3 % of
  the blocks, where they run over 16 %);
- the rest.
Each line: its share of the squared error (with the reference's noise in
those blocks taken out; shares may be negative where that noise is larger
than the error), the share of blocks, the RMSE there and the render
without SSS's (denoised) in the same blocks: where the two are alike the
error is not the scattering's.

Writes DIR/budget.json, DIR/budget.md, DIR/time.png (make compare's plot of
the trade at equal time) and DIR/errors.png (reference, ours
+ OIDN, |error| at quarter resolution on one scale, the blocks' causes:
red silhouettes, blue transmission, green crevices, yellow edges, grey
the rest). With
--summary, DIR/summary.md gathers every DIR/*/budget.json (and each
scene's time.png is drawn again from it).
"""
import argparse
import glob
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import numpy as np  # noqa: E402

from script_cli import run_main, script_argv  # noqa: E402

CAUSES = ("silhouettes", "transmission", "crevices", "edges", "rest")
TRANSMISSION_SHARE = 0.05
CONCAVE_X = -0.05
CONVEX_EDGE_X = 2.0
# A unit normal averaged over faces 30 degrees apart in equal parts is
# 0.966 long; over one face 1.
TWO_FACES_NORMAL = 0.97
# Seeds of the runs, apart from each other and from the reference's
# (compare_runs.REF_SEED_OFFSET, 7919 apart).
SEED_STEP = 101


def log(*a):
    print("budget:", *a, flush=True)


def parse_args():
    p = argparse.ArgumentParser(prog="error_budget.py")
    p.add_argument("--scene")
    p.add_argument("--out", help="the scene's output folder")
    p.add_argument("--name")
    p.add_argument("--resolution", default="240x135")
    p.add_argument("--ref-samples", type=int, default=1024)
    p.add_argument("--rw-samples", default="4,8,16,64")
    p.add_argument("--samples", default="16",
                   help="ours' (and the render without SSS's) counts, "
                        "comma-separated; the budget is the first's")
    p.add_argument("--back-samples", type=int, default=0,
                   help="the back-light layer's samples for ours (0: the "
                        "scene's setting)")
    p.add_argument("--seeds", type=int, default=1,
                   help="render ours and the walk with this many seeds "
                        "and pool their errors (the scene's seed and the "
                        "next ones, SEED_STEP apart)")
    p.add_argument("--cache", help="where the reference renders are kept "
                   "(default: DIR/../cache)")
    p.add_argument("--summary", help="gather DIR/*/budget.json into "
                   "DIR/summary.md and stop")
    args = p.parse_args(script_argv())
    if args.summary:
        return args
    if not args.scene or not args.out:
        p.error("--scene and --out are required (or --summary)")
    try:
        w, _, h = args.resolution.partition("x")
        args.resolution = (int(w), int(h))
        args.rw_samples = sorted({int(x) for x in args.rw_samples.split(",")})
        args.samples = list(dict.fromkeys(int(x) for x in
                                          args.samples.split(",")))
    except ValueError as e:
        p.error(f"--resolution, --rw-samples or --samples: {e}")
    if args.seeds < 1:
        p.error(f"--seeds {args.seeds}: must be 1 or more")
    if args.back_samples < 0:
        p.error(f"--back-samples {args.back_samples}: must be 0 (the "
                "scene's setting) or more")
    args.scene = os.path.abspath(args.scene)
    args.out = os.path.abspath(args.out)
    args.name = args.name or os.path.splitext(os.path.basename(
        args.scene))[0]
    args.cache = os.path.abspath(args.cache or os.path.join(
        os.path.dirname(args.out), "cache"))
    args.eevee_samples = 1   # compare_runs.open_scene reads it
    return args


# ------------------------------------------------------------- measures

def down(a, f=4):
    """4 x 4 block means (compare_metrics.downsample), any trailing axes."""
    import compare_metrics as cm
    return cm.downsample(a, f)


def mean_curvature(pos, valid):
    """Mean curvature (1 / scene units, positive where convex seen from the
    camera's side) per pixel from the Position pass: the normals of the
    surface the pixels span (cross product of the position's differences)
    and their divergence along the surface. NaN where a neighbour is not
    valid."""
    p = pos.astype(np.float64)
    dx = np.zeros_like(p)
    dy = np.zeros_like(p)
    dx[:, 1:-1] = (p[:, 2:] - p[:, :-2]) / 2
    dy[1:-1] = (p[2:] - p[:-2]) / 2
    n = np.cross(dx, dy)
    ln = np.linalg.norm(n, axis=-1, keepdims=True)
    n = np.where(ln > 0, n / np.maximum(ln, 1e-30), np.nan)
    ndx = np.full_like(n, np.nan)
    ndy = np.full_like(n, np.nan)
    ndx[:, 1:-1] = (n[:, 2:] - n[:, :-2]) / 2
    ndy[1:-1] = (n[2:] - n[:-2]) / 2
    kx = np.sum(ndx * dx, -1) / np.maximum(np.sum(dx * dx, -1), 1e-30)
    ky = np.sum(ndy * dy, -1) / np.maximum(np.sum(dy * dy, -1), 1e-30)
    H = 0.5 * (kx + ky)
    ok = valid.copy()
    for axis in (0, 1):
        for s in (1, -1, 2, -2):
            ok &= np.roll(valid, s, axis)
    H[~ok] = np.nan
    return H


def two_faces(normal, mask):
    """Scattering pixels that cover two faces: their normal, averaged over
    the pixel's samples (the Denoising Normal pass), is shorter than
    TWO_FACES_NORMAL."""
    length = np.linalg.norm(np.nan_to_num(normal.astype(np.float64)), axis=-1)
    return mask & (length < TWO_FACES_NORMAL)


def budget(ours, ref, halves, mask, idx, depth, back_share, curv_x,
           plain=None, faces=None):
    """The squared-error budget of ours against ref (see the module doc):
    ours, one image per seed, whose squared errors are averaged; with plain
    (the render without SSS, denoised, per seed), each cause's RMSE of
    that render in the same blocks too (rmse_plain): what the blocks'
    error would be without scattering. faces: two_faces(), or None."""
    import compare_metrics as cm
    cover = down(mask.astype(np.float64)) >= cm.QUARTER_COVERAGE
    qos, qr = [down(o) for o in ours], down(ref)
    qa, qb = down(halves[0]), down(halves[1])
    noise = ((qa - qb) ** 2 / 4).sum(-1)          # per block, over RGB
    # the block's material: the most common scattering index in it
    h4, w4 = qr.shape[:2]
    ids = np.rint(idx[:h4 * 4, :w4 * 4]).reshape(h4, 4, w4, 4)
    ids = ids.transpose(0, 2, 1, 3).reshape(h4, w4, 16)
    block_id = np.array([[np.bincount(b.astype(np.int64)).argmax()
                          for b in row] for row in ids])
    err = np.mean([((qo - qr) ** 2).sum(-1) for qo in qos], 0)
    total = float(err[cover].sum() - noise[cover].sum())
    # one gain per material and channel over every seed's blocks
    gains = {}
    fitted = [qo.copy() for qo in qos]
    for m in np.unique(block_id[cover]):
        sel = cover & (block_id == m)
        k = sum((qo[sel] * qr[sel]).sum(0) for qo in qos) / np.maximum(
            sum((qo[sel] ** 2).sum(0) for qo in qos), 1e-30)
        gains[int(m)] = [float(v) for v in k]
        for f, qo in zip(fitted, qos):
            f[sel] = qo[sel] * k
    err2 = np.mean([((f - qr) ** 2).sum(-1) for f in fitted], 0)
    cal = float(err[cover].sum() - err2[cover].sum())
    edges = cm.silhouettes(idx, depth)
    qe = down(edges.astype(np.float64)) > 0
    qt = down(np.nan_to_num(back_share) * mask) >= TRANSMISSION_SHARE
    cx = np.where(np.isfinite(curv_x), curv_x, 0.0) * mask
    qc = down(cx) < CONCAVE_X
    sharp = cx > CONVEX_EDGE_X
    if faces is not None:
        sharp = sharp | faces
    qv = down(sharp.astype(np.float64)) > 0
    cause = np.full(qr.shape[:2], len(CAUSES) - 1)
    for i, sel in reversed(list(enumerate((qe, qt, qc, qv)))):
        cause[sel] = i
    cause[~cover] = -1
    rows = {"calibration": dict(share=cal / total if total > 0 else np.nan,
                                blocks=float("nan"), rmse=float("nan"),
                                gains=gains)}
    n_blocks = int(cover.sum())
    perr = np.mean([((down(p) - qr) ** 2).sum(-1) for p in plain], 0) \
        if plain is not None else None
    for i, name in enumerate(CAUSES):
        sel = cause == i
        se = float(err2[sel].sum() - noise[sel].sum())
        rows[name] = dict(
            share=se / total if total > 0 else float("nan"),
            blocks=float(sel.sum()) / max(n_blocks, 1),
            rmse=float(np.sqrt(max(se, 0.0) / max(3 * sel.sum(), 1))))
        if perr is not None:
            sp = float(perr[sel].sum() - noise[sel].sum())
            rows[name]["rmse_plain"] = float(
                np.sqrt(max(sp, 0.0) / max(3 * sel.sum(), 1)))
    rows["total"] = dict(share=1.0, blocks=1.0, rmse=float(np.sqrt(
        max(total, 0.0) / max(3 * n_blocks, 1))))
    return rows, cause, np.sqrt(np.maximum(err - noise, 0.0) / 3)


# ------------------------------------------------------------- the run

def reference(args, scene):
    import compare_runs as compare
    from exr_io import read_exr, rgb
    os.makedirs(args.cache, exist_ok=True)
    # Each Blender's walk is its own reference: the key names the version.
    version = blender_version().split()[0]
    stem = os.path.join(args.cache, f"{args.name}_{args.resolution[0]}x"
                        f"{args.resolution[1]}_rw{args.ref_samples}"
                        f"_{version}")
    paths = [f"{stem}_{k}.exr" for k in (1, 2)]
    if all(os.path.exists(p) for p in paths):
        log(f"reference from {stem}_[12].exr")
        return tuple(rgb(read_exr(p), "Combined").astype(np.float32)
                     for p in paths)
    t0 = time.perf_counter()
    halves, _ = compare.render_reference(scene, args.ref_samples, stem)
    log(f"reference rendered in {time.perf_counter() - t0:.0f} s")
    return halves


def render_seed(args, k, ref, halves):
    """Ours, the render without SSS and the walk at each count, every one
    denoised, with the scene's seed + k * SEED_STEP (k = 0: the scene's
    own seed and file names without a suffix). Returns dict(images:
    (what, samples) -> (image, seconds), ch: the first count's passes,
    found)."""
    import compare_runs as compare
    from separable_sss import native, pipeline
    from exr_io import read_exr, rgb
    work = os.path.join(args.out, "work")
    tag = f"_s{k}" if k else ""
    layer = bpy_layer_name()
    scene = compare.open_scene(args, "CYCLES")
    found = pipeline.analyse(scene)
    scene.cycles.seed += k * SEED_STEP
    seed = scene.cycles.seed     # the denoiser opens the file again
    # Ours: SSS off, our default method (its SSS layer denoised below),
    # at each count; the first is the budget's.
    if args.back_samples > 0:
        scene.sss.transmission_samples = args.back_samples
    offs = []
    for n in args.samples:
        scene.cycles.samples = n
        inp = os.path.join(work, f"off_{n}{tag}_passes.exr")
        desc = os.path.join(work, f"off_{n}{tag}_scene.json")
        out = os.path.join(work, f"off_{n}{tag}_sss.exr")
        t0 = time.perf_counter()
        compare.render_sss_off(scene, found, inp, desc)
        render_s = time.perf_counter() - t0
        t0 = time.perf_counter()
        with native.Scene(desc) as sc:
            sc.process(inp, out)
        post_s = time.perf_counter() - t0
        offs.append((n, inp, out, render_s, post_s))
    ch = read_exr(offs[0][1])
    # The random walk at each count.
    walks = []
    for n in args.rw_samples:
        scene.cycles.samples = n
        path = os.path.join(work, f"rw_{n}{tag}.exr")
        t0 = time.perf_counter()
        compare.render(scene)
        walks.append((n, path, time.perf_counter() - t0))
        pipeline.save_passes(scene, path)
    # OIDN on each, after every render (the denoiser opens the scene).
    denoiser = compare.Denoiser(args)
    images = {}
    for n, inp, out, render_s, post_s in offs:
        plain_dn, plain_dn_s = denoiser(inp, layer, "Combined")
        ours_dn, ours_dn_s = denoiser(out, "SSS", "Combined")
        images[("no SSS + OIDN", n)] = (plain_dn, render_s + plain_dn_s)
        images[("ours", n)] = (rgb(read_exr(out), "SSS.Combined"),
                               render_s + post_s)
        images[("ours + OIDN", n)] = (ours_dn,
                                      render_s + post_s + ours_dn_s)
    for n, path, seconds in walks:
        img, dn_s = denoiser(path, layer, "Combined")
        images[("walk + OIDN", n)] = (img, seconds + dn_s)
    if k:
        # Only the first seed's files stay in DIR/work (the budget's map
        # is made from them); the others' would be about 17 MB a seed
        # at 240x135.
        written = [p for _, inp, out, _, _ in offs
                   for p in (inp, out, inp.replace(".exr", ".json")
                             .replace("_passes", "_scene"))]
        written += [path for _, path, _ in walks]
        for path in written:      # and what the denoiser wrote beside
            for p in {path, path.replace(".exr", "_oidn.exr")}:
                try:
                    os.remove(p)
                except FileNotFoundError:
                    pass
    mask = compare.scattering_pixels(ch, found)[0]
    log(f"seed {seed}: " + ", ".join(
        f"{what} at {n} spp "
        f"{metrics(v[0], ref, mask, halves)['rmse_q_c']:.4f}"
        for (what, n), v in images.items()
        if what in ("ours + OIDN", "walk + OIDN") and n in args.samples))
    return dict(images=images, ch=ch, found=found)


def run(args):
    import compare_runs as compare
    from separable_sss import pipeline
    from exr_io import rgb
    os.makedirs(args.out, exist_ok=True)
    os.makedirs(os.path.join(args.out, "work"), exist_ok=True)
    scene = compare.open_scene(args, "CYCLES")
    found = pipeline.analyse(scene)
    if not found.materials:
        raise RuntimeError("nothing scatters in this scene")
    import mesh_check
    notes = mesh_check.notes(scene, [f.material for f in found.materials])
    for note in notes:
        log(f"{args.name}: note: {note}")
    halves = reference(args, scene)
    ref = (halves[0] + halves[1]) / 2
    layer = bpy_layer_name()
    # Every seed renders the same frame: the passes' geometry (mask,
    # index, depth, normals) is the first seed's.
    seeds = [render_seed(args, k, ref, halves) for k in range(args.seeds)]
    ch, found = seeds[0]["ch"], seeds[0]["found"]
    mask, idx, depth = compare.scattering_pixels(ch, found)
    rows = []
    for key in seeds[0]["images"]:
        each = [metrics(s["images"][key][0], ref, mask, halves)
                for s in seeds]
        rows.append(dict(
            what=key[0], samples=key[1],
            seconds=float(np.mean([s["images"][key][1] for s in seeds])),
            **pool(each)))
    scene = compare.open_scene(args, "CYCLES")

    # The budget of ours + OIDN.
    front = rgb(ch, "DiffDir") + rgb(ch, "DiffInd")
    back_share = np.zeros(mask.shape)
    if "SSSBackLight.DiffDir.R" in ch:
        back = rgb(ch, "SSSBackLight.DiffDir") + \
            rgb(ch, "SSSBackLight.DiffInd")
        back_share = back.sum(-1) / np.maximum(front.sum(-1), 1e-6)
    curv_x = np.full(mask.shape, np.nan)
    if f"{layer}.Position.X" in ch:
        pos = np.stack([ch[f"{layer}.Position.{c}"] for c in "XYZ"], -1)
        H = mean_curvature(pos, mask)
        radius = np.zeros(mask.shape)
        for f in found.materials:
            radius[idx == f.pass_index] = max(f.radius)
        curv_x = orient(H, pos, scene) * radius
    faces = None
    if f"{layer}.Denoising Normal.X" in ch:
        faces = two_faces(np.stack([ch[f"{layer}.Denoising Normal.{c}"]
                                    for c in "XYZ"], -1), mask)
    ours_key, plain_key = ("ours + OIDN", args.samples[0]), \
        ("no SSS + OIDN", args.samples[0])
    rows_b, cause, qerr = budget(
        [s["images"][ours_key][0] for s in seeds], ref, halves, mask, idx,
        depth, back_share, curv_x,
        [s["images"][plain_key][0] for s in seeds], faces)
    result = dict(scene=args.name, resolution=list(args.resolution),
                  ref_samples=args.ref_samples, blender=blender_version(),
                  seeds=args.seeds, runs=rows, budget=rows_b,
                  mesh_notes=notes)
    with open(os.path.join(args.out, "budget.json"), "w") as f:
        json.dump(result, f, indent=1)
    with open(os.path.join(args.out, "budget.md"), "w") as f:
        f.write(markdown([result]))
    picture(os.path.join(args.out, "errors.png"), ref,
            seeds[0]["images"][ours_key][0], qerr, cause, mask)
    time_plot(result, os.path.join(args.out, "time.png"))
    log(markdown([result]))


def pool(each):
    """One row's metrics over seeds: the RMSEs as the root of the mean
    squared error (each seed's is already the noise-free reference's), the
    mean ratio averaged, and each seed's quarter-resolution RMSE."""
    return dict(rmse_q_c=float(np.sqrt(np.mean([m["rmse_q_c"] ** 2
                                                for m in each]))),
                rmse_c=float(np.sqrt(np.mean([m["rmse_c"] ** 2
                                              for m in each]))),
                mean_ratio=float(np.mean([m["mean_ratio"] for m in each])),
                rmse_q_c_seeds=[m["rmse_q_c"] for m in each])


def bpy_layer_name():
    import bpy
    return bpy.context.view_layer.name


def blender_version():
    import bpy
    return bpy.app.version_string


def orient(H, pos, scene):
    """H signed so that a surface bulging towards the camera reads
    positive: the cross product's normal is compared with the direction
    to the camera at each pixel."""
    cam = np.array(scene.camera.matrix_world.translation)
    p = pos.astype(np.float64)
    dx = np.zeros_like(p)
    dy = np.zeros_like(p)
    dx[:, 1:-1] = (p[:, 2:] - p[:, :-2]) / 2
    dy[1:-1] = (p[2:] - p[:-2]) / 2
    n = np.cross(dx, dy)
    if scene.camera.data.type == "ORTHO":
        to_cam = -np.array(scene.camera.matrix_world.to_3x3() @
                           __import__("mathutils").Vector((0, 0, -1)))
        facing = np.sum(n * to_cam, -1)
    else:
        facing = np.sum(n * (cam - p), -1)
    # The differences' normal faces the camera on most pixels or on
    # none (it follows the image's axes): one sign for the frame.
    sign = 1.0 if np.nanmedian(np.sign(facing)) >= 0 else -1.0
    return sign * H


def metrics(img, ref, mask, halves):
    import compare_metrics as cm
    m = cm.all_metrics(img, ref, mask, 1.0, halves)
    return dict(rmse_q_c=m["rmse_q_c"], rmse_c=m["rmse_c"],
                mean_ratio=float(img[mask].mean() / ref[mask].mean()))


def picture(path, ref, ours, qerr, cause, mask):
    scale = np.percentile(ref[mask], 99) if mask.any() else 1.0

    def show(a):
        return np.clip(a / max(scale, 1e-6), 0, 1) ** (1 / 2.2)
    h4, w4 = qerr.shape
    up = np.kron(qerr, np.ones((4, 4)))
    e = np.clip(up / max(np.percentile(qerr[cause >= 0], 99), 1e-6), 0, 1)
    colours = np.array([[0.9, 0.2, 0.2], [0.2, 0.4, 1.0], [0.2, 0.9, 0.3],
                        [1.0, 0.8, 0.1], [0.5, 0.5, 0.5]])
    c = np.zeros((h4 * 4, w4 * 4, 3))
    cu = np.kron(cause, np.ones((4, 4), int))
    for i in range(len(CAUSES)):
        c[cu == i] = colours[i]
    h, w = h4 * 4, w4 * 4
    row = np.concatenate([show(ref[:h, :w]), show(ours[:h, :w]),
                          np.repeat(e[..., None], 3, -1), c], axis=1)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    plt.imsave(path, np.clip(row, 0, 1))


def markdown(results):
    out = ["| scene | ours + OIDN, quarter-res RMSE | calibration | " +
           " | ".join(CAUSES) + " |", "|---|---|" + "---|" * (1 + len(CAUSES))]
    for r in results:
        b = r["budget"]
        cells = [f"{100 * b['calibration']['share']:.0f} %"]
        for k in CAUSES:
            if k not in b:
                cells.append("")
                continue
            plain = b[k].get("rmse_plain")
            cells.append(f"{100 * b[k]['share']:.0f} % "
                         f"({100 * b[k]['blocks']:.0f} % "
                         f"of blocks, {b[k]['rmse']:.3f}" +
                         (f"; no SSS {plain:.3f}" if plain is not None
                          else "") + ")")
        out.append(f"| {r['scene']} | {b['total']['rmse']:.4f} | " +
                   " | ".join(cells) + " |")
    out += ["", "| scene | run | samples | seconds | quarter-res RMSE | "
            "mean over the walk's |", "|---|---|---|---|---|---|"]
    for r in results:
        for x in r["runs"]:
            out.append(f"| {r['scene']} | {x['what']} | {x['samples']} | "
                       f"{x['seconds']:.1f} | {x['rmse_q_c']:.4f} | "
                       f"{x['mean_ratio']:.3f} |")
    out.append("")
    out += [equal_time_line(r) for r in results]
    out += [f"{r['scene']}: note: {n}" for r in results
            for n in r.get("mesh_notes", ())]
    return "\n".join(out) + "\n"


def trade(result):
    """(line, ours, walk, equal_time's result) of a budget result: up to
    what wall time ours + OIDN is ahead of the denoised walk
    (compare_metrics.equal_time, as make compare says it)."""
    import compare_metrics as cm

    def series(what):
        return [(x["seconds"], x["rmse_q_c"], x["samples"])
                for x in result["runs"] if x["what"] == what]
    ours, walk = series("ours + OIDN"), series("walk + OIDN")
    ahead = cm.equal_time(ours, walk)
    return cm.equal_time_line(result["scene"], ahead, walk), ours, walk, \
        ahead


def equal_time_line(result):
    return trade(result)[0]


def time_plot(result, path):
    """The trade's plot (make compare's time.png) of a budget result."""
    import trade_plot
    line, ours, walk, ahead = trade(result)
    seeds = result.get("seeds", 1)
    trade_plot.draw_time_plot(
        path, line, ours, walk, ahead,
        "SSS off + libsss (default method) + OIDN" +
        (f"; both over {seeds} seeds" if seeds > 1 else ""),
        "RMSE at quarter resolution vs reference (its noise removed)")


def summary(folder):
    paths = sorted(glob.glob(os.path.join(folder, "*", "budget.json")))
    results = [json.load(open(p)) for p in paths]
    with open(os.path.join(folder, "summary.md"), "w") as f:
        f.write(markdown(results))
    for path, r in zip(paths, results):   # each scene's time.png again
        time_plot(r, os.path.join(os.path.dirname(path), "time.png"))
    log(f"wrote {folder}/summary.md and each scene's time.png "
        f"({len(results)} scenes)")


def main():
    args = parse_args()
    if args.summary:
        summary(os.path.abspath(args.summary))
        return
    os.environ.setdefault("SSS_LIB", os.path.join(os.path.dirname(HERE),
                                                  "build", "libsss.so"))
    import compare_runs  # noqa: F401  (puts the add-on on sys.path)
    import separable_sss
    separable_sss.register()
    try:
        run(args)
    finally:
        separable_sss.unregister()


if __name__ == "__main__":
    run_main(main)
