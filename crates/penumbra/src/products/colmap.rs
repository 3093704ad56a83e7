//! Poses as COLMAP's text model, the input Gaussian splatting and most NeRF trainers read
//! (`sparse/0/`): a folder of `cameras.txt` (one camera per distinct model, size, K and
//! distortion),
//! `images.txt` (each image's world-to-camera rotation as a quaternion `QW QX QY QZ`, its
//! translation, its camera and its name, and an empty line for its 2D points) and an empty
//! `points3D.txt`, as COLMAP's `model_converter` writes them.
//!
//! COLMAP's camera axes are OpenCV's (x right, y down, z forward) and its pixel centres lie at
//! +½, so cx and cy are K's plus ½ (as NeRF's are). An image's name is its path below the
//! folder every image of the model shares, with `/` between names (`images/0001.png` in a
//! folder `out` gives `0001.png` when every image is in `out/images`).
//!
//! Cameras are `PINHOLE`, `OPENCV`, `FULL_OPENCV` or `OPENCV_FISHEYE` by their lens
//! ([`colmap_model`]). A camera COLMAP cannot hold (a K with skew, thin-prism terms, a
//! panorama, an orthographic camera) is an error that names it.

use std::collections::HashMap;
use std::fmt::Write;
use std::path::{Component, Path};

use super::frames::PoseFrame;
use super::ProductError;
use crate::staged::{commit_all, StagedFile};

/// The three files of the model of `frames`, by name.
pub fn files(frames: &[PoseFrame], folder: &Path) -> Result<[(String, String); 3], ProductError> {
    let mut cameras = String::from(
        "# Camera list with one line of data per camera:\n\
         #   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n",
    );
    let mut images = String::from(
        "# Image list with two lines of data per image:\n\
         #   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n\
         #   POINTS2D[] as (X, Y, POINT3D_ID)\n",
    );
    super::frames::unskewed(frames, folder, "COLMAP's camera models")?;
    let mut ids: HashMap<String, usize> = HashMap::new();
    let mut lines = String::new();
    let root = shared_folder(frames);
    for (i, f) in frames.iter().enumerate() {
        let (model, distortion) = colmap_model(f, folder)?;
        let mut camera = format!(
            "{model} {} {} {:?} {:?} {:?} {:?}",
            f.width,
            f.height,
            f.k[0][0],
            f.k[1][1],
            f.k[0][2] + 0.5,
            f.k[1][2] + 0.5
        );
        for c in distortion {
            let _ = write!(camera, " {c:?}");
        }
        let next = ids.len() + 1;
        let id = *ids.entry(camera.clone()).or_insert_with(|| {
            let _ = writeln!(lines, "{next} {camera}");
            next
        });
        let [qw, qx, qy, qz] = quaternion(&f.world_to_camera);
        let t = f.world_to_camera.map(|row| row[3]);
        let name = below(Path::new(&f.file), &root);
        let _ = writeln!(
            images,
            "{} {qw:?} {qx:?} {qy:?} {qz:?} {:?} {:?} {:?} {id} {name}\n",
            i + 1,
            t[0],
            t[1],
            t[2]
        );
    }
    let _ = writeln!(cameras, "# Number of cameras: {}", ids.len());
    cameras.push_str(&lines);
    let points = "# 3D point list with one line of data per point:\n\
                  #   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n\
                  # Number of points: 0, mean track length: 0\n";
    Ok([
        ("cameras.txt".to_owned(), cameras),
        ("images.txt".to_owned(), images),
        ("points3D.txt".to_owned(), points.to_owned()),
    ])
}

/// COLMAP's camera model of frame `f` and its distortion parameters: `PINHOLE`, `OPENCV`
/// (k1 k2 p1 p2, for OpenCV's model without k3 or rational terms), `FULL_OPENCV` (k1 k2 p1 p2
/// k3 k4 k5 k6) or `OPENCV_FISHEYE` (k1 k2 k3 k4); an error for thin-prism terms, panoramas
/// and orthographic cameras.
fn colmap_model(f: &PoseFrame, folder: &Path) -> Result<(&'static str, Vec<f64>), ProductError> {
    let d = f.lens.opencv_coefficients();
    let cannot = |why: &str| super::frames::cannot_hold(folder, f, "COLMAP", why);
    Ok(match f.lens.model.as_str() {
        "pinhole" => ("PINHOLE", vec![]),
        "opencv" if d[8..].iter().any(|&c| c != 0.0) => {
            return Err(cannot("has thin-prism terms (s1 … s4)"))
        }
        "opencv" if d[4..].iter().all(|&c| c == 0.0) => ("OPENCV", d[..4].to_vec()),
        "opencv" => ("FULL_OPENCV", d[..8].to_vec()),
        "fisheye" => ("OPENCV_FISHEYE", d[..4].to_vec()),
        "equirectangular" => return Err(cannot("is a panorama")),
        _ => return Err(cannot("is parallel")),
    })
}

