"""Files that appear whole or not at all, as the command line writes them (``staged.rs``):
each is written under a temporary name in its destination's folder (``.a.png.tmp-PID-N``),
flushed to disk, then renamed into place. Errors name the file asked for, never the
temporary one."""

from __future__ import annotations

import contextlib
import itertools
import json
import os
from typing import Any, Callable, Iterator, Optional, TextIO

_writes = itertools.count()


def temporary_name(path: str) -> str:
    """The temporary name ``path`` is staged under: ``out/a.png`` →
    ``out/.a.png.tmp-PID-N``, the command line's scheme (so that ``--resume`` knows what a
    killed run left)."""
    folder, name = os.path.split(os.path.abspath(path))
    return os.path.join(folder, f".{name}.tmp-{os.getpid()}-{next(_writes)}")


@contextlib.contextmanager
def naming(path: str) -> Iterator[None]:
    """Re-raises an ``OSError`` of the block as one that names ``path`` (the file asked for)
    instead of the temporary file the block was writing."""
    try:
        yield
    except OSError as e:
        reason = e.strerror or str(e)
        raise type(e)(e.errno, f"cannot write: {reason}", path) from None


def stage(path: str, write: Callable[[Any], None], mode: str = "wb") -> str:
    """Writes the file ``write(f)`` writes under :func:`temporary_name` of ``path``, flushed to
    disk, and returns that name for the caller to rename into place; nothing is left on
    failure, and an ``OSError`` names ``path``."""
    tmp = temporary_name(path)
    try:
        with naming(path):
            encoding: Optional[str] = None if "b" in mode else "utf-8"
            with open(tmp, mode, encoding=encoding) as f:
                write(f)
                f.flush()
                os.fsync(f.fileno())
    except BaseException:
        if os.path.lexists(tmp):
            os.remove(tmp)
        raise
    return tmp


def commit(tmp: str, path: str) -> None:
    """Renames the staged ``tmp`` into place at ``path`` (an ``OSError`` names ``path``)."""
    with naming(path):
        os.replace(tmp, path)


def stage_json(path: str, value: Any, **dump: Any) -> str:
    """Stages ``value`` as JSON (``json.dump`` with ``dump``) and a newline for ``path``;
    returns the temporary name (see :func:`stage`)."""

    def write(f: TextIO) -> None:
        json.dump(value, f, **dump)
        f.write("\n")

    return stage(path, write, "w")


def write_json(path: str, value: Any, **dump: Any) -> None:
    """Writes ``value`` as JSON (``json.dump`` with ``dump``) to ``path``, whole or not at
    all."""
    commit(stage_json(path, value, **dump), path)
