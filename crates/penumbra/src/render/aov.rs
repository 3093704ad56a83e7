//! Arbitrary output variables (AOVs): per-pixel geometric and material data beside the colour,
//! as dataset generators and denoisers use them (Mitsuba's `aov` integrator, Blender's passes).
//!
//! How each is taken over a pixel:
//! - `depth` (alias `range`), `z`, `position`, `normal`, `object_id` and `primitive_id` come
//!   from one ray: the ray
//!   through the pixel's center, whatever the sampler and sample count. They never blend two
//!   surfaces at a silhouette, they agree with each other (`position` is the camera position
//!   plus `depth` along that ray's unit direction), and they do not change with the seed or
//!   the samples per pixel.
//! - `albedo` is filtered like the colour: the mean over all of the pixel's samples, a sample
//!   that misses counting as black. It matches the colour's edges, as denoisers expect.
//!
//! `depth` is the distance along that ray (Mitsuba's depth, a range); `z` is the planar depth
//! along the camera's forward axis (ROS REP 118's, OpenCV's Z): `depth` times the cosine
//! between the ray and the forward axis, so that `z` is the same across a wall facing the
//! camera.
//!
//! On a miss: depth and z are `+inf`, position, normal and albedo are zero, and both ids are
//! [`NO_ID`].
//!
//! What is written or returned of them is one conversion, [`AovFilm::values`]: the values of
//! one [`Aov`] pixel by pixel, as the command line writes them to files and Python returns
//! them as arrays.
//!
//! ```
//! use penumbra::{Aov, AovFilm, AovPixel, AovValues};
//!
//! let film = AovFilm { width: 2, height: 1, pixels: vec![AovPixel::MISS; 2] };
//! let depth: Aov = "depth".parse()?;
//! assert_eq!(film.values(depth)?, AovValues::Floats(vec![f32::INFINITY; 2]));
//! assert_eq!(Aov::Normal.components(), 3);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::collections::TryReserveError;
use std::str::FromStr;

use glam::Vec3;

use crate::camera::FilmCamera;
use crate::geometry::Surface;
use crate::integrator::CAMERA_T_MIN;
use crate::math::{Ray, Rgb};
use crate::names::{parse_name, UnknownName};
use crate::world::{ObjectIndex, World};

/// The id of "nothing hit" in [`AovPixel::object_id`] and [`AovPixel::primitive_id`].
pub const NO_ID: u32 = u32::MAX;

/// The AOVs of one pixel. See the [module documentation](self) for how each is filtered.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AovPixel {
    /// Distance from the camera to the surface along the ray through the pixel center (not
    /// the z-depth); `+inf` on a miss.
    pub depth: f32,
    /// Planar depth: the hit's distance along the camera's forward axis (the camera-space Z
    /// of `position`); `+inf` on a miss.
    pub z: f32,
    /// World-space hit point of the center ray; zero on a miss.
    pub position: Vec3,
    /// World-space unit shading normal of the center ray's hit, turned to the camera's side
    /// as shading turns it; zero on a miss.
    pub normal: Vec3,
    /// The diffuse reflectance k_d times the texture and the vertex colour, averaged over the
    /// pixel's samples.
    pub albedo: Rgb,
    /// Index of the object hit (the scene file's `objects` entry, in order), or [`NO_ID`].
    pub object_id: u32,
    /// Index of the triangle hit within its object, in the order its mesh lists them, or
    /// [`NO_ID`].
    pub primitive_id: u32,
}

impl AovPixel {
    /// The value of a pixel whose center ray hits nothing and whose samples all miss.
    pub const MISS: AovPixel = AovPixel {
        depth: f32::INFINITY,
        z: f32::INFINITY,
        position: Vec3::ZERO,
        normal: Vec3::ZERO,
        albedo: Rgb::ZERO,
        object_id: NO_ID,
        primitive_id: NO_ID,
    };
}

