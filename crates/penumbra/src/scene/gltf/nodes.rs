//! The scene graph: the node hierarchy checked to be a forest first (every node a child of at
//! most one node, no cycle), over all the file's nodes whether or not it has scenes, so that a
//! cycle is the same error with or without `scenes`; then the chosen scene's nodes walked from
//! its roots (iteratively, so a deep chain cannot overflow the stack; a node reached twice is
//! an error), each node's world matrix the product of its ancestors' and its own.

use std::collections::HashMap;

use glam::{Mat4, Vec3};
use gltf::khr_lights_punctual::Kind;

use super::{GltfCamera, GltfError, GltfLight, GltfLightKind, GltfModel, MeshUse, Reader, Result};

impl Reader<'_> {
    /// Walks the chosen scene into `model`: mesh uses (each mesh read once), cameras and
    /// lights, and the materials and images the used meshes need.
    pub(super) fn scene(&mut self, model: &mut GltfModel) -> Result<()> {
        let doc = self.doc;
        check_forest(doc)?;
        let roots: Vec<usize> = match doc.default_scene().or_else(|| doc.scenes().next()) {
            Some(scene) => scene.nodes().map(|n| n.index()).collect(),
            None => {
                self.ignored
                    .note("the file has no scene: every root node is rendered");
                root_nodes(doc)
            }
        };
        let extra_scenes = doc.scenes().len().saturating_sub(1);
        self.ignored.add(
            "{n} scene(s) besides the default one are ignored",
            extra_scenes,
        );
        self.ignored.add(
            "{n} animation(s) are ignored: the nodes' rest pose is rendered",
            doc.animations().len(),
        );
        self.ignored.add(
            "{n} skin(s) are ignored: skinned meshes are rendered in their bind pose",
            doc.skins().len(),
        );
        let mut seen = vec![false; doc.nodes().len()];
        let mut mesh_of: HashMap<usize, usize> = HashMap::new();
        let mut stack: Vec<(usize, Mat4)> =
            roots.iter().rev().map(|&i| (i, Mat4::IDENTITY)).collect();
        while let Some((i, parent)) = stack.pop() {
            let at = format!("nodes[{i}]");
            let node = doc
                .nodes()
                .nth(i)
                .ok_or_else(|| GltfError::new(&at, "no such node"))?;
            if std::mem::replace(&mut seen[i], true) {
                return Err(GltfError::new(
                    at,
                    "the node is reached twice from the scene's roots (the node hierarchy must \
                     be a tree)",
                ));
            }
            let local = Mat4::from_cols_array_2d(&node.transform().matrix());
            let matrix = parent * local;
            if !matrix.is_finite() {
                return Err(GltfError::new(at, "the node's transform is not finite"));
            }
            if let Some(mesh) = node.mesh() {
                if matrix.determinant() == 0.0 {
                    self.ignored
                        .note("{n} node(s) with a zero scale are not placed (invisible)");
                } else {
                    let k = match mesh_of.get(&mesh.index()) {
                        Some(&k) => k,
                        None => {
                            model.meshes.push(self.mesh(mesh.index())?);
                            mesh_of.insert(mesh.index(), model.meshes.len() - 1);
                            model.meshes.len() - 1
                        }
                    };
                    if !placed_bounds_finite(&model.meshes[k].mesh, matrix) {
                        return Err(GltfError::new(
                            at,
                            "the node's transform takes its mesh beyond the range of 32-bit \
                             floats",
                        ));
                    }
                    model.uses.push(MeshUse { mesh: k, matrix });
                }
            }
            if let Some(camera) = node.camera() {
                self.camera(model, &node, camera, matrix);
            }
            if let Some(light) = node.light() {
                self.light(model, light, matrix);
            }
            let first = stack.len();
            stack.extend(node.children().map(|c| (c.index(), matrix)));
            stack[first..].reverse();
        }
        self.materials(model)
    }

    fn camera(
        &mut self,
        model: &mut GltfModel,
        node: &gltf::Node,
        camera: gltf::Camera,
        matrix: Mat4,
    ) {
        let (fov, ymag) = match camera.projection() {
            gltf::camera::Projection::Perspective(p) => (p.yfov().to_degrees(), None),
            // The film's aspect gives the width, as it does a perspective camera's.
            gltf::camera::Projection::Orthographic(o) => {
                let ymag = o.ymag().abs();
                if !(ymag > 0.0 && ymag.is_finite()) {
                    self.ignored
                        .note("{n} orthographic camera(s) with a ymag of 0 are ignored");
                    return;
                }
                (60.0, Some(ymag))
            }
        };
        if !(fov > 0.0 && fov < 180.0) {
            self.ignored
                .note("{n} camera(s) with a yfov outside (0, 180) degrees are ignored");
            return;
        }
        let base = camera
            .name()
            .or(node.name())
            .filter(|n| !n.is_empty())
            .unwrap_or("camera");
        let name = unique(base, |n| model.cameras.iter().any(|c| c.name == n));
        model.cameras.push(GltfCamera {
            name,
            matrix,
            fov_y_deg: fov,
            ymag,
        });
    }

    fn light(
        &mut self,
        model: &mut GltfModel,
        light: gltf::khr_lights_punctual::Light,
        matrix: Mat4,
    ) {
        let kind = match light.kind() {
            Kind::Point => GltfLightKind::Point,
            Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => GltfLightKind::Spot {
                inner: inner_cone_angle,
                outer: outer_cone_angle,
            },
            Kind::Directional => GltfLightKind::Directional,
        };
        if light.range().is_some() && kind != GltfLightKind::Directional {
            self.ignored
                .note("{n} light range(s) are ignored (light falls off as 1/d²)");
        }
        model.lights.push(GltfLight {
            position: matrix.transform_point3(Vec3::ZERO),
            direction: matrix.transform_vector3(Vec3::NEG_Z).normalize_or_zero(),
            color: Vec3::from(light.color()),
            intensity: light.intensity(),
            kind,
        });
    }
}

