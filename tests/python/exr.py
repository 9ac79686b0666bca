"""Reading and writing EXR channels by name with OpenImageIO (test side:
an implementation independent of the one under test)."""
import numpy as np
import OpenImageIO as oiio


def read_channels(path):
    """{channel name: float32 (h, w) array} of the first subimage."""
    inp = oiio.ImageInput.open(str(path))
    assert inp, oiio.geterror()
    spec = inp.spec()
    pixels = inp.read_image(oiio.FLOAT)
    inp.close()
    return {name: np.array(pixels[:, :, i]) for i, name in
            enumerate(spec.channelnames)}, spec


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


def write_channels(path, channels, width, height, half=()):
    """Writes {name: (h, w) array} as one EXR (names as given)."""
    names = list(channels)
    spec = oiio.ImageSpec(width, height, len(names), oiio.FLOAT)
    spec.channelnames = names
    spec.channelformats = [oiio.HALF if n in half else oiio.FLOAT
                           for n in names]
    spec.attribute("compression", "zip")
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec), out.geterror()
    data = np.stack([channels[n] for n in names], axis=-1).astype(np.float32)
    assert out.write_image(data), out.geterror()
    out.close()


def pass_rgb(channels, prefix):
    """(h, w, 3) array of prefix.R/G/B."""
    return np.stack([channels[f"{prefix}.{c}"] for c in "RGB"], axis=-1)
