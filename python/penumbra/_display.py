"""Images in notebooks: PNGs that IPython shows inline, one image updated in place while a
render refines, and a scene's summary with a small preview."""

from __future__ import annotations

import base64
import html
import time
from typing import Any, Optional

import numpy as np

from . import _args, _core
from ._image import _rgb

#: The longest side :func:`display` shows; a larger image is shrunk by a whole factor (the
#: mean of each block of pixels, in linear light) so that it fits.
MAX_SIDE = 1024

#: The longest side of the preview in a scene's notebook summary.
PREVIEW_SIDE = 160


class Picture:
    """An image encoded as a PNG (8-bit sRGB, as the command line writes PNGs), which
    IPython and Jupyter show inline; :attr:`png` holds the file's bytes."""

    def __init__(self, png: bytes, width: int, height: int) -> None:
        self.png = png
        self.width = width
        self.height = height

    def _repr_png_(self) -> bytes:
        return self.png

    def __repr__(self) -> str:
        return f"<penumbra.Picture {self.width}x{self.height} PNG, {len(self.png)} bytes>"


def _shrink(a: np.ndarray, max_side: int) -> np.ndarray:
    """``a`` shrunk by the smallest whole factor that brings its longest side to
    ``max_side`` or below (each output pixel the mean of a block), or ``a`` itself."""
    h, w, c = a.shape
    k = -(-max(h, w) // max_side)
    if k <= 1:
        return a
    ky, kx = min(k, h), min(k, w)
    h2, w2 = h // ky, w // kx
    blocks = a[: h2 * ky, : w2 * kx].reshape(h2, ky, w2, kx, c)
    return np.ascontiguousarray(blocks.mean(axis=(1, 3), dtype=np.float64), dtype=np.float32)


def picture(image: Any, gamma: Optional[float] = None, max_side: int = MAX_SIDE) -> Picture:
    """The :class:`Picture` of a (height, width, 3) linear RGB image, or of the image of
    :meth:`Scene.render`'s ``(image, aovs)``, shrunk to ``max_side`` pixels at most."""
    if isinstance(image, tuple):
        image = image[0]
    a = _shrink(_rgb(image), _args.size("picture", "max_side", max_side))
    return Picture(_core.encode_png(a, _args.gamma("picture", gamma)), a.shape[1], a.shape[0])


def _shell() -> Any:
    """The running IPython shell, or None (plain Python, or IPython not installed)."""
    try:
        from IPython import get_ipython
    except ImportError:
        return None
    return get_ipython()


def display(
    image: Any, gamma: Optional[float] = None, max_side: int = MAX_SIDE
) -> Optional[Picture]:
    """Show a (height, width, 3) linear RGB image (or :meth:`Scene.render`'s ``(image,
    aovs)``) inline in a notebook or IPython, as a PNG encoded like the command line's,
    shrunk by a whole factor when its longest side is above ``max_side`` (1024). Outside
    IPython nothing is shown and the :class:`Picture` is returned (its ``png`` holds the
    bytes); in IPython it is shown and None is returned, so a cell does not show it twice."""
    pic = picture(image, gamma, max_side)
    if _shell() is None:
        return pic
    from IPython.display import display as show

    show(pic)
    return None


class LiveImage:
    """One image in a notebook's output, replaced in place each time :meth:`show` is called:
    what ``Scene.render(progress="notebook")`` shows. With ``ipywidgets`` installed it is an
    ``ipywidgets.Image`` whose PNG is replaced (the front end redraws the image alone);
    without, an IPython display handle whose output is replaced."""

    def __init__(self) -> None:
        if _shell() is None:
            raise RuntimeError(
                'progress="notebook" needs IPython or Jupyter (pip install ipython); '
                "use progress=True for a bar on stderr"
            )
        self._handle: Any = None
        self._widget: Any = None
        try:
            import ipywidgets
        except ImportError:
            return
        self._widget = ipywidgets.Image(format="png")

    def show(self, image: Any) -> None:
        """Show ``image`` (as :func:`picture` encodes it) in place of the one shown before,
        or below the cell the first time."""
        pic = picture(image)
        from IPython.display import display as show

        if self._widget is not None:
            first = not self._widget.value
            self._widget.value = pic.png
            if first:
                show(self._widget)
        elif self._handle is None:
            self._handle = show(pic, display_id=True)
        else:
            self._handle.update(pic)


def summary_html(scene: Any) -> str:
    """A scene's notebook summary: a table of its triangles, lights, cameras and bounds,
    and a small preview render (center sampling, 1 light sample, longest side
    :data:`PREVIEW_SIDE`) with the time it took."""
    s = scene.stats
    lo, hi = scene.bounds
    box = ", ".join(f"[{a:.3g}, {b:.3g}]" for a, b in zip(lo, hi))
    rows = [
        ("triangles", f"{s['triangles']:,}"),
        ("lights", str(s["lights"])),
        ("cameras", ", ".join(scene.cameras) or "none"),
        ("bounds (x, y, z)", box),
    ]
    cells = "".join(
        f"<tr><th style='text-align:left'>{html.escape(k)}</th><td>{html.escape(v)}</td></tr>"
        for k, v in rows
    )
    width, height = scene.settings["width"], scene.settings["height"]
    scale = PREVIEW_SIDE / max(width, height)
    size = max(1, round(width * scale)), max(1, round(height * scale))
    preview = ""
    try:
        start = time.perf_counter()
        image = scene.render(
            width=size[0], height=size[1], sampler="center", light_samples=1
        )
        took = time.perf_counter() - start
        png = base64.b64encode(picture(image).png).decode("ascii")
        preview = (
            f"<img src='data:image/png;base64,{png}' width='{size[0]}' height='{size[1]}'/>"
            f"<div style='font-size:smaller'>preview: {took * 1000:.0f} ms</div>"
        )
    except (ValueError, RuntimeError) as e:
        preview = f"<div>no preview: {html.escape(str(e))}</div>"
    return (
        "<div style='display:flex;gap:1em;align-items:flex-start'>"
        f"<table><caption>penumbra.Scene</caption>{cells}</table><div>{preview}</div></div>"
    )
