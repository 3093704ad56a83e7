//! [`SceneDesc`](super::SceneDesc) → [`Scene`]: checks every value the parser could not (ranges,
//! names that refer to other entries), loads meshes and textures, and feeds a
//! [`WorldBuilder`]. Split by concern: `settings` (film, cameras, `[render]`), `materials`
//! (textures, materials, lights, and MTL materials through the same conversion) and `objects`
//! (shapes and OBJ meshes). Every error is located in the file.

mod bounds;
mod budget;
mod gltf;
mod materials;
mod objects;
mod paths;
mod placements;
pub(crate) use placements::{copy_transforms, scale_error};
mod settings;
mod still;

use std::collections::{BTreeSet, HashMap};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use super::error::{ErrorKind, KeyPath, SceneError};
use super::{Scene, SceneFile};
use crate::integrator::LightModel;
use crate::pool::thread_pool;
use crate::texture::Image;
use crate::world::WorldBuilder;

type Result<T> = std::result::Result<T, SceneError>;

/// Builder state: the file for locating errors, caches shared across entries, the world being
/// built and the threads that read meshes and build the BVH.
struct Builder<'a> {
    file: &'a SceneFile,
    /// `None` when the system refused threads: everything then runs on the calling thread.
    pool: Option<rayon::ThreadPool>,
    /// Decoded images by canonical path and color space, shared by every texture using one.
    images: HashMap<(PathBuf, bool), Arc<Image>>,
    /// OBJ files read once per scene.
    meshes: HashMap<PathBuf, objects::LoadedObj>,
    /// glTF files read once per scene.
    gltfs: HashMap<PathBuf, gltf::LoadedGltf>,
    /// What the files read ignored (glTF features penumbra does not render), each naming
    /// its file.
    warnings: Vec<String>,
    /// How many copies of each OBJ file the scene places.
    uses: HashMap<PathBuf, usize>,
    /// `.npy` files of instance transforms read once per scene.
    transforms: HashMap<PathBuf, std::rc::Rc<[glam::Mat4]>>,
    /// Every file read (meshes, material libraries, images), as resolved.
    read: BTreeSet<PathBuf>,
    world: WorldBuilder,
    /// What the lights emit together, the ambient light and the light model: the bounds an
    /// MTL material is checked against (see `bounds`).
    lighting: Lighting,
    /// The memory the scene may take, and what it takes so far.
    budget: budget::Budget,
    /// The cameras with a path, by name, in file order.
    paths: Vec<(String, crate::camera_path::CameraPath)>,
}

/// The light a material reflects, for its radiance bound.
#[derive(Clone, Copy)]
struct Lighting {
    emission: f64,
    ambient: f64,
    model: LightModel,
}

