//! Camera paths: a camera that changes from frame to frame, as `[[cameras.NAME.keys]]` or
//! `path = { type = "orbit", ... }` describe it (docs/scene-format.md, "Camera paths").
//!
//! Frames are integers, as in Blender. A path of keys has the frames from its first key to
//! its last; between two keys, position and look_at follow a Catmull-Rom spline over frame
//! time (the tangent at a key is the difference of its neighbours divided by their frame
//! distance, one-sided at the first and last key; with two keys this is a straight line), and
//! up and fov change linearly. A frame on a key is exactly that key's camera. An orbit has
//! the frames 0 to frames − 1 and gives the same cameras as Python's `penumbra.views.orbit`.
//! Everything is computed in double precision and rounded to the camera's single precision
//! once, at the end.
//!
//! ```
//! use glam::DVec3;
//! use penumbra::{CameraKey, CameraPath};
//!
//! let key = |frame, x| CameraKey {
//!     frame,
//!     position: DVec3::new(x, 0.0, 5.0),
//!     look_at: DVec3::ZERO,
//!     up: DVec3::Y,
//!     fov_y_deg: 40.0,
//! };
//! let path = CameraPath::keys(vec![key(1, 0.0), key(11, 2.0)])?;
//! assert_eq!(path.frames(), 1..=11);
//! assert_eq!(path.camera(6).unwrap().position().x, 1.0);
//! assert!(path.camera(12).is_none());
//! # Ok::<(), penumbra::PathError>(())
//! ```

use std::ops::RangeInclusive;

use glam::DVec3;
use thiserror::Error;

use crate::camera::{Camera, CameraError, Optics};

/// The most frames a path may have: each is an image, and each is checked when the path is
/// made (Python's `penumbra.views.orbit` takes as many).
pub const MAX_PATH_FRAMES: u64 = 100_000;

/// One keyframe of a path: the camera at `frame`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraKey {
    /// The frame (any integer; keys come in increasing frame order).
    pub frame: i64,
    /// The eye.
    pub position: DVec3,
    /// The point seen at the film's center.
    pub look_at: DVec3,
    /// The up direction.
    pub up: DVec3,
    /// The vertical field of view in degrees, in (0, 180).
    pub fov_y_deg: f64,
}

/// A turntable around `center`, as `penumbra.views.orbit` makes it: frame k stands at
/// `start_deg + 360·k/frames` degrees on a circle of `radius`, `height` above `center` along
/// `up` (an axis), counted from the axis after up (z for y up) toward the next (x).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    /// The point every frame looks at.
    pub center: DVec3,
    /// The circle's radius (> 0).
    pub radius: f64,
    /// How far above `center` the circle is, along `up`.
    pub height: f64,
    /// How many frames (1 to [`MAX_PATH_FRAMES`]).
    pub frames: i64,
    /// The angle of frame 0, in degrees.
    pub start_deg: f64,
    /// The up direction: an axis, such as +y or −z.
    pub up: DVec3,
    /// The vertical field of view in degrees, in (0, 180).
    pub fov_y_deg: f64,
}

/// A camera that changes with the frame: made checked by [`CameraPath::keys`] or
/// [`CameraPath::orbit`], so that every frame in [`CameraPath::frames`] has a camera.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraPath {
    motion: Motion,
    /// What every frame's camera sees through, when not the pinhole of its fov.
    optics: Option<Optics>,
}

/// How a path's cameras move.
#[derive(Clone, Debug, PartialEq)]
enum Motion {
    /// Keyframes in increasing frame order, at least one.
    Keys(Vec<CameraKey>),
    /// A turntable.
    Orbit(Orbit),
}

