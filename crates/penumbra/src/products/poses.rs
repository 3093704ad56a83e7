//! Every image's camera as computer vision reads it (see [`CameraPose`] and docs/spec.md,
//! "Poses and intrinsics"), in one of three layouts ([`PosesFormat`]), as `penumbra render
//! --poses` and Python's `penumbra.poses.write_poses` write them:
//!
//! - `penumbra`: `{"frames": [...]}`, per image its `frame`, `camera`, `file`, `width`,
//!   `height`, `fov` (vertical, degrees), `K` (OpenCV: pixel centres at integer coordinates),
//!   `camera_to_world` (OpenCV axes), `camera_to_world_opengl`, `world_to_camera`, the
//!   camera's `position`, `look_at` and `up`, and its lens: `model`, and as the model has them
//!   `distortion`, `max_angle`, `orthographic_height`, `aperture_radius`, `focus_distance`;
//! - `nerf`: a `transforms.json` as instant-ngp and nerfstudio read it: `camera_model`
//!   ("OPENCV" for the pinhole and OpenCV's model, with k1 k2 k3 p1 p2; "OPENCV_FISHEYE" with
//!   k1 … k4; "EQUIRECTANGULAR"), `fl_x`, `fl_y`, `cx`, `cy`, `w`, `h` (NeRF's pixel centres
//!   at +½, so a centred camera has cx = W/2), `camera_angle_x`/`_y`, and per frame
//!   `file_path` (relative to the file's folder) and `transform_matrix` (camera to world,
//!   OpenGL axes), with the intrinsics repeated per frame for paths whose fov changes;
//! - `colmap`: COLMAP's text model, a folder of `cameras.txt`, `images.txt` and
//!   `points3D.txt` (see [`super::colmap`]).
//!
//! ```
//! use glam::Vec3;
//! use penumbra::products::poses::{layout, PoseFrame, PosesFormat};
//! use penumbra::{Camera, CameraPose};
//!
//! let camera = Camera::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 90.0)?;
//! let frame = PoseFrame::new(Some(0), "front", "out/front.png", &camera, CameraPose::new(&camera, 64, 48, (0, 0)), (64, 48));
//! let nerf = layout(PosesFormat::Nerf, &[frame], std::path::Path::new("out/transforms.json"))?;
//! assert_eq!(nerf["cx"], 32.0); // NeRF's centre: W/2
//! assert_eq!(nerf["frames"][0]["file_path"], "front.png");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::{Component, Path, PathBuf};

use serde_json::{json, Map, Value};

pub use super::frames::{LensFields, PoseFrame};

use super::frames::{cannot_hold, unskewed};
use super::ProductError;
use crate::staged::StagedFile;

/// The layouts of poses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PosesFormat {
    /// penumbra's own: `{"frames": [...]}`.
    Penumbra,
    /// NeRF's `transforms.json`.
    Nerf,
    /// COLMAP's text model, a folder of three files (see [`super::colmap`]).
    Colmap,
}

impl std::str::FromStr for PosesFormat {
    type Err = crate::UnknownName;

    fn from_str(name: &str) -> Result<PosesFormat, crate::UnknownName> {
        let all = [
            PosesFormat::Penumbra,
            PosesFormat::Nerf,
            PosesFormat::Colmap,
        ];
        crate::names::parse_name("poses format", name, &all, |f| match f {
            PosesFormat::Penumbra => "penumbra",
            PosesFormat::Nerf => "nerf",
            PosesFormat::Colmap => "colmap",
        })
    }
}

/// The poses file of `frames` in `format`, for the file at `path` (NeRF's `file_path`s are
/// relative to its folder).
pub fn layout(
    format: PosesFormat,
    frames: &[PoseFrame],
    path: &Path,
) -> Result<Value, ProductError> {
    Ok(match format {
        PosesFormat::Penumbra => json!({ "frames": frames }),
        PosesFormat::Nerf => {
            unskewed(frames, path, "NeRF's camera model")?;
            nerf(frames, path)?
        }
        PosesFormat::Colmap => {
            let files = super::colmap::files(frames, path)?;
            Value::Object(
                files
                    .into_iter()
                    .map(|(n, t)| (n, Value::String(t)))
                    .collect(),
            )
        }
    })
}

