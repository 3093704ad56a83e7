//! A camera as computer vision writes it: the intrinsic matrix K and the camera-to-world
//! pose, in OpenCV's and OpenGL's axes (docs/spec.md, "Poses and intrinsics").
//!
//! penumbra's pixel (i, j) covers [i, i+1) × [j, j+1) of the film, its center at
//! (i + ½, j + ½) (SPEC §4). OpenCV puts a pixel's center at integer coordinates, so the
//! film point (x, y) is the OpenCV pixel coordinate (x − ½, y − ½): a centred camera has
//! cx = (W − 1)/2. The pinhole of SPEC §3 sees the camera-space point (X, Y, Z) (OpenCV
//! axes: +x right, +y down, +z forward) at film point x = W/2 + f·X/Z with
//! f = H / (2·tan(fov/2)) in both axes (square pixels), likewise y.
//!
//! ```
//! use glam::Vec3;
//! use penumbra::{Camera, CameraPose};
//!
//! let camera = Camera::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 90.0)?;
//! let pose = CameraPose::new(&camera, 64, 48, (0, 0));
//! // f = 48 / (2·tan 45°) = 24; the centre of the film is between pixels 31 and 32.
//! let [[fx, _, cx], [_, fy, cy], _] = pose.k;
//! assert!((fx - 24.0).abs() < 1e-9 && fx == fy);
//! assert_eq!((cx, cy), (31.5, 23.5));
//! // The camera looks down −z: OpenCV's +z (forward) is world −z.
//! assert_eq!(pose.camera_to_world[2][2], -1.0);
//! assert_eq!(pose.camera_to_world[2][3], 5.0);
//! # Ok::<(), penumbra::CameraError>(())
//! ```

use crate::camera::{Aperture, Camera, Lens};

/// A 3×3 matrix, row by row.
pub type Mat3Rows = [[f64; 3]; 3];
/// A 4×4 matrix, row by row (the last row 0, 0, 0, 1).
pub type Mat4Rows = [[f64; 4]; 4];

/// The intrinsics and pose of a camera on a film.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPose {
    /// K: fx, fy on the diagonal, the principal point (cx, cy) in the last column (and a
    /// camera's given skew in K[0][1]), in pixels of the image with pixel centers at integer
    /// coordinates, row 0 at the top. A distorted lens's K is the one before its distortion.
    /// A panorama's maps (longitude, −latitude) in radians to pixels (fx = W/2π, fy = H/π),
    /// an orthographic camera's (x, y) in world units on its image plane (fx = fy = H/height).
    pub k: Mat3Rows,
    /// Camera to world, OpenCV axes: the columns are +x right, +y down, +z forward and the
    /// eye position.
    pub camera_to_world: Mat4Rows,
    /// Camera to world, OpenGL (NeRF, Blender) axes: +x right, +y up, +z backward.
    pub camera_to_world_opengl: Mat4Rows,
    /// World to camera, OpenCV axes (BOP's `cam_R_w2c`, `cam_t_w2c`): the inverse of
    /// `camera_to_world`.
    pub world_to_camera: Mat4Rows,
    /// The camera's lens model, which K goes with.
    pub lens: Lens,
    /// The camera's aperture (the pose is the aperture centre's).
    pub aperture: Option<Aperture>,
}

impl CameraPose {
    /// `camera` on a `width × height` film, for the image of the pixels from `offset`
    /// (x0, y0) on (a `--pixelbounds` region; (0, 0) for the whole film).
    pub fn new(camera: &Camera, width: u32, height: u32, offset: (u32, u32)) -> CameraPose {
        let h = (0.5 * f64::from(camera.fov_y_deg()).to_radians()).tan();
        let (w, hh) = (f64::from(width), f64::from(height));
        // The pinhole's f, or for a panorama pixels per radian of longitude and latitude, for
        // an orthographic camera pixels per world unit.
        let (fx, fy) = match camera.lens() {
            Lens::Equirectangular => (w / std::f64::consts::TAU, hh / std::f64::consts::PI),
            Lens::Orthographic { height: span } => (hh / f64::from(span), hh / f64::from(span)),
            _ => (hh / (2.0 * h), hh / (2.0 * h)),
        };
        let mut k = [
            [fx, 0.0, w / 2.0 - 0.5],
            [0.0, fy, hh / 2.0 - 0.5],
            [0.0, 0.0, 1.0],
        ];
        // A camera given K writes it, as it renders through it on this film.
        if let Some(given) = camera.intrinsics() {
            k = given.on_film(width, height).rows();
        }
        k[0][2] -= f64::from(offset.0);
        k[1][2] -= f64::from(offset.1);
        let (forward, right, up) = camera.basis();
        let [fw, r, u, e] = [forward, right, up, camera.position()].map(|v| v.as_dvec3());
        let down = -u;
        // `+ 0.0` writes a negated zero as 0.
        let (r, down, u, fw) = (r + 0.0, down + 0.0, u + 0.0, fw + 0.0);
        let back = -fw + 0.0;
        let pose = |x: glam::DVec3, y: glam::DVec3, z: glam::DVec3| {
            [
                [x.x, y.x, z.x, e.x],
                [x.y, y.y, z.y, e.y],
                [x.z, y.z, z.z, e.z],
                [0.0, 0.0, 0.0, 1.0],
            ]
        };
        // The inverse of a rotation and translation: Rᵀ and −Rᵀ·e.
        let row = |a: glam::DVec3| [a.x, a.y, a.z, -a.dot(e) + 0.0];
        CameraPose {
            k,
            camera_to_world: pose(r, down, fw),
            camera_to_world_opengl: pose(r, u, back),
            world_to_camera: [row(r), row(down), row(fw), [0.0, 0.0, 0.0, 1.0]],
            lens: camera.lens(),
            aperture: camera.aperture(),
        }
    }

