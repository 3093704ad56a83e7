//! Moving an object of a scene file: [`SceneFile::with_transform`] gives an object (or one
//! placement of an `instances` object) a `matrix` in place of its own transform, as an
//! override of its entry. So a moved scene is a scene file like any other: its build is a
//! fresh load's, byte for byte, and its pack, digest and records carry the move.

use std::ops::Range;

use toml::{Table, Value};

use super::desc::{ShapeDesc, TransformsDesc};
use super::error::{ErrorKind, KeyPath, SceneError};
use super::{build, Override, SceneFile};
use crate::world::World;

impl SceneFile {
    /// This file with object `object` (its position in `objects`) placed by `matrix` (its
    /// object-to-world matrix, by rows; the last row must be 0, 0, 0, 1) instead of its own
    /// transform. For an `instances` object, `placement` picks which of its inline
    /// placements `matrix` replaces (that copy then goes under the object's own transform,
    /// as every placement does; its material stays); `None` moves the object, and with it
    /// every copy.
    ///
    /// The move replaces the value as a `--set` override of the entry would (the entry with
    /// `matrix` and without `scale`, `rotate` and `translate`), dropping any earlier override
    /// of that entry or of a value under it, so a move made each frame does not pile up. A
    /// matrix that cannot be inverted is refused by the build, as in a file.
    ///
    /// ```
    /// use penumbra::{SceneFile, SceneFormat};
    /// let text = "[film]\nwidth = 8\nheight = 8\n[camera]\nposition = [0, 0, 5]\n\
    ///     look_at = [0, 0, 0]\nfov = 40\n[[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\n\
    ///     radius = 1\ntranslate = [0, 1, 0]\n";
    /// let file = SceneFile::from_str(text, SceneFormat::Toml, "s.toml", ".")?;
    /// let up = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 2.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
    /// let moved = file.with_transform(0, None, up)?;
    /// let o = &moved.desc.objects[0];
    /// assert_eq!((o.translate, o.matrix.map(|m| m[1][3].0)), (None, Some(2.0)));
    /// assert_ne!(moved.digest(&[]), file.digest(&[]));
    /// # Ok::<(), penumbra::SceneError>(())
    /// ```
    pub fn with_transform(
        &self,
        object: usize,
        placement: Option<usize>,
        matrix: [[f64; 4]; 4],
    ) -> Result<SceneFile, SceneError> {
        let objects = KeyPath::root("objects");
        let bad = |path: &KeyPath, message: String| self.error(ErrorKind::BadValue, path, message);
        let Some(o) = self.desc.objects.get(object) else {
            let n = self.desc.objects.len();
            return Err(bad(
                &objects,
                format!("no object {object}: the scene has {n}"),
            ));
        };
        let at = objects.index(object);
        let path = match (placement, &o.shape) {
            (None, _) => at.clone(),
            (Some(i), ShapeDesc::Instances(d)) => match &d.transforms {
                TransformsDesc::List(list) if i < list.len() => at.key("transforms").index(i),
                TransformsDesc::List(list) => {
                    let message = format!("no placement {i}: the object has {}", list.len());
                    return Err(bad(&at.key("transforms"), message));
                }
                TransformsDesc::Npy(_) => {
                    let message = "the placements are a .npy file: only an inline list's \
                                   placements move one by one (move the object, or list them)";
                    return Err(bad(&at.key("transforms"), message.to_owned()));
                }
            },
            (Some(_), _) => {
                let message = format!(
                    "a {} has no placements to pick from (only `instances` objects do)",
                    o.kind()
                );
                return Err(bad(&at, message));
            }
        };
        if let Some(v) = matrix.iter().flatten().find(|v| !v.is_finite()) {
            return Err(bad(&path.key("matrix"), format!("{v} in the matrix")));
        }
        let tree = self.source.tree_now()?;
        let mut entry = entry_at(&tree, &path).cloned().unwrap_or_default();
        if placement.is_some() {
            entry.retain(|key, _| key == "material");
        }
        for key in ["scale", "rotate", "translate"] {
            entry.remove(key);
        }
        let rows = matrix.map(|row| Value::Array(row.map(Value::Float).to_vec()));
        entry.insert("matrix".to_owned(), Value::Array(rows.to_vec()));
        let text = format!("{path}={}", one_line(&Value::Table(entry)));
        let moved = Override::parse(&text).map_err(|e| bad(&path, e.to_string()))?;
        // Earlier overrides at or under the entry are part of it now.
        let kept = self
            .source
            .set()
            .iter()
            .filter(|(p, _)| !p.0.starts_with(&path.0));
        let mut overrides = (kept.map(|(_, text)| Override::parse(text)))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| bad(&path, e.to_string()))?;
        overrides.push(moved);
        let file = SceneFile::from_source(self.source.unset(), self.base_dir.clone(), &overrides)?;
        Ok(file.with_files(self.files.clone()))
    }
}

