"""Records beside images from Python (issue 28): a scene's named cameras, its digest and its
objects are the command line's, and penumbra.record writes the layout of `penumbra render
--meta`. render_views(meta=True) is tested on Ray in test_distributed.py."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

import penumbra
from penumbra import poses, record

from conftest import SCENES, run_cli


def test_named_cameras_are_the_ones_a_render_uses():
    scene = penumbra.load(SCENES / "cornell.toml")
    for name in scene.cameras:
        camera = scene.camera(name)
        assert isinstance(camera, penumbra.Camera)
        # The same numbers: the image of the name and of the explicit camera agree.
        by_name = scene.render(camera=name, width=12, height=9, spp=1)
        explicit = scene.render(camera=camera, width=12, height=9, spp=1)
        assert (by_name == explicit).all(), name
    assert scene.camera() == scene.camera(scene.cameras[0])
    assert scene.camera("high").fov == 50.0
    with pytest.raises(ValueError, match=r"unknown camera 'nowhere' \(the scene's cameras: front, left, high\)"):
        scene.camera("nowhere")
    with pytest.raises(TypeError, match="camera name"):
        scene.camera(3)


def test_a_path_cameras_name_gives_its_first_frame(tmp_path):
    text = (SCENES / "cornell.toml").read_text() + (
        '\n[cameras.turn]\nfov = 30\npath = { type = "orbit", center = [0, 1, 0], '
        "radius = 3, height = 1, frames = 4, start_angle = 90 }\n"
    )
    scene = penumbra.loads(text, base_dir=SCENES)
    assert scene.camera("turn") == scene.camera_path("turn")[0]


def test_the_digest_and_objects_are_the_command_lines(tmp_path):
    # A scene with an OBJ and its MTL: the digest covers their bytes, as the CLI's does.
    folder = tmp_path / "scene"
    shutil.copytree(SCENES.parent / "assets" / "scenes" / "cornell_box", folder / "box")
    scene_file = folder / "box.toml"
    scene_file.write_text(
        (SCENES / "cornell_obj.toml").read_text().replace("../assets/scenes/cornell_box/", "box/")
    )
    run_cli("render", scene_file, "--width", 4, "--height", 3, "--spp", 1, "--meta",
            "--quiet", "-o", tmp_path / "a.png")
    cli = json.loads((tmp_path / "a.meta.json").read_text())
    scene = penumbra.load(scene_file)
    assert scene.scene_digest == cli["settings"]["scene_digest"]
    assert scene.objects == cli["objects"]
    assert scene.objects[0]["type"].startswith("mesh ")
    # An edited material library changes both, and a loaded scene keeps what it read.
    mtl = next((folder / "box").glob("*.mtl"))
    mtl.write_text(mtl.read_text() + "\n# edited\n")
    run_cli("render", scene_file, "--width", 4, "--height", 3, "--spp", 1, "--meta",
            "--quiet", "-o", tmp_path / "b.png")
    edited = json.loads((tmp_path / "b.meta.json").read_text())["settings"]["scene_digest"]
    assert edited != cli["settings"]["scene_digest"]
    assert scene.scene_digest == cli["settings"]["scene_digest"]
    assert penumbra.load(scene_file).scene_digest == edited


def test_instances_entries_name_their_object_ids():
    scene = penumbra.load_dict(
        {
            "film": {"width": 8, "height": 6},
            "camera": {"position": [0, 0, 9], "look_at": [0, 0, 0], "fov": 40},
            "objects": [
                {"type": "sphere", "center": [0, 0, 0], "radius": 1},
                {
                    "type": "instances",
                    "file": str(SCENES.parent / "assets" / "meshes" / "spot_triangulated.obj"),
                    "transforms": [{"translate": [x, 0, 0]} for x in (-2, 0, 2)],
                },
                {"type": "cube", "center": [0, -2, 0], "size": 1},
            ],
        }
    )
    kinds = [(o["key"], o["type"].split()[0], o["ids"]) for o in scene.objects]
    assert kinds == [
        ("objects[0]", "sphere", [0, 1]),
        ("objects[1]", "instances", [1, 4]),
        ("objects[2]", "cube", [4, 5]),
    ]


def test_a_record_holds_the_pose_of_each_kind_of_view(tmp_path):
    scene = penumbra.load(SCENES / "cornell.toml")
    side = penumbra.Camera((1, 2, 6), (0, 1, 0), (0, 1, 0), 30)
    for view, camera in (("left", scene.camera("left")), (side, side),
                         ({"spp": 1}, scene.camera("front"))):
        r = record.record(scene, view, tmp_path / "x.exr")
        pose = poses.camera_pose(camera, 512, 512)
        assert all(r[k] == m.tolist() for k, m in pose.items())
        assert r["settings"]["format"] == "exr" and r["files"] == [str(tmp_path / "x.exr")]
    r = record.record(scene, {"camera": "high", "width": 8, "height": 4, "aovs": "depth"},
                      tmp_path / "y.JPEG")
    assert (r["width"], r["height"], r["settings"]["format"]) == (8, 4, "jpg")
    assert r["files"] == [str(tmp_path / "y.JPEG"), str(tmp_path / "y.aovs.npz")]
    path = record.write_record(tmp_path / "y.JPEG", r)
    assert path == str(tmp_path / "y.meta.json")
    assert json.loads((tmp_path / "y.meta.json").read_text()) == r
    assert sorted(p.name for p in tmp_path.iterdir()) == ["y.meta.json"]
    with pytest.raises(ValueError, match=r"out\.bmp: a record's image is .*not '\.bmp'"):
        record.record(scene, "front", "out.bmp")
    with pytest.raises(ValueError, match="unknown camera 'nowhere'"):
        record.record(scene, "nowhere", "out.png")


def test_a_view_that_cannot_be_written_names_its_image_not_a_temporary_file(tmp_path):
    # Issue 63, class 7: the message named `.a.png.tmp-22127-0.png`.
    from penumbra._view_files import write_view

    wide = np.zeros((1, 70_000, 3), np.float32)  # beyond JPEG's 65535 pixels a side
    image = tmp_path / "a.jpg"
    with pytest.raises(ValueError) as info:
        write_view(str(image), wide, {"depth": np.zeros((1, 70_000), np.float32)})
    assert str(image) in str(info.value) and ".tmp-" not in str(info.value), str(info.value)
    # An image whose place is taken by a folder: the rename names the image.
    (tmp_path / "b.png").mkdir()
    with pytest.raises(OSError) as info:
        write_view(str(tmp_path / "b.png"), np.zeros((2, 2, 3), np.float32), {})
    assert str(tmp_path / "b.png") in str(info.value) and ".tmp-" not in str(info.value)
    # Nothing is left behind: no temporary file, no AOV file without its image.
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.png"]