/// The AOVs of a rendered film (or region), row-major, row 0 at the top, like
/// [`Film`](crate::Film).
#[derive(Clone, Debug, PartialEq)]
pub struct AovFilm {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` pixels.
    pub pixels: Vec<AovPixel>,
}

impl AovFilm {
    /// The pixel in column `x`, row `y` (from the top).
    pub fn get(&self, x: u32, y: u32) -> AovPixel {
        self.pixels[(y as usize) * (self.width as usize) + x as usize]
    }
}

/// One AOV of [`AovPixel`], by the name the command line's `--aov` and Python's `aovs=` take.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Aov {
    /// [`AovPixel::depth`].
    Depth,
    /// [`AovPixel::normal`].
    Normal,
    /// [`AovPixel::albedo`].
    Albedo,
    /// [`AovPixel::position`].
    Position,
    /// [`AovPixel::object_id`].
    ObjectId,
    /// [`AovPixel::primitive_id`].
    PrimitiveId,
    /// [`AovPixel::z`].
    Z,
}

impl Aov {
    /// Every AOV, in the order files, channels and messages list them.
    pub const ALL: [Aov; 7] = [
        Aov::Depth,
        Aov::Normal,
        Aov::Albedo,
        Aov::Position,
        Aov::ObjectId,
        Aov::PrimitiveId,
        Aov::Z,
    ];

    /// Its name: "depth", "normal", "albedo", "position", "object_id", "primitive_id" or
    /// "z"; [`str::parse`] takes it back (and "range" for depth).
    pub fn name(self) -> &'static str {
        match self {
            Aov::Depth => "depth",
            Aov::Normal => "normal",
            Aov::Albedo => "albedo",
            Aov::Position => "position",
            Aov::ObjectId => "object_id",
            Aov::PrimitiveId => "primitive_id",
            Aov::Z => "z",
        }
    }

    /// Values per pixel: 3 for normal, albedo and position, else 1.
    pub fn components(self) -> usize {
        match self {
            Aov::Normal | Aov::Albedo | Aov::Position => 3,
            Aov::Depth | Aov::Z | Aov::ObjectId | Aov::PrimitiveId => 1,
        }
    }

    /// True for the ids, whose values are integers ([`AovValues::Ids`]).
    pub fn is_id(self) -> bool {
        matches!(self, Aov::ObjectId | Aov::PrimitiveId)
    }
}

/// An AOV by its [`Aov::name`], or `range` for [`Aov::Depth`] (the distance along the ray);
/// an unknown name is an error listing the names.
impl FromStr for Aov {
    type Err = UnknownName;

    fn from_str(name: &str) -> Result<Aov, UnknownName> {
        if name == "range" {
            return Ok(Aov::Depth);
        }
        parse_name("AOV", name, &Aov::ALL, Aov::name)
    }
}

/// The values of one [`Aov`] over a film, row-major from the top: [`Aov::components`] per
/// pixel, one after another.
#[derive(Clone, Debug, PartialEq)]
pub enum AovValues {
    /// Depth, normal, albedo or position.
    Floats(Vec<f32>),
    /// An id; exact, which floats could not promise above 2^24.
    Ids(Vec<u32>),
}

impl AovFilm {
    /// The values of `aov` at every pixel, in a buffer of their own; an error when its memory
    /// cannot be had.
    pub fn values(&self, aov: Aov) -> Result<AovValues, TryReserveError> {
        let px = &self.pixels;
        let vec3 = |f: fn(&AovPixel) -> Vec3| {
            let values = px.iter().flat_map(move |p| f(p).to_array());
            collect(px.len() * 3, values).map(AovValues::Floats)
        };
        match aov {
            Aov::Depth => collect(px.len(), px.iter().map(|p| p.depth)).map(AovValues::Floats),
            Aov::Z => collect(px.len(), px.iter().map(|p| p.z)).map(AovValues::Floats),
            Aov::Normal => vec3(|p| p.normal),
            Aov::Albedo => vec3(|p| p.albedo),
            Aov::Position => vec3(|p| p.position),
            Aov::ObjectId => collect(px.len(), px.iter().map(|p| p.object_id)).map(AovValues::Ids),
            Aov::PrimitiveId => {
                collect(px.len(), px.iter().map(|p| p.primitive_id)).map(AovValues::Ids)
            }
        }
    }
}

/// `len` values in a vector of their own, allocated before any is computed.
fn collect<T>(len: usize, values: impl Iterator<Item = T>) -> Result<Vec<T>, TryReserveError> {
    let mut v = Vec::new();
    v.try_reserve_exact(len)?;
    v.extend(values);
    Ok(v)
}

/// What a render needs to compute AOVs: where every object's triangles are, to number
/// triangles within their object.
pub(crate) struct AovContext {
    objects: ObjectIndex,
}

impl AovContext {
    /// Indexes the objects of `world`.
    pub(crate) fn new(world: &World) -> Self {
        Self {
            objects: ObjectIndex::new(world),
        }
    }

    /// The geometric AOVs of pixel `(x, y)` from the ray through its center; albedo zero.
    pub(crate) fn center(&self, world: &World, camera: &FilmCamera, x: u32, y: u32) -> AovPixel {
        // The lens's centre: a thin lens's AOVs are the pinhole's.
        let Some(ray) = camera.ray(x as f32 + 0.5, y as f32 + 0.5) else {
            return AovPixel::MISS;
        };
        let Some(hit) = world.intersect(&ray, CAMERA_T_MIN, f32::INFINITY) else {
            return AovPixel::MISS;
        };
        let surface = world.surface(&hit);
        // An instance's triangles are numbered within its mesh already.
        let first = match hit.instance {
            Some(_) => 0,
            None => self.objects.first_triangle(surface.object),
        };
        AovPixel {
            // The camera's rays have unit directions, so t is the distance.
            depth: hit.t,
            z: hit.t * ray.direction.dot(camera.forward()),
            position: surface.position,
            normal: facing_normal(&ray, &surface),
            albedo: Rgb::ZERO,
            object_id: surface.object,
            primitive_id: surface.triangle - first,
        }
    }
}

/// The shading normal turned as the integrator turns it (see [`Surface::facing`]).
pub(crate) fn facing_normal(ray: &Ray, surface: &Surface) -> Vec3 {
    surface.facing(ray.direction).1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::geometry::{cube, quad};
    use crate::material::Material;
    use crate::math::Transform;
    use crate::world::WorldBuilder;

    #[test]
    fn triangles_are_numbered_within_their_object() {
        let mut b = WorldBuilder::new();
        let m = b
            .add_material(Material {
                diffuse: Rgb::new(0.5, 0.25, 1.0),
                ..Material::default()
            })
            .unwrap();
        // Object 0: a cube far off to the side; object 1: a quad facing the camera at z = 0.
        let far = Transform::from_srt(Vec3::ONE, Vec3::ZERO, Vec3::new(100.0, 0.0, 0.0));
        b.add_mesh(&cube(Vec3::ONE), &far, &[m]).unwrap();
        let q = quad(Vec3::new(-1.0, -1.0, 0.0), 2.0 * Vec3::X, 2.0 * Vec3::Y);
        b.add_mesh(&q, &Transform::IDENTITY, &[m]).unwrap();
        let world = b.build(1);
        let cam = Camera::new(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y, 40.0).unwrap();
        let camera = FilmCamera::new(&cam, 1, 1);
        let ctx = AovContext::new(&world);
        let px = ctx.center(&world, &camera, 0, 0);
        assert_eq!(px.depth, 3.0);
        assert_eq!(px.object_id, 1);
        assert!(px.primitive_id < 2, "{}", px.primitive_id);
        assert_eq!(px.normal, Vec3::Z);
        assert!(px.position.length() < 1e-6);

        let ray = camera.ray(0.5, 0.5).unwrap();
        let hit = world.intersect(&ray, CAMERA_T_MIN, f32::INFINITY).unwrap();
        let s = world.surface(&hit);
        assert_eq!(world.albedo(&s), Rgb::new(0.5, 0.25, 1.0));
    }

    #[test]
    fn z_is_planar_depth_and_depth_the_distance_along_the_ray() {
        // A wall facing the camera 3 units away: z is 3 everywhere on it, depth grows toward
        // the edges, and z is the forward coordinate of the position.
        let mut b = WorldBuilder::new();
        let m = b.add_material(Material::default()).unwrap();
        let q = quad(Vec3::new(-10.0, -10.0, 0.0), 20.0 * Vec3::X, 20.0 * Vec3::Y);
        b.add_mesh(&q, &Transform::IDENTITY, &[m]).unwrap();
        let world = b.build(1);
        let eye = Vec3::new(0.0, 0.0, 3.0);
        let cam = Camera::new(eye, Vec3::ZERO, Vec3::Y, 90.0).unwrap();
        let camera = FilmCamera::new(&cam, 7, 5);
        let ctx = AovContext::new(&world);
        for (x, y) in [(0, 0), (3, 2), (6, 4), (1, 3)] {
            let px = ctx.center(&world, &camera, x, y);
            assert!((px.z - 3.0).abs() < 1e-5, "{x},{y}: {}", px.z);
            assert!(px.depth >= px.z);
            assert!(((px.position - eye).length() - px.depth).abs() < 1e-5);
            assert!(((px.position - eye).dot(camera.forward()) - px.z).abs() < 1e-5);
        }
        assert!(ctx.center(&world, &camera, 0, 0).depth > 3.5);
        assert_eq!(AovPixel::MISS.z, f32::INFINITY);
    }

    #[test]
    fn aov_names_round_trip() {
        for a in Aov::ALL {
            assert_eq!(a.name().parse::<Aov>(), Ok(a));
        }
        let e = "zdepth".parse::<Aov>().unwrap_err();
        assert_eq!((e.name.as_str(), e.known.len()), ("zdepth", 7));
        assert_eq!("range".parse::<Aov>(), Ok(Aov::Depth));
        assert!(e
            .to_string()
            .starts_with(r#"unknown AOV "zdepth" (use "depth", "normal""#));
    }

    #[test]
    fn values_come_pixel_by_pixel_in_film_order() {
        let px = |i: u32| AovPixel {
            depth: i as f32,
            z: 0.5 * i as f32,
            position: Vec3::new(1.0, 2.0, 3.0) * i as f32,
            normal: Vec3::new(0.0, 0.0, i as f32),
            albedo: Rgb::new(0.5, i as f32, 0.25),
            object_id: 10 + i,
            // Above 2^24: exact as an id, not as a float.
            primitive_id: (1 << 24) + 1 + i,
        };
        let film = AovFilm {
            width: 2,
            height: 1,
            pixels: vec![px(0), px(1)],
        };
        let floats = |a| match film.values(a).unwrap() {
            AovValues::Floats(v) => v,
            AovValues::Ids(_) => panic!("{a:?} gave ids"),
        };
        let ids = |a| match film.values(a).unwrap() {
            AovValues::Ids(v) => v,
            AovValues::Floats(_) => panic!("{a:?} gave floats"),
        };
        assert_eq!(floats(Aov::Depth), [0.0, 1.0]);
        assert_eq!(floats(Aov::Normal), [0.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
        assert_eq!(floats(Aov::Albedo), [0.5, 0.0, 0.25, 0.5, 1.0, 0.25]);
        assert_eq!(floats(Aov::Position), [0.0, 0.0, 0.0, 1.0, 2.0, 3.0]);
        assert_eq!(ids(Aov::ObjectId), [10, 11]);
        assert_eq!(ids(Aov::PrimitiveId), [(1 << 24) + 1, (1 << 24) + 2]);
        for a in Aov::ALL {
            let len = match film.values(a).unwrap() {
                AovValues::Floats(v) => v.len(),
                AovValues::Ids(v) => v.len(),
            };
            assert_eq!(len, 2 * a.components(), "{a:?}");
        }
    }

    #[test]
    fn a_miss_has_the_documented_values() {
        let world = WorldBuilder::new().build(1);
        let cam = Camera::new(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y, 40.0).unwrap();
        let px = AovContext::new(&world).center(&world, &FilmCamera::new(&cam, 2, 2), 1, 1);
        assert_eq!(px, AovPixel::MISS);
        assert_eq!((px.object_id, px.primitive_id), (NO_ID, NO_ID));
    }

    #[test]
    fn normals_face_the_viewer_like_shading() {
        let s = Surface {
            position: Vec3::ZERO,
            error: Vec3::ZERO,
            geometric_normal: Vec3::Z,
            shading_normal: -Vec3::Z,
            uv: glam::Vec2::ZERO,
            color: Rgb::ONE,
            triangle: 0,
            object: 0,
            material: 0,
        };
        // Seen from +z, a shading normal that disagrees with the geometric one is flipped.
        let from_front = Ray::new(Vec3::new(0.0, 0.0, 1.0), -Vec3::Z);
        assert_eq!(facing_normal(&from_front, &s), Vec3::Z);
        // Seen from -z, both are turned to the back.
        let from_back = Ray::new(Vec3::new(0.0, 0.0, -1.0), Vec3::Z);
        assert_eq!(facing_normal(&from_back, &s), -Vec3::Z);
    }
}
