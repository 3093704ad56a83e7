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


def finite(
    call: str, name: str, value: Any, low: float = -math.inf, positive: bool = False
) -> float:
    """:func:`real`, refusing NaN and infinities, values below ``low`` and, with
    ``positive``, zero and below (each a ``ValueError`` naming the argument)."""
    v = real(call, name, value)
    if not math.isfinite(v):
        raise ValueError(f"{call}: {name} must be a finite number, not {value!r}")
    if v < low or (positive and v <= 0):
        least = "positive" if positive else f"at least {low:g}"
        raise ValueError(f"{call}: {name} must be {least}, not {value!r}")
    return v


def gamma(call: str, value: Any) -> Optional[float]:
    """An 8-bit encoding's gamma: None (the sRGB curve) or a positive finite number."""
    return None if value is None else finite(call, "gamma", value, positive=True)


def size(call: str, name: str, value: Any) -> int:
    """A size in pixels (a width, a height, a longest side): an integer from 1 to
    :data:`U32_MAX`, checked as :func:`integer` checks."""
    return integer(call, name, value, 1, U32_MAX)


def vector(call: str, name: str, value: Any) -> Tuple[float, float, float]:
    """Three real numbers, from an ordered sequence (see :func:`sequence`)."""
    x, y, z = (real(call, f"{name}[{i}]", c) for i, c in enumerate(sequence(call, name, value, 3)))
    return (x, y, z)


def finite_vector(call: str, name: str, value: Any) -> Tuple[float, float, float]:
    """:func:`vector`, refusing NaN and infinities as :func:`finite` does."""
    x, y, z = (finite(call, f"{name}[{i}]", c) for i, c in enumerate(vector(call, name, value)))
    return (x, y, z)


#: How deep a scene dict may nest: far deeper than the scene format's few levels, and far
#: below Python's recursion limit.
MAX_DEPTH = 100


def scene_dict_problem(
    value: Any, key: str = "", parents: Tuple[int, ...] = ()
) -> Optional[Tuple[str, str]]:
    """The key path (as scene errors spell it: ``objects[2].center[1]``) and what is wrong
    there, for the first value of a scene dict that JSON cannot hold as it is meant: a NaN or
    infinite number, a set (it has no order to take a vector from), or a dict or list that
    contains itself (or nests deeper than :data:`MAX_DEPTH`); None when there is none."""
    where = key or "the top level"
    if isinstance(value, (float, np.floating)):
        if math.isfinite(value):
            return None
        return key, f"{float_name(float(value))} is not a finite number"
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "fc":
            bad = np.argwhere(~np.isfinite(value))
            if len(bad):
                index = tuple(int(i) for i in bad[0])
                at = key + "".join(f"[{i}]" for i in index)
                return at, f"{float_name(float(value[index].real))} is not a finite number"
            return None
        if value.dtype.kind != "O":
            return None
        value = value.tolist()
    if isinstance(value, (set, frozenset)):
        return where, "a set has no order: give a list or a tuple"
    if not isinstance(value, (Mapping, list, tuple)):
        return None
    if id(value) in parents:
        return where, "contains itself (a dict or list that refers to one that holds it)"
    if len(parents) >= MAX_DEPTH:
        return where, f"nests deeper than {MAX_DEPTH} levels"
    inside = parents + (id(value),)
    if isinstance(value, Mapping):
        items = ((f"{key}.{k}" if key else str(k), v) for k, v in value.items())
    else:
        items = ((f"{key}[{i}]", v) for i, v in enumerate(value))
    for at, v in items:
        found = scene_dict_problem(v, at, inside)
        if found:
            return found
    return None


def float_name(value: float) -> str:
    """A non-finite float as the scene files' messages spell it: NaN, inf, -inf."""
    return "NaN" if math.isnan(value) else ("inf" if value > 0 else "-inf")
