"""penumbra.distributed on a real local Ray instance (one node, 2 CPUs): frames over tiles and
batches of views are the bytes one process renders; the world is built once per worker; a
worker killed mid-batch changes nothing; a second run skips what is done."""

from __future__ import annotations

import json
import math
import os
import signal
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import ray_env

ray = ray_env.ray

import penumbra  # noqa: E402
from penumbra import _view_files, distributed, poses, views  # noqa: E402

from conftest import SCENES, run_cli, same_bits  # noqa: E402


@pytest.fixture(scope="module")
def cluster():
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield
    ray.shutdown()


@pytest.fixture(scope="module")
def showcase():
    """Meshes, an MTL and textures: everything a pack must carry."""
    return penumbra.load(SCENES / "showcase.toml", allow_paths=[SCENES.parent / "assets"])


def fresh_room(tag: str) -> penumbra.Scene:
    """The seed's room with a comment that makes its pack (and digest) new, so that no worker
    has its world yet."""
    text = (SCENES / "cornell.toml").read_text()
    return penumbra.loads(f"# {tag} {time.time_ns()}\n{text}", base_dir=SCENES)


@pytest.mark.parametrize("tiles", [1, 5, (3, 2), (7, 9), 1000])
def test_a_frame_over_tiles_is_the_single_process_render(cluster, showcase, tiles):
    kw = dict(width=57, height=41, spp=4, seed=3, sampler="jittered", light_samples=2)
    aovs = ("depth", "normal", "albedo", "position", "object_id", "primitive_id")
    image, passes = distributed.render_frame(showcase, tiles=tiles, aovs=aovs, **kw)
    ref, ref_passes = showcase.render(aovs=aovs, **kw)
    assert same_bits(image, ref)
    assert sorted(passes) == sorted(ref_passes)
    for name in aovs:
        assert passes[name].dtype == ref_passes[name].dtype, name
        assert np.array_equal(passes[name].view(np.uint32), ref_passes[name].view(np.uint32)), name


def test_progress_true_without_tqdm_warns_how_to_install_it(cluster, monkeypatch):
    monkeypatch.setitem(sys.modules, "tqdm", None)
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)
    scene = penumbra.load(SCENES / "cornell.toml")
    with pytest.warns(RuntimeWarning, match="pip install tqdm") as caught:
        image = distributed.render_frame(scene, tiles=2, width=8, height=6, progress=True)
    assert image.shape == (6, 8, 3) and caught[0].filename == __file__


def test_tiles_and_connect_take_whole_numbers_naming_the_argument():
    # Issue 63, class 6: int(2.5) made 2 tiles; NaN failed inside int().
    for tiles, error in [(2.5, TypeError), ((2, math.nan), TypeError), ({1, 2}, TypeError),
                         (0, ValueError), ((3, -1), ValueError)]:
        with pytest.raises(error, match="tile_regions: tiles"):
            distributed.tile_regions(8, 6, tiles)
    with pytest.raises(TypeError, match="tile_regions: width must be an integer, not float 8.0"):
        distributed.tile_regions(8.0, 6, 2)
    assert distributed.tile_regions(np.int64(8), 6, (np.int32(2), 1)) == [(0, 4, 0, 6), (4, 8, 0, 6)]
    with pytest.raises(TypeError, match="connect: num_cpus must be an integer, not float 2.5"):
        distributed.connect("local", num_cpus=2.5)
    with pytest.raises(ValueError, match="connect: timeout must be a finite number, not nan"):
        distributed.connect("auto", timeout=math.nan)


def test_tiles_cover_the_frame_once():
    for w, h, tiles in [(57, 41, 5), (57, 41, (3, 2)), (4, 3, (9, 9)), (1, 1, 7)]:
        cover = np.zeros((h, w), int)
        for x0, x1, y0, y1 in distributed.tile_regions(w, h, tiles):
            assert x0 < x1 and y0 < y1
            cover[y0:y1, x0:x1] += 1
        assert (cover == 1).all(), (w, h, tiles)
    with pytest.raises(ValueError):
        distributed.tile_regions(8, 8, 0)


