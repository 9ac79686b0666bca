"""How the add-on's ctypes module (addon/separable_sss/native.py, which
imports nothing of Blender) names and looks for the library on each
platform, and what it says when none is there."""
import importlib.util
import os
import sys

import pytest

NATIVE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..",
                      "addon", "separable_sss", "native.py")


@pytest.fixture
def native(monkeypatch):
    monkeypatch.delenv("SSS_LIB", raising=False)
    spec = importlib.util.spec_from_file_location("sss_native_test", NATIVE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("system,name", [("linux", "libsss.so"),
                                         ("win32", "libsss.dll"),
                                         ("cygwin", "libsss.dll"),
                                         ("darwin", "libsss.dylib"),
                                         ("freebsd14", "libsss.so")])
def test_library_name_per_system(native, system, name):
    assert native.library_name(system) == name


def test_sss_lib_and_the_preference_come_first(native, monkeypatch):
    monkeypatch.setenv("SSS_LIB", "/from/env/libsss.dylib")
    native.set_preferred_path("/from/preferences/libsss.dll")
    paths = list(native.candidates())
    assert paths[:2] == ["/from/env/libsss.dylib",
                         "/from/preferences/libsss.dll"]
    assert all(os.path.basename(p) == native.library_name()
               for p in paths[2:])


def test_missing_library_names_the_platform_and_the_file(native,
                                                         monkeypatch,
                                                         tmp_path):
    missing = str(tmp_path / native.library_name())
    monkeypatch.setattr(native, "candidates", lambda: iter([missing]))
    with pytest.raises(native.LibraryError) as e:
        native.library()
    message = str(e.value)
    assert native.platform_name() in message
    assert f"{missing} (missing)" in message
    assert native.library_name() in message
    assert e.value.name == "NOT_FOUND"


def test_platform_name_is_blenders(native, monkeypatch):
    import platform
    for system, machine, want in [("linux", "x86_64", "linux-x64"),
                                  ("linux", "aarch64", "linux-arm64"),
                                  ("win32", "AMD64", "windows-x64"),
                                  ("darwin", "arm64", "macos-arm64"),
                                  ("darwin", "x86_64", "macos-x64")]:
        monkeypatch.setattr(sys, "platform", system)
        monkeypatch.setattr(platform, "machine", lambda m=machine: m)
        assert native.platform_name() == want