/// Writes the model of `frames` into `folder` (made when missing), its three files together
/// or none of them.
pub fn write(folder: &Path, frames: &[PoseFrame]) -> Result<(), ProductError> {
    let files = files(frames, folder)?;
    if !folder.as_os_str().is_empty() && !folder.is_dir() {
        std::fs::create_dir_all(folder)
            .map_err(|e| ProductError::io(folder, format_args!("cannot make the folder: {e}")))?;
    }
    let staged = files
        .iter()
        .map(|(name, text)| StagedFile::write_bytes(&folder.join(name), text.as_bytes()))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(commit_all(staged)?)
}

/// The unit quaternion (w, x, y, z), w ≥ 0, of the rotation in the upper left of `m` (rows),
/// by Shepperd's method: the largest of the four squares is taken first, so that no division
/// is by a small number.
fn quaternion(m: &[[f64; 4]; 4]) -> [f64; 4] {
    let (r00, r11, r22) = (m[0][0], m[1][1], m[2][2]);
    let trace = r00 + r11 + r22;
    let q = if trace >= r00.max(r11).max(r22) {
        let s = (1.0 + trace).sqrt() * 2.0;
        [
            0.25 * s,
            (m[2][1] - m[1][2]) / s,
            (m[0][2] - m[2][0]) / s,
            (m[1][0] - m[0][1]) / s,
        ]
    } else if r00 >= r11 && r00 >= r22 {
        let s = (1.0 + r00 - r11 - r22).sqrt() * 2.0;
        [
            (m[2][1] - m[1][2]) / s,
            0.25 * s,
            (m[0][1] + m[1][0]) / s,
            (m[0][2] + m[2][0]) / s,
        ]
    } else if r11 >= r22 {
        let s = (1.0 + r11 - r00 - r22).sqrt() * 2.0;
        [
            (m[0][2] - m[2][0]) / s,
            (m[0][1] + m[1][0]) / s,
            0.25 * s,
            (m[1][2] + m[2][1]) / s,
        ]
    } else {
        let s = (1.0 + r22 - r00 - r11).sqrt() * 2.0;
        [
            (m[1][0] - m[0][1]) / s,
            (m[0][2] + m[2][0]) / s,
            (m[1][2] + m[2][1]) / s,
            0.25 * s,
        ]
    };
    let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    let sign = if q[0] < 0.0 { -1.0 } else { 1.0 };
    q.map(|v| sign * v / norm + 0.0)
}

/// The folder every frame's file lies in (the longest shared run of folder names).
fn shared_folder(frames: &[PoseFrame]) -> Vec<String> {
    let folders = frames.iter().map(|f| names(Path::new(&f.file).parent()));
    folders
        .reduce(|a, b| {
            let n = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
            a[..n].to_vec()
        })
        .unwrap_or_default()
}

/// The names of `path`'s components, `.` left out.
fn names(path: Option<&Path>) -> Vec<String> {
    let parts = path.into_iter().flat_map(|p| p.components());
    parts
        .filter(|c| !matches!(c, Component::CurDir))
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect()
}

/// `file` below `root` (a folder all files share), its names joined by `/`.
fn below(file: &Path, root: &[String]) -> String {
    let all = names(Some(file));
    all[root.len().min(all.len())..].join("/")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quaternions_are_unit_with_a_non_negative_w_for_every_branch() {
        // Identity, and half turns about x, y and z (each picks another branch).
        let rows = |r: [[f64; 3]; 3]| {
            let mut m = [[0.0; 4]; 4];
            for i in 0..3 {
                m[i][..3].copy_from_slice(&r[i]);
            }
            m[3][3] = 1.0;
            m
        };
        let cases = [
            (
                [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                [1.0, 0.0, 0.0, 0.0],
            ),
            (
                [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]],
                [0.0, 1.0, 0.0, 0.0],
            ),
            (
                [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]],
                [0.0, 0.0, 1.0, 0.0],
            ),
            (
                [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]],
                [0.0, 0.0, 0.0, 1.0],
            ),
        ];
        for (r, q) in cases {
            assert_eq!(quaternion(&rows(r)), q, "{r:?}");
        }
        // A quarter turn about z: x → y.
        let q = quaternion(&rows([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]));
        let h = 0.5f64.sqrt();
        assert!(
            (q[0] - h).abs() < 1e-15 && (q[3] - h).abs() < 1e-15,
            "{q:?}"
        );
    }

    #[test]
    fn names_are_below_the_folder_every_image_shares() {
        let root = vec!["out".to_owned(), "images".to_owned()];
        assert_eq!(below(Path::new("out/images/a/1.png"), &root), "a/1.png");
        assert_eq!(below(Path::new("./out/images/2.png"), &root), "2.png");
    }
}
