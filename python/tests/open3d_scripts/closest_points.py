"""Open3D's distance-queries tutorial, closest points: the point of a box or a sphere closest
to each query point, with the geometry and triangle it lies on. The import line below is the
only difference from the same script for Open3D
(``from open3d.t.geometry import RaycastingScene``).

Run it as ``python closest_points.py``; its results are ``query_points``, ``points``,
``geometry_ids``, ``primitive_ids`` and ``distance``, numpy arrays.
"""

import numpy as np

from meshes import create_box, create_sphere
from penumbra import RaycastingScene

scene = RaycastingScene()
box_id = scene.add_triangles(*create_box(translate=[-1.2, -1.2, 0]))
sphere_id = scene.add_triangles(*create_sphere(radius=0.5, translate=[0.7, 0.8, 0]))

rng = np.random.default_rng(2)
query_points = rng.uniform(low=-2, high=2, size=[1000, 3]).astype(np.float32)
ans = scene.compute_closest_points(query_points)
points = ans["points"].numpy()
geometry_ids = ans["geometry_ids"].numpy()
primitive_ids = ans["primitive_ids"].numpy()
distance = np.linalg.norm(points - query_points, axis=-1)
print(points.shape, np.bincount(geometry_ids))
