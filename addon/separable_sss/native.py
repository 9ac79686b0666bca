"""The add-on's only ctypes module: loads libsss once, declares every
signature it uses, checks the ABI and struct sizes, and turns status codes
into exceptions with the library's own messages."""
import contextlib
import ctypes
import importlib.util
import json
import os
import platform
import sys
import threading

ABI_VERSION = 15  # must match SSS_ABI_VERSION in csrc/sss.h

_HERE = os.path.dirname(os.path.abspath(__file__))


class LibraryError(Exception):
    """A libsss call failed; str() is the library's message."""

    def __init__(self, code, name, message):
        super().__init__(message)
        self.code = code
        self.name = name


class ExrOptions(ctypes.Structure):
    _fields_ = [("struct_size", ctypes.c_uint32),
                ("max_width", ctypes.c_int32),
                ("max_height", ctypes.c_int32),
                ("max_pixels", ctypes.c_int64),
                ("compression", ctypes.c_int32),
                ("num_threads", ctypes.c_int32),
                ("temporary_fn", ctypes.c_void_p),
                ("temporary_user", ctypes.c_void_p),
                ("progress_fn", ctypes.c_void_p),
                ("progress_user", ctypes.c_void_p),
                ("max_channels", ctypes.c_int32),
                ("max_bytes", ctypes.c_int64)]


# sss_process_options.progress_fn: (stage, share of it done, user)
ProgressFn = ctypes.CFUNCTYPE(None, ctypes.c_char_p, ctypes.c_double,
                              ctypes.c_void_p)


class ProcessOptions(ctypes.Structure):
    _fields_ = [("struct_size", ctypes.c_uint32),
                ("layer", ctypes.c_char_p),
                ("method", ctypes.c_int32),
                ("radius_scale", ctypes.c_float),
                ("num_threads", ctypes.c_int32),
                ("exr", ExrOptions),
                ("samples", ctypes.c_int32),
                ("progress_fn", ProgressFn),
                ("progress_user", ctypes.c_void_p),
                ("chosen_methods", ctypes.POINTER(ctypes.c_int32))]


class Image(ctypes.Structure):
    _fields_ = [("data", ctypes.POINTER(ctypes.c_float)),
                ("width", ctypes.c_int32), ("height", ctypes.c_int32),
                ("channels", ctypes.c_int32), ("row_stride", ctypes.c_int64)]


class FieldInfo(ctypes.Structure):
    _fields_ = [("key", ctypes.c_char_p), ("member", ctypes.c_char_p),
                ("type", ctypes.c_int32), ("profile", ctypes.c_int32),
                ("transmits", ctypes.c_int32),
                ("default_value", ctypes.c_double * 3),
                ("lo", ctypes.c_double), ("hi", ctypes.c_double),
                ("lo_open", ctypes.c_int32), ("name_count", ctypes.c_int32),
                ("help", ctypes.c_char_p)]


class PassInfo(ctypes.Structure):
    _fields_ = [("name", ctypes.c_char_p), ("components", ctypes.c_char_p),
                ("alt", ctypes.c_char_p), ("need", ctypes.c_int32),
                ("blender", ctypes.c_char_p), ("hint", ctypes.c_char_p)]


class Timings(ctypes.Structure):
    _fields_ = [("read", ctypes.c_double), ("scatter", ctypes.c_double),
                ("write", ctypes.c_double)]


# The add-on's Preferences > Library (preferences.py); "" = not set.
_preferred_path = ""


def set_preferred_path(path):
    """The library the add-on's preferences name, tried after $SSS_LIB. A
    library already loaded stays loaded (ctypes cannot unload one): the
    new path counts from the next start of Blender."""
    global _preferred_path
    _preferred_path = path or ""


def loaded_path():
    """The path the library was loaded from, or None."""
    return getattr(_lib, "_name", None) if _lib is not None else None


# The library's file name on each system (sys.platform's start).
LIBRARY_NAMES = (("win32", "libsss.dll"), ("cygwin", "libsss.dll"),
                 ("darwin", "libsss.dylib"), ("", "libsss.so"))


def library_name(system=None):
    """libsss.so, libsss.dll or libsss.dylib, for this system or the given
    sys.platform value."""
    system = sys.platform if system is None else system
    return next(name for prefix, name in LIBRARY_NAMES
                if system.startswith(prefix))


