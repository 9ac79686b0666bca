"""The farm integrations run for real: the OpenJD template through
`openjd check` and `openjd run` (PyPI's openjd-cli, build/openjd), and the
Flamenco job type compiled under Node by tests/farm/flamenco_harness.js (our
implementation of Flamenco's job compiler globals: the job type is tested,
not a Flamenco Manager), its tasks' commands run here in dependency order.
Each on a 3-frame job in 2 chunks of a small bundled scene, in Blender 3.4,
4.5 and 5.0; every frame must equal the add-on's own result for that frame
(blender_scripts/render_sss.py), a re-run redoes only what is missing, and a
frame that cannot be scattered fails with the library's message while the
other frames are written."""
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("SSS_BUILD", ROOT / "build"))
SSS = BUILD / "sss"
OPENJD = BUILD / "openjd" / "bin" / "openjd"
TEMPLATE = ROOT / "farm" / "openjd" / "sss_job.yaml"
JOB_TYPE = ROOT / "farm" / "flamenco" / "sss.js"
HARNESS = ROOT / "tests" / "farm" / "flamenco_harness.js"
FRAMES = (1, 2, 3)

sys.path.insert(0, str(ROOT / "tests" / "python"))
from exr import read_channels  # noqa: E402

BLENDERS = {"3.4": "blender",
            "4.5": str(BUILD / "bpy-4.5.15" / "bin" / "blender"),
            "5.0": str(BUILD / "bpy-5.0.1" / "bin" / "blender")}


def need(path, what):
    if not (shutil.which(str(path)) or Path(path).exists()):
        pytest.fail(f"{path} is missing ({what}); make farm-test installs it")
    return str(path)


def run(cmd, env=None, check=True):
    proc = subprocess.run([str(c) for c in cmd], capture_output=True,
                          text=True, timeout=600, env=env)
    log = proc.stdout + proc.stderr
    if check:
        assert proc.returncode == 0, log[-6000:]
    return proc.returncode, log


def checkout_env(tmp=None):
    """The environment of a run from the checkout; with tmp, a private
    temporary folder (render_sss.py keeps its working files in the add-on's
    default folder under it)."""
    env = dict(os.environ)
    env["SSS_LIB"] = str(BUILD / "libsss.so")
    if tmp:
        Path(tmp).mkdir(parents=True, exist_ok=True)
        env["TMPDIR"] = str(tmp)
    return env


def channels(path):
    return read_channels(path)[0]


def out_path(out, frame):
    return Path(out) / f"shot_{frame:04d}.exr"


def passes_path(out, frame):
    return Path(out) / "passes" / f"shot_{frame:04d}.exr"


@pytest.fixture(scope="module", params=sorted(BLENDERS))
def shot(request, tmp_path_factory):
    """The bundled two-material scene, tiny, with Cycles' seed animated so
    that every frame differs, and the add-on's own result per frame."""
    version = request.param
    blender = need(BLENDERS[version], f"Blender {version}")
    need(SSS, "make")
    work = tmp_path_factory.mktemp(f"farm-{version}")
    blend = work / "shot.blend"
    run([blender, "-b", "--factory-startup", "--python-exit-code", "1",
         "--python", ROOT / "blender_scripts" / "build_scene.py",
         "--python-expr", "import bpy; bpy.context.scene.cycles."
         "use_animated_seed = True; bpy.ops.wm.save_mainfile()",
         "--", "--kind", "two", "--out", blend, "--size", "24",
         "--samples", "4"])
    ref = work / "ref"
    run([blender, "-b", blend, "--python-exit-code", "1", "--python",
         ROOT / "blender_scripts" / "render_sss.py", "--",
         "--output", ref / "ref_####.exr", "--frames", "1-3"],
        env=checkout_env(work / "tmp"))
    refs = {f: channels(ref / f"ref_{f:04d}.exr") for f in FRAMES}
    # The frames differ: a frame written under another's number is caught.
    assert not np.array_equal(refs[1]["SSS.Combined.R"],
                              refs[2]["SSS.Combined.R"])
    return {"version": version, "blender": blender, "blend": blend,
            "work": work, "refs": refs}


def assert_frame(shot, out, frame):
    """The frame has the SSS layer and equals the add-on's own result: every
    channel (the passes and the SSS layer), bit for bit."""
    got = channels(out_path(out, frame))
    want = shot["refs"][frame]
    assert {"SSS.Combined.R", "SSS.Combined.A", "SSS.DiffLight.R"} <= set(got)
    assert sorted(got) == sorted(want)
    for name in want:
        assert np.array_equal(got[name], want[name]), (frame, name)


