//! `--display-server HOST[:PORT]`: a live preview in tev (pbrt's flag and tev's default port,
//! 14158), spoken in tev's IPC protocol over TCP.
//!
//! # Packets (tev's `Ipc.h`)
//!
//! Every packet is its total length in bytes (a little-endian `u32`, counting these four bytes),
//! a type byte, then its fields: a bool is one byte (0 or 1), a string its UTF-8 bytes and a
//! NUL, integers and floats little-endian, a list its elements back to back (no count).
//! - CreateImage (4): grab focus, image name, width `i32`, height `i32`, channel count `i32`,
//!   the channel names.
//! - UpdateImageV3 (6): grab focus, image name, channel count `i32`, the channel names, x, y,
//!   width, height (`i32`), per channel an offset then (after all offsets) a stride (`i64`, in
//!   floats), then the `f32` data: channel c of pixel p at `offset[c] + p·stride[c]`.
//!
//! The channels are R, G, B (the film's linear RGB) and, with `--aov`, the passes named as an
//! EXR output names them (`depth.Z`, `normal.X`, …; ids as numbers, −1 for none),
//! interleaved pixel by pixel.
//!
//! # Never in the render's way
//!
//! Workers hand each finished tile to a channel and go on; one thread of the preview's own
//! writes the packets, in batches. A viewer that is absent, closes, or stops reading (a write blocked for
//! [`STALL`]) is dropped quietly: the render and its files are never affected. At the end the
//! writer gets at most [`STALL`] to send what is left.

use std::io::Write;
use std::net::{TcpStream, ToSocketAddrs};
use std::sync::mpsc::{channel, Sender};
use std::thread::JoinHandle;
use std::time::Duration;

use penumbra::{AovPixel, PixelBounds, Rgb};

use crate::aov::{self, Passes};

/// tev's default port, as pbrt's `--display-server` uses it.
pub const DEFAULT_PORT: u16 = 14158;

/// How long a connection attempt or one blocked write may take before the viewer is dropped.
pub const STALL: Duration = Duration::from_millis(500);

/// The writer's pause between batches.
const PAUSE: Duration = Duration::from_millis(5);

/// Bytes of queued packets the writer gathers into one write.
const BATCH: usize = 1 << 20;

const CREATE_IMAGE: u8 = 4;
const UPDATE_IMAGE_V3: u8 = 6;

/// The film's channels, sent first.
const RGB: [&str; 3] = ["R", "G", "B"];

/// `HOST` or `HOST:PORT` with the default port filled in.
pub fn address(server: &str) -> String {
    let has_port = server
        .rsplit_once(':')
        .is_some_and(|(host, port)| !host.ends_with(':') && port.parse::<u16>().is_ok());
    match has_port {
        true => server.to_owned(),
        false => format!("{server}:{DEFAULT_PORT}"),
    }
}

/// A packet under construction: its fields in tev's encoding.
struct Packet(Vec<u8>);

impl Packet {
    fn new(kind: u8) -> Packet {
        let mut bytes = vec![0; 4];
        bytes.push(kind);
        Packet(bytes)
    }

    fn bool(mut self, v: bool) -> Packet {
        self.0.push(u8::from(v));
        self
    }

    fn string(mut self, s: &str) -> Packet {
        // A NUL inside would end the string early in tev: drop it.
        self.0.extend(s.bytes().filter(|&b| b != 0));
        self.0.push(0);
        self
    }

    fn i32(mut self, v: i32) -> Packet {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }

    fn i64(mut self, v: i64) -> Packet {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }

    fn f32s(mut self, values: impl Iterator<Item = f32>) -> Packet {
        for v in values {
            self.0.extend_from_slice(&v.to_le_bytes());
        }
        self
    }

    /// The finished bytes, with the length in front.
    fn bytes(mut self) -> Vec<u8> {
        let len = self.0.len() as u32;
        self.0[..4].copy_from_slice(&len.to_le_bytes());
        self.0
    }
}

/// CreateImage for an image of `width × height` with `channels`.
fn create_image(name: &str, width: u32, height: u32, channels: &[String]) -> Vec<u8> {
    let p = Packet::new(CREATE_IMAGE).bool(true).string(name);
    let p = p
        .i32(width as i32)
        .i32(height as i32)
        .i32(channels.len() as i32);
    channels.iter().fold(p, |p, c| p.string(c)).bytes()
}

/// UpdateImageV3 for the tile `bounds`: `values` holds each pixel's `channels` in turn
/// (channel c at offset c, stride the channel count).
fn update_image(name: &str, channels: &[String], bounds: &PixelBounds, values: &[f32]) -> Vec<u8> {
    let n = channels.len();
    let p = Packet::new(UPDATE_IMAGE_V3).bool(false).string(name);
    let p = channels.iter().fold(p.i32(n as i32), |p, c| p.string(c));
    let (w, h) = (bounds.x1 - bounds.x0, bounds.y1 - bounds.y0);
    let p = p.i32(bounds.x0 as i32).i32(bounds.y0 as i32);
    let p = p.i32(w as i32).i32(h as i32);
    let p = (0..n as i64).fold(p, |p, c| p.i64(c));
    let p = (0..n).fold(p, |p, _| p.i64(n as i64));
    p.f32s(values.iter().copied()).bytes()
}