def platform_name():
    """This machine as Blender names platforms (linux-x64, windows-x64,
    macos-arm64, ...), for messages."""
    system = {"win32": "windows", "darwin": "macos"}.get(sys.platform,
                                                        sys.platform)
    machine = platform.machine().lower()
    arch = {"x86_64": "x64", "amd64": "x64", "aarch64": "arm64",
            "arm64": "arm64"}.get(machine, machine)
    return f"{system}-{arch}"


def candidates():
    """Where the library may be: $SSS_LIB, the path in the add-on's
    preferences, beside this file (the legacy zip), in the wheel the
    extension installs (package libsss_native), or the checkout's build
    folder (running from the repository); named for this system."""
    env = os.environ.get("SSS_LIB")
    if env:
        yield env
    if _preferred_path:
        yield _preferred_path
    name = library_name()
    yield os.path.join(_HERE, name)
    spec = importlib.util.find_spec("libsss_native")
    if spec is not None and spec.origin:
        yield os.path.join(os.path.dirname(spec.origin), name)
    yield os.path.normpath(os.path.join(_HERE, "..", "..", "build", name))


_lib = None
_lock = threading.Lock()


def _declare(lib):
    c = ctypes
    sig = {
        "sss_abi_version": (c.c_uint32, []),
        "sss_version_string": (c.c_char_p, []),
        "sss_status_name": (c.c_char_p, [c.c_int32]),
        "sss_status_string": (c.c_char_p, [c.c_int32]),
        "sss_struct_size": (c.c_size_t, [c.c_char_p]),
        "sss_scene_load": (c.c_int32, [c.c_char_p, c.POINTER(c.c_void_p),
                                       c.c_char_p, c.c_size_t, c.c_char_p,
                                       c.c_size_t]),
        "sss_scene_parse": (c.c_int32, [c.c_char_p, c.c_size_t,
                                        c.POINTER(c.c_void_p), c.c_char_p,
                                        c.c_size_t, c.c_char_p, c.c_size_t]),
        "sss_scene_free": (None, [c.c_void_p]),
        "sss_scene_camera": (c.c_void_p, [c.c_void_p]),
        "sss_camera_pixels_per_metre": (c.c_int32, [c.c_void_p, c.c_int32,
                                                    c.c_int32, c.c_double,
                                                    c.POINTER(c.c_double),
                                                    c.c_char_p, c.c_size_t]),
        "sss_scene_materials": (c.c_void_p, [c.c_void_p,
                                             c.POINTER(c.c_int32)]),
        "sss_scene_material_name": (c.c_char_p, [c.c_void_p, c.c_int32]),
        "sss_burley_d": (c.c_int32, [c.c_void_p, c.POINTER(c.c_double)]),
        "sss_material_support": (c.c_int32, [c.c_void_p,
                                             c.POINTER(c.c_double)]),
        "sss_transmittance": (c.c_int32, [c.c_void_p, c.c_double,
                                          c.c_double,
                                          c.POINTER(c.c_double)]),
        "sss_transmission_reach": (c.c_int32, [c.c_void_p,
                                               c.POINTER(c.c_double)]),
        "sss_thin_measured": (c.c_int32, [c.c_void_p, c.POINTER(c.c_int)]),
        "sss_transmission_slab": (c.c_int32, [c.c_void_p] +
                                  [c.POINTER(c.c_double)] * 3),
        "sss_transmission_table": (c.c_int32, [c.c_void_p, c.c_int32,
                                               c.POINTER(c.c_float),
                                               c.POINTER(c.c_double),
                                               c.POINTER(c.c_double)]),
        "sss_method_name": (c.c_char_p, [c.c_int32]),
        "sss_render_pass": (c.c_int32, [c.c_int32, c.POINTER(PassInfo)]),
        "sss_material_field": (c.c_int32, [c.c_int32,
                                           c.POINTER(FieldInfo)]),
        "sss_material_field_name": (c.c_char_p, [c.c_int32, c.c_int32,
                                                 c.POINTER(c.c_int32)]),
        "sss_option_field": (c.c_int32, [c.c_int32, c.POINTER(FieldInfo)]),
        "sss_method_summary": (c.c_char_p, [c.c_int32]),
        "sss_profile_name": (c.c_char_p, [c.c_int32]),
        "sss_process_options_default": (None,
                                        [c.POINTER(ProcessOptions)]),
        "sss_exr_read": (c.c_int32, [c.c_char_p, c.c_void_p,
                                     c.POINTER(c.c_void_p), c.c_char_p,
                                     c.c_size_t]),
        "sss_exr_free": (None, [c.c_void_p]),
        "sss_exr_pass_count": (c.c_int32, [c.c_void_p]),
        "sss_exr_pass": (c.c_int32, [c.c_void_p, c.c_int32,
                                     c.POINTER(c.c_char_p),
                                     c.POINTER(c.c_char_p),
                                     c.POINTER(c.c_char_p),
                                     c.POINTER(Image)]),
        "sss_exr_add_pass": (c.c_int32, [c.c_void_p, c.c_char_p, c.c_char_p,
                                         c.c_char_p, c.POINTER(c.c_float),
                                         c.c_char_p, c.c_size_t]),
        "sss_exr_write": (c.c_int32, [c.c_void_p, c.c_char_p, c.c_void_p,
                                      c.c_char_p, c.c_size_t]),
        "sss_frame_read": (c.c_int32, [c.c_char_p, c.c_char_p,
                                       c.POINTER(ExrOptions),
                                       c.POINTER(c.c_void_p), c.c_char_p,
                                       c.c_size_t]),
        "sss_frame_free": (None, [c.c_void_p]),
        "sss_frame_trim": (None, [c.c_void_p]),
        "sss_frame_width": (c.c_int32, [c.c_void_p]),
        "sss_frame_height": (c.c_int32, [c.c_void_p]),
        "sss_frame_layer": (c.c_char_p, [c.c_void_p]),
        "sss_frame_scatter": (c.c_int32, [c.c_void_p, c.c_void_p,
                                          c.POINTER(ProcessOptions),
                                          c.POINTER(Image), c.POINTER(Image),
                                          c.POINTER(c.c_double), c.c_char_p,
                                          c.c_size_t]),
        "sss_frame_write": (c.c_int32, [c.c_void_p, c.c_char_p,
                                        c.c_void_p, c.c_void_p,
                                        c.POINTER(ExrOptions), c.c_char_p,
                                        c.c_size_t]),
        "sss_exr_options_default": (None, [c.POINTER(ExrOptions)]),
        "sss_process_exr": (c.c_int32, [c.c_char_p, c.c_char_p, c.c_void_p,
                                        c.POINTER(ProcessOptions),
                                        c.POINTER(Timings), c.c_char_p,
                                        c.c_size_t]),
    }
    for name, (restype, argtypes) in sig.items():
        fn = getattr(lib, name)
        fn.restype = restype
        fn.argtypes = argtypes