def stamps(out):
    return {f: (out_path(out, f).stat().st_ino, out_path(out, f).stat()
                .st_mtime_ns) for f in FRAMES if out_path(out, f).exists()}


def no_leftovers(out):
    """Nothing but the frames, their passes and descriptions: no temporary
    file or work folder stays behind."""
    names = sorted(p.name for p in Path(out).rglob("*"))
    allowed = re.compile(r"^(passes|shot_\d{4}\.exr|shot_\d{4}_scene\.json)$")
    assert all(allowed.match(n) for n in names), names


def break_passes(out, frame):
    """Cuts a frame's passes short (as a full disk would) and returns what
    the library says about them."""
    p = passes_path(out, frame)
    p.write_bytes(p.read_bytes()[:2000])
    code, log = run([SSS, p, "-o", Path(out) / "probe.exr", "--scene",
                     p.with_name(p.stem + "_scene.json")], check=False)
    assert code == 1
    message = [line for line in log.splitlines()
               if line.startswith("sss: error:")]
    assert message, log
    return message[0]


# ------------------------------------------------------------------ OpenJD

def openjd(shot, out, check=True):
    """`openjd run` of the template: frames 1-3 in chunks of 2. On 3.4 the
    executables are the defaults (blender and sss on PATH); on 4.5 they are
    given as parameters."""
    cmd = [need(OPENJD, "openjd-cli"), "run", TEMPLATE,
           "-p", f"BlendFile={shot['blend']}", "-p", "Frames=1-3",
           "-p", "ChunkSize=2", "-p", f"OutputDir={out}",
           "-p", f"AddonCheckout={ROOT}"]
    env = checkout_env()
    if shot["version"] == "3.4":
        env["PATH"] = f"{BUILD}{os.pathsep}{env['PATH']}"
    else:
        cmd += ["-p", f"BlenderExecutable={shot['blender']}",
                "-p", f"SssExecutable={SSS}"]
    code, log = run(cmd, env=env, check=False)
    if check:
        assert code == 0, log[-6000:]
    return code, log


def chunks_run(log):
    return re.findall(r"Frame\(CHUNK\[INT\]\) = (\S+)", log)


def rendered(log):
    """The frames Blender rendered (the add-on's farm task's lines)."""
    return sorted(int(m) for m in re.findall(
        r"farm: frame (\d+): \S+ \(render", log))


def scattered(log):
    return sorted(int(m) for m in re.findall(
        r"-> \S+shot_(\d{4})\.exr: read", log))


def test_openjd_check():
    code, log = run([need(OPENJD, "openjd-cli"), "check", TEMPLATE])
    assert "passes validation checks" in log


@pytest.fixture(scope="module")
def openjd_job(shot):
    out = shot["work"] / "openjd"
    code, log = openjd(shot, out)
    return out, log


def test_openjd_run(shot, openjd_job):
    out, log = openjd_job
    assert chunks_run(log) == ["1-2", "3-3"], log[-3000:]
    assert rendered(log) == [1, 2, 3] and scattered(log) == [1, 2, 3]
    for f in FRAMES:
        assert_frame(shot, out, f)
    no_leftovers(out)


def test_openjd_rerun_redoes_only_the_missing(shot, openjd_job, tmp_path):
    out = tmp_path / "out"
    shutil.copytree(openjd_job[0], out)
    out_path(out, 2).unlink()
    before = stamps(out)
    code, log = openjd(shot, out)
    assert rendered(log) == [] and scattered(log) == [2], log[-3000:]
    assert "shot_0001.exr: exists, skipped (--resume)" in log
    after = stamps(out)
    assert after[1] == before[1] and after[3] == before[3]
    assert_frame(shot, out, 2)
    # Without its passes either, the frame is rendered again, alone.
    out_path(out, 3).unlink()
    passes_path(out, 3).unlink()
    code, log = openjd(shot, out)
    assert rendered(log) == [3] and scattered(log) == [3], log[-3000:]
    assert_frame(shot, out, 3)
    no_leftovers(out)


