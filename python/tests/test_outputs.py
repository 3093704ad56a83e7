"""Files a batch writes (issue 63): an error names the file asked for, never the temporary
one it was staged under; a record keeps each file's size and digest, so that an image cut
short after its record was written is not taken as done; a record that is a named pipe is
never opened."""

from __future__ import annotations

import errno
import json
import os
import threading

import numpy as np
import pytest

import penumbra
from penumbra import _core, record, views
from penumbra._view_files import write_view

from conftest import SCENES, run_cli


def _image() -> np.ndarray:
    return np.linspace(0, 1, 4 * 6 * 3, dtype=np.float32).reshape(4, 6, 3)


def test_an_image_that_cannot_be_written_is_named_not_its_temporary_file(tmp_path):
    # A name the file system takes, whose temporary name (longer) it does not.
    path = str(tmp_path / ("a" * 240 + ".png"))
    aovs = {"depth": np.ones((4, 6), dtype=np.float32)}
    for with_aovs in (False, True):
        with pytest.raises(OSError) as e:
            write_view(path, _image(), aovs if with_aovs else {})
        message = str(e.value)
        # The image, or with AOVs the first file staged, its .aovs.npz.
        asked = views.aov_path(path) if with_aovs else path
        assert asked in message and ".tmp-" not in message, message
    # Every whole file Python writes goes through the one staged writer: its error is the
    # system's (an OSError subclass with its errno) and names the file asked for.
    with pytest.raises(OSError) as e:
        _core.write_bytes(path[:-4] + ".json", b"{}")
    assert ".tmp-" not in str(e.value) and e.value.filename == path[:-4] + ".json"
    assert e.value.errno == errno.ENAMETOOLONG
    with pytest.raises(FileNotFoundError) as e:
        _core.write_bytes(str(tmp_path / "no" / "such" / "x.json"), b"{}")
    assert e.value.filename == str(tmp_path / "no" / "such" / "x.json")
    assert os.listdir(tmp_path) == []


