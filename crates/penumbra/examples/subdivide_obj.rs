//! Writes a 1-to-4 midpoint subdivision of an OBJ's triangles, repeated `levels` times: a way to
//! make million-triangle benchmark meshes from the scanned meshes we ship, instead of
//! committing them.
//!
//! ```text
//! cargo run --release -p penumbra --example subdivide_obj -- IN.obj OUT.obj LEVELS
//! ```
//!
//! Only `v` and `f` statements are read (faces fan-triangulated, `v/vt/vn` indices reduced to
//! the position); the output has positions and triangles only.

use std::collections::HashMap;
use std::io::{BufRead, BufReader, BufWriter, Write};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let [_, input, output, levels] = &args[..] else {
        return Err("usage: subdivide_obj IN.obj OUT.obj LEVELS".into());
    };
    let levels: u32 = levels.parse()?;
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut tris: Vec<[u32; 3]> = Vec::new();
    for line in BufReader::new(std::fs::File::open(input)?).lines() {
        let line = line?;
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let p: Vec<f32> = words.take(3).map(str::parse).collect::<Result<_, _>>()?;
                positions.push([p[0], p[1], p[2]]);
            }
            Some("f") => {
                let idx: Vec<u32> = words
                    .map(|w| {
                        let i: i64 = w.split('/').next().unwrap_or("").parse()?;
                        let i = if i < 0 {
                            positions.len() as i64 + i
                        } else {
                            i - 1
                        };
                        Ok(i as u32)
                    })
                    .collect::<Result<_, std::num::ParseIntError>>()?;
                for k in 1..idx.len().saturating_sub(1) {
                    tris.push([idx[0], idx[k], idx[k + 1]]);
                }
            }
            _ => {}
        }
    }
    for _ in 0..levels {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut mid = |a: u32, b: u32, positions: &mut Vec<[f32; 3]>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (pa, pb) = (positions[a as usize], positions[b as usize]);
                positions.push([0, 1, 2].map(|i| 0.5 * (pa[i] + pb[i])));
                positions.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for &[a, b, c] in &tris {
            let (ab, bc, ca) = (
                mid(a, b, &mut positions),
                mid(b, c, &mut positions),
                mid(c, a, &mut positions),
            );
            next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        tris = next;
    }
    let mut w = BufWriter::new(std::fs::File::create(output)?);
    writeln!(
        w,
        "# {} triangles, subdivided {levels} times from {input}",
        tris.len()
    )?;
    for p in &positions {
        writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
    }
    for t in &tris {
        writeln!(w, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
    }
    eprintln!(
        "{} vertices, {} triangles -> {output}",
        positions.len(),
        tris.len()
    );
    Ok(())
}
