//! Rays, bounding boxes and object transforms: the small value types every other module uses.

use glam::{Mat3, Mat4, Vec3};

/// `v` normalized, or zero for a zero or non-finite `v`. A vector whose squared length
/// overflows (|v| ≳ 1e19) or underflows (|v| ≲ 1e-19) is first scaled by its largest
/// component; other vectors take the plain path, bit for bit, so the images of ordinary scenes
/// do not change. The plain path is inlined (it runs once per camera hit); the rescaling is not.
#[inline(always)]
pub(crate) fn unit(v: Vec3) -> Vec3 {
    let n = v.normalize_or_zero();
    if n != Vec3::ZERO {
        n
    } else {
        rescaled_unit(v)
    }
}

#[cold]
#[inline(never)]
fn rescaled_unit(v: Vec3) -> Vec3 {
    let largest = v.abs().max_element();
    if largest > 0.0 && largest.is_finite() {
        (v / largest).normalize_or_zero()
    } else {
        Vec3::ZERO
    }
}

/// `e1 × e2` normalized (a triangle's unit normal from two of its edges), zero only when the
/// edges are parallel or not finite: edges 1e-15 long, or 1e20, still give the normal (they are
/// scaled by their largest components first when the cross product would underflow or
/// overflow).
#[inline(always)]
pub(crate) fn unit_cross(e1: Vec3, e2: Vec3) -> Vec3 {
    let n = e1.cross(e2).normalize_or_zero();
    if n != Vec3::ZERO {
        n
    } else {
        rescaled_unit_cross(e1, e2)
    }
}

#[cold]
#[inline(never)]
fn rescaled_unit_cross(e1: Vec3, e2: Vec3) -> Vec3 {
    let n = rescaled_unit(e1.cross(e2));
    if n != Vec3::ZERO {
        return n;
    }
    let (s1, s2) = (e1.abs().max_element(), e2.abs().max_element());
    if s1 > 0.0 && s2 > 0.0 && s1.is_finite() && s2.is_finite() {
        unit((e1 / s1).cross(e2 / s2))
    } else {
        Vec3::ZERO
    }
}

/// Linear RGB radiance or reflectance. Channels are unbounded floats.
pub type Rgb = Vec3;

/// A ray `origin + t·direction`. The direction need not be normalized; `t` is measured in
/// units of its length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where the ray starts.
    pub origin: Vec3,
    /// Which way it goes (any non-zero length).
    pub direction: Vec3,
}

impl Ray {
    /// A ray from `origin` along `direction`.
    pub fn new(origin: Vec3, direction: Vec3) -> Self {
        Self { origin, direction }
    }

    /// The point at parameter `t`.
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.direction
    }
}

/// An axis-aligned bounding box. The empty box has `min > max` so that growing it by any point
/// gives that point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The box that contains nothing.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// The smallest box holding both.
    pub fn union(self, other: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// The smallest box holding the box and the point.
    pub fn grow(self, p: Vec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// The box of this box's eight corners mapped by `transform`: it holds every point of
    /// the box so mapped (up to the rounding of the map). Empty stays empty.
    pub fn transformed(&self, transform: &Transform) -> Aabb {
        if self.is_empty() {
            return Aabb::EMPTY;
        }
        (0..8)
            .map(|k: u32| {
                let pick = |bit: u32, lo: f32, hi: f32| if k & bit == 0 { lo } else { hi };
                Vec3::new(
                    pick(1, self.min.x, self.max.x),
                    pick(2, self.min.y, self.max.y),
                    pick(4, self.min.z, self.max.z),
                )
            })
            .map(|c| transform.point(c))
            .fold(Aabb::EMPTY, Aabb::grow)
    }

    /// True when the box holds no point.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// Center point (meaningless for the empty box).
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Edge lengths (zero or negative for degenerate or empty boxes).
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// Half the surface area, the quantity the SAH compares (0 for the empty box).
    pub fn half_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.extent();
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    /// Centre and radius (half the diagonal) of the box's bounding sphere, in double
    /// precision; radius 1 for a box of no extent (one point). `None` for the empty box or one
    /// with a non-finite corner.
    pub fn bounding_sphere(&self) -> Option<(glam::DVec3, f64)> {
        let (min, max) = (self.min.as_dvec3(), self.max.as_dvec3());
        if self.is_empty() || !min.is_finite() || !max.is_finite() {
            return None;
        }
        let radius = (max - min).length() / 2.0;
        let radius = if radius > 0.0 && radius.is_finite() {
            radius
        } else {
            1.0
        };
        Some(((min + max) / 2.0, radius))
    }

    /// True when `p` lies inside or on the boundary.
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
}

/// An affine transform that also carries the matrix for normals (the inverse transpose of its
/// linear part), so that shading normals stay perpendicular under non-uniform scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Maps points from object to world space.
    pub world_from_object: Mat4,
    /// Maps normals from object to world space (inverse transpose of the linear part).
    pub normal_from_object: Mat3,
}

impl Default for Transform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

/// The matrix of the scene format's transform `T·Rz·Ry·Rx·S` (see [`Transform::from_srt`]).
pub(crate) fn srt_matrix(scale: Vec3, rotate_deg: Vec3, translate: Vec3) -> Mat4 {
    let r = Mat4::from_rotation_z(rotate_deg.z.to_radians())
        * Mat4::from_rotation_y(rotate_deg.y.to_radians())
        * Mat4::from_rotation_x(rotate_deg.x.to_radians());
    Mat4::from_translation(translate) * r * Mat4::from_scale(scale)
}

