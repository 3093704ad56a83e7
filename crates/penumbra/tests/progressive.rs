//! Progressive rendering through the library: the final film of a render in passes is the
//! same, bit for bit, as the film of one pass, for every sampler and any thread count; each
//! intermediate pass is the same for any thread count too, and refines toward the final
//! image; the first, a preview of the even rows, shows each on the odd row below it.

use std::path::Path;
use std::sync::Mutex;

use penumbra::{render, Film, Pass, RenderOptions, Sampler, SceneFile};

fn bits(film: &Film) -> Vec<u32> {
    film.pixels
        .iter()
        .flat_map(|c| [c.x, c.y, c.z].map(f32::to_bits))
        .collect()
}

fn mean_error(a: &Film, b: &Film) -> f32 {
    let n = a.pixels.len() as f32;
    a.pixels
        .iter()
        .zip(&b.pixels)
        .map(|(x, y)| (*x - *y).abs().element_sum())
        .sum::<f32>()
        / n
}

#[test]
fn passes_end_in_the_film_of_one_pass() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell.toml");
    let scene = SceneFile::load(&path).unwrap().build(0).unwrap();
    // 128 × 96 with 16 samples puts a camera ray exactly through the edge the floor shares
    // with the red wall (pixel (31, 80)): both triangles at one `t`, where packets of
    // different sizes once took different triangles.
    for (sampler, spp, size) in [
        (Sampler::Rgss, 4, (40, 30)),
        (Sampler::Rgss, 16, (128, 96)),
        (Sampler::Grid, 16, (40, 30)),
        (Sampler::Jittered, 9, (40, 30)),
    ] {
        let mut settings = scene.settings.clone();
        (settings.width, settings.height) = size;
        (settings.sampler, settings.spp) = (sampler, spp);
        let (once, _) = render(&scene.world, &settings, &RenderOptions::default()).unwrap();
        let mut by_threads = Vec::new();
        for threads in [1, 2] {
            let seen: Mutex<Vec<(u32, Film)>> = Mutex::new(Vec::new());
            let keep = |p: &Pass| seen.lock().unwrap().push((p.samples, p.film.clone()));
            let options = RenderOptions {
                threads,
                passes: Some(&keep),
                ..RenderOptions::default()
            };
            let (last, _) = render(&scene.world, &settings, &options).unwrap();
            assert_eq!(bits(&last), bits(&once), "{sampler:?}, {threads} threads");
            let seen = seen.into_inner().unwrap();
            let counts: Vec<u32> = seen.iter().map(|(s, _)| *s).collect();
            // The preview (0: the first sample of the even rows), then 1, 2, 4, ... samples.
            let expected: Vec<u32> = [0, 1, 2, 4, 8].into_iter().filter(|&s| s < spp).collect();
            assert_eq!(counts, expected, "{sampler:?}");
            // The preview shows each even row on the odd row below too, and its even rows
            // are those of the first whole sample.
            let (preview, one) = (&seen[0].1, &seen[1].1);
            let w = preview.width as usize;
            let row = |f: &Film, y: usize| bits(f)[3 * w * y..3 * w * (y + 1)].to_vec();
            for y in (0..preview.height as usize).step_by(2) {
                assert_eq!(row(preview, y), row(one, y), "{sampler:?}, row {y}");
                if y + 1 < preview.height as usize {
                    assert_eq!(row(preview, y + 1), row(preview, y), "{sampler:?}, row {y}");
                }
            }
            by_threads.push(seen);
        }
        // Each pass is the same for any thread count.
        for ((_, a), (_, b)) in by_threads[0].iter().zip(&by_threads[1]) {
            assert_eq!(bits(a), bits(b), "{sampler:?}");
        }
        // The preview is a whole image, nearer the final one than black is.
        let first = &by_threads[0][0].1;
        let black = Film {
            pixels: vec![Default::default(); first.pixels.len()],
            ..first.clone()
        };
        assert!(mean_error(first, &once) < 0.5 * mean_error(&black, &once));
    }
}