def test_views_are_their_one_by_one_renders_and_worlds_are_built_once_per_worker(cluster, tmp_path):
    scene = fresh_room("views")
    batch = [
        "front",
        {"name": "high", "camera": "high", "spp": 1, "seed": 9},
        {"name": "pose", "position": [2.5, 5, -0.5], "look_at": [-1, 1, -4], "fov": 60},
        *views.orbit(center=(0, 1, -3), radius=2.6, height=4.2, frames=5, fov=75),
    ]
    summary = distributed.render_views(
        scene, batch, output=str(tmp_path / "{index}-{name}.png"), width=40, height=30, spp=4
    )
    # A view given as a camera name is called by it ("front" -> {name} = front).
    assert [r["name"] for r in summary] == ["front", "high", "pose"] + [
        f"orbit{k:04d}" for k in range(5)
    ]
    for i, (spec, r) in enumerate(zip(batch, summary)):
        v = views.view(spec, i, width=40, height=30, spp=4)
        local = scene.render(
            camera=v["camera"], **{k: v[k] for k in views.RENDER_KEYS if v[k] is not None}
        )
        expected = tmp_path / f"expected-{i}.png"
        penumbra.write_image(expected, local)
        assert Path(r["path"]).read_bytes() == expected.read_bytes(), r["name"]
        assert r["path"] == str(tmp_path / f"{i}-{r['name']}.png")
        assert not r["skipped"] and r["seconds"] > 0 and r["rays_per_second"] > 0
    # Each worker process that rendered built the (new) world exactly once.
    pids = {r["pid"] for r in summary}
    assert sum(r["built"] for r in summary) == len(pids) <= 2
    # A second batch of the same scene builds nothing.
    again = distributed.render_views(
        scene, batch[:3], output=str(tmp_path / "again-{name}.png"), width=8, height=6
    )
    assert not any(r["built"] for r in again)


def test_a_second_run_skips_complete_views_and_force_renders_them(cluster, tmp_path):
    scene = penumbra.load(SCENES / "cornell.toml")
    out = str(tmp_path / "{name}.png")
    batch = ["front", "left", {"name": "hi", "camera": "high", "aovs": ["depth", "object_id"]}]
    first = distributed.render_views(scene, batch, output=out, width=16, height=12)
    assert not any(r["skipped"] for r in first)
    assert sorted(p.name for p in tmp_path.glob("*.png")) == ["front.png", "hi.png", "left.png"]
    npz = np.load(tmp_path / "hi.aovs.npz")
    assert sorted(npz.files) == ["depth", "object_id"] and npz["depth"].shape == (12, 16)
    (tmp_path / "left.png").unlink()
    stamp = (tmp_path / "front.png").stat().st_mtime_ns
    told: list = []

    def heard(r):  # what on_view is told, and whether the image is there by then
        told.append((r["name"], r["skipped"], "seconds" in r, Path(r["path"]).is_file()))

    second = distributed.render_views(
        scene, batch, output=out, width=16, height=12, on_view=heard
    )
    assert [r["skipped"] for r in second] == [True, False, True]
    assert (tmp_path / "front.png").stat().st_mtime_ns == stamp
    # Every view once, the skipped ones first; a rendered one after its image is written.
    assert told == [("front", True, False, True), ("hi", True, False, True),
                    ("left", False, True, True)]
    third = distributed.render_views(scene, batch, output=out, width=16, height=12, force=True)
    assert not any(r["skipped"] for r in third)


def test_a_view_is_done_only_when_its_record_says_it_was_made_so(cluster, tmp_path):
    # The rule of `penumbra render --resume`: the image there and its record's settings
    # those of the render it would be now; anything else renders the view again.
    room = penumbra.load(SCENES / "cornell.toml")
    warm = penumbra.load(SCENES / "cornell_warm.toml")
    batch = ["front", {"name": "hi", "camera": "high", "aovs": ["depth"]}]
    kw = dict(output=str(tmp_path / "{name}.png"), width=16, height=12, spp=1)

    def skipped(scene, **change):
        return [r["skipped"] for r in distributed.render_views(scene, batch, **{**kw, **change})]

    assert skipped(room) == [False, False]
    assert skipped(room) == [True, True]
    # Another scene into the same files (issue 62): both render again, and the images are its.
    assert skipped(warm) == [False, False]
    penumbra.write_image(tmp_path / "expected.png", warm.render(camera="front", width=16,
                                                                height=12, spp=1))
    assert (tmp_path / "front.png").read_bytes() == (tmp_path / "expected.png").read_bytes()
    assert skipped(warm) == [True, True]
    # Other settings, and another camera under the same name.
    assert skipped(warm, spp=4) == [False, False]
    assert skipped(warm, spp=4, seed=9) == [False, False]
    moved = [{"name": "front", "camera": "left"}, batch[1]]
    assert [r["skipped"] for r in distributed.render_views(
        warm, moved, **{**kw, "spp": 4, "seed": 9})] == [False, True]
    # A record that is unreadable, or an AOV file that is missing: that view alone.
    (tmp_path / "front.meta.json").write_text("{")
    (tmp_path / "hi.aovs.npz").unlink()
    batch[0] = moved[0]
    assert skipped(warm, spp=4, seed=9) == [False, False]
    assert skipped(warm, spp=4, seed=9) == [True, True]
    # Without records nothing is known to be done, and no old record is left behind.
    assert skipped(warm, spp=4, seed=9, meta=False) == [False, False]
    assert not list(tmp_path.glob("*.meta.json"))
    assert skipped(warm, spp=4, seed=9) == [False, False]