/// Why a path cannot be made.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum PathError {
    /// A path of keys without any.
    #[error("a camera path needs at least one key")]
    NoKeys,
    /// `keys[index]` comes before the key above it.
    #[error("frame {frame} comes after frame {previous}: keys must be in increasing frame order")]
    OutOfOrder {
        /// The key out of order.
        index: usize,
        /// Its frame.
        frame: i64,
        /// The frame of the key before it.
        previous: i64,
    },
    /// `keys[index]` has the frame of the key before it.
    #[error("frame {frame} is the frame of keys[{other}] too: each key has a frame of its own")]
    Duplicate {
        /// The second key of that frame.
        index: usize,
        /// The frame.
        frame: i64,
        /// The first key of that frame.
        other: usize,
    },
    /// More frames than [`MAX_PATH_FRAMES`] (or an orbit of fewer than one).
    #[error("a camera path has from 1 to {MAX_PATH_FRAMES} frames, not {0}")]
    Frames(i128),
    /// An orbit's radius is not positive.
    #[error("an orbit's radius must be positive, not {0}")]
    Radius(f64),
    /// An orbit's up is not an axis.
    #[error("an orbit's up must be an axis such as [0, 1, 0], not {0}")]
    Up(DVec3),
    /// The camera of a frame cannot be made; `key` is the key at or before it.
    #[error("the camera of frame {frame}: {source}")]
    Camera {
        /// The frame.
        frame: i64,
        /// For a path of keys, the last key at or before the frame.
        key: Option<usize>,
        /// Why.
        source: CameraError,
    },
}

impl CameraPath {
    /// A path through `keys`, in increasing frame order; every frame's camera is checked.
    pub fn keys(keys: Vec<CameraKey>) -> Result<CameraPath, PathError> {
        let (Some(first), Some(last)) = (keys.first(), keys.last()) else {
            return Err(PathError::NoKeys);
        };
        for (i, pair) in keys.windows(2).enumerate() {
            let (previous, frame) = (pair[0].frame, pair[1].frame);
            if frame == previous {
                return Err(PathError::Duplicate {
                    index: i + 1,
                    frame,
                    other: i,
                });
            }
            if frame < previous {
                return Err(PathError::OutOfOrder {
                    index: i + 1,
                    frame,
                    previous,
                });
            }
        }
        let count = last.frame as i128 - first.frame as i128 + 1;
        if count > MAX_PATH_FRAMES as i128 {
            return Err(PathError::Frames(count));
        }
        CameraPath::of(Motion::Keys(keys)).checked()
    }

    /// An orbit; every frame's camera is checked.
    pub fn orbit(orbit: Orbit) -> Result<CameraPath, PathError> {
        if !(1..=MAX_PATH_FRAMES as i64).contains(&orbit.frames) {
            return Err(PathError::Frames(orbit.frames.into()));
        }
        if orbit.radius.is_nan() || orbit.radius <= 0.0 {
            return Err(PathError::Radius(orbit.radius));
        }
        if axis(orbit.up).is_none() {
            return Err(PathError::Up(orbit.up));
        }
        CameraPath::of(Motion::Orbit(orbit)).checked()
    }

    fn of(motion: Motion) -> CameraPath {
        CameraPath {
            motion,
            optics: None,
        }
    }

    /// This path, every frame's camera seeing through `optics` (K, lens model, aperture: see
    /// [`Camera::optics`]) instead of its field of view's pinhole.
    pub fn with_optics(self, optics: Optics) -> CameraPath {
        CameraPath {
            optics: Some(optics),
            ..self
        }
    }

    /// The path, once the camera of each of its frames is known to exist.
    fn checked(self) -> Result<CameraPath, PathError> {
        for frame in self.frames() {
            self.make(frame).map_err(|source| PathError::Camera {
                frame,
                key: match &self.motion {
                    Motion::Keys(keys) => Some(keys.partition_point(|k| k.frame <= frame) - 1),
                    Motion::Orbit(_) => None,
                },
                source,
            })?;
        }
        Ok(self)
    }

    /// The path's frames, first to last (both included).
    pub fn frames(&self) -> RangeInclusive<i64> {
        match &self.motion {
            Motion::Keys(keys) => {
                let first = keys.first().map_or(0, |k| k.frame);
                first..=keys.last().map_or(first - 1, |k| k.frame)
            }
            Motion::Orbit(o) => 0..=o.frames - 1,
        }
    }

    /// The camera at `frame`; `None` outside [`CameraPath::frames`].
    pub fn camera(&self, frame: i64) -> Option<Camera> {
        if !self.frames().contains(&frame) {
            return None;
        }
        self.make(frame).ok()
    }

