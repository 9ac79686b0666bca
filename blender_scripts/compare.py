"""Measure the speed/accuracy trade of libsss against Cycles' random-walk
SSS and EEVEE's own SSS, on one .blend, headless.

    blender -b --python-exit-code 1 --python blender_scripts/compare.py -- \\
        --scene SCENE.blend --out DIR [--quick] [--no-eevee] [--no-denoise]
        [--resolution WxH] [--rw-samples 16,64,256,1024]
        [--samples 16,64,256] [--eevee-samples 64] [--name NAME]

Renders, all in this one run (so every time is measured on the same
machine under the same load):
- Cycles with the materials' random-walk SSS at each --rw-samples count;
  the highest count is the reference: two renders of half as many samples
  with two other seeds, averaged, so that its own noise is measured and
  taken out of every error (rmse_c, compare_metrics.py);
- Cycles with material SSS switched off (the add-on's switched_off) at each
  --samples count, then each method the library accepts (enumerated at run
  time: a method the library answers SSS_ERR_UNSUPPORTED is skipped with a
  message) on those passes, through the add-on's native binding;
- OIDN (Blender's compositor Denoise node, with the render's albedo and
  normal) on the random walk, on SSS off and on the default method at each
  of their sample counts ("+oidn" rows; skipped where the node does not
  denoise: a Blender built without OpenImageDenoise);
- EEVEE with its own SSS, and EEVEE with SSS off plus each method. EEVEE
  3.4 has no Material Index pass: each scattering material gets a value AOV
  output ("SSSCovN", 1 on that material) for the render; the pixel's index
  is the material with the largest coverage if that is >= 0.5, written into
  the pass file as IndexMA, beside EEVEE's Depth, Diffuse Light/Colour,
  Specular Light/Colour, Emission and Environment (which the library reads
  as DiffDir, DiffCol, GlossDir, GlossCol, Emit, Env). EEVEE needs an
  OpenGL context: without $DISPLAY the script re-runs itself under
  xvfb-run, and skips EEVEE with a message where there is none.

Writes into DIR: sheet.png (contact sheet: one crop and one exposure for
every image, each labelled, with its error heat-map against the reference
below it), results.csv and results.md (one row per image: scene, renderer,
method, samples, render and post-process seconds, RMSE and relative MAE
over the scattering pixels at full and at quarter resolution, SSIM, max
error; metrics in compare_metrics.py), plot.png (error against total time,
log axes, one line per method) and summary.txt (also in results.md): per
sample count, the error reduction of the best and of the default method
against the no-SSS render at the same samples (also both denoised), and
the random-walk sample count reaching the same error, with both times.

The .blend is opened, never saved; the add-on restores what it switches
off. --quick: 160x120, random walk 16/64/256 (reference 256), our methods
on 16 and 64 samples, EEVEE 16 samples.
"""
import argparse
import csv
import math
import os
import shutil
import subprocess
import sys
import time
import traceback

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, ".."))
sys.path.insert(0, os.path.join(ROOT, "addon"))
sys.path.insert(0, HERE)
import separable_sss  # noqa: E402
from separable_sss import blender_compat as compat  # noqa: E402
from separable_sss import description, native  # noqa: E402

import numpy as np  # noqa: E402

import compare_metrics as cm  # noqa: E402
from exr_io import SHORT_PASS_NAMES, read_exr, write_exr  # noqa: E402
from script_cli import run_main, script_argv  # noqa: E402

BACKGROUND = 1e10
REF_SEED_OFFSET = 7919  # reference noise independent of the others'


def log(*a):
    print("compare:", *a, flush=True)


def parse_args():
    argv = script_argv()
    p = argparse.ArgumentParser(prog="compare.py")
    p.add_argument("--scene", required=True, help=".blend to compare on")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--quick", action="store_true")
    p.add_argument("--name", help="scene name in the tables (default: the "
                   "file's name)")
    p.add_argument("--resolution", help="WxH (default 320x240; quick "
                   "160x120)")
    p.add_argument("--rw-samples", help="random-walk sample counts, the "
                   "highest is the reference (default 16,64,256,1024)")
    p.add_argument("--samples", help="sample counts of the SSS-off renders "
                   "(default 16,64,256)")
    p.add_argument("--eevee-samples", type=int)
    p.add_argument("--no-eevee", action="store_true")
    p.add_argument("--no-denoise", action="store_true",
                   help="no OIDN rows (the random walk, SSS off and the "
                   "default method, each denoised)")
    args = p.parse_args(argv)
    q = args.quick

    def ints(text, default):
        return sorted({int(x) for x in (text or default).split(",")})
    args.rw_samples = ints(args.rw_samples, "16,64,256" if q else
                           "16,64,256,1024")
    args.samples = ints(args.samples, "16,64" if q else "16,64,256")
    if len(args.rw_samples) < 2:
        p.error("--rw-samples needs at least two counts")
    args.eevee_samples = args.eevee_samples or (16 if q else 64)
    w, _, h = (args.resolution or ("160x120" if q else "320x240")) \
        .partition("x")
    args.resolution = (int(w), int(h))
    args.scene = os.path.abspath(args.scene)
    args.out = os.path.abspath(args.out)
    args.name = args.name or os.path.splitext(os.path.basename(
        args.scene))[0]
    return args


