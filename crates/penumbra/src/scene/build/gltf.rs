//! glTF objects: a `type = "mesh"` or `"instances"` object naming a `.gltf` or `.glb` file
//! places the file's node graph under the object's transform (and each placement's). Each
//! glTF mesh is read once per scene; a mesh the scene places several times is built once
//! and instanced, as the file's node graph says (glTF does not use [`flatten_instances`]:
//! its nodes name the sharing, and `check` reports a file's meshes stored once). Materials come from the
//! file (unless the object names one), each image decoded once. Cameras and point lights of
//! the file are added before the scene's objects (see [`Builder::gltf_cameras_and_lights`]).

use std::collections::HashMap;
use std::path::Path;
use std::rc::Rc;
use std::sync::Arc;

use glam::{Mat4, Vec3};

use super::placements::Placement;
use super::{Builder, Result};
use crate::camera::{Camera, Lens};
use crate::light::{DirectionalLight, Light, PointLight, SpotLight};
use crate::material::{Cutout, Material};
use crate::math::Transform;
use crate::scene::desc::{ObjectDesc, ShapeDesc};
use crate::scene::error::{AssetKind, ErrorKind, KeyPath};
use crate::scene::gltf::{
    load_gltf, unique, AlphaMode, GltfLight, GltfLightKind, GltfMaterial, GltfModel, ImageSource,
};
use crate::texture::{Image, ImageTexture, Texture, TextureKind};
use crate::texture_file::decode_texture_image;
#[cfg(doc)]
use crate::world::flatten_instances;
use crate::world::DEFAULT_MATERIAL;

/// Shininess bounds of the roughness mapping: 2/α² − 2 is 0 at roughness 1 and infinite at 0.
const SHININESS: (f32, f32) = (1.0, 10_000.0);

/// A glTF file read once for every object that uses it.
pub(super) struct LoadedGltf {
    model: Rc<GltfModel>,
    /// World materials of the file's materials, made when an object first uses the file
    /// without a `material` of its own.
    materials: Option<Vec<u32>>,
    /// Decoded images by glTF index.
    images: Vec<Option<Arc<Image>>>,
    /// The world's shared mesh of each glTF mesh, once instanced.
    shared: HashMap<usize, u32>,
}

