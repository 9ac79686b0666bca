"""Writes a PNG with the render without and with SSS side by side, from an
EXR that holds both (a Blender layer's Combined and SSS.Combined).

    /usr/bin/python3 scripts/side_by_side.py RESULT.exr OUT.png [LAYER]
"""
import os
import sys

import numpy as np
import OpenImageIO as oiio

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                "..", "blender_scripts"))
from exr_io import read_exr_parts  # noqa: E402  (5.0 names, every part)


def srgb(linear):
    x = np.clip(linear, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x,
                    1.055 * np.power(x, 1 / 2.4) - 0.055)


def main():
    src, dst = sys.argv[1], sys.argv[2]
    try:
        channels, spec = read_exr_parts(src)
    except RuntimeError as e:
        sys.exit(f"side_by_side: {e}")
    names = list(channels)
    # The render's own layer: not our SSS output, and not the back-light
    # layer the add-on renders for transmission (SSSBackLight).
    layer = sys.argv[3] if len(sys.argv) > 3 else next(
        (n.split(".")[0] for n in names
         if n.endswith(".DiffDir.R") and n.split(".")[0] not in
         ("SSS", "SSSBackLight")), None)
    if layer is None or "SSS.Combined.R" not in channels:
        sys.exit(f"side_by_side: {src}: needs a view layer's passes and "
                 "the SSS layer (the output of the add-on or of sss)")

    def rgb(prefix):
        return np.stack([channels[f"{prefix}.{c}"] for c in "RGB"], axis=-1)

    before, after = rgb(f"{layer}.Combined"), rgb("SSS.Combined")
    gap = np.ones((spec.height, 8, 3), np.float32)
    image = np.concatenate([srgb(before), gap, srgb(after)], axis=1)
    out = oiio.ImageOutput.create(dst)
    tmp = dst + ".tmp.png"
    ospec = oiio.ImageSpec(image.shape[1], image.shape[0], 3, oiio.UINT8)
    if not out.open(tmp, ospec) or not out.write_image(
            (image * 255 + 0.5).astype(np.uint8)):
        sys.exit(f"side_by_side: {dst}: {out.geterror()}")
    out.close()
    os.replace(tmp, dst)


main()
