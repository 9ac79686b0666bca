#!/usr/bin/env python3
"""Crafted seeds for the fuzz corpus (see make_corpus.sh).

    make_crafted.py DIR                      EXR files, valid and broken
    make_crafted.py --scenes DIR SKIN.json   scene descriptions, broken

EXR files are written byte by byte here (no EXR library), so that headers
can be wrong in ways no writer produces: bad magic, truncation, huge,
empty or inverted data windows, no channels, duplicate channels, bad
pixel types, bad chunk tables. Each is a few hundred bytes.
"""
import json
import math
import os
import struct
import sys

HALF, FLOAT, UINT = 1, 2, 0
SIZE = {UINT: 4, HALF: 2, FLOAT: 4}
PACK = {UINT: "<I", HALF: "<e", FLOAT: "<f"}


def attr(name, type_name, value):
    return (name.encode() + b"\0" + type_name.encode() + b"\0" +
            struct.pack("<i", len(value)) + value)


def chlist(channels):
    out = b""
    for ch in channels:
        name, ptype = ch[0], ch[1]
        xs, ys = (ch[2], ch[3]) if len(ch) > 2 else (1, 1)
        out += name.encode() + b"\0" + struct.pack("<iB3xii", ptype, 0, xs, ys)
    return out + b"\0"


def box(x0, y0, x1, y1):
    return struct.pack("<iiii", x0, y0, x1, y1)


def header(channels, dw, compression=0, line_order=0, tiles=None,
           extra=b"", dispw=None, sort=True):
    chans = sorted(channels, key=lambda c: c[0]) if sort else channels
    h = attr("channels", "chlist", chlist(chans))
    h += attr("compression", "compression", bytes([compression]))
    h += attr("dataWindow", "box2i", box(*dw))
    h += attr("displayWindow", "box2i", box(*(dispw or dw)))
    h += attr("lineOrder", "lineOrder", bytes([line_order]))
    h += attr("pixelAspectRatio", "float", struct.pack("<f", 1.0))
    h += attr("screenWindowCenter", "v2f", struct.pack("<ff", 0, 0))
    h += attr("screenWindowWidth", "float", struct.pack("<f", 1.0))
    if tiles:
        h += attr("tiles", "tiledesc", struct.pack("<IIB", *tiles))
    return h + extra


def value(fn, name, x, y):
    return fn(name, x, y) if fn else float((x + 2 * y) % 5) * 0.25


def scan_data(chans, x0, x1, y, fn):
    out = b""
    for name, ptype in chans:
        for x in range(x0, x1 + 1):
            v = value(fn, name, x, y)
            out += struct.pack(PACK[ptype], int(v) if ptype == UINT else v)
    return out


def scanline_exr(channels, dw=(0, 0, 3, 3), fn=None, extra=b"",
                 line_order=0, flags=0, magic=b"\x76\x2f\x31\x01"):
    """Uncompressed scanline file, one scanline per chunk."""
    chans = sorted([(c[0], c[1]) for c in channels])
    h = header(channels, dw, 0, line_order, extra=extra)
    x0, y0, x1, y1 = dw
    head = magic + struct.pack("<I", 2 | flags) + h + b"\0"
    nchunks = y1 - y0 + 1
    pos = len(head) + 8 * nchunks
    table, body = b"", b""
    for y in range(y0, y1 + 1):
        data = scan_data(chans, x0, x1, y, fn)
        chunk = struct.pack("<ii", y, len(data)) + data
        table += struct.pack("<Q", pos)
        body += chunk
        pos += len(chunk)
    return head + table + body


def tiled_exr(channels, w, h, tw, th, fn=None):
    chans = sorted(channels)
    hd = header(channels, (0, 0, w - 1, h - 1), 0, tiles=(tw, th, 0))
    head = b"\x76\x2f\x31\x01" + struct.pack("<I", 2 | 0x200) + hd + b"\0"
    ntx, nty = (w + tw - 1) // tw, (h + th - 1) // th
    pos = len(head) + 8 * ntx * nty
    table, body = b"", b""
    for ty in range(nty):
        for tx in range(ntx):
            data = b""
            for y in range(ty * th, min(h, (ty + 1) * th)):
                data += scan_data(chans, tx * tw, min(w, (tx + 1) * tw) - 1,
                                  y, fn)
            chunk = struct.pack("<iiiii", tx, ty, 0, 0, len(data)) + data
            table += struct.pack("<Q", pos)
            body += chunk
            pos += len(chunk)
    return head + table + body


def blender(prefix, ptype=FLOAT, depth="Z", index="X"):
    chans = []
    for p in ("DiffDir", "DiffCol", "DiffInd"):
        chans += [(prefix + p + "." + c, ptype) for c in "RGB"]
    chans += [(prefix + "Depth." + depth, FLOAT),
              (prefix + "IndexMA." + index, FLOAT)]
    return chans


