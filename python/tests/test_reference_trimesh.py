"""penumbra's reading of the shared glTF and PLY files against trimesh's: for every file of
../shared/assets/gltf/ and ../shared/assets/ply/ (skipped when the folder is absent),
`penumbra check --json FILE` gives trimesh's triangle count and world bounds (within 1e-4 of the
bounds' diagonal), trimesh reading it as `trimesh.load(path, force="scene", process=False)` with
the node transforms applied. A file whose format `check` does not know yet (exit 2, "unknown"
or "unsupported" in the message) is skipped, never passed."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

from conftest import cli_binary

trimesh = pytest.importorskip("trimesh")

ASSETS = Path(__file__).resolve().parents[3] / "shared" / "assets"
SUFFIXES = {"gltf": (".gltf", ".glb"), "ply": (".ply",)}


def shared_files() -> list[Path]:
    files = []
    for folder, suffixes in SUFFIXES.items():
        root = ASSETS / folder
        if root.is_dir():
            files += sorted(p for p in root.rglob("*") if p.suffix.lower() in suffixes)
    return files


def trimesh_reading(path: Path) -> tuple[int, np.ndarray]:
    """Triangles (every node's use of a mesh) and world bounds, node transforms applied.
    glTF materials are skipped: geometry is all this compares, and the pine's normal maps are
    absent upstream."""
    gltf = path.suffix.lower() in SUFFIXES["gltf"]
    extra = {"skip_materials": True} if gltf else {}
    scene = trimesh.load(path, force="scene", process=False, **extra)
    meshes = [g for g in scene.dump() if hasattr(g, "faces")]
    triangles = sum(len(m.faces) for m in meshes)
    vertices = np.concatenate([m.vertices[np.unique(m.faces)] for m in meshes if len(m.faces)])
    return triangles, np.array([vertices.min(axis=0), vertices.max(axis=0)])


@pytest.mark.parametrize("path", shared_files(), ids=lambda p: f"{p.parent.name}/{p.name}")
def test_check_reads_what_trimesh_reads(path: Path):
    out = subprocess.run(
        [str(cli_binary()), "check", "--json", str(path)],
        capture_output=True,
        text=True,
        check=False,
    )
    message = out.stderr.lower()
    if out.returncode == 2 and ("unknown" in message or "unsupported" in message):
        pytest.skip(f"check does not read this format yet: {out.stderr.strip()}")
    assert out.returncode == 0, out.stderr
    summary = json.loads(out.stdout)
    triangles, bounds = trimesh_reading(path)
    assert summary["triangles"] == triangles
    ours = np.array([summary["bounds"]["min"], summary["bounds"]["max"]])
    diagonal = np.linalg.norm(bounds[1] - bounds[0])
    assert np.abs(ours - bounds).max() <= 1e-4 * diagonal, (ours, bounds)


def test_the_shared_files_are_found_when_present():
    if not ASSETS.is_dir():
        pytest.skip("../shared/assets is absent")
    names = {p.name for p in shared_files()}
    assert {"bunny_zipper.ply", "cube_blender_uv.ply"} <= names