impl Transform {
    /// The identity.
    pub const IDENTITY: Transform = Transform {
        world_from_object: Mat4::IDENTITY,
        normal_from_object: Mat3::IDENTITY,
    };

    /// Wraps a matrix, deriving the normal matrix from it.
    pub fn from_matrix(world_from_object: Mat4) -> Self {
        let linear = Mat3::from_mat4(world_from_object);
        Self {
            world_from_object,
            normal_from_object: linear.inverse().transpose(),
        }
    }

    /// The scene format's transform `T·Rz·Ry·Rx·S`: scale, then rotate about x, y and z
    /// (degrees, right-hand rule), then translate.
    pub fn from_srt(scale: Vec3, rotate_deg: Vec3, translate: Vec3) -> Self {
        Self::from_matrix(srt_matrix(scale, rotate_deg, translate))
    }

    /// `self` applied after `inner`.
    pub fn then_after(self, inner: Transform) -> Transform {
        Transform::from_matrix(self.world_from_object * inner.world_from_object)
    }

    /// A point mapped to world space.
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.world_from_object.transform_point3(p)
    }

    /// A normal mapped to world space and normalized.
    pub fn normal(&self, n: Vec3) -> Vec3 {
        unit(self.normal_from_object * n)
    }

    /// A bound on how much the map stretches a length: the Frobenius norm of its linear part,
    /// at least its largest singular value.
    pub fn largest_stretch(&self) -> f32 {
        let m = Mat3::from_mat4(self.world_from_object);
        (m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared()).sqrt()
    }

    /// True when the linear part cannot be inverted (a zero scale), so normals are undefined.
    pub fn is_singular(&self) -> bool {
        !self.normal_from_object.is_finite()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-5
    }

    #[test]
    fn transform_order_is_scale_then_rotate_x_y_z_then_translate() {
        // Scale x by 2, rotate 90° about z (x → y), then translate by +1 in z.
        let t = Transform::from_srt(Vec3::new(2.0, 1.0, 1.0), Vec3::new(0.0, 0.0, 90.0), Vec3::Z);
        assert!(close(t.point(Vec3::X), Vec3::new(0.0, 2.0, 1.0)));
        // Rotations compose x first: (90, 90, 0) sends +y to +z (about x), then +z to +x (about y).
        let t = Transform::from_srt(Vec3::ONE, Vec3::new(90.0, 90.0, 0.0), Vec3::ZERO);
        assert!(close(t.point(Vec3::Y), Vec3::X));
    }

    #[test]
    fn positive_angles_turn_counter_clockwise() {
        let t = Transform::from_srt(Vec3::ONE, Vec3::new(0.0, 90.0, 0.0), Vec3::ZERO);
        // Looking down +y toward the origin, +z turns toward +x.
        assert!(close(t.point(Vec3::Z), Vec3::X));
        let t = Transform::from_srt(Vec3::ONE, Vec3::new(90.0, 0.0, 0.0), Vec3::ZERO);
        assert!(close(t.point(Vec3::Y), Vec3::Z));
    }

    #[test]
    fn normals_stay_perpendicular_under_non_uniform_scale() {
        let t = Transform::from_srt(Vec3::new(4.0, 1.0, 1.0), Vec3::ZERO, Vec3::ZERO);
        // A plane x + y = 0 has normal (1, 1, 0); scaled, the tangent (1, -1, 0) becomes (4, -1, 0).
        let n = t.normal(Vec3::new(1.0, 1.0, 0.0));
        let tangent = t.point(Vec3::new(1.0, -1.0, 0.0));
        assert!(n.dot(tangent).abs() < 1e-5);
    }

    #[test]
    fn normals_of_tiny_and_huge_triangles_are_unit_vectors() {
        for scale in [1e-15, 1e-20, 1e-30, 1.0, 1e15, 1e20, 1e30] {
            let (e1, e2) = (Vec3::new(scale, 0.0, 0.0), Vec3::new(0.0, scale, 0.0));
            assert_eq!(unit_cross(e1, e2), Vec3::Z, "edges of length {scale}");
        }
        // A sliver 1e-15 wide and 1 long.
        let n = unit_cross(Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.5, 1e-15, 0.0));
        assert_eq!(n, Vec3::Z);
        // Degenerate and non-finite edges have no normal.
        assert_eq!(unit_cross(Vec3::X, 2.0 * Vec3::X), Vec3::ZERO);
        assert_eq!(unit_cross(Vec3::ZERO, Vec3::Y), Vec3::ZERO);
        assert_eq!(unit_cross(Vec3::NAN, Vec3::Y), Vec3::ZERO);
        assert_eq!(unit(Vec3::new(f32::INFINITY, 0.0, 0.0)), Vec3::ZERO);
    }

    #[test]
    fn ordinary_vectors_normalize_bit_for_bit_as_glam_does() {
        let mut state = 12345u32;
        for _ in 0..10_000 {
            let mut next = || {
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (state >> 8) as f32 / (1 << 24) as f32 * 20.0 - 10.0
            };
            let (a, b) = (
                Vec3::new(next(), next(), next()),
                Vec3::new(next(), next(), next()),
            );
            assert_eq!(unit(a), a.normalize_or_zero());
            assert_eq!(unit_cross(a, b), a.cross(b).normalize_or_zero());
        }
    }

    #[test]
    fn aabb_grows_from_empty() {
        let b = Aabb::EMPTY.grow(Vec3::ONE).grow(-Vec3::ONE);
        assert_eq!(b.center(), Vec3::ZERO);
        assert_eq!(b.half_area(), 12.0);
        assert_eq!(Aabb::EMPTY.half_area(), 0.0);
    }
}
