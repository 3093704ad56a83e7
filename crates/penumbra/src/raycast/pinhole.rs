//! Rays of a pinhole camera with Open3D's conventions (`RaycastingScene.create_rays_pinhole`):
//! one ray per pixel through the pixel's center, `height × width` rays in row-major order,
//! origin at the camera center and direction `Rᵀ·K⁻¹·(x + ½, y + ½, 1)`, not normalized (its
//! camera-space z is 1, so `t_hit` is the depth along the optical axis).

use glam::{DMat3, DVec3, Mat3, Vec3};

use super::run::room;
use super::RaycastError;

/// Most pixels [`create_rays_pinhole`] makes (2³² − 1, well beyond memory for 24-byte rays).
const MAX_RAYS: u64 = u32::MAX as u64;

/// The rays of a camera with intrinsic matrix `intrinsic` (row-major 3×3, `[[fx, s, cx], [0,
/// fy, cy], [0, 0, 1]]`) and extrinsic matrix `extrinsic` (row-major 4×4 world-to-camera
/// `[R | t]`), for an image of `width × height` pixels: `height·width` rays
/// `[ox, oy, oz, dx, dy, dz]`, ray `y·width + x` through pixel `(x, y)`.
///
/// The camera looks along its +z axis; pixel x grows along its +x axis and pixel y along +y,
/// as in Open3D (for the `fov` form, [`create_rays_pinhole_fov`], +y is `up`).
pub fn create_rays_pinhole(
    intrinsic: [[f64; 3]; 3],
    extrinsic: [[f64; 4]; 4],
    width: u32,
    height: u32,
) -> Result<Vec<[f32; 6]>, RaycastError> {
    let invalid = |why: &str| RaycastError::InvalidCamera(why.to_string());
    if intrinsic.iter().flatten().any(|v| !v.is_finite())
        || extrinsic.iter().flatten().any(|v| !v.is_finite())
    {
        return Err(invalid("the camera matrices must be finite"));
    }
    if width as u64 * height as u64 > MAX_RAYS {
        return Err(invalid("the image has more than 2^32 - 1 pixels"));
    }
    if width == 0 || height == 0 {
        return Ok(Vec::new());
    }
    // glam's matrices are column-major: build them from the transposed rows.
    let k = DMat3::from_cols_array_2d(&intrinsic).transpose();
    if k.determinant() == 0.0 {
        return Err(invalid("the intrinsic matrix is singular"));
    }
    let r = DMat3::from_cols_array_2d(&[
        [extrinsic[0][0], extrinsic[0][1], extrinsic[0][2]],
        [extrinsic[1][0], extrinsic[1][1], extrinsic[1][2]],
        [extrinsic[2][0], extrinsic[2][1], extrinsic[2][2]],
    ])
    .transpose();
    // The rotation part must turn the camera's axes into three independent directions: an
    // all-zero or singular one would make every ray's direction zero or flat.
    let scale = r.to_cols_array().iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if r.determinant().abs() <= 1e-9 * scale * scale * scale {
        return Err(invalid(
            "the extrinsic matrix's rotation part (its upper-left 3x3) is singular",
        ));
    }
    let t = DVec3::new(extrinsic[0][3], extrinsic[1][3], extrinsic[2][3]);
    let center = (-(r.transpose() * t)).as_vec3();
    let world_from_pixel: Mat3 = (r.transpose() * k.inverse()).as_mat3();
    if !world_from_pixel.is_finite() || !center.is_finite() {
        return Err(invalid("the camera matrices overflow"));
    }
    let mut rays = room(width as usize * height as usize, "the rays")?;
    for y in 0..height {
        for x in 0..width {
            let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
            let d: Vec3 = world_from_pixel.x_axis * px
                + world_from_pixel.y_axis * py
                + world_from_pixel.z_axis;
            rays.push([center.x, center.y, center.z, d.x, d.y, d.z]);
        }
    }
    Ok(rays)
}

/// The rays of a camera at `eye` looking at `center` with `up` toward the image's growing row
/// index (Open3D's layout: row 0 is the bottom when shown with row 0 at the top) and
/// a horizontal field of view of `fov_deg` degrees, for `width × height` pixels with square
/// pixels and the principal point at the image center; see [`create_rays_pinhole`] for the
/// ray layout.
pub fn create_rays_pinhole_fov(
    fov_deg: f64,
    center: [f64; 3],
    eye: [f64; 3],
    up: [f64; 3],
    width: u32,
    height: u32,
) -> Result<Vec<[f32; 6]>, RaycastError> {
    let invalid = |why: &str| RaycastError::InvalidCamera(why.to_string());
    if !(fov_deg > 0.0 && fov_deg < 180.0) {
        return Err(invalid("fov_deg must be in (0, 180)"));
    }
    let (center, eye, up) = (DVec3::from(center), DVec3::from(eye), DVec3::from(up));
    let forward = (center - eye).normalize_or_zero();
    let up = up.normalize_or_zero();
    let x_axis = up.cross(forward).normalize_or_zero();
    if forward == DVec3::ZERO || up == DVec3::ZERO || x_axis == DVec3::ZERO || !x_axis.is_finite() {
        return Err(invalid(
            "eye and center must differ, and up must not be parallel to center - eye",
        ));
    }
    // Camera axes as in Open3D: x = up × forward, y = forward × x, z = forward.
    let y_axis = forward.cross(x_axis);
    let rows = [x_axis, y_axis, forward];
    let t = -DVec3::new(rows[0].dot(eye), rows[1].dot(eye), rows[2].dot(eye));
    let mut extrinsic = [[0.0; 4]; 4];
    for (i, row) in rows.iter().enumerate() {
        extrinsic[i] = [row.x, row.y, row.z, t[i]];
    }
    extrinsic[3][3] = 1.0;
    if width == 0 || height == 0 {
        return Ok(Vec::new());
    }
    let focal = 0.5 * width as f64 / (0.5 * fov_deg.to_radians()).tan();
    let intrinsic = [
        [focal, 0.0, 0.5 * width as f64],
        [0.0, focal, 0.5 * height as f64],
        [0.0, 0.0, 1.0],
    ];
    create_rays_pinhole(intrinsic, extrinsic, width, height)
}
