"""RaycastingScene.add_instance (penumbra's extension of Open3D's API): a placement answers
every query as the same triangles added transformed by add_triangles (the same triangles hit
and counted, t within rounding: the ray is mapped into the geometry's space; closest points
bit for bit); the transform's forms
(numpy of any real dtype, nested lists, Open3D-style tensors); each mistake a one-line
ValueError or TypeError naming the argument, adding nothing. And Scene.raycasting_scene()
of a scene with instances."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import penumbra
from raycast_ref import icosphere, random_rays

#: Exact placements (entries 0, ±1, ±2, ±0.5 and whole translations, so that float32
#: arithmetic places every vertex exactly as numpy does): a quarter turn about z, a mirror
#: in x with non-uniform scale, and both.
EXACT = [
    np.array([[0, -1, 0, 3], [1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], np.float64),
    np.array([[-1, 0, 0, -3], [0, 2, 0, 1], [0, 0, 0.5, 0], [0, 0, 0, 1]], np.float64),
    np.array([[0, 0, -2, 0], [0, 0.5, 0, -3], [1, 0, 0, 1], [0, 0, 0, 1]], np.float64),
]


def rotation(axis, degrees):
    """A rotation matrix about a unit axis (Rodrigues)."""
    a = np.asarray(axis, np.float64) / np.linalg.norm(axis)
    t = np.radians(degrees)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(t) * k + (1 - np.cos(t)) * k @ k


def general():
    """Rotated by 37° about a tilted axis, scaled non-uniformly and mirrored, translated."""
    m = np.eye(4)
    m[:3, :3] = rotation([1, 2, 0.5], 37) @ np.diag([1.3, -0.7, 2.1])
    m[:3, 3] = [0.5, -2.0, 1.5]
    return m


def placed(vertices, m):
    """``vertices`` placed by ``m``, as float32."""
    return (vertices.astype(np.float64) @ m[:3, :3].T + m[:3, 3]).astype(np.float32)


def rays_at_everything(n=3000, seed=1):
    """Rays from a shell of radius 8 toward points within 3 of the origin."""
    rng = np.random.default_rng(seed)
    origins = rng.normal(size=(n, 3))
    origins *= 8 / np.linalg.norm(origins, axis=1, keepdims=True)
    targets = rng.uniform(-3, 3, (n, 3))
    return np.concatenate([origins, targets - origins], axis=1).astype(np.float32)


def same(a, b):
    assert a.keys() == b.keys()
    for k in a:
        assert a[k].dtype == b[k].dtype and np.array_equal(a[k], b[k]), k


def test_exact_placements_answer_as_the_triangles_added_transformed():
    v, t = icosphere(2)
    instanced, added = penumbra.RaycastingScene(), penumbra.RaycastingScene()
    assert instanced.add_triangles(v, t) == added.add_triangles(v, t) == 0
    for i, m in enumerate(EXACT):
        assert instanced.add_instance(0, m) == i + 1
        assert added.add_triangles(placed(v, m), t) == i + 1
    rays = rays_at_everything()
    a, b = instanced.cast_rays(rays), added.cast_rays(rays)
    # The placements' corners are exact, but each ray is mapped into the sphere's space
    # (its origin moved by the translation, rounded): t within rounding, the same triangles.
    np.testing.assert_allclose(a["t_hit"], b["t_hit"], rtol=1e-6)
    np.testing.assert_array_equal(a["geometry_ids"], b["geometry_ids"])
    np.testing.assert_array_equal(a["primitive_ids"], b["primitive_ids"])
    # Normals come from the placed corners: the copy's, bit for bit.
    np.testing.assert_array_equal(a["primitive_normals"], b["primitive_normals"])
    assert set(np.unique(a["geometry_ids"]).tolist()) >= {0, 1, 2, 3}
    la, lb = instanced.list_intersections(rays), added.list_intersections(rays)
    for k in ("ray_splits", "ray_ids", "geometry_ids", "primitive_ids"):
        np.testing.assert_array_equal(la[k], lb[k])
    np.testing.assert_allclose(la["t_hit"], lb["t_hit"], rtol=1e-6)
    points = rays[:, :3] * 0.3
    same(instanced.compute_closest_points(points), added.compute_closest_points(points))


def test_a_rotated_scaled_mirrored_instance_agrees_with_its_triangles_added_transformed():
    v, t = icosphere(2)
    m = general()
    instanced, added = penumbra.RaycastingScene(), penumbra.RaycastingScene()
    instanced.add_triangles(v, t)
    added.add_triangles(v, t)
    assert instanced.add_instance(0, m) == 1
    added.add_triangles(placed(v, m), t)
    rays = rays_at_everything(seed=2)
    a, b = instanced.cast_rays(rays), added.cast_rays(rays)
    # The two place vertices in float32 by different sums: equal within rounding.
    np.testing.assert_allclose(a["t_hit"], b["t_hit"], rtol=1e-5)
    np.testing.assert_allclose(a["primitive_normals"], b["primitive_normals"], atol=1e-5)
    np.testing.assert_array_equal(a["geometry_ids"], b["geometry_ids"])
    assert (a["geometry_ids"] == 1).sum() > 100
    # Away from edges, the same triangle is hit.
    uv = b["primitive_uvs"]
    inside = (uv.min(axis=1) > 1e-3) & (uv.sum(axis=1) < 1 - 1e-3)
    np.testing.assert_array_equal(a["primitive_ids"][inside], b["primitive_ids"][inside])
    # The mirror turns the triangles' winding: normals keep pointing out of the sphere.
    hit = a["geometry_ids"] == 1
    centre = m[:3, 3]
    points = rays[hit, :3] + a["t_hit"][hit, None] * rays[hit, 3:]
    outward = np.einsum("ij,ij->i", a["primitive_normals"][hit], points - centre)
    reference = np.einsum("ij,ij->i", b["primitive_normals"][hit], points - centre)
    np.testing.assert_array_equal(np.sign(outward), np.sign(reference))


class FakeTensor:
    """What open3d.core.Tensor offers: .cpu() and .numpy()."""

    def __init__(self, a):
        self.a = np.asarray(a)

    def cpu(self):
        return self

    def numpy(self):
        return self.a


@pytest.mark.parametrize(
    "form",
    [
        lambda m: m.astype(np.float32),
        lambda m: m.astype(np.float16),
        lambda m: m.astype(np.int64),
        lambda m: m.tolist(),
        lambda m: tuple(map(tuple, m.tolist())),
        lambda m: FakeTensor(m.astype(np.float32)),
        lambda m: np.asfortranarray(m),
    ],
    ids=["float32", "float16", "int64", "list", "tuple", "tensor", "fortran"],
)
def test_every_form_of_the_matrix_places_the_same_copy(form):
    v, t = icosphere(1)
    m = EXACT[1].copy()
    m[2, 2] = 1.0  # whole numbers: the same matrix in every dtype
    want = penumbra.RaycastingScene()
    want.add_triangles(v, t)
    want.add_instance(0, m)
    s = penumbra.RaycastingScene()
    s.add_triangles(v, t)
    assert s.add_instance(0, form(m)) == 1
    rays = rays_at_everything(500)
    same(s.cast_rays(rays), want.cast_rays(rays))


def test_real_open3d_tensors_are_taken():
    o3d = pytest.importorskip("open3d", reason="open3d is not installed (pip install open3d)")
    v, t = icosphere(1)
    s = penumbra.RaycastingScene()
    s.add_triangles(v, t)
    assert s.add_instance(0, o3d.core.Tensor(EXACT[0])) == 1


def test_queries_report_the_copys_geometry_id():
    v, t = icosphere(1)
    s = penumbra.RaycastingScene()
    s.add_triangles(v, t)
    far = np.eye(4)
    far[:3, 3] = [10, 0, 0]
    assert s.add_instance(0, far) == 1
    ray = [[10, 0, 5, 0, 0, -1]]
    ans = s.cast_rays(ray)
    assert ans["geometry_ids"].tolist() == [1]
    assert ans["t_hit"][0] == pytest.approx(4.0, abs=0.02)
    assert s.count_intersections(ray).tolist() == [2]
    assert s.list_intersections(ray)["geometry_ids"].tolist() == [1, 1]
    assert s.compute_closest_points([[10, 0, 3]])["geometry_ids"].tolist() == [1]
    assert s.compute_occupancy([[10, 0, 0], [5, 0, 0]]).tolist() == [1.0, 0.0]
    assert "2 geometries" in repr(s)


def bad_rows(change):
    m = np.eye(4)
    change(m)
    return m


@pytest.mark.parametrize(
    "geometry_id, transform, error, words",
    [
        (1, np.eye(4), ValueError, "add_instance: geometry_id: geometry 1 does not exist"),
        (-1, np.eye(4), ValueError, "add_instance: geometry_id must be from 0"),
        (2**32, np.eye(4), ValueError, "add_instance: geometry_id must be from 0"),
        (0.0, np.eye(4), TypeError, "add_instance: geometry_id must be an integer"),
        (True, np.eye(4), TypeError, "add_instance: geometry_id must be an integer"),
        ("0", np.eye(4), TypeError, "add_instance: geometry_id must be an integer"),
        (0, bad_rows(lambda m: m.__setitem__((1, 2), np.nan)), ValueError,
         "add_instance: transform: the matrix entry [1][2] is not a finite"),
        (0, bad_rows(lambda m: m.__setitem__((0, 3), np.inf)), ValueError,
         "add_instance: transform: the matrix entry [0][3] is not a finite"),
        (0, bad_rows(lambda m: m.__setitem__((0, 0), 1e300)), ValueError,
         "add_instance: transform: the matrix entry [0][0] is not a finite"),
        (0, bad_rows(lambda m: m.__setitem__((3, 0), 0.5)), ValueError,
         "add_instance: transform: the matrix's last row must be [0, 0, 0, 1]"),
        (0, bad_rows(lambda m: m.__setitem__((1, 1), 0.0)), ValueError,
         "add_instance: transform: the matrix cannot be inverted"),
        (0, bad_rows(lambda m: m.__setitem__((2, 3), 3e12)), ValueError,
         "add_instance: transform: placed vertex 0 has a coordinate beyond"),
        (0, np.eye(3), ValueError,
         "add_instance: transform must have shape (4, 4), not (3, 3)"),
        (0, np.eye(4).reshape(1, 4, 4), ValueError, "add_instance: transform must have shape"),
        (0, np.eye(4).ravel(), ValueError, "add_instance: transform must have shape"),
        (0, np.eye(4).astype(bool), TypeError, "add_instance: transform must be an array of real"),
        (0, np.eye(4).astype(complex), TypeError,
         "add_instance: transform must be an array of real"),
        (0, [["a"] * 4] * 4, TypeError, "add_instance: transform must be an array of real"),
        (0, [{1, 0, 0, 0}] * 4, TypeError, "add_instance: transform must be an array or a list"),
        (0, None, TypeError, "add_instance: transform must be an array of real"),
    ],
)
def test_each_mistake_is_one_line_naming_the_argument_and_adds_nothing(
    geometry_id, transform, error, words
):
    v, t = icosphere(1)
    s = penumbra.RaycastingScene()
    s.add_triangles(v, t)
    before = s.cast_rays(random_rays(np.random.default_rng(3), 50))
    with pytest.raises(error) as e:
        s.add_instance(geometry_id, transform)
    message = str(e.value)
    assert words in message and "\n" not in message, message
    assert repr(s) == f"<penumbra.RaycastingScene: 1 geometries, {len(t)} triangles>"
    same(s.cast_rays(random_rays(np.random.default_rng(3), 50)), before)


SPOT = Path(__file__).resolve().parents[2] / "assets" / "meshes" / "spot_triangulated.obj"


def test_a_scenes_raycasting_scene_holds_its_instances():
    # 180 copies of spot's 5856 triangles are more than penumbra copies (2^20 triangles):
    # the scene instances them (see penumbra::flatten_instances).
    count = 180
    rows = np.tile(np.eye(4), (count, 1, 1))
    rows[:, 0, 3] = np.arange(count) * 10.0
    scene = penumbra.load_dict(
        {
            "film": {"width": 8, "height": 8},
            "camera": {"position": [0, 0, 50], "look_at": [0, 0, 0], "fov": 40},
            "objects": [
                {"type": "quad", "corner": [-5, -5, -5], "u": [2000, 0, 0], "v": [0, 10, 0]},
                {"type": "instances", "file": str(SPOT), "transforms": rows},
            ],
        }
    )
    assert (scene.stats["meshes"], scene.stats["instances"]) == (1, count)
    rc = scene.raycasting_scene()
    triangles = scene.stats["triangles"]
    assert triangles == 2 + count * 5856
    want = f"<penumbra.RaycastingScene: {1 + count} geometries, {triangles} triangles>"
    assert repr(rc) == want
    # A ray down onto the middle of each copy's box: object ids count the copies (the quad
    # is 0, copy i is 1 + i).
    lines = SPOT.read_text().splitlines()
    v = np.array([line.split()[1:4] for line in lines if line.startswith("v ")], float)
    middle = (v.min(axis=0) + v.max(axis=0)) / 2
    rays = [[10.0 * i + middle[0], 20, middle[2], 0, -1, 0] for i in range(count)]
    ans = rc.cast_rays(rays)
    assert ans["geometry_ids"].tolist() == list(range(1, count + 1))
    assert (ans["primitive_ids"] < 5856).all()


def test_a_moved_placement_answers_as_one_added_there():
    v, t = icosphere(2)

    def scene(first, lift):
        s = penumbra.RaycastingScene()
        s.add_triangles(v, t)
        s.add_instance(0, first)
        s.add_instance(0, EXACT[1])
        up = np.eye(4)
        up[2, 3] = lift
        s.add_instance(1, up)  # a placement of placement 1
        return s

    rays = rays_at_everything()
    moved = scene(EXACT[0], 2.0)
    before = moved.cast_rays(rays)
    moved.set_transform(1, general())
    lift = np.eye(4)
    lift[2, 3] = -1.5
    moved.set_transform(3, lift.tolist())
    after = moved.cast_rays(rays)
    assert not np.array_equal(after["t_hit"], before["t_hit"])
    same(after, scene(general(), -1.5).cast_rays(rays))


@pytest.mark.parametrize(
    "geometry_id, transform, error, words",
    [
        (0, np.eye(4), ValueError, "set_transform: geometry_id: geometry 0 is not a placement"),
        (2, np.eye(4), ValueError, "set_transform: geometry_id: geometry 2 is not a placement"),
        (-1, np.eye(4), ValueError, "set_transform: geometry_id must be from 0"),
        (1.0, np.eye(4), TypeError, "set_transform: geometry_id must be an integer"),
        (1, bad_rows(lambda m: m.__setitem__((1, 1), 0.0)), ValueError,
         "set_transform: transform: the matrix cannot be inverted"),
        (1, bad_rows(lambda m: m.__setitem__((0, 3), np.nan)), ValueError,
         "set_transform: transform: the matrix entry [0][3] is not a finite"),
        (1, np.eye(3), ValueError, "set_transform: transform must have shape (4, 4)"),
    ],
)
def test_each_bad_move_is_one_line_naming_the_argument_and_moves_nothing(
    geometry_id, transform, error, words
):
    v, t = icosphere(1)
    s = penumbra.RaycastingScene()
    s.add_triangles(v, t)
    s.add_instance(0, EXACT[0])
    rays = random_rays(np.random.default_rng(3), 50)
    before = s.cast_rays(rays)
    with pytest.raises(error) as e:
        s.set_transform(geometry_id, transform)
    message = str(e.value)
    assert words in message and "\n" not in message, message
    same(s.cast_rays(rays), before)


def test_a_scenes_own_objects_move_with_the_scene_not_the_raycasting_scene():
    scene = penumbra.load_dict(
        {
            "film": {"width": 8, "height": 8},
            "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 40},
            "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1}],
        }
    )
    rc = scene.raycasting_scene()
    with pytest.raises(ValueError, match="set_transform: geometry_id: geometry 0 is an object"):
        rc.set_transform(0, np.eye(4))
    # A placement added to it moves: a copy of the sphere, from 3 to 6 along x.
    shift = np.eye(4)
    shift[0, 3] = 3
    copy = rc.add_instance(0, shift)
    ray = [[9, 0, 0, -1, 0, 0]]
    assert rc.cast_rays(ray)["t_hit"].numpy()[0] == pytest.approx(5, abs=0.05)
    shift[0, 3] = 6
    rc.set_transform(copy, shift)
    hit = rc.cast_rays(ray)
    assert hit["geometry_ids"].numpy()[0] == copy
    assert hit["t_hit"].numpy()[0] == pytest.approx(2, abs=0.05)
