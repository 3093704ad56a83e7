"""penumbra: a fast, exact CPU ray tracer, from Python.

Load a scene file (or text, or a dict with the file's schema), then render it as often as you
like with other cameras, sizes, samplers or seeds: the world (meshes, textures, BVH) is built
once. Images are C-contiguous ``float32`` numpy arrays of linear RGB, shape (height, width, 3),
row 0 at the top: the numbers the command line writes to EXR and PFM files.

>>> import penumbra
>>> scene = penumbra.loads('''
... [film]
... width = 4
... height = 3
... [camera]
... position = [0, 0, 3]
... look_at = [0, 0, 0]
... fov = 40
... [[lights]]
... type = "point"
... position = [0, 0, 3]
... [[objects]]
... type = "quad"
... corner = [-1, -1, 0]
... u = [2, 0, 0]
... v = [0, 2, 0]
... ''')
>>> image = scene.render(width=8, height=6, spp=1, sampler="center")
>>> image.shape, image.dtype
((6, 8, 3), dtype('float32'))

``penumbra.__version__`` is the package's version, the Rust workspace's.
"""

import warnings as _warnings

from ._camera import Camera
from ._core import MAX_THREADS, NO_ID, SIMD_ENV_PROBLEM, SceneError, __version__
from ._display import LiveImage, Picture, display, picture
from ._image import to_srgb8, write_image
from ._pack import PackedScene
from ._raycast import INVALID_ID, RaycastingScene
from ._scene import AOV_NAMES, Scene, load, load_dict, load_pack, loads
from ._tensor import Tensor

__all__ = [
    "AOV_NAMES",
    "Camera",
    "INVALID_ID",
    "LiveImage",
    "MAX_THREADS",
    "NO_ID",
    "PackedScene",
    "Picture",
    "RaycastingScene",
    "Scene",
    "SceneError",
    "Tensor",
    "display",
    "load",
    "load_dict",
    "load_pack",
    "loads",
    "picture",
    "to_srgb8",
    "write_image",
]

if SIMD_ENV_PROBLEM is not None:
    # The command line refuses to run; a library import only warns, loudly, once.
    _warnings.warn(
        f"{SIMD_ENV_PROBLEM}: using the best instruction set this CPU has instead",
        RuntimeWarning,
        stacklevel=2,
    )