def library():
    """The loaded library; raises LibraryError with what was tried."""
    global _lib
    with _lock:
        if _lib is not None:
            return _lib
        tried = []
        for path in candidates():
            if not os.path.exists(path):
                tried.append(f"{path} (missing)")
                continue
            try:
                lib = ctypes.CDLL(path)
                _declare(lib)
            except (OSError, AttributeError) as e:
                tried.append(f"{path} ({e})")
                continue
            if lib.sss_abi_version() != ABI_VERSION:
                tried.append(f"{path} (ABI {lib.sss_abi_version()}, add-on "
                             f"needs {ABI_VERSION})")
                continue
            for struct, cls in (("sss_exr_options", ExrOptions),
                                ("sss_process_options", ProcessOptions),
                                ("sss_timings", Timings)):
                if lib.sss_struct_size(struct.encode()) != ctypes.sizeof(cls):
                    raise LibraryError(-1, "ABI", f"{path}: {struct} layout "
                                       "differs from the add-on's")
            _lib = lib
            return lib
        raise LibraryError(-1, "NOT_FOUND", f"libsss ({library_name()}) for "
                           f"{platform_name()} not found: " +
                           "; ".join(tried) + " (install the add-on's zip "
                           f"for {platform_name()}, run make, or set "
                           "SSS_LIB)")


def version():
    return library().sss_version_string().decode()


def _check(code, detail):
    if code != 0:
        lib = library()
        message = (detail.value.decode(errors="replace") if detail
                   is not None else "") or \
            lib.sss_status_string(code).decode()
        raise LibraryError(code, lib.sss_status_name(code).decode(), message)


def methods():
    """[(name, summary)] of the library's methods, in sss_method order (the
    value a method has in sss_options.method is its place here)."""
    lib, out = library(), []
    while lib.sss_method_name(len(out)):
        i = len(out)
        out.append((lib.sss_method_name(i).decode(),
                    lib.sss_method_summary(i).decode()))
    return out


