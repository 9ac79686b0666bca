"""make bench: what the SSS post-process costs, measured side by side.

    /usr/bin/python3 bench/run_bench.py [--out out/bench] [--build build]

Runs build/sss-bench (one configuration per process, so that peak memory is
per configuration) over image sizes, scattering coverage and projected
kernel radii for every method; then, in the same run, the ratios that say
whether the separable method is fast: one thread against all cores, the
AVX2 loop against the scalar one, separable against the brute-force
reference, separable against Blender's compositor Bilateral Blur node on
the same image (when Blender is installed), and the `sss` command end to
end against a plain read + write of the same EXR with oiiotool. Writes
bench.csv (every run), bench.md (tables) and bench.png (plots) into --out
and prints the tables.

Timings are the best of a few runs on a machine that may be shared: read
the ratios, which are measured minutes apart on the same machine.
"""
import argparse
import csv
import io
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

SIZES = [(960, 540), (1920, 1080), (3840, 2160)]
COVERAGES = [0.1, 0.5, 1.0]
RADII = [4, 16, 64]
FIELDS = ["method", "width", "height", "rows", "coverage", "radius_px",
          "threads", "simd", "seconds", "mpx_per_s", "ns_per_scattering_px",
          "rss_inputs_mib", "rss_peak_mib"]


def log(msg):
    print(f"bench: {msg}", flush=True)


class Bench:
    def __init__(self, build):
        self.exe = os.path.join(build, "sss-bench")
        self.rows = []
        # The library's methods, as it names them.
        self.methods = subprocess.run([self.exe, "--methods"], check=True,
                                      capture_output=True,
                                      text=True).stdout.split()

    def run(self, tag, size=(1920, 1080), coverage=1.0, radius=16,
            method="separable", threads=0, scalar=False, repeat=2, rows=0,
            dump=None, no_scatter=False, calibrated=False):
        cmd = [self.exe, "--size", str(size[0]), str(size[1]),
               "--coverage", str(coverage), "--radius", str(radius),
               "--method", method, "--threads", str(threads),
               "--repeat", str(repeat)]
        if scalar:
            cmd.append("--scalar")
        if rows:
            cmd += ["--rows", str(rows)]
        if dump:
            cmd += ["--dump", dump]
        if no_scatter:
            cmd.append("--no-scatter")
        if calibrated:
            cmd.append("--calibrated")
        out = subprocess.run(cmd, check=True, capture_output=True, text=True)
        row = dict(zip(FIELDS, next(csv.reader(io.StringIO(out.stdout)))))
        row["tag"] = tag
        for k in FIELDS[1:]:
            if k != "simd":
                row[k] = float(row[k])
        self.rows.append(row)
        return row


def grid(b):
    for size in SIZES:
        for cov in COVERAGES:
            for r in RADII:
                row = b.run("grid", size, cov, r,
                            repeat=1 if size[0] * size[1] > 4e6 else 2)
                log(f"separable {size[0]}x{size[1]} coverage {cov:.0%} "
                    f"radius {r:2d} px: {row['ns_per_scattering_px']:8.1f} ns "
                    f"per scattering pixel, peak {row['rss_peak_mib']:.0f} MiB")
    # The other methods on the small size: they are slower by design (the
    # reference gets a band of the frame below).
    for method in b.methods:
        if method in ("separable", "reference"):
            continue
        for cov in (0.1, 1.0):
            for r in RADII:
                row = b.run("grid", SIZES[0], cov, r, method=method, repeat=1)
                log(f"{method} {SIZES[0][0]}x{SIZES[0][1]} coverage {cov:.0%} "
                    f"radius {r:2d} px: {row['ns_per_scattering_px']:8.1f} ns")
    # The reference on a band of rows: its cost per pixel does not depend
    # on how many rows there are, and a whole frame would take minutes.
    for r in (4, 16):
        row = b.run("grid", SIZES[0], 1.0, r, method="reference", repeat=1,
                    rows=68 if r == 4 else 24)
        log(f"reference {SIZES[0][0]}x{row['rows']:.0f} band radius {r:2d} px: "
            f"{row['ns_per_scattering_px']:8.1f} ns")


