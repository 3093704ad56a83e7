"""`python -m penumbra.batch`, end to end in subprocesses that start their own local Ray
instance: the example jobs file, a second run that skips, errors in the jobs file, an
unreachable cluster and Ctrl-C."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import ray_env  # noqa: F401  (sets Ray's environment; skips without Ray)

import penumbra
import penumbra.coco
import penumbra.poses
from penumbra import batch, views

from conftest import SCENES, python_with_sigint


def run_batch(
    *args: object, timeout: float = 300, env: "dict | None" = None
) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "penumbra.batch", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=os.environ if env is None else env,
    )


def example_jobs(tmp_path: Path, **replace: str) -> Path:
    """scenes/batch/orbit.toml moved to tmp_path: its scene by absolute path, its images under
    tmp_path/out."""
    text = (SCENES / "batch" / "orbit.toml").read_text()
    text = text.replace('scene = "../cornell.toml"', f'scene = "{SCENES / "cornell.toml"}"')
    text = text.replace('output = "../../out/batch/{name}.png"', 'output = "out/{name}.png"')
    for old, new in replace.items():
        assert old in text, old
        text = text.replace(old, new)
    path = tmp_path / "jobs.toml"
    path.write_text(text)
    return path


SMALL = {"spp = 4": "spp = 1", "width = 256": "width = 64", "height = 256": "height = 48"}


def test_the_example_jobs_file_end_to_end(tmp_path):
    jobs = example_jobs(tmp_path, **SMALL)
    # Ray's own default (token authentication for a new local instance, its token under
    # HOME), named by the batch so that Ray does not warn about it on every run.
    home = tmp_path / "home"
    home.mkdir()
    env = {k: v for k, v in os.environ.items() if k != "RAY_AUTH_MODE"}
    out = run_batch(jobs, "--num-cpus", 2, "--json", env={**env, "HOME": str(home)})
    assert out.returncode == 0, out.stderr
    assert "Token authentication" not in out.stderr, out.stderr
    summary = json.loads(out.stdout)["views"]
    spec = batch.read_jobs(str(jobs))
    assert [r["name"] for r in summary] == [v["name"] for v in spec["views"]]
    assert len(summary) == 3 + 8 and not any(r["skipped"] for r in summary)
    # With --json, each view's line went to stderr as it finished (stdout is the JSON).
    told = [line.split("\t")[0] for line in out.stderr.splitlines() if line.endswith("Mrays/s")]
    assert sorted(told) == sorted(r["name"] for r in summary), out.stderr
    scene = penumbra.load(SCENES / "cornell.toml")
    for v, r in zip(spec["views"], summary):
        assert r["path"] == str(tmp_path / "out" / f"{v['name']}.png")
        local = scene.render(
            camera=v["camera"], **{k: v[k] for k in views.RENDER_KEYS if v[k] is not None}
        )
        penumbra.write_image(tmp_path / "expected.png", local)
        assert Path(r["path"]).read_bytes() == (tmp_path / "expected.png").read_bytes(), r["name"]

    again = run_batch(jobs, "--num-cpus", 2)
    assert again.returncode == 0, again.stderr
    lines = again.stdout.splitlines()
    assert len(lines) == 11 and all("skipped (done before" in line for line in lines), again.stdout
    assert all((tmp_path / "out" / f"{v['name']}.meta.json").is_file() for v in spec["views"])
    # Another scene's batch into the same files is not done: every view renders again (issue
    # 62: the images of the first scene were left under the names of the second).
    warm = example_jobs(tmp_path, **SMALL, **{"cornell.toml": "cornell_warm.toml"})
    other = run_batch(warm, "--num-cpus", 2, "--json")
    assert other.returncode == 0, other.stderr
    assert not any(r["skipped"] for r in json.loads(other.stdout)["views"])
    front = penumbra.load(SCENES / "cornell_warm.toml").render(
        camera="front", width=64, height=48, spp=1
    )
    penumbra.write_image(tmp_path / "expected.png", front)
    assert (tmp_path / "out" / "front.png").read_bytes() == (tmp_path / "expected.png").read_bytes()
    forced = run_batch(warm, "--num-cpus", 2, "--json", "--force")
    assert forced.returncode == 0, forced.stderr
    assert not any(r["skipped"] for r in json.loads(forced.stdout)["views"])


def test_mistakes_in_the_jobs_file_exit_2_naming_them(tmp_path):
    jobs = example_jobs(
        tmp_path, **{'output = "out/{name}.png"\n': 'output = "out/{name}.png"\nspeed = 3\n'}
    )
    out = run_batch(jobs)
    assert out.returncode == 2 and "unknown key 'speed'" in out.stderr and str(jobs) in out.stderr
    jobs = example_jobs(tmp_path, **{"frames = 8": "frames = 0"})
    out = run_batch(jobs)
    assert out.returncode == 2 and "orbit" in out.stderr and "orbit: frames must be from 1" in out.stderr
    # A view is named by its name (else its place from 1), its key path and its line; the
    # scene's cameras are checked before Ray starts.
    jobs = example_jobs(tmp_path, **{'camera = "high"': 'camera = "nowhere"'})
    out = run_batch(jobs, "--num-cpus", 1)
    assert out.returncode == 2, out.stderr
    assert f"{jobs}:15: view 'high' (views[1]): unknown camera 'nowhere'" in out.stderr
    assert "Traceback" not in out.stderr and "Ray" not in out.stderr
    jobs = example_jobs(tmp_path, **{'name = "corner"': 'named = "corner"'})
    out = run_batch(jobs)
    assert out.returncode == 2
    assert f"{jobs}:19: view 3 (views[2]): unknown key 'named'" in out.stderr, out.stderr
    jobs = example_jobs(tmp_path, **{'name = "high"': 'name = "front"'})
    out = run_batch(jobs)
    assert out.returncode == 2
    assert f"{jobs}:15: view 'front' (views[1]): views[0] has this name too" in out.stderr
    out = run_batch(tmp_path / "missing.toml")
    assert out.returncode == 2 and "missing.toml" in out.stderr


def test_an_unreachable_cluster_fails_fast_with_a_clear_message(tmp_path):
    jobs = example_jobs(tmp_path)
    start = time.monotonic()
    out = run_batch(jobs, "--address", "127.0.0.1:9")
    assert out.returncode == 1, out.stderr
    assert "no Ray cluster answers at 127.0.0.1:9" in out.stderr
    assert time.monotonic() - start < 30
    assert not (tmp_path / "out").exists()


def test_ctrl_c_exits_130_and_leaves_no_partial_image(tmp_path):
    jobs = example_jobs(tmp_path, **{"spp = 4": "spp = 64", "frames = 8": "frames = 40"})
    proc = subprocess.Popen(
        python_with_sigint("penumbra.batch", str(jobs), "--num-cpus", "2"),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=os.environ,
    )
    out_dir = tmp_path / "out"
    deadline = time.monotonic() + 120

    def finished() -> bool:
        # A committed image (temporary files have other names): the folder alone appears
        # before the first image is written, and a signal then leaves none.
        return out_dir.exists() and any(out_dir.glob("*.png"))

    while not finished() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.05)
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130, stderr
    assert "interrupted" in stderr
    files = sorted(p.name for p in out_dir.iterdir())
    written = [n for n in files if n.endswith(".png")]
    # Each image with its record (written right after it), and no temporary file.
    assert 0 < len(written) < 43, files
    assert files == sorted(written + [n[: -len(".png")] + ".meta.json" for n in written]), files
    for name in written:
        assert (out_dir / name).read_bytes().endswith(b"IEND\xaeB`\x82"), name
    # Each finished view was printed as it finished, before the interruption (the last
    # may have been written just as the signal came, before its line).
    told = [line.split("\t")[0] + ".png" for line in stdout.splitlines()]
    assert set(told) <= set(written) and len(told) >= len(written) - 1, (stdout, written)


def test_with_json_stdout_holds_the_json_alone(tmp_path):
    # Whatever else writes to standard output while the batch runs (Ray's processes, which
    # inherit it, and their messages such as a worker that died) goes to stderr. Ray is
    # replaced by a stand-in that writes there as they do: from this process, from Python and
    # from a child process.
    jobs = example_jobs(tmp_path)
    code = f"""