PASS_NEEDS = ("optional", "required", "cycles")  # sss_pass_need's order


def render_passes():
    """[dict] of the render passes the library reads (sss_render_pass):
    name (in the EXR), components, need (PASS_NEEDS), blender (the view
    layer's use_pass_<blender>) and hint (where it is in Blender)."""
    lib = library()
    if lib.sss_struct_size(b"sss_pass_info") != ctypes.sizeof(PassInfo):
        raise LibraryError(-1, "ABI", "sss_pass_info layout differs from "
                           "the add-on's")
    out, info = [], PassInfo()
    while lib.sss_render_pass(len(out), ctypes.byref(info)) == 0:
        out.append({"name": info.name.decode(),
                    "components": info.components.decode(),
                    "need": PASS_NEEDS[info.need],
                    "blender": info.blender.decode(),
                    "hint": info.hint.decode()})
    return out


FIELD_TYPES = ("float", "rgb", "int", "enum", "double")  # sss_field_type's


def _check_field_info(lib):
    if lib.sss_struct_size(b"sss_field_info") != ctypes.sizeof(FieldInfo):
        raise LibraryError(-1, "ABI", "sss_field_info layout differs from "
                           "the add-on's")


def option_fields():
    """{key: dict} of the library's options schema (sss_option_field, the
    scene description's top-level keys, docs/scene.md): member, type
    (FIELD_TYPES; the method is an "enum" named by methods()), default,
    lo, hi, lo_open and help."""
    lib = library()
    _check_field_info(lib)
    out, info, i = {}, FieldInfo(), 0
    while lib.sss_option_field(i, ctypes.byref(info)) == 0:
        out[info.key.decode()] = {
            "member": info.member.decode(), "type": FIELD_TYPES[info.type],
            "default": info.default_value[0], "lo": info.lo, "hi": info.hi,
            "lo_open": bool(info.lo_open), "help": info.help.decode()}
        i += 1
    return out


def material_fields():
    """{member: dict} of the library's material schema (sss_material_field,
    docs/scene.md): key, type (FIELD_TYPES), profile (-1: every one),
    transmits, default (a number, or a list of 3 for "rgb"), lo, hi,
    lo_open, names (enum: [(name, value)]) and help."""
    lib = library()
    _check_field_info(lib)
    out, info, i = {}, FieldInfo(), 0
    while lib.sss_material_field(i, ctypes.byref(info)) == 0:
        kind = FIELD_TYPES[info.type]
        value = ctypes.c_int32()
        names = []
        while lib.sss_material_field_name(i, len(names), ctypes.byref(value)):
            names.append((lib.sss_material_field_name(
                i, len(names), None).decode(), value.value))
        default = list(info.default_value)
        out[info.member.decode()] = {
            "key": info.key.decode(), "type": kind,
            "profile": info.profile, "transmits": bool(info.transmits),
            "default": default if kind == "rgb" else default[0],
            "lo": info.lo, "hi": info.hi, "lo_open": bool(info.lo_open),
            "names": names, "help": info.help.decode()}
        i += 1
    return out


def profiles():
    """{name: kind} of the library's profiles (sss_profile_name: "burley"
    -> SSS_PROFILE_BURLEY, ...), the kinds sss_field_info.profile holds."""
    lib, out, kind = library(), {}, 0
    while lib.sss_profile_name(kind):
        out[lib.sss_profile_name(kind).decode()] = kind
        kind += 1
    return out


@contextlib.contextmanager
def _material(material):
    """The library's row (a pointer to sss_material) for one material of a
    scene description (a dict, docs/scene.md), parsed and checked by the
    library itself."""
    lib = library()
    # (any valid pass index: nothing asked here depends on it)
    text = json.dumps({"version": 1, "materials": [
        dict(material, pass_index=1)]}).encode()
    ptr = ctypes.c_void_p()
    warn = ctypes.create_string_buffer(4096)
    err = ctypes.create_string_buffer(4096)
    _check(lib.sss_scene_parse(text, len(text), ctypes.byref(ptr), warn,
                               len(warn), err, len(err)), err)
    try:
        yield lib.sss_scene_materials(ptr, None)
    finally:
        lib.sss_scene_free(ptr)


