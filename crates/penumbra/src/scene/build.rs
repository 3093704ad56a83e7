//! SceneDesc → Scene: checks every value, resolves names, loads meshes and textures, turns
//! every object into world-space triangles and builds the BVH.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::desc::*;
use super::error::{KeyPath, SceneError};
use super::obj::{load_obj, ObjMaterial};
use super::{Scene, SceneFile};
use crate::camera::{Camera, CameraError};
use crate::geometry::{self, Mesh};
use crate::image_io::{load_texture_image, OutputFormat};
use crate::integrator::{LightModel, Shading};
use crate::light::{AreaLight, Light, PointLight};
use crate::material::Material;
use crate::math::{Rgb, Transform};
use crate::render::{RenderSettings, View, MAX_LIGHT_SAMPLES, MAX_PIXELS, MAX_SPP};
use crate::sampling::{perfect_square_root, Sampler};
use crate::texture::{Filter, Image, ImageTexture, Texture, TextureKind, Wrap};
use crate::world::{WorldBuilder, DEFAULT_MATERIAL};

const DEFAULT_LIGHT_SAMPLES: u32 = 5;

type Result<T> = std::result::Result<T, SceneError>;

fn v3(v: Vec3Desc) -> Vec3 {
    Vec3::new(v.0[0] as f32, v.0[1] as f32, v.0[2] as f32)
}

fn v2(v: Vec2Desc) -> Vec2 {
    Vec2::new(v.0[0] as f32, v.0[1] as f32)
}

fn rgb(c: ColorDesc) -> Rgb {
    Vec3::new(c.0[0] as f32, c.0[1] as f32, c.0[2] as f32)
}

/// Builder state: the file for locating errors, and caches shared across objects.
struct Builder<'a> {
    file: &'a SceneFile,
    images: HashMap<(PathBuf, bool), Arc<Image>>,
    meshes: HashMap<PathBuf, LoadedObj>,
    world: WorldBuilder,
}

/// An OBJ file read once for every object that uses it.
struct LoadedObj {
    mesh: Rc<Mesh>,
    mtl: Vec<ObjMaterial>,
    /// Scene materials made from `mtl` (then the default for faces without one), made when
    /// an object first uses the file without a `material` override.
    scene_materials: Option<Vec<u32>>,
}

pub(super) fn build(file: &SceneFile, threads: usize) -> Result<Scene> {
    let desc = &file.desc;
    let mut b = Builder {
        file,
        images: HashMap::new(),
        meshes: HashMap::new(),
        world: WorldBuilder::new(),
    };
    let (width, height, output, gamma) = b.film()?;
    b.cameras()?;
    let (settings, default_light_samples) = b.settings(width, height)?;

    for (name, tex) in &desc.textures.0 {
        let t = b.texture(&KeyPath::root("textures").key(name), tex)?;
        b.world.add_texture(t);
    }
    // Material 0 is the format's default; named materials follow in file order.
    for (name, m) in &desc.materials.0 {
        let path = KeyPath::root("materials").key(name);
        let mat = b.material(&path, m)?;
        b.world
            .add_material(mat)
            .map_err(|e| b.err(&path, e.to_string()))?;
    }
    for (i, l) in desc.lights.iter().enumerate() {
        let light = b.light(&KeyPath::root("lights").index(i), l, default_light_samples)?;
        b.world.add_light(light);
    }
    for (i, o) in desc.objects.iter().enumerate() {
        b.object(&KeyPath::root("objects").index(i), o)?;
    }
    Ok(Scene {
        world: Arc::new(b.world.build(threads)),
        settings,
        output,
        gamma,
    })
}