import os, subprocess, sys
from penumbra import batch, distributed
def render_views(scene, views, on_view=None, **kw):
    os.write(1, b"(raylet) A worker died or was killed while executing a task\\n")
    print("a line from Python")
    subprocess.run(["{sys.executable}", "-c", "print('a line from a child process')"])
    return [{{"name": "front", "path": "x.png", "skipped": True}}]
distributed.connect = lambda *a, **k: None
distributed.check_num_cpus = lambda *a, **k: None
distributed.render_views = render_views
sys.exit(batch.main([{str(jobs)!r}, "--json", "--address", "auto"]))
"""
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=os.environ
    )
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout) == {"views": [{"name": "front", "path": "x.png", "skipped": True}]}
    for line in ("A worker died", "a line from Python", "a line from a child process"):
        assert line in out.stderr, out.stderr


def test_view_mistakes_found_by_the_render_are_one_line_before_ray_starts(tmp_path):
    cases = [
        ({'fov = 60': 'fov = 60\nspp = 3'}, ":19: view 'corner' (views[2]): samples per pixel must be a perfect square"),
        ({'fov = 60': 'fov = 60\naovs = ["depth", "dpth"]'}, ":19: view 'corner' (views[2]): unknown AOV 'dpth' in aovs"),
        ({"spp = 4": "spp = 4\nsampler = \"center\""}, ":12: view 'front' (views[0]): the center sampler takes exactly 1 sample"),
        ({"spp = 4": "sppp = 4"}, "[defaults]: unknown key 'sppp'"),
        ({'output = "out/{name}.png"': "output = 3"}, "output must be a file name pattern, not 3"),
    ]
    for replace, words in cases:
        jobs = example_jobs(tmp_path, **replace)
        out = run_batch(jobs, "--address", "127.0.0.1:9")  # nothing answers there: never reached
        assert out.returncode == 2, out.stderr
        assert out.stderr.count("\n") == 1 and words in out.stderr, out.stderr
        assert "Traceback" not in out.stderr and "\x1b" not in out.stderr
        assert not (tmp_path / "out").exists()


def test_more_cpus_per_task_than_any_node_has_exit_2_at_once(tmp_path):
    jobs = example_jobs(tmp_path)
    start = time.monotonic()
    out = run_batch(jobs, "--num-cpus", 1, "--cpus-per-task", 4)
    assert out.returncode == 2, out.stderr
    assert "--cpus-per-task is 4 CPUs per task, more than any node of the cluster has (at most 1)" in out.stderr
    assert time.monotonic() - start < 60 and not (tmp_path / "out").exists()


def test_the_manifest_has_a_line_per_view_of_every_run(tmp_path):
    jobs = example_jobs(
        tmp_path,
        **{"spp = 4": "spp = 1", "width = 256": "width = 16", "height = 256": "height = 12"},
    )
    manifest = tmp_path / "logs" / "manifest.jsonl"
    for _ in range(2):
        out = run_batch(jobs, "--num-cpus", 2, "--manifest", manifest, "--quiet")
        assert out.returncode == 0, out.stderr
    lines = [json.loads(line) for line in manifest.read_text().splitlines()]
    assert len(lines) == 2 * 11
    first, second = lines[:11], lines[11:]
    assert sorted(line["task"] for line in first) == list(range(11))
    assert all(line["status"] == "rendered" for line in first)
    assert all(line["status"] == "skipped" for line in second), "nothing rendered twice"
    spec = batch.read_jobs(str(jobs))
    for line in first:
        v = spec["views"][line["task"]]
        assert line["outputs"] == [str(tmp_path / "out" / f"{v['name']}.png")]
        assert line["host"] and line["peak_memory_bytes"] > 1 << 20 and line["seconds"] > 0
        assert line["camera"] == (v["camera"] if isinstance(v["camera"], str) else None)
    bad = run_batch(jobs, "--manifest", tmp_path)
    assert bad.returncode == 2 and "cannot write the manifest" in bad.stderr, bad.stderr


def test_a_view_that_fails_is_listed_at_the_end_and_the_others_are_done(tmp_path):
    jobs = example_jobs(
        tmp_path,
        **{"spp = 4": "spp = 1", "width = 256": "width = 16", "height = 256": "height = 12"},
    )
    spec = batch.read_jobs(str(jobs))
    names = [v["name"] for v in spec["views"]]
    # A folder where the second view's image goes: its write fails, however often retried.
    blocked = tmp_path / "out" / f"{names[1]}.png"
    blocked.mkdir(parents=True)
    manifest = tmp_path / "manifest.jsonl"
    out = run_batch(jobs, "--num-cpus", 2, "--manifest", manifest, "--quiet")
    assert out.returncode == 1, out.stderr
    assert f"1 of {len(names)} views failed" in out.stderr
    assert any(line.strip().startswith(f"{names[1]}:") for line in out.stderr.splitlines())
    for name in names[:1] + names[2:]:
        assert (tmp_path / "out" / f"{name}.png").is_file(), name
    lines = {json.loads(line)["task"]: json.loads(line) for line in manifest.read_text().splitlines()}
    assert lines[1]["status"] == "failed" and lines[1]["error"]
    assert all(lines[t]["status"] == "rendered" for t in lines if t != 1)


def test_meta_and_coco_write_each_record_and_the_annotations(tmp_path):
    pytest.importorskip("pycocotools")  # tools/test.sh installs it
    jobs = example_jobs(
        tmp_path,
        **{
            "spp = 4": 'spp = 1\naovs = ["object_id"]',
            "width = 256": "width = 24",
            "height = 256": "height = 18",
        },
    )
    annotations = tmp_path / "coco" / "annotations.json"
    out = run_batch(jobs, "--num-cpus", 2, "--meta", "--coco", annotations, "--quiet")
    assert out.returncode == 0, out.stderr
    spec = batch.read_jobs(str(jobs))
    scene = penumbra.load(SCENES / "cornell.toml")
    for v in spec["views"]:
        image = tmp_path / "out" / f"{v['name']}.png"
        record = json.loads(image.with_suffix(".meta.json").read_text())
        camera = v["camera"] if isinstance(v["camera"], penumbra.Camera) else scene.camera(v["camera"])
        pose = penumbra.poses.camera_pose(camera, 24, 18)
        assert all(record[k] == m.tolist() for k, m in pose.items()), v["name"]
        assert record["files"] == [str(image), str(image.with_suffix(".aovs.npz"))]
        assert record["settings"]["scene_digest"] == scene.scene_digest
    coco = json.loads(annotations.read_text())
    assert [i["file_name"] for i in coco["images"]] == [
        f"../out/{v['name']}.png" for v in spec["views"]
    ]
    for k, v in enumerate(spec["views"], 1):
        with np.load(tmp_path / "out" / f"{v['name']}.aovs.npz") as aovs:
            ids = aovs["object_id"]
        mine = sorted((a["object_id"], a["area"]) for a in coco["annotations"] if a["image_id"] == k)
        assert mine == [(g["object_id"], g["area"]) for g in penumbra.coco.instances(ids)]
        assert all(0 < a["visible_fraction"] <= 1 for a in coco["annotations"])


def test_coco_needs_the_object_id_aov_and_pycocotools(tmp_path):
    pytest.importorskip("pycocotools")  # without it, the batch stops at its absence first
    jobs = example_jobs(tmp_path)
    out = run_batch(jobs, "--coco", tmp_path / "a.json")
    assert out.returncode == 2, out.stderr
    assert "--coco: " in out.stderr and "view 'front' (views[0]): has no object_id AOV" in out.stderr
    # pycocotools hidden by a package of that name that cannot be imported.
    fake = tmp_path / "fake" / "pycocotools"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text("raise ImportError('hidden by the test')\n")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(fake.parent), os.environ.get("PYTHONPATH", "")]))
    hidden = subprocess.run(
        [sys.executable, "-m", "penumbra.batch", str(jobs), "--coco", str(tmp_path / "a.json")],
        capture_output=True, text=True, timeout=120, env=env,
    )
    assert hidden.returncode == 1, hidden.stderr
    assert "pip install pycocotools" in hidden.stderr
    assert not (tmp_path / "out").exists() and not (tmp_path / "a.json").exists()
