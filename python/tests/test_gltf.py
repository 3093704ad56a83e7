"""glTF models in Python: penumbra.load("model.glb") builds the scene `penumbra render` makes
of it, and raycasting_scene() works on it. The shared assets (../shared/assets/gltf beside the
repository) are compared with trimesh's reading when both are present; otherwise skipped."""

from __future__ import annotations

import json
import struct
from pathlib import Path

import numpy as np
import pytest

import penumbra

SHARED = Path(__file__).resolve().parents[2].parent / "shared" / "assets" / "gltf"
FILES = ["BoxTextured.glb", "Duck.glb", "CesiumMilkTruck.glb", "balloon/scene.gltf",
         "smallpine/scene.gltf"]


def shared(name: str) -> Path:
    path = SHARED / name
    if not path.is_file():
        pytest.skip(f"{path} is absent")
    return path


def trimesh_reading(path: Path):
    """Triangles and world bounds as trimesh reads the file, node transforms applied."""
    trimesh = pytest.importorskip("trimesh")
    # Geometry only: the pine names normal maps that are absent upstream, which trimesh (with
    # Pillow present) would try to read.
    scene = trimesh.load(path, force="scene", process=False, skip_materials=True)
    triangles, lo, hi = 0, np.full(3, np.inf), np.full(3, -np.inf)
    for node in scene.graph.nodes_geometry:
        transform, name = scene.graph[node]
        mesh = scene.geometry[name]
        triangles += len(mesh.faces)
        used = trimesh.transform_points(mesh.vertices[np.unique(mesh.faces)], transform)
        lo, hi = np.minimum(lo, used.min(0)), np.maximum(hi, used.max(0))
    return triangles, lo, hi


@pytest.mark.parametrize("name", FILES)
def test_a_shared_file_has_trimeshs_triangles_and_its_rays_hit_it(name):
    path = shared(name)
    triangles, lo, hi = trimesh_reading(path)
    scene = penumbra.load(path, threads=1)
    assert scene.stats["triangles"] == triangles
    # Rays from outside the bounds toward their centre hit the model inside the bounds.
    centre = (lo + hi) / 2
    diagonal = np.linalg.norm(hi - lo)
    directions = np.array([[1, 0, 0], [0, -1, 0], [0, 0, -1], [-1, 0, 0]], dtype=np.float32)
    origins = centre - directions * diagonal
    rays = np.hstack([origins, directions]).astype(np.float32)
    hits = scene.raycasting_scene().cast_rays(rays)
    t = hits["t_hit"].numpy()
    assert np.isfinite(t).any(), t
    points = origins + directions * t[:, None]
    inside = points[np.isfinite(t)]
    assert (inside >= lo - 1e-3 * diagonal).all() and (inside <= hi + 1e-3 * diagonal).all()


def glb(doc: dict, blob: bytes) -> bytes:
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    blob += b"\0" * (-len(blob) % 4)
    total = 12 + 8 + len(text) + 8 + len(blob)
    return (b"glTF" + struct.pack("<II", 2, total) + struct.pack("<I", len(text)) + b"JSON"
            + text + struct.pack("<I", len(blob)) + b"BIN\0" + blob)


def test_a_glb_with_a_camera_renders_through_it(tmp_path):
    # A red unit square at z = 0, seen by the file's camera from z = 2.
    positions = struct.pack("<12f", -0.5, -0.5, 0, 0.5, -0.5, 0, 0.5, 0.5, 0, -0.5, 0.5, 0)
    indices = struct.pack("<6H", 0, 1, 2, 0, 2, 3)
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": 60}],
        "bufferViews": [{"buffer": 0, "byteLength": 48},
                        {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [-0.5, -0.5, 0], "max": [0.5, 0.5, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.1, 0.1, 1],
                                                "metallicFactor": 0}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1,
                                    "material": 0}]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.6, "znear": 0.1}}],
        "nodes": [{"mesh": 0}, {"camera": 0, "name": "front", "translation": [0, 0, 2]}],
        "scenes": [{"nodes": [0, 1]}],
    }
    path = tmp_path / "square.glb"
    path.write_bytes(glb(doc, positions + indices))
    scene = penumbra.load(path, threads=1)
    assert scene.cameras == ["front"]
    assert scene.stats["triangles"] == 2
    image = np.asarray(scene.render(spp=1, light_samples=1, width=20, height=20))
    centre = image[10, 10, :3]
    assert centre[0] > 2 * centre[1] and centre[0] > 2 * centre[2], centre
    hits = scene.raycasting_scene().cast_rays(
        np.array([[0, 0, 2, 0, 0, -1]], dtype=np.float32))
    assert hits["t_hit"].numpy()[0] == pytest.approx(2.0)


@pytest.mark.parametrize("edit, at, message", [
    (lambda d: d["accessors"][0].pop("type"), "accessors[0].type", "is missing"),
    (lambda d: (d.pop("scenes"), d.update(nodes=[{"mesh": 0, "children": [1]},
                                                 {"children": [0]}])),
     "nodes[0]", "cycle"),
])
def test_bad_json_is_named_by_its_json_path(tmp_path, edit, at, message):
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": 36}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
    }
    edit(doc)
    path = tmp_path / "bad.glb"
    path.write_bytes(glb(doc, struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)))
    with pytest.raises(penumbra.SceneError) as info:
        penumbra.load(path, threads=1)
    text = str(info.value)
    assert "bad.glb" in text and f"{at}: " in text and message in text, text
    assert "column" not in text, text
