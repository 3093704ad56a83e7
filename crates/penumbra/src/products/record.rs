//! The record beside each image (`out.png` → `out.meta.json`), as `penumbra render --meta`
//! and `--resume` and Python's batches write it, and the rule that says an image is done.
//!
//! A record holds `settings` ([`RecordSettings`]), `image`, `files` (the image, then its AOV
//! files), `digests` (each file's size and FNV-1a as written), `width`, `height`, `K`, the
//! camera's poses (see [`CameraPose`]), its lens (`model` and, as the model has them,
//! `distortion`, `max_angle`, `orthographic_height`, `aperture_radius`, `focus_distance`, as
//! `--poses` writes them), `objects` (the object ids of each `[[objects]]` entry) and, from
//! Python, `view` (the view's name).
//!
//! An image is done ([`finished`]) when its record's settings are exactly those it would be
//! rendered with now and every file the record lists is a regular file of the size and
//! digest the record keeps: an image cut short or changed after its record was written, a
//! record of other settings or of an older layout is not done. A record is removed before its
//! image is replaced and renamed into place after it, so that no record describes an image
//! it was not written with.

use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::frames::LensFields;
use super::{ProductError, RecordSettings};
use crate::fnv::FileDigest;
use crate::pose::{CameraPose, Mat3Rows, Mat4Rows};
use crate::scene::SceneFile;
use crate::staged::StagedFile;

/// The largest record read back: far more than any record penumbra writes.
pub const MAX_RECORD_BYTES: u64 = 1 << 20;

/// An image's record (see the module's docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// What the image depends on.
    pub settings: RecordSettings,
    /// The image's path, as given.
    pub image: String,
    /// The files written: the image, then its AOV files.
    pub files: Vec<String>,
    /// Each file's size and digest, as written; `None` before they are written.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub digests: Option<Vec<FileEntry>>,
    /// The image's width in pixels (its region's, when it has one).
    pub width: u32,
    /// The image's height in pixels.
    pub height: u32,
    /// K (OpenCV: pixel centres at integer coordinates).
    #[serde(rename = "K")]
    pub k: Option<Mat3Rows>,
    /// Camera to world, OpenCV axes.
    pub camera_to_world: Option<Mat4Rows>,
    /// Camera to world, OpenGL axes.
    pub camera_to_world_opengl: Option<Mat4Rows>,
    /// World to camera, OpenCV axes.
    pub world_to_camera: Option<Mat4Rows>,
    /// The camera's lens: `model` and its coefficients, as `--poses` writes them.
    #[serde(flatten, default, skip_serializing_if = "Option::is_none")]
    pub lens: Option<LensFields>,
    /// Each `[[objects]]` entry and its object ids.
    pub objects: Vec<ObjectEntry>,
    /// The view's name (Python's batches).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub view: Option<String>,
}

/// A file's size and digest, as a record keeps them.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileEntry {
    /// Its size in bytes.
    pub bytes: u64,
    /// Its 64-bit FNV-1a, 16 hex digits.
    pub fnv1a64: String,
}

impl From<FileDigest> for FileEntry {
    fn from(d: FileDigest) -> FileEntry {
        FileEntry {
            bytes: d.bytes,
            fnv1a64: d.hex(),
        }
    }
}

/// An `[[objects]]` entry: `key` (`objects[3]`), its `name` when it has one, `type` (and
/// file) and the object ids it added as `[first, end)`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ObjectEntry {
    /// `objects[i]`.
    pub key: String,
    /// The object's `name`, when it has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Its type, and the file of a mesh or instances (`mesh models/bunny.obj`).
    #[serde(rename = "type")]
    pub kind: String,
    /// `[first, end)`.
    pub ids: [u32; 2],
}

/// The entries of `file`'s `[[objects]]` and the object ids its build gave each
/// ([`Scene::objects`](crate::Scene::objects)).
pub fn objects(file: &SceneFile, ids: &[Range<u32>]) -> Vec<ObjectEntry> {
    file.desc
        .objects
        .iter()
        .zip(ids)
        .enumerate()
        .map(|(i, (o, ids))| ObjectEntry {
            key: format!("objects[{i}]"),
            name: o.name.clone(),
            kind: o.kind(),
            ids: [ids.start, ids.end],
        })
        .collect()
}