    fn make(&self, frame: i64) -> Result<Camera, CameraError> {
        let (position, look_at, up, fov) = match &self.motion {
            Motion::Keys(keys) => between(keys, frame),
            Motion::Orbit(o) => on_orbit(o, frame),
        };
        let camera = Camera::new(
            position.as_vec3(),
            look_at.as_vec3(),
            up.as_vec3(),
            fov as f32,
        )?;
        Ok(match self.optics {
            Some(optics) => camera.with_optics(optics),
            None => camera,
        })
    }
}

/// The index of the axis `up` lies along (exactly one nonzero coordinate).
fn axis(up: DVec3) -> Option<usize> {
    let nonzero: Vec<usize> = (0..3).filter(|&i| up[i] != 0.0).collect();
    match nonzero[..] {
        [a] if up[a].is_finite() => Some(a),
        _ => None,
    }
}

/// Frame `frame` of an orbit, computed as `penumbra.views.orbit` computes it (in the same
/// order of double-precision operations, so that both round to the same camera).
fn on_orbit(o: &Orbit, frame: i64) -> (DVec3, DVec3, DVec3, f64) {
    let a = axis(o.up).unwrap_or(1);
    let sign = if o.up[a] > 0.0 { 1.0 } else { -1.0 };
    let (u, v) = ((a + 1) % 3, (a + 2) % 3);
    let angle = (o.start_deg + 360.0 * frame as f64 / o.frames as f64).to_radians();
    let mut p = o.center;
    p[u] += o.radius * angle.cos();
    p[v] += o.radius * angle.sin();
    p[a] += sign * o.height;
    (p, o.center, o.up, o.fov_y_deg)
}

/// The pose at `frame`, which lies within the keys' frames.
fn between(keys: &[CameraKey], frame: i64) -> (DVec3, DVec3, DVec3, f64) {
    // The key at or before the frame; on a key, that key exactly.
    let i = keys.partition_point(|k| k.frame <= frame).saturating_sub(1);
    let k0 = keys[i];
    let Some(&k1) = keys.get(i + 1).filter(|_| k0.frame != frame) else {
        return (k0.position, k0.look_at, k0.up, k0.fov_y_deg);
    };
    let span = (k1.frame - k0.frame) as f64;
    let s = (frame - k0.frame) as f64 / span;
    let spline = |get: fn(&CameraKey) -> DVec3| {
        let tangent = |j: usize| {
            let (a, b) = (keys[j.saturating_sub(1)], keys[(j + 1).min(keys.len() - 1)]);
            (get(&b) - get(&a)) / (b.frame - a.frame) as f64
        };
        hermite(
            get(&k0),
            tangent(i) * span,
            get(&k1),
            tangent(i + 1) * span,
            s,
        )
    };
    (
        spline(|k| k.position),
        spline(|k| k.look_at),
        k0.up.lerp(k1.up, s),
        k0.fov_y_deg + (k1.fov_y_deg - k0.fov_y_deg) * s,
    )
}

