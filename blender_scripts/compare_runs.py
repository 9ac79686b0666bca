"""The runs of make compare (compare.py): every render and every library
run, each timed on the same machine in one process, collected in a Bench.
Cycles' random walk (and its two-seed reference), Cycles with material SSS
switched off plus each of the library's methods, EEVEE with and without
its own SSS, and OIDN on each of them."""
import os
import sys
import time

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, ".."))
sys.path.insert(0, os.path.join(ROOT, "addon"))
sys.path.insert(0, HERE)
from separable_sss import blender_compat as compat  # noqa: E402
from separable_sss import native, pipeline  # noqa: E402
from separable_sss.switch_off import switched_off  # noqa: E402

import numpy as np  # noqa: E402

import compare_metrics as cm  # noqa: E402
from exr_io import (SHORT_PASS_NAMES, read_exr, rgb, single,  # noqa: E402
                    write_exr)


BACKGROUND = 1e10


REF_SEED_OFFSET = 7919  # reference noise independent of the others'


def log(*a):
    print("compare:", *a, flush=True)


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
        self.mesh_notes = []  # mesh_check.notes: where the walk differs
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
    mask = np.isin(idx, [f.pass_index for f in found.materials]) & (depth < 1e9)
    return mask, idx, depth


def apply_methods(bench, renderer, samples, render_s, inp, desc, base_rgb):
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
    scene = open_scene(args, "CYCLES")
    found = pipeline.analyse(scene)
    if not found.materials:
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
    for f in found.materials:
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


# The light passes the library recombines: (light passes, colour pass)
# products, then the passes it adds as they are (sss_apply.c).
PRODUCTS = ((("DiffDir", "DiffInd"), "DiffCol"),
            (("GlossDir", "GlossInd"), "GlossCol"),
            (("TransDir", "TransInd"), "TransCol"))
PLAIN = ("Emit", "Env")


def recombined(ch, layer):
    """What the library makes of a layer's passes without scattering: the
    sum of light x colour and of the plain passes, (h, w, 3)."""
    def get(name):
        return rgb(ch, f"{layer}.{name}") if f"{layer}.{name}.R" in ch \
            else None
    total = np.zeros(rgb(ch, f"{layer}.Combined").shape, np.float64)
    for lights, colour in PRODUCTS:
        col = get(colour)
        for name in lights:
            light = get(name)
            if light is not None and col is not None:
                total += light.astype(np.float64) * col
    for name in PLAIN:
        a = get(name)
        if a is not None:
            total += a
    return total


def eevee_residual_into_emit(out, layer):
    """EEVEE averages each pass over its samples separately, so at a pixel
    whose samples differ (an anti-aliased silhouette: light and colour
    each times the coverage f, their product f^2 where Combined has f; a
    texture or a highlight that changes within the pixel) the product of
    the averages is not the average of the products: on the bundled
    marble, 0.095 RMSE between the recombined passes and Combined, 78 %
    of it on the 7 % of pixels at a silhouette, where the recombined
    glossy light is half of Combined's. Cycles' light passes are divided
    by their colour pass after accumulation and recombine exactly. What
    the passes miss (Combined minus their recombination) is added to the
    Emit pass, which the library adds as it is: without scattering the
    library then returns EEVEE's Combined, and scattering changes only the
    diffuse light."""
    comb = rgb(out, f"{layer}.Combined")
    residual = comb - recombined(out, layer)
    for i, c in enumerate("RGB"):
        key = f"{layer}.Emit.{c}"
        out[key] = (out.get(key, 0.0) + residual[:, :, i]).astype(np.float32)
    return out


def eevee_passes_for_library(ch, found):
    """EEVEE's pass file with IndexMA from the coverage AOVs, the
    background's depth (EEVEE writes 65504) moved past background_depth,
    and what its light passes do not hold put into Emit
    (eevee_residual_into_emit)."""
    out = {k: v for k, v in ch.items() if not k.split(".")[-2].startswith(
        "SSSCov")}
    covs = [(f.pass_index, single(ch, f"SSSCov{f.pass_index}"))
            for f in found.materials]
    stack = np.stack([c for _, c in covs], axis=0)
    best = np.argmax(stack, axis=0)
    idx = np.array([i for i, _ in covs], dtype=np.float32)[best]
    idx[np.max(stack, axis=0) < 0.5] = 0.0
    out["ViewLayer.IndexMA.X"] = idx
    depth_key = next(k for k in ch if k.split(".")[-2] == "Depth")
    depth = ch[depth_key].copy()
    depth[(depth >= 65504) | ~np.isfinite(depth)] = BACKGROUND
    out[depth_key] = depth
    return eevee_residual_into_emit(out, depth_key.rsplit(".", 2)[0])


def run_eevee(bench, args):
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
        """(denoised RGB of layer.name in path, seconds); the result is
        kept beside path as PATH_oidn.exr (Combined) or PATH_oidn_NAME.exr
        (a light pass), so that a pass does not overwrite the image."""
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
        suffix = "_oidn" if name == "Combined" else f"_oidn_{name}"
        result = save_result(self.scene, path.replace(".exr",
                                                      suffix + ".exr"))
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
