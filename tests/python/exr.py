"""Reading and writing EXR channels by name with OpenImageIO (test side:
an implementation independent of the one under test)."""
import os
import sys

import numpy as np
import OpenImageIO as oiio

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                "..", "..", "blender_scripts"))
from exr_io import read_exr_parts  # noqa: E402


def read_channels(path):
    """{channel name: float32 (h, w) array} over every part, Blender 5.0's
    full pass names under the short ones; and the first part's spec."""
    return read_exr_parts(path)


def read_raw(path):
    """{channel name: array in the file's own type} for bit-exact checks."""
    inp = oiio.ImageInput.open(str(path))
    spec = inp.spec()
    out = {}
    for i, name in enumerate(spec.channelnames):
        fmt = spec.channelformat(i)
        data = inp.read_image(0, 0, i, i + 1, fmt)
        out[name] = np.array(data).reshape(spec.height, spec.width)
    inp.close()
    return out


def write_channels(path, channels, width, height, half=(), attributes=None):
    """Writes {name: (h, w) array} as one EXR (names as given), with extra
    string header attributes {name: value}."""
    names = list(channels)
    spec = oiio.ImageSpec(width, height, len(names), oiio.FLOAT)
    spec.channelnames = names
    spec.channelformats = [oiio.HALF if n in half else oiio.FLOAT
                           for n in names]
    spec.attribute("compression", "zip")
    for key, value in (attributes or {}).items():
        spec.attribute(key, value)
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec), out.geterror()
    data = np.stack([channels[n] for n in names], axis=-1).astype(np.float32)
    assert out.write_image(data), out.geterror()
    out.close()


def read_png(path):
    """An 8- or 16-bit image's RGB as stored, in [0, 1] (float32)."""
    buf = oiio.ImageBuf(str(path))
    assert not buf.has_error, buf.geterror()
    return buf.get_pixels(oiio.FLOAT)[:, :, :3]


def pass_rgb(channels, prefix):
    """(h, w, 3) array of prefix.R/G/B."""
    return np.stack([channels[f"{prefix}.{c}"] for c in "RGB"], axis=-1)
