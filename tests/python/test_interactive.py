"""The add-on in a real Blender window (Xvfb): what headless tests cannot
reach. Debian's Blender 3.4 only (the bpy module has no windows)."""
import os
import shutil
import subprocess

import numpy as np
import pytest

from conftest import BUILD, ROOT
from exr import read_png


def test_f12_scatters_with_the_switch_on(tmp_path):
    blender, xvfb = shutil.which("blender"), shutil.which("xvfb-run")
    if not blender or not xvfb:
        pytest.skip("needs blender and xvfb-run (make test installs them)")
    if "ASAN_OPTIONS" in os.environ:
        pytest.skip("Blender cannot load the sanitizer build of libsss")
    blend = tmp_path / "two.blend"
    subprocess.run([blender, "-b", "--factory-startup", "--python-exit-code",
                    "1", "--python",
                    str(ROOT / "blender_scripts" / "build_scene.py"), "--",
                    "--kind", "two", "--out", str(blend), "--size", "48",
                    "--samples", "4"], check=True, capture_output=True,
                   timeout=600)
    env = dict(os.environ, SSS_LIB=str(BUILD / "libsss.so"))
    proc = subprocess.run(
        [xvfb, "-a", blender, "--factory-startup", "--enable-event-simulate",
         "--python", str(ROOT / "tests" / "interactive" / "f12.py"), "--",
         str(blend), str(tmp_path)], capture_output=True, text=True,
        timeout=600, env=env)
    log = proc.stdout + proc.stderr
    assert "F12 on: saved" in log and "F12 off: saved" in log, log[-3000:]
    assert "error None; scenes 1" in log, log[-3000:]
    assert log.count("view layer ViewLayer:") == 1, log[-3000:]
    on, off = read_png(tmp_path / "on.png"), read_png(tmp_path / "off.png")
    assert np.abs(on - off).max() > 4 / 255  # SSS shows only when on