    /// Where the world point `p` appears in the image of a pinhole (OpenCV pixel
    /// coordinates: pixel centers at integers) and its depth along the forward axis; `None`
    /// behind the camera.
    pub fn project(&self, p: glam::DVec3) -> Option<(f64, f64, f64)> {
        let m = &self.world_to_camera;
        let c = |i: usize| m[i][0] * p.x + m[i][1] * p.y + m[i][2] * p.z + m[i][3];
        let (x, y, z) = (c(0), c(1), c(2));
        if z <= 0.0 {
            return None;
        }
        let k = &self.k;
        Some((k[0][0] * x / z + k[0][2], k[1][1] * y / z + k[1][2], z))
    }
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, Vec3};

    use super::*;
    use crate::camera::FilmCamera;

    #[test]
    fn a_pixel_centres_ray_projects_back_onto_that_pixel() {
        // An off-axis camera with a tilted up: each pixel centre's ray, followed to depth 7,
        // lands on that pixel's integer coordinates.
        let camera = Camera::new(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-0.5, 0.3, -1.0),
            Vec3::new(0.1, 1.0, 0.2),
            50.0,
        )
        .unwrap();
        let (w, h) = (37, 23);
        let pose = CameraPose::new(&camera, w, h, (0, 0));
        let pinhole = FilmCamera::new(&camera, w, h);
        for (i, j) in [(0, 0), (36, 22), (18, 11), (5, 17)] {
            let ray = pinhole.ray(i as f32 + 0.5, j as f32 + 0.5).unwrap();
            let p = (ray.origin + 7.0 * ray.direction).as_dvec3();
            let (u, v, _) = pose.project(p).unwrap();
            assert!(
                (u - i as f64).abs() < 1e-3 && (v - j as f64).abs() < 1e-3,
                "{i},{j}: {u},{v}"
            );
        }
        // A region's image shifts the principal point by its offset.
        let region = CameraPose::new(&camera, w, h, (10, 4));
        assert_eq!(region.k[0][2], pose.k[0][2] - 10.0);
        assert_eq!(region.k[1][2], pose.k[1][2] - 4.0);
    }

    #[test]
    fn the_poses_agree_with_each_other() {
        let camera = Camera::new(Vec3::new(3.0, 1.0, -2.0), Vec3::ZERO, Vec3::Y, 40.0).unwrap();
        let p = CameraPose::new(&camera, 8, 8, (0, 0));
        let m = |a: &Mat4Rows| glam::DMat4::from_cols_array_2d(a).transpose();
        let c2w = m(&p.camera_to_world);
        assert!((c2w * m(&p.world_to_camera) - glam::DMat4::IDENTITY)
            .abs_diff_eq(glam::DMat4::ZERO, 1e-6));
        // OpenGL's axes are OpenCV's with y and z flipped.
        let flip = glam::DMat4::from_diagonal(glam::DVec4::new(1.0, -1.0, -1.0, 1.0));
        assert!((c2w * flip).abs_diff_eq(m(&p.camera_to_world_opengl), 1e-12));
        // The eye sits at the camera's origin, and forward points at the target.
        assert_eq!(c2w.w_axis.truncate(), DVec3::new(3.0, 1.0, -2.0));
        assert!(
            c2w.z_axis
                .truncate()
                .dot(-DVec3::new(3.0, 1.0, -2.0).normalize())
                > 0.999_999
        );
    }
}