/// A connection to a viewer, fed tiles from the render's workers.
pub struct Preview {
    /// The packets on their way to the writer thread (`None` once the render is over).
    packets: Option<Sender<Vec<u8>>>,
    writer: Option<JoinHandle<()>>,
    name: String,
    /// R, G, B, then the passes' channels.
    channels: Vec<String>,
    passes: Passes,
}

impl Preview {
    /// Connects to the viewer at `server` (`HOST[:PORT]`), saying on stderr whether it did;
    /// `None` when no viewer answers (the render goes on without one).
    pub fn connect(server: &str, note: impl Fn(&str)) -> Option<Preview> {
        let address = address(server);
        let stream = address
            .to_socket_addrs()
            .ok()
            .and_then(|mut all| all.find_map(|a| TcpStream::connect_timeout(&a, STALL).ok()));
        let Some(mut stream) = stream else {
            note(&format!(
                "no viewer at {address}: continuing without preview"
            ));
            return None;
        };
        note(&format!("connected to tev at {address}"));
        let _ = stream.set_write_timeout(Some(STALL));
        let _ = stream.set_nodelay(true);
        let (tx, rx) = channel::<Vec<u8>>();
        // Packets waiting together go out in one write (fewer system calls and wake-ups of
        // the viewer). The first failed or stalled write drops the viewer; the rest is
        // drained unsent.
        let writer = std::thread::spawn(move || {
            let (mut alive, mut batch) = (true, Vec::new());
            while let Ok(first) = rx.recv() {
                batch.clear();
                batch.extend_from_slice(&first);
                while let Some(next) = (batch.len() < BATCH).then(|| rx.try_recv().ok()).flatten() {
                    batch.extend_from_slice(&next);
                }
                alive = alive && stream.write_all(&batch).is_ok();
                // A writer that waits in `recv` is woken by every tile; pausing between
                // batches lets tiles queue without waking anyone (at most every PAUSE).
                std::thread::sleep(PAUSE);
            }
        });
        Some(Preview {
            packets: Some(tx),
            writer: Some(writer),
            name: String::new(),
            channels: Vec::new(),
            passes: Passes(Vec::new()),
        })
    }

    /// Starts a new image in the viewer, named `name` (the output's name), of the film's size,
    /// with the channels of `passes` beside R, G and B.
    pub fn begin(&mut self, name: &str, width: u32, height: u32, passes: &Passes) {
        self.name = name.to_owned();
        self.channels = RGB.iter().map(|c| c.to_string()).collect();
        self.channels.extend(aov::channel_names(passes));
        self.passes = passes.clone();
        self.send(create_image(name, width, height, &self.channels));
    }

    /// Shows one finished tile (called from the render's workers); `aovs` is empty or holds
    /// the pixels' AOVs.
    pub fn tile(&self, bounds: &PixelBounds, pixels: &[Rgb], aovs: &[AovPixel]) {
        let mut values = Vec::with_capacity(pixels.len() * self.channels.len());
        for (i, c) in pixels.iter().enumerate() {
            values.extend(c.to_array());
            if let Some(px) = aovs.get(i) {
                aov::push_values(&self.passes, px, &mut values);
            }
        }
        // Without AOVs (a progressive pass) only the colour channels are sent.
        let channels = match aovs.is_empty() {
            true => &self.channels[..RGB.len()],
            false => &self.channels[..],
        };
        self.send(update_image(&self.name, channels, bounds, &values));
    }

    fn send(&self, packet: Vec<u8>) {
        if let Some(tx) = &self.packets {
            let _ = tx.send(packet);
        }
    }
}

impl Drop for Preview {
    /// Lets the writer send what is queued (each write bounded by [`STALL`]) and waits for it.
    fn drop(&mut self) {
        self.packets.take();
        if let Some(writer) = self.writer.take() {
            let _ = writer.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_port_defaults_to_tevs() {
        assert_eq!(address("localhost"), "localhost:14158");
        assert_eq!(address("127.0.0.1:9000"), "127.0.0.1:9000");
        assert_eq!(address("[::1]:9000"), "[::1]:9000");
    }

    #[test]
    fn packets_carry_their_length_and_fields() {
        let rgb: Vec<String> = RGB.iter().map(|c| c.to_string()).collect();
        let p = create_image("a", 2, 1, &rgb);
        assert_eq!(
            u32::from_le_bytes(p[..4].try_into().unwrap()) as usize,
            p.len()
        );
        assert_eq!(&p[4..8], &[CREATE_IMAGE, 1, b'a', 0]);
        assert_eq!(&p[8..20], &[2, 0, 0, 0, 1, 0, 0, 0, 3, 0, 0, 0]);
        assert_eq!(&p[20..], b"R\0G\0B\0");
        let b = PixelBounds {
            x0: 1,
            x1: 2,
            y0: 0,
            y1: 1,
        };
        let u = update_image("a", &rgb, &b, &[0.5, 1.0, 2.0]);
        assert_eq!(
            u32::from_le_bytes(u[..4].try_into().unwrap()) as usize,
            u.len()
        );
        // Header, name, count, names, rectangle, offsets and strides, then 3 floats.
        assert_eq!(u.len(), 4 + 1 + 1 + 2 + 4 + 6 + 16 + 48 + 12);
        assert_eq!(&u[u.len() - 4..], &2.0f32.to_le_bytes());
    }
}
