//! Wavefront OBJ meshes through tobj: polygons fan-triangulated, `vt`/`vn` when present,
//! `mtllib`/`usemtl` materials with `map_Kd` resolved against the MTL file's folder.

use std::cell::RefCell;
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use crate::geometry::Mesh;

/// A material from an MTL file.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ObjMaterial {
    pub name: String,
    pub diffuse: Option<[f32; 3]>,
    pub ambient: Option<[f32; 3]>,
    pub specular: Option<[f32; 3]>,
    pub shininess: Option<f32>,
    /// `map_Kd`, resolved against the MTL file's folder.
    pub diffuse_texture: Option<PathBuf>,
}

/// An OBJ file as one mesh. Triangle material slot `k < materials.len()` is `materials[k]`;
/// slot `materials.len()` marks faces without `usemtl`.
#[derive(Clone, Debug)]
pub(crate) struct ObjModel {
    pub mesh: Mesh,
    pub materials: Vec<ObjMaterial>,
}

/// The most triangles a mesh may have: indices are 32-bit.
const MAX_TRIANGLES: usize = (u32::MAX / 4) as usize;

/// Loads `path`. Errors are messages that do not repeat the path.
pub(crate) fn load_obj(path: &Path) -> Result<ObjModel, String> {
    let file = File::open(path).map_err(|e| e.to_string())?;
    let mut reader = BufReader::new(file);
    let obj_dir = path.parent().unwrap_or(Path::new("")).to_owned();
    let mtl_error: RefCell<Option<String>> = RefCell::new(None);
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, materials) = tobj::load_obj_buf(&mut reader, &options, |mtl: &Path| {
        let mtl_path = obj_dir.join(mtl);
        let result = tobj::load_mtl(&mtl_path);
        match result {
            Ok((mut mats, map)) => {
                let mtl_dir = mtl_path.parent().unwrap_or(Path::new("")).to_owned();
                for m in &mut mats {
                    if let Some(t) = &m.diffuse_texture {
                        m.diffuse_texture = Some(mtl_dir.join(t).to_string_lossy().into_owned());
                    }
                }
                Ok((mats, map))
            }
            Err(e) => {
                *mtl_error.borrow_mut() = Some(format!(
                    "cannot load material library \"{}\": {e}",
                    mtl_path.display()
                ));
                Err(e)
            }
        }
    })
    .map_err(|e| e.to_string())?;
    if let Some(e) = mtl_error.into_inner() {
        return Err(e);
    }
    let materials = materials.map_err(|e| e.to_string())?;
    let no_material = materials.len() as u32;

    let mut mesh = Mesh::default();
    let mut any_normals = false;
    for model in &models {
        let m = &model.mesh;
        let count = m.positions.len() / 3;
        any_normals |= m.normals.len() == m.positions.len() && !m.normals.is_empty();
        if mesh.positions.len() + count > MAX_TRIANGLES
            || mesh.indices.len() + m.indices.len() / 3 > MAX_TRIANGLES
        {
            return Err("the mesh is too large (more than a billion vertices or triangles)".into());
        }
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        let normals: Vec<Vec3> = if m.normals.len() == m.positions.len() {
            m.normals
                .chunks_exact(3)
                .map(|n| Vec3::new(n[0], n[1], n[2]))
                .collect()
        } else {
            vec![Vec3::ZERO; count]
        };
        mesh.normals.extend(normals);
        if m.texcoords.len() / 2 == count {
            mesh.uvs
                .extend(m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], t[1])));
        } else {
            mesh.uvs.extend(std::iter::repeat_n(Vec2::ZERO, count));
        }
        let slot = model.mesh.material_id.map_or(no_material, |id| id as u32);
        for tri in m.indices.chunks_exact(3) {
            if tri.iter().any(|&i| i as usize >= count) {
                return Err("face vertex index out of bounds".into());
            }
            mesh.indices
                .push([base + tri[0], base + tri[1], base + tri[2]]);
            mesh.material_slots.push(slot);
        }
    }
    if !any_normals {
        mesh.normals.clear();
    } else if mesh.normals.contains(&Vec3::ZERO) {
        // Some groups lack `vn`: shade everything flat rather than mix garbage normals in.
        mesh.normals.clear();
    }
    let materials = materials
        .into_iter()
        .map(|m| ObjMaterial {
            name: m.name,
            diffuse: m.diffuse,
            ambient: m.ambient,
            specular: m.specular,
            shininess: m.shininess,
            diffuse_texture: m.diffuse_texture.map(PathBuf::from),
        })
        .collect();
    Ok(ObjModel { mesh, materials })
}
