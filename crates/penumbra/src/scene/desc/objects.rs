//! `[[objects]]`: one struct per shape, chosen by the table's `type` key (read by `tagged`).
//!
//! ```
//! use penumbra::desc::{ObjectDesc, ShapeDesc};
//! let file = penumbra::SceneFile::from_str(r#"
//! [film]
//! width = 8
//! height = 8
//! [camera]
//! position = [0, 0, 5]
//! look_at = [0, 0, 0]
//! fov = 40
//! [[objects]]
//! type = "sphere"
//! center = [0, 0, 0]
//! radius = 1
//! translate = [0, 1, 0]
//! "#, penumbra::SceneFormat::Toml, "doc.toml", ".").unwrap();
//! let ObjectDesc { shape: ShapeDesc::Sphere(s), translate, .. } = &file.desc.objects[0] else {
//!     panic!("a sphere")
//! };
//! assert_eq!((s.radius.0, translate.unwrap().0[1]), (1.0, 1.0));
//! ```

use std::fmt;

use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;

use super::tagged::{self, Tagged};
use super::values::{ColorDesc, Exact, Num, Vec2Desc, Vec3Desc};

/// `[[objects]]`: a shape, its material and its placement (`T·Rz·Ry·Rx·S`, or a 4×4
/// `matrix`).
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectDesc {
    /// What the object is.
    pub shape: ShapeDesc,
    /// Its name, unique among the scene's objects, by which Python's `Scene.set_transform`
    /// finds it and records beside images name its ids.
    pub name: Option<String>,
    /// Material name (default: the format's default material).
    pub material: Option<String>,
    /// Scale factor(s).
    pub scale: Option<ColorDesc>,
    /// Rotation about x, y, z in degrees.
    pub rotate: Option<Vec3Desc>,
    /// Translation.
    pub translate: Option<Vec3Desc>,
    /// An object-to-world matrix, by rows (the last must be 0, 0, 0, 1), instead of `scale`,
    /// `rotate` and `translate`, as Mitsuba's `to_world` and pbrt's `Transform` take one.
    pub matrix: Option<Matrix>,
}

/// A 4×4 matrix by rows, as scene files write one.
pub type Matrix = [[Num; 4]; 4];

impl ObjectDesc {
    /// Its `type`, and the file for a mesh or instances: `sphere`, `mesh models/bunny.obj`,
    /// as `penumbra check` and records beside images name an entry.
    pub fn kind(&self) -> String {
        match &self.shape {
            ShapeDesc::Triangle(_) => "triangle".to_owned(),
            ShapeDesc::Quad(_) => "quad".to_owned(),
            ShapeDesc::Cube(_) => "cube".to_owned(),
            ShapeDesc::Sphere(_) => "sphere".to_owned(),
            ShapeDesc::Mesh(m) => format!("mesh {}", m.file),
            ShapeDesc::Instances(d) => format!("instances {}", d.file),
        }
    }
}

/// The shape of an object, by its `type`.
#[derive(Clone, Debug, PartialEq)]
pub enum ShapeDesc {
    /// `type = "triangle"`.
    Triangle(TriangleDesc),
    /// `type = "quad"`: a parallelogram.
    Quad(QuadDesc),
    /// `type = "cube"`: a box.
    Cube(CubeDesc),
    /// `type = "sphere"`: a tessellated sphere.
    Sphere(SphereDesc),
    /// `type = "mesh"`: a Wavefront OBJ, PLY, glTF or GLB file.
    Mesh(MeshDesc),
    /// `type = "instances"`: many copies of one mesh file, built once.
    Instances(InstancesDesc),
}

/// One triangle.
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleDesc {
    /// Its corners.
    pub vertices: [Vec3Desc; 3],
    /// Texture coordinates (default (0,0), (1,0), (0,1)).
    pub uvs: Option<[Vec2Desc; 3]>,
    /// Vertex normals for smooth shading.
    pub normals: Option<[Vec3Desc; 3]>,
}

/// The parallelogram `corner`, `corner + u`, `corner + u + v`, `corner + v`.
#[derive(Clone, Debug, PartialEq)]
pub struct QuadDesc {
    /// First corner.
    pub corner: Vec3Desc,
    /// First edge.
    pub u: Vec3Desc,
    /// Second edge.
    pub v: Vec3Desc,
}