impl Record {
    /// The record of an image at `image`, `width × height`, seen by `pose`, listing `files`
    /// (none yet: [`stage`] lists the files staged); without digests.
    pub fn new(
        settings: RecordSettings,
        image: &Path,
        (width, height): (u32, u32),
        pose: Option<CameraPose>,
        objects: Vec<ObjectEntry>,
    ) -> Record {
        Record {
            settings,
            image: image.display().to_string(),
            files: vec![image.display().to_string()],
            digests: None,
            width,
            height,
            k: pose.map(|p| p.k),
            camera_to_world: pose.map(|p| p.camera_to_world),
            camera_to_world_opengl: pose.map(|p| p.camera_to_world_opengl),
            world_to_camera: pose.map(|p| p.world_to_camera),
            lens: pose.as_ref().map(LensFields::of),
            objects,
            view: None,
        }
    }
}

/// Where the record of the image at `image` goes: its extension replaced by `.meta.json`.
pub fn path_of(image: &Path) -> PathBuf {
    image.with_extension("meta.json")
}

/// Stages `record` beside its image, listing `files` (staged, not yet in place: the image,
/// then its AOV files) with their sizes and digests as written.
pub fn stage(mut record: Record, files: &[&StagedFile]) -> Result<StagedFile, ProductError> {
    let image = PathBuf::from(&record.image);
    record.files = files
        .iter()
        .map(|f| f.path().display().to_string())
        .collect();
    let digests = files.iter().map(|f| f.digest().map(FileEntry::from));
    record.digests = Some(digests.collect::<Result<_, _>>()?);
    let text = serde_json::to_string(&record).map_err(|e| ProductError::io(&image, e))? + "\n";
    Ok(StagedFile::write_bytes(&path_of(&image), text.as_bytes())?)
}

/// Renames an image's files into place together: `image` and the files `beside` it (its AOV
/// files), staged, with the `record` that lists them (the image, then `beside`, with their
/// sizes and digests), when given. The old record is removed first, whether or not a new one
/// is written, and the new one is renamed last: no record ever describes an image it was not
/// written with. On an error the files not yet renamed are removed.
pub fn commit_with_record(
    image: StagedFile,
    beside: Vec<StagedFile>,
    record: Option<Record>,
) -> Result<(), ProductError> {
    let staged = match record {
        Some(r) => Some(stage(
            r,
            &std::iter::once(&image).chain(&beside).collect::<Vec<_>>(),
        )?),
        None => None,
    };
    remove(image.path())?;
    let files = beside.into_iter().chain([image]).chain(staged);
    Ok(crate::commit_all(files.collect())?)
}

/// Writes `record` beside its image as it is (digests and all), whole or not at all.
pub fn write(record: &Record) -> Result<PathBuf, ProductError> {
    let path = path_of(Path::new(&record.image));
    let text = serde_json::to_string(record).map_err(|e| ProductError::io(&path, e))? + "\n";
    StagedFile::write_bytes(&path, text.as_bytes())?.commit()?;
    Ok(path)
}

/// Removes the record of `image`, if any: before the image is replaced.
pub fn remove(image: &Path) -> Result<(), ProductError> {
    let path = path_of(image);
    match std::fs::remove_file(&path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(ProductError::io(
            &path,
            format_args!("cannot remove the old record: {e}"),
        )),
        _ => Ok(()),
    }
}

/// The record at `path` as JSON, when it is a regular file of at most [`MAX_RECORD_BYTES`]
/// holding JSON: a named pipe, a device or a folder there is never opened (opening a pipe
/// would wait for a writer forever).
pub fn read(path: &Path) -> std::io::Result<serde_json::Value> {
    use std::io::{Error, ErrorKind};
    let bytes = crate::files::read_bounded(path, MAX_RECORD_BYTES)
        .map_err(|e| Error::new(ErrorKind::InvalidInput, e))?;
    serde_json::from_slice(&bytes).map_err(|e| Error::new(ErrorKind::InvalidData, e))
}