def maybe_reexec_with_display(args):
    """EEVEE renders need an X display even in background mode."""
    if args.no_eevee or os.environ.get("DISPLAY") or \
            os.environ.get("SSS_COMPARE_XVFB"):
        return
    xvfb = shutil.which("xvfb-run")
    if not xvfb:
        log("no $DISPLAY and no xvfb-run: EEVEE is skipped")
        args.no_eevee = True
        return
    env = dict(os.environ, SSS_COMPARE_XVFB="1")
    cmd = [xvfb, "-a", "-s", "-screen 0 640x480x24",
           compat.blender_command()] + sys.argv[1:]
    log("no $DISPLAY: running again under xvfb-run for EEVEE")
    sys.stdout.flush()
    sys.exit(subprocess.call(cmd, env=env))


# ------------------------------------------- passes (EXR I/O: exr_io.py)

def rgb(ch, name):
    """(h, w, 3) of the first channel set ending in name.R/G/B."""
    for prefix in (f"ViewLayer.{name}", name):
        if f"{prefix}.R" in ch:
            return np.stack([ch[f"{prefix}.{c}"] for c in "RGB"], axis=-1)
    cands = [k for k in ch if k.endswith(f".{name}.R")]
    if not cands:
        raise KeyError(f"no {name} pass (have {sorted(ch)[:12]}...)")
    prefix = cands[0][:-2]
    return np.stack([ch[f"{prefix}.{c}"] for c in "RGB"], axis=-1)


def single(ch, name):
    for k in ch:
        if k.split(".")[-2:-1] == [name]:
            return ch[k]
    raise KeyError(f"no {name} pass")


# ----------------------------------------------------------- the library

def library_methods():
    """[(name, code)] of the library's methods, as the library names them;
    every one is tried on real passes and the library itself decides
    (SSS_ERR_UNSUPPORTED: skipped)."""
    return [(name, code) for code, (name, _) in enumerate(native.methods())]


# --------------------------------------------------------------- scenes

def open_scene(args, engine):
    bpy.ops.wm.open_mainfile(filepath=args.scene)
    scene = bpy.context.scene
    r = scene.render
    r.engine = engine
    r.resolution_x, r.resolution_y = args.resolution
    r.resolution_percentage = 100
    r.use_compositing = False
    r.use_sequencer = False
    if engine == "CYCLES":
        scene.cycles.device = "CPU"
        scene.cycles.use_denoising = False
        # Cycles' default indirect clamp: without it, rare back-lit paths
        # through thin parts are fireflies that dominate every error
        # (the same setting for every Cycles render here).
        scene.cycles.sample_clamp_direct = 0.0
        scene.cycles.sample_clamp_indirect = 10.0
        scene.cycles.use_adaptive_sampling = False
        # Albedo and normal for OIDN (denoise_rows): every Cycles render
        # keeps them, so all pay the same.
        for layer in scene.view_layers:
            layer.cycles.denoising_store_passes = True
    else:
        compat.plain_eevee(scene, args.eevee_samples)
    return scene


def render(scene):
    t0 = time.perf_counter()
    status = bpy.ops.render.render()
    seconds = time.perf_counter() - t0
    if status != {"FINISHED"}:
        raise RuntimeError(f"render failed: {status}")
    return seconds


def save_result(scene, path):
    from separable_sss import pipeline
    pipeline.save_passes(scene, path)
    return read_exr(path)


class Bench:
    """Holds every image and row of one scene."""

    def __init__(self, args):
        self.args = args
        self.work = os.path.join(args.out, "work")
        os.makedirs(self.work, exist_ok=True)
        self.rows = []     # dicts: renderer, method, samples, times, image
        self.mask = None
        self.skipped = []
        self.ref_halves = None
        self.edges = None

    def add(self, renderer, method, samples, render_s, post_s, image,
            io_s=0.0, path=None):
        """A row; path: the EXR it came from (for denoise_rows)."""
        self.rows.append(dict(renderer=renderer, method=method,
                              samples=samples, render_s=render_s,
                              post_s=post_s, io_s=io_s,
                              total_s=render_s + post_s,
                              image=image[:, :, :3].astype(np.float32)))
        if path:
            self.rows[-1]["path"] = path
        log(f"{renderer:>6} {method:<16} {samples:>5} spp  render "
            f"{render_s:7.2f} s  post {post_s:6.3f} s")


