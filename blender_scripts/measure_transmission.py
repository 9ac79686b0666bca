"""Back-lit transmission against Cycles' random walk, on one scene.

    blender -b --python-exit-code 1 --python \
        blender_scripts/measure_transmission.py -- --scene head.blend \
        --out out/transmission [--resolution 160x120] [--rw-samples 512] \
        [--samples 64]

Renders (same settings as compare.py: CPU, no denoising, indirect clamp
10, no adaptive sampling):
  1. the reference: the materials' own random-walk SSS;
  2. material SSS switched off with the back-light layer (the add-on's
     switched_off), timed, and the same without the layer (its cost);
then runs the library twice on the SAME passes, with the materials'
transmission and with it off, so the difference is transmission alone.

Error (compare_metrics: RMSE and relative MAE, full and quarter
resolution) over the scattering pixels and over the back-lit ones: the
scattering pixels where the light arriving from behind (the back-light
layer's DiffDir + DiffInd, luminance) is at least 5 % of its 99th
percentile there; and ours over the walk per channel, summed over the
pixels three or more inside the outline (the shapes of build_scene.py
--kind cup, dome). Writes results.txt, results.json and sheet.png
(reference | blur alone | blur + transmission | back light, with the
|error| maps below, same exposure)."""
import argparse
import json
import math
import os
import sys
import time
import traceback

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, ".."))
sys.path.insert(0, os.path.join(ROOT, "addon"))
sys.path.insert(0, HERE)
from separable_sss import blender_compat as compat  # noqa: E402

import numpy as np  # noqa: E402

import compare_metrics as cm  # noqa: E402
from exr_io import read_exr, rgb  # noqa: E402

