//! MTL material libraries: the [`Library`] of every `mtllib` an OBJ file names, and the
//! resolution of the file names they contain.
//!
//! Read: `newmtl`, `Kd`, `Ka`, `Ks` (one number means grey), `Ns`, `map_Kd` and `map_d`
//! (relative to the MTL file's folder; options such as `-s` or `-clamp` are skipped and the
//! rest of the line is the file name, spaces included). Everything else (`illum`, `Ni`, `d`,
//! `Tr`, `Tf`, `Ke`, other maps) is ignored, as are statements before the first `newmtl`.
//! Errors are messages that name the MTL file and the line.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

use super::lines::{check_text, decode, for_each_line, numbers, rest_of_line};
use super::{ObjMaterial, MAX_FILE_BYTES};
use crate::files::Files;
use crate::reach::{Outside, Reach};

/// The materials of every `mtllib`, later definitions of a name replacing earlier ones.
#[derive(Default)]
pub(super) struct Library {
    materials: Vec<ObjMaterial>,
    by_name: HashMap<String, usize>,
    /// MTL files already read, so that a library named twice is read once.
    loaded: HashSet<PathBuf>,
    /// Where the MTL files (and the textures they name) are read from.
    files: Files,
    /// The model whose libraries these are, and its folder: where its MTL files and their
    /// textures may be (see the module `reach`).
    model: PathBuf,
    root: PathBuf,
}

impl Library {
    /// An empty library of the model `model`, whose MTL files are read from `files` within the
    /// model's folder `root` (and the folders `files` allows).
    pub(super) fn new(files: Files, model: &Path, root: &Path) -> Library {
        Library {
            files,
            model: model.to_owned(),
            root: root.to_owned(),
            ..Library::default()
        }
    }

    /// Reads the MTL file `path` into the library, unless it was read already.
    pub(super) fn load(&mut self, path: PathBuf) -> Result<(), String> {
        if self.loaded.insert(path.clone()) {
            load_mtl(&path, self)?;
        }
        Ok(())
    }

    /// The MTL files read, in no particular order.
    pub(super) fn files_read(&self) -> impl Iterator<Item = &PathBuf> {
        self.loaded.iter()
    }

    /// True when `path` is a file where the library reads its files.
    pub(super) fn is_file(&self, path: &Path) -> bool {
        self.files.is_file(path)
    }

    /// `name` relative to `dir`, as [`resolve`] finds it in the library's files, when the
    /// model may read it.
    pub(super) fn resolve(&self, dir: &Path, name: &str) -> Result<PathBuf, Outside> {
        checked(&self.files, &self.model, &self.root, dir, name)
    }

    /// How many materials have been defined; [`Library::find`] gives indices below this.
    pub(super) fn len(&self) -> usize {
        self.materials.len()
    }

    /// Every material defined, in order (a name defined twice appears twice).
    pub(super) fn materials(&self) -> &[ObjMaterial] {
        &self.materials
    }

    /// The latest definition of the material `name` and its index.
    pub(super) fn find(&self, name: &str) -> Option<(usize, &ObjMaterial)> {
        let &index = self.by_name.get(name)?;
        Some((index, &self.materials[index]))
    }
}

/// Reads an MTL file into `library`. Errors name the MTL file.
fn load_mtl(path: &Path, library: &mut Library) -> Result<(), String> {
    let bytes = library
        .files
        .read(path, MAX_FILE_BYTES)
        .map_err(|e| format!("cannot load material library \"{}\": {e}", path.display()))?;
    read_mtl(&bytes, path, library)
}

/// The library of the one MTL file whose bytes are `bytes`; `path` names it in messages, and
/// its folder is where its textures may be.
pub(super) fn parse_bytes(bytes: &[u8], path: &Path) -> Result<Library, String> {
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut library = Library::new(Files::disk(), path, dir);
    read_mtl(bytes, path, &mut library)?;
    Ok(library)
}

fn read_mtl(bytes: &[u8], path: &Path, library: &mut Library) -> Result<(), String> {
    check_text(bytes, "an MTL")
        .map_err(|e| format!("material library \"{}\": {e}", path.display()))?;
    parse_mtl(&decode(bytes), path, library)
}

