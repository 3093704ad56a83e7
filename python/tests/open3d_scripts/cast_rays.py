"""Open3D's ray-casting tutorial, first part (open3d.org, Tutorial > Geometry > Ray
Casting): cast two rays at a scene of a box, a torus and a sphere, then the rays of a pinhole
camera, and image the hit distance, the normals and the geometry ids. Open3D's code but for
the meshes, built with numpy (meshes.py); the import line below is the only difference from
the same script for Open3D (``from open3d.t.geometry import RaycastingScene``).

Run it as ``python cast_rays.py``; its results are ``t_hit``, ``geometry_ids`` (the two
rays), ``depth``, ``normals`` and ``ids`` (the 640 x 480 images), plain numpy arrays.
"""

import numpy as np

from meshes import create_box, create_sphere, create_torus
from penumbra import RaycastingScene

cube = create_box(translate=[0, 0, 0])
torus = create_torus(translate=[0, 0, 2])
sphere = create_sphere(radius=0.5, translate=[1, 2, 3])

scene = RaycastingScene()
cube_id = scene.add_triangles(*cube)
torus_id = scene.add_triangles(*torus)
sphere_id = scene.add_triangles(*sphere)
print(cube_id, torus_id, sphere_id)

# One ray hits the box from above; the other misses everything.
rays = np.array([[0.5, 0.5, 10, 0, 0, -1], [-1, -1, -1, 0, 0, -1]], dtype=np.float32)
ans = scene.cast_rays(rays)
print(sorted(ans.keys()))
t_hit = ans["t_hit"].numpy()
geometry_ids = ans["geometry_ids"].numpy()
print(t_hit, geometry_ids)

# The rays of a camera at [2, 3, 0] looking at [0, 0, 2]: one per pixel of a 640 x 480 image.
rays = RaycastingScene.create_rays_pinhole(
    fov_deg=90, center=[0, 0, 2], eye=[2, 3, 0], up=[0, 1, 0], width_px=640, height_px=480
)
ans = scene.cast_rays(rays)
depth = ans["t_hit"].numpy()                       # plt.imshow(depth)
normals = np.abs(ans["primitive_normals"].numpy())  # plt.imshow(normals)
ids = ans["geometry_ids"].numpy()                   # plt.imshow(ids, vmax=3)
print(depth.shape, np.isfinite(depth).mean(), np.bincount(ids[ids < 3]))