/// True when every file `record` lists is a regular file of the size and digest its
/// `digests` keep (false without digests).
pub fn intact(record: &serde_json::Value) -> bool {
    let (Some(files), Some(digests)) = (record["files"].as_array(), record["digests"].as_array())
    else {
        return false;
    };
    !files.is_empty()
        && files.len() == digests.len()
        && files.iter().zip(digests).all(|(f, d)| {
            let kept = serde_json::from_value::<FileEntry>(d.clone()).ok();
            f.as_str().is_some_and(|f| {
                FileDigest::of_file(Path::new(f))
                    .is_ok_and(|got| Some(FileEntry::from(got)) == kept)
            })
        })
}

/// The files of the image at `image` (the image, then its AOV files), when it is done: its
/// record lists it first, was made with exactly `settings`, and every file it lists is
/// [`intact`]. A missing or unreadable record, one of other settings or of an older layout
/// is not done.
pub fn finished(image: &Path, settings: &RecordSettings) -> Option<Vec<PathBuf>> {
    let record = read(&path_of(image)).ok()?;
    let kept: RecordSettings = serde_json::from_value(record.get("settings")?.clone()).ok()?;
    let files = record["files"].as_array()?;
    let image_listed = files.first().and_then(|f| f.as_str()) == Some(&image.display().to_string());
    // Read last: every byte of every file.
    (kept == *settings && image_listed && intact(&record)).then(|| {
        files
            .iter()
            .filter_map(|f| f.as_str())
            .map(PathBuf::from)
            .collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::products::{CameraRecord, RenderRecord};
    use crate::RenderSettings;

    fn settings() -> RecordSettings {
        RecordSettings {
            penumbra: "0".into(),
            scene_digest: "0123456789abcdef".into(),
            camera: Some("front".into()),
            frame: None,
            render: RenderRecord::of(&RenderSettings::default()),
            region: None,
            aovs: vec!["depth".into()],
            gamma: Some(1.8),
            format: "pfm".into(),
        }
    }

    #[test]
    fn a_written_image_is_done_until_its_settings_or_bytes_change() {
        let dir = std::env::temp_dir().join(format!("penumbra-record-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let image = dir.join("a.pfm");
        let depth = dir.join("a.depth.pfm");
        assert_eq!(finished(&image, &settings()), None);
        let stage_both = || {
            let image = StagedFile::write_bytes(&image, b"image").unwrap();
            (
                image,
                vec![StagedFile::write_bytes(&depth, b"depth").unwrap()],
            )
        };
        let record = Record::new(settings(), &image, (2, 1), None, Vec::new());
        let (staged, beside) = stage_both();
        commit_with_record(staged, beside, Some(record)).unwrap();
        assert_eq!(
            finished(&image, &settings()),
            Some(vec![image.clone(), depth.clone()])
        );
        let text = std::fs::read_to_string(path_of(&image)).unwrap();
        assert!(
            text.contains(r#""digests":[{"bytes":5,"fnv1a64":"#),
            "{text}"
        );
        // Other settings are not done.
        let mut other = settings();
        other.render.camera = CameraRecord::Named("other".into());
        assert_eq!(finished(&image, &other), None);
        // An older record's Debug text is no settings: not done, and no error.
        let old = text.replacen(r#""render":{"#, r#""render":"RenderSettings { ","x":{"#, 1);
        std::fs::write(path_of(&image), old).unwrap();
        assert_eq!(finished(&image, &settings()), None);
        std::fs::write(path_of(&image), &text).unwrap();
        // A pass file changed after its record was written.
        std::fs::write(&depth, b"DEPTH").unwrap();
        assert_eq!(finished(&image, &settings()), None);
        remove(&image).unwrap();
        remove(&image).unwrap();
        assert!(!path_of(&image).exists());
        // Written again without a record: the old one goes too.
        std::fs::write(path_of(&image), &text).unwrap();
        let (staged, beside) = stage_both();
        commit_with_record(staged, beside, None).unwrap();
        assert!(!path_of(&image).exists() && image.exists() && depth.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