def scene_pixels(bad=False):
    """Index 1 on the left half, 2 on the right, 0 in a corner; depth 2;
    with bad=True also NaN, Inf, huge and negative values."""
    def fn(name, x, y):
        if name.endswith("IndexMA.X") or name.endswith("IndexMA.V"):
            if bad and (x, y) == (1, 1):
                return 1e30
            if bad and (x, y) == (2, 1):
                return -1.0
            return 0.0 if (x, y) == (3, 3) else (1.0 if x < 2 else 2.0)
        if ".Depth." in name or name.startswith("Depth."):
            if bad and (x, y) == (0, 1):
                return math.nan
            if bad and (x, y) == (1, 2):
                return 1e-30
            return 2.0 + 0.1 * x
        if bad and (x, y) == (2, 2):
            return math.inf
        if bad and (x, y) == (0, 0):
            return math.nan
        return 0.5 + 0.1 * ((x * 3 + y) % 4)
    return fn


def exr_seeds():
    seeds = {}
    valid = scanline_exr([("R", FLOAT)], (0, 0, 1, 1))
    seeds["min_r_2x2_none.exr"] = valid
    seeds["blender_like_4x4_none.exr"] = scanline_exr(
        blender("ViewLayer."), fn=scene_pixels())
    seeds["fileout_like_4x4_half_none.exr"] = scanline_exr(
        blender("", HALF, "V", "V"), fn=scene_pixels())
    seeds["blender_like_nan_inf_4x4.exr"] = scanline_exr(
        blender("ViewLayer."), fn=scene_pixels(bad=True))
    seeds["bad_magic.exr"] = scanline_exr([("R", FLOAT)], (0, 0, 1, 1),
                                          magic=b"\x76\x2f\x31\x02")
    seeds["empty.exr"] = b""
    seeds["magic_only.exr"] = b"\x76\x2f\x31\x01"
    full = scanline_exr(blender("ViewLayer."), fn=scene_pixels())
    seeds["truncated_header.exr"] = full[:60]
    seeds["truncated_pixels.exr"] = full[:len(full) - 40]
    # Past OpenEXR's own limits, and past only the harness's 512 caps.
    for name, side in (("huge", 1 << 30), ("large", 4096)):
        seeds[name + "_data_window.exr"] = \
            b"\x76\x2f\x31\x01\x02\0\0\0" + header(
                [("R", HALF)], (0, 0, side, side), dispw=(0, 0, 1, 1)) + \
            b"\0" + bytes(64)
    seeds["int_range_window.exr"] = b"\x76\x2f\x31\x01\x02\0\0\0" + header(
        [("R", HALF)], (-(1 << 31), 0, (1 << 31) - 1, 0),
        dispw=(0, 0, 1, 1)) + b"\0" + bytes(64)
    seeds["zero_channels.exr"] = scanline_exr([], (0, 0, 1, 1))
    seeds["negative_window.exr"] = b"\x76\x2f\x31\x01\x02\0\0\0" + header(
        [("R", FLOAT)], (3, 3, 0, 0), dispw=(0, 0, 1, 1)) + b"\0" + bytes(32)
    seeds["negative_origin_4x4.exr"] = scanline_exr(
        blender("ViewLayer."), (-3, -2, 0, 1), fn=scene_pixels())
    seeds["duplicate_channel.exr"] = scanline_exr(
        [("R", FLOAT), ("R", FLOAT)], (0, 0, 1, 1))
    seeds["duplicate_component_dot.exr"] = scanline_exr(
        [("P.R", FLOAT), (".P.R", FLOAT)], (0, 0, 1, 1))
    seeds["subsampled_channel.exr"] = b"\x76\x2f\x31\x01\x02\0\0\0" + header(
        [("Y", HALF), ("RY", HALF, 2, 2)], (0, 0, 3, 3)) + b"\0" + bytes(64)
    seeds["bad_pixel_type.exr"] = b"\x76\x2f\x31\x01\x02\0\0\0" + header(
        [("R", 7)], (0, 0, 1, 1)) + b"\0" + bytes(32)
    seeds["deep_scanline.exr"] = b"\x76\x2f\x31\x01" + struct.pack(
        "<I", 2 | 0x800) + header([("Z", FLOAT)], (0, 0, 1, 1), extra=attr(
            "type", "string", b"deepscanline") + attr(
            "version", "int", struct.pack("<i", 1)) + attr(
            "maxSamplesPerPixel", "int", struct.pack("<i", 4)) + attr(
            "chunkCount", "int", struct.pack("<i", 2)) + attr(
            "name", "string", b"deep")) + b"\0" + bytes(64)
    seeds["tiled_4x4_tiles2_none.exr"] = tiled_exr(
        blender("ViewLayer."), 4, 4, 2, 2, fn=scene_pixels())
    seeds["tiled_3x5_tiles2_none.exr"] = tiled_exr(
        [("R", HALF), ("G", HALF)], 3, 5, 2, 2)
    t = tiled_exr([("R", HALF)], 4, 4, 2, 2)
    seeds["tiled_zero_tile.exr"] = t.replace(
        struct.pack("<IIB", 2, 2, 0), struct.pack("<IIB", 0, 0, 0))
    seeds["tiled_huge_tile.exr"] = t.replace(
        struct.pack("<IIB", 2, 2, 0), struct.pack("<IIB", 1 << 30, 1 << 30, 0))
    # Offset table entries pointing past the end / chunks lying about y
    # and size.
    v = scanline_exr([("R", FLOAT), ("G", FLOAT)], (0, 0, 1, 3))
    tab = len(v) - 4 * (8 + 2 * 2 * 4) - 4 * 8  # 4 chunks of 2x1 x 2 floats
    seeds["offset_past_end.exr"] = (v[:tab] + struct.pack("<Q", 1 << 40) +
                                    v[tab + 8:])
    first = struct.unpack("<Q", v[tab:tab + 8])[0]
    seeds["chunk_wrong_y.exr"] = (v[:first] + struct.pack("<i", 3) +
                                  v[first + 4:])
    seeds["chunk_huge_size.exr"] = (v[:first + 4] +
                                    struct.pack("<i", 0x7fffffff) +
                                    v[first + 8:])
    seeds["chunk_negative_size.exr"] = (v[:first + 4] +
                                        struct.pack("<i", -16) +
                                        v[first + 8:])
    seeds["offset_table_zero.exr"] = (v[:tab] + bytes(32) + v[tab + 32:])
    long = "ViewLayer.AVeryLongPassNameThatNeedsLongNames.R"
    seeds["long_names.exr"] = scanline_exr([(long, HALF)], (0, 0, 1, 1),
                                           flags=0x400)
    seeds["long_names_without_flag.exr"] = scanline_exr(
        [(long, HALF)], (0, 0, 1, 1))
    seeds["decreasing_y_4x4.exr"] = scanline_exr(
        blender("ViewLayer."), fn=scene_pixels(), line_order=1)
    u = bytearray(scanline_exr([("R", FLOAT)], (0, 0, 1, 1)))
    at = bytes(u).index(b"compression\0compression\0") + 24 + 4
    u[at] = 42
    seeds["unknown_compression.exr"] = bytes(u)
    seeds["uint_channels.exr"] = scanline_exr(
        [("L.P.X", UINT), ("L.P.Y", UINT)], (0, 0, 1, 1),
        fn=lambda n, x, y: (0xffffffff if x else 1 << 25))
    many = [("L.P.c%03d" % i, HALF) for i in range(40)]
    seeds["many_components_1x1.exr"] = scanline_exr(many, (0, 0, 0, 0))
    seeds["odd_names.exr"] = scanline_exr(
        [(".R", FLOAT), ("a..G", FLOAT), ("x.", FLOAT), ("..", FLOAT),
         ("L.P.", FLOAT)], (0, 0, 0, 0))
    seeds["metadata_attrs.exr"] = scanline_exr(
        [("R", FLOAT)], (0, 0, 1, 1), extra=attr(
            "owner", "string", b"fuzz") + attr(
            "comments", "stringvector",
            struct.pack("<i", 2) + b"ab" + struct.pack("<i", 0)) + attr(
            "worldToCamera", "m44f", struct.pack("<16f", *range(16))) + attr(
            "custom", "opaqueType", b"\1\2\3") + attr(
            "framesPerSecond", "rational", struct.pack("<iI", 24, 1)) + attr(
            "timeCode", "timecode", struct.pack("<II", 1, 2)) + attr(
            "chromaticities", "chromaticities", struct.pack("<8f", *[.1] * 8)))
    # A user attribute with no bytes (OpenEXRCore 3.1 leaked it on write).
    seeds["empty_user_attr.exr"] = scanline_exr(
        [("R", FLOAT)], (0, 0, 1, 1), extra=attr("empty", "userType", b""))
    # Two parts: only the first is read.
    p1 = header([("R", FLOAT)], (0, 0, 0, 0), extra=attr(
        "name", "string", b"a") + attr("type", "string", b"scanlineimage") +
        attr("chunkCount", "int", struct.pack("<i", 1)))
    p2 = header([("G", FLOAT)], (0, 0, 0, 0), extra=attr(
        "name", "string", b"b") + attr("type", "string", b"scanlineimage") +
        attr("chunkCount", "int", struct.pack("<i", 1)))
    head = b"\x76\x2f\x31\x01" + struct.pack("<I", 2 | 0x1000) + p1 + b"\0" \
        + p2 + b"\0" + b"\0"
    pos = len(head) + 16
    c1 = struct.pack("<iii", 0, 0, 4) + struct.pack("<f", 1.0)
    c2 = struct.pack("<iii", 1, 0, 4) + struct.pack("<f", 2.0)
    seeds["multipart_2.exr"] = head + struct.pack(
        "<QQ", pos, pos + len(c1)) + c1 + c2
    return seeds


