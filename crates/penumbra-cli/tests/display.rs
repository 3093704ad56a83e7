//! `--display-server`: a fake tev that parses every packet byte by byte (the layout of tev's
//! `Ipc.h`: a little-endian `u32` length counting itself, a type byte, then the fields) and
//! assembles the image from the tiles; the image it sees must be the file's, bit for bit. A
//! viewer that is absent, or that accepts and then never reads, changes nothing but a line on
//! stderr.

mod harness;

use std::io::Read;
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::thread;
use std::time::{Duration, Instant};

use harness::{ok, read_pfm, run_in};

fn repository() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A cursor over one packet's bytes, reading tev's field encodings.
struct Fields<'a>(&'a [u8]);

impl Fields<'_> {
    fn take(&mut self, n: usize) -> &[u8] {
        assert!(self.0.len() >= n, "packet too short");
        let (head, rest) = self.0.split_at(n);
        self.0 = rest;
        head
    }
    fn u8(&mut self) -> u8 {
        self.take(1)[0]
    }
    fn bool(&mut self) -> bool {
        match self.u8() {
            0 => false,
            1 => true,
            b => panic!("bool byte {b}"),
        }
    }
    fn i32(&mut self) -> i32 {
        i32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn i64(&mut self) -> i64 {
        i64::from_le_bytes(self.take(8).try_into().unwrap())
    }
    fn f32(&mut self) -> f32 {
        f32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn string(&mut self) -> String {
        let end = self.0.iter().position(|&b| b == 0).expect("NUL-terminated");
        let s = String::from_utf8(self.take(end).to_vec()).unwrap();
        self.take(1);
        s
    }
}

/// What the fake viewer saw: the image created, its channels, and its pixels (every channel,
/// rows top to bottom) with how many times each was sent.
#[derive(Debug, Default)]
struct Seen {
    name: String,
    size: (usize, usize),
    channels: Vec<String>,
    pixels: Vec<f32>,
    sent: Vec<u32>,
}

impl Seen {
    /// Channel `name` of every pixel.
    fn channel(&self, name: &str) -> Vec<f32> {
        let n = self.channels.len();
        let c = self.channels.iter().position(|x| x == name).unwrap();
        self.pixels.iter().skip(c).step_by(n).copied().collect()
    }

    /// R, G and B of every pixel, interleaved.
    fn rgb(&self) -> Vec<f32> {
        let [r, g, b] = ["R", "G", "B"].map(|c| self.channel(c));
        (0..r.len()).flat_map(|i| [r[i], g[i], b[i]]).collect()
    }
}

/// Reads packets from `stream` until it closes.
fn serve(mut stream: TcpStream) -> Seen {
    let mut bytes = Vec::new();
    stream.read_to_end(&mut bytes).unwrap();
    let mut seen = Seen::default();
    let mut rest = &bytes[..];
    while !rest.is_empty() {
        let len = u32::from_le_bytes(rest[..4].try_into().unwrap()) as usize;
        let mut p = Fields(&rest[4..len]);
        rest = &rest[len..];
        match p.u8() {
            4 => {
                assert!(p.bool(), "CreateImage grabs focus");
                seen.name = p.string();
                let (w, h) = (p.i32() as usize, p.i32() as usize);
                let n = p.i32() as usize;
                seen.channels = (0..n).map(|_| p.string()).collect();
                assert_eq!(seen.channels[..3], ["R", "G", "B"]);
                seen.size = (w, h);
                seen.pixels = vec![f32::NAN; w * h * n];
                seen.sent = vec![0; w * h];
            }
            6 => {
                p.bool();
                assert_eq!(p.string(), seen.name);
                let n = p.i32() as usize;
                let names: Vec<String> = (0..n).map(|_| p.string()).collect();
                assert_eq!(names, seen.channels[..n], "known channels, in order");
                let [x, y, w, h] = [0; 4].map(|_| p.i32() as usize);
                let offsets: Vec<i64> = (0..n).map(|_| p.i64()).collect();
                let strides: Vec<i64> = (0..n).map(|_| p.i64()).collect();
                let data: Vec<f32> =
                    std::iter::from_fn(|| (!p.0.is_empty()).then(|| p.f32())).collect();
                let all = seen.channels.len();
                for k in 0..w * h {
                    let at = (y + k / w) * seen.size.0 + x + k % w;
                    seen.sent[at] += 1;
                    for c in 0..n {
                        let i = (offsets[c] + k as i64 * strides[c]) as usize;
                        seen.pixels[at * all + c] = data[i];
                    }
                }
            }
            t => panic!("unexpected packet type {t}"),
        }
    }
    seen
}

#[test]
fn the_viewer_sees_every_tile_of_the_image_written() {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let viewer = thread::spawn(move || serve(listener.accept().unwrap().0));
    let dir = std::env::temp_dir().join(format!("penumbra-display-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("preview.pfm");
    let r = ok(run_in(
        &repository(),
        [
            "render",
            "scenes/cornell.toml",
            "--width",
            "100",
            "--height",
            "70",
            "--display-server",
            &address,
            "-o",
            out.to_str().unwrap(),
        ],
    ));
    assert!(
        r.stderr.contains(&format!("connected to tev at {address}")),
        "{}",
        r.stderr
    );
    let seen = viewer.join().unwrap();
    assert_eq!(seen.name, out.display().to_string());
    assert_eq!(seen.size, (100, 70));
    assert!(seen.sent.iter().all(|&n| n == 1), "every pixel sent once");
    let (w, h, channels, file) = read_pfm(&out);
    assert_eq!((w, h, channels), (100, 70, 3));
    let same = |a: &[f32], b: &[f32]| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
    assert!(same(&seen.rgb(), &file), "the viewer's image is the file's");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn progressive_passes_reach_the_viewer_and_end_in_the_same_file() {
    let dir = std::env::temp_dir().join(format!("penumbra-passes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (once, passes) = (dir.join("once.pfm"), dir.join("passes.pfm"));
    let args = |out: &Path| {
        let out = out.to_str().unwrap().to_owned();
        let size = ["--width", "48", "--height", "40", "--spp", "16", "-o"];
        let mut a: Vec<String> = ["render", "scenes/cornell.toml"].map(String::from).to_vec();
        a.extend(size.map(String::from));
        a.push(out);
        a
    };
    ok(run_in(&repository(), args(&once)));
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let viewer = thread::spawn(move || serve(listener.accept().unwrap().0));
    let mut progressive = args(&passes);
    progressive.extend(["--progressive", "--display-server", &address].map(String::from));
    ok(run_in(&repository(), progressive));
    let seen = viewer.join().unwrap();
    // Bit for bit the image of one pass; the viewer got every pixel once per pass (the
    // preview of the even rows, then 1, 2, 4, 8 and 16 samples), the last being the image.
    assert_eq!(
        std::fs::read(&once).unwrap(),
        std::fs::read(&passes).unwrap()
    );
    assert!(seen.sent.iter().all(|&n| n == 6), "six passes");
    let (_, _, _, file) = read_pfm(&passes);
    assert!(seen
        .rgb()
        .iter()
        .zip(&file)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn passes_asked_for_are_channels_of_the_viewers_image() {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let viewer = thread::spawn(move || serve(listener.accept().unwrap().0));
    let dir = std::env::temp_dir().join(format!("penumbra-aovview-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("a.pfm");
    let size = [
        "--width",
        "40",
        "--height",
        "30",
        "--aov",
        "depth,normal,object_id",
    ];
    let mut args: Vec<&str> = vec!["render", "scenes/cornell.toml"];
    args.extend(size);
    args.extend(["--display-server", &address, "-o", out.to_str().unwrap()]);
    ok(run_in(&repository(), args));
    let seen = viewer.join().unwrap();
    let names = [
        "R",
        "G",
        "B",
        "depth.Z",
        "normal.X",
        "normal.Y",
        "normal.Z",
        "object_id",
    ];
    assert_eq!(seen.channels, names);
    // As the files beside the image hold them.
    let (_, _, _, depth) = read_pfm(&dir.join("a.depth.pfm"));
    let (_, _, _, normal) = read_pfm(&dir.join("a.normal.pfm"));
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&seen.channel("depth.Z")), bits(&depth));
    let nx: Vec<f32> = normal.iter().step_by(3).copied().collect();
    assert_eq!(bits(&seen.channel("normal.X")), bits(&nx));
    let ids = seen.channel("object_id");
    assert!(ids
        .iter()
        .all(|&v| v == -1.0 || (v >= 0.0 && v.fract() == 0.0)));
    assert!(ids.iter().any(|&v| v >= 0.0));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn without_a_viewer_the_render_goes_on() {
    // A port nobody listens on: bound, then closed.
    let address = {
        let l = TcpListener::bind("127.0.0.1:0").unwrap();
        l.local_addr().unwrap().to_string()
    };
    let dir = std::env::temp_dir().join(format!("penumbra-noview-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("x.png");
    let r = ok(run_in(
        &repository(),
        [
            "render",
            "scenes/cornell.toml",
            "--width",
            "32",
            "--height",
            "32",
            "--display-server",
            &address,
            "-o",
            out.to_str().unwrap(),
        ],
    ));
    let line = format!("no viewer at {address}: continuing without preview");
    assert!(r.stderr.contains(&line), "{}", r.stderr);
    assert!(out.is_file());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_viewer_that_stops_reading_is_dropped() {
    // Accepts, then never reads: 1024² of RGB floats (12 MiB) overflows the socket buffers,
    // so the writer blocks; the render must still finish and write its file promptly.
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let holder = thread::spawn(move || {
        let (stream, _) = listener.accept().unwrap();
        thread::sleep(Duration::from_secs(30));
        drop(stream);
    });
    let dir = std::env::temp_dir().join(format!("penumbra-stall-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("big.png");
    let start = Instant::now();
    let r = ok(run_in(
        &repository(),
        [
            "render",
            "scenes/cornell.toml",
            "--width",
            "1024",
            "--height",
            "1024",
            "--sampler",
            "center",
            "--light-samples",
            "1",
            "--display-server",
            &address,
            "-o",
            out.to_str().unwrap(),
        ],
    ));
    let took = start.elapsed();
    assert!(r.stderr.contains("connected to tev"), "{}", r.stderr);
    assert!(out.is_file());
    assert!(took < Duration::from_secs(25), "took {took:?}");
    drop(holder);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_viewer_that_reads_slowly_holds_the_exit_at_most_the_timeout() {
    // Reads 16 KiB every 50 ms: the 12 MiB of a 1024² image would take it 40 s. The run
    // must end about 0.5 s after its render (the documented timeout), with one warning.
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let reader = thread::spawn(move || {
        let (mut stream, _) = listener.accept().unwrap();
        let mut buf = vec![0u8; 16 << 10];
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(60) {
            match stream.read(&mut buf) {
                Ok(0) | Err(_) => break,
                Ok(_) => thread::sleep(Duration::from_millis(50)),
            }
        }
    });
    let dir = std::env::temp_dir().join(format!("penumbra-slowview-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("big.pfm");
    let start = Instant::now();
    let r = ok(run_in(
        &repository(),
        [
            "render",
            "scenes/cornell.toml",
            "--width",
            "1024",
            "--height",
            "1024",
            "--sampler",
            "center",
            "--light-samples",
            "1",
            "--json",
            "--display-server",
            &address,
            "-o",
            out.to_str().unwrap(),
        ],
    ));
    let took = start.elapsed().as_secs_f64();
    let report: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    let work =
        report["load_seconds"].as_f64().unwrap() + report["render_seconds"].as_f64().unwrap();
    assert!(out.is_file());
    // 0.5 s for the viewer; the rest is starting, writing the file and a loaded machine.
    assert!(
        took - work < 5.0,
        "took {took:.2} s for {work:.2} s of work"
    );
    let warnings: Vec<&str> = r
        .stderr
        .lines()
        .filter(|l| l.contains("warning: the viewer"))
        .collect();
    assert_eq!(warnings.len(), 1, "{}", r.stderr);
    assert!(warnings[0].contains(&address), "{}", r.stderr);
    reader.join().unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
}