def cpu_flags():
    """The CPU's vector extensions, as /proc/cpuinfo names them."""
    try:
        with open("/proc/cpuinfo") as f:
            flags = next((line.split(":", 1)[1].split() for line in f
                          if line.startswith("flags")), [])
    except OSError:
        return "unknown"
    wanted = [f for f in flags if f.startswith(("sse4", "avx", "fma"))]
    return " ".join(sorted(set(wanted))) or "none of sse4/avx/fma"


def ratios(b, results):
    hd, cov, r = (1920, 1080), 1.0, 16
    one = b.run("threads", hd, cov, r, threads=1, repeat=3)
    every = b.run("threads", hd, cov, r, threads=0, repeat=3)
    scalar = b.run("simd", hd, cov, r, threads=1, scalar=True, repeat=2)
    ref = b.run("reference", hd, cov, r, threads=1, method="reference",
                repeat=1, rows=34)
    # Coverage: what every frame costs (the passes read and recombined,
    # no pixel scattering) and, above it, the cost per scattering pixel at
    # 10 % and 100 %: proportional to coverage when the two are alike.
    floor = b.run("coverage", hd, cov, r, threads=1, repeat=3,
                  no_scatter=True)
    tenth = b.run("coverage", hd, 0.1, r, threads=1, repeat=3)
    # Matching the random walk's energy: the view cosine and the surface's
    # curvature at every scattering pixel.
    calibrated = b.run("calibrated", hd, cov, r, threads=1, repeat=3,
                       calibrated=True)
    npix = hd[0] * hd[1]

    def above(row):
        return (row["seconds"] - floor["seconds"]) / \
            (row["coverage"] * npix) * 1e9
    cores = os.cpu_count() or 1
    per_core = npix / one["seconds"] * 1e-6
    results.update({
        "cores": cores,
        "separable_1080p_16px_1thread_s": one["seconds"],
        "separable_1080p_16px_all_s": every["seconds"],
        "mpx_per_s_per_core": per_core,
        "thread_scaling": one["seconds"] / every["seconds"],
        "simd_speedup": scalar["seconds"] / one["seconds"],
        "vs_reference": ref["ns_per_scattering_px"] /
                        one["ns_per_scattering_px"],
        "peak_working_mib": every["rss_peak_mib"] - every["rss_inputs_mib"],
        "two_rgb_images_mib": 2 * 3 * 4 * hd[0] * hd[1] / 2**20,
        "frame_floor_s": floor["seconds"],
        "ns_above_floor_100": above(one),
        "ns_above_floor_10": above(tenth),
        "coverage_10_vs_100": above(tenth) / above(one),
        "calibrated_vs_not": calibrated["seconds"] / one["seconds"],
        "cpu_flags": cpu_flags(),
    })
    log(f"1080p, 100% coverage, 16 px, separable: {per_core:.2f} Mpx/s per "
        f"core (1 thread), {cores} threads {results['thread_scaling']:.2f}x, "
        f"AVX2 vs scalar {results['simd_speedup']:.2f}x, vs reference "
        f"{results['vs_reference']:.0f}x")


def write_exr(path, width, height, channels, compression="zip"):
    """channels: list of (name, float32 array of height x width)."""
    import OpenImageIO as oiio
    spec = oiio.ImageSpec(width, height, len(channels), "float")
    spec.channelnames = tuple(name for name, _ in channels)
    spec.attribute("compression", compression)
    data = np.stack([a for _, a in channels], axis=-1).astype(np.float32)
    out = oiio.ImageOutput.create(path)
    if not out or not out.open(path, spec) or not out.write_image(data):
        raise RuntimeError(f"cannot write {path}: {oiio.geterror()}")
    out.close()


