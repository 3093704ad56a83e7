"""The README's gallery cannot go stale: every image in it is byte-identical to what the
command beside it renders (tools/gallery.py reads the table; `python3 tools/gallery.py`
renders them anew after a change that is meant to alter them)."""

from __future__ import annotations

import importlib.util
import sys

import pytest

from conftest import ROOT, cli_binary

_spec = importlib.util.spec_from_file_location("gallery", ROOT / "tools" / "gallery.py")
gallery = importlib.util.module_from_spec(_spec)
sys.modules["gallery"] = gallery  # dataclasses look their module up there
_spec.loader.exec_module(gallery)

ENTRIES = gallery.entries()


def test_the_gallery_lists_every_image_in_docs_images():
    listed = {e.image for e in ENTRIES}
    on_disk = {f"docs/images/{p.name}" for p in (ROOT / "docs" / "images").glob("*.png")}
    assert listed == on_disk


@pytest.mark.parametrize("entry", ENTRIES, ids=lambda e: e.image.rsplit("/", 1)[-1])
def test_gallery_image_is_what_its_command_renders(entry):
    assert gallery.check(cli_binary(), entry), (
        f"{entry.image} differs from `render {' '.join(entry.args)}`: "
        "run `python3 tools/gallery.py` if the change is meant to alter it"
    )
