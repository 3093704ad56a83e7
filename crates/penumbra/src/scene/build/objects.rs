//! Objects: each shape becomes an object-space [`Mesh`] (OBJ and PLY files read once per
//! scene, an OBJ file's MTL materials made once per file) and is added to the world with its
//! transform: copied, or, for a mesh file the scene places many times, built once and
//! instanced.

use std::path::Path;
use std::rc::Rc;

use glam::Vec3;

use super::materials::{material, Phong};
use super::placements::Placement;
use super::{Builder, Result};
use crate::geometry::{self, Mesh};
use crate::material::Cutout;
use crate::math::Transform;
use crate::scene::desc::{ColorDesc, ObjectDesc, ShapeDesc};
use crate::scene::error::{AssetKind, ErrorKind, KeyPath, SceneError};
use crate::scene::obj::{load_obj, ObjMaterial};
use crate::scene::ply::{is_ply, load_model};
use crate::texture::{Filter, ImageTexture, Texture, TextureKind, Wrap};
use crate::world::{flatten_instances, WorldError, DEFAULT_MATERIAL};

/// An OBJ file read once for every object that uses it.
pub(super) struct LoadedObj {
    mesh: Rc<Mesh>,
    mtl: Vec<ObjMaterial>,
    /// World materials made from `mtl` (then the default for faces without one), made when an
    /// object first uses the file without a `material` of its own.
    world_materials: Option<Vec<u32>>,
    /// The world's shared mesh of the file, once an object instances it.
    shared: Option<u32>,
}