def frame_from_dump(prefix, width, height, path):
    """A Blender-style multilayer frame (render-output naming, every pass
    Cycles writes, float, ZIP) around the benchmark's light and depth."""
    light = np.fromfile(prefix + "_light.f32", np.float32).reshape(height, width, 3)
    depth = np.fromfile(prefix + "_depth.f32", np.float32).reshape(height, width)
    index = np.fromfile(prefix + "_index.f32", np.float32).reshape(height, width)
    rng = np.random.default_rng(1)
    ch = [("ViewLayer.Combined." + c, light[..., i % 3] if c != "A"
           else np.ones_like(depth)) for i, c in enumerate("RGBA")]
    ch.append(("ViewLayer.Depth.Z", depth))
    ch.append(("ViewLayer.IndexMA.X", index))
    for name in ("DiffDir", "DiffInd", "DiffCol", "GlossDir", "GlossInd",
                 "GlossCol", "TransDir", "TransInd", "TransCol", "Emit", "Env"):
        for i, c in enumerate("RGB"):
            if name == "DiffDir":
                a = light[..., i]
            elif name == "DiffCol":
                a = np.full_like(depth, 0.8)
            else:
                a = (0.05 * rng.random((height, width))).astype(np.float32)
            ch.append((f"ViewLayer.{name}.{c}", a))
    write_exr(path, width, height, ch)
    return len(ch)


def best_of(cmd, repeat, parse=None):
    best, text = float("inf"), ""
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = subprocess.run(cmd, check=True, capture_output=True, text=True)
        t = time.perf_counter() - t0
        if t < best:
            best, text = t, out.stdout
    return best, text


def end_to_end(b, build, tmp, results):
    hd = (1920, 1080)
    prefix = os.path.join(tmp, "frame")
    b.run("dump", hd, 1.0, 16, repeat=1, dump=prefix)
    src = os.path.join(tmp, "frame.exr")
    n = frame_from_dump(prefix, hd[0], hd[1], src)
    size_mb = os.path.getsize(src) / 1e6
    sss = [os.path.join(build, "sss"), src, "-o", os.path.join(tmp, "sss.exr"),
           "--scene", prefix + "_scene.json", "--threads", "0"]
    t_sss, text = best_of(sss, 2)
    m = re.search(r"read ([\d.]+) s, sss ([\d.]+) s, write ([\d.]+) s", text)
    results.update({"exr_channels": n, "exr_mb": size_mb,
                    "sss_end_to_end_s": t_sss})
    if m:
        results.update({"sss_read_s": float(m.group(1)),
                        "sss_sss_s": float(m.group(2)),
                        "sss_write_s": float(m.group(3))})
    oiiotool = shutil.which("oiiotool")
    if oiiotool:
        t_io, _ = best_of([oiiotool, src, "-o", os.path.join(tmp, "io.exr")], 2)
        results["oiiotool_read_write_s"] = t_io
        results["end_to_end_vs_io"] = t_sss / t_io
        log(f"1080p ZIP frame ({n} channels, {size_mb:.0f} MB): sss end to end "
            f"{t_sss:.2f} s (read {results.get('sss_read_s', 0):.2f}, sss "
            f"{results.get('sss_sss_s', 0):.2f}, write "
            f"{results.get('sss_write_s', 0):.2f}), oiiotool read+write "
            f"{t_io:.2f} s: {t_sss / t_io:.2f}x")
    else:
        log("oiiotool not found: end-to-end ratio skipped")