/// True for a path naming a glTF file (`.gltf` or `.glb`, in any case).
pub(crate) fn is_gltf(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// The glTF file an object names, if it names one.
pub(super) fn gltf_file(o: &ObjectDesc) -> Option<&str> {
    let file = match &o.shape {
        ShapeDesc::Mesh(m) => &m.file,
        ShapeDesc::Instances(d) => &d.file,
        _ => return None,
    };
    is_gltf(Path::new(file)).then_some(file.as_str())
}

/// The metallic-roughness → Phong mapping (docs/scene-format.md): specular
/// lerp(0.04, base colour, metallic), shininess 2/α² − 2 with α = roughness², clamped.
pub(crate) fn phong_of(m: &GltfMaterial) -> (Vec3, f32) {
    let base = m.base_color.truncate();
    let specular = Vec3::splat(0.04).lerp(base, m.metallic);
    let alpha = m.roughness * m.roughness;
    let shininess = match alpha > 0.0 {
        true => 2.0 / (alpha * alpha) - 2.0,
        false => f32::INFINITY,
    };
    (specular, shininess.clamp(SHININESS.0, SHININESS.1))
}

/// The cut-out threshold of an alpha mode: none for OPAQUE; `alphaCutoff` for MASK; 0.5 for
/// BLEND, read as a cut-out (as pbrt and Blender's alpha clip read it: a ray tracer without
/// transparency keeps a texel whose alpha is at least half).
pub(crate) fn cutout_of(alpha: AlphaMode) -> Option<f32> {
    match alpha {
        AlphaMode::Opaque => None,
        AlphaMode::Mask(cutoff) => Some(cutoff),
        AlphaMode::Blend => Some(0.5),
    }
}

impl Builder<'_> {
    /// The glTF file `file` named at `path`, read once per scene.
    fn gltf(&mut self, path: &KeyPath, file: &str) -> Result<Rc<GltfModel>> {
        let resolved = self.reference(path, file, ErrorKind::Asset(AssetKind::Mesh))?;
        let key = self.file.files().identity(&resolved);
        if let Some(loaded) = self.gltfs.get(&key) {
            return Ok(loaded.model.clone());
        }
        self.check_obj_size(path, &resolved)?;
        let model = load_gltf(self.file.files(), &resolved, self.budget.left()).map_err(|e| {
            self.err(
                ErrorKind::Asset(AssetKind::Mesh),
                path,
                format!("cannot load glTF \"{}\": {e}", resolved.display()),
            )
        })?;
        self.read.insert(resolved.clone());
        for w in &model.warnings {
            self.warnings.push(format!("{}: {w}", resolved.display()));
        }
        let model = Rc::new(model);
        self.gltfs.insert(
            key,
            LoadedGltf {
                model: model.clone(),
                materials: None,
                images: vec![None; model.images.len()],
                shared: HashMap::new(),
            },
        );
        Ok(model)
    }

    /// Adds the cameras and point lights of every `type = "mesh"` object that asks for them
    /// (`cameras = true`, `lights = true`), placed by the object's transform: cameras named
    /// uniquely among the scene's, lights after the scene's. Returns how many cameras.
    pub(super) fn gltf_cameras(&mut self) -> Result<usize> {
        let desc = &self.file.desc;
        let mut taken: Vec<String> = match &desc.camera {
            Some(_) => vec!["camera".to_owned()],
            None => desc.cameras.names().map(str::to_owned).collect(),
        };
        let mut added = 0;
        for (i, o) in self.file.desc.objects.iter().enumerate() {
            let ShapeDesc::Mesh(m) = &o.shape else {
                continue;
            };
            if m.cameras != Some(true) {
                continue;
            }
            let path = KeyPath::root("objects").index(i);
            let model = self.gltf_for_key(&path, &m.file, "cameras")?;
            let world = self.object_matrix(&path, o)?;
            for c in &model.cameras {
                let (position, look_at, up) = c.view(world);
                let name = unique(&c.name, |n| taken.iter().any(|t| t == n));
                taken.push(name.clone());
                let camera = Camera::new(position, look_at, up, c.fov_y_deg)
                    .and_then(|camera| match c.orthographic_height(world) {
                        Some(height) => camera.with_lens(Lens::Orthographic { height }),
                        None => Ok(camera),
                    })
                    .map_err(|e| {
                        self.bad(&path.key("cameras"), format!("camera \"{}\": {e}", c.name))
                    })?;
                self.world
                    .add_camera(name, camera)
                    .map_err(|e| self.bad(&path.key("cameras"), e.to_string()))?;
                added += 1;
            }
        }
        Ok(added)
    }

    /// The lights of every object with `lights = true`, each with its object's path.
    pub(super) fn gltf_lights(&mut self) -> Result<Vec<(KeyPath, Light)>> {
        let mut lights = Vec::new();
        for (i, o) in self.file.desc.objects.iter().enumerate() {
            let ShapeDesc::Mesh(m) = &o.shape else {
                continue;
            };
            if m.lights != Some(true) {
                continue;
            }
            let path = KeyPath::root("objects").index(i);
            let model = self.gltf_for_key(&path, &m.file, "lights")?;
            let world = self.object_matrix(&path, o)?;
            for l in &model.lights {
                lights.push((path.clone(), gltf_light(l, world)));
            }
        }
        Ok(lights)
    }

    /// The model of the glTF `file` of the object at `path`, whose `key` asks for its
    /// cameras or lights (which only glTF files have).
    fn gltf_for_key(&mut self, path: &KeyPath, file: &str, key: &str) -> Result<Rc<GltfModel>> {
        if !is_gltf(Path::new(file)) {
            return Err(self.bad(
                &path.key(key),
                format!("{key} are read from glTF files (.gltf, .glb) only"),
            ));
        }
        self.gltf(&path.key("file"), file)
    }

    /// Places the glTF file `file` of the object `o` at `path`: every mesh use of its scene,
    /// for each of `placements`, under the object's transform `world`.
    pub(super) fn gltf_object(
        &mut self,
        path: &KeyPath,
        o: &ObjectDesc,
        file: &str,
        world: Transform,
        placements: &[Placement],
    ) -> Result<()> {
        let model = self.gltf(&path.key("file"), file)?;
        let key = self.file.files().identity(&self.file.resolve(file));
        let own = match &o.material {
            Some(name) => Some(self.material_index(&path.key("material"), name)?),
            None => None,
        };
        let file_materials = match own {
            Some(_) => Vec::new(),
            None => self.gltf_materials(&path.key("file"), &key, &model)?,
        };
        let mut uses = vec![0usize; model.meshes.len()];
        for u in &model.uses {
            uses[u.mesh] += placements.len();
        }
        let instances = matches!(o.shape, ShapeDesc::Instances(_));
        for (i, p) in placements.iter().enumerate() {
            let at = match instances {
                true => path.key("transforms").index(i),
                false => path.clone(),
            };
            let placed = world.world_from_object * p.matrix;
            let own = match &p.material {
                Some(name) => Some(self.material_index(&at.key("material"), name)?),
                None => own,
            };
            for u in &model.uses {
                let mesh = &model.meshes[u.mesh];
                let materials: Vec<u32> = match own {
                    Some(m) => vec![m],
                    None => mesh
                        .materials
                        .iter()
                        .map(|m| m.map_or(DEFAULT_MATERIAL, |k| file_materials[k]))
                        .collect(),
                };
                let transform = Transform::from_matrix(placed * u.matrix);
                if transform.is_singular() {
                    return Err(self.bad(
                        &at,
                        format!(
                            "the transform of mesh \"{}\" (the object's times its node's) cannot \
                             be inverted in 32-bit floats",
                            mesh.name
                        ),
                    ));
                }
                let added = match uses[u.mesh] <= 1 {
                    true => {
                        self.take_triangles(&at, mesh.mesh.len())?;
                        self.world.add_mesh(&mesh.mesh, &transform, &materials)
                    }
                    false => {
                        let shared = self.gltf_shared(&at, &key, &model, u.mesh)?;
                        self.take_instance(&at)?;
                        self.world.add_instance(shared, &transform, &materials)
                    }
                };
                added.map_err(|e| {
                    let message = format!("mesh \"{}\": {e}", mesh.name);
                    self.err(ErrorKind::Asset(AssetKind::Mesh), &at, message)
                })?;
            }
        }
        Ok(())
    }

    /// The world's shared mesh of glTF mesh `k`, added once.
    fn gltf_shared(
        &mut self,
        at: &KeyPath,
        key: &Path,
        model: &GltfModel,
        k: usize,
    ) -> Result<u32> {
        if let Some(&id) = self.gltfs.get(key).and_then(|l| l.shared.get(&k)) {
            return Ok(id);
        }
        let mesh = &model.meshes[k];
        self.take_triangles(at, mesh.mesh.len())?;
        let id = self.world.add_shared_mesh(mesh.mesh.clone()).map_err(|e| {
            let message = format!("mesh \"{}\": {e}", mesh.name);
            self.err(ErrorKind::Asset(AssetKind::Mesh), at, message)
        })?;
        if let Some(loaded) = self.gltfs.get_mut(key) {
            loaded.shared.insert(k, id);
        }
        Ok(id)
    }

    /// The world materials of every material of the glTF file (by its identity `key`), made
    /// once per file.
    fn gltf_materials(&mut self, at: &KeyPath, key: &Path, model: &GltfModel) -> Result<Vec<u32>> {
        if let Some(ids) = self.gltfs.get(key).and_then(|l| l.materials.clone()) {
            return Ok(ids);
        }
        let mut ids = Vec::with_capacity(model.materials.len());
        for m in &model.materials {
            let (texture, alpha_texture) = match &m.texture {
                Some(t) if model.images.get(t.image).is_some_and(Option::is_some) => {
                    let image = self.gltf_image(at, key, model, t.image)?;
                    let has_alpha = image.alpha.is_some();
                    let id = self.world.add_texture(Texture {
                        kind: TextureKind::Image(ImageTexture {
                            image,
                            filter: t.filter,
                            wrap: t.wrap,
                        }),
                        uv_scale: t.uv_scale,
                        uv_offset: t.uv_offset,
                    });
                    // A texture without an alpha channel is opaque (alpha 1) in glTF.
                    (Some(id), has_alpha.then_some(id))
                }
                _ => (None, None),
            };
            let cutout = cutout_of(m.alpha).map(|cutoff| Cutout {
                texture: alpha_texture,
                factor: m.base_color.w,
                cutoff,
            });
            let (specular, shininess) = phong_of(m);
            let diffuse = m.base_color.truncate();
            // Fields penumbra adds to materials later take their defaults.
            #[allow(clippy::needless_update)]
            let built = Material {
                ambient: diffuse,
                diffuse,
                specular,
                shininess,
                texture,
                cutout,
                ..Material::default()
            };
            let (most, _) = self.reflected(&built, 1.0);
            self.check_reflected(at, &format!("the glTF material \"{}\"", m.name), most)?;
            let id = self
                .world
                .add_material(built)
                .map_err(|e| self.bad(at, e.to_string()))?;
            ids.push(id);
        }
        if let Some(loaded) = self.gltfs.get_mut(key) {
            loaded.materials = Some(ids.clone());
        }
        Ok(ids)
    }

    /// Image `k` of the glTF file, decoded once (sRGB to linear).
    fn gltf_image(
        &mut self,
        at: &KeyPath,
        key: &Path,
        model: &GltfModel,
        k: usize,
    ) -> Result<Arc<Image>> {
        if let Some(img) = self.gltfs.get(key).and_then(|l| l.images[k].clone()) {
            return Ok(img);
        }
        let what = format!("texture (images[{k}] of the glTF file)");
        let image = match &model.images[k] {
            Some(ImageSource::File(file)) => self.image(at, file.clone(), true, &what)?,
            Some(ImageSource::Bytes(bytes)) => {
                let img = decode_texture_image(bytes, true, self.budget.left()).map_err(|e| {
                    self.err(
                        ErrorKind::Asset(AssetKind::Image),
                        at,
                        format!("cannot decode {what} in \"{}\": {e}", key.display()),
                    )
                })?;
                self.budget.texture_bytes +=
                    img.width as u64 * img.height as u64 * super::budget::BYTES_PER_TEXEL;
                Arc::new(img)
            }
            None => return Err(self.bad(at, format!("images[{k}] of the glTF file was not read"))),
        };
        if let Some(loaded) = self.gltfs.get_mut(key) {
            loaded.images[k] = Some(image.clone());
        }
        Ok(image)
    }
}

/// The penumbra light of glTF light `l` placed by `world`: candela (point, spot) and lux
/// (directional) map 1:1 onto a point light's intensity and a directional light's irradiance
/// (docs/scene-format.md).
fn gltf_light(l: &GltfLight, world: Mat4) -> Light {
    let intensity = l.color * l.intensity;
    let position = world.transform_point3(l.position);
    // A direction squashed to zero by the placement keeps the file's own.
    let direction = world
        .transform_vector3(l.direction)
        .try_normalize()
        .unwrap_or(l.direction);
    match l.kind {
        GltfLightKind::Point => Light::Point(PointLight {
            position,
            intensity,
        }),
        GltfLightKind::Spot { inner, outer } => Light::Spot(SpotLight {
            position,
            direction,
            intensity,
            cos_inner: inner.cos(),
            cos_outer: outer.cos(),
        }),
        GltfLightKind::Directional => Light::Directional(DirectionalLight {
            direction,
            irradiance: intensity,
            cos_half_angle: 1.0,
            n: 1,
        }),
    }
}
