"""Batches and packs without a cluster: jobs files checked whole before anything runs, names
that stay inside the output folder, orbits checked before they are made, packs that are
snapshots of what was loaded, and digests that identify a pack."""

from __future__ import annotations

import os
import pickle
import time
from pathlib import Path

import pytest

import penumbra
from penumbra import batch, views
from penumbra._pack import PackedScene

from conftest import SCENES, same_bits


@pytest.mark.parametrize(
    "name, part",
    [
        ("..", "_."),
        (".", "_"),
        ("../../up", "_._.._up"),
        ("a/b", "a_b"),
        ("a\\b", "a_b"),
        ("C:", "C_"),
        ("nul\0byte", "nul_byte"),
        ("new\nline\x1b[31m", "new_line_[31m"),
        ("-rf", "_rf"),
        (".hidden", "_hidden"),
        ("", "_"),
        ("front", "front"),
        ("café 2", "café 2"),
    ],
)
def test_view_names_stay_one_file_name_in_the_output_folder(tmp_path, name, part):
    out = views.output_path(str(tmp_path / "out" / "{name}" / "{index}.png"), {"name": name}, 7)
    assert out == str(tmp_path / "out" / part / "7.png")
    assert os.path.dirname(os.path.dirname(os.path.normpath(out))) == str(tmp_path / "out")


def test_view_names_follow_the_command_lines_rule():
    # One rule: the library's, which the command line applies to {camera}.
    assert penumbra._core.file_name_part("../x") == views.output_path("{name}", {"name": "../x"}, 0)


def jobs_file(tmp_path: Path, text: str) -> str:
    path = tmp_path / "jobs.toml"
    path.write_text(f'scene = "{SCENES / "cornell.toml"}"\n{text}')
    return str(path)


VIEW = '[[views]]\nname = "a"\ncamera = "front"\n'


@pytest.mark.parametrize(
    "text, words",
    [
        # Unknown keys, everywhere in the file.
        ("[defaults]\nsppp = 4\n" + VIEW, "[defaults]: unknown key 'sppp'"),
        ("[orbit]\ncenter = [0, 1, 0]\nradius = 2\nframes = 2\nframe = 3\n", "[orbit]: unknown key 'frame'"),
        ("speed = 3\n" + VIEW, "unknown key 'speed'"),
        (VIEW + "spd = 4\n", "view 'a' (views[0]): unknown key 'spd'"),
        # Values of the wrong type.
        ("output = 3\n" + VIEW, "output must be a file name pattern, not 3"),
        ("cpus_per_task = \"2\"\n" + VIEW, "cpus_per_task must be a number of CPUs"),
        ("cpus_per_task = 0\n" + VIEW, "cpus_per_task must be a positive number of CPUs"),
        ("views_file = 5\n" + VIEW, "views_file must be a file name, not 5"),
        ("views = 3\n", "views must be a list of tables"),
        ("defaults = 3\n" + VIEW, "defaults must be a table"),
        ("orbit = [1]\n" + VIEW, "orbit must be a table"),
        ("[defaults]\nspp = \"4\"\n" + VIEW, "[defaults]: spp must be a positive integer, not '4'"),
        ("[defaults]\nwidth = 0\n" + VIEW, "[defaults]: width must be a positive integer, not 0"),
        ("[defaults]\nseed = -1\n" + VIEW, "[defaults]: seed must be an integer from 0"),
        ("[defaults]\naovs = [\"dpth\"]\n" + VIEW, "[defaults]: unknown AOV 'dpth' in aovs"),
        ("[defaults]\nsampler = 3\n" + VIEW, "[defaults]: sampler must be a name"),
        (VIEW + "spp = 2.5\n", "view 'a' (views[0]): spp must be a positive integer, not 2.5"),
        (VIEW + "height = true\n", "view 'a' (views[0]): height must be a positive integer"),
        (VIEW + "aovs = [\"depth\", 3]\n", "view 'a' (views[0]): unknown AOV 3 in aovs"),
        ('[[views]]\nname = 3\ncamera = "front"\n', "view 1 (views[0]): name must be a string"),
        ('[[views]]\nname = "p"\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\nfov = [1]\n',
         "view 'p' (views[0]):"),
        # An orbit is checked before its frames are made.
        ("[orbit]\ncenter = [0, 1, 0]\nradius = 2\nframes = 100000000\n",
         "orbit: frames must be from 1 to 100000, not 100000000"),
        ("[orbit]\ncenter = [0, 1, 0]\nradius = 2\nframes = 2.5\n",
         "orbit: frames must be an integer, not float 2.5"),
        ("[orbit]\ncenter = [0, 1, 0]\nradius = nan\nframes = 2\n",
         "orbit: radius must be a finite number, not nan"),
        ("[orbit]\ncenter = [0, 1, 0]\nradius = 2\nframes = 2\nname = \"o{frame}\"\n",
         "orbit: name 'o{frame}' is a pattern of {index} only"),
    ],
)
def test_mistakes_in_a_jobs_file_are_one_line_naming_the_key(tmp_path, text, words):
    path = jobs_file(tmp_path, text)
    start = time.monotonic()
    with pytest.raises(batch.JobsError) as caught:
        batch.read_jobs(path)
    message = str(caught.value)
    assert words in message and path in message, message
    assert "\n" not in message and "\x1b" not in message
    assert time.monotonic() - start < 5


