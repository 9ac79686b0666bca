"""Shared fixtures: the built `sss` command and a real Blender render."""
import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("SSS_BUILD", ROOT / "build"))
SSS = BUILD / "sss"


@pytest.fixture(scope="session")
def sss_cmd():
    if not SSS.exists():
        pytest.fail(f"{SSS} is missing: run make first")
    return str(SSS)


@pytest.fixture(scope="session")
def blender_render(tmp_path_factory):
    """A 64x64 Cycles render of blender_scripts/make_test_scene.py."""
    blender = shutil.which("blender")
    if not blender:
        pytest.skip("blender is not installed (make test installs it)")
    out = tmp_path_factory.mktemp("render")
    proc = subprocess.run(
        [blender, "-b", "--factory-startup", "--python-exit-code", "1",
         "--python", str(ROOT / "blender_scripts" / "make_test_scene.py"),
         "--", "--out", str(out)],
        capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    return out


def run(cmd, *args, check=None):
    """Runs the command; check=0/1/2 asserts the exit status."""
    proc = subprocess.run([cmd, *map(str, args)], capture_output=True,
                          text=True, timeout=600)
    if check is not None:
        assert proc.returncode == check, (proc.returncode, proc.stdout,
                                          proc.stderr)
    return proc