def test_openjd_frame_that_cannot_be_scattered(shot, openjd_job, tmp_path):
    out = tmp_path / "out"
    shutil.copytree(openjd_job[0], out)
    message = break_passes(out, 1)
    (out / "probe.exr").unlink(missing_ok=True)
    for f in (1, 2):
        out_path(out, f).unlink()
    before = stamps(out)
    code, log = openjd(shot, out, check=False)
    assert code != 0
    assert message in log, (message, log[-3000:])
    assert "Session ended with errors" in log
    assert not out_path(out, 1).exists()
    assert_frame(shot, out, 2)
    assert stamps(out)[3] == before[3]
    no_leftovers(out)


def test_openjd_path_mapping(shot, tmp_path):
    """Paths as the submitting machine wrote them (/studio/...), mapped to
    this worker's by path mapping rules, as a farm's worker applies them:
    the .blend, the output folder and the checkout are all mapped."""
    rules = {"version": "pathmapping-1.0", "path_mapping_rules": [
        {"source_path_format": "POSIX", "source_path": "/studio/shots",
         "destination_path": str(shot["work"])},
        {"source_path_format": "POSIX", "source_path": "/studio/renders",
         "destination_path": str(tmp_path)},
        {"source_path_format": "POSIX", "source_path": "/studio/libsss",
         "destination_path": str(ROOT)}]}
    code, log = run([need(OPENJD, "openjd-cli"), "run", TEMPLATE,
                     "--path-mapping-rules", json.dumps(rules),
                     "-p", "BlendFile=/studio/shots/shot.blend",
                     "-p", "Frames=3", "-p", "OutputDir=/studio/renders/out",
                     "-p", "AddonCheckout=/studio/libsss",
                     "-p", f"BlenderExecutable={shot['blender']}",
                     "-p", f"SssExecutable={SSS}"], env=checkout_env())
    assert rendered(log) == [3], log[-3000:]
    assert_frame(shot, tmp_path / "out", 3)


def test_openjd_samples_and_method(shot, tmp_path):
    """Samples and Method reach the render and the library: frame 1 equals
    render_sss.py's with the same --samples and --method, and differs from
    the scene's own settings."""
    out = tmp_path / "out"
    code, log = run([need(OPENJD, "openjd-cli"), "run", TEMPLATE,
                     "-p", f"BlendFile={shot['blend']}", "-p", "Frames=1",
                     "-p", "ChunkSize=1", "-p", f"OutputDir={out}",
                     "-p", "Samples=2", "-p", "Method=disk",
                     "-p", f"AddonCheckout={ROOT}",
                     "-p", f"BlenderExecutable={shot['blender']}",
                     "-p", f"SssExecutable={SSS}"], env=checkout_env())
    assert "Skin disk" in log, log[-3000:]
    run([shot["blender"], "-b", shot["blend"], "--python-exit-code", "1",
         "--python", ROOT / "blender_scripts" / "render_sss.py", "--",
         "--output", tmp_path / "ref.exr", "--frames", "1", "--samples", "2",
         "--method", "disk"], env=checkout_env(tmp_path / "tmp"))
    got, want = channels(out_path(out, 1)), channels(tmp_path / "ref.exr")
    assert sorted(got) == sorted(want)
    for name in want:
        assert np.array_equal(got[name], want[name]), name
    assert not np.array_equal(got["SSS.Combined.R"],
                              shot["refs"][1]["SSS.Combined.R"])


def test_embedded_copies_equal_the_files():
    """The template's embedded files and the job type's ADDON_BOOTSTRAP are
    farm/sss_chunk.sh and farm/sss_addon.py, character for character."""
    code, text = run([OPENJD.parent / "python", "-c",
                      "import json, sys, yaml; t = yaml.safe_load(open(sys.argv[1]));"
                      " print(json.dumps({f['filename']: f['data'] for f in"
                      " t['steps'][0]['script']['embeddedFiles']}))", TEMPLATE])
    embedded = json.loads(text)
    files = {name: (ROOT / "farm" / name).read_text()
             for name in ("sss_chunk.sh", "sss_addon.py")}
    assert embedded == files
    js = JOB_TYPE.read_text()
    bootstrap = re.search(r"const ADDON_BOOTSTRAP = `(.*?)`;", js, re.S)[1]
    assert bootstrap == files["sss_addon.py"]