/// Reads the text of the MTL file `path` into `library`; `path` names the file in messages
/// and its folder is where texture names are resolved.
fn parse_mtl(text: &str, path: &Path, library: &mut Library) -> Result<(), String> {
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut current: Option<usize> = None;
    for_each_line(text, |n, line| {
        let at = |message: &str| {
            format!(
                "material library \"{}\", line {n}: {message}",
                path.display()
            )
        };
        let mut words = line.split_ascii_whitespace();
        let Some(keyword) = words.next() else {
            return Ok(());
        };
        if keyword == "newmtl" {
            let name = rest_of_line(line, keyword).to_owned();
            let index = library.materials.len();
            library.by_name.insert(name.clone(), index);
            library.materials.push(ObjMaterial {
                name,
                diffuse: None,
                ambient: None,
                specular: None,
                shininess: None,
                diffuse_texture: None,
                dissolve_texture: None,
            });
            current = Some(index);
            return Ok(());
        }
        // Statements before the first `newmtl` belong to no material.
        let Some(m) = current.map(|i| &mut library.materials[i]) else {
            return Ok(());
        };
        match keyword {
            "Kd" | "Ka" | "Ks" => {
                // The `spectral` and `xyz` forms are not RGB; leave the default.
                if matches!(words.clone().next(), Some("spectral" | "xyz")) {
                    return Ok(());
                }
                let given = words.clone().count();
                let c = numbers::<3>(&mut words, 1)
                    .filter(|c| c.iter().all(|x| x.is_finite()))
                    .ok_or_else(|| at(&format!("`{keyword}` needs one or three numbers")))?;
                // `Kd r` means grey.
                let c = if given < 3 { [c[0]; 3] } else { c };
                match keyword {
                    "Kd" => m.diffuse = Some(c),
                    "Ka" => m.ambient = Some(c),
                    _ => m.specular = Some(c),
                }
            }
            "Ns" => {
                let [p] = numbers::<1>(&mut words, 1)
                    .filter(|p| p[0].is_finite())
                    .ok_or_else(|| at("`Ns` needs a number"))?;
                m.shininess = Some(p);
            }
            "map_Kd" | "map_d" => {
                if let Some(name) = texture_file_name(line, words) {
                    let file = checked(&library.files, &library.model, &library.root, dir, name)
                        .map_err(|e| at(&format!("`{keyword}` {e}")))?;
                    let file = Some(file);
                    match keyword {
                        "map_Kd" => m.diffuse_texture = file,
                        _ => m.dissolve_texture = file,
                    }
                }
            }
            _ => {}
        }
        Ok(())
    })
}

/// The file name of a `map_Kd` or `map_d` statement: what follows its options, to the end of
/// the line.
fn texture_file_name<'a>(
    line: &'a str,
    mut words: std::str::SplitAsciiWhitespace<'a>,
) -> Option<&'a str> {
    while let Some(word) = words.next() {
        if !word.starts_with('-') || word.len() == 1 {
            // `word` is a slice of `line`: the name runs from it to the end of the line.
            let start = word.as_ptr() as usize - line.as_ptr() as usize;
            return Some(line[start..].trim_end());
        }
        match word {
            "-blendu" | "-blendv" | "-cc" | "-clamp" | "-texres" | "-bm" | "-boost"
            | "-imfchan" | "-type" => {
                words.next();
            }
            "-mm" => {
                words.next();
                words.next();
            }
            // `-o`, `-s`, `-t` (and options unknown here): up to three numbers.
            _ => {
                for _ in 0..3 {
                    let mut peek = words.clone();
                    match peek.next() {
                        Some(w) if w.parse::<f32>().is_ok() => words = peek,
                        _ => break,
                    }
                }
            }
        }
    }
    None
}

/// [`resolve`], when the model `model` with the folder `root` may read the file (see the
/// module `reach`).
fn checked(
    files: &Files,
    model: &Path,
    root: &Path,
    dir: &Path,
    name: &str,
) -> Result<PathBuf, Outside> {
    let path = resolve(files, dir, name);
    Reach::new(files, model, root, "model")
        .check(name, &path)
        .map(|()| path)
}

