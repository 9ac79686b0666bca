"""scripts/side_by_side.py (make demo's picture) shows the render's own
layer on the left, never the back-light layer the add-on adds for
transmission, and SSS.Combined on the right."""
import subprocess
import sys

import numpy as np
import OpenImageIO as oiio

from conftest import ROOT


def test_left_is_the_render_layer(tmp_path):
    w, h = 6, 4
    chans, planes = [], []

    def add(layer, pass_, value, comps="RGB"):
        for c in comps:
            chans.append(f"{layer}.{pass_}.{c}")
            planes.append(np.full((h, w), value, np.float32))

    # Sorted before ViewLayer, as Blender writes it.
    add("SSSBackLight", "DiffDir", 0.9)
    add("SSSBackLight", "Combined", 0.9, "RGBA")
    add("ViewLayer", "DiffDir", 0.2)
    add("ViewLayer", "Combined", 0.2, "RGBA")
    add("SSS", "Combined", 0.5, "RGBA")
    src = tmp_path / "in.exr"
    spec = oiio.ImageSpec(w, h, len(chans), "float")
    spec.channelnames = tuple(chans)
    out = oiio.ImageOutput.create(str(src))
    assert out.open(str(src), spec)
    assert out.write_image(np.stack(planes, axis=-1))
    out.close()

    png = tmp_path / "out.png"
    subprocess.run([sys.executable, str(ROOT / "scripts" / "side_by_side.py"),
                    str(src), str(png)], check=True)
    img = oiio.ImageInput.open(str(png))
    pixels = img.read_image(oiio.FLOAT)
    img.close()
    srgb = lambda x: 1.055 * x ** (1 / 2.4) - 0.055
    assert abs(pixels[0, 0, 0] - srgb(0.2)) < 2 / 255   # ViewLayer, not 0.9
    assert abs(pixels[0, -1, 0] - srgb(0.5)) < 2 / 255  # SSS.Combined
