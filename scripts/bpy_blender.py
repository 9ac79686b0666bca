"""Blender's command line for Blender as a Python module (PyPI's `bpy`),
so that `make demo`, `make compare` and the Blender tests run the same
commands on the `bpy` builds as on a `blender` binary:

    python bpy_blender.py -b [--factory-startup] [FILE.blend]
        [--python-exit-code N] [--python SCRIPT | --python-expr EXPR]
        [-E ENGINE] [-o PATH] [-s N] [-e N] [-f N[,N..] | -a] [-- ARGS]

Arguments are handled in order, as Blender does; sys.argv inside a script
is the whole command line, so scripts find their own arguments after `--`.
The module always runs in the background with factory settings (user
preferences are not read), so -b and --factory-startup change nothing.
"""
import os
import runpy
import sys
import traceback

import bpy

NO_VALUE = {"-b", "--background", "--factory-startup", "-noaudio",
            "--disable-autoexec", "-Y", "--enable-autoexec", "-y"}


def fail(message):
    print(f"bpy_blender: {message}", file=sys.stderr, flush=True)
    sys.exit(1)


def frames(spec, scene):
    """Blender's -f syntax: N, N,M, N..M; + and - are relative to start
    and end."""
    out = []
    for part in spec.split(","):
        lo, _, hi = part.partition("..")
        ends = []
        for text in (lo, hi) if hi else (lo,):
            if text.startswith("+"):
                ends.append(scene.frame_start + int(text[1:]))
            elif text.startswith("-"):
                ends.append(scene.frame_end - int(text[1:]))
            else:
                ends.append(int(text))
        out.extend(range(ends[0], ends[-1] + 1))
    return out


def render_frames(numbers):
    """Each frame as a one-frame animation render, as Blender's -f does: the
    file is written and render_write handlers run."""
    scene = bpy.context.scene
    saved = scene.frame_start, scene.frame_end
    try:
        for n in numbers:
            scene.frame_start = scene.frame_end = n
            bpy.ops.render.render(animation=True)
    finally:
        scene.frame_start, scene.frame_end = saved


TAKES_VALUE = {"--python-exit-code", "--python", "-P", "--python-expr",
               "-E", "--engine", "-o", "--render-output", "-s",
               "--frame-start", "-e", "--frame-end", "-t", "--threads",
               "-f", "--render-frame", "--addons"}


def run_script(arg, value, exit_code):
    """A script's exception ends the process only with --python-exit-code;
    sys.exit() inside it always does, as in Blender."""
    try:
        if arg == "--python-expr":
            exec(compile(value, "<expr>", "exec"), {"__name__": "__main__"})
        else:
            runpy.run_path(value, run_name="__main__")
    except SystemExit as e:
        code = e.code if isinstance(e.code, int) else \
            (0 if e.code is None else 1)
        if code:
            sys.exit(code)
    except Exception:
        traceback.print_exc()
        if exit_code:
            sys.exit(exit_code)


def main(argv):
    print(f"Blender {bpy.app.version_string} (bpy module)", flush=True)
    exit_code = 0          # --python-exit-code: 0 means carry on
    i = 0
    while i < len(argv):
        arg = argv[i]
        i += 1
        if arg == "--":
            break
        if arg in NO_VALUE:
            continue
        value = None
        if arg in TAKES_VALUE:
            if i == len(argv):
                fail(f"{arg} needs a value")
            value = argv[i]
            i += 1
        scene = bpy.context.scene
        if arg == "--python-exit-code":
            exit_code = int(value)
        elif arg in ("--python", "-P", "--python-expr"):
            run_script(arg, value, exit_code)
        elif arg in ("-E", "--engine"):
            scene.render.engine = value
        elif arg in ("-o", "--render-output"):
            scene.render.filepath = value
        elif arg in ("-s", "--frame-start"):
            scene.frame_start = int(value)
        elif arg in ("-e", "--frame-end"):
            scene.frame_end = int(value)
        elif arg in ("-t", "--threads"):
            scene.render.threads_mode = "FIXED" if int(value) else "AUTO"
            if int(value):
                scene.render.threads = int(value)
        elif arg in ("-f", "--render-frame"):
            render_frames(frames(value, scene))
        elif arg in ("-a", "--render-anim"):
            bpy.ops.render.render(animation=True)
        elif arg == "--addons":
            import addon_utils
            for name in value.split(","):
                addon_utils.enable(name, default_set=True)
        elif arg.startswith("-"):
            fail(f"unknown option {arg}")
        else:
            path = os.path.abspath(arg)
            if not os.path.exists(path):
                fail(f"cannot read file {path!r}")
            bpy.ops.wm.open_mainfile(filepath=path)
    return 0


def exit_now(code):
    """Ends the process without Python's shutdown: the bpy module can hang
    in its exit handlers (a condition variable destroyed while its thread
    still waits on it), which Blender's own binary never runs into."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(code)


if __name__ == "__main__":
    # What a script runs to start this Blender again (bpy.app.binary_path
    # is empty in the module): the wrapper install-bpy.sh writes.
    wrapper = os.path.join(os.path.dirname(sys.executable), "blender")
    if os.access(wrapper, os.X_OK):
        os.environ["SSS_BLENDER"] = wrapper
    try:
        code = main(sys.argv[1:])
    except SystemExit as e:
        code = e.code if isinstance(e.code, int) else \
            (0 if e.code is None else 1)
        if not isinstance(e.code, int) and e.code is not None:
            print(e.code, file=sys.stderr)
    except BaseException:
        traceback.print_exc()
        code = 1
    exit_now(code)