def camera_pixels_per_metre(camera, unit_scale, width, height, depth):
    """Horizontal pixels per metre at planar depth `depth` (scene units) of
    a scene description's camera (a dict, docs/scene.md) in a width x
    height image, as the library projects it."""
    lib = library()
    text = json.dumps({"version": 1, "camera": camera,
                       "unit_scale": unit_scale, "materials": []}).encode()
    ptr = ctypes.c_void_p()
    err = ctypes.create_string_buffer(4096)
    _check(lib.sss_scene_parse(text, len(text), ctypes.byref(ptr), None, 0,
                               err, len(err)), err)
    try:
        out = ctypes.c_double()
        _check(lib.sss_camera_pixels_per_metre(
            lib.sss_scene_camera(ptr), width, height, depth,
            ctypes.byref(out), err, len(err)), err)
        return out.value
    finally:
        lib.sss_scene_free(ptr)


def _doubles(call, material, count):
    """Runs call(lib, row, *arrays) with `count` arrays of 3 doubles and
    returns them as lists (one list when count is 1)."""
    arrays = [(ctypes.c_double * 3)() for _ in range(count)]
    with _material(material) as row:
        _check(call(library(), row, *arrays), None)
    lists = [list(a) for a in arrays]
    return lists[0] if count == 1 else lists


def burley_d(material):
    """Burley's shape parameter d (metres) per channel, as the library
    derives it from the radius, the mapping and the albedo."""
    return _doubles(lambda lib, row, d: lib.sss_burley_d(row, d),
                    material, 1)


def _metres(fn, material):
    """fn(row, double *) for one material: the double."""
    metres = ctypes.c_double()
    with _material(material) as row:
        _check(fn(row, ctypes.byref(metres)), None)
    return metres.value


def material_support(material):
    """Metres beyond which the material's profile is treated as 0, before
    the scene's radius scale."""
    return _metres(library().sss_material_support, material)


def transmittance(material, thickness_metres, facing=1.0):
    """What multiplies the back light at a thickness (metres), per
    channel."""
    return _doubles(lambda lib, row, out: lib.sss_transmittance(
        row, thickness_metres, facing, out), material, 1)


def transmission_reach(material):
    """Metres of thickness beyond which the material lets (almost) nothing
    through; 0 when it does not transmit."""
    return _metres(library().sss_transmission_reach, material)


def thin_measured(material):
    """Whether the library measured how much light the material's thin
    parts reflect, lit from the front (its thin_reflectance has an
    effect)."""
    out = ctypes.c_int()
    with _material(material) as row:
        _check(library().sss_thin_measured(row, ctypes.byref(out)), None)
    return bool(out.value)


def transmission_slab(material):
    """(sigma_tr, a, zb), three lists of 3 (metres), of the diffusion slab
    behind a Burley profile's transmission; None when the material's
    transmission is not that slab."""
    try:
        return tuple(_doubles(lambda lib, row, s, a, zb:
                              lib.sss_transmission_slab(row, s, a, zb),
                              material, 3))
    except LibraryError as e:
        if e.name == "SSS_ERR_UNSUPPORTED":
            return None
        raise


def transmission_table(material, n):
    """(step, span, table) of the slab behind a Burley profile's
    transmission (sss_transmission_table): table, n x 3 floats (a flat
    ctypes array), is T(t) / T(0) per channel at t_i = step (e^{i g} - 1),
    g = ln(1 + span / step) / (n - 1), metres of the thickness pass at
    radius scale 1. None when the material's transmission is not that
    slab."""
    table = (ctypes.c_float * (3 * n))()
    step, span = ctypes.c_double(), ctypes.c_double()
    try:
        with _material(material) as row:
            _check(library().sss_transmission_table(
                row, n, table, ctypes.byref(step), ctypes.byref(span)), None)
    except LibraryError as e:
        if e.name == "SSS_ERR_UNSUPPORTED":
            return None
        raise
    return step.value, span.value, table