def test_a_record_keeps_the_digests_that_tell_a_whole_image(tmp_path):
    scene = penumbra.load(SCENES / "cornell.toml")
    path = str(tmp_path / "front.pfm")
    value = record.record(scene, "front", path)
    write_view(path, _image(), {}, value)
    kept = record.read_record(record.record_path(path))
    whole = open(path, "rb").read()
    assert kept["digests"] == [record.digest(path)]
    assert kept["digests"][0]["bytes"] == len(whole)
    assert record.intact(kept) and record.done(path, value["settings"])
    # Cut short after its record was written; then the same size, one byte changed.
    with open(path, "wb") as f:
        f.write(whole[: len(whole) // 2])
    assert not record.intact(kept) and not record.done(path, value["settings"])
    with open(path, "wb") as f:
        f.write(whole[:-1] + bytes([whole[-1] ^ 1]))
    assert not record.intact(kept) and not record.done(path, value["settings"])
    # No temporary file is left beside the files.
    assert sorted(os.listdir(tmp_path)) == ["front.meta.json", "front.pfm"]


def test_the_digest_is_the_command_lines(tmp_path):
    # The CLI and Python hash files alike: FNV-1a over the bytes.
    p = tmp_path / "f.bin"
    p.write_bytes(b"foobar")
    assert record.digest(p) == {"bytes": 6, "fnv1a64": "85944171f73967e8"}


def test_a_record_that_is_a_named_pipe_is_never_opened(tmp_path):
    fifo = tmp_path / "a.meta.json"
    os.mkfifo(fifo)
    result = []
    t = threading.Thread(target=lambda: result.append(record.read_record(fifo)), daemon=True)
    t.start()
    t.join(10)
    assert not t.is_alive(), "read_record blocked on a named pipe"
    assert result == [None]
    (tmp_path / "b.meta.json").write_text(json.dumps({"files": []}))
    assert record.read_record(tmp_path / "b.meta.json") == {"files": []}


def test_the_command_lines_record_is_intact_for_python(tmp_path):
    out = tmp_path / "a.png"
    run_cli("render", SCENES / "cornell.toml", "--width", "8", "--height", "6", "--meta",
            "--aov", "depth", "-o", out)
    kept = record.read_record(record.record_path(out))
    assert [d["bytes"] for d in kept["digests"]] == [
        os.path.getsize(f) for f in kept["files"]
    ]
    assert record.intact(kept)


def test_patterns_that_climb_out_or_collide_are_refused():
    two = [{"name": "a"}, {"name": "b"}]
    with pytest.raises(ValueError, match=r"views 0 and 1 the same file x\.png"):
        views.output_paths("f{index}/../x.png", two)
    with pytest.raises(ValueError, match="outside its folder out"):
        views.output_path("out/{name}/../../x.png", {"name": "a"}, 0)
    assert views.output_paths("out/{index}/../x{index}.png", two) == [
        "out/0/../x0.png",
        "out/1/../x1.png",
    ]
    assert views.output_path("../out/{name}.png", {"name": ".."}, 0) == "../out/_..png"


def test_a_batch_pattern_is_read_as_the_command_line_reads_its_own():
    # One expander for `penumbra render -o` and a batch's `output`: widths in either
    # spelling, the same messages for a field it does not know or a brace left open.
    v = {"name": "front"}
    assert views.output_path("out/{name}_{index:04d}.png", v, 7) == "out/front_0007.png"
    assert views.output_path("out/{index:03}.png", v, 7) == "out/007.png"
    assert views.output_path("{{{name}}}.png", v, 0) == "{front}.png"
    with pytest.raises(ValueError, match=r"unknown field `\{camera\}`.*known: \{name\}, \{index\}"):
        views.output_path("{camera}.png", v, 0)
    with pytest.raises(ValueError, match=r"an unclosed `\{`"):
        views.output_path("{name.png", v, 0)
    with pytest.raises(ValueError, match="`name` takes no format"):
        views.output_path("{name:>9}.png", v, 0)


def test_a_views_aovs_are_the_npz_numpy_reads_back(tmp_path):
    # Written by the library's NPZ writer (products::npz), read by numpy as its own.
    rng = np.random.default_rng(3)
    aovs = {
        "depth": rng.random((4, 6), dtype=np.float32),
        "normal": rng.random((6, 4, 3), dtype=np.float32).transpose(1, 0, 2),  # not C order
        "object_id": np.arange(24, dtype=np.uint32).reshape(4, 6) | np.uint32(1 << 31),
    }
    path = str(tmp_path / "a.png")
    write_view(path, _image(), aovs)
    with np.load(views.aov_path(path)) as back:
        assert back.files == list(aovs)
        for name, a in aovs.items():
            assert back[name].dtype == a.dtype and np.array_equal(back[name], a), name
    with pytest.raises(TypeError, match='AOV "depth": a float32 or uint32 .* not a float64'):
        write_view(str(tmp_path / "b.png"), _image(), {"depth": np.zeros((4, 6))})
    assert sorted(os.listdir(tmp_path)) == ["a.aovs.npz", "a.png"]


def test_a_record_of_an_older_layout_is_not_done(tmp_path):
    # Earlier versions kept `render` as Debug text: no settings of today's, so not done.
    scene = penumbra.load(SCENES / "cornell.toml")
    path = str(tmp_path / "front.pfm")
    value = record.record(scene, "front", path)
    write_view(path, _image(), {}, value)
    assert record.done(path, value["settings"])
    kept = record.read_record(record.record_path(path))
    kept["settings"]["render"] = "RenderSettings { view: Named(\"front\"), width: 512 }"
    with open(record.record_path(path), "w") as f:
        json.dump(kept, f)
    assert record.intact(kept) and not record.done(path, value["settings"])
    with pytest.raises(ValueError, match="another image"):
        record.write_record(tmp_path / "other.pfm", value)