impl SceneFile {
    /// The position in `objects` of the object whose `name` is `name`; an error at `objects`
    /// listing the names the scene has when none is.
    pub fn object_index(&self, name: &str) -> Result<usize, SceneError> {
        let objects = &self.desc.objects;
        if let Some(i) = objects.iter().position(|o| o.name.as_deref() == Some(name)) {
            return Ok(i);
        }
        let names: Vec<String> = (objects.iter())
            .filter_map(|o| Some(format!("`{}`", o.name.as_ref()?)))
            .collect();
        let known = match names.is_empty() {
            true => "no object has a name".to_owned(),
            false => format!("the named objects: {}", names.join(", ")),
        };
        let message = format!("no object named `{name}` ({known})");
        Err(self.error(ErrorKind::BadValue, &KeyPath::root("objects"), message))
    }
}

impl SceneFile {
    /// The world this file builds, made from `world` by moving instances, when that is all
    /// that differs: `world` was built from a file that differs from this one only in the
    /// transform of object `object` (or of one of its copies: see
    /// [`SceneFile::with_transform`]), whose copies have the object ids `ids`. When every
    /// copy is an instance, each takes the transform this file's build would compose for it
    /// ([`World::set_transforms`]: nothing is built but the top level) and the world renders
    /// the bytes this file's build renders. `None` when the copies are not instances
    /// (copied into the world's own triangles, or made of a glTF file's nodes): then only a
    /// build makes the world. Errors are the build's, at the same keys.
    pub fn moved_world(
        &self,
        object: usize,
        world: &World,
        ids: Range<u32>,
    ) -> Result<Option<World>, SceneError> {
        let placed = world.placed().iter().enumerate();
        let instances: Vec<usize> = (placed.filter(|(_, p)| ids.contains(&p.object)))
            .map(|(i, _)| i)
            .collect();
        if instances.len() != ids.len() {
            return Ok(None);
        }
        // Each copy checked as the build checks it, in order, so that the first refused is
        // the build's, at its key.
        let check = |i: usize, t: &_| match instances.get(i) {
            Some(&instance) => world.check_move(instance, t),
            None => Ok(()),
        };
        let Some(transforms) = build::copy_transforms(self, object, check)? else {
            return Ok(None);
        };
        if transforms.len() != instances.len() {
            return Ok(None);
        }
        let mut moved = world.clone();
        let moves: Vec<_> = instances.into_iter().zip(transforms).collect();
        moved
            .set_transforms(&moves)
            .expect("every move was checked");
        if let Some(problem) = moved.scale_problem() {
            return Err(build::scale_error(self, problem));
        }
        Ok(Some(moved))
    }
}

/// The table at `path` (keys and indices) in `tree`.
fn entry_at<'t>(tree: &'t Table, path: &KeyPath) -> Option<&'t Table> {
    use super::error::Segment;
    let mut value: Option<&Value> = None;
    for step in &path.0 {
        value = match (value, step) {
            (None, Segment::Key(k)) => tree.get(k),
            (Some(Value::Table(t)), Segment::Key(k)) => t.get(k),
            (Some(Value::Array(a)), Segment::Index(i)) => a.get(*i),
            _ => None,
        };
        value?;
    }
    value?.as_table()
}

/// `value` as TOML on one line, as an override's value is read (see `Override::parse`):
/// inline tables and arrays, and strings with their line breaks escaped (a multi-line string
/// would not be one line).
fn one_line(value: &Value) -> String {
    let string = |s: &str| serde_json::to_string(s).expect("a string serializes");
    match value {
        Value::String(s) => string(s),
        Value::Array(items) => {
            let items: Vec<String> = items.iter().map(one_line).collect();
            format!("[{}]", items.join(", "))
        }
        Value::Table(table) => {
            let bare = |k: &str| {
                !k.is_empty()
                    && k.bytes()
                        .all(|b| b.is_ascii_alphanumeric() || b"_-".contains(&b))
            };
            let entries: Vec<String> = (table.iter())
                .map(|(k, v)| match bare(k) {
                    true => format!("{k} = {}", one_line(v)),
                    false => format!("{} = {}", string(k), one_line(v)),
                })
                .collect();
            format!("{{ {} }}", entries.join(", "))
        }
        other => other.to_string(),
    }
}
