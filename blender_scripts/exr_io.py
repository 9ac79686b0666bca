"""EXR files as dicts of channel name -> 2-D float32 array, through
OpenImageIO: what the comparison, calibration and transmission scripts
read and write besides the library itself."""
import numpy as np


# Blender 5.0 names render passes in full where 3.x and 4.x wrote short
# names; channels are read under the short ones, so one name serves every
# version (the library reads both: csrc/sss_exr.c).
SHORT_PASS_NAMES = {
    "Diffuse Direct": "DiffDir", "Diffuse Indirect": "DiffInd",
    "Diffuse Color": "DiffCol", "Glossy Direct": "GlossDir",
    "Glossy Indirect": "GlossInd", "Glossy Color": "GlossCol",
    "Transmission Direct": "TransDir", "Transmission Indirect": "TransInd",
    "Transmission Color": "TransCol", "Emission": "Emit",
    "Environment": "Env", "Material Index": "IndexMA",
}


def short_name(channel):
    """ "ViewLayer.Diffuse Direct.R" -> "ViewLayer.DiffDir.R"; other
    names unchanged."""
    parts = channel.split(".")
    if len(parts) >= 2 and parts[-2] in SHORT_PASS_NAMES:
        parts[-2] = SHORT_PASS_NAMES[parts[-2]]
    return ".".join(parts)


def read_exr_parts(path):
    """{channel name: float32 (h, w) array} over every part (Blender 5.0
    saves a multilayer EXR as one part per pass), short pass names; and
    the first part's ImageSpec."""
    import OpenImageIO as oiio
    inp = oiio.ImageInput.open(str(path))
    if not inp:
        raise RuntimeError(f"cannot read {path}: {oiio.geterror()}")
    first, out, part = inp.spec(), {}, 0
    while inp.seek_subimage(part, 0):
        spec = inp.spec()
        px = inp.read_image(part, 0, 0, spec.nchannels, oiio.FLOAT)
        if px is None:
            raise RuntimeError(f"cannot read {path}: {inp.geterror()}")
        px = np.asarray(px).reshape(spec.height, spec.width, spec.nchannels)
        for i, name in enumerate(spec.channelnames):
            out[short_name(name)] = np.array(px[:, :, i])
        part += 1
    inp.close()
    return out, first


def read_exr(path):
    return read_exr_parts(path)[0]


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


def rgb(ch, name):
    """(h, w, 3) of the first channel set ending in name.R/G/B: name under
    ViewLayer, name itself, else any layer's; KeyError names the pass."""
    for prefix in (f"ViewLayer.{name}", name):
        if f"{prefix}.R" in ch:
            return np.stack([ch[f"{prefix}.{c}"] for c in "RGB"], axis=-1)
    cands = [k for k in ch if k.endswith(f".{name}.R")]
    if not cands:
        raise KeyError(f"no {name} pass (have {sorted(ch)[:12]}...)")
    prefix = cands[0][:-2]
    return np.stack([ch[f"{prefix}.{c}"] for c in "RGB"], axis=-1)


def single(ch, name):
    """The one channel of pass name (Depth.Z, IndexMA.X, ...) in any
    layer; KeyError names the pass."""
    for k in ch:
        if k.split(".")[-2:-1] == [name]:
            return ch[k]
    raise KeyError(f"no {name} pass")