pub(super) fn build(file: &SceneFile, threads: usize) -> Result<Scene> {
    let start = Instant::now();
    let desc = &file.desc;
    let pool = thread_pool(threads).ok().map(|(pool, _)| pool);
    let mut b = Builder::new(file, pool, crate::memory::available());
    let film = b.film()?;
    let file_cameras = b.cameras()?;
    let gltf_cameras = b.gltf_cameras()?;
    if file_cameras + gltf_cameras == 0 {
        let path = desc.objects.iter().position(|o| {
            matches!(&o.shape, crate::scene::desc::ShapeDesc::Mesh(m) if m.cameras == Some(true))
        });
        return Err(match path {
            Some(i) => b.err(
                ErrorKind::MissingKey,
                &KeyPath::root("objects").index(i).key("cameras"),
                "the glTF file has no perspective camera, and the scene has no [camera] table",
            ),
            None => b.err(
                ErrorKind::MissingKey,
                &KeyPath::default(),
                "missing key `camera` (a [camera] table or [cameras.NAME] tables)",
            ),
        });
    }
    let (settings, default_light_samples) = b.settings(film.width, film.height)?;

    let render = KeyPath::root("render");
    b.check_render_color(&render.key("ambient"), settings.ambient)?;
    b.check_render_color(&render.key("background"), settings.background)?;

    // The largest channel of each texture, for the materials' radiance bounds.
    let mut texture_peaks = Vec::new();
    for (name, tex) in &desc.textures.0 {
        let texture = b.texture(&KeyPath::root("textures").key(name), tex)?;
        texture_peaks.push(bounds::texture_peak(&texture));
        b.world.add_texture(texture);
    }
    // Material 0 is the format's default; named materials follow in file order.
    let mut materials = Vec::new();
    for (name, m) in &desc.materials.0 {
        let path = KeyPath::root("materials").key(name);
        let material = b.material(&path, m)?;
        materials.push(material.clone());
        b.world
            .add_material(material)
            .map_err(|e| b.err(ErrorKind::BadValue, &path, e.to_string()))?;
    }
    let mut emission = 0.0;
    for (i, l) in desc.lights.iter().enumerate() {
        let path = KeyPath::root("lights").index(i);
        let light = b.light(&path, l, default_light_samples)?;
        let emitted = bounds::emission(l, &light, settings.light_model);
        emission += emitted;
        b.check_emission(&path, bounds::light_key(l), emitted, emission)?;
        b.world.add_light(light);
    }
    for (path, light) in b.gltf_lights()? {
        let emitted = bounds::peak(match &light {
            crate::light::Light::Point(p) => p.intensity,
            crate::light::Light::Spot(s) => s.intensity,
            crate::light::Light::Directional(d) => d.irradiance,
            _ => continue,
        });
        emission += emitted;
        b.check_emission(&path, "lights", emitted, emission)?;
        b.world.add_light(light);
    }
    b.lighting = Lighting {
        emission,
        ambient: bounds::peak(settings.ambient),
        model: settings.light_model,
    };
    for ((name, m), material) in desc.materials.0.iter().zip(&materials) {
        let texture = material.texture.map_or(1.0, |t| texture_peaks[t as usize]);
        let (most, term) = b.reflected(material, texture);
        let path = KeyPath::root("materials").key(name);
        b.check_reflected(&bounds::material_key(&path, m, term), "this material", most)?;
    }
    b.uses = b.count_uses(&desc.objects);
    b.check_names(&desc.objects)?;
    let mut objects = Vec::with_capacity(desc.objects.len());
    for (i, o) in desc.objects.iter().enumerate() {
        let first = b.world.object_count();
        b.object(&KeyPath::root("objects").index(i), o)?;
        objects.push(first..b.world.object_count());
    }
    if let Some(problem) = b.world.scale_problem() {
        return Err(scale_error(file, problem));
    }
    let load_time = start.elapsed();
    let world = b.world.build_on(b.pool.as_ref());
    Ok(Scene {
        world: Arc::new(world),
        load_time,
        settings,
        output: film.output,
        gamma: film.gamma,
        files: b.read.into_iter().collect(),
        objects,
        warnings: b.warnings,
        paths: b.paths,
    })
}

impl<'a> Builder<'a> {
    /// A builder of `file` with nothing built yet, on `pool`'s threads (`None`: the calling
    /// thread's), within `available` bytes of memory (`None`: no bound).
    fn new(
        file: &'a SceneFile,
        pool: Option<rayon::ThreadPool>,
        available: Option<u64>,
    ) -> Builder<'a> {
        Builder {
            file,
            pool,
            images: HashMap::new(),
            meshes: HashMap::new(),
            gltfs: HashMap::new(),
            warnings: Vec::new(),
            uses: HashMap::new(),
            transforms: HashMap::new(),
            read: BTreeSet::new(),
            world: WorldBuilder::new(),
            lighting: Lighting {
                emission: 0.0,
                ambient: 0.0,
                model: LightModel::Phong,
            },
            budget: budget::Budget::new(available),
            paths: Vec::new(),
        }
    }
}

impl Builder<'_> {
    fn err(&self, kind: ErrorKind, path: &KeyPath, message: impl Into<String>) -> SceneError {
        self.file.error(kind, path, message)
    }

    /// A value out of its range.
    fn bad(&self, path: &KeyPath, message: impl Into<String>) -> SceneError {
        self.err(ErrorKind::BadValue, path, message)
    }

    /// The file that `text`, the value at `path`, names: resolved against the scene's folder,
    /// when the scene may read it (see the module `reach`); else an error of `kind`.
    fn reference(&self, path: &KeyPath, text: &str, kind: ErrorKind) -> Result<PathBuf> {
        self.file
            .reach()
            .resolve(&self.file.base_dir, text)
            .map_err(|e| self.err(kind, path, e.to_string()))
    }
}

/// " (known: a, b)" or " (none are defined)", to end an unknown-name message.
fn list(known: &[&str]) -> String {
    if known.is_empty() {
        " (none are defined)".to_owned()
    } else {
        format!(" (known: {})", known.join(", "))
    }
}
