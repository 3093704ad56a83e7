"""Packed scenes: a scene file's text with the bytes of every file its build read, to build
the same scene in another process or on another machine without those files."""

from __future__ import annotations

import hashlib
import os
from typing import Any, Dict, List


class PackedScene:
    """A scene file and every mesh, material library and image its build read, in memory.
    Make one with :meth:`Scene.pack`; build it with :func:`penumbra.load_pack`, which reads
    nothing from disk. It pickles as plain bytes and strings, so it travels to other processes
    and machines (``ray.put`` it once for a cluster). A :class:`Scene` pickles as its pack.

    ``digest`` identifies the scene by content (the SHA-256 of the text, format, base folder,
    overrides and every file's path and bytes, each framed by its length and each list by its
    count): workers keep one built world per digest.
    """

    __slots__ = ("_data", "_digest")

    def __init__(self, data: Dict[str, Any]) -> None:
        self._data = data
        self._digest = None

    @property
    def digest(self) -> str:
        """The SHA-256 of the pack's content, as 64 hexadecimal digits."""
        if self._digest is None:
            h = hashlib.sha256()
            d = self._data
            # Every value framed by its length and every list by its count, so that no two
            # different packs give the same stream (an override cannot pass for a file).
            for value in (d["format"], d["name"], d["base_dir"], d["text"]):
                _update(h, os.fsencode(value))
            h.update(len(d["overrides"]).to_bytes(8, "little"))
            for value in d["overrides"]:
                _update(h, os.fsencode(value))
            h.update(len(d["files"]).to_bytes(8, "little"))
            for path in sorted(d["files"]):
                _update(h, os.fsencode(path))
                _update(h, d["files"][path])
            self._digest = h.hexdigest()
        return self._digest

    @property
    def files(self) -> List[str]:
        """The packed files' paths, as the scene resolved them, sorted."""
        return sorted(self._data["files"])

    @property
    def nbytes(self) -> int:
        """The size of the scene's text and files together, in bytes."""
        return len(self._data["text"].encode()) + sum(len(b) for b in self._data["files"].values())

    def __reduce__(self):
        return (PackedScene, (self._data,))

    def __repr__(self) -> str:
        return (
            f"<penumbra.PackedScene {self._data['name']!r}: {len(self._data['files'])} files, "
            f"{self.nbytes} bytes>"
        )


def _update(h: "hashlib._Hash", data: bytes) -> None:
    # Length-prefixed, so that no two different packs hash the same stream.
    h.update(len(data).to_bytes(8, "little"))
    h.update(data)