/// An axis-aligned box before its transform.
#[derive(Clone, Debug, PartialEq)]
pub struct CubeDesc {
    /// Center.
    pub center: Vec3Desc,
    /// Edge length(s), not negative.
    pub size: ColorDesc,
}

/// A sphere.
#[derive(Clone, Debug, PartialEq)]
pub struct SphereDesc {
    /// Center.
    pub center: Vec3Desc,
    /// Radius, not negative.
    pub radius: Num,
}

/// A mesh file.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshDesc {
    /// Wavefront OBJ, PLY, glTF or GLB file (by extension), relative to the scene file's
    /// folder.
    pub file: String,
    /// For a glTF file: add its perspective cameras to the scene's (default false).
    pub cameras: Option<bool>,
    /// For a glTF file: add its point lights to the scene's (default false).
    pub lights: Option<bool>,
}

/// Copies of one mesh file, each placed by one of `transforms` and then by the object's own
/// `scale`, `rotate` and `translate`.
#[derive(Clone, Debug, PartialEq)]
pub struct InstancesDesc {
    /// Wavefront OBJ, PLY, glTF or GLB file (by extension), relative to the scene file's
    /// folder.
    pub file: String,
    /// Where the copies go.
    pub transforms: TransformsDesc,
}

/// The placements of `type = "instances"`.
#[derive(Clone, Debug, PartialEq)]
pub enum TransformsDesc {
    /// An inline list, one entry per copy.
    List(Vec<PlacementDesc>),
    /// A `.npy` file of (N, 4, 4) float32 or float64 matrices (row-major, as numpy writes
    /// them), relative to the scene file's folder.
    Npy(String),
}

/// One copy's placement (`T·Rz·Ry·Rx·S`, as an object's, or a 4×4 `matrix`) and, optionally,
/// its material.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PlacementDesc {
    /// Material name (default: the object's).
    pub material: Option<String>,
    /// Scale factor(s).
    pub scale: Option<ColorDesc>,
    /// Rotation about x, y, z in degrees.
    pub rotate: Option<Vec3Desc>,
    /// Translation.
    pub translate: Option<Vec3Desc>,
    /// An object-to-world matrix, by rows (the last must be 0, 0, 0, 1), instead of `scale`,
    /// `rotate` and `translate`.
    pub matrix: Option<Matrix>,
}

impl<'de> Deserialize<'de> for TransformsDesc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct TransformsVisitor;
        impl<'de> Visitor<'de> for TransformsVisitor {
            type Value = TransformsDesc;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(
                    "a list of placements ({ translate, rotate, scale, material }) or the name \
                     of a .npy file of (N, 4, 4) matrices",
                )
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<TransformsDesc, E> {
                Ok(TransformsDesc::Npy(v.to_owned()))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<TransformsDesc, A::Error> {
                let list = Vec::deserialize(de::value::SeqAccessDeserializer::new(seq))?;
                Ok(TransformsDesc::List(list))
            }
        }
        d.deserialize_any(TransformsVisitor)
    }
}

/// The `type` of an object.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum ObjectType {
    /// One triangle.
    Triangle,
    /// A parallelogram.
    Quad,
    /// A box.
    Cube,
    /// A tessellated sphere.
    Sphere,
    /// A Wavefront OBJ or PLY file.
    Mesh,
    /// Copies of an OBJ file.
    Instances,
}

#[derive(Default)]
pub(super) struct ObjectFields {
    name: Option<String>,
    material: Option<String>,
    scale: Option<ColorDesc>,
    rotate: Option<Vec3Desc>,
    translate: Option<Vec3Desc>,
    matrix: Option<Matrix>,
    vertices: Option<[Vec3Desc; 3]>,
    uvs: Option<[Vec2Desc; 3]>,
    normals: Option<[Vec3Desc; 3]>,
    corner: Option<Vec3Desc>,
    u: Option<Vec3Desc>,
    v: Option<Vec3Desc>,
    center: Option<Vec3Desc>,
    size: Option<ColorDesc>,
    radius: Option<Num>,
    file: Option<String>,
    transforms: Option<TransformsDesc>,
    cameras: Option<bool>,
    lights: Option<bool>,
}