def bilateral(b, tmp, results):
    blender = shutil.which("blender")
    if not blender:
        log("Blender not found: Bilateral Blur comparison skipped")
        return
    size, r = (640, 360), 16
    prefix = os.path.join(tmp, "small")
    ours = b.run("bilateral", size, 1.0, r, threads=0, repeat=3, dump=prefix)
    light = np.fromfile(prefix + "_light.f32", np.float32).reshape(size[1], size[0], 3)
    depth = np.fromfile(prefix + "_depth.f32", np.float32).reshape(size[1], size[0])
    lp, dp = os.path.join(tmp, "light.exr"), os.path.join(tmp, "depth.exr")
    write_exr(lp, size[0], size[1], [(c, light[..., i]) for i, c in enumerate("RGB")])
    write_exr(dp, size[0], size[1], [("R", depth), ("G", depth), ("B", depth)])
    out = subprocess.run(
        [blender, "-b", "--factory-startup", "--python-exit-code", "1",
         "--python", os.path.join(HERE, "blender_bilateral.py"), "--",
         "--light", lp, "--depth", dp, "--sigma-space", str(r), "--repeat", "1"],
        check=True, capture_output=True, text=True)
    m = re.search(r"bilateral_seconds=([\d.]+) baseline_seconds=([\d.]+)",
                  out.stdout)
    if not m:
        raise RuntimeError("blender_bilateral.py printed no timing:\n" + out.stdout[-2000:])
    node = float(m.group(1)) - float(m.group(2))
    results.update({"bilateral_s": node, "bilateral_size": f"{size[0]}x{size[1]}",
                    "separable_same_image_s": ours["seconds"],
                    "vs_bilateral": node / ours["seconds"]})
    log(f"{size[0]}x{size[1]}, 16 px: Blender Bilateral Blur {node:.2f} s, "
        f"separable {ours['seconds']:.3f} s: {node / ours['seconds']:.0f}x")


def real_render(build, tmp, results):
    blender = shutil.which("blender")
    if not blender:
        return
    out_dir = os.path.join(tmp, "render")
    subprocess.run(
        [blender, "-b", "--factory-startup", "--python-exit-code", "1",
         "--python", os.path.join(ROOT, "blender_scripts", "make_test_scene.py"),
         "--", "--out", out_dir, "--size", "512", "--samples", "2"],
        check=True, capture_output=True, text=True)
    cmd = [os.path.join(build, "sss"), os.path.join(out_dir, "render.exr"), "-o",
           os.path.join(tmp, "render_sss.exr"), "--scene",
           os.path.join(out_dir, "scene.json"), "--threads", "0"]
    t, text = best_of(cmd, 2)
    m = re.search(r"read ([\d.]+) s, sss ([\d.]+) s, write ([\d.]+) s", text)
    results["blender_512_end_to_end_s"] = t
    if m:
        results["blender_512_sss_s"] = float(m.group(2))
    log(f"Blender render 512x512 (Cycles test scene): sss end to end {t:.2f} s"
        + (f", of which SSS {float(m.group(2)):.3f} s" if m else ""))


F12_SCENES = ("head", "marble", "mixed")


def f12(build, tmp, results, scenes, size=(1920, 1080), samples=64):
    """What Screen-space SSS adds to F12 / `blender -b -f` on the bundled
    scenes: the same frame rendered with the switch on, and with it off
    twice: as the scene is (the materials' own random walk) and `plain`
    (material SSS off, the passes on: what the add-on itself renders). The
    add-on's overhead is on / plain - 1: the library, its files and the
    back-light layer where the scene needs it."""
    blender = blender_for_f12(build)
    if not blender or not scenes:
        log("F12 overhead skipped (no Blender, or F12_SCENES is empty)")
        return
    env = {**os.environ, "SSS_LIB": os.path.join(os.path.abspath(build),
                                                 "libsss.so")}
    for kind in scenes:
        blend = os.path.join(tmp, f"f12_{kind}.blend")
        subprocess.run(
            [blender, "-b", "--factory-startup", "--python-exit-code", "1",
             "--python", os.path.join(ROOT, "blender_scripts", "build_scene.py"),
             "--", "--kind", kind, "--out", blend],
            check=True, capture_output=True, text=True)
        times = {}
        for mode in ("plain", "on", "off"):
            out = subprocess.run(
                [blender, "-b", blend, "--python-exit-code", "1", "--python",
                 os.path.join(HERE, "blender_f12.py"), "--", "--sss", mode,
                 "--size", str(size[0]), str(size[1]), "--samples",
                 str(samples), "--out", tmp],
                check=True, capture_output=True, text=True, env=env)
            m = re.search(r"f12_seconds=([\d.]+) layer=(\w+)", out.stdout)
            if not m:
                raise RuntimeError(f"blender_f12.py printed no timing:\n"
                                   f"{out.stdout[-2000:]}{out.stderr[-2000:]}")
            times[mode] = float(m.group(1))
            if mode == "on":
                results[f"f12_{kind}_backlight_layer"] = m.group(2)
        for mode, t in times.items():
            results[f"f12_{kind}_{mode}_s"] = t
        results[f"f12_{kind}_overhead"] = times["on"] / times["plain"] - 1.0
        results[f"f12_{kind}_vs_random_walk"] = times["on"] / times["off"]
        log(f"F12 {kind} {size[0]}x{size[1]} {samples} spp: SSS on "
            f"{times['on']:.1f} s, plain passes {times['plain']:.1f} s "
            f"(+{100 * results[f'f12_{kind}_overhead']:.1f} %), switch off "
            f"(random walk) {times['off']:.1f} s")
    results["f12_size"] = f"{size[0]}x{size[1]}, {samples} spp"