def test_chunk_script_alone(shot, tmp_path):
    """farm/sss_chunk.sh run by hand from a checkout (what a Deadline 10,
    OpenCue or cron task runs): frames 2-3, then again, which does
    nothing."""
    out = tmp_path / "out"
    cmd = ["bash", ROOT / "farm" / "sss_chunk.sh", shot["blend"], out, "2-3",
           "0", "scene", shot["blender"], SSS, ROOT]
    code, log = run(cmd, env=checkout_env())
    assert rendered(log) == [2, 3] and scattered(log) == [2, 3], log[-3000:]
    for f in (2, 3):
        assert_frame(shot, out, f)
    before = stamps(out)
    code, log = run(cmd, env=checkout_env())
    assert rendered(log) == [] and scattered(log) == [], log[-3000:]
    assert stamps(out) == before
    no_leftovers(out)


def test_method_choices_are_the_librarys():
    """The template's and the job type's Method choices are `scene` and the
    methods `sss --help` lists."""
    code, text = run([SSS, "--help"])
    listed = re.findall(r"^  ([a-z-]+)  ", text.split("\nmethods:\n")[1],
                        re.M)
    assert listed[:2] == ["auto", "separable"], text
    code, text = run([OPENJD.parent / "python", "-c",
                      "import json, sys, yaml; t = yaml.safe_load(open(sys.argv[1]));"
                      " print(json.dumps([p for p in t['parameterDefinitions']"
                      " if p['name'] == 'Method'][0]['allowedValues']))", TEMPLATE])
    assert json.loads(text) == ["scene", *listed]
    js = re.search(r'choices: (\[[^\]]*\])', JOB_TYPE.read_text())[1]
    assert json.loads(js) == ["scene", *listed]


# ---------------------------------------------------------------- Flamenco

def compile_job(shot, out, **settings):
    """The job type compiled as a Manager would: JSON tasks."""
    node = need("node", "Debian's nodejs")
    given = {"frames": "1-3", "chunk_size": 2, "output_dir": str(out),
             "blendfile": str(shot["blend"]), "addon_checkout": str(ROOT),
             "sss": str(SSS), **settings}
    variables = {"blender": shot["blender"], "blenderArgs": "-b -y"}
    code, text = run([node, HARNESS, JOB_TYPE, json.dumps(given),
                      json.dumps(variables)])
    return json.loads(text)


def command_line(command):
    """A command as Flamenco's Worker runs it."""
    p = command["parameters"]
    if command["name"] == "blender-render":
        return [p["exe"], *shlex.split(p.get("exeArgs", "")),
                *p["argsBefore"], *([p["blendfile"]] if p["blendfile"]
                                    else []), *p["args"]]
    assert command["name"] == "exec", command
    return [p["exe"], *p["args"]]


def run_tasks(job):
    """Every task in dependency order, each command in turn; a failed
    command fails its task, and a task whose dependency failed is not run.
    Returns {task name: (status, log)}."""
    results, tasks = {}, list(job["tasks"])
    while tasks:
        ready = [t for t in tasks
                 if all(d in results for d in t["dependencies"])]
        assert ready, "the tasks' dependencies form a cycle"
        for task in ready:
            tasks.remove(task)
            if any(results[d][0] != "completed" for d in task["dependencies"]):
                results[task["name"]] = ("skipped", "")
                continue
            status, logs = "completed", []
            for command in task["commands"]:
                code, log = run(command_line(command), env=checkout_env(),
                                check=False)
                logs.append(log)
                if code != 0:
                    status = "failed"
                    break
            results[task["name"]] = (status, "".join(logs))
    return results


def test_flamenco_job_type_compiles(shot, tmp_path):
    job = compile_job(shot, tmp_path, samples=3, method="separable",
                      frames="1-3,7", chunk_size=3)
    names = [t["name"] for t in job["tasks"]]
    assert names == ["render-1-3", "sss-1", "sss-2", "sss-3", "render-7",
                     "sss-7"]
    render = job["tasks"][0]
    assert render["type"] == "blender" and render["dependencies"] == []
    line = command_line(render["commands"][0])
    assert line[:4] == [shot["blender"], "-b", "-y", str(shot["blend"])]
    assert line[line.index("--frames") + 1] == "1-3"
    assert line[line.index("--samples") + 1] == "3"
    assert line[line.index("--method") + 1] == "separable"
    assert job["tasks"][5]["dependencies"] == ["render-7"]
    assert command_line(job["tasks"][5]["commands"][0]) == [
        str(SSS), str(passes_path(tmp_path, 7)), "-o",
        str(out_path(tmp_path, 7)), "--scene",
        str(passes_path(tmp_path, 7)).replace(".exr", "_scene.json"),
        "--resume"]