def run_rw(bench, args):
    """The random walk at each count; the highest is the reference, the
    mean of two renders of half its samples with two other seeds, so that
    its own noise can be measured (compare_metrics: rmse_c)."""
    scene = open_scene(args, "CYCLES")
    seed = scene.cycles.seed
    for n in args.rw_samples[:-1]:
        scene.cycles.samples = n
        scene.cycles.seed = seed
        seconds = render(scene)
        path = os.path.join(bench.work, f"rw_{n}.exr")
        ch = save_result(scene, path)
        bench.add("cycles", "random-walk", n, seconds, 0.0,
                  rgb(ch, "Combined"), path=path)
    n = args.rw_samples[-1]
    halves, seconds = render_reference(
        scene, n, os.path.join(bench.work, f"rw_{n}"))
    bench.ref_halves = halves
    bench.add("cycles", "random-walk (ref)", n, seconds, 0.0,
              (halves[0] + halves[1]) / 2)


def render_reference(scene, samples, path_stem):
    """The reference: two renders of samples/2 with two seeds other than
    the scene's (saved as path_stem_1.exr, _2.exr), so that its noise is
    independent of the other renders' and measurable from the difference
    of the two. Returns ((half_1, half_2) as RGB arrays, seconds); the
    scene's seed is left as it was."""
    seed = scene.cycles.seed
    halves, seconds = [], 0.0
    try:
        for k in (1, 2):
            scene.cycles.samples = samples // 2
            scene.cycles.seed = seed + k * REF_SEED_OFFSET
            seconds += render(scene)
            ch = save_result(scene, f"{path_stem}_{k}.exr")
            halves.append(rgb(ch, "Combined").astype(np.float32))
    finally:
        scene.cycles.seed = seed
    return tuple(halves), seconds


def render_sss_off(scene, found, passes, description):
    """Render with material SSS switched off (restored afterwards); write
    the passes and the scene description the library reads. Returns the
    render's seconds."""
    from separable_sss import pipeline
    from separable_sss.switch_off import switched_off
    with switched_off(scene, found):
        seconds = render(scene)
        pipeline.save_passes(scene, passes)
        pipeline.write_description(scene, found, description)
    return seconds


def scattering_pixels(ch, found):
    """(mask of the scattering materials' pixels, material index, depth)
    from a pass file."""
    idx = np.rint(single(ch, "IndexMA"))
    depth = single(ch, "Depth")
    mask = np.isin(idx, [f.pass_index for f in found.found]) & (depth < 1e9)
    return mask, idx, depth


def apply_methods(bench, renderer, samples, render_s, inp, desc, base_rgb):
    from separable_sss import native
    bench.add(renderer, "no-sss", samples, render_s, 0.0, base_rgb,
              path=inp)
    with native.Scene(desc) as sc:
        for name, code in bench.methods:
            out = inp.replace("_passes.exr", f"_{name}.exr")
            try:
                t = sc.process(inp, out, method=code)
            except native.LibraryError as e:
                if e.name == "SSS_ERR_UNSUPPORTED":
                    msg = f"method {name} skipped: the library says: {e}"
                elif e.name == "SSS_ERR_INVALID_ARGUMENT" and \
                        name.startswith("method-"):
                    continue
                else:
                    msg = f"method {name} failed: {e.name}: {e}"
                if msg not in bench.skipped:
                    bench.skipped.append(msg)
                    log(msg)
                continue
            ch = read_exr(out)
            bench.add(renderer, name, samples, render_s, t["scatter"],
                      rgb(ch, "SSS.Combined") if "SSS.Combined.R" in ch
                      else rgb(ch, "Combined"), t["read"] + t["write"],
                      path=out)


def run_sss_off(bench, args):
    from separable_sss import pipeline
    scene = open_scene(args, "CYCLES")
    found = pipeline.analyse(scene)
    if not found.found:
        raise RuntimeError("nothing scatters in this scene")
    for n in args.samples:
        scene.cycles.samples = n
        inp = os.path.join(bench.work, f"cycles_{n}_passes.exr")
        desc = os.path.join(bench.work, f"cycles_{n}_scene.json")
        seconds = render_sss_off(scene, found, inp, desc)
        ch = read_exr(inp)
        if n == max(args.samples):
            bench.mask, idx, depth = scattering_pixels(ch, found)
            bench.edges = cm.silhouettes(idx, depth)
        apply_methods(bench, "cycles", n, seconds, inp, desc,
                      rgb(ch, "Combined"))


def _remove_aov(layer, name):
    """ViewLayer.aovs has no remove() in 3.4: the operator removes the
    active one."""
    for i, aov in enumerate(layer.aovs):
        if aov.name == name:
            layer.active_aov_index = i
            with bpy.context.temp_override(view_layer=layer):
                bpy.ops.scene.view_layer_remove_aov()
            return
    raise RuntimeError(f"AOV {name} vanished")


def _eevee_index_aovs(scene, found, undo):
    """A value AOV per scattering material carrying its coverage."""
    layer = bpy.context.view_layer
    for f in found.found:
        name = f"SSSCov{f.pass_index}"
        aov = layer.aovs.add()
        aov.name, aov.type = name, "VALUE"
        undo.add(lambda name=name: _remove_aov(layer, name))
        tree = f.material.node_tree
        node = tree.nodes.new("ShaderNodeOutputAOV")
        compat.set_aov_output(node, name)
        node.label = "SSS compare"
        node.inputs["Value"].default_value = 1.0
        undo.add(lambda tree=tree, node=node: tree.nodes.remove(node))


