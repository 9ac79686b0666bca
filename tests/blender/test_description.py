"""The add-on asks the library instead of mirroring it: the Method choices
are the library's methods, the scene description it writes is one the
library reads without a warning, and the sizes it shows and sets up come
from the library's own answers."""
import json

import bpy
import pytest

from helpers import build_blend, load_addon, registered

separable_sss = load_addon()
from separable_sss import (analysis, description, native,  # noqa: E402
                           pipeline, properties, transmission)


addon = registered(separable_sss)


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    path = build_blend("two", str(tmp_path_factory.mktemp("b") / "two.blend"))
    bpy.ops.wm.open_mainfile(filepath=path)
    return bpy.context.scene


def write(scene, found, path):
    """As the pipeline does: with the pass indices the render gets."""
    with pipeline.switched_off(scene, found, backlight=False):
        description.write_description(scene, found, path)


def test_method_choices_are_the_librarys():
    names = [name for name, _ in native.methods()]
    assert len(names) >= 5 and "auto" == names[0]
    items = properties.method_items()
    assert [i[0] for i in items] == [n.upper().replace("-", "_")
                                     for n in names]
    assert [i[3] for i in items] == list(range(len(names)))
    assert all(i[2] for i in items)     # the library's summary as tooltip
    for identifier, *_ in items:
        assert description.method_name(identifier) in names


def test_every_method_choice_reaches_the_library(scene, tmp_path):
    found = analysis.analyse(scene)
    for value, (name, _) in enumerate(native.methods()):
        scene.sss.method = name.upper().replace("-", "_")
        path = str(tmp_path / f"{name}.json")
        write(scene, found, path)
        assert json.load(open(path))["method"] == name
        with native.Scene(path) as sc:
            assert sc.warnings == []
    scene.sss.method = "AUTO"


def test_description_is_read_without_warnings(scene, tmp_path):
    found = analysis.analyse(scene)
    assert len(found.materials) == 2
    scene.sss.radius_scale = 1.5
    path = str(tmp_path / "scene.json")
    write(scene, found, path)
    data = json.load(open(path))
    assert data["radius_scale"] == pytest.approx(1.5)
    with native.Scene(path) as sc:
        assert sc.warnings == []
    scene.sss.radius_scale = 1.0


def test_sizes_come_from_the_library(scene):
    found = analysis.analyse(scene).materials[0]
    entry = description.library_material(scene, found)
    scene.sss.radius_scale = 2.0
    assert pipeline.support_metres(scene, found) == pytest.approx(
        2.0 * native.material_support(entry))
    scene.sss.radius_scale = 1.0
    # The back-light layer's thickness reach is the library's answer.
    found.material.sss.transmission = "BEER_LAMBERT"
    found.material.sss.transmission_color = (0.6, 0.3, 0.2)
    entry = description.library_material(scene, found)
    reach = native.transmission_reach(entry)
    assert reach > 0.0
    assert max(native.transmittance(entry, reach)) <= 0.0101
    assert transmission._len_metres(found, scene) == pytest.approx(reach)
    found.material.sss.transmission = "AUTO"


