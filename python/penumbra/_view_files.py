"""A view's files, as a batch writes them: its image, its AOVs beside it (``.aovs.npz``) and,
when asked, its record (``.meta.json``, see :mod:`penumbra.record`), written together or not
at all, and the test of whether a view is done: the rule of ``penumbra render --resume``.
"""

from __future__ import annotations

import json
import os
from typing import Any, Dict, List, Mapping, Optional, Tuple

import numpy as np

from . import _core
from ._image import _rgb
from ._staged import commit, naming, stage
from .record import digest, intact, read_record, record_path, stage_record
from .views import aov_path


def done(path: str, with_aovs: bool, settings: Mapping[str, Any]) -> bool:
    """True when the view's image is at ``path`` with its AOV file (``with_aovs``) beside it
    and its record says it was made with exactly ``settings`` (the ``settings`` of the record
    it would be written with now: the scene's digest, penumbra's version, the camera, the
    render settings, the AOVs, the gamma and the format) and that its files still have the
    sizes and digests they were written with, as ``penumbra render --resume`` decides. A
    missing, unreadable or different record, or a file cut short or changed, is not done."""
    if not complete(path, with_aovs):
        return False
    kept = read_record(record_path(path))
    # Through JSON, as it was written: tuples become lists, floats keep their bits.
    return (
        kept is not None
        and kept.get("settings") == json.loads(json.dumps(settings))
        and intact(kept)
    )


def complete(path: str, with_aovs: bool, with_record: bool = False) -> bool:
    """True when the view's image is at ``path`` with its AOV file (``with_aovs``) and, with
    ``with_record``, its record beside it listing them with the sizes and digests they still
    have (see :func:`penumbra.record.intact`: an image cut short after its record was
    written is not complete)."""
    if not (os.path.isfile(path) and (not with_aovs or os.path.isfile(aov_path(path)))):
        return False
    if not with_record:
        return True
    value = read_record(record_path(path))
    return value is not None and intact(value)


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
    without), so that no record ever describes an image it was not written with. A failure leaves the other old
    files as they were and no temporary file, and its error names the file asked for."""
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    staged: List[Tuple[str, str]] = []
    digests: Dict[str, Dict[str, Any]] = {}
    try:
        if aovs:
            final = aov_path(path)
            tmp = stage(final, lambda f: np.savez(f, **aovs))
            staged.append((tmp, final))
            digests[final] = digest(tmp)
        tmp, size, fnv = _core.stage_image(path, _rgb(image), gamma)
        staged.append((os.fspath(tmp), path))
        digests[path] = {"bytes": size, "fnv1a64": fnv}
        old_record = record_path(path)
        if record is not None:
            files = record.get("files", [path])
            value = {**record, "digests": [digests.get(f) for f in files]}
            staged.append((stage_record(old_record, value), old_record))
        if os.path.lexists(old_record):
            with naming(old_record):
                os.remove(old_record)
        for tmp, final in staged:
            commit(tmp, final)
    finally:
        for tmp, _ in staged:
            if os.path.lexists(tmp):
                os.remove(tmp)