class Scene:
    """A loaded scene description (JSON); use as a context manager."""

    def __init__(self, path=None, *, text=None):
        """From a file, or from JSON text (nothing read or written)."""
        lib = library()
        self._ptr = ctypes.c_void_p()
        warn = ctypes.create_string_buffer(4096)
        err = ctypes.create_string_buffer(4096)
        if text is not None:
            data = text.encode()
            code = lib.sss_scene_parse(data, len(data),
                                       ctypes.byref(self._ptr), warn,
                                       len(warn), err, len(err))
        else:
            code = lib.sss_scene_load(os.fsencode(path),
                                      ctypes.byref(self._ptr), warn,
                                      len(warn), err, len(err))
        self.warnings = [w for w in warn.value.decode(errors="replace")
                         .splitlines() if w]
        _check(code, err)

    def close(self):
        if self._ptr:
            library().sss_scene_free(self._ptr)
            self._ptr = ctypes.c_void_p()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def options(self, *, method=None, radius_scale=1.0, threads=None,
                layer=None, samples=None, progress=None):
        """sss_process_options for a run with this scene, and what must
        stay referenced while it runs: (options, chosen methods, keep)."""
        lib = library()
        opt = ProcessOptions()
        lib.sss_process_options_default(ctypes.byref(opt))
        if method is not None:
            opt.method = method
        opt.radius_scale = radius_scale
        if threads is not None:
            opt.num_threads = threads
        if samples is not None:
            opt.samples = samples
        keep = []
        if layer:
            keep.append(layer.encode())
            opt.layer = keep[-1]
        if progress is not None:
            # Kept referenced for the call: the library holds the pointer.
            keep.append(ProgressFn(lambda stage, done, _user: progress(
                stage.decode(), done)))
            opt.progress_fn = keep[-1]
        count = ctypes.c_int32()
        lib.sss_scene_materials(self._ptr, ctypes.byref(count))
        chosen = (ctypes.c_int32 * max(count.value, 1))()
        for i in range(count.value):
            chosen[i] = -1
        opt.chosen_methods = chosen
        return opt, chosen, keep

    def chosen_methods(self, chosen):
        """{material name: method name} for the materials that ran."""
        lib = library()
        count = ctypes.c_int32()
        lib.sss_scene_materials(self._ptr, ctypes.byref(count))
        names = dict(enumerate(name for name, _ in methods()))
        return {(lib.sss_scene_material_name(self._ptr, i) or b"").decode(
                    errors="replace") or f"material {i}": names[chosen[i]]
                for i in range(count.value) if chosen[i] >= 0}

    def process(self, input_exr, output_exr, *, method=None,
                radius_scale=1.0, threads=None, layer=None, samples=None,
                progress=None):
        """One frame through the library; returns the timings as a dict.
        Releases the GIL for the duration (ctypes does). progress(stage,
        done) is told where the frame is (sss_process_options), on the
        calling thread."""
        opt, chosen, _keep = self.options(
            method=method, radius_scale=radius_scale, threads=threads,
            layer=layer, samples=samples, progress=progress)
        timings = Timings()
        err = ctypes.create_string_buffer(4096)
        code = library().sss_process_exr(
            os.fsencode(input_exr), os.fsencode(output_exr), self._ptr,
            ctypes.byref(opt), ctypes.byref(timings), err, len(err))
        _check(code, err)
        return {"read": timings.read, "scatter": timings.scatter,
                "write": timings.write,
                "methods": self.chosen_methods(chosen)}


# sss_exr_options.progress_fn: (share done, user)
ExrProgressFn = ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.c_void_p)


def _exr_options(progress, keep):
    """sss_exr_options with the defaults and, when given, progress(done)."""
    opt = ExrOptions()
    library().sss_exr_options_default(ctypes.byref(opt))
    if progress is not None:
        keep.append(ExrProgressFn(lambda done, _user: progress(done)))
        opt.progress_fn = ctypes.cast(keep[-1], ctypes.c_void_p)
    return opt


def _float_view(array, channels):
    """An sss_image over a C-contiguous float32 numpy array (h, w, c)."""
    h, w = array.shape[:2]
    return Image(array.ctypes.data_as(ctypes.POINTER(ctypes.c_float)), w, h,
                 channels, 0)