def test_material_properties_are_made_from_the_librarys_schema():
    """Every field of the library's material schema (sss_material_field)
    that artists set is a material setting made from it: its default, its
    range (1e30: no upper bound), its help as the tooltip, and for an enum
    every library name as a choice; the values stored in .blend files stay
    what they were before the settings came from the table."""
    import numpy as np
    fields = native.material_fields()
    rna = properties.SSSMaterialSettings.bl_rna.properties
    offered = [m for m in fields if m not in description.DERIVED]
    assert len(offered) >= 20, offered
    for member in offered:
        f = fields[member]
        prop = rna[description.property_name(member)]
        assert prop.description.lower() == f["help"].lower(), member
        if f["type"] == "enum":
            values = {i.identifier: i.value for i in prop.enum_items}
            for name, value in f["names"]:
                ident = description.identifier(name)
                assert ident in values, (member, name)
                assert description.library_name(ident) == name
            continue
        if f["type"] == "rgb":
            assert list(prop.default_array) == list(
                np.float32(f["default"])), member
        elif f["type"] == "float":
            assert prop.default == np.float32(f["default"]), member
        else:
            assert prop.default == int(f["default"]), member
        assert prop.hard_min > f["lo"] if f["lo_open"] else \
            prop.hard_min == np.float32(f["lo"]), member
        assert prop.hard_max == np.float32(f["hi"]) if f["hi"] < 1e30 \
            else prop.hard_max > 1e30, member
    for member in description.DERIVED:
        assert member in fields and member not in rna.keys()
    # .blend files hold an enum's value: these are the values the settings
    # had before they were made from the table.
    stored = {name: {i.identifier: i.value for i in rna[name].enum_items}
              for name in ("mapping", "transmission", "texturing")}
    assert stored["mapping"] == {
        "AUTO": 0, "CYCLES": 1, "EEVEE": 2, "RANDOM_WALK": 3,
        "CYCLES_RANDOM_WALK": 4, "CYCLES4_RANDOM_WALK": 5}
    assert stored["transmission"] == {
        "AUTO": 5, "OFF": 0, "BURLEY": 1, "JIMENEZ": 2, "BEER_LAMBERT": 3,
        "FAST": 4}
    assert stored["texturing"] == {"POST": 0, "PRE_AND_POST": 1}
    # The profile choices are the library's profiles, with From Material.
    assert {i.identifier for i in rna["profile"].enum_items} == {"BLENDER"} \
        | {description.identifier(n) for n in native.profiles()}


def test_scene_settings_are_the_librarys_options(scene):
    """The scene's Taps is the library's taps option (sss_option_field):
    its range and default; and every top-level key the description writes
    but the camera's is one of the library's options."""
    options = native.option_fields()
    taps = options["taps"]
    prop = properties.SSSSceneSettings.bl_rna.properties["taps"]
    assert taps["type"] == "int" and taps["member"] == "taps"
    assert (prop.hard_min, prop.hard_max, prop.default) == (
        int(taps["lo"]), int(taps["hi"]), int(taps["default"]))
    assert prop.hard_min >= 1 and prop.hard_max > 33
    found = analysis.analyse(scene)
    data = description.scene_description(scene, found)
    written = set(data) - {"version", "camera", "unit_scale", "materials"}
    assert written and written <= set(options), written
    scene.sss.taps = prop.hard_max
    assert description.scene_description(scene, found)["taps"] == \
        prop.hard_max
    scene.sss.taps = int(taps["default"])


def test_material_entries_are_the_schemas_fields(scene):
    """The description's material entry has a key for every field of the
    schema its profile reads (transmission's only while it transmits),
    from the material's setting, and the library reads it as it is."""
    found = analysis.analyse(scene).materials[0]
    s = found.material.sss
    saved = (s.profile, s.transmission, s.taps)
    fields = native.material_fields()
    kinds = native.profiles()
    try:
        for profile in ("BURLEY", "GAUSSIANS", "JIMENEZ", "NEAR_FAR"):
            for model in ("OFF", "FAST"):
                s.profile, s.transmission, s.taps = profile, model, 5
                entry = description.material_entry(found)
                kind = kinds[description.library_name(profile)]
                want = {f["key"] for m, f in fields.items()
                        if m not in description.DERIVED
                        and f["profile"] in (-1, kind)
                        and not (f["transmits"] and model == "OFF")}
                # what the add-on resolves (the calibration and the
                # walk's surface where Match Energy finds a walk)
                got = set(entry) - {"pass_index", "name", "profile"} - {
                    fields[m]["key"] for m in description.DERIVED}
                assert got == want, (profile, model, got ^ want)
                assert entry["taps"] == 5
                assert entry["transmission"] == \
                    description.library_name(model)
                with native.Scene(text=json.dumps(
                        {"version": 1, "materials": [
                            dict(entry, pass_index=1)]})) as sc:
                    assert sc.warnings == [], (profile, model)
        s.taps = 0          # 0: the profile's own, so not written
        assert "taps" not in description.material_entry(found)
    finally:
        s.profile, s.transmission, s.taps = saved


