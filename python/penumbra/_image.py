"""Images from arrays: writing files as the command line does, and 8-bit encoding."""

from __future__ import annotations

import os
from typing import Optional, Union

import numpy as np

from . import _args, _core


def _rgb(array: "np.typing.ArrayLike") -> np.ndarray:
    """``array`` as a C-contiguous float32 image: (height, width, 3) linear RGB, or
    (height, width, 4) premultiplied RGBA as ``Scene.render(alpha=True)`` returns it."""
    a = np.ascontiguousarray(array, dtype=np.float32)
    if a.ndim != 3 or a.shape[2] not in (3, 4):
        raise ValueError(
            f"an image is a (height, width, 3) or (height, width, 4) array, not shape {a.shape}"
        )
    return a


def write_image(
    path: Union[str, "os.PathLike[str]"],
    array: "np.typing.ArrayLike",
    gamma: Optional[float] = None,
) -> None:
    """Write a (height, width, 3) linear RGB image to ``path``, in the format its extension
    names: ``.png`` and ``.jpg``/``.jpeg`` (8-bit, the sRGB curve unless ``gamma`` is given),
    ``.exr`` and ``.pfm`` (32-bit float, linear). The file is written to a temporary name and
    renamed into place, so it appears complete or not at all, as with the command line.

    A (height, width, 4) array is premultiplied RGBA, as ``Scene.render(alpha=True)`` returns
    it: a PNG gets straight alpha (the colour divided by alpha, then encoded; alpha linear),
    an EXR the premultiplied values and ``A`` (OpenEXR's convention); JPEG and PFM, which have
    no alpha channel, are refused.

    Raises ``ValueError`` for an unknown extension, a bad shape or alpha for a format without
    it, ``OSError`` when the file cannot be written.
    """
    _core.write_image(os.fspath(path), _rgb(array), _args.gamma("write_image", gamma))


def to_srgb8(array: "np.typing.ArrayLike", gamma: Optional[float] = None) -> np.ndarray:
    """The 8-bit encoding of a (height, width, 3) linear RGB image as a uint8 array of the same
    shape: each value clamped to [0, 1] (NaN as 0), encoded with the sRGB curve (or
    ``c ** (1 / gamma)``) and rounded. These are the bytes the command line writes to a PNG.
    A (height, width, 4) premultiplied RGBA image gives the PNG's straight RGBA: the colour
    divided by alpha (0 where alpha is 0), then encoded; alpha linear, ``round(255 a)``.

    >>> import numpy as np
    >>> to_srgb8(np.array([[[0.0, 0.5, 1.0]]], dtype=np.float32))
    array([[[  0, 188, 255]]], dtype=uint8)
    """
    return _core.to_srgb8(_rgb(array), _args.gamma("to_srgb8", gamma))