REF_SEED_OFFSET = 7919


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="measure_transmission.py")
    p.add_argument("--scene", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--resolution", default="160x120")
    p.add_argument("--rw-samples", type=int, default=512)
    p.add_argument("--samples", type=int, default=64)
    p.add_argument("--slab-sweep", default="",
                   help="thin-slab mode (build_scene.py --kind slab): "
                   "comma-separated thicknesses in metres, e.g. "
                   "0.005,0.015,0.04; --scene is the slab .blend")
    p.add_argument("--slab-subsurface", default="0.02,0.05",
                   help="slab mode: the Subsurface values (radius factors) "
                   "to sweep")
    p.add_argument("--slab-albedo", default="",
                   help="slab mode: the skin's colour (Base and Subsurface "
                   "Color) as R,G,B instead of the scene's")
    p.add_argument("--slab-method", default="",
                   help="slab mode: the skin's subsurface method "
                   "(RANDOM_WALK_SKIN, RANDOM_WALK; the add-on's names: "
                   "3.x's Random Walk is RANDOM_WALK_SKIN) instead of the "
                   "scene's")
    p.add_argument("--slab-light", default="back", choices=("back", "front"),
                   help="slab mode: lit only from behind (transmission, "
                   "the default), or only from the front, by a sun along "
                   "the view (reflectance against thickness: the walk's "
                   "light over the library's without transmission)")
    p.add_argument("--model", default="BURLEY",
                   help="transmission model for materials that have it off "
                   "(the add-on's default): BURLEY, JIMENEZ, BEER_LAMBERT, "
                   "FAST")
    a = p.parse_args(argv)
    a.resolution = tuple(int(v) for v in a.resolution.lower().split("x"))
    return a


def open_scene(args):
    bpy.ops.wm.open_mainfile(filepath=args.scene)
    scene = bpy.context.scene
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y = args.resolution
    r.resolution_percentage = 100
    r.use_compositing = False
    r.use_sequencer = False
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False
    scene.cycles.sample_clamp_direct = 0.0
    scene.cycles.sample_clamp_indirect = 10.0
    scene.cycles.use_adaptive_sampling = False
    return scene


def render(scene):
    t0 = time.perf_counter()
    if bpy.ops.render.render() != {"FINISHED"}:
        raise RuntimeError("render failed")
    return time.perf_counter() - t0


def write_png(path, img):
    import OpenImageIO as oiio
    h, w, _ = img.shape
    out = oiio.ImageOutput.create(path)
    out.open(path, oiio.ImageSpec(w, h, 3, oiio.UINT8))
    out.write_image((np.clip(img, 0, 1) * 255 + 0.5).astype(np.uint8))
    out.close()


def light_from_the_front(scene):
    """The slab lit only from the front: its lights gone, a sun along the
    view (the camera looks along +Y at the slab's face)."""
    for obj in list(scene.objects):
        if obj.type == "LIGHT":
            bpy.data.objects.remove(obj)
    data = bpy.data.lights.new("Front", "SUN")
    data.energy = 3.0
    sun = bpy.data.objects.new("Front", data)
    scene.collection.objects.link(sun)
    sun.rotation_euler = (math.pi / 2, 0.0, 0.0)  # shining along +Y


def process(work, tag, desc, on, passes):
    """The library on the passes with the description, transmission on or
    off: SSS.Combined (RGB), the library's timings and the description as
    run (written beside it in work)."""
    from separable_sss import native
    d = json.loads(json.dumps(desc))
    if not on:
        for mm in d["materials"]:
            mm["transmission"] = "off"
    jp = os.path.join(work, f"{tag}_{int(on)}.json")
    with open(jp, "w") as f:
        json.dump(d, f, indent=1)
    out = os.path.join(work, f"{tag}_sss{int(on)}.exr")
    with native.Scene(jp) as sc:
        t = sc.process(passes, out, layer="ViewLayer")
    return rgb(read_exr(out), "SSS.Combined"), t, d


def scatter_slab(work, tag, desc, on, mask):
    """The library on one slab's SSS-off passes with its description,
    transmission on or off: the mean SSS.Combined over mask, and the
    description as run."""
    image, _, d = process(work, tag, desc, on,
                          os.path.join(work, f"{tag}_off.exr"))
    return image[mask].mean(0), d


def front_row(work, tag, thick, sub, desc, ref, mask, lum):
    """One thickness of the front-lit slab: the walk's light and the
    library's (transmission off: nothing comes from behind) over the
    middle of the slab, and their ratio per channel."""
    ours, d = scatter_slab(work, tag, desc, False, mask)
    row = dict(thickness=thick, subsurface=sub,
               material=d["materials"][0], rw=ref.tolist(),
               model=ours.tolist(), rw_lum=float(ref @ lum),
               model_lum=float(ours @ lum),
               rw_over_model=(ref / ours).tolist())
    print("slab", json.dumps(row), flush=True)
    return row


def write_front_rows(args, rows):
    lines = ["| thickness (cm) | Subsurface | random walk R, G, B | library "
             "R, G, B | walk / library R, G, B |", "|" + "---|" * 5]
    for r in rows:
        lines.append(
            f"| {100 * r['thickness']:g} | {r['subsurface']:g} | " +
            ", ".join(f"{v:.3f}" for v in r["rw"]) + " | " +
            ", ".join(f"{v:.3f}" for v in r["model"]) + " | " +
            ", ".join(f"{v:.3f}" for v in r["rw_over_model"]) + " |")
    text = "\n".join(lines)
    print(text)
    with open(os.path.join(args.out, "slab_front.md"), "w") as f:
        f.write(text + "\n")
    with open(os.path.join(args.out, "slab_front.json"), "w") as f:
        json.dump(rows, f, indent=1)


def slab_sweep(args):
    """Front brightness of the back-lit slab at several thicknesses and
    radii: random walk against the library (blur alone and with
    transmission), over the middle of the slab (a quarter of its width on
    each side left out, so the sides play no part), per channel and as
    luminance. Materials with the slab model get their attenuation in the
    back-light layer's light itself (transmission.py), so the thickness
    pass reads 0 there. Each row also has the material as the library
    read it and the library's transmittance at the slab's thickness
    (t_library): the walk's, in the library's terms, is t_rw / t_model x
    t_library (scripts/fit_transmission4.py)."""
    from separable_sss import native, pipeline, transmission
    from separable_sss.switch_off import switched_off
    import ctypes  # noqa: F401
    work = os.path.join(args.out, "work")
    os.makedirs(work, exist_ok=True)
    lum = np.array(cm.LUMA)
    rows = []
    for sub in [float(v) for v in args.slab_subsurface.split(",")]:
        for thick in [float(v) for v in args.slab_sweep.split(",")]:
            tag = f"t{thick:g}_s{sub:g}"
            means = {}
            for kind in ("rw", "off"):
                scene = open_scene(args)
                if args.slab_light == "front":
                    light_from_the_front(scene)
                slab = scene.objects["Cube"]
                slab.scale[1] = thick
                mat = bpy.data.materials["Skin"]
                bsdf = mat.node_tree.nodes["Principled BSDF"]
                compat.set_subsurface_factor(bsdf, sub)
                if args.slab_method:
                    compat.set_method(bsdf, args.slab_method)
                if args.slab_albedo:
                    colour = (*[float(v) for v in
                                args.slab_albedo.split(",")], 1.0)
                    compat.set_principled(bsdf, base=colour,
                                          subsurface_color=colour,
                                          subsurface=sub)
                bpy.context.view_layer.update()
                path = os.path.join(work, f"{tag}_{kind}.exr")
                if kind == "rw":
                    scene.cycles.samples = args.rw_samples
                    scene.cycles.seed += REF_SEED_OFFSET
                    render(scene)
                    pipeline.save_passes(scene, path)
                    continue
                scene.cycles.samples = args.samples
                found = pipeline.analyse(scene)
                mat.sss.transmission = args.model
                with switched_off(scene, found, backlight=True):
                    render(scene)
                    pipeline.save_passes(scene, path)
                    desc = pipeline.scene_description(scene, found)
            ch = read_exr(os.path.join(work, f"{tag}_off.exr"))
            idx = np.rint(ch["ViewLayer.IndexMA.X"]) > 0
            ys, xs = np.nonzero(idx)
            x0, x1 = xs.min(), xs.max()
            y0, y1 = ys.min(), ys.max()
            cx, cy = (x1 - x0) // 4, (y1 - y0) // 4
            m = np.zeros_like(idx)
            m[y0 + cy:y1 - cy + 1, x0 + cx:x1 - cx + 1] = True
            m &= idx
            ref = rgb(read_exr(os.path.join(work, f"{tag}_rw.exr")),
                      "ViewLayer.Combined")
            if args.slab_light == "front":
                rows.append(front_row(work, tag, thick, sub, desc,
                                      ref[m].mean(0), m, lum))
                continue
            for on in (False, True):
                means[on], _ = scatter_slab(work, tag, desc, on, m)
            b = rgb(ch, f"{transmission.LAYER}.DiffDir") + \
                rgb(ch, f"{transmission.LAYER}.DiffInd")
            dc = rgb(ch, "ViewLayer.DiffCol")
            t_meas = np.sqrt(np.maximum(
                ch[f"{transmission.LAYER}.{transmission.THICKNESS_AOV}.X"],
                0.0))[m].mean()
            bd = (b * dc)[m].mean(0)
            r = ref[m].mean(0)
            entry = desc["materials"][0]  # the slab's, as the library reads it
            row = dict(thickness=thick, subsurface=sub,
                       material=entry,
                       t_library=native.transmittance(entry, thick),
                       measured_thickness=float(t_meas),
                       rw=r.tolist(), off=means[False].tolist(),
                       model=means[True].tolist(),
                       rw_lum=float(r @ lum),
                       off_lum=float(means[False] @ lum),
                       model_lum=float(means[True] @ lum),
                       t_rw=((r - means[False]) / bd).tolist(),
                       t_model=((means[True] - means[False]) / bd).tolist())
            rows.append(row)
            print("slab", json.dumps(row), flush=True)
    if args.slab_light == "front":
        return write_front_rows(args, rows)
    lines = ["| thickness (cm) | Subsurface | random walk R, G, B (lum.) | "
             "blur alone (lum.) | model R, G, B (lum.) | model / rw |",
             "|" + "---|" * 6]
    for r in rows:
        lines.append(
            f"| {100 * r['thickness']:g} | {r['subsurface']:g} | " +
            ", ".join(f"{v:.3f}" for v in r["rw"]) +
            f" ({r['rw_lum']:.3f}) | {r['off_lum']:.3f} | " +
            ", ".join(f"{v:.3f}" for v in r["model"]) +
            f" ({r['model_lum']:.3f}) | "
            f"{r['model_lum'] / max(r['rw_lum'], 1e-9):.2f} |")
    text = "\n".join(lines)
    print(text)
    with open(os.path.join(args.out, "slab.md"), "w") as f:
        f.write(text + "\n")
    with open(os.path.join(args.out, "slab.json"), "w") as f:
        json.dump(rows, f, indent=1)


def inside(mask, margin):
    """The pixels of mask whose every pixel within margin (a square) is
    in mask too."""
    h, w = mask.shape
    out = mask.copy()
    for dy in range(-margin, margin + 1):
        for dx in range(-margin, margin + 1):
            shifted = np.zeros_like(mask)
            shifted[max(dy, 0):h + min(dy, 0), max(dx, 0):w + min(dx, 0)] = \
                mask[max(-dy, 0):h + min(-dy, 0), max(-dx, 0):w + min(-dx, 0)]
            out &= shifted
    return out


def main():
    args = parse_args()
    if args.slab_sweep:
        os.makedirs(args.out, exist_ok=True)
        slab_sweep(args)
        return
    from separable_sss import pipeline, transmission
    from separable_sss.switch_off import switched_off
    os.makedirs(args.out, exist_ok=True)
    work = os.path.join(args.out, "work")
    os.makedirs(work, exist_ok=True)

    scene = open_scene(args)
    scene.cycles.samples = args.rw_samples
    scene.cycles.seed += REF_SEED_OFFSET
    rw_s = render(scene)
    pipeline.save_passes(scene, os.path.join(work, "rw.exr"))
    ref = rgb(read_exr(os.path.join(work, "rw.exr")), "ViewLayer.Combined")

    scene = open_scene(args)
    scene.cycles.samples = args.samples
    found = pipeline.analyse(scene)
    for f in found.materials:
        if f.material.sss.transmission in ("OFF", "AUTO"):
            f.material.sss.transmission = args.model
    need, why = transmission.wanted(scene, found)
    times = {}
    inp = os.path.join(work, "passes.exr")
    for layer in (False, True):
        with switched_off(scene, found, backlight=layer):
            times[layer] = render(scene)
            if layer:
                pipeline.save_passes(scene, inp)
                desc = pipeline.scene_description(scene, found)
    results = {}
    for on in (False, True):
        image, t, _ = process(work, "scene", desc, on, inp)
        results[on] = (image, t["scatter"])

    ch = read_exr(inp)
    idx = np.rint(ch["ViewLayer.IndexMA.X"])
    depth = ch["ViewLayer.Depth.Z"]
    mask = np.isin(idx, [f.pass_index for f in found.materials]) & (depth < 1e9)
    back = np.zeros(mask.shape)
    if f"{transmission.LAYER}.DiffDir.R" in ch:
        b = rgb(ch, f"{transmission.LAYER}.DiffDir") + \
            rgb(ch, f"{transmission.LAYER}.DiffInd")
        back = b @ cm.LUMA
    thresh = 0.05 * np.percentile(back[mask], 99) if mask.any() else 0
    backlit = mask & (back > thresh) & (thresh > 0)
    exposure = cm.exposure_for(ref, mask)

    lines = [f"scene {args.scene} at {args.resolution[0]}x"
             f"{args.resolution[1]}: reference random walk "
             f"{args.rw_samples} spp ({rw_s:.1f} s); SSS off "
             f"{args.samples} spp",
             f"back-light layer: {'on' if need else 'off'} ({why}), "
             f"{transmission.layer_samples(scene)} samples",
             f"render without the layer {times[False]:.2f} s, with it "
             f"{times[True]:.2f} s: +{times[True] - times[False]:.2f} s "
             f"({100 * (times[True] / times[False] - 1):.0f} %)",
             f"scattering pixels {int(mask.sum())}, back-lit "
             f"{int(backlit.sum())}"]
    summary = {"times": times, "need": need, "why": why}
    for name, m in (("scattering", mask), ("back-lit", backlit)):
        if not m.any():
            continue
        row = {}
        for on in (False, True):
            img = results[on][0]
            q = cm.quarter(img, ref, m)
            row[on] = dict(rmse=cm.rmse(img, ref, m),
                           rel_mae=cm.rel_mae(img, ref, m),
                           rmse_q=cm.rmse(*q) if q[2].any() else 0.0)
        cut = 100 * (1 - row[True]["rmse"] / row[False]["rmse"])
        cut_mae = 100 * (1 - row[True]["rel_mae"] / row[False]["rel_mae"])
        lines.append(
            f"{name:>10}: RMSE blur alone {row[False]['rmse']:.5f}, with "
            f"transmission {row[True]['rmse']:.5f} ({cut:.0f} % less); "
            f"rel. MAE {row[False]['rel_mae']:.4f} -> "
            f"{row[True]['rel_mae']:.4f} ({cut_mae:.0f} % less); quarter-res "
            f"RMSE {row[False]['rmse_q']:.5f} -> {row[True]['rmse_q']:.5f}")
        summary[name] = {str(k): v for k, v in row.items()}
    inner = inside(mask, 3)
    if inner.any():
        ratio = {on: results[on][0][inner].sum(0) / ref[inner].sum(0)
                 for on in (False, True)}
        lines.append(
            f"ours over the walk, {int(inner.sum())} pixels 3 or more "
            "inside the outline: blur alone " +
            " / ".join(f"{v:.3f}" for v in ratio[False]) +
            ", with transmission " +
            " / ".join(f"{v:.3f}" for v in ratio[True]))
        summary["inside_ratio"] = {str(k): v.tolist()
                                   for k, v in ratio.items()}
    lines.append(f"library scatter time: off {results[False][1]:.3f} s, "
                 f"on {results[True][1]:.3f} s")
    text = "\n".join(lines)
    print(text)
    with open(os.path.join(args.out, "results.txt"), "w") as f:
        f.write(text + "\n")
    with open(os.path.join(args.out, "results.json"), "w") as f:
        json.dump(summary, f, indent=1, default=float)

    def show(img):
        return np.clip(img * exposure, 0, None) ** (1 / 2.2)

    b3 = np.repeat(back[:, :, None], 3, axis=2) * mask[:, :, None]
    top = [ref, results[False][0], results[True][0], b3]
    err = [np.zeros_like(ref)] + [np.abs(results[k][0] - ref) * 4
                                  for k in (False, True)] + \
        [np.stack([backlit] * 3, axis=-1).astype(np.float32) / exposure]
    sheet = np.concatenate([np.concatenate([show(i) for i in top], axis=1),
                            np.concatenate([show(i) for i in err], axis=1)],
                           axis=0)
    write_png(os.path.join(args.out, "sheet.png"), sheet)


try:
    import separable_sss
    separable_sss.register()
    main()
except Exception:
    traceback.print_exc()
    sys.exit(1)
