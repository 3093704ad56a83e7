"""Images in notebooks: `penumbra.display` and `picture` (PNGs encoded like the command line's,
shrunk above 1024 px), a scene's HTML summary with its preview, and the example notebook
`docs/examples/preview.ipynb` executed in a real kernel (nbclient): the scene's table, one image
updated in place pass by pass, and the displayed image."""

from __future__ import annotations

import base64
import struct
import sys
from pathlib import Path

import numpy as np
import pytest

import penumbra
from conftest import SCENES

ROOT = Path(__file__).resolve().parents[2]


def png_size(png: bytes):
    """Width and height from a PNG's IHDR chunk."""
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert png[12:16] == b"IHDR"
    return struct.unpack(">II", png[16:24])


@pytest.fixture(scope="module")
def cornell() -> penumbra.Scene:
    return penumbra.load(SCENES / "cornell.toml")


def test_a_picture_is_the_png_the_command_line_writes(cornell, tmp_path):
    image = cornell.render(width=40, height=30, spp=4)
    pic = penumbra.picture(image)
    assert png_size(pic.png) == (40, 30)
    assert pic._repr_png_() == pic.png
    penumbra.write_image(tmp_path / "x.png", image)
    assert (tmp_path / "x.png").read_bytes() == pic.png


def test_large_images_shrink_by_a_whole_factor_in_linear_light():
    image = np.zeros((1000, 2050, 3), np.float32)
    image[:, 1::2] = 1.0  # alternating columns: their mean is 0.5
    pic = penumbra.picture(image)
    assert png_size(pic.png) == (683, 333)  # 2050 / 3 and 1000 / 3, rounded down
    small = penumbra.picture(np.full((2, 2, 3), 0.5, np.float32))
    half = penumbra.picture(image, max_side=2050)
    assert png_size(small.png) == (2, 2) and png_size(half.png) == (2050, 1000)
    # The mean of three columns (1/3 or 2/3 lit), not a sample of them.
    shrunk = penumbra.to_srgb8(image[:999, :2049].reshape(333, 3, 683, 3, 3).mean(axis=(1, 3)))
    assert shrunk.min() > 0 and shrunk.max() < 255


def test_display_outside_ipython_returns_the_picture(cornell, monkeypatch):
    monkeypatch.setitem(sys.modules, "IPython", None)
    pic = penumbra.display(cornell.render(width=8, height=8, aovs="depth"))
    assert isinstance(pic, penumbra.Picture) and png_size(pic.png) == (8, 8)
    with pytest.raises(RuntimeError, match="needs IPython"):
        cornell.render(width=8, height=8, progress="notebook")


def test_a_scene_in_a_notebook_is_a_table_and_a_preview(cornell):
    page = cornell._repr_html_()
    for word in ("<table", "triangles", "lights", "cameras", "bounds", "front"):
        assert word in page, word
    png = base64.b64decode(page.split("data:image/png;base64,")[1].split("'")[0])
    w, h = png_size(png)
    assert max(w, h) == 160
    lo, hi = cornell.bounds
    assert all(a < b for a, b in zip(lo, hi))


def test_the_example_notebook_runs_and_shows_its_images():
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    path = ROOT / "docs" / "examples" / "preview.ipynb"
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(
        nb, timeout=120, kernel_name="python3", resources={"metadata": {"path": str(path.parent)}}
    )
    client.execute()
    summary, live, shown = [c.outputs for c in nb.cells if c.cell_type == "code"]
    assert "<table" in summary[0]["data"]["text/html"]
    # One image, updated in place (the kernel's updates replace it): the final image.
    assert [o["output_type"] for o in live] == ["display_data"]
    final = penumbra.load(SCENES / "cornell.toml").render(width=256, height=192, spp=16)
    png = base64.b64decode(live[0]["data"]["image/png"])
    assert png == penumbra.picture(final).png
    assert base64.b64decode(shown[0]["data"]["image/png"]) == png


def test_progress_notebook_updates_one_image_per_pass(cornell, monkeypatch):
    # A stand-in for IPython's display: what `progress="notebook"` asks of it.
    import types

    shown = []

    class Handle:
        def update(self, pic):
            shown.append(("update", pic))

    def display(pic, display_id=False):
        shown.append(("display", pic))
        assert display_id is True
        return Handle()

    ipython = types.ModuleType("IPython")
    ipython.get_ipython = lambda: object()
    ipython_display = types.ModuleType("IPython.display")
    ipython_display.display = display
    ipython.display = ipython_display
    monkeypatch.setitem(sys.modules, "IPython", ipython)
    monkeypatch.setitem(sys.modules, "IPython.display", ipython_display)
    monkeypatch.setitem(sys.modules, "ipywidgets", None)  # not installed: a display handle
    image = cornell.render(width=24, height=16, spp=16, progress="notebook")
    # The preview, 1, 2, 4 and 8 samples, then the final image.
    assert [k for k, _ in shown] == ["display"] + ["update"] * 5
    assert shown[-1][1].png == penumbra.picture(image).png


def test_progress_notebook_replaces_an_ipywidgets_image_when_there_is_one(cornell, monkeypatch):
    # Stand-ins for IPython's display and ipywidgets.Image: one widget shown once, its PNG
    # replaced at every pass.
    import types

    shown, values = [], []

    class Image:
        def __init__(self, format):
            assert format == "png"
            self._value = b""

        @property
        def value(self):
            return self._value

        @value.setter
        def value(self, png):
            values.append(png)
            self._value = png

    ipython = types.ModuleType("IPython")
    ipython.get_ipython = lambda: object()
    ipython_display = types.ModuleType("IPython.display")
    ipython_display.display = lambda widget: shown.append(widget)
    ipython.display = ipython_display
    widgets = types.ModuleType("ipywidgets")
    widgets.Image = Image
    monkeypatch.setitem(sys.modules, "IPython", ipython)
    monkeypatch.setitem(sys.modules, "IPython.display", ipython_display)
    monkeypatch.setitem(sys.modules, "ipywidgets", widgets)
    image = cornell.render(width=24, height=16, spp=16, progress="notebook")
    assert len(shown) == 1 and isinstance(shown[0], Image)
    assert len(values) == 6 and len(set(values)) > 1
    assert values[-1] == penumbra.picture(image).png