def retune(build, tmp, results, size=(1920, 1080)):
    """A live re-tune at 1080p on the head-sized skin scene (the demo):
    Render with SSS once, then five changes of the material's Subsurface
    Scale each followed by Apply (bench/blender_retune.py: the median of
    the operator's whole call and of the library's scatter); and the
    library's scatter of that frame's kept passes on 1 and on all cores
    (sss-retune)."""
    blender = blender_for_f12(build)
    if not blender:
        log("re-tune skipped (no Blender)")
        return
    env = {**os.environ, "SSS_LIB": os.path.join(os.path.abspath(build),
                                                 "libsss.so")}
    blend = os.path.join(tmp, "retune.blend")
    folder = os.path.join(tmp, "retune")
    os.makedirs(folder, exist_ok=True)
    subprocess.run(
        [blender, "-b", "--factory-startup", "--python-exit-code", "1",
         "--python", os.path.join(ROOT, "blender_scripts", "build_scene.py"),
         "--", "--kind", "demo", "--out", blend],
        check=True, capture_output=True, text=True)
    out = subprocess.run(
        [blender, "-b", blend, "--python-exit-code", "1", "--python",
         os.path.join(HERE, "blender_retune.py"), "--", "--size",
         str(size[0]), str(size[1]), "--samples", "1", "--out", folder],
        check=True, capture_output=True, text=True, env=env)
    m = re.search(r"retune_seconds=([\d.]+) scatter_seconds=([\d.]+)",
                  out.stdout)
    if not m:
        raise RuntimeError("blender_retune.py printed no timing:\n" +
                           out.stdout[-2000:] + out.stderr[-2000:])
    results["retune_1080p_s"] = float(m.group(1))
    results["retune_1080p_scatter_s"] = float(m.group(2))
    passes = next(os.path.join(folder, f) for f in sorted(os.listdir(folder))
                  if f.endswith("_passes.exr"))
    scene = passes[:-len("_passes.exr")] + "_scene.json"
    # The same frame lit from the front only, as a material without back
    # light scatters: transmission off, so the crease term runs.
    with open(scene) as f:
        desc = json.load(f)
    for m in desc.get("materials", []):
        m["transmission"] = "off"
        m.pop("transmission_baked_scale", None)
    front = os.path.join(folder, "front_lit_scene.json")
    with open(front, "w") as f:
        json.dump(desc, f)
    for name, path in (("", scene), ("front_lit_", front)):
        for threads in (1, 0):
            line = subprocess.run(
                [os.path.join(build, "sss-retune"), passes, path, "--threads",
                 str(threads), "--repeat", "3"],
                check=True, capture_output=True, text=True).stdout.split(",")
            results[f"retune_{name}scatter_"
                    f"{'1_core' if threads else 'all_cores'}_s"] = \
                float(line[4])
    log(f"live re-tune {size[0]}x{size[1]} (demo): Apply "
        f"{results['retune_1080p_s']:.3f} s (median of 5), of which SSS "
        f"{results['retune_1080p_scatter_s']:.3f} s; sss-retune 1 core "
        f"{results['retune_scatter_1_core_s']:.3f} s, all cores "
        f"{results['retune_scatter_all_cores_s']:.3f} s; lit from the front "
        f"only {results['retune_front_lit_scatter_1_core_s']:.3f} / "
        f"{results['retune_front_lit_scatter_all_cores_s']:.3f} s")