/// Writes the poses of `frames` to `path` in `format` (pretty JSON and a newline), whole or
/// not at all; its folder is made when missing. For COLMAP, `path` is the model's folder
/// ([`super::colmap::write`]). A camera the layout cannot hold (a K with skew, for NeRF and
/// COLMAP) is [`ProductError::Invalid`], and nothing is written.
pub fn write(path: &Path, format: PosesFormat, frames: &[PoseFrame]) -> Result<(), ProductError> {
    if format == PosesFormat::Colmap {
        return super::colmap::write(path, frames);
    }
    let value = layout(format, frames, path)?;
    let text = serde_json::to_string_pretty(&value).map_err(|e| ProductError::io(path, e))? + "\n";
    if let Some(dir) = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty() && !d.is_dir())
    {
        std::fs::create_dir_all(dir)
            .map_err(|e| ProductError::io(path, format_args!("cannot make its folder: {e}")))?;
    }
    Ok(StagedFile::write_bytes(path, text.as_bytes())?.commit()?)
}

/// A `camera_model` and its distortion keys.
type NerfModel = (&'static str, Vec<(&'static str, f64)>);

/// nerfstudio's `camera_model` of frame `f` and its distortion keys: the pinhole and
/// OpenCV's model as `OPENCV` (k1 k2 k3 p1 p2), the fisheye as `OPENCV_FISHEYE` (k1…k4), the
/// panorama as `EQUIRECTANGULAR`.
fn nerf_model(f: &PoseFrame, path: &Path) -> Result<NerfModel, ProductError> {
    let d = f.lens.opencv_coefficients();
    Ok(match f.lens.model.as_str() {
        "pinhole" => (
            "OPENCV",
            vec![("k1", 0.0), ("k2", 0.0), ("p1", 0.0), ("p2", 0.0)],
        ),
        "opencv" if d[5..].iter().any(|&c| c != 0.0) => {
            let why = "has rational or thin-prism terms (k4 … s4)";
            return Err(cannot_hold(path, f, "nerfstudio's OPENCV", why));
        }
        "opencv" => (
            "OPENCV",
            vec![
                ("k1", d[0]),
                ("k2", d[1]),
                ("k3", d[4]),
                ("p1", d[2]),
                ("p2", d[3]),
            ],
        ),
        "fisheye" => (
            "OPENCV_FISHEYE",
            vec![("k1", d[0]), ("k2", d[1]), ("k3", d[2]), ("k4", d[3])],
        ),
        "equirectangular" => ("EQUIRECTANGULAR", vec![]),
        _ => {
            return Err(cannot_hold(
                path,
                f,
                "NeRF's transforms.json",
                "is parallel",
            ))
        }
    })
}

/// NeRF's intrinsics of one image: pixel centres at +½, so cx and cy are K's plus ½. A
/// panorama's are nerfstudio's: fl_x = W/2, fl_y = H and the centre (W/2, H/2).
fn nerf_intrinsics(f: &PoseFrame) -> Map<String, Value> {
    let (w, h) = (f64::from(f.width), f64::from(f.height));
    let mut m = Map::new();
    if f.lens.model == "equirectangular" {
        for (key, v) in [
            ("fl_x", w / 2.0),
            ("fl_y", h),
            ("cx", w / 2.0),
            ("cy", h / 2.0),
        ] {
            m.insert(key.into(), json!(v));
        }
        m.insert("w".into(), json!(f.width));
        m.insert("h".into(), json!(f.height));
        return m;
    }
    let (fx, fy) = (f.k[0][0], f.k[1][1]);
    m.insert("fl_x".into(), json!(fx));
    m.insert("fl_y".into(), json!(fy));
    m.insert("cx".into(), json!(f.k[0][2] + 0.5));
    m.insert("cy".into(), json!(f.k[1][2] + 0.5));
    m.insert("w".into(), json!(f.width));
    m.insert("h".into(), json!(f.height));
    m.insert(
        "camera_angle_x".into(),
        json!(2.0 * (w / (2.0 * fx)).atan()),
    );
    m.insert(
        "camera_angle_y".into(),
        json!(2.0 * (h / (2.0 * fy)).atan()),
    );
    m
}

