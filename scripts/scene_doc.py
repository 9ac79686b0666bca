"""Adds to docs/scene.md's material tables a row for every field of the
library's material schema (sss_material_field) that has none yet, made
from the field's row in csrc/sss_fields.h: type, unit (the help's leading
"metres" or "mm"), default, range, and the member with the help. Rows
already there are left as they are (their prose is the document's own;
tests/test_scene.c checks their type, default, range and member against
the schema). A new material field is then its schema row, its struct
member and, if artists set it, its line in the panel: `make scene-doc`
writes its documentation.

    SSS_LIB=build/libsss.so python3 scripts/scene_doc.py [docs/scene.md]

Prints the rows it added; writes the file only when it changed."""
import importlib.util
import os
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(__file__), ".."))


def _native():
    """The add-on's ctypes module, loaded on its own (it needs no bpy)."""
    path = os.path.join(ROOT, "addon", "separable_sss", "native.py")
    spec = importlib.util.spec_from_file_location("sss_native", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


TYPES = {"float": "number", "double": "number", "rgb": "RGB", "int": "integer",
         "enum": "string"}


def cells(field, member):
    """The row's cells as tests/test_scene.c expects them to start."""
    kind, d = field["type"], field["default"]
    if kind == "enum":
        default = next((f'`"{n}"`' for n, v in field["names"] if v == int(d)),
                       "")
        span = ", ".join(f'`"{n}"`' for n, _ in field["names"])
    else:
        default = ("[%g, %g, %g]" % tuple(d) if kind == "rgb" else
                   "%d" % int(d) if kind == "int" else "%g" % d)
        each = "each " if kind == "rgb" else ""
        if kind == "int" or field["hi"] < 1e30:
            span = "%s%g .. %g" % (each, field["lo"], field["hi"])
        else:
            span = "%s%s %g" % (each, ">" if field["lo_open"] else ">=",
                                field["lo"])
    help_text = field["help"]
    unit = next((u for u in ("metres", "mm") if help_text.startswith(u)), "")
    return [f"`{field['key']}`", TYPES.get(kind, kind), unit, default, span,
            f"`{member}`: {help_text}"]


def table_end(lines, start, heading):
    """The index after the last row of the first table after the line
    starting with heading (from start), or None."""
    i = next((k for k in range(start, len(lines))
              if lines[k].startswith(heading)), None)
    if i is None:
        return None
    while i < len(lines) and not lines[i].startswith("| key |"):
        i += 1
    while i < len(lines) and lines[i].startswith("|"):
        i += 1
    return i


def main(argv):
    path = argv[1] if len(argv) > 1 else os.path.join(ROOT, "docs",
                                                     "scene.md")
    native = _native()
    fields = native.material_fields()
    profiles = {kind: name for name, kind in native.profiles().items()}
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    section = next(k for k, line in enumerate(lines)
                   if line.startswith("### `materials[]`"))
    added = []
    for member, field in fields.items():
        if any(line.startswith(f"| `{field['key']}` |")
               for line in lines[section:]):
            continue
        if field["profile"] >= 0:
            heading = f'`"{profiles[field["profile"]]}"`'
        elif field["transmits"]:
            heading = "Transmission ("
        else:
            heading = "Keys for every profile"
        end = table_end(lines, section, heading)
        if end is None:
            raise SystemExit(f"scene_doc: {path} has no table under "
                             f"{heading!r} for '{field['key']}'")
        row = "| " + " | ".join(cells(field, member)) + " |"
        lines.insert(end, row)
        added.append(row)
    if added:
        tmp = path + ".tmp"
        with open(tmp, "w", encoding="utf-8") as f:
            f.write("\n".join(lines))
        os.replace(tmp, path)
    for row in added:
        print("scene_doc: added", row)
    if not added:
        print("scene_doc: every material field has its row")


if __name__ == "__main__":
    main(sys.argv)
