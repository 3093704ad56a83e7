"""Errors: scene mistakes as penumbra.SceneError with their location, unreadable files as
OSError, as Python users expect."""

from __future__ import annotations

import errno
import os
import subprocess
import sys

import pytest

import penumbra
from conftest import SCENES

GOOD = """[film]
width = 4
height = 4
[camera]
position = [0, 0, 3]
look_at = [0, 0, 0]
fov = 40
"""


def scene_error(text: str, **kwargs) -> penumbra.SceneError:
    with pytest.raises(penumbra.SceneError) as info:
        penumbra.loads(text, **kwargs)
    return info.value


def test_scene_error_is_a_value_error_with_its_location():
    e = scene_error(GOOD + '[[objects]]\ntype = "sphere"\ncenter = [0, 0, 0]\nradius = -1\n')
    assert isinstance(e, ValueError)
    assert (e.file, e.line, e.column, e.key, e.kind) == (
        "<string>",
        11,
        1,
        "objects[0].radius",
        "bad_value",
    )
    assert str(e).startswith("<string>:11:1: objects[0].radius:")


@pytest.mark.parametrize(
    "tail, kind, key, line",
    [
        ("[film\n", "syntax", None, 8),
        ("[render]\nsamplez = 4\n", "unknown_key", "render.samplez", 9),
        ('[[objects]]\ntype = "quad"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\n', "missing_key", "objects[0]", 8),
        ('[[objects]]\ntype = "cube"\ncenter = [0, 0, 0]\nsize = 1\nmaterial = "gold"\n', "unknown_name", "objects[0].material", 12),
        ('[[objects]]\ntype = "mesh"\nfile = "nowhere.obj"\n', "asset_mesh", "objects[0].file", 10),
        ('[textures.t]\ntype = "image"\nfile = "nowhere.png"\n', "asset_image", "textures.t.file", 10),
    ],
)
def test_each_kind_of_mistake(tail, kind, key, line):
    e = scene_error(GOOD + tail)
    assert e.kind == kind
    assert e.key == key
    assert e.line == line
    assert e.file == "<string>"


def test_asset_errors_keep_the_systems_reason(tmp_path):
    e = scene_error(GOOD + '[[objects]]\ntype = "mesh"\nfile = "nowhere.obj"\n', base_dir=tmp_path)
    assert "nowhere.obj" in str(e)
    assert "No such file" in str(e) or "not found" in str(e).lower()


def test_unreadable_scene_files_are_os_errors(tmp_path):
    with pytest.raises(FileNotFoundError) as info:
        penumbra.load(tmp_path / "missing.toml")
    assert info.value.errno == errno.ENOENT
    assert info.value.filename == str(tmp_path / "missing.toml")
    (tmp_path / "d.toml").mkdir()
    with pytest.raises(OSError):
        penumbra.load(tmp_path / "d.toml")


def test_a_file_name_without_a_format_is_a_scene_error(tmp_path):
    p = tmp_path / "scene.yaml"
    p.write_text(GOOD)
    with pytest.raises(penumbra.SceneError) as info:
        penumbra.load(p)
    assert (info.value.kind, info.value.file, info.value.line) == ("file", str(p), None)


def test_errors_in_files_and_dicts_name_them(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text(GOOD + "[render]\nsamples = 3.5\n")
    with pytest.raises(penumbra.SceneError) as info:
        penumbra.load(p)
    assert (info.value.file, info.value.line, info.value.key) == (str(p), 9, "render.samples")

    with pytest.raises(penumbra.SceneError) as info:
        penumbra.load_dict(
            {
                "film": {"width": 4, "height": 4},
                "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov": 40},
                "objects": [{"type": "cube", "center": [0, 0, 0], "size": 1},
                    {"type": "sphere", "center": [0, 0, 0], "radius": "big"},],
            }
        )
    assert (info.value.file, info.value.key, info.value.kind) == ("<dict>", "objects[1].radius", "bad_value")
    with pytest.raises(TypeError, match="object"):
        penumbra.load_dict({"film": object()})
    with pytest.raises(ValueError, match="unknown scene format"):
        penumbra.loads(GOOD, format="yaml")


def test_the_scene_files_of_the_repository_load():
    # Some read the repository's assets/, beside scenes/, as the README's commands allow.
    for path in sorted(SCENES.glob("*.toml")):
        loaded = penumbra.load(path, allow_paths=[SCENES.parent / "assets"])
        assert loaded.stats["triangles"] > 0, path


@pytest.mark.parametrize("value", ["avx-2", "AVX2", "sse"])
def test_a_simd_path_that_cannot_be_honoured_warns_on_import(value):
    env = {**os.environ, "PENUMBRA_SIMD": value}
    code = "import warnings; warnings.simplefilter('always'); import penumbra"
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "RuntimeWarning" in done.stderr and f'PENUMBRA_SIMD="{value}"' in done.stderr
    quiet = subprocess.run(
        [sys.executable, "-c", code],
        env={**os.environ, "PENUMBRA_SIMD": "portable"},
        capture_output=True,
        text=True,
    )
    assert quiet.returncode == 0 and "PENUMBRA_SIMD" not in quiet.stderr