@pytest.fixture(scope="module")
def flamenco_job(shot):
    out = shot["work"] / "flamenco"
    results = run_tasks(compile_job(shot, out))
    return out, results


def test_flamenco_tasks_run(shot, flamenco_job):
    out, results = flamenco_job
    assert sorted(results) == ["render-1-2", "render-3", "sss-1", "sss-2",
                               "sss-3"]
    assert all(s == "completed" for s, _ in results.values()), results
    assert rendered(results["render-1-2"][1]) == [1, 2]
    assert rendered(results["render-3"][1]) == [3]
    for f in FRAMES:
        assert_frame(shot, out, f)
    no_leftovers(out)


def test_flamenco_rerun_and_failure(shot, flamenco_job, tmp_path):
    out = tmp_path / "out"
    shutil.copytree(flamenco_job[0], out)
    out_path(out, 2).unlink()
    before = stamps(out)
    results = run_tasks(compile_job(shot, out))
    assert all(s == "completed" for s, _ in results.values()), results
    assert rendered("".join(log for _, log in results.values())) == []
    assert scattered(results["sss-2"][1]) == [2]
    assert "exists, skipped (--resume)" in results["sss-1"][1]
    after = stamps(out)
    assert after[1] == before[1] and after[3] == before[3]
    assert_frame(shot, out, 2)

    message = break_passes(out, 1)
    (out / "probe.exr").unlink(missing_ok=True)
    for f in (1, 2):
        out_path(out, f).unlink()
    results = run_tasks(compile_job(shot, out))
    status = {name: s for name, (s, _) in results.items()}
    assert status == {"render-1-2": "completed", "render-3": "completed",
                      "sss-1": "failed", "sss-2": "completed",
                      "sss-3": "completed"}
    assert message in results["sss-1"][1]
    assert not out_path(out, 1).exists()
    assert_frame(shot, out, 2)
    no_leftovers(out)


# ------------------------------------------------- the add-on, installed

def install_addon(shot, home):
    """The add-on as an artist installs it, in an empty user folder: the
    extension with Blender's own operator on 4.5 (its library in the wheel),
    the legacy zip unpacked into the user add-ons on 3.4 (its library
    beside it). Returns the environment that Blender then runs in and the
    add-on's module name."""
    env = {k: v for k, v in os.environ.items() if k != "SSS_LIB"}
    if shot["version"] == "3.4":
        with zipfile.ZipFile(BUILD / "separable_sss.zip") as z:
            z.extractall(home / "scripts" / "addons")
        env["BLENDER_USER_SCRIPTS"] = str(home / "scripts")
        return env, "separable_sss", home / "scripts" / "addons"
    env["BLENDER_USER_RESOURCES"] = str(home / "resources")
    zips = sorted(BUILD.glob("separable_sss-*-linux-*.zip"))
    assert len(zips) == 1, zips
    run([shot["blender"], "-b", "--python-exit-code", "1", "--python-expr",
         "import bpy; assert bpy.ops.extensions.package_install_files("
         f"filepath={str(zips[0])!r}, repo='user_default') == {{'FINISHED'}}"],
        env=env)
    return env, "bl_ext.user_default.separable_sss", home / "resources"


def test_installed_addon(shot, tmp_path):
    """AddonCheckout empty: the add-on installed in the worker's Blender
    renders the passes with its own library, and the frame equals the
    add-on's own result."""
    env, module, where = install_addon(shot, tmp_path / "home")
    out = tmp_path / "out"
    code, log = run([need(OPENJD, "openjd-cli"), "run", TEMPLATE,
                     "-p", f"BlendFile={shot['blend']}", "-p", "Frames=2",
                     "-p", "ChunkSize=1", "-p", f"OutputDir={out}",
                     "-p", f"BlenderExecutable={shot['blender']}",
                     "-p", f"SssExecutable={SSS}"], env=env)
    used = re.search(r"farm: add-on (\S+) \((\S+)\), library (\S+)", log)
    assert used, log[-3000:]
    assert used[1] == module
    assert used[2].startswith(str(where)) and used[3].startswith(str(where))
    assert rendered(log) == [2], log[-3000:]
    assert_frame(shot, out, 2)
