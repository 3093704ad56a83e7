//! The chunked reader against a single-chunk reading of the same bytes: meshes, materials and
//! error messages (with their line numbers) must be identical whatever the chunk size and
//! whether chunks are parsed on a pool or not. The reader's behaviour itself is tested through
//! the public API in `tests/obj.rs`.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use super::*;

fn pool() -> &'static rayon::ThreadPool {
    crate::pool::test_pool()
}

/// A folder of the system's temporary folder holding `lib.mtl`, for `mtllib` statements.
fn mtl_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("penumbra-obj-chunks-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mtl = "newmtl red\nKd 1 0 0\nnewmtl green\nKd 0 1 0\nnewmtl blue\nKd 0 0 1\n";
        std::fs::write(dir.join("lib.mtl"), mtl).unwrap();
        dir
    })
}

/// Reads `bytes` in chunks of `chunk_bytes`, on the pool or not, into a model or an error.
fn read_with(bytes: &[u8], chunk_bytes: usize, on_pool: bool) -> Result<ObjModel, String> {
    let pool = on_pool.then(pool);
    build_mesh(read(
        bytes,
        mtl_dir(),
        Library::new(Files::disk(), mtl_dir(), mtl_dir()),
        pool,
        chunk_bytes,
    )?)
}

/// Every chunk size from one byte (a chunk per line) to the whole file, on the pool and off
/// it, gives what a single chunk gives; returns that.
fn assert_chunking_agrees(bytes: &[u8]) -> Result<ObjModel, String> {
    let whole = read_with(bytes, usize::MAX, false);
    for chunk_bytes in [1, 2, 7, 30, 64, 100, 333, 1000, 4096] {
        for on_pool in [false, true] {
            let chunked = read_with(bytes, chunk_bytes, on_pool);
            match (&whole, &chunked) {
                (Ok(a), Ok(b)) => {
                    assert_eq!(a.mesh, b.mesh, "chunks of {chunk_bytes} bytes");
                    assert_eq!(a.materials, b.materials, "chunks of {chunk_bytes} bytes");
                }
                (a, b) => assert_eq!(
                    a.as_ref().err(),
                    b.as_ref().err(),
                    "chunks of {chunk_bytes} bytes"
                ),
            }
        }
    }
    whole
}

/// A file of every statement the reader handles: vertices with and without `vt` and `vn`,
/// relative indices (some reaching back over many lines), materials switched and repeated,
/// continued lines, comments, CRLF, tabs, a byte-order mark and bytes that are not UTF-8.
fn varied_obj(rows: usize) -> Vec<u8> {
    let mut s = String::from("\u{feff}# test\r\nmtllib lib.mtl\r\no thing\n");
    for i in 0..rows {
        let (x, y) = (i as f32 * 0.5, (i % 7) as f32);
        s += &format!(
            "v {x} {y} 0\nv {x} {y} 1 # comment\nv\t{x} \\\n  {} 2\n",
            y + 1.0
        );
        s += &format!("vt {} 0.5\nvn 0 0 {}\n", i as f32 / 9.0, 1 + i % 3);
        match i % 6 {
            0 => s += "usemtl red\n",
            2 => s += "usemtl green\r\n",
            3 => s += "usemtl\n",
            4 => s += "usemtl unknown name\n",
            _ => {}
        }
        let v = 3 * i + 1;
        s += &match i % 5 {
            0 => format!("f {v} {} {}\n", v + 1, v + 2),
            1 => "f -3/-1 -2/-1 -1/-1\n".to_owned(),
            2 => format!(
                "f {v}//{} {}//{} \\\n {}//{}\n",
                i + 1,
                v + 1,
                i + 1,
                v + 2,
                i + 1
            ),
            3 => format!("f -3/{}/-1 -2/-1/-1 -1/-1/{}\n", i + 1, i + 1),
            _ => format!("g part\ns 1\nf {v} {} {} {}\n", v + 1, v + 2, v.max(4) - 3),
        };
        if i % 10 == 9 {
            // Relative indices reaching back over many chunks of a few bytes.
            s += "f -30 -20 -10\n";
        }
    }
    let mut bytes = s.into_bytes();
    // Bytes that are not UTF-8, in an ignored statement.
    bytes.extend_from_slice(b"# caf\xe9 \xff\xfe\nl 1 2\n");
    bytes.extend_from_slice(b"f 1 2 3\n");
    bytes
}