/// The `transforms.json` of `frames` at `path`: one camera model and distortion for the
/// file (nerfstudio reads them once), intrinsics per frame.
fn nerf(frames: &[PoseFrame], path: &Path) -> Result<Value, ProductError> {
    let folder = absolute(path.parent().unwrap_or(Path::new("")));
    let mut top = Map::new();
    top.insert("camera_model".into(), json!("OPENCV"));
    if let Some(first) = frames.first() {
        let lens = |f: &PoseFrame| (f.lens.model.clone(), f.lens.distortion.clone());
        if let Some(other) = frames.iter().find(|f| lens(f) != lens(first)) {
            let why = format!("has another lens than camera `{}`", first.camera);
            return Err(cannot_hold(path, other, "one transforms.json", &why));
        }
        let (model, distortion) = nerf_model(first, path)?;
        top.insert("camera_model".into(), json!(model));
        top.extend(nerf_intrinsics(first));
        for (key, v) in distortion {
            top.insert(key.into(), json!(v));
        }
    }
    let mut listed = Vec::with_capacity(frames.len());
    for f in frames {
        let intrinsics = nerf_intrinsics(f);
        let file_path = relative(&absolute(Path::new(&f.file)), &folder);
        let mut frame = Map::new();
        frame.insert("file_path".into(), json!(file_path.display().to_string()));
        frame.insert("transform_matrix".into(), json!(f.camera_to_world_opengl));
        frame.extend(intrinsics);
        frame.insert("camera".into(), json!(f.camera));
        frame.insert("frame".into(), json!(f.frame));
        listed.push(Value::Object(frame));
    }
    top.insert("frames".into(), Value::Array(listed));
    Ok(Value::Object(top))
}

/// `path` from the current folder, each `.` dropped and each `..` taking off the name before
/// it (as Python's `os.path.abspath` does).
fn absolute(path: &Path) -> PathBuf {
    let joined = std::env::current_dir()
        .map(|d| d.join(path))
        .unwrap_or_else(|_| path.to_owned());
    super::output_name::normalized(&joined)
}

/// `file` relative to `folder`, both absolute and normalized, with `..` for each of
/// `folder`'s names that `file` is not under (as Python's `os.path.relpath` gives it).
fn relative(file: &Path, folder: &Path) -> PathBuf {
    let (a, b): (Vec<Component>, Vec<Component>) =
        (file.components().collect(), folder.components().collect());
    let common = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
    if common == 0 {
        return file.to_owned(); // Another root (a Windows drive): kept whole.
    }
    let mut out: PathBuf = b[common..].iter().map(|_| Component::ParentDir).collect();
    out.extend(&a[common..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_are_relative_to_the_poses_folder() {
        let r = |f: &str, d: &str| relative(Path::new(f), Path::new(d));
        assert_eq!(r("/a/b/c.png", "/a/b"), Path::new("c.png"));
        assert_eq!(r("/a/b/c/d.png", "/a/b"), Path::new("c/d.png"));
        assert_eq!(r("/a/x/c.png", "/a/b"), Path::new("../x/c.png"));
        assert_eq!(absolute(Path::new("/a/./b/../c")), Path::new("/a/c"));
    }

    #[test]
    fn formats_parse_by_name() {
        assert_eq!("nerf".parse::<PosesFormat>().unwrap(), PosesFormat::Nerf);
        assert_eq!(
            "colmap".parse::<PosesFormat>().unwrap(),
            PosesFormat::Colmap
        );
        let e = "bundler".parse::<PosesFormat>().unwrap_err().to_string();
        assert_eq!(
            e,
            r#"unknown poses format "bundler" (use "penumbra", "nerf" or "colmap")"#
        );
    }
}