impl Tagged for ObjectDesc {
    type Kind = ObjectType;
    type Fields = ObjectFields;
    const COMMON: &'static [&'static str] =
        &["name", "material", "scale", "rotate", "translate", "matrix"];
    const ALL: &'static [&'static str] = &[
        "vertices",
        "uvs",
        "normals",
        "corner",
        "u",
        "v",
        "center",
        "size",
        "radius",
        "file",
        "transforms",
        "cameras",
        "lights",
    ];

    const KINDS: &'static [ObjectType] = &[
        ObjectType::Triangle,
        ObjectType::Quad,
        ObjectType::Cube,
        ObjectType::Sphere,
        ObjectType::Mesh,
        ObjectType::Instances,
    ];

    fn keys(kind: ObjectType) -> &'static [&'static str] {
        match kind {
            ObjectType::Triangle => &["vertices", "uvs", "normals"],
            ObjectType::Quad => &["corner", "u", "v"],
            ObjectType::Cube => &["center", "size"],
            ObjectType::Sphere => &["center", "radius"],
            ObjectType::Mesh => &["file", "cameras", "lights"],
            ObjectType::Instances => &["file", "transforms"],
        }
    }

    fn describe(kind: ObjectType) -> &'static str {
        match kind {
            ObjectType::Triangle => "a triangle",
            ObjectType::Quad => "a quad",
            ObjectType::Cube => "a cube",
            ObjectType::Sphere => "a sphere",
            ObjectType::Mesh => "a mesh",
            ObjectType::Instances => "instances of a mesh",
        }
    }

    fn read<'de, A: MapAccess<'de>>(
        f: &mut ObjectFields,
        key: &str,
        map: &mut A,
    ) -> Result<(), A::Error> {
        match key {
            "name" => f.name = Some(map.next_value()?),
            "material" => f.material = Some(map.next_value()?),
            "scale" => f.scale = Some(map.next_value()?),
            "rotate" => f.rotate = Some(map.next_value()?),
            "translate" => f.translate = Some(map.next_value()?),
            "matrix" => f.matrix = Some(map.next_value()?),
            "vertices" => f.vertices = Some(map.next_value::<Exact<_, 3>>()?.0),
            "uvs" => f.uvs = Some(map.next_value::<Exact<_, 3>>()?.0),
            "normals" => f.normals = Some(map.next_value::<Exact<_, 3>>()?.0),
            "corner" => f.corner = Some(map.next_value()?),
            "u" => f.u = Some(map.next_value()?),
            "v" => f.v = Some(map.next_value()?),
            "center" => f.center = Some(map.next_value()?),
            "size" => f.size = Some(map.next_value()?),
            "radius" => f.radius = Some(map.next_value()?),
            "transforms" => f.transforms = Some(map.next_value()?),
            "cameras" => f.cameras = Some(map.next_value()?),
            "lights" => f.lights = Some(map.next_value()?),
            _ => f.file = Some(map.next_value()?),
        }
        Ok(())
    }

    fn finish(kind: ObjectType, f: ObjectFields) -> Result<Self, &'static str> {
        let shape = match kind {
            ObjectType::Triangle => ShapeDesc::Triangle(TriangleDesc {
                vertices: f.vertices.ok_or("vertices")?,
                uvs: f.uvs,
                normals: f.normals,
            }),
            ObjectType::Quad => ShapeDesc::Quad(QuadDesc {
                corner: f.corner.ok_or("corner")?,
                u: f.u.ok_or("u")?,
                v: f.v.ok_or("v")?,
            }),
            ObjectType::Cube => ShapeDesc::Cube(CubeDesc {
                center: f.center.ok_or("center")?,
                size: f.size.ok_or("size")?,
            }),
            ObjectType::Sphere => ShapeDesc::Sphere(SphereDesc {
                center: f.center.ok_or("center")?,
                radius: f.radius.ok_or("radius")?,
            }),
            ObjectType::Mesh => ShapeDesc::Mesh(MeshDesc {
                file: f.file.ok_or("file")?,
                cameras: f.cameras,
                lights: f.lights,
            }),
            ObjectType::Instances => ShapeDesc::Instances(InstancesDesc {
                file: f.file.ok_or("file")?,
                transforms: f.transforms.ok_or("transforms")?,
            }),
        };
        Ok(ObjectDesc {
            shape,
            name: f.name,
            material: f.material,
            scale: f.scale,
            rotate: f.rotate,
            translate: f.translate,
            matrix: f.matrix,
        })
    }
}

impl<'de> Deserialize<'de> for ObjectDesc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        tagged::deserialize(d)
    }
}
