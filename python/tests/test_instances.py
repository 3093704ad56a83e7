"""load_dict with `type = "instances"`: transforms as an (N, 4, 4) numpy array render as the
same placements given inline (translate/scale entries, matrix entries) or as a .npy file;
a wrong array is a SceneError at its key."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import penumbra

SPOT = Path(__file__).resolve().parents[2] / "assets" / "meshes" / "spot_triangulated.obj"
SPOT_TRIANGLES = 5856

#: 200 copies (more triangles than penumbra copies, so the mesh is built once and
#: instanced) on a 20 × 10 grid, half size, every third one mirrored in x.
COPIES = [
    {
        "translate": [2.0 * (i % 20) - 19, 2.0 * (i // 20) - 9, 0],
        "scale": [-0.5 if i % 3 == 0 else 0.5, 0.5, 0.5],
    }
    for i in range(200)
]


def matrices(copies):
    """The placements as (N, 4, 4) row-major matrices: exact, as scale then translate."""
    m = np.tile(np.eye(4), (len(copies), 1, 1))
    for k, c in enumerate(copies):
        m[k, :3, :3] = np.diag(c["scale"])
        m[k, :3, 3] = c["translate"]
    return m


def scene(transforms):
    return {
        "film": {"width": 40, "height": 24},
        "camera": {"position": [0, 0, 40], "look_at": [0, 0, 0], "fov": 40},
        "render": {"samples": 1, "sampler": "center"},
        "lights": [{"type": "point", "position": [5, 10, 30]}],
        "objects": [
            {"type": "quad", "corner": [-30, -20, -2], "u": [60, 0, 0], "v": [0, 40, 0]},
            {"type": "instances", "file": str(SPOT), "transforms": transforms},
        ],
    }


@pytest.fixture(scope="module")
def inline():
    """The placements given inline, as translate and scale entries."""
    s = penumbra.load_dict(scene(COPIES))
    assert (s.stats["meshes"], s.stats["instances"]) == (1, len(COPIES))
    assert s.stats["triangles"] == 2 + len(COPIES) * SPOT_TRIANGLES
    assert s.stats["unique_triangles"] == 2 + SPOT_TRIANGLES
    return s.render(threads=2)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_an_array_of_matrices_renders_as_the_same_placements_inline(inline, dtype):
    array = matrices(COPIES).astype(dtype)
    d = scene(array)
    s = penumbra.load_dict(d)
    assert s.stats["instances"] == len(COPIES)
    image = s.render(threads=2)
    assert np.array_equal(image, inline)
    assert d["objects"][1]["transforms"] is array  # the caller's dict is not changed
    # The image is not blank: the copies are there.
    assert len(np.unique(image.reshape(-1, 3), axis=0)) > 10


def test_matrix_entries_and_a_npy_file_render_the_same(inline, tmp_path):
    rows = matrices(COPIES)
    listed = penumbra.load_dict(scene([{"matrix": m.tolist()} for m in rows]))
    assert np.array_equal(listed.render(threads=2), inline)
    np.save(tmp_path / "copies.npy", rows)
    # The mesh is outside tmp_path, the scene's folder: allowed.
    from_file = penumbra.load_dict(scene("copies.npy"), base_dir=tmp_path, allow_paths=SPOT.parent)
    assert np.array_equal(from_file.render(threads=2), inline)


@pytest.mark.parametrize(
    "array, words",
    [
        (np.tile(np.eye(4), (3, 1, 1))[:, :, :3], "must have shape (N, 4, 4), one row-major "
         "4x4 matrix per copy, not (3, 4, 3)"),
        (np.eye(4), "must have shape (N, 4, 4), one row-major 4x4 matrix per copy, not (4, 4)"),
        (np.zeros((2, 3, 4)), "not (2, 3, 4)"),
        (np.zeros((0, 4)), "not (0, 4)"),
        (np.full((2, 4, 4), "1"), "must hold real numbers, not dtype <U1"),
        (np.ones((2, 4, 4), bool), "must hold real numbers, not dtype bool"),
    ],
)
def test_a_wrong_array_is_a_scene_error_at_its_key(array, words):
    with pytest.raises(penumbra.SceneError) as e:
        penumbra.load_dict(scene(array))
    message = str(e.value)
    assert e.value.key == "objects[1].transforms" and e.value.kind == "bad_value"
    assert message.startswith("<dict>: objects[1].transforms: ") and words in message, message
    assert "\n" not in message


def test_bad_matrices_in_an_array_are_located_by_their_index():
    rows = matrices(COPIES[:4])
    nan = rows.copy()
    nan[2, 1, 3] = np.nan
    with pytest.raises(penumbra.SceneError) as e:
        penumbra.load_dict(scene(nan))
    assert e.value.key == "objects[1].transforms[2][1][3]"
    projective = rows.copy()
    projective[3, 3, 0] = 1.0
    with pytest.raises(penumbra.SceneError) as e:
        penumbra.load_dict(scene(projective))
    assert e.value.key == "objects[1].transforms[3].matrix" and "[0, 0, 0, 1]" in str(e.value)



def test_object_ids_name_each_copy_and_the_aov_reports_them():
    s = penumbra.load_dict(scene(COPIES))
    assert s.object_ids == [range(0, 1), range(1, 1 + len(COPIES))]
    image, aovs = s.render(aovs=["object_id"], threads=2)
    ids = aovs["object_id"]
    # Every pixel sees the backdrop (object 0), nothing, or a copy of entry 1.
    seen = set(np.unique(ids).tolist()) - {0, penumbra.NO_ID}
    assert seen and seen <= set(s.object_ids[1]), seen
    # Copies are told apart: at 40 × 24 pixels, dozens of the 200 are seen.
    assert len(seen) > 20, len(seen)
