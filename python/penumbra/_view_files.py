"""A view's files, as a batch writes them: its image, its AOVs beside it (``.aovs.npz``) and,
when asked, its record (``.meta.json``, see :mod:`penumbra.record`), written together or not
at all, and the test of whether a view is done: the rule of ``penumbra render --resume``.
"""

from __future__ import annotations

import itertools
import json
import os
from typing import Any, List, Mapping, Optional, Tuple

import numpy as np

from ._image import write_image
from .record import record_path, stage_record
from .views import aov_path


#: The largest record read back: far more than any record penumbra writes (the command
#: line's limit).
MAX_RECORD_BYTES = 1 << 20


def done(path: str, with_aovs: bool, settings: Mapping[str, Any]) -> bool:
    """True when the view's image is at ``path`` with its AOV file (``with_aovs``) beside it
    and its record says it was made with exactly ``settings`` (the ``settings`` of the record
    it would be written with now: the scene's digest, penumbra's version, the camera, the
    render settings, the AOVs, the gamma and the format), as ``penumbra render --resume``
    decides. A missing, unreadable or different record is not done."""
    if not os.path.isfile(path) or (with_aovs and not os.path.isfile(aov_path(path))):
        return False
    try:
        with open(record_path(path), "rb") as f:
            data = f.read(MAX_RECORD_BYTES + 1)
        if len(data) > MAX_RECORD_BYTES:
            return False
        kept = json.loads(data)
    except (OSError, ValueError):
        return False
    # Through JSON, as it was written: tuples become lists, floats keep their bits.
    return isinstance(kept, dict) and kept.get("settings") == json.loads(json.dumps(settings))


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
    the record last (a rename takes no space). The old record is removed before anything is
    replaced (with a new record or without), so that no record ever describes an image it was
    not written with. A failure leaves the other old files as they were and no temporary file,
    and its message names the file that was to be written (``out/a.png``), not its temporary
    name."""
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
        old_record = record_path(path)
        if record is not None:
            staged.append((stage_record(old_record, record), old_record))
        if os.path.lexists(old_record):
            os.remove(old_record)
        for tmp, final in staged:
            os.replace(tmp, final)
    except (OSError, ValueError, MemoryError) as e:
        named = _named(e, staged)
        if named is e:
            raise
        raise named from e
    finally:
        for tmp, _ in staged:
            if os.path.exists(tmp):
                os.remove(tmp)


def _named(e: Exception, staged: List[Tuple[str, str]]) -> Exception:
    """``e`` naming the files the temporary ones of ``staged`` were to become, or ``e`` itself
    when it names none of them."""
    finals = dict(staged)
    if isinstance(e, OSError) and e.errno is not None and e.strerror:
        # open() names the temporary file; a rename names it and its target.
        name = e.filename2 if e.filename2 is not None else finals.get(e.filename)
        if name is None:
            return e
        return type(e)(e.errno, e.strerror, name)
    text = str(e)
    for tmp, final in staged:
        text = text.replace(tmp, final)
    if text == str(e):
        return e
    try:
        return type(e)(text)
    except TypeError:  # an exception type with other arguments
        return e