def scene_seeds(skin_path):
    with open(skin_path) as f:
        skin = json.load(f)
    text = json.dumps(skin, indent=1)
    s = {}

    def put(name, obj_or_text):
        s[name] = (obj_or_text if isinstance(obj_or_text, (str, bytes))
                   else json.dumps(obj_or_text))

    def variant(path, val, drop=False):
        d = json.loads(text)
        o = d
        for k in path[:-1]:
            o = o[k]
        if drop:
            del o[path[-1]]
        else:
            o[path[-1]] = val
        return d

    put("truncated.json", text[:len(text) // 2])
    put("trailing_text.json", text + " x")
    put("lens_string.json", variant(["camera", "lens"], "85"))
    put("duplicate_key.json", text.replace('"unit_scale": 1.0',
                                           '"unit_scale": 1.0, "unit_scale": 2'))
    put("unknown_keys.json", variant(["camera", "focus_\u00e9\u0001"], 1))
    put("version_2.json", variant(["version"], 2))
    put("overflow.json", text.replace('"lens": 85.0', '"lens": 1e999'))
    put("pass_index_0.json", variant(["materials", 0, "pass_index"], 0))
    put("pass_index_dup.json", variant(["materials", 1, "pass_index"], 1))
    put("pass_index_frac.json", variant(["materials", 0, "pass_index"], 1.5))
    put("radius_short.json", variant(["materials", 0, "radius"], [1, 2]))
    put("no_profile.json", variant(["materials", 0, "profile"], None,
                                   drop=True))
    put("ortho.json", variant(["camera"], {"type": "ORTHO",
                                            "ortho_scale": 1e-300}))
    put("clip_inverted.json", variant(["camera"], {"clip_start": 10,
                                                    "clip_end": 1}))
    put("reference_taps.json", {"method": "reference", "taps": 4097,
                                "max_support_px": 2147483647,
                                "materials": [{"pass_index": 65535,
                                               "profile": "burley",
                                               "radius": [1e30, 1e-30, 0],
                                               "taps": 4097}]})
    put("gaussians_zero.json", {"materials": [{
        "pass_index": 1, "profile": "gaussians",
        "gaussians": [{"variance": 1, "weight": [0, 0, 0]}]}]})
    put("gaussians_9.json", {"materials": [{
        "pass_index": 1, "profile": "gaussians",
        "gaussians": [{"variance": 1, "weight": [1, 1, 1]}] * 9}]})
    put("jimenez_nearfar.json", {"radius_scale": 3.4e38, "materials": [
        {"pass_index": 7, "profile": "jimenez", "width": 1e30,
         "falloff": [1e-45, 1, 1]},
        {"pass_index": 8, "profile": "near-far", "scatter_scale": 0,
         "near_sigma": [1e30, 1, 1], "radius": [1, 1, 1]}]})
    put("many_unknown.json", {"k%03d_%s" % (i, "x" * 60): i
                              for i in range(40)})
    s["nul_inside.json"] = text[:40].encode() + b"\0" + text[40:].encode()
    s["bad_utf8.json"] = b'{"materials":[{"pass_index":1,"profile":"none",' \
        b'"name":"\xff\xfe\xc0"}]}'
    s["empty_object.json"] = "{}"
    # 'J' selector: any JSON text, not only objects.
    s["J_array.json"] = "J[1, 2, 3]"
    s["J_blank.json"] = "J  \n\t "
    s["J_deep.json"] = "J" + "[" * 3000 + "]" * 3000
    s["J_string.json"] = 'J"\\ud800\\udc00\\u0000"'
    return s


def main():
    args = sys.argv[1:]
    if args and args[0] == "--scenes":
        out, seeds = args[1], scene_seeds(args[2])
    else:
        out, seeds = args[0], exr_seeds()
    os.makedirs(out, exist_ok=True)
    for name, data in seeds.items():
        if isinstance(data, str):
            data = data.encode()
        with open(os.path.join(out, name), "wb") as f:
            f.write(data)


if __name__ == "__main__":
    main()