def test_a_typo_in_defaults_was_silently_ignored_before(tmp_path):
    # The same file with the key spelled right reads, and its views take the default.
    jobs = batch.read_jobs(jobs_file(tmp_path, "[defaults]\nspp = 16\n" + VIEW))
    assert jobs["views"][0]["spp"] == 16


def test_an_orbit_of_a_hundred_million_frames_is_refused_at_once():
    start = time.monotonic()
    for frames in (10**8, 0, -3, 2.5, "8", True):
        with pytest.raises((TypeError, ValueError), match="orbit: frames must be"):
            views.orbit(center=(0, 1, 0), radius=2, frames=frames)
    assert time.monotonic() - start < 1
    assert len(views.orbit(center=(0, 1, 0), radius=2, frames=views.MAX_FRAMES)) == 100_000


SNAPSHOT_SCENE = """
[film]
width = 16
height = 12
[camera]
position = [0, 0, 4]
look_at = [0, 0, 0]
fov = 40
[[lights]]
type = "point"
position = [0, 0, 4]
[[objects]]
type = "mesh"
file = "tri.obj"
"""


def test_a_loaded_scene_is_a_snapshot_its_pickle_holds_the_mesh_as_loaded(tmp_path):
    mesh = tmp_path / "tri.obj"
    mesh.write_text("v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n")
    scene = penumbra.loads(SNAPSHOT_SCENE, base_dir=tmp_path)
    before = scene.render()
    digest = scene.pack().digest
    # The mesh edited after loading: two triangles, elsewhere.
    mesh.write_text("v 0 0 0\nv 2 0 0\nv 0 2 0\nv 2 2 0\nf 1 2 3\nf 2 4 3\n")
    copy = pickle.loads(pickle.dumps(scene))
    assert copy.stats["triangles"] == scene.stats["triangles"] == 1
    assert same_bits(copy.render(), before)
    assert scene.pack().digest == digest
    # A scene loaded now is the edited one, with another digest.
    now = penumbra.loads(SNAPSHOT_SCENE, base_dir=tmp_path)
    assert now.stats["triangles"] == 2 and now.pack().digest != digest


def pack(**data) -> PackedScene:
    base = {"format": "toml", "name": "s.toml", "base_dir": "/s", "text": "", "overrides": [],
            "files": {}}
    return PackedScene({**base, **data})


def test_different_packs_have_different_digests():
    # Pairs whose streams were the same when values were framed but lists were not counted.
    pairs = [
        (pack(overrides=["a=1", "m.obj", "v 0 0 0"]),
         pack(overrides=["a=1"], files={"m.obj": b"v 0 0 0"})),
        (pack(overrides=["a=1", "b.png", ""]), pack(overrides=["a=1"], files={"b.png": b""})),
    ]
    for one, other in pairs:
        assert one.digest != other.digest
    # And the digest stays a function of the content.
    assert pack(files={"m.obj": b"1"}).digest == pack(files={"m.obj": b"1"}).digest


@pytest.mark.parametrize("bad", ["film.width", "=3", '"film.width=3'])
def test_load_pack_with_a_bad_override_is_a_scene_error_naming_it(bad):
    scene = penumbra.load(SCENES / "cornell.toml")
    data = dict(scene.pack()._data, overrides=["film.width=8", bad])
    with pytest.raises(penumbra.SceneError) as caught:
        penumbra.load_pack(PackedScene(data))
    e = caught.value
    assert not isinstance(e, OSError)
    assert e.kind == "syntax" and bad in str(e) and "KEY.PATH=VALUE" in str(e), str(e)