def test_required_passes_are_the_librarys(scene):
    """The passes the add-on turns on and checks for are the library's
    table (sss_render_pass), named as Blender's view layer names them."""
    from separable_sss import switch_off
    table = native.render_passes()
    assert [p["name"] for p in table][:3] == ["DiffDir", "DiffInd",
                                              "DiffCol"]
    layer = scene.view_layers[0]
    for p in table:
        if p["blender"] != "combined":   # always rendered, no switch
            assert hasattr(layer, "use_pass_" + p["blender"]), p
    required = switch_off.required_passes()
    assert set(required) == {"diffuse_direct", "diffuse_indirect",
                             "diffuse_color", "z", "material_index"}
    with pipeline.switched_off(scene, analysis.analyse(scene),
                               backlight=False):
        assert all(getattr(layer, "use_pass_" + p) for p in required)


def test_kernel_width_comes_from_the_camera_model(scene):
    """Found in Scene's blur width uses the library's projection (Blender's
    sensor fit, pixel aspect, unit scale), not a copy of it."""
    cam = scene.camera.data
    render = scene.render
    saved = (cam.type, cam.lens, cam.sensor_width, cam.sensor_fit,
             render.resolution_x, render.resolution_y,
             render.resolution_percentage, render.pixel_aspect_x)
    try:
        cam.type, cam.lens, cam.sensor_width = 'PERSP', 50.0, 36.0
        cam.sensor_fit = 'AUTO'
        render.resolution_x, render.resolution_y = 400, 300
        render.resolution_percentage, render.pixel_aspect_x = 50, 1.0
        ppm = description.camera_pixels_per_metre(scene, 2.0)
        assert ppm == pytest.approx(200 * 50.0 / (36.0 * 2.0), rel=1e-9)
        render.pixel_aspect_x = 2.0     # wider pixels: the fit goes by it
        cam.sensor_fit = 'VERTICAL'
        assert description.camera_pixels_per_metre(scene, 2.0) == \
            pytest.approx(0.5 * 150 * 50.0 / (cam.sensor_height * 2.0),
                          rel=1e-9)
        found = pipeline.analyse(scene).materials[0]
        assert pipeline.kernel_pixels(scene, found) > 0.0
    finally:
        (cam.type, cam.lens, cam.sensor_width, cam.sensor_fit,
         render.resolution_x, render.resolution_y,
         render.resolution_percentage, render.pixel_aspect_x) = saved


def test_a_radius_scale_keeps_the_colour(scene):
    """blender_compat.scale_radius (make sweep) scales the radius the
    description reads and leaves its colour: in 3.x Subsurface is also the
    diffuse / subsurface mix, which Cycles extrapolates past 1, so the
    radius vector is scaled there instead."""
    from separable_sss import blender_compat as compat
    before = pipeline.analyse(scene).materials[0]
    node = before.node
    saved = [tuple(i.default_value) if hasattr(i.default_value, "__len__")
             else i.default_value for i in node.inputs
             if hasattr(i, "default_value")]
    try:
        compat.scale_radius(node, 300.0)
        after = pipeline.analyse(scene).materials[0]
        assert after.radius == pytest.approx(
            [300.0 * r for r in before.radius], rel=1e-5)
        assert after.albedo == pytest.approx(before.albedo, abs=1e-6)
        assert all(0.0 <= a <= 1.0 for a in after.albedo)
    finally:
        values = iter(saved)
        for i in node.inputs:
            if hasattr(i, "default_value"):
                i.default_value = next(values)
