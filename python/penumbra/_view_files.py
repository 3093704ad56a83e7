"""A view's files, as a batch writes them: its image, its AOVs beside it (``.aovs.npz``) and,
when asked, its record (``.meta.json``, see :mod:`penumbra.record`), written together or not
at all, and the test of whether a view is done.
"""

from __future__ import annotations

import itertools
import os
from typing import Any, List, Mapping, Optional, Tuple

import numpy as np

from ._image import write_image
from .record import record_path, stage_record
from .views import aov_path


def complete(path: str, with_aovs: bool, with_record: bool = False) -> bool:
    """True when the view's image is at ``path`` with its AOV file (``with_aovs``) and its
    record (``with_record``) beside it."""
    return (
        os.path.isfile(path)
        and (not with_aovs or os.path.isfile(aov_path(path)))
        and (not with_record or os.path.isfile(record_path(path)))
    )


_writes = itertools.count()


def write_view(
    path: str,
    image: np.ndarray,
    aovs: Mapping[str, np.ndarray],
    record: Optional[Mapping[str, Any]] = None,
    gamma: Optional[float] = None,
) -> None:
    """Writes a view's image to ``path`` (8-bit formats with ``gamma``, the scene's
    ``film.gamma``, as the command line does), its AOVs (if any) and its ``record`` (if given)
    beside it, together or not at all, as the command line writes an image, its AOV files and
    its record: each file is written whole under a temporary name in its folder first (where a
    full disk fails), and only then are they renamed into place, the image after its AOVs and
    the record last (a rename takes no space). With a record, the old record is removed before
    anything is replaced, so that no record ever describes an image it was not written with.
    A failure leaves the other old files as they were and no temporary file."""
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
        write_image(tmp, image, gamma)
        if record is not None:
            final = record_path(path)
            staged.append((stage_record(final, record), final))
            if os.path.lexists(final):
                os.remove(final)
        for tmp, final in staged:
            os.replace(tmp, final)
    finally:
        for tmp, _ in staged:
            if os.path.exists(tmp):
                os.remove(tmp)