/// A grid of quads whose every `v` has one `vt` and one `vn`, as most exported meshes.
fn grid_obj(size: usize) -> Vec<u8> {
    let mut s = String::from("mtllib lib.mtl\n");
    for y in 0..=size {
        for x in 0..=size {
            s += &format!(
                "v {x} {y} {}\nvt {} {}\nvn 0 0.{} 1\n",
                (x * y) % 3,
                x,
                y,
                x % 10
            );
        }
    }
    for y in 0..size {
        for x in 0..size {
            let v = y * (size + 1) + x + 1;
            let corners = [v, v + 1, v + size + 2, v + size + 1].map(|i| format!("{i}/{i}/{i}"));
            if x == 0 {
                s += ["usemtl red\n", "usemtl blue\n", "usemtl\n"][y % 3];
            }
            s += &format!("f {}\n", corners.join(" "));
        }
    }
    s.into_bytes()
}

#[test]
fn chunked_reading_equals_a_single_chunk() {
    let model = assert_chunking_agrees(&grid_obj(12)).unwrap();
    assert_eq!(model.mesh.positions.len(), 13 * 13);
    assert_eq!(model.mesh.indices.len(), 2 * 12 * 12);
    assert_eq!(model.materials.len(), 2);
    let model = assert_chunking_agrees(&varied_obj(40)).unwrap();
    assert!(model.mesh.indices.len() > 40);
    assert_eq!(model.materials.len(), 2);
    let model = assert_chunking_agrees(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3").unwrap();
    assert_eq!(model.mesh.indices, [[0, 1, 2]]);
    // A file ending in a continued line, and an empty file.
    assert_chunking_agrees(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 \\\n2 \\\n3 \\").unwrap();
    assert_chunking_agrees(b"").unwrap();
}

#[test]
fn errors_are_the_first_a_serial_reading_meets() {
    let good = varied_obj(60);
    let line_count = good.iter().filter(|&&b| b == b'\n').count();
    let with = |line: &str| {
        let mut bytes = good.clone();
        bytes.extend_from_slice(line.as_bytes());
        bytes.extend_from_slice(b"v 0 0 0\nf 1 2 x\n");
        bytes
    };
    // An error on a late line names that line.
    let late = format!(
        "line {}: a vertex `v` needs three numbers (x y z)",
        line_count + 1
    );
    assert_eq!(assert_chunking_agrees(&with("v 1 2\n")).err(), Some(late));
    // A relative index reaching back before the file's start is found after the chunks are
    // merged, yet comes before the later malformed corner.
    let relative = format!(
        "line {}: face corner \"-9999\": relative vertex index -9999 is out of range (only {} \
         defined so far)",
        line_count + 1,
        3 * 60
    );
    assert_eq!(
        assert_chunking_agrees(&with("f -1 -2 -9999\n")).err(),
        Some(relative)
    );
    // An index past the end is reported with its face's line once all vertices are known.
    let past = format!(
        "line {}: vertex index 100000 is out of range (the file has {} `v`)",
        line_count + 1,
        3 * 60
    );
    let mut bytes = good.clone();
    bytes.extend_from_slice(b"f 1 2 100000\n");
    assert_eq!(assert_chunking_agrees(&bytes).err(), Some(past));
    // A missing material library comes before a later parse error, and after an earlier one.
    let missing = with("mtllib missing.mtl\n");
    let message = assert_chunking_agrees(&missing).unwrap_err();
    assert!(message.contains("missing.mtl"), "{message}");
    let mut early = b"vt x\n".to_vec();
    early.extend_from_slice(&missing);
    assert_eq!(
        assert_chunking_agrees(&early).err(),
        Some("line 1: a texture coordinate `vt` needs numbers (u [v])".into())
    );
}

#[test]
fn vertex_colours_are_read_as_srgb_and_agree_across_chunks() {
    // The first and third `v` carry colours, the second a `w`; every chunking gives one mesh.
    let obj = b"v 0 0 0 1 0 0.5\nv 1 0 0 1\nv 0 1 0 0 1 0\nf 1 2 3\nv 0 0 1\nf 1 2 4\n";
    let model = assert_chunking_agrees(obj).unwrap();
    let colors = &model.mesh.colors;
    assert_eq!(colors.len(), model.mesh.positions.len());
    // sRGB 0.5 is about 0.214 linear; a `v` without a colour is white.
    assert_eq!((colors[0].x, colors[0].y), (1.0, 0.0));
    assert!((colors[0].z - 0.2140).abs() < 1e-4, "{}", colors[0]);
    assert_eq!(colors[1..], [Vec3::ONE, Vec3::Y, Vec3::ONE]);
    let plain = assert_chunking_agrees(b"v 0 0 0 1\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    assert!(plain.mesh.colors.is_empty());
    let e = assert_chunking_agrees(b"v 0 0 0 1 nan 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap_err();
    assert_eq!(e, "line 1: a vertex colour is not a finite number");
}