def running_task_pids(title: str) -> list:
    """Processes whose title Ray set to ``ray::TITLE``: workers running that task now."""
    pids = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                cmdline = (entry / "cmdline").read_bytes()
            except OSError:
                continue
            if cmdline.startswith(f"ray::{title}".encode()):
                pids.append(int(entry.name))
    return pids


def kill_a_worker_running(title: str, killed: list) -> None:
    """Kills (SIGKILL) the first worker seen running the task ``title``, within 20 s."""
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline:
        for pid in running_task_pids(title):
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                continue
            killed.append(pid)
            return
        time.sleep(0.01)


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="finds Ray's workers through /proc")
def test_a_worker_killed_mid_batch_changes_nothing(cluster, tmp_path):
    scene = fresh_room("kill")
    batch = views.orbit(center=(0, 1, -3), radius=2.6, height=4.2, frames=12, fov=75)
    settings = dict(width=64, height=64, spp=16, light_samples=5)
    killed: list = []
    killer = threading.Thread(target=kill_a_worker_running, args=("render_task", killed))
    killer.start()
    try:
        summary = distributed.render_views(
            scene, batch, output=str(tmp_path / "{name}.png"), **settings
        )
    finally:
        killer.join()
    assert killed, "no worker was seen running a render task"
    with pytest.raises(ProcessLookupError):
        os.kill(killed[0], 0)
    for v, r in zip(batch, summary):
        local = scene.render(camera=v["camera"], **settings)
        expected = tmp_path / "expected.png"
        penumbra.write_image(expected, local)
        assert Path(r["path"]).read_bytes() == expected.read_bytes(), r["name"]
    # Every image whole with its record, and nothing else (no temporary file) in the folder.
    names = sorted(p.name for p in tmp_path.iterdir())
    written = [f"{v['name']}{ext}" for v in batch for ext in (".png", ".meta.json")]
    assert names == sorted(written + ["expected.png"])


def test_every_public_name_is_documented():
    from test_docs import public_undocumented

    assert distributed.__doc__ and public_undocumented(distributed) == []


def test_a_scene_pickles_as_its_pack(showcase):
    import pickle

    pack = showcase.pack()
    assert pack.files == showcase.files and len(pack.files) == 4
    again = pickle.loads(pickle.dumps(showcase))
    assert again.pack().digest == pack.digest
    kw = dict(width=24, height=16, spp=1)
    assert same_bits(again.render(**kw), showcase.render(**kw))


@pytest.mark.parametrize(
    "kw, words",
    [
        (dict(width=0), "render_frame: width must be a positive integer, not 0"),
        (dict(height=-2), "render_frame: height must be a positive integer, not -2"),
        (dict(spp=3), "render_frame: samples per pixel must be a perfect square"),
        (dict(aovs=("depth", "dpth")), "render_frame: unknown AOV 'dpth' in aovs"),
        (dict(camera="nowhere"), "render_frame: no camera named"),
        (dict(num_cpus=64), "render_frame: num_cpus is 64 CPUs per task, more than any node"),
        (dict(num_cpus=0), "render_frame: num_cpus must be a positive number of CPUs"),
    ],
)
def test_render_frame_refuses_bad_arguments_at_once_naming_them(cluster, kw, words):
    scene = penumbra.load(SCENES / "cornell.toml")
    start = time.monotonic()
    with pytest.raises(ValueError) as caught:
        distributed.render_frame(scene, tiles=2, **kw)
    assert words in str(caught.value) and "\n" not in str(caught.value), str(caught.value)
    assert time.monotonic() - start < 10