def blender_for_f12(build):
    """The newest Blender the bench can run: the bpy builds in build/
    (make bpy), else `blender` on PATH."""
    import glob
    found = sorted(glob.glob(os.path.join(build, "bpy-*", "bin", "blender")),
                   key=lambda p: [int(x) for x in
                                  re.findall(r"\d+", p.split("bpy-")[-1])])
    return found[-1] if found else shutil.which("blender")


def plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(13, 5))
    grid_rows = [r for r in rows if r["tag"] == "grid"]
    styles = {0.1: ":", 0.5: "--", 1.0: "-"}
    methods = list(dict.fromkeys(r["method"] for r in grid_rows))
    colours = {m: f"C{i}" for i, m in enumerate(methods)}
    for method in colours:
        for cov in COVERAGES:
            pts = sorted((r["radius_px"], r["ns_per_scattering_px"])
                         for r in grid_rows if r["method"] == method and
                         abs(r["coverage"] - cov) < 0.06 and
                         (method != "separable" or r["width"] == 1920))
            if method == "reference":
                pts = sorted((r["radius_px"], r["ns_per_scattering_px"])
                             for r in grid_rows if r["method"] == method)
                if cov != 1.0:
                    continue
            if pts:
                ax[0].plot(*zip(*pts), styles.get(cov, "-"), marker="o",
                           color=colours[method],
                           label=f"{method}, {cov:.0%} coverage"
                           if method != "reference" else "reference (band)")
    ax[0].set(xscale="log", yscale="log", xlabel="projected kernel radius (px)",
              ylabel="ns per scattering pixel (all cores)",
              title="Cost per scattering pixel: method, radius, coverage")
    ax[0].set_xticks(RADII, [str(r) for r in RADII])
    ax[0].legend(fontsize=7)
    for r_px, colour in zip(RADII, ("C0", "C1", "C2")):
        for cov in COVERAGES:
            pts = sorted((r["width"] * r["height"] / 1e6, r["ns_per_scattering_px"])
                         for r in grid_rows if r["method"] == "separable" and
                         r["radius_px"] == r_px and abs(r["coverage"] - cov) < 0.06)
            if pts:
                ax[1].plot(*zip(*pts), styles[cov], marker="o", color=colour,
                           label=f"{r_px} px, {cov:.0%}")
    ax[1].set(xscale="log", yscale="log", xlabel="image size (megapixels)",
              ylabel="ns per scattering pixel (all cores)",
              title="separable: flat in image size and coverage?")
    ax[1].legend(fontsize=7, ncol=3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def markdown(rows, results):
    out = ["# make bench", "",
           f"Machine: {results['cores']} cores ({results['cpu_flags']}). "
           "Times are the best of 1-3 runs; "
           "ns per scattering pixel with all cores unless noted.", "",
           "## Targets (1920x1080, 100% coverage, 16 px, separable)", "",
           "| measure | value | target |", "|---|---|---|",
           f"| Mpx/s per core (1 thread) | {results['mpx_per_s_per_core']:.2f} | >= 25 |",
           f"| thread scaling, {results['cores']} threads | "
           f"{results['thread_scaling']:.2f}x | >= 1.8x on 2 cores |",
           f"| AVX2 vs scalar loop (1 thread) | {results['simd_speedup']:.2f}x | |",
           f"| vs reference (per pixel, 1 thread) | {results['vs_reference']:.0f}x | >= 30x |",
           f"| cost per scattering pixel above the frame's floor "
           f"({1e3 * results['frame_floor_s']:.0f} ms: passes read and "
           f"recombined), 10 % coverage vs 100 % (1 thread) | "
           f"{results['ns_above_floor_10']:.0f} vs "
           f"{results['ns_above_floor_100']:.0f} ns: "
           f"{results['coverage_10_vs_100']:.2f}x | about 1x |",
           f"| energy matched to Random Walk (Skin) (view and curvature at "
           f"every pixel) vs not (1 thread) | "
           f"{results['calibrated_vs_not']:.2f}x | |"]
    if "vs_bilateral" in results:
        out.append(f"| vs Blender Bilateral Blur ({results['bilateral_size']}, "
                   f"all cores) | {results['vs_bilateral']:.0f}x | >= 5x |")
    if "end_to_end_vs_io" in results:
        out.append(f"| sss end to end vs oiiotool read+write (1080p ZIP, "
                   f"{results['exr_channels']} channels) | "
                   f"{results['end_to_end_vs_io']:.2f}x | <= 0.5x |")
    for kind in F12_SCENES:
        if f"f12_{kind}_overhead" in results:
            out.append(f"| F12 with SSS vs the same passes without "
                       f"({kind}, {results['f12_size']}) | "
                       f"+{100 * results[f'f12_{kind}_overhead']:.1f} % | "
                       f"<= +10 % |")
    if "retune_1080p_s" in results:
        out.append(f"| live re-tune at 1920x1080 (demo scene: Subsurface "
                   f"Scale changed, Apply; median of 5) | "
                   f"{results['retune_1080p_s']:.3f} s | <= 0.25 s |")
        out.append(f"| its SSS stage, 1 core / all cores | "
                   f"{results['retune_scatter_1_core_s']:.3f} / "
                   f"{results['retune_scatter_all_cores_s']:.3f} s | "
                   f"<= 0.1 s on 2 cores |")
        out.append(f"| the same lit from the front only (crease term on), "
                   f"1 core / all cores | "
                   f"{results['retune_front_lit_scatter_1_core_s']:.3f} / "
                   f"{results['retune_front_lit_scatter_all_cores_s']:.3f} s"
                   f" | <= 0.1 s on 2 cores |")
    out.append(f"| peak working memory beyond the inputs | "
               f"{results['peak_working_mib']:.0f} MiB | two RGB float images "
               f"= {results['two_rgb_images_mib']:.0f} MiB |")
    out += ["", "## Every run", "",
            "| tag | method | size | coverage | radius | threads | simd | s | "
            "ns/scattering px | peak MiB |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['tag']} | {r['method']} | {r['width']:.0f}x{r['rows']:.0f} | "
                   f"{r['coverage']:.2f} | {r['radius_px']:.0f} | {r['threads']:.0f} | "
                   f"{r['simd']} | {r['seconds']:.4f} | {r['ns_per_scattering_px']:.1f} | "
                   f"{r['rss_peak_mib']:.0f} |")
    out += ["", "## Other figures", ""]
    out += [f"- {k}: {v:.4g}" if isinstance(v, float) else f"- {k}: {v}"
            for k, v in results.items()]
    return "\n".join(out) + "\n"


def main():
    p = argparse.ArgumentParser(prog="run_bench.py")
    p.add_argument("--out", default=os.path.join(ROOT, "out", "bench"))
    p.add_argument("--build", default=os.path.join(ROOT, "build"))
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)
    b = Bench(args.build)
    results = {}
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="sss-bench-") as tmp:
        ratios(b, results)
        grid(b)
        end_to_end(b, args.build, tmp, results)
        bilateral(b, tmp, results)
        real_render(args.build, tmp, results)
        retune(args.build, tmp, results)
        f12(args.build, tmp, results,
            [k for k in os.environ.get("F12_SCENES", " ".join(F12_SCENES))
             .split() if k])
    with open(os.path.join(args.out, "bench.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["tag"] + FIELDS)
        w.writeheader()
        w.writerows(b.rows)
    md = markdown(b.rows, results)
    with open(os.path.join(args.out, "bench.md"), "w") as f:
        f.write(md)
    plot(b.rows, os.path.join(args.out, "bench.png"))
    print(md.split("## Every run")[0])
    log(f"wrote {args.out}/bench.csv, bench.md, bench.png "
        f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    sys.exit(main())
