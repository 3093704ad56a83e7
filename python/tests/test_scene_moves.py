"""Scene.set_transform: a moved object (a shape, a mesh, a whole instances object, one copy of
many that are instanced) renders the bytes of a fresh load of the scene written with that
transform; the move rides in the pack and the digest, is built from the bytes the first load
read, and a bad move is refused at its key with the scene unchanged."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest

import penumbra

SPOT = Path(__file__).resolve().parents[2] / "assets" / "meshes" / "spot_triangulated.obj"

CUBE = (
    "v -0.5 -0.5 -0.5\nv 0.5 -0.5 -0.5\nv 0.5 0.5 -0.5\nv -0.5 0.5 -0.5\n"
    "v -0.5 -0.5 0.5\nv 0.5 -0.5 0.5\nv 0.5 0.5 0.5\nv -0.5 0.5 0.5\n"
    "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 7 3\nf 4 8 7\nf 1 5 8\nf 1 8 4\n"
    "f 2 3 7\nf 2 7 6\n"
)

#: A quarter turn about y and a shift.
TURN = np.array(
    [[0.0, 0.0, 1.0, 0.5], [0.0, 1.0, 0.0, -0.25], [-1.0, 0.0, 0.0, 1.5], [0, 0, 0, 1]]
)


def description(cube: str):
    """A sphere, a mesh, and 200 copies of spot (more triangles than penumbra copies, so
    they are placements of one tree) on a grid."""
    grid = np.tile(np.eye(4), (200, 1, 1))
    grid[:, 0, 3] = 1.5 * (np.arange(200) % 20) - 14
    grid[:, 1, 3] = 1.5 * (np.arange(200) // 20) - 7
    grid[:, :3, :3] *= 0.4
    return {
        "film": {"width": 96, "height": 64},
        "camera": {"position": [0, 0, 30], "look_at": [0, 0, 0], "fov": 40},
        "render": {"samples": 1, "sampler": "center"},
        "lights": [{"type": "point", "position": [5, 10, 30]}],
        "objects": [
            {"type": "sphere", "center": [0, 0, 0], "radius": 2, "translate": [-6, 0, 4]},
            {"type": "mesh", "file": cube, "scale": 3, "rotate": [0, 30, 0]},
            {"type": "instances", "file": "spot.obj", "name": "spots", "transforms": grid,
             "translate": [0, 0, -2]},
        ],
    }


@pytest.fixture()
def cube(tmp_path):
    (tmp_path / "spot.obj").write_bytes(SPOT.read_bytes())
    path = tmp_path / "cube.obj"
    path.write_text(CUBE)
    return "cube.obj"


def written(desc, obj, matrix, index=None):
    """The description with object ``obj`` (a position, or a name) or its copy ``index``
    given ``matrix``."""
    desc = copy.deepcopy(desc)
    if isinstance(obj, str):
        obj = next(i for i, o in enumerate(desc["objects"]) if o.get("name") == obj)
    o = desc["objects"][obj]
    if index is None:
        for key in ("translate", "rotate", "scale"):
            o.pop(key, None)
        o["matrix"] = matrix.tolist()
    else:
        o["transforms"][index] = matrix
    return desc


@pytest.mark.parametrize(
    "obj, index", [(0, None), (1, None), (2, None), (2, 77), ("spots", 77)]
)
def test_a_moved_object_renders_the_bytes_of_a_fresh_load(cube, tmp_path, obj, index):
    desc = description(cube)
    scene = penumbra.load_dict(desc, base_dir=tmp_path)
    assert scene.stats["instances"] == 200
    before, digest = scene.render(threads=2), scene.scene_digest
    scene.set_transform(obj, TURN, index=index)
    image = scene.render(threads=2)
    fresh = penumbra.load_dict(written(desc, obj, TURN, index), base_dir=tmp_path)
    assert np.array_equal(image, fresh.render(threads=2))
    assert not np.array_equal(image, before)
    assert scene.scene_digest != digest
    # The pack carries the move.
    assert np.array_equal(penumbra.load_pack(scene.pack()).render(threads=2), image)


def test_moves_are_built_from_the_bytes_the_load_read(cube, tmp_path):
    desc = description(cube)
    scene = penumbra.load_dict(desc, base_dir=tmp_path)
    expected = penumbra.load_dict(written(desc, 1, TURN), base_dir=tmp_path).render()
    (tmp_path / cube).write_text(CUBE.replace("0.5", "0.25"))
    scene.set_transform(1, TURN)
    assert np.array_equal(scene.render(), expected)
    # Each frame's move replaces the last: the digest of many moves is that of the last.
    for k in range(5):
        shifted = TURN.copy()
        shifted[0, 3] = k
        scene.set_transform(1, shifted)
    scene.set_transform(1, TURN)
    once = penumbra.load_pack(scene.pack())
    assert once.scene_digest == scene.scene_digest
    assert np.array_equal(once.render(), expected)


def test_bad_moves_are_refused_and_change_nothing(cube, tmp_path):
    scene = penumbra.load_dict(description(cube), base_dir=tmp_path)
    digest = scene.scene_digest
    nan = TURN.copy()
    nan[1, 2] = np.nan
    singular = TURN.copy()
    singular[0] = 0
    projective = TURN.copy()
    projective[3, 0] = 1
    cases = [
        ((3, TURN), {}, "objects", "no object 3"),
        (("cows", TURN), {}, "objects", "no object named `cows` (the named objects: `spots`)"),
        ((0, TURN), {"index": 0}, "objects[0]", "no placements"),
        ((2, TURN), {"index": 200}, "objects[2].transforms", "no placement 200"),
        ((1, nan), {}, "objects[1].matrix", "NaN"),
        ((1, singular), {}, "objects[1].matrix", "cannot be inverted"),
        ((2, projective), {"index": 3}, "objects[2].transforms[3].matrix", "not affine"),
    ]
    for args, kwargs, key, words in cases:
        with pytest.raises(penumbra.SceneError) as e:
            scene.set_transform(*args, **kwargs)
        assert e.value.key == key and words in str(e.value), str(e.value)
    with pytest.raises(ValueError, match=r"shape \(4, 4\)"):
        scene.set_transform(0, np.eye(3))
    with pytest.raises(TypeError, match="obj must be an integer"):
        scene.set_transform(True, TURN)
    with pytest.raises(ValueError, match="index must be from 0"):
        scene.set_transform(2, TURN, index=-1)
    assert scene.scene_digest == digest


def test_a_model_file_moves_as_a_scene_and_its_errors_name_no_line_of_text(cube, tmp_path):
    scene = penumbra.load(tmp_path / cube)
    before = scene.render(width=32, height=24)
    with pytest.raises(penumbra.SceneError) as e:
        scene.set_transform(0, TURN, index=0)
    assert e.value.key == "objects[0]" and e.value.line is None, str(e.value)
    scene.set_transform(0, TURN)
    assert not np.array_equal(scene.render(width=32, height=24), before)