@pytest.mark.parametrize(
    "view, words",
    [
        ({"name": "b", "camera": "high", "spp": 3}, "views[1] ('b'): samples per pixel must be a perfect square"),
        ({"name": "b", "camera": "high", "spp": 3.0}, "views[1] ('b'): spp must be a positive integer"),
        ({"name": "b", "camera": "high", "aovs": ["normals"]}, "views[1] ('b'): unknown AOV 'normals'"),
        ({"name": "b", "camera": "high", "sampler": "center", "spp": 4}, "views[1] ('b'): the center sampler"),
        ({"name": "b", "camera": "high", "width": 10**6, "height": 10**6}, "views[1] ('b'): a 1000000x1000000 image"),
        ({"name": "b", "camera": "high", "sampler": "random"}, "views[1] ('b'): unknown sampler \"random\""),
    ],
)
def test_views_are_checked_on_this_process_before_anything_is_shipped(cluster, tmp_path, view, words):
    scene = fresh_room("checked")
    with pytest.raises(views.ViewError) as caught:
        distributed.render_views(scene, ["front", view], output=str(tmp_path / "o" / "{name}.png"))
    message = str(caught.value)
    assert words in message and "\n" not in message and "\x1b" not in message, message
    assert not (tmp_path / "o").exists()


def test_more_cpus_per_task_than_any_node_has_is_refused_not_queued_forever(cluster, tmp_path):
    scene = penumbra.load(SCENES / "cornell.toml")
    start = time.monotonic()
    with pytest.raises(ValueError, match=r"num_cpus is 3 CPUs per task, more than any node .*at most 2"):
        distributed.render_views(scene, ["front"], output=str(tmp_path / "{name}.png"), num_cpus=3)
    assert time.monotonic() - start < 10 and not list(tmp_path.iterdir())
    # As many as a node has is fine.
    done = distributed.render_views(
        scene, ["front"], output=str(tmp_path / "{name}.png"), num_cpus=2, width=8, height=6
    )
    assert not done[0]["skipped"]


def test_an_image_and_its_aovs_are_written_together_or_not_at_all(cluster, tmp_path, monkeypatch):
    scene = penumbra.load(SCENES / "cornell.toml")
    out = str(tmp_path / "{name}.png")
    batch = [{"name": "hi", "camera": "high", "aovs": ["depth"]}]
    distributed.render_views(scene, batch, output=out, width=16, height=12)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    assert sorted(before) == ["hi.aovs.npz", "hi.meta.json", "hi.png"]

    def full_disk(path, image, gamma=None):
        raise OSError(28, "No space left on device", str(path))

    # The disk fills while the image is written, after its AOVs: nothing changes.
    monkeypatch.setattr(_view_files._core, "stage_image", full_disk)
    with pytest.raises(OSError, match="No space left") as info:
        distributed.render_views(scene, batch, output=out, width=8, height=6, force=True)
    # Named as the image asked for, not its temporary file (issue 63, class 7).
    assert str(tmp_path / "hi.png") in str(info.value) and ".tmp-" not in str(info.value)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
    # A new view: neither file, and no temporary file.
    with pytest.raises(OSError, match="No space left"):
        distributed.render_views(scene, [dict(batch[0], name="new")], output=out, width=16, height=12)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(before)


def settings_text(path) -> str:
    """The text of a record's ``settings``, as written (its first key)."""
    text = path.read_text()
    assert text.startswith('{"settings":{'), text[:40]
    return text[: text.index(',"image":')]


