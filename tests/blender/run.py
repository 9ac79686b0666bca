"""Runs pytest inside Blender (bpy is importable only there).

    blender -b --factory-startup --python-exit-code 1 \
        --python tests/blender/run.py -- [pytest arguments]
"""
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import pytest  # noqa: E402

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
code = pytest.main(["-q", "-p", "no:cacheprovider", "--rootdir", HERE] +
                   (argv or [HERE]))
sys.exit(int(code))