impl Builder<'_> {
    /// An error at the `name` of an object whose name is empty or an earlier object's.
    pub(super) fn check_names(&self, objects: &[ObjectDesc]) -> Result<()> {
        let mut seen = std::collections::HashMap::new();
        for (i, o) in objects.iter().enumerate() {
            let Some(name) = &o.name else { continue };
            let path = KeyPath::root("objects").index(i).key("name");
            if name.is_empty() {
                return Err(self.bad(&path, "a name is not empty"));
            }
            if let Some(first) = seen.insert(name.as_str(), i) {
                let message = format!("`{name}` is already the name of objects[{first}]");
                return Err(self.bad(&path, message));
            }
        }
        Ok(())
    }

    pub(super) fn object(&mut self, path: &KeyPath, o: &ObjectDesc) -> Result<()> {
        let mut world = self.object_transform(path, o)?;
        if let Some(file) = super::gltf::gltf_file(o) {
            let placements = match &o.shape {
                ShapeDesc::Instances(d) => self.placements(path, &d.transforms)?,
                _ => vec![Placement {
                    matrix: glam::Mat4::IDENTITY,
                    material: None,
                }],
            };
            return self.gltf_object(path, o, file, world, &placements);
        }
        let material = match &o.material {
            Some(name) => Some(self.material_index(&path.key("material"), name)?),
            None => None,
        };
        let mut materials = vec![material.unwrap_or(DEFAULT_MATERIAL)];
        let mut placements = Vec::new();
        let mut file = None;
        let mesh = match &o.shape {
            ShapeDesc::Triangle(t) => {
                let uvs = t
                    .uvs
                    .map_or([glam::Vec2::ZERO, glam::Vec2::X, glam::Vec2::Y], |u| {
                        u.map(|v| v.vec2())
                    });
                let normals = t.normals.map(|n| n.map(|v| v.vec3()));
                Rc::new(geometry::triangle(
                    t.vertices.map(|v| v.vec3()),
                    uvs,
                    normals,
                ))
            }
            ShapeDesc::Quad(q) => Rc::new(geometry::quad(q.corner.vec3(), q.u.vec3(), q.v.vec3())),
            ShapeDesc::Cube(c) => {
                world =
                    Transform::from_srt(Vec3::ONE, Vec3::ZERO, c.center.vec3()).then_after(world);
                let size = c.size.rgb();
                if size.cmplt(Vec3::ZERO).any() {
                    return Err(self.bad(&path.key("size"), "size must not be negative"));
                }
                Rc::new(geometry::cube(size))
            }
            ShapeDesc::Sphere(s) => {
                world =
                    Transform::from_srt(Vec3::ONE, Vec3::ZERO, s.center.vec3()).then_after(world);
                if s.radius.0 < 0.0 {
                    return Err(self.bad(&path.key("radius"), "radius must not be negative"));
                }
                Rc::new(geometry::sphere(s.radius.f32()))
            }
            ShapeDesc::Mesh(m) => {
                file = Some(&m.file);
                self.obj_with_materials(path, &m.file, material.is_none(), &mut materials)?
            }
            ShapeDesc::Instances(d) => {
                file = Some(&d.file);
                placements = self.placements(path, &d.transforms)?;
                self.obj_with_materials(path, &d.file, material.is_none(), &mut materials)?
            }
        };
        let instances = matches!(o.shape, ShapeDesc::Instances(_));
        if !instances {
            placements.push(Placement {
                matrix: glam::Mat4::IDENTITY,
                material: None,
            });
        }
        let at = |i: usize| match instances {
            true => path.key("transforms").index(i),
            false => path.clone(),
        };
        let shared = match file {
            Some(file) => self.shared_mesh(path, file, &mesh, placements.len())?,
            None => None,
        };
        // Each copy: its placement, then the object's transform; its material, or the
        // object's materials.
        for (i, p) in placements.iter().enumerate() {
            let transform = self.copy_transform(&at(i), &world, p)?;
            let own;
            let materials = match &p.material {
                Some(name) => {
                    own = [self.material_index(&at(i).key("material"), name)?];
                    &own[..]
                }
                None => &materials[..],
            };
            let added = match shared {
                Some(id) => {
                    self.take_instance(&at(i))?;
                    self.world.add_instance(id, &transform, materials)
                }
                None => {
                    self.take_triangles(&at(i), mesh.len())?;
                    self.world.add_mesh(&mesh, &transform, materials)
                }
            };
            added.map_err(|e| self.world_error(&at(i), e))?;
        }
        Ok(())
    }

    /// The error of the world's refusal `e` of the copy or object at `at`.
    pub(super) fn world_error(&self, at: &KeyPath, e: WorldError) -> SceneError {
        let kind = match e {
            WorldError::VertexOutOfRange { .. } => ErrorKind::Asset(AssetKind::Mesh),
            _ => ErrorKind::BadValue,
        };
        self.err(kind, at, e.to_string())
    }

    /// The object-to-world transform of object `o` at `path`, checked.
    pub(super) fn object_transform(&self, path: &KeyPath, o: &ObjectDesc) -> Result<Transform> {
        let world = Transform::from_matrix(self.object_matrix(path, o)?);
        let key = if o.matrix.is_some() {
            "matrix"
        } else {
            "scale"
        };
        self.check_invertible(&path.key(key), &world, o.scale)?;
        Ok(world)
    }

    /// The transform of the copy at `at` placed by `p` under its object's `world`, checked.
    pub(super) fn copy_transform(
        &self,
        at: &KeyPath,
        world: &Transform,
        p: &Placement,
    ) -> Result<Transform> {
        let transform = Transform::from_matrix(world.world_from_object * p.matrix);
        self.check_invertible(at, &transform, None)?;
        Ok(transform)
    }

    /// The object-to-world matrix of object `o` at `path` (see [`Builder::own_matrix`]).
    pub(super) fn object_matrix(&self, path: &KeyPath, o: &ObjectDesc) -> Result<glam::Mat4> {
        self.own_matrix(path, (o.scale, o.rotate, o.translate), o.matrix.as_ref())
    }

    /// `Err` at `path` when `transform` cannot be inverted (which the normals need).
    fn check_invertible(
        &self,
        path: &KeyPath,
        transform: &Transform,
        scale: Option<ColorDesc>,
    ) -> Result<()> {
        if !transform.is_singular() {
            return Ok(());
        }
        // The rotation is orthonormal: a zero factor, or factors so large or small that the
        // inverse leaves the range of f32.
        let zero = scale.is_some_and(|s| s.rgb().cmpeq(Vec3::ZERO).any());
        let message = if zero {
            "scale must not be zero"
        } else {
            "this transform cannot be inverted in 32-bit floats (which the normals need): a zero \
             scale, or factors (or their products) beyond about 1e-38..1e38"
        };
        Err(self.bad(path, message))
    }

    /// The mesh of the OBJ `file` of the object at `path`, replacing `materials` with its MTL
    /// materials when the object names none (`with_mtl`).
    fn obj_with_materials(
        &mut self,
        path: &KeyPath,
        file: &str,
        with_mtl: bool,
        materials: &mut Vec<u32>,
    ) -> Result<Rc<Mesh>> {
        let (mesh, mtl_materials) = self.obj(&path.key("file"), file, with_mtl)?;
        if let Some(m) = mtl_materials {
            *materials = m;
        }
        Ok(mesh)
    }

    /// The shared mesh index of the OBJ `file` when the scene places it as instances rather
    /// than copies (see [`flatten_instances`]), adding it to the world once; `None` to copy.
    /// `copies` is how many this object places.
    fn shared_mesh(
        &mut self,
        path: &KeyPath,
        file: &str,
        mesh: &Rc<Mesh>,
        copies: usize,
    ) -> Result<Option<u32>> {
        let key = self.file.files().identity(&self.file.resolve(file));
        let uses = self.uses.get(&key).copied().unwrap_or(0).max(copies);
        if flatten_instances(mesh.len(), uses) {
            return Ok(None);
        }
        if let Some(id) = self.meshes.get(&key).and_then(|l| l.shared) {
            return Ok(Some(id));
        }
        self.take_triangles(path, mesh.len())?;
        let id = self
            .world
            .add_shared_mesh(Mesh::clone(mesh))
            .map_err(|e| self.err(ErrorKind::Asset(AssetKind::Mesh), path, e.to_string()))?;
        if let Some(loaded) = self.meshes.get_mut(&key) {
            loaded.shared = Some(id);
        }
        Ok(Some(id))
    }

    /// The mesh of the OBJ or PLY `file` (read once per scene) and, when `with_mtl`, the world
    /// materials of its MTL materials followed by the default (made once per file).
    fn obj(
        &mut self,
        path: &KeyPath,
        file: &str,
        with_mtl: bool,
    ) -> Result<(Rc<Mesh>, Option<Vec<u32>>)> {
        let obj_path = self.reference(path, file, ErrorKind::Asset(AssetKind::Mesh))?;
        let key = self.file.files().identity(&obj_path);
        let loaded = match self.meshes.get(&key) {
            Some(loaded) => loaded,
            None => {
                self.check_obj_size(path, &obj_path)?;
                // A `.ply` file by its extension; any other is read as OBJ.
                let model = match is_ply(&obj_path) {
                    true => load_model(self.file.files(), &obj_path).map(|(model, warnings)| {
                        let shown = warnings
                            .iter()
                            .map(|w| format!("{}: {w}", obj_path.display()));
                        self.warnings.extend(shown);
                        model
                    }),
                    false => load_obj(self.file.files(), &obj_path, self.pool.as_ref()),
                }
                .map_err(|e| {
                    self.err(
                        ErrorKind::Asset(AssetKind::Mesh),
                        path,
                        format!("cannot load mesh \"{}\": {e}", obj_path.display()),
                    )
                })?;
                self.read.insert(obj_path.clone());
                self.read.extend(model.mtl_files);
                let loaded = LoadedObj {
                    mesh: Rc::new(model.mesh),
                    mtl: model.materials,
                    world_materials: None,
                    shared: None,
                };
                self.meshes.entry(key.clone()).or_insert(loaded)
            }
        };
        let mesh = loaded.mesh.clone();
        if !with_mtl {
            return Ok((mesh, None));
        }
        if let Some(ids) = &loaded.world_materials {
            return Ok((mesh, Some(ids.clone())));
        }
        let mtl = loaded.mtl.clone();
        let mut ids = Vec::with_capacity(mtl.len() + 1);
        for m in &mtl {
            let texture = match &m.diffuse_texture {
                None => None,
                Some(t) => {
                    let what = format!("texture (map_Kd of material \"{}\")", m.name);
                    Some(self.mtl_texture(path, t, true, &what)?)
                }
            };
            // `map_d`: a cut-out at 0.5 of the image's alpha, or of its grey level as stored.
            let cutout = match &m.dissolve_texture {
                None => None,
                Some(t) => {
                    let what = format!("texture (map_d of material \"{}\")", m.name);
                    let texture = self.mtl_texture(path, t, false, &what)?;
                    Some(Cutout::with_texture(texture, 0.5))
                }
            };
            let built = material(Phong {
                diffuse: m.diffuse.map(Vec3::from),
                ambient: m.ambient.map(Vec3::from),
                specular: m.specular.map(Vec3::from),
                shininess: m.shininess.map(|s| s.max(0.0)),
                texture,
                cutout,
            });
            // A decoded image texture is at most 1.
            let (most, _) = self.reflected(&built, 1.0);
            let what = format!("the MTL's material \"{}\"", m.name);
            self.check_reflected(path, &what, most)?;
            let id = self
                .world
                .add_material(built)
                .map_err(|e| self.bad(path, e.to_string()))?;
            ids.push(id);
        }
        // Faces without an MTL material use slot `mtl.len()`: the default material.
        ids.push(DEFAULT_MATERIAL);
        if let Some(loaded) = self.meshes.get_mut(&key) {
            loaded.world_materials = Some(ids.clone());
        }
        Ok((mesh, Some(ids)))
    }

    /// A texture of an MTL file's `file` (a `map_Kd` in sRGB, or a `map_d` read as stored),
    /// bilinear and repeating, added to the world; returns its index.
    fn mtl_texture(&mut self, path: &KeyPath, file: &Path, srgb: bool, what: &str) -> Result<u32> {
        let image = self.image(path, file.to_path_buf(), srgb, what)?;
        Ok(self.world.add_texture(Texture {
            kind: TextureKind::Image(ImageTexture {
                image,
                filter: Filter::Bilinear,
                wrap: Wrap::Repeat,
            }),
            uv_scale: glam::Vec2::ONE,
            uv_offset: glam::Vec2::ZERO,
        }))
    }
}