/// `name` relative to `dir`. Names written with Windows separators are tried with `/` when
/// the name as written is not a file of `files`.
pub(super) fn resolve(files: &Files, dir: &Path, name: &str) -> PathBuf {
    let path = dir.join(name);
    if name.contains('\\') && !files.is_file(&path) {
        let alt = dir.join(name.replace('\\', "/"));
        if files.is_file(&alt) {
            return alt;
        }
    }
    path
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The MTL text `text` as if read from `lib/test.mtl` (nothing is read from disk).
    fn parse(text: &str) -> Result<Library, String> {
        let mut library = Library::default();
        parse_mtl(text, Path::new("lib/test.mtl"), &mut library)?;
        Ok(library)
    }

    fn material<'a>(library: &'a Library, name: &str) -> &'a ObjMaterial {
        library
            .find(name)
            .unwrap_or_else(|| panic!("no material {name:?}"))
            .1
    }

    #[test]
    fn reads_every_supported_statement_and_leaves_the_rest_unset() {
        let library =
            parse("newmtl all\nKd 0.1 0.2 0.3\nKa 0.25\nKs 1 1 1 1\nNs 7.5\nmap_Kd d.png\nmap_d -clamp on leaf mask.png\nnewmtl none of it\nillum 2\nd 0.5\n")
                .unwrap();
        assert_eq!(library.len(), 2);
        let all = material(&library, "all");
        assert_eq!(
            all,
            &ObjMaterial {
                name: "all".into(),
                diffuse: Some([0.1, 0.2, 0.3]),
                ambient: Some([0.25; 3]),
                specular: Some([1.0; 3]),
                shininess: Some(7.5),
                diffuse_texture: Some(Path::new("lib").join("d.png")),
                dissolve_texture: Some(Path::new("lib").join("leaf mask.png")),
            }
        );
        // Nothing given is nothing set: the scene's defaults apply later.
        let none = material(&library, "none of it");
        assert_eq!(
            (
                none.diffuse,
                none.ambient,
                none.specular,
                none.shininess,
                &none.diffuse_texture
            ),
            (None, None, None, None, &None)
        );
    }

    #[test]
    fn spectral_and_xyz_colors_are_skipped() {
        let library =
            parse("newmtl m\nKd spectral d.spd 1.0\nKa xyz 0.5 0.5 0.5\nKs 0.5\n").unwrap();
        let m = material(&library, "m");
        assert_eq!(
            (m.diffuse, m.ambient, m.specular),
            (None, None, Some([0.5; 3]))
        );
    }

    #[test]
    fn statements_before_the_first_newmtl_belong_to_no_material() {
        let library = parse("Kd 1 0 0\nmap_Kd early.png\nnewmtl m\nNs 3\n").unwrap();
        let m = material(&library, "m");
        assert_eq!((m.diffuse, &m.diffuse_texture), (None, &None));
        assert_eq!(m.shininess, Some(3.0));
    }

    #[test]
    fn a_name_defined_again_refers_to_the_later_definition() {
        let library = parse("newmtl m\nKd 1 0 0\nnewmtl m\nKd 0 0 1\n").unwrap();
        assert_eq!(library.len(), 2);
        let (index, m) = library.find("m").unwrap();
        assert_eq!((index, m.diffuse), (1, Some([0.0, 0.0, 1.0])));
        assert!(library.find("M").is_none(), "names are case-sensitive");
    }

    #[test]
    fn malformed_numbers_are_errors_naming_the_file_and_line() {
        // (`Kd 0.5` is not among them: one number is grey.)
        let cases = [
            ("Kd", "`Kd` needs one or three numbers"),
            ("Ka 0.5 half 0.5", "`Ka` needs one or three numbers"),
            ("Ks 1 inf 1", "`Ks` needs one or three numbers"),
            ("Kd NaN", "`Kd` needs one or three numbers"),
            ("Ns", "`Ns` needs a number"),
            ("Ns shiny", "`Ns` needs a number"),
            ("Ns -inf", "`Ns` needs a number"),
        ];
        for (statement, message) in cases {
            let text = format!("# header\nnewmtl m\n\n  {statement} \\\n\nKd 1 1 1\n");
            let e = parse(&text)
                .err()
                .unwrap_or_else(|| panic!("{statement:?} parsed"));
            assert_eq!(
                e,
                format!("material library \"lib/test.mtl\", line 4: {message}"),
                "{statement:?}"
            );
        }
    }

    #[test]
    fn map_kd_options_come_before_the_file_name() {
        let cases = [
            ("t.png", "t.png"),
            ("-o 0.5 t.png", "t.png"),
            ("-s 1 1 1 -t 0 0 0 t.png", "t.png"),
            ("-s 2 4.png", "4.png"),
            (
                "-blendu on -blendv off -cc on -clamp off -texres 512 t.png",
                "t.png",
            ),
            ("-bm 0.5 -boost 2 -imfchan l -type sphere t.png", "t.png"),
            ("-mm 0.1 0.9 my texture.png", "my texture.png"),
            ("-halo 1 2 t.png", "t.png"),
        ];
        for (args, name) in cases {
            let library = parse(&format!("newmtl m\nmap_Kd {args}\n")).unwrap();
            assert_eq!(
                material(&library, "m").diffuse_texture,
                Some(Path::new("lib").join(name)),
                "map_Kd {args}"
            );
        }
        // Options and no name: no texture, and no error.
        let library = parse("newmtl m\nmap_Kd -clamp on -s 1 1 1\n").unwrap();
        assert_eq!(material(&library, "m").diffuse_texture, None);
    }

    #[test]
    fn a_library_is_read_once_however_often_it_is_named() {
        let dir = std::env::temp_dir().join(format!("penumbra-mtl-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("once.mtl");
        std::fs::write(&path, "newmtl m\nKd 1 0 0\n").unwrap();
        let mut library = Library::default();
        let result = library
            .load(path.clone())
            .and_then(|()| library.load(path.clone()));
        let _ = std::fs::remove_dir_all(&dir);
        result.unwrap();
        assert_eq!(library.len(), 1);

        let e = library.load(dir.join("gone.mtl")).unwrap_err();
        assert!(
            e.starts_with("cannot load material library \"") && e.contains("gone.mtl"),
            "{e}"
        );
    }
}
