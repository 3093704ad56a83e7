"""Open3D's distance-queries tutorial (open3d.org, Tutorial > Geometry > Distance Queries)
on a closed torus instead of the Armadillo: unsigned and signed distance and occupancy of a
point, of random points in the mesh's bounds, and of a 32 x 32 x 32 grid. The import line
below is the only difference from the same script for Open3D
(``from open3d.t.geometry import RaycastingScene``).

Run it as ``python distance_queries.py``; its results are ``one`` (the first point's three
answers), ``query_points`` and ``signed_random`` (256 random points), and ``grid``,
``signed_grid``, ``unsigned_grid`` and ``occupancy_grid`` (the 32³ grid), numpy arrays.
"""

import numpy as np

from meshes import create_torus
from penumbra import RaycastingScene

vertices, triangles = create_torus(torus_radius=1.0, tube_radius=0.4)
scene = RaycastingScene()
_ = scene.add_triangles(vertices, triangles)  # we do not need the geometry id for one mesh

query_point = np.array([[10, 10, 10]], dtype=np.float32)
unsigned_distance = scene.compute_distance(query_point)
signed_distance = scene.compute_signed_distance(query_point)
occupancy = scene.compute_occupancy(query_point)
print("unsigned distance", unsigned_distance.numpy())
print("signed_distance", signed_distance.numpy())
print("occupancy", occupancy.numpy())
one = np.concatenate([unsigned_distance.numpy(), signed_distance.numpy(), occupancy.numpy()])

min_bound = vertices.min(0)
max_bound = vertices.max(0)
N = 256
rng = np.random.default_rng(1)
query_points = rng.uniform(low=min_bound, high=max_bound, size=[N, 3]).astype(np.float32)
signed_random = scene.compute_signed_distance(query_points).numpy()

xyz_range = np.linspace(min_bound, max_bound, num=32)
grid = np.stack(np.meshgrid(*xyz_range.T), axis=-1).astype(np.float32)
signed_grid = scene.compute_signed_distance(grid).numpy()  # plt.imshow(signed_grid[:, :, 15])
unsigned_grid = scene.compute_distance(grid).numpy()
occupancy_grid = scene.compute_occupancy(grid).numpy()  # plt.imshow(occupancy_grid[:, :, 15])
print(signed_grid.shape, occupancy_grid.mean())
