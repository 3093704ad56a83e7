"""``allow_paths=``: a scene reads only files in its folder and below (a model in its own)
unless a folder is allowed, as the CLI's ``--allow-path``; a refusal is a SceneError naming the
key, the reference and the rule, and a pack carries the folders allowed."""

import json
import pickle

import pytest

import penumbra

TRIANGLE = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
SCENE = {
    "film": {"width": 4, "height": 4},
    "camera": {"position": [0.3, 0.3, 3], "look_at": [0.3, 0.3, 0], "fov": 40},
    "lights": [{"type": "point", "position": [0, 0, 3]}],
    "objects": [{"type": "mesh", "file": "../assets/tri.obj"}],
}


@pytest.fixture
def folders(tmp_path):
    (tmp_path / "assets").mkdir()
    (tmp_path / "assets" / "tri.obj").write_text(TRIANGLE)
    (tmp_path / "scenes").mkdir()
    return tmp_path


def test_a_file_outside_the_scene_folder_is_refused_unless_allowed(folders):
    scenes, assets = folders / "scenes", folders / "assets"
    path = scenes / "s.json"
    path.write_text(json.dumps(SCENE))
    refusals = [
        lambda **kw: penumbra.load(path, **kw),
        lambda **kw: penumbra.loads(json.dumps(SCENE), format="json", base_dir=scenes, **kw),
        lambda **kw: penumbra.load_dict(SCENE, base_dir=scenes, **kw),
    ]
    for load in refusals:
        with pytest.raises(penumbra.SceneError) as e:
            load()
        assert e.value.key == "objects[0].file"
        assert e.value.kind == "asset_mesh"
        message = str(e.value)
        assert '"../assets/tri.obj" is outside the scene\'s folder' in message
        assert "allow_paths=" in message
        assert load(allow_paths=[assets]).stats["triangles"] == 1
        # One folder alone is a list of one, as --allow-path once is.
        assert load(allow_paths=str(assets)).stats["triangles"] == 1
    with pytest.raises(penumbra.SceneError):
        penumbra.load(path, allow_paths=[folders / "scenes"])


def test_a_pack_carries_the_folders_allowed(folders):
    scene = penumbra.load_dict(SCENE, base_dir=folders / "scenes", allow_paths=[folders / "assets"])
    copy = pickle.loads(pickle.dumps(scene))
    assert copy.stats["triangles"] == 1
    assert copy.files == scene.files