def eevee_passes_for_library(ch, found):
    """EEVEE's pass file with IndexMA from the coverage AOVs and the
    background's depth (EEVEE writes 65504) moved past background_depth."""
    out = {k: v for k, v in ch.items() if not k.split(".")[-2].startswith(
        "SSSCov")}
    covs = [(f.pass_index, single(ch, f"SSSCov{f.pass_index}"))
            for f in found.found]
    stack = np.stack([c for _, c in covs], axis=0)
    best = np.argmax(stack, axis=0)
    idx = np.array([i for i, _ in covs], dtype=np.float32)[best]
    idx[np.max(stack, axis=0) < 0.5] = 0.0
    out["ViewLayer.IndexMA.X"] = idx
    depth_key = next(k for k in ch if k.split(".")[-2] == "Depth")
    depth = ch[depth_key].copy()
    depth[(depth >= 65504) | ~np.isfinite(depth)] = BACKGROUND
    out[depth_key] = depth
    return out


def run_eevee(bench, args):
    from separable_sss import pipeline
    from separable_sss.switch_off import switched_off
    n = args.eevee_samples
    scene = open_scene(args, compat.EEVEE)
    seconds = render(scene)
    ch = save_result(scene, os.path.join(bench.work, f"eevee_{n}_own.exr"))
    bench.add("eevee", "eevee-sss", n, seconds, 0.0, rgb(ch, "Combined"))

    scene = open_scene(args, compat.EEVEE)
    found = pipeline.analyse(scene)
    raw = os.path.join(bench.work, f"eevee_{n}_raw.exr")
    inp = os.path.join(bench.work, f"eevee_{n}_passes.exr")
    desc = os.path.join(bench.work, f"eevee_{n}_scene.json")
    with switched_off(scene, found) as undo:
        _eevee_index_aovs(scene, found, undo)
        seconds = render(scene)
        pipeline.save_passes(scene, raw)
        pipeline.write_description(scene, found, desc)
    ch = read_exr(raw)
    write_exr(inp, eevee_passes_for_library(ch, found))
    apply_methods(bench, "eevee", n, seconds, inp, desc, rgb(ch, "Combined"))


# --------------------------------------------------------------- results

# ----------------------------------------------------------- denoising

DENOISED = "+oidn"   # method suffix of a denoised row


def denoise_jobs(bench):
    """(source row, EXR, whether its image is our SSS layer) for each
    image an artist would denoise: the random walk's (not the reference),
    SSS off and the default method, at every sample count."""
    ours = {"random-walk": False, "no-sss": False,
            bench.default_method: True}
    return [(r, r["path"], ours[r["method"]]) for r in bench.rows
            if r["renderer"] == "cycles" and "path" in r and
            r["method"] in ours]


# Blender 5.0's Image node sockets carry the full pass names.
FULL_PASS_NAMES = {short: full for full, short in SHORT_PASS_NAMES.items()}


class Denoiser:
    """Blender's compositor Denoise node (OIDN, with the render's albedo
    and normal) on one pass of an EXR, in a compositor-only render (no
    Render Layers node: Blender composites without rendering the scene
    again)."""

    def __init__(self, args):
        scene = open_scene(args, "CYCLES")
        self.scene = scene
        self.layer = bpy.context.view_layer.name     # the render's passes
        tree = compat.compositor_tree(scene, create=True)
        for node in list(tree.nodes):
            tree.nodes.remove(node)
        self.tree = tree
        self.out = compat.composite_input(tree, create=True)
        self.image_node = tree.nodes.new("CompositorNodeImage")
        self.aux_node = tree.nodes.new("CompositorNodeImage")
        self.denoise = tree.nodes.new("CompositorNodeDenoise")
        tree.links.new(self.denoise.outputs[0], self.out)
        scene.render.use_compositing = True

    def __call__(self, path, layer, name):
        """(denoised RGB of layer.name in path, seconds)."""
        tree, image_node, aux_node = self.tree, self.image_node, self.aux_node
        image = bpy.data.images.load(path, check_existing=False)
        image_node.image = aux_node.image = image
        image_node.layer = layer
        aux_node.layer = self.layer
        full = FULL_PASS_NAMES.get(name, name)
        socket = image_node.outputs.get(name) or image_node.outputs[full]
        tree.links.new(socket, self.denoise.inputs["Image"])
        tree.links.new(aux_node.outputs["Denoising Normal"],
                       self.denoise.inputs["Normal"])
        tree.links.new(aux_node.outputs["Denoising Albedo"],
                       self.denoise.inputs["Albedo"])
        seconds = render(self.scene)
        result = save_result(self.scene, path.replace(".exr", "_oidn.exr"))
        bpy.data.images.remove(image)
        return rgb(result, "Composite.Combined"), seconds