def test_render_views_writes_the_command_lines_record_beside_each_image(cluster, tmp_path):
    # Each view's OUT.meta.json decodes to the numbers penumbra.poses computes and to the
    # record penumbra render --meta writes for the same scene, camera and settings.
    scene = penumbra.load(SCENES / "cornell.toml")
    side = penumbra.Camera((2.5, 1.5, 6), (0, 1.2, -1), (0, 1, 0), 35)
    batch = [
        {"name": "high", "camera": "high", "aovs": ["object_id"]},
        {"name": "side", "camera": side},
        {"name": "default", "width": 10},
    ]
    out = str(tmp_path / "py" / "{name}.png")
    done = distributed.render_views(scene, batch, output=out, width=16, height=12, spp=1, meta=True)
    assert not any(r["skipped"] for r in done)
    cli_side = "cameras.side={position = [2.5, 1.5, 6], look_at = [0, 1.2, -1], fov = 35}"
    for view, camera, extra in (
        (batch[0], "high", ["--aov", "object_id"]),
        (batch[1], "side", ["--set", cli_side]),
        (batch[2], "front", []),
    ):
        w = 10 if view["name"] == "default" else 16
        image = tmp_path / "py" / f"{view['name']}.png"
        mine = json.loads((tmp_path / "py" / f"{view['name']}.meta.json").read_text())
        cli_image = tmp_path / "cli" / f"{view['name']}.png"
        run_cli(
            "render", SCENES / "cornell.toml", "--camera", camera, "--width", w, "--height", 12,
            "--spp", 1, "--meta", "--quiet", "-o", cli_image, *extra,
        )
        cli = json.loads(cli_image.with_suffix(".meta.json").read_text())
        pose = poses.camera_pose(side if camera == "side" else scene.camera(camera), w, 12)
        assert (mine["width"], mine["height"]) == (cli["width"], cli["height"]) == (w, 12)
        for key, matrix in pose.items():
            assert mine[key] == matrix.tolist() == cli[key], (view["name"], key)
        assert mine["image"] == str(image) and mine["view"] == view["name"]
        assert mine["objects"] == cli["objects"] == scene.objects
        assert mine["files"] == [str(image)] + (
            [str(image.with_suffix(".aovs.npz"))] if view.get("aovs") else []
        )
        # Both records are written by one function (penumbra::products::record): what this
        # tests is that the batch hands it the settings the command line does.
        settings = settings_text(tmp_path / "py" / f"{view['name']}.meta.json")
        cli_settings = settings_text(cli_image.with_suffix(".meta.json"))
        if view["name"] == "side":
            # The explicit camera is no camera of the file, and the CLI's scene has an
            # override: its digest and camera differ, the rest is the same, to the bit.
            render, cli_render = mine["settings"]["render"], cli["settings"]["render"]
            assert render.pop("camera") == {"pinhole": {
                "position": [2.5, 1.5, 6.0], "look_at": [0.0, 1.2, -1.0], "up": [0.0, 1.0, 0.0],
                "fov": 35.0}}
            assert cli_render.pop("camera") == {"named": "side"}
            assert render == cli_render
            assert mine["settings"]["camera"] is None and cli["settings"]["camera"] == "side"
            assert mine["settings"]["scene_digest"] == scene.scene_digest
            assert cli["settings"]["scene_digest"] != scene.scene_digest
            for key in ("penumbra", "frame", "region", "aovs", "gamma", "format"):
                assert mine["settings"][key] == cli["settings"][key], key
        else:
            assert settings == cli_settings, view["name"]
            assert mine["settings"]["render"]["camera"] == {"named": camera}
        assert mine["settings"]["aovs"] == list(view.get("aovs", []))

    # With meta, a view without its record is not done: only that one renders again.
    again = distributed.render_views(scene, batch, output=out, width=16, height=12, spp=1, meta=True)
    assert all(r["skipped"] for r in again)
    (tmp_path / "py" / "side.meta.json").unlink()
    again = distributed.render_views(scene, batch, output=out, width=16, height=12, spp=1, meta=True)
    assert [r["skipped"] for r in again] == [True, False, True]
    assert (tmp_path / "py" / "side.meta.json").is_file()
    assert not [p for p in (tmp_path / "py").iterdir() if p.name.startswith(".")]


def test_a_view_the_record_cannot_describe_fails_before_any_task(cluster, tmp_path):
    scene = penumbra.load(SCENES / "cornell.toml")
    with pytest.raises(ValueError, match=r"views\[0\] \('front'\): .*\.bmp.*record's image"):
        distributed.render_views(scene, ["front"], output=str(tmp_path / "{name}.bmp"), meta=True)
    assert not list(tmp_path.iterdir())



def test_render_views_writes_the_scenes_gamma_as_the_command_line_does(cluster, tmp_path):
    # film.gamma changes the 8-bit encoding: the batch's PNG is the CLI's, byte for byte, and
    # both records say which gamma.
    text = (SCENES / "cornell.toml").read_text().replace("[film]\n", "[film]\ngamma = 1.8\n", 1)
    path = tmp_path / "gamma.toml"
    path.write_text(text)
    scene = penumbra.load(path)
    assert scene.gamma == pytest.approx(1.8)
    out = str(tmp_path / "py" / "{name}.png")
    distributed.render_views(scene, [{"name": "front"}], output=out, width=16, height=12,
                             spp=1, meta=True)
    cli_image = tmp_path / "cli" / "front.png"
    run_cli("render", path, "--width", 16, "--height", 12, "--spp", 1, "--meta", "--quiet",
            "-o", cli_image)
    mine = (tmp_path / "py" / "front.png").read_bytes()
    assert mine == cli_image.read_bytes()
    # The sRGB curve gives other bytes: the test sees the gamma.
    image = scene.render(width=16, height=12, spp=1)
    srgb = tmp_path / "srgb.png"
    penumbra.write_image(srgb, image)
    assert srgb.read_bytes() != mine
    record = json.loads((tmp_path / "py" / "front.meta.json").read_text())
    cli = json.loads(cli_image.with_suffix(".meta.json").read_text())
    assert record["settings"]["gamma"] == cli["settings"]["gamma"] == pytest.approx(1.8)
