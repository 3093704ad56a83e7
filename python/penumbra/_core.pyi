"""Type stubs of penumbra._core, the compiled core of the penumbra package. Use the public
names of ``penumbra`` instead: they wrap these."""

from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

_Vec = Tuple[float, float, float]

AOV_NAMES: List[str]
NO_ID: int
MAX_THREADS: int
INVALID_ID: int
__version__: str
SIMD_ENV_PROBLEM: Optional[str]

class SceneError(ValueError):
    """A mistake in a scene, located by ``file``, ``line``, ``column`` and ``key``."""

    file: Optional[str]
    line: Optional[int]
    column: Optional[int]
    key: Optional[str]
    kind: str

class CoreScene:
    """A built scene: the world and the file's default settings."""

    @property
    def gamma(self) -> Optional[float]: ...
    @property
    def cameras(self) -> List[str]: ...
    @property
    def bounds(self) -> Tuple[Tuple[float, float, float], Tuple[float, float, float]]: ...
    @property
    def settings(self) -> Dict[str, Any]: ...
    @property
    def stats(self) -> Dict[str, Any]: ...
    @property
    def files(self) -> List[str]: ...
    @property
    def object_ids(self) -> List[Tuple[int, int]]: ...
    @property
    def object_kinds(self) -> List[str]: ...
    @property
    def scene_digest(self) -> str: ...
    def camera(self, name: Optional[str] = None) -> Optional[Tuple[_Vec, _Vec, _Vec, float]]: ...
    def settings_record(self, **kwargs: Any) -> str: ...
    def pack(self) -> Dict[str, Any]: ...
    def camera_path(
        self, name: str
    ) -> Optional[Tuple[int, List[Tuple[_Vec, _Vec, _Vec, float]]]]: ...
    def render(
        self,
        *,
        camera: Union[None, str, Tuple[_Vec, _Vec, _Vec, float]] = None,
        spp: Optional[int] = None,
        sampler: Optional[str] = None,
        light_samples: Optional[int] = None,
        seed: Optional[int] = None,
        width: Optional[int] = None,
        height: Optional[int] = None,
        region: Optional[Tuple[int, int, int, int]] = None,
        threads: int = 0,
        progress: Optional[Callable[[int, int], Any]] = None,
        passes: Optional[Callable[[int, np.ndarray], Any]] = None,
        aovs: List[str] = ...,
        stats: Optional[Dict[str, Any]] = None,
    ) -> Union[np.ndarray, Tuple[np.ndarray, Dict[str, np.ndarray]]]: ...

    def raycasting_scene(self) -> CoreRaycastingScene: ...
    def surface_attributes(
        self, geometry_ids: np.ndarray, primitive_ids: np.ndarray, primitive_uvs: np.ndarray
    ) -> Dict[str, np.ndarray]: ...

class CoreRaycastingScene:
    """Triangle meshes to cast rays against; arrays are C-contiguous (n, k) rows."""

    def __init__(self, nthreads: int = 0) -> None: ...
    @property
    def geometry_count(self) -> int: ...
    @property
    def triangle_count(self) -> int: ...
    def add_triangles(self, vertices: np.ndarray, triangles: np.ndarray) -> int: ...
    def add_instance(self, geometry_id: int, transform: List[List[float]]) -> int: ...
    def cast_rays(
        self,
        rays: np.ndarray,
        nthreads: int,
        row_length: int = 0,
        tnear: float = 0.0,
        tfar: float = float("inf"),
    ) -> Dict[str, np.ndarray]: ...
    def test_occlusions(
        self, rays: np.ndarray, tnear: float, tfar: float, nthreads: int
    ) -> np.ndarray: ...
    def count_intersections(
        self, rays: np.ndarray, nthreads: int, tnear: float = 0.0, tfar: float = float("inf")
    ) -> np.ndarray: ...
    def list_intersections(self, rays: np.ndarray, nthreads: int) -> Dict[str, np.ndarray]: ...
    def compute_closest_points(
        self, points: np.ndarray, nthreads: int
    ) -> Dict[str, np.ndarray]: ...
    def compute_distance(self, points: np.ndarray, nthreads: int) -> np.ndarray: ...
    def compute_signed_distance(
        self, points: np.ndarray, nthreads: int, nsamples: int
    ) -> np.ndarray: ...
    def compute_occupancy(
        self, points: np.ndarray, nthreads: int, nsamples: int
    ) -> np.ndarray: ...

def create_rays_pinhole(
    intrinsic: List[List[float]], extrinsic: List[List[float]], width: int, height: int
) -> np.ndarray: ...
def create_rays_pinhole_fov(
    fov_deg: float, center: List[float], eye: List[float], up: List[float], width: int, height: int
) -> np.ndarray: ...
def load(path: str, threads: int = 0, allow_paths: Sequence[str] = ()) -> CoreScene: ...
def loads(
    text: str,
    format: str = "toml",
    base_dir: str = ".",
    name: str = "<string>",
    threads: int = 0,
    allow_paths: Sequence[str] = (),
) -> CoreScene: ...
def load_pack(pack: Dict[str, Any], threads: int = 0) -> CoreScene: ...
def file_name_part(name: str) -> str: ...
def check_camera(position: _Vec, look_at: _Vec, up: _Vec, fov: float) -> None: ...
def camera_pose(
    position: _Vec, look_at: _Vec, up: _Vec, fov: float, width: int, height: int
) -> Tuple[List[List[float]], List[List[float]], List[List[float]], List[List[float]]]: ...
def write_image(path: str, array: np.ndarray, gamma: Optional[float] = None) -> None: ...
def to_srgb8(array: np.ndarray, gamma: Optional[float] = None) -> np.ndarray: ...
def encode_png(array: np.ndarray, gamma: Optional[float] = None) -> bytes: ...
def camera_rays(
    position: _Vec, look_at: _Vec, up: _Vec, fov: float, width: int, height: int
) -> np.ndarray: ...
