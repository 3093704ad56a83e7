"""A view's files, as a batch writes them: its image, its AOVs beside it (``.aovs.npz``) and,
when asked, its record (``.meta.json``, see :mod:`penumbra.record`), written together or not
at all by the command line's code (``penumbra::products``); :func:`penumbra.record.done` tells
whether a view is done.
"""

from __future__ import annotations

import json
import os
from typing import Any, List, Mapping, Optional

import numpy as np

from . import _core
from ._image import _rgb
from .views import aov_path


def write_view(
    path: str,
    image: np.ndarray,
    aovs: Mapping[str, np.ndarray],
    record: Optional[Mapping[str, Any]] = None,
    gamma: Optional[float] = None,
) -> None:
    """Writes a view's image to ``path`` (8-bit formats with ``gamma``, the scene's
    ``film.gamma``, as the command line does), its AOVs (if any) and its ``record`` (if given,
    with the ``digests`` of the files as written) beside it, together or not at all, as the
    command line writes an image, its AOV files and its record: each file is written whole
    under a temporary name in its folder first (where a full disk fails), and only then are
    they renamed into place, the image after its AOVs and the record last (a rename takes no
    space). The old record is removed before anything is replaced (with a new record or
    without), so that no record ever describes an image it was not written with. A failure
    leaves the other old files as they were and no temporary file, and its error names the
    file asked for."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    staged: List[Any] = []
    try:
        if aovs:
            staged.append(_core.stage_npz(aov_path(path), dict(aovs)))
        image_file = _core.stage_image(path, _rgb(image), gamma)
        staged.append(image_file)
        text = None if record is None else json.dumps(dict(record))
        _core.commit_view(image_file, staged[:-1], text)
    finally:
        for f in staged:  # what was not renamed into place
            f.discard()
