"""scripts/scene_doc.py: docs/scene.md's row for a material field made
from the library's schema."""
import os
import subprocess
import sys

import pytest

from conftest import BUILD, ROOT

SCRIPT = ROOT / "scripts" / "scene_doc.py"
DOC = ROOT / "docs" / "scene.md"
LIB = BUILD / "libsss.so"

# The script loads the library into Python (ctypes): a sanitizer build's
# runtime would have to come first in the process, which Python's cannot.
pytestmark = pytest.mark.skipif(
    LIB.exists() and b"__asan_init" in LIB.read_bytes(),
    reason="the library is a sanitizer build; make test runs this with the "
    "plain one")


def run(path):
    env = {**os.environ, "SSS_LIB": str(LIB)}
    return subprocess.run([sys.executable, str(SCRIPT), str(path)], env=env,
                          capture_output=True, text=True, timeout=60)


def test_every_field_has_its_row(tmp_path):
    doc = tmp_path / "scene.md"
    doc.write_bytes(DOC.read_bytes())
    proc = run(doc)
    assert proc.returncode == 0, proc.stderr
    assert "every material field has its row" in proc.stdout
    assert doc.read_bytes() == DOC.read_bytes()


def test_missing_row_is_written_in_its_profiles_table(tmp_path):
    lines = DOC.read_text(encoding="utf-8").split("\n")
    kept = [line for line in lines if not line.startswith("| `balance` |")]
    assert len(kept) == len(lines) - 1
    doc = tmp_path / "scene.md"
    doc.write_text("\n".join(kept), encoding="utf-8")
    proc = run(doc)
    assert proc.returncode == 0, proc.stderr
    out = doc.read_text(encoding="utf-8").split("\n")
    row = next(line for line in out if line.startswith("| `balance` |"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[1:2] + cells[3:5] == ["number", "0.5", "0 .. 1"]
    assert cells[5].startswith("`near_far_balance`: ")
    # In the near-far profile's table, after its other rows.
    at = out.index(row)
    start = next(i for i, line in enumerate(out)
                 if line.startswith('`"near-far"`'))
    end = next(i for i in range(start, len(out))
               if out[i].startswith("`\"none\"`"))
    assert start < at < end
    assert out[at - 1].startswith("| `far_sigma` |")