/// The cubic Hermite curve from `p0` (tangent `m0`) to `p1` (tangent `m1`) at `s` in [0, 1].
fn hermite(p0: DVec3, m0: DVec3, p1: DVec3, m1: DVec3, s: f64) -> DVec3 {
    let (s2, s3) = (s * s, s * s * s);
    p0 * (2.0 * s3 - 3.0 * s2 + 1.0)
        + m0 * (s3 - 2.0 * s2 + s)
        + p1 * (-2.0 * s3 + 3.0 * s2)
        + m1 * (s3 - s2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(frame: i64, position: DVec3, fov: f64) -> CameraKey {
        CameraKey {
            frame,
            position,
            look_at: DVec3::ZERO,
            up: DVec3::Y,
            fov_y_deg: fov,
        }
    }

    #[test]
    fn a_frame_on_a_key_is_that_keys_camera() {
        let keys = vec![
            key(0, DVec3::new(0.0, 0.0, 5.0), 30.0),
            key(7, DVec3::new(3.0, 1.0, 4.0), 50.0),
            key(20, DVec3::new(-2.0, 2.0, 6.0), 45.0),
        ];
        let path = CameraPath::keys(keys.clone()).unwrap();
        for k in &keys {
            let c = path.camera(k.frame).unwrap();
            let expected = Camera::new(
                k.position.as_vec3(),
                k.look_at.as_vec3(),
                k.up.as_vec3(),
                k.fov_y_deg as f32,
            )
            .unwrap();
            assert_eq!(c, expected, "frame {}", k.frame);
        }
        assert_eq!(path.frames(), 0..=20);
        assert!(path.camera(-1).is_none() && path.camera(21).is_none());
    }

    #[test]
    fn two_keys_interpolate_linearly_and_fov_always_does() {
        let path = CameraPath::keys(vec![
            key(0, DVec3::new(0.0, 0.0, 4.0), 20.0),
            key(4, DVec3::new(4.0, 0.0, 4.0), 60.0),
        ])
        .unwrap();
        let c = path.camera(1).unwrap();
        assert!((c.position().x - 1.0).abs() < 1e-6, "{c:?}");
        assert!((c.fov_y_deg() - 30.0).abs() < 1e-6);
    }

    #[test]
    fn catmull_rom_passes_smoothly_through_evenly_spaced_keys() {
        // Keys on the line x = frame: the spline stays on the line, at the frame's x.
        let keys: Vec<CameraKey> = (0..4)
            .map(|i| key(i * 10, DVec3::new(i as f64 * 10.0, 0.0, 5.0), 40.0))
            .collect();
        let path = CameraPath::keys(keys).unwrap();
        for f in 0..=30 {
            let x = path.camera(f).unwrap().position().x;
            assert!((x - f as f32).abs() < 1e-4, "frame {f}: {x}");
        }
        // A bend: the middle key pulls the curve, which overshoots neither end.
        let bend = CameraPath::keys(vec![
            key(0, DVec3::new(0.0, 0.0, 5.0), 40.0),
            key(10, DVec3::new(5.0, 0.0, 5.0), 40.0),
            key(20, DVec3::new(5.0, 5.0, 5.0), 40.0),
        ])
        .unwrap();
        let p = bend.camera(15).unwrap().position();
        assert!(p.x > 5.0 && p.y > 0.0 && p.y < 5.0, "{p}");
    }

    #[test]
    fn bad_keys_are_refused() {
        let k = |f| key(f, DVec3::new(f as f64, 0.0, 5.0), 40.0);
        assert_eq!(CameraPath::keys(vec![]), Err(PathError::NoKeys));
        assert_eq!(
            CameraPath::keys(vec![k(0), k(5), k(3)]),
            Err(PathError::OutOfOrder {
                index: 2,
                frame: 3,
                previous: 5
            })
        );
        assert_eq!(
            CameraPath::keys(vec![k(0), k(5), k(5)]),
            Err(PathError::Duplicate {
                index: 2,
                frame: 5,
                other: 1
            })
        );
        assert!(matches!(
            CameraPath::keys(vec![k(0), k(200_000)]),
            Err(PathError::Frames(200_001))
        ));
        // The eye passes through the target on the way: frame 5 has no camera.
        let through = CameraPath::keys(vec![
            key(0, DVec3::new(-1.0, 0.0, 0.0), 40.0),
            key(10, DVec3::new(1.0, 0.0, 0.0), 40.0),
        ]);
        assert!(matches!(
            through,
            Err(PathError::Camera {
                frame: 5,
                key: Some(0),
                ..
            })
        ));
    }

    #[test]
    fn orbits_turn_counter_clockwise_seen_from_above() {
        let orbit = Orbit {
            center: DVec3::new(0.0, 1.0, 0.0),
            radius: 4.0,
            height: 1.5,
            frames: 4,
            start_deg: 0.0,
            up: DVec3::Y,
            fov_y_deg: 40.0,
        };
        let path = CameraPath::orbit(orbit).unwrap();
        assert_eq!(path.frames(), 0..=3);
        let p = |f| path.camera(f).unwrap().position();
        assert!((p(0) - glam::Vec3::new(0.0, 2.5, 4.0)).length() < 1e-6);
        assert!((p(1) - glam::Vec3::new(4.0, 2.5, 0.0)).length() < 1e-6);
        for bad in [
            Orbit { frames: 0, ..orbit },
            Orbit {
                radius: 0.0,
                ..orbit
            },
            Orbit {
                up: DVec3::new(0.0, 1.0, 1.0),
                ..orbit
            },
        ] {
            assert!(CameraPath::orbit(bad).is_err());
        }
    }
}
