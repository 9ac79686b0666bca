"""EXR files as dicts of channel name -> 2-D float32 array, through
OpenImageIO: what the comparison, calibration and transmission scripts
read and write besides the library itself."""
import numpy as np


def read_exr(path):
    import OpenImageIO as oiio
    inp = oiio.ImageInput.open(path)
    if not inp:
        raise RuntimeError(f"cannot read {path}: {oiio.geterror()}")
    spec = inp.spec()
    px = inp.read_image(oiio.FLOAT)
    inp.close()
    return {n: np.array(px[:, :, i]) for i, n in
            enumerate(spec.channelnames)}


def write_exr(path, channels):
    """channels: name -> (h, w) array, written as float, ZIP."""
    import OpenImageIO as oiio
    names = list(channels)
    h, w = channels[names[0]].shape
    spec = oiio.ImageSpec(w, h, len(names), oiio.FLOAT)
    spec.channelnames = names
    spec.attribute("compression", "zip")
    out = oiio.ImageOutput.create(path)
    if not out or not out.open(path, spec):
        raise RuntimeError(f"cannot write {path}: {oiio.geterror()}")
    out.write_image(np.stack([channels[n] for n in names], axis=-1)
                    .astype(np.float32))
    out.close()
