"""A view's files, as a batch writes them: its image and its AOVs beside it (``.aovs.npz``),
written together or not at all, and the test of whether a view is done.
"""

from __future__ import annotations

import itertools
import os
from typing import List, Mapping, Tuple

import numpy as np

from ._image import write_image
from .views import aov_path


def complete(path: str, with_aovs: bool) -> bool:
    """True when the view's image is at ``path`` with its AOV file (``with_aovs``) beside it."""
    return os.path.isfile(path) and (not with_aovs or os.path.isfile(aov_path(path)))


_writes = itertools.count()


def write_view(
    path: str,
    image: np.ndarray,
    aovs: Mapping[str, np.ndarray],
) -> None:
    """Writes a view's image to ``path`` and its AOVs (if any) beside it, together or not at
    all, as the command line writes an image and its AOV files: each file is written whole
    under a temporary name in its folder first (where a full disk fails), and only then are
    they renamed into place, the image last (a rename takes no space). A failure leaves the
    old files as they were and no temporary file."""
    folder, name = os.path.split(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    tag = f".tmp-{os.getpid()}-{next(_writes)}"
    staged: List[Tuple[str, str]] = []
    try:
        if aovs:
            final = aov_path(path)
            tmp = os.path.join(folder, f".{os.path.basename(final)}{tag}")
            staged.append((tmp, final))
            with open(tmp, "wb") as f:
                np.savez(f, **aovs)
                f.flush()
                os.fsync(f.fileno())
        # The same extension, which names the image's format.
        tmp = os.path.join(folder, f".{name}{tag}{os.path.splitext(name)[1]}")
        staged.append((tmp, path))
        write_image(tmp, image)
        for tmp, final in staged:
            os.replace(tmp, final)
    finally:
        for tmp, _ in staged:
            if os.path.exists(tmp):
                os.remove(tmp)
