"""Open3D's ray-casting tutorial, second part: a virtual point cloud, the hit points of a
pinhole camera's rays, found with ``t_hit.isfinite()`` and boolean indexing of the rays. The
import line below is the only difference from the same script for Open3D
(``from open3d.t.geometry import RaycastingScene``); Open3D would go on with
``o3d.t.geometry.PointCloud(points)``.

Run it as ``python virtual_point_cloud.py``; its results are ``hit`` (480 x 640 bool),
``points`` (the hit points, (n, 3) float32) and ``rays_hit`` (their rays), numpy arrays.
"""

import numpy as np

from meshes import create_box, create_sphere, create_torus
from penumbra import RaycastingScene

scene = RaycastingScene()
scene.add_triangles(*create_box())
scene.add_triangles(*create_torus(translate=[0, 0, 2]))
scene.add_triangles(*create_sphere(radius=0.5, translate=[1, 2, 3]))

rays = RaycastingScene.create_rays_pinhole(
    fov_deg=90, center=[0, 0, 2], eye=[2, 3, 0], up=[0, 1, 0], width_px=640, height_px=480
)
ans = scene.cast_rays(rays)

hit = ans["t_hit"].isfinite()
points = rays[hit][:, :3] + rays[hit][:, 3:] * ans["t_hit"][hit].reshape((-1, 1))
print(points.shape)

rays_hit = rays[hit].numpy()
points = points.numpy()
hit = hit.numpy()