/// `base`, or `base-2`, `base-3`, … the first that `taken` does not refuse.
pub(crate) fn unique(base: &str, taken: impl Fn(&str) -> bool) -> String {
    if !taken(base) {
        return base.to_owned();
    }
    (2..)
        .map(|k| format!("{base}-{k}"))
        .find(|n| !taken(n))
        .unwrap_or_default()
}

/// True when the corners of `mesh`'s bounding box stay finite under `matrix`.
fn placed_bounds_finite(mesh: &crate::geometry::Mesh, matrix: Mat4) -> bool {
    let b = mesh
        .positions
        .iter()
        .fold(crate::math::Aabb::EMPTY, |b, &p| b.grow(p));
    if b.is_empty() {
        return true;
    }
    (0..8).all(|k| {
        let pick = |bit: usize, lo: f32, hi: f32| if k & bit == 0 { lo } else { hi };
        let corner = Vec3::new(
            pick(1, b.min.x, b.max.x),
            pick(2, b.min.y, b.max.y),
            pick(4, b.min.z, b.max.z),
        );
        matrix.transform_point3(corner).is_finite()
    })
}

/// Nodes no other node names as a child, in index order.
fn root_nodes(doc: &gltf::Document) -> Vec<usize> {
    let mut child = vec![false; doc.nodes().len()];
    for node in doc.nodes() {
        for c in node.children() {
            child[c.index()] = true;
        }
    }
    (0..child.len()).filter(|&i| !child[i]).collect()
}

/// Refuses a node hierarchy that is not a forest (glTF 2.0 §3.5.3: "the node hierarchy must be
/// a set of disjoint strict trees"): a node that is the child of two nodes, or a cycle, named
/// by its nodes. Every node of the file is checked, used by a scene or not.
fn check_forest(doc: &gltf::Document) -> Result<()> {
    let n = doc.nodes().len();
    let mut parent: Vec<Option<usize>> = vec![None; n];
    for node in doc.nodes() {
        for c in node.children() {
            let (i, c) = (node.index(), c.index());
            if let Some(p) = parent[c].replace(i) {
                return Err(GltfError::new(
                    format!("nodes[{c}]"),
                    format!(
                        "the node is a child of both nodes[{p}] and nodes[{i}] (the node \
                         hierarchy must be a tree)"
                    ),
                ));
            }
        }
    }
    // Each node has one parent at most: a cycle is a walk up the parents that comes back.
    // `walk[i]` is the node whose walk first reached node i, so every node is passed once.
    let mut walk: Vec<Option<usize>> = vec![None; n];
    for start in 0..n {
        let mut i = start;
        while walk[i].is_none() {
            walk[i] = Some(start);
            match parent[i] {
                Some(p) => i = p,
                None => break,
            }
        }
        if walk[i] == Some(start) && parent[i].is_some() && walk_returns(&parent, i) {
            return Err(cycle_error(&parent, i));
        }
    }
    Ok(())
}

/// True when the walk up the parents from `i` comes back to `i`.
fn walk_returns(parent: &[Option<usize>], i: usize) -> bool {
    let mut at = parent[i];
    for _ in 0..parent.len() {
        match at {
            Some(p) if p == i => return true,
            Some(p) => at = parent[p],
            None => return false,
        }
    }
    false
}

/// The error for the cycle through node `i`: at its lowest node, listing the cycle from there
/// down its children (the first eight nodes of a long one).
fn cycle_error(parent: &[Option<usize>], i: usize) -> GltfError {
    let mut up = vec![i];
    let mut at = parent[i];
    while let Some(p) = at.filter(|&p| p != i) {
        up.push(p);
        at = parent[p];
    }
    // `up` runs child → parent; the message runs parent → child from the lowest index.
    up.reverse();
    let low = (0..up.len()).min_by_key(|&k| up[k]).unwrap_or(0);
    up.rotate_left(low);
    let mut shown: Vec<String> = up.iter().take(8).map(|k| format!("nodes[{k}]")).collect();
    shown.push(if up.len() > 8 {
        "…".into()
    } else {
        format!("nodes[{}]", up[0])
    });
    GltfError::new(
        format!("nodes[{}]", up[0]),
        format!(
            "the node hierarchy has a cycle ({}): it must be a tree",
            shown.join(" → ")
        ),
    )
}