impl Builder<'_> {
    fn err(&self, path: &KeyPath, message: impl Into<String>) -> SceneError {
        self.file.error(path, message)
    }

    fn require<T: Copy>(&self, path: &KeyPath, key: &str, value: Option<T>) -> Result<T> {
        value.ok_or_else(|| self.err(path, format!("missing key `{key}`")))
    }

    /// Rejects keys that are present but mean nothing for this kind of entry.
    fn only_keys(
        &self,
        path: &KeyPath,
        kind: &str,
        present: &[(&str, bool)],
        allowed: &[&str],
    ) -> Result<()> {
        for (key, is_present) in present {
            if *is_present && !allowed.contains(key) {
                return Err(self.err(
                    &path.key(key),
                    format!(
                        "unknown key `{key}` for {kind} (it takes: {})",
                        allowed.join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }

    fn film(&self) -> Result<(u32, u32, Option<PathBuf>, Option<f32>)> {
        let d = &self.file.desc.film;
        let path = KeyPath::root("film");
        let dim = |key: &str, v: i64| -> Result<u32> {
            if v < 1 {
                return Err(self.err(
                    &path.key(key),
                    format!("{key} must be at least 1 pixel, not {v}"),
                ));
            }
            u32::try_from(v)
                .map_err(|_| self.err(&path.key(key), format!("{key} {v} is too large")))
        };
        let width = dim("width", d.width)?;
        let height = dim("height", d.height)?;
        if width as u64 * height as u64 > MAX_PIXELS {
            let message = format!(
                "a {width}x{height} image is too large for memory (at most {MAX_PIXELS} pixels)"
            );
            return Err(self.err(&path.key("width"), message));
        }
        let gamma = match d.gamma {
            Some(Num(g)) if g <= 0.0 => {
                return Err(self.err(
                    &path.key("gamma"),
                    format!("gamma must be positive, not {g}"),
                ))
            }
            g => g.map(|g| g.0 as f32),
        };
        let output = match d.output.as_deref() {
            None => None,
            // Checked even when the command line's -o wins: the file is wrong either way.
            Some(o) if OutputFormat::from_path(Path::new(o)).is_none() => {
                return Err(self.err(
                    &path.key("output"),
                    format!("unknown image format \"{o}\" (use .png, .jpg, .exr or .pfm)"),
                ))
            }
            Some(o) => Some(self.file.resolve(o)),
        };
        Ok((width, height, output, gamma))
    }

    /// Every camera of the file, checked, into the world under its name.
    fn cameras(&mut self) -> Result<()> {
        let desc = &self.file.desc;
        let named: Vec<(String, &CameraDesc, KeyPath)> =
            match (&desc.camera, desc.cameras.0.is_empty()) {
                (Some(_), false) => {
                    return Err(self.err(
                        &KeyPath::root("cameras"),
                        "a scene has either [camera] or [cameras.NAME] tables, not both",
                    ))
                }
                (None, true) => {
                    return Err(self.err(
                        &KeyPath::default(),
                        "missing key `camera` (a [camera] table or [cameras.NAME] tables)",
                    ))
                }
                (Some(c), true) => vec![("camera".to_owned(), c, KeyPath::root("camera"))],
                (None, false) => desc
                    .cameras
                    .0
                    .iter()
                    .map(|(n, c)| (n.clone(), c, KeyPath::root("cameras").key(n)))
                    .collect(),
            };
        for (name, c, path) in named {
            let cam = Camera::new(
                v3(c.position),
                v3(c.look_at),
                c.up.map_or(Vec3::Y, v3),
                c.fov.0 as f32,
            )
            .map_err(|e| match e {
                CameraError::FovOutOfRange => self.err(
                    &path.key("fov"),
                    format!("fov must be between 0 and 180 degrees, not {}", c.fov.0),
                ),
                CameraError::Degenerate => self.err(&path.key("look_at"), e.to_string()),
            })?;
            // Names are table keys, unique by construction.
            self.world
                .add_camera(name, cam)
                .map_err(|e| self.err(&path, e.to_string()))?;
        }
        Ok(())
    }

    /// The file's render settings on a `width × height` film, and the default N of area
    /// lights.
    fn settings(&self, width: u32, height: u32) -> Result<(RenderSettings, u32)> {
        let r = &self.file.desc.render;
        let path = KeyPath::root("render");
        let file_sampler = match &r.sampler {
            None => None,
            Some(s) => Some(Sampler::from_name(s).ok_or_else(|| {
                self.err(
                    &path.key("sampler"),
                    format!("unknown sampler \"{s}\" (use center, grid, rgss or jittered)"),
                )
            })?),
        };
        let file_samples = match r.samples {
            None => None,
            Some(s) => {
                let n = u32::try_from(s)
                    .ok()
                    .filter(|&s| s <= MAX_SPP)
                    .and_then(perfect_square_root)
                    .ok_or_else(|| {
                        self.err(&path.key("samples"), format!("samples must be a perfect square (1, 4, 9, 16, ...) up to {MAX_SPP}, not {s}"))
                    })?;
                if file_sampler == Some(Sampler::Center) && n != 1 {
                    return Err(self.err(
                        &path.key("samples"),
                        "the center sampler takes exactly 1 sample",
                    ));
                }
                Some(n)
            }
        };
        let sampler = file_sampler.unwrap_or(Sampler::Rgss);
        let samples_per_axis = if sampler == Sampler::Center {
            1
        } else {
            file_samples.unwrap_or(2)
        };

        let light_samples = match r.light_samples {
            None => DEFAULT_LIGHT_SAMPLES,
            Some(n) => self.light_n(&path.key("light_samples"), n)?,
        };
        let shading = match r.shading.as_deref() {
            None | Some("phong") => Shading::Phong,
            Some("blinn-phong") => Shading::BlinnPhong,
            Some(s) => {
                return Err(self.err(
                    &path.key("shading"),
                    format!("unknown shading \"{s}\" (use phong or blinn-phong)"),
                ))
            }
        };
        let light_model = match r.light_model.as_deref() {
            None | Some("phong") => LightModel::Phong,
            Some("physical") => LightModel::Physical,
            Some(s) => {
                return Err(self.err(
                    &path.key("light_model"),
                    format!("unknown light model \"{s}\" (use phong or physical)"),
                ))
            }
        };
        let settings = RenderSettings {
            view: View::First,
            width,
            height,
            sampler,
            spp: samples_per_axis * samples_per_axis,
            light_samples: None,
            seed: r.seed.unwrap_or(0),
            shading,
            light_model,
            ambient: r.ambient.map_or(Rgb::splat(0.1), rgb),
            background: r.background.map_or(Rgb::ZERO, rgb),
        };
        Ok((settings, light_samples))
    }

    fn light_n(&self, path: &KeyPath, n: i64) -> Result<u32> {
        u32::try_from(n)
            .ok()
            .filter(|&n| (1..=MAX_LIGHT_SAMPLES).contains(&n))
            .ok_or_else(|| {
                self.err(
                    path,
                    format!("light samples N must be between 1 and {MAX_LIGHT_SAMPLES}, not {n}"),
                )
            })
    }

    fn image(
        &mut self,
        path: &KeyPath,
        file: PathBuf,
        srgb: bool,
        what: &str,
    ) -> Result<Arc<Image>> {
        let key = (std::fs::canonicalize(&file).unwrap_or(file.clone()), srgb);
        if let Some(img) = self.images.get(&key) {
            return Ok(img.clone());
        }
        let img = load_texture_image(&file, srgb).map_err(|e| {
            self.err(
                path,
                format!("cannot load {what} \"{}\": {e}", file.display()),
            )
        })?;
        let img = Arc::new(img);
        self.images.insert(key, img.clone());
        Ok(img)
    }

    fn texture(&mut self, path: &KeyPath, t: &TextureDesc) -> Result<Texture> {
        let present = [
            ("file", t.file.is_some()),
            ("filter", t.filter.is_some()),
            ("wrap", t.wrap.is_some()),
            ("colorspace", t.colorspace.is_some()),
            ("even", t.even.is_some()),
            ("odd", t.odd.is_some()),
            ("checks", t.checks.is_some()),
        ];
        let kind = match t.kind {
            TextureType::Image => {
                self.only_keys(
                    path,
                    "an image texture",
                    &present,
                    &["file", "filter", "wrap", "colorspace"],
                )?;
                let file = t
                    .file
                    .as_deref()
                    .ok_or_else(|| self.err(path, "missing key `file`"))?;
                let filter = match t.filter.as_deref() {
                    None | Some("bilinear") => Filter::Bilinear,
                    Some("nearest") => Filter::Nearest,
                    Some(s) => {
                        return Err(self.err(
                            &path.key("filter"),
                            format!("unknown filter \"{s}\" (use bilinear or nearest)"),
                        ))
                    }
                };
                let wrap = match t.wrap.as_deref() {
                    None | Some("repeat") => Wrap::Repeat,
                    Some("clamp") => Wrap::Clamp,
                    Some(s) => {
                        return Err(self.err(
                            &path.key("wrap"),
                            format!("unknown wrap \"{s}\" (use repeat or clamp)"),
                        ))
                    }
                };
                let srgb = match t.colorspace.as_deref() {
                    None | Some("srgb") => true,
                    Some("linear") => false,
                    Some(s) => {
                        return Err(self.err(
                            &path.key("colorspace"),
                            format!("unknown colorspace \"{s}\" (use srgb or linear)"),
                        ))
                    }
                };
                let image =
                    self.image(&path.key("file"), self.file.resolve(file), srgb, "texture")?;
                TextureKind::Image(ImageTexture {
                    image,
                    filter,
                    wrap,
                })
            }
            TextureType::Checker => {
                self.only_keys(
                    path,
                    "a checker texture",
                    &present,
                    &["even", "odd", "checks"],
                )?;
                TextureKind::Checker {
                    even: t.even.map_or(Rgb::ONE, rgb),
                    odd: t.odd.map_or(Rgb::ZERO, rgb),
                    checks: t.checks.map_or(8.0, |c| c.0 as f32),
                }
            }
        };
        Ok(Texture {
            kind,
            uv_scale: t.uv_scale.map_or(Vec2::ONE, v2),
            uv_offset: t.uv_offset.map_or(Vec2::ZERO, v2),
        })
    }

    fn material(&self, path: &KeyPath, m: &MaterialDesc) -> Result<Material> {
        let diffuse = m.diffuse.map_or(Rgb::splat(0.8), rgb);
        let shininess = match m.shininess {
            Some(Num(p)) if p < 0.0 => {
                return Err(self.err(
                    &path.key("shininess"),
                    format!("shininess must be at least 0, not {p}"),
                ))
            }
            p => p.map_or(16.0, |p| p.0 as f32),
        };
        let texture = match &m.texture {
            None => None,
            Some(name) => Some(
                self.file
                    .desc
                    .textures
                    .get(name)
                    .map(|(i, _)| i as u32)
                    .ok_or_else(|| {
                        let known: Vec<&str> = self.file.desc.textures.names().collect();
                        self.err(
                            &path.key("texture"),
                            format!("unknown texture \"{name}\"{}", list(&known)),
                        )
                    })?,
            ),
        };
        Ok(Material {
            ambient: m.ambient.map_or(diffuse, rgb),
            diffuse,
            specular: m.specular.map_or(Rgb::ZERO, rgb),
            shininess,
            texture,
        })
    }

    fn light(&self, path: &KeyPath, l: &LightDesc, default_n: u32) -> Result<Light> {
        let present = [
            ("center", l.center.is_some()),
            ("u", l.u.is_some()),
            ("v", l.v.is_some()),
            ("position", l.position.is_some()),
            ("samples", l.samples.is_some()),
            ("jitter", l.jitter.is_some()),
        ];
        let color = l.color.map_or(Rgb::ONE, rgb) * l.intensity.map_or(1.0, |i| i.0 as f32);
        Ok(match l.kind {
            LightType::Area => {
                self.only_keys(
                    path,
                    "an area light",
                    &present,
                    &["center", "u", "v", "samples", "jitter"],
                )?;
                let file_n = match l.samples {
                    Some(n) => self.light_n(&path.key("samples"), n)?,
                    None => default_n,
                };
                Light::Area(AreaLight {
                    center: v3(self.require(path, "center", l.center)?),
                    u: v3(self.require(path, "u", l.u)?),
                    v: v3(self.require(path, "v", l.v)?),
                    radiance: color,
                    n: file_n,
                    jitter: l.jitter.unwrap_or(false),
                })
            }
            LightType::Point => {
                self.only_keys(path, "a point light", &present, &["position"])?;
                Light::Point(PointLight {
                    position: v3(self.require(path, "position", l.position)?),
                    intensity: color,
                })
            }
        })
    }

    fn material_index(&self, path: &KeyPath, name: &str) -> Result<u32> {
        self.file
            .desc
            .materials
            .get(name)
            .map(|(i, _)| i as u32 + 1)
            .ok_or_else(|| {
                let known: Vec<&str> = self.file.desc.materials.names().collect();
                self.err(path, format!("unknown material \"{name}\"{}", list(&known)))
            })
    }

    fn object(&mut self, path: &KeyPath, o: &ObjectDesc) -> Result<()> {
        let present = [
            ("vertices", o.vertices.is_some()),
            ("uvs", o.uvs.is_some()),
            ("normals", o.normals.is_some()),
            ("corner", o.corner.is_some()),
            ("u", o.u.is_some()),
            ("v", o.v.is_some()),
            ("center", o.center.is_some()),
            ("size", o.size.is_some()),
            ("radius", o.radius.is_some()),
            ("file", o.file.is_some()),
        ];
        let kind = format!("a {}", o.kind.name());
        let allowed: &[&str] = match o.kind {
            ObjectType::Triangle => &["vertices", "uvs", "normals"],
            ObjectType::Quad => &["corner", "u", "v"],
            ObjectType::Cube => &["center", "size"],
            ObjectType::Sphere => &["center", "radius"],
            ObjectType::Mesh => &["file"],
        };
        self.only_keys(path, &kind, &present, allowed)?;

        let mut world = Transform::from_srt(
            o.scale.map_or(Vec3::ONE, rgb),
            o.rotate.map_or(Vec3::ZERO, v3),
            o.translate.map_or(Vec3::ZERO, v3),
        );
        if world.is_singular() {
            return Err(self.err(&path.key("scale"), "scale must not be zero"));
        }
        let mut materials = vec![match &o.material {
            Some(name) => self.material_index(&path.key("material"), name)?,
            None => DEFAULT_MATERIAL,
        }];

        let mesh = match o.kind {
            ObjectType::Triangle => {
                let vertices = self.require(path, "vertices", o.vertices)?.map(v3);
                let uvs = o.uvs.map_or([Vec2::ZERO, Vec2::X, Vec2::Y], |u| u.map(v2));
                Rc::new(geometry::triangle(
                    vertices,
                    uvs,
                    o.normals.map(|n| n.map(v3)),
                ))
            }
            ObjectType::Quad => Rc::new(geometry::quad(
                v3(self.require(path, "corner", o.corner)?),
                v3(self.require(path, "u", o.u)?),
                v3(self.require(path, "v", o.v)?),
            )),
            ObjectType::Cube | ObjectType::Sphere => {
                let center = v3(self.require(path, "center", o.center)?);
                world = Transform::from_srt(Vec3::ONE, Vec3::ZERO, center).then_after(world);
                if o.kind == ObjectType::Cube {
                    let size = rgb(self.require(path, "size", o.size)?);
                    if size.cmplt(Vec3::ZERO).any() {
                        return Err(self.err(&path.key("size"), "size must not be negative"));
                    }
                    Rc::new(geometry::cube(size))
                } else {
                    let radius = self.require(path, "radius", o.radius)?.0;
                    if radius < 0.0 {
                        return Err(self.err(&path.key("radius"), "radius must not be negative"));
                    }
                    Rc::new(geometry::sphere(radius as f32))
                }
            }
            ObjectType::Mesh => {
                let file = o
                    .file
                    .as_deref()
                    .ok_or_else(|| self.err(path, "missing key `file`"))?;
                let (mesh, mtl_materials) =
                    self.obj(&path.key("file"), file, o.material.is_none())?;
                if let Some(m) = mtl_materials {
                    materials = m;
                }
                mesh
            }
        };
        self.world
            .add_mesh(&mesh, &world, &materials)
            .map_err(|e| self.err(path, e.to_string()))?;
        Ok(())
    }
}

impl Builder<'_> {
    /// The mesh of the OBJ `file` (read once per scene) and, when `with_mtl`, the scene
    /// materials of its MTL materials followed by the default (made once per file).
    fn obj(
        &mut self,
        path: &KeyPath,
        file: &str,
        with_mtl: bool,
    ) -> Result<(Rc<Mesh>, Option<Vec<u32>>)> {
        let obj_path = self.file.resolve(file);
        let key = std::fs::canonicalize(&obj_path).unwrap_or_else(|_| obj_path.clone());
        let loaded = match self.meshes.get(&key) {
            Some(loaded) => loaded,
            None => {
                let model = load_obj(&obj_path).map_err(|e| {
                    self.err(
                        path,
                        format!("cannot load mesh \"{}\": {e}", obj_path.display()),
                    )
                })?;
                let loaded = LoadedObj {
                    mesh: Rc::new(model.mesh),
                    mtl: model.materials,
                    scene_materials: None,
                };
                self.meshes.entry(key.clone()).or_insert(loaded)
            }
        };
        let mesh = loaded.mesh.clone();
        if !with_mtl {
            return Ok((mesh, None));
        }
        if let Some(ids) = &loaded.scene_materials {
            return Ok((mesh, Some(ids.clone())));
        }
        let mtl = loaded.mtl.clone();
        let mut ids = Vec::with_capacity(mtl.len() + 1);
        for m in &mtl {
            let texture = match &m.diffuse_texture {
                None => None,
                Some(t) => {
                    let what = format!("texture (map_Kd of material \"{}\")", m.name);
                    let image = self.image(path, t.clone(), true, &what)?;
                    Some(self.world.add_texture(Texture {
                        kind: TextureKind::Image(ImageTexture {
                            image,
                            filter: Filter::Bilinear,
                            wrap: Wrap::Repeat,
                        }),
                        uv_scale: Vec2::ONE,
                        uv_offset: Vec2::ZERO,
                    }))
                }
            };
            let diffuse = m.diffuse.map_or(Rgb::splat(0.8), Vec3::from);
            let id = self
                .world
                .add_material(Material {
                    ambient: m.ambient.map_or(diffuse, Vec3::from),
                    diffuse,
                    specular: m.specular.map_or(Rgb::ZERO, Vec3::from),
                    shininess: m.shininess.map_or(16.0, |s| s.max(0.0)),
                    texture,
                })
                .map_err(|e| self.err(path, e.to_string()))?;
            ids.push(id);
        }
        // Faces without an MTL material use slot `mtl.len()`: the default material.
        ids.push(DEFAULT_MATERIAL);
        if let Some(loaded) = self.meshes.get_mut(&key) {
            loaded.scene_materials = Some(ids.clone());
        }
        Ok((mesh, Some(ids)))
    }
}

fn list(known: &[&str]) -> String {
    if known.is_empty() {
        " (none are defined)".to_owned()
    } else {
        format!(" (known: {})", known.join(", "))
    }
}
