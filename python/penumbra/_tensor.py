"""``penumbra.Tensor``: the arrays ray casting returns. A numpy array in every way (a subclass
of ``np.ndarray``), with the few methods of ``open3d.core.Tensor`` that Open3D's ray-casting
code calls on results, so that such code runs unchanged: ``numpy()``, ``cpu()``,
``isfinite()``, ``isinf()`` and ``isnan()``.

>>> import numpy as np, penumbra
>>> t = np.array([2.0, np.inf], dtype=np.float32).view(penumbra.Tensor)
>>> t.isfinite().tolist(), type(t.numpy()).__name__, float(t.min())
([True, False], 'ndarray', 2.0)
"""

from __future__ import annotations

from typing import Any

import numpy as np


class Tensor(np.ndarray):
    """A numpy array (``isinstance(t, np.ndarray)`` holds; numpy functions, indexing and
    arithmetic work as on any array) with the conversion and test methods of
    ``open3d.core.Tensor`` that ray-casting code uses: ``t.numpy()``, ``t.cpu()``,
    ``t.isfinite()``, ``t.isinf()``, ``t.isnan()``. Operations on a Tensor give Tensors;
    those that give one number (``t.sum()``, ``t.max()``) give a numpy scalar, as for an
    array. Make one from an array with ``array.view(penumbra.Tensor)``."""

    def numpy(self) -> np.ndarray:
        """The same data as a plain ``np.ndarray`` (a view, not a copy), as Open3D's
        ``Tensor.numpy()``."""
        return self.view(np.ndarray)

    def cpu(self) -> "Tensor":
        """This tensor: its data is in main memory already (Open3D's ``Tensor.cpu()``)."""
        return self

    def isfinite(self) -> "Tensor":
        """Element-wise: not inf and not NaN (a bool Tensor of the same shape)."""
        return np.isfinite(self)

    def isinf(self) -> "Tensor":
        """Element-wise: +inf or -inf (a bool Tensor of the same shape)."""
        return np.isinf(self)

    def isnan(self) -> "Tensor":
        """Element-wise: NaN (a bool Tensor of the same shape)."""
        return np.isnan(self)

    def __array_wrap__(self, array: Any, context: Any = None, return_scalar: bool = False) -> Any:
        # Whole-array reductions (sum, max, mean, ...) give a numpy scalar, as for a plain
        # array, not a 0-d Tensor.
        if array.ndim == 0:
            return array[()]
        return np.ndarray.__array_wrap__(self, array, context)


def tensor(array: np.ndarray) -> Tensor:
    """``array`` as a :class:`Tensor` (a view: no copy)."""
    return array.view(Tensor)
