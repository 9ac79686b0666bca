"""Time Blender's compositor Bilateral Blur node on an image, for comparison
with the separable blur (make bench).

    blender -b --factory-startup --python-exit-code 1 \
        --python bench/blender_bilateral.py -- --light L.exr --depth D.exr \
        --sigma-space PX [--repeat N]

Prints one line: "bilateral_seconds=S baseline_seconds=B" where S is the
best render time of Image -> Bilateral Blur (determinator: depth) ->
Composite, and B that of Image -> Composite alone (loading, conversion and
the output), so S - B is the node's own cost. The scene has no Render
Layers node, so Blender runs the compositor without rendering.
"""
import argparse
import os
import sys
import time

import bpy

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__))), "addon"))
from separable_sss import blender_compat as compat  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="blender_bilateral.py")
    p.add_argument("--light", required=True)
    p.add_argument("--depth", required=True)
    p.add_argument("--sigma-space", type=float, default=16.0)
    p.add_argument("--sigma-color", type=float, default=0.3)
    p.add_argument("--repeat", type=int, default=2)
    return p.parse_args(argv)


def best_render(scene, repeat):
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        bpy.ops.render.render(write_still=False)
        best = min(best, time.perf_counter() - t0)
    return best


def main():
    args = parse_args()
    scene = bpy.context.scene
    light = bpy.data.images.load(args.light)
    depth = bpy.data.images.load(args.depth)
    scene.render.resolution_x, scene.render.resolution_y = light.size
    scene.render.resolution_percentage = 100
    scene.render.use_compositing = True
    scene.render.use_sequencer = False
    tree = compat.compositor_tree(scene, create=True)
    tree.nodes.clear()
    src = tree.nodes.new("CompositorNodeImage")
    src.image = light
    det = tree.nodes.new("CompositorNodeImage")
    det.image = depth
    out = compat.composite_input(tree)  # Composite, or 5.0's group output

    tree.links.new(src.outputs["Image"], out)
    baseline = best_render(scene, args.repeat)

    blur = tree.nodes.new("CompositorNodeBilateralblur")
    compat.set_bilateral(blur, args.sigma_space, args.sigma_color)
    tree.links.new(src.outputs["Image"], blur.inputs["Image"])
    tree.links.new(det.outputs["Image"], blur.inputs["Determinator"])
    tree.links.new(blur.outputs["Image"], out)
    bilateral = best_render(scene, args.repeat)
    print(f"bilateral_seconds={bilateral:.4f} baseline_seconds={baseline:.4f}")


main()