def denoise_rows(bench, args):
    """Adds a denoised row per job (denoise_jobs): its render time, post =
    its post-process plus the denoise; then the default method on passes
    denoised before the blur (denoise_passes_rows)."""
    jobs = denoise_jobs(bench)
    if not jobs:
        return
    denoiser = Denoiser(args)
    for row, path, is_ours in jobs:
        img, seconds = denoiser(path, "SSS" if is_ours else denoiser.layer,
                                "Combined")
        if np.array_equal(img, row["image"]):
            msg = ("OIDN rows skipped: this Blender's Denoise node leaves "
                   "the image as it is (built without OpenImageDenoise)")
            bench.skipped.append(msg)
            log(msg)
            return
        bench.add(row["renderer"], row["method"] + DENOISED, row["samples"],
                  row["render_s"], row["post_s"] + seconds, img,
                  row["io_s"])
    denoise_passes_rows(bench, denoiser)


LIGHT_PASSES = ("DiffDir", "DiffInd", "GlossDir", "GlossInd", "TransDir",
                "TransInd")
DENOISED_PASSES = "+oidn-passes"   # the light passes denoised, then SSS


def denoise_passes_rows(bench, denoiser):
    """The other order: every light pass of the SSS-off render denoised
    (each by the Denoise node with the render's albedo and normal), then
    the default method scatters and recombines them."""
    from separable_sss import native
    code = dict(bench.methods)[bench.default_method]
    layer = denoiser.layer
    for row in [r for r in bench.rows if r["renderer"] == "cycles" and
                r["method"] == "no-sss" and "path" in r]:
        inp = row["path"]
        ch = read_exr(inp)
        seconds = 0.0
        for name in LIGHT_PASSES:
            if f"{layer}.{name}.R" not in ch:
                continue
            img, s = denoiser(inp, layer, name)
            seconds += s
            for i, c in enumerate("RGB"):
                ch[f"{layer}.{name}.{c}"] = img[:, :, i]
        merged = inp.replace("_passes.exr", "_oidnpasses_passes.exr")
        write_exr(merged, ch)
        out = merged.replace("_passes.exr", f"_{bench.default_method}.exr")
        with native.Scene(inp.replace("_passes.exr", "_scene.json")) as sc:
            t = sc.process(merged, out, method=code)
        bench.add("cycles", bench.default_method + DENOISED_PASSES,
                  row["samples"], row["render_s"], seconds + t["scatter"],
                  rgb(read_exr(out), "SSS.Combined"), t["read"] + t["write"])


COLUMNS = ("scene", "renderer", "method", "samples", "render_s", "post_s",
           "io_s", "total_s", "rmse", "rel_mae", "rmse_q", "rel_mae_q",
           "rmse_c", "rmse_q_c", "rmse_in_c", "ssim", "max_err")


def cut(after, before):
    """% less error after than before."""
    return 100 * (1 - after / before) if before > 0 else float("nan")


def err(r, key):
    """r's error `key` ("rmse" or "rmse_q") against the noise-free image
    the reference estimates where measured, else against the reference."""
    c = r.get(key + "_c", float("nan"))
    return c if math.isfinite(c) else r[key]


def score(bench, args):
    ref = next(r for r in bench.rows if r["method"].endswith("(ref)"))
    mask = bench.mask
    bench.exposure = cm.exposure_for(ref["image"], mask)
    for r in bench.rows:
        r.update(cm.all_metrics(r["image"], ref["image"], mask,
                                bench.exposure, bench.ref_halves,
                                bench.edges))
        r["scene"] = args.name
    return ref


def fmt(v, col):
    if isinstance(v, float):
        if col.endswith("_s"):
            return f"{v:.3f}"
        return f"{v:.5g}"
    return str(v)


