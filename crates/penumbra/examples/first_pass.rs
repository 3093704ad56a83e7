//! When each pass of a progressive render arrives (`RenderOptions::passes`), for the time to
//! the first whole frame: a release build, the world built before the clock starts.
//!
//! ```text
//! cargo run --release -p penumbra --example first_pass -- scenes/cornell.toml 1024 2 5
//! ```
//!
//! Arguments: the scene, the film's side, the threads, the runs. Prints one line per run on
//! stdout: `samples:seconds` for each pass (0 is the preview), then the whole render's time.

use std::sync::Mutex;
use std::time::Instant;

use penumbra::{render, Pass, RenderOptions, SceneFile};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |i: usize, default: &str| args.get(i).cloned().unwrap_or(default.into());
    let path = std::path::PathBuf::from(arg(1, "scenes/cornell.toml"));
    let scene = SceneFile::load(&path)
        .and_then(|f| f.build(0))
        .expect("the scene loads");
    let side: u32 = arg(2, "1024").parse().expect("a side in pixels");
    let threads: usize = arg(3, "2").parse().expect("a thread count");
    let runs: usize = arg(4, "5").parse().expect("a run count");
    let mut settings = scene.settings.clone();
    (settings.width, settings.height) = (side, side);
    for _ in 0..runs {
        let marks = Mutex::new(Vec::new());
        let start = Instant::now();
        let keep = |p: &Pass| marks.lock().unwrap().push((p.samples, start.elapsed()));
        let options = RenderOptions {
            threads,
            passes: Some(&keep),
            ..RenderOptions::default()
        };
        render(&scene.world, &settings, &options).expect("the render runs");
        let total = start.elapsed().as_secs_f64();
        let marks = marks.into_inner().unwrap();
        let shown: Vec<String> = marks
            .iter()
            .map(|(s, t)| format!("{s}:{:.3}", t.as_secs_f64()))
            .collect();
        println!("{} total {total:.3}", shown.join(" "));
    }
}