class Frame:
    """One EXR frame's passes, read once and kept decoded in the library
    (sss_frame): scattered again with any scene description, into numpy
    arrays, with no file read or written; use as a context manager or
    close() it. Reading, writing and closing must not overlap another
    call on the same frame."""

    def __init__(self, path, layer=None, progress=None):
        """progress(done): the share of the file read (0..1)."""
        lib = library()
        self._ptr = ctypes.c_void_p()
        keep = []
        opt = _exr_options(progress, keep)
        err = ctypes.create_string_buffer(4096)
        _check(lib.sss_frame_read(os.fsencode(path),
                                  layer.encode() if layer else None,
                                  ctypes.byref(opt), ctypes.byref(self._ptr),
                                  err, len(err)), err)
        self.path = path
        self.width = lib.sss_frame_width(self._ptr)
        self.height = lib.sss_frame_height(self._ptr)
        self.layer = lib.sss_frame_layer(self._ptr).decode(errors="replace")

    def close(self):
        if self._ptr:
            library().sss_frame_free(self._ptr)
            self._ptr = ctypes.c_void_p()

    def trim(self):
        """Frees the working memory the frame keeps from its last scatter
        for the next one (sss_frame_trim); must not overlap a scatter."""
        if self._ptr:
            library().sss_frame_trim(self._ptr)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        with contextlib.suppress(Exception):
            self.close()

    def scatter(self, scene, combined, light=None, *, method=None,
                radius_scale=1.0, threads=None, samples=None,
                progress=None):
        """Scatters into combined (float32 numpy, height x width x 4,
        rows top first as in the file) and light (x 3, optional); returns
        {"scatter": seconds, "methods": {material: method}}. Releases
        the GIL for the duration."""
        if not self._ptr:
            raise LibraryError(-1, "CLOSED", f"{self.path}: frame closed")
        opt, chosen, _keep = scene.options(
            method=method, radius_scale=radius_scale, threads=threads,
            samples=samples, progress=progress)
        out_c = _float_view(combined, 4)
        out_l = _float_view(light, 3) if light is not None else None
        seconds = ctypes.c_double()
        err = ctypes.create_string_buffer(4096)
        _check(library().sss_frame_scatter(
            self._ptr, scene._ptr, ctypes.byref(opt), ctypes.byref(out_c),
            ctypes.byref(out_l) if out_l is not None else None,
            ctypes.byref(seconds), err, len(err)), err)
        return {"scatter": seconds.value,
                "methods": scene.chosen_methods(chosen)}

    def write(self, path, combined, light, progress=None):
        """The frame's file with the SSS layer, written atomically."""
        keep = []
        opt = _exr_options(progress, keep)
        err = ctypes.create_string_buffer(4096)
        _check(library().sss_frame_write(
            self._ptr, os.fsencode(path), combined.ctypes.data,
            light.ctypes.data, ctypes.byref(opt), err, len(err)), err)


class Exr:
    """A multilayer EXR in memory (sss_exr): its passes, more passes from
    another, and an atomic write. What the render flow uses to put a
    frame's passes beside Blender's composite."""

    def __init__(self, path):
        lib = library()
        self._ptr = ctypes.c_void_p()
        err = ctypes.create_string_buffer(4096)
        _check(lib.sss_exr_read(os.fsencode(path), None,
                                ctypes.byref(self._ptr), err, len(err)), err)

    def close(self):
        if self._ptr:
            library().sss_exr_free(self._ptr)
            self._ptr = ctypes.c_void_p()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def passes(self):
        """[(layer, pass, components, view)] in file order."""
        lib, out = library(), []
        for i in range(lib.sss_exr_pass_count(self._ptr)):
            layer, name, comps = (ctypes.c_char_p(), ctypes.c_char_p(),
                                  ctypes.c_char_p())
            view = Image()
            _check(lib.sss_exr_pass(self._ptr, i, ctypes.byref(layer),
                                    ctypes.byref(name), ctypes.byref(comps),
                                    ctypes.byref(view)), None)
            out.append((layer.value.decode(), name.value.decode(),
                        comps.value.decode(), view))
        return out

    def copy_layer(self, source, layer, as_layer=None):
        """Adds every pass of source's layer (under as_layer)."""
        lib = library()
        err = ctypes.create_string_buffer(4096)
        for src_layer, name, comps, view in source.passes():
            if src_layer != layer:
                continue
            row = view.width * view.channels
            stride = view.row_stride or row
            packed = (ctypes.c_float * (row * view.height))()
            size = ctypes.sizeof(ctypes.c_float)
            for y in range(view.height):
                ctypes.memmove(ctypes.byref(packed, y * row * size),
                               ctypes.addressof(view.data.contents) +
                               y * stride * size, row * size)
            _check(lib.sss_exr_add_pass(
                self._ptr, (as_layer or layer).encode(), name.encode(),
                comps.encode(), packed, err, len(err)), err)

    def write(self, path):
        err = ctypes.create_string_buffer(4096)
        _check(library().sss_exr_write(self._ptr, os.fsencode(path), None,
                                       err, len(err)), err)