def write_tables(bench, args, summary):
    with open(os.path.join(args.out, "results.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(COLUMNS)
        for r in bench.rows:
            w.writerow([fmt(r[c], c) for c in COLUMNS])
    lines = [f"# SSS comparison: {args.name}", "",
             f"Scene `{args.scene}`, {args.resolution[0]}x"
             f"{args.resolution[1]}, reference: Cycles random walk at "
             f"{max(args.rw_samples)} samples (two renders of half as "
             "many with two other seeds, averaged). Errors over "
             f"the {int(bench.mask.sum())} scattering pixels, linear "
             "light; `_q`: at quarter resolution (4x4 boxes); `_c`: against "
             "the noise-free image the reference estimates (its own noise, "
             "measured from the difference of its halves, removed; the "
             "summary uses these); `rmse_in_c`: `rmse_c` away from "
             "silhouettes (pixels next to another material or a depth "
             "step). Times in "
             "seconds, measured in this run; post = the library's scatter "
             "time (io = its EXR read + write, not counted in total).", "",
             "| " + " | ".join(COLUMNS) + " |",
             "|" + "---|" * len(COLUMNS)]
    for r in bench.rows:
        lines.append("| " + " | ".join(fmt(r[c], c) for c in COLUMNS) +
                     " |")
    if bench.skipped:
        lines += ["", "Skipped: " + "; ".join(bench.skipped)]
    lines += ["", "## Summary", "", "```", *summary, "```", "",
              "![contact sheet](sheet.png)", "", "![error against time]"
              "(plot.png)", ""]
    with open(os.path.join(args.out, "results.md"), "w") as f:
        f.write("\n".join(lines))
    with open(os.path.join(args.out, "summary.txt"), "w") as f:
        f.write("\n".join(summary) + "\n")


def summarise(bench, args):
    rows = bench.rows
    rw = sorted((r for r in rows if r["method"] == "random-walk"),
                key=lambda r: r["samples"])
    rw_all = sorted((r for r in rows if r["renderer"] == "cycles" and
                     r["method"].startswith("random-walk")),
                    key=lambda r: r["samples"])
    ours = [m for m, _ in bench.methods]
    default = bench.default_method
    out = [f"scene {args.name}: error = RMSE over scattering pixels vs "
           f"random walk {max(args.rw_samples)} spp"
           + (" with its own noise removed (rmse_c)" if bench.ref_halves
              else "") + f"; default method {default}"]
    for renderer, counts in (("cycles", args.samples),
                             ("eevee", [args.eevee_samples])):
        for n in counts:
            base = next((r for r in rows if r["renderer"] == renderer and
                         r["method"] == "no-sss" and r["samples"] == n),
                        None)
            if base is None:
                continue
            cands = [r for r in rows if r["renderer"] == renderer and
                     r["samples"] == n and r["method"] in ours]
            if not cands:
                continue
            best = min(cands, key=lambda r: err(r, "rmse"))
            dflt = next((r for r in cands if r["method"] == default), best)
            out.append(f"  {renderer} {n} spp: no-sss RMSE "
                       f"{err(base, 'rmse'):.4g} ({base['total_s']:.2f} s)")
            ceiling = noise_ceiling(rows, base)
            if ceiling:
                out.append(f"    {ceiling}")
            for label, r in (("default", dflt), ("best", best)):
                red = cut(err(r, "rmse"), err(base, "rmse"))
                s, how = cm.interp_samples([x["samples"] for x in rw],
                                           [err(x, "rmse") for x in rw],
                                           err(r, "rmse"))
                t_rw = cm.time_at([x["samples"] for x in rw_all],
                                  [x["render_s"] for x in rw_all], s) \
                    if math.isfinite(s) else float("nan")
                out.append(
                    f"    {label:<7} {r['method']:<16} RMSE "
                    f"{err(r, 'rmse'):.4g}: {red:.1f} % less error than no-sss; "
                    f"random walk reaches it at ~{s:.0f} spp ({how}) "
                    f"in ~{t_rw:.2f} s; ours {r['total_s']:.2f} s "
                    f"(render {r['render_s']:.2f} + post "
                    f"{r['post_s']:.3f})")
                # At quarter resolution noise averages away, bias stays.
                sq, howq = cm.interp_samples([x["samples"] for x in rw],
                                             [err(x, "rmse_q") for x in rw],
                                             err(r, "rmse_q"))
                redq = cut(err(r, "rmse_q"), err(base, "rmse_q"))
                out.append(
                    f"      quarter res: RMSE {err(r, 'rmse_q'):.4g} vs no-sss "
                    f"{err(base, 'rmse_q'):.4g} ({redq:.1f} % less); random walk "
                    f"reaches it at ~{sq:.0f} spp ({howq})")
                if math.isfinite(r["rmse_in_c"]) and \
                        math.isfinite(base["rmse_in_c"]):
                    share = 100 * (bench.mask & ~bench.edges).sum() / \
                        bench.mask.sum()
                    out.append(
                        f"      away from silhouettes ({share:.0f} % of the "
                        f"pixels): RMSE {r['rmse_in_c']:.4g} vs no-sss "
                        f"{base['rmse_in_c']:.4g} ("
                        f"{cut(r['rmse_in_c'], base['rmse_in_c']):.1f} % less)")
            if renderer == "cycles":
                out += oidn_lines(rows, n, default)
    out += goal_lines(rows, default)
    for r in rows:
        if r["method"] == "eevee-sss":
            out.append(f"  eevee own SSS {r['samples']} spp: RMSE "
                       f"{err(r, 'rmse'):.4g} in {r['total_s']:.2f} s")
    return out


def oidn_lines(rows, n, default):
    """The default method and SSS off, both denoised (OIDN), and the random
    walk denoised at the same samples."""
    def row(method):
        return next((r for r in rows if r["renderer"] == "cycles" and
                     r["method"] == method and r["samples"] == n), None)
    base, ours = row("no-sss" + DENOISED), row(default + DENOISED)
    if not (base and ours):
        return []
    rw = row("random-walk" + DENOISED)
    lines = [f"    with OIDN on both: {default}{DENOISED} RMSE "
             f"{err(ours, 'rmse'):.4g} vs no-sss{DENOISED} "
             f"{err(base, 'rmse'):.4g}: "
             f"{cut(err(ours, 'rmse'), err(base, 'rmse')):.1f} % less error"
             + (f"; random-walk{DENOISED} at {n} spp: RMSE "
                f"{err(rw, 'rmse'):.4g}" if rw else "")]
    passes = row(default + DENOISED_PASSES)
    if passes:
        lines.append(f"    light passes denoised before the blur: "
                     f"{default}{DENOISED_PASSES} RMSE "
                     f"{err(passes, 'rmse'):.4g} "
                     f"({cut(err(passes, 'rmse'), err(base, 'rmse')):.1f} % "
                     f"less error than no-sss{DENOISED})")
    return lines


def noise_ceiling(rows, base):
    """What the render's own noise leaves to win at base's sample count:
    its RMSE (compare_metrics.render_noise, from the no-sss errors at this
    and the next count) and the error reduction of a post-process with no
    bias at all that left that noise as it is. Scattering blurs only the
    diffuse light, so the noise of every other pass stays in the result;
    a blur also lowers the diffuse noise, which can take a method a little
    past this."""
    more = sorted((r for r in rows if r["renderer"] == base["renderer"] and
                   r["method"] == "no-sss" and
                   r["samples"] > base["samples"]),
                  key=lambda r: r["samples"])
    if not more:
        return ""
    noise = cm.render_noise(err(base, "rmse"), base["samples"],
                            err(more[0], "rmse"), more[0]["samples"])
    if not math.isfinite(noise):
        return ""
    head = (f"the render's own noise is {noise:.4g} RMSE here (from the "
            f"no-sss errors at {base['samples']} and {more[0]['samples']} "
            "spp)")
    if noise >= 0.95 * err(base, "rmse"):
        return (f"{head}: about all of its error; only blurring its diffuse "
                "noise can lower it")
    return (f"{head}: with no bias left and that noise as it is, a "
            f"post-process would have {cut(noise, err(base, 'rmse')):.1f} % "
            "less error (blurring the diffuse noise adds a little)")


GOAL_CUT = 30.0        # % less error than the render without SSS ...
GOAL_TIME_SHARE = 0.05  # ... in at most this share of the reference's time


def goal_lines(rows, default):
    """The product's accuracy goal, judged on the most samples whose render
    plus post-process stays within GOAL_TIME_SHARE of the reference's
    render time (Cycles rows)."""
    ref = next(r for r in rows if r["method"].endswith("(ref)"))
    budget = GOAL_TIME_SHARE * ref["render_s"]
    ours = [r for r in rows if r["renderer"] == "cycles" and
            r["method"] == default and r["total_s"] <= budget]
    head = (f"  goal: {GOAL_CUT:.0f} % less error than no-sss within "
            f"{100 * GOAL_TIME_SHARE:.0f} % of the reference's "
            f"{ref['render_s']:.1f} s")
    if not ours:
        return [f"{head}: no render with material SSS off fits in "
                f"{budget:.2f} s; measure with more reference samples"]
    r = max(ours, key=lambda r: r["samples"])
    base = next(x for x in rows if x["renderer"] == "cycles" and
                x["method"] == "no-sss" and x["samples"] == r["samples"])
    full, full_q = cut(err(r, "rmse"), err(base, "rmse")), \
        cut(err(r, "rmse_q"), err(base, "rmse_q"))
    raw, raw_q = cut(r["rmse"], base["rmse"]), cut(r["rmse_q"], base["rmse_q"])
    inner = cut(r["rmse_in_c"], base["rmse_in_c"])
    ceiling = noise_ceiling(rows, base)
    return [f"{head}: {'met' if full >= GOAL_CUT else 'missed'} at "
            f"{r['samples']} spp ({100 * r['total_s'] / ref['render_s']:.1f}"
            f" % of it): {full:.1f} % less at full resolution, {full_q:.1f} "
            f"% at quarter resolution, {inner:.1f} % away from silhouettes "
            f"(against the reference itself, with its noise: {raw:.1f} % and "
            f"{raw_q:.1f} %)"] + \
        ([f"    {ceiling}"] if ceiling else [])


def crop_box(mask, pad=0.12):
    ys, xs = np.nonzero(mask)
    h, w = mask.shape
    y0, y1, x0, x1 = ys.min(), ys.max() + 1, xs.min(), xs.max() + 1
    py, px = int((y1 - y0) * pad) + 2, int((x1 - x0) * pad) + 2
    return (max(0, y0 - py), min(h, y1 + py), max(0, x0 - px),
            min(w, x1 + px))


def groups(bench):
    """Rows of the sheet: random walk, then each (renderer, samples)."""
    out = [("Cycles random walk", [r for r in bench.rows
                                   if r["method"].startswith("random")])]
    seen = []
    for r in bench.rows:
        key = (r["renderer"], r["samples"])
        if r["method"].startswith("random") or key in seen:
            continue
        seen.append(key)
        label = f"Cycles SSS off {key[1]} spp" if key[0] == "cycles" else \
            f"EEVEE {key[1]} spp"
        out.append((label, [x for x in bench.rows if
                            (x["renderer"], x["samples"]) == key and not
                            x["method"].startswith("random")]))
    return out


def contact_sheet(bench, args, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    y0, y1, x0, x1 = crop_box(bench.mask)
    rows = groups(bench)
    ncol = max(len(g) for _, g in rows)
    aspect = (y1 - y0) / max(1, x1 - x0)
    cw = 2.3
    fig, axes = plt.subplots(2 * len(rows), ncol, squeeze=False,
                             figsize=(cw * ncol + 0.8, 2 * len(rows) *
                                      (cw * aspect + 0.4) + 0.5),
                             layout="constrained")
    ref = next(r for r in bench.rows if r["method"].endswith("(ref)"))
    heat_max = 0.25
    im = None
    for gi, (label, items) in enumerate(rows):
        for ci in range(ncol):
            a, b = axes[2 * gi, ci], axes[2 * gi + 1, ci]
            a.axis("off")
            b.axis("off")
            if ci >= len(items):
                continue
            r = items[ci]
            img = r["image"][y0:y1, x0:x1] * bench.exposure
            a.imshow(np.clip(img, 0, 1) ** (1 / 2.2), interpolation="nearest")
            a.set_title(f"{label}\n{r['method']}  "
                        f"{r['total_s']:.1f} s", fontsize=7)
            err = np.abs(r["image"] - ref["image"]).mean(axis=2)[y0:y1,
                                                               x0:x1]
            im = b.imshow(err * bench.exposure, cmap="inferno", vmin=0,
                          vmax=heat_max, interpolation="nearest")
            b.set_title(f"|error| RMSE {r['rmse']:.3g} SSIM "
                        f"{r['ssim']:.3f}", fontsize=6.5)
    fig.suptitle(f"{args.name}: same crop and exposure for every image\n"
                 f"heat maps: mean |error| per pixel vs random walk "
                 f"{ref['samples']} spp (x exposure, 0 to {heat_max})",
                 fontsize=8)
    if im is not None:
        fig.colorbar(im, ax=axes.ravel().tolist(), fraction=0.02,
                     shrink=0.5)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot(bench, args, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    series = {}
    for r in bench.rows:
        if r["method"].endswith("(ref)"):
            continue
        series.setdefault((r["renderer"], r["method"]), []).append(r)
    for ax, key, title in ((axes[0], "rmse", "RMSE, full resolution"),
                           (axes[1], "rmse_q", "RMSE, quarter resolution")):
        title += " (reference noise removed)" if bench.ref_halves else ""
        for (renderer, method), rs in series.items():
            rs = sorted(rs, key=lambda r: r["total_s"])
            t = [r["total_s"] for r in rs]
            e = [max(err(r, key), 1e-6) for r in rs]
            style = "o-" if renderer == "cycles" else "s--"
            ax.plot(t, e, style, label=f"{renderer} {method}")
            for r in rs:
                ax.annotate(str(r["samples"]), (r["total_s"],
                                                max(err(r, key), 1e-6)),
                            fontsize=6, xytext=(3, 3),
                            textcoords="offset points")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("total time, s (render + SSS post-process)")
        ax.set_ylabel("error vs reference")
        ax.set_title(f"{args.name}: {title}")
        ax.grid(True, which="both", alpha=0.3)
    axes[1].legend(fontsize=7, loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ------------------------------------------------------------------ main

def main():
    args = parse_args()
    maybe_reexec_with_display(args)
    os.environ.setdefault("SSS_LIB", os.path.join(ROOT, "build",
                                                  "libsss.so"))
    separable_sss.register()
    log(f"{args.name}: libsss {native.version()}, {args.resolution[0]}x"
        f"{args.resolution[1]}, random walk {args.rw_samples}, SSS off "
        f"{args.samples}, EEVEE "
        f"{'off' if args.no_eevee else args.eevee_samples}")
    t_start = time.perf_counter()
    bench = Bench(args)
    bench.methods = library_methods()
    scene = open_scene(args, "CYCLES")
    bench.default_method = description.method_name(scene.sss.method)
    run_rw(bench, args)
    run_sss_off(bench, args)
    if not args.no_denoise:
        denoise_rows(bench, args)
    if not args.no_eevee:
        try:
            run_eevee(bench, args)
        except Exception as e:  # keep the Cycles results
            traceback.print_exc()
            bench.skipped.append(f"EEVEE failed: {e}")
            log(f"EEVEE failed: {e}")
    score(bench, args)
    summary = summarise(bench, args)
    contact_sheet(bench, args, os.path.join(args.out, "sheet.png"))
    plot(bench, args, os.path.join(args.out, "plot.png"))
    write_tables(bench, args, summary)
    for line in summary:
        print(line)
    log(f"wrote {args.out}/results.csv, results.md, sheet.png, plot.png "
        f"({time.perf_counter() - t_start:.0f} s)")
    if os.environ.get("SSS_COMPARE_KEEP_WORK") != "1":
        shutil.rmtree(bench.work, ignore_errors=True)
    separable_sss.unregister()


if __name__ == "__main__":
    run_main(main)
