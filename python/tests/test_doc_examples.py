"""The Python examples of README.md and docs/distributed.md run, so that none breaks unseen
(issue 62; docs/python.md's run through pytest's --doctest-glob, the README's Rust snippets
as the library's doc-tests). Each file's ```python blocks run in order in one namespace, in a
folder that holds the repository's scenes and assets, on a local Ray instance, after the
``penumbra render`` commands of its ```sh blocks that its Python reads (docs/distributed.md's
poses file). Sizes and counts are made small by replacements that must each match once, so
that an edited example fails here until this list follows it."""

from __future__ import annotations

import re
import shlex
import subprocess

import pytest

import ray_env

from conftest import ROOT, cli_binary

ray = ray_env.ray

#: Per file: the replacements that make its examples small, and whether its `penumbra`
#: shell commands run first.
DOCS = {
    "README.md": (
        {
            "image, aovs = scene.render(aovs=": "image, aovs = scene.render(width=32, height=32, aovs=",
            "width=4096, height=4096, spp=64)": "width=32, height=32, spp=1)",
            "frames=120, fov=75), output=": "frames=3, fov=75), width=16, height=16, output=",
        },
        False,
    ),
    "docs/distributed.md": (
        {
            "width=4096, height=4096, spp=64, progress=True": "width=32, height=32, spp=1, progress=True",
            "tiles=(4, 4), aovs=": "tiles=(4, 4), width=16, height=16, spp=1, aovs=",
            "frames=120, fov=75)": "frames=3, fov=75)",
            "width=512, height=512, on_view=print": "width=16, height=16, spp=1, on_view=print",
        },
        True,
    ),
}


def blocks(text: str, language: str) -> list:
    return re.findall(rf"^```{language}\n(.*?)^```", text, flags=re.S | re.M)


@pytest.fixture(scope="module")
def local_ray():
    yield
    ray.shutdown()


@pytest.fixture
def checkout(tmp_path, monkeypatch):
    """A folder with the repository's scenes and assets, as the examples' working folder."""
    for name in ("scenes", "assets"):
        (tmp_path / name).symlink_to(ROOT / name)
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize("doc", sorted(DOCS))
def test_the_python_examples_of_the_docs_run(doc, local_ray, checkout):
    replace, commands = DOCS[doc]
    text = (ROOT / doc).read_text()
    code = "\n".join(blocks(text, "python"))
    for old, new in replace.items():
        assert code.count(old) == 1, f"{doc}: the example changed: {old!r} is not there once"
        code = code.replace(old, new)
    if commands:
        for block in blocks(text, "sh"):
            for line in block.splitlines():
                if line.startswith("penumbra "):
                    args = shlex.split(line.split("#")[0])[1:]
                    subprocess.run([str(cli_binary()), *args, "--quiet"], check=True)
    namespace: dict = {"__name__": "__doc_example__"}
    exec(compile(code, f"<{doc}>", "exec"), namespace)
    if doc == "docs/distributed.md":
        from PIL import Image

        summary = namespace["summary"]
        names = [r["name"] for r in summary]
        assert names == ["front", "side", "orbit0000", "orbit0001", "orbit0002", "high"]
        assert all((checkout / r["path"]).is_file() for r in summary)
        # The poses file's view keeps the size `penumbra render --poses` wrote.
        assert Image.open(checkout / "out" / "views" / "high.png").size == (64, 48)
        assert Image.open(checkout / "out" / "views" / "front.png").size == (16, 16)
    else:
        assert sorted(p.name for p in (checkout / "out" / "orbit").glob("*.png")) == [
            "orbit0000.png", "orbit0001.png", "orbit0002.png"
        ]
