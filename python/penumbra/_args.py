"""Checking the arguments of the public calls, so that every mistake is one line naming the
call and the argument: a ``TypeError`` for a value of the wrong kind (a float where an integer
is meant, a set where a vector is), a ``ValueError`` for one out of range."""

from __future__ import annotations

import math
import numbers
import operator
from collections.abc import Mapping
from typing import Any, Optional, Tuple

import numpy as np

from . import _core

#: The largest value of the library's 32-bit counts and sizes.
U32_MAX = 2**32 - 1

#: The largest seed.
U64_MAX = 2**64 - 1


def integer(call: str, name: str, value: Any, low: int, high: int) -> int:
    """``value`` as an int in ``[low, high]``. Python and numpy integers are taken; a bool,
    a float (even 4.0) or a string is a ``TypeError``, a value out of range a ``ValueError``."""
    if isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{call}: {name} must be an integer, not a bool ({value!r})")
    try:
        v = operator.index(value)
    except TypeError:
        raise TypeError(
            f"{call}: {name} must be an integer, not {type(value).__name__} {value!r}"
        ) from None
    if not low <= v <= high:
        raise ValueError(f"{call}: {name} must be from {low} to {high}, not {v}")
    return v


def optional_integer(call: str, name: str, value: Any, low: int, high: int) -> Optional[int]:
    """:func:`integer`, with None kept as None."""
    return None if value is None else integer(call, name, value, low, high)


def threads(call: str, value: Any) -> int:
    """A worker-thread count: 0 (one per core) to ``MAX_THREADS``. The one check of every call
    that takes ``threads``, so that what ``load`` takes, ``render`` takes too."""
    return integer(call, "threads", value, 0, _core.MAX_THREADS)


def sequence(call: str, name: str, value: Any, length: int) -> Tuple[Any, ...]:
    """The ``length`` items of an ordered sequence (list, tuple, numpy array, ...). A set, a
    dict, a string or an iterator is a ``TypeError`` (a set has no order to take a vector
    from); another length a ``ValueError``."""
    indexable = hasattr(value, "__getitem__") and hasattr(value, "__len__")
    if not indexable or isinstance(value, (str, bytes, Mapping)):
        raise TypeError(
            f"{call}: {name} must be a list, tuple or array of {length} items, "
            f"not {type(value).__name__} {value!r}"
        )
    items = tuple(np.asarray(value).reshape(-1)) if isinstance(value, np.ndarray) else tuple(value)
    if len(items) != length:
        raise ValueError(f"{call}: {name} must have {length} items, not {len(items)}: {value!r}")
    return items


def real(call: str, name: str, value: Any) -> float:
    """A real number (Python or numpy; not a string or a bool) as a float; NaN and infinities
    pass, for the library to refuse where they are wrong."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise TypeError(f"{call}: {name} must be a number, not {type(value).__name__} {value!r}")
    return float(value)


def vector(call: str, name: str, value: Any) -> Tuple[float, float, float]:
    """Three real numbers, from an ordered sequence (see :func:`sequence`)."""
    x, y, z = (real(call, f"{name}[{i}]", c) for i, c in enumerate(sequence(call, name, value, 3)))
    return (x, y, z)


def first_non_finite(value: Any, key: str = "") -> Optional[Tuple[str, float]]:
    """The key path (as scene errors spell it: ``objects[2].center[1]``) and value of the
    first NaN or infinite number in a scene dict, or None."""
    if isinstance(value, (float, np.floating)):
        return None if math.isfinite(value) else (key, float(value))
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "fc":
            bad = np.argwhere(~np.isfinite(value))
            if len(bad):
                index = tuple(int(i) for i in bad[0])
                return key + "".join(f"[{i}]" for i in index), float(value[index].real)
            return None
        if value.dtype.kind != "O":
            return None
        value = value.tolist()
    if isinstance(value, Mapping):
        for k, v in value.items():
            found = first_non_finite(v, f"{key}.{k}" if key else str(k))
            if found:
                return found
        return None
    if isinstance(value, (list, tuple, set, frozenset)):
        for i, v in enumerate(value):
            found = first_non_finite(v, f"{key}[{i}]")
            if found:
                return found
    return None


def float_name(value: float) -> str:
    """A non-finite float as the scene files' messages spell it: NaN, inf, -inf."""
    return "NaN" if math.isnan(value) else ("inf" if value > 0 else "-inf")
