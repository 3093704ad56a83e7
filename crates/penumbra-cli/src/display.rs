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
//! The channels are R, G, B (the film's linear RGB, premultiplied with `--alpha`), A with
//! `--alpha`, and, with `--aov`, the passes named as an EXR output names them (`depth.Z`, `normal.X`, …; ids as numbers, −1 for none),
//! interleaved pixel by pixel.
//!
//! # Never in the render's way
//!
//! Workers hand each finished tile to a channel and go on; one thread of the preview's own
//! writes the packets, in batches. The viewer never holds the run longer than [`STALL`] in
//! total: the attempts to connect and, at the end, the wait for it to take what is left share
//! that one budget (when it runs out the connection is shut, which ends a write in progress).
//! A viewer that closes, or stops reading for [`STALL`] during the render, or is still behind
//! when the budget runs out, is dropped with one warning on stderr; the render and its files
//! are never affected.

use std::io::Write;
use std::net::{Shutdown, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use penumbra::{PixelBounds, Tile};

use crate::aov::{self, Passes};

/// tev's default port, as pbrt's `--display-server` uses it.
pub const DEFAULT_PORT: u16 = 14158;

/// The most a viewer may hold the run, in total (connecting, and the wait at the end for it to
/// take the rest), and the longest one write may stay blocked before the viewer is dropped.
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
    /// Closed by the writer thread when it ends (in a mutex: tiles come from many threads).
    ended: Mutex<Receiver<()>>,
    /// A handle on the connection, to shut it when the budget runs out.
    stream: TcpStream,
    /// Set when the run shut the connection (then the writer says nothing more).
    cut: Arc<AtomicBool>,
    /// What is left of [`STALL`] after connecting.
    budget: Duration,
    address: String,
    name: String,
    /// R, G, B, A with alpha, then the passes' channels.
    channels: Vec<String>,
    /// How many of `channels` the colour takes: R, G, B and A with alpha.
    colors: usize,
    passes: Passes,
}

/// The first of `address`'s addresses that accepts a connection, each tried for what is left
/// of `budget`.
fn connect(address: &str, budget: Duration) -> Option<TcpStream> {
    let start = Instant::now();
    address.to_socket_addrs().ok()?.find_map(|a| {
        let left = budget.saturating_sub(start.elapsed());
        (!left.is_zero())
            .then(|| TcpStream::connect_timeout(&a, left).ok())
            .flatten()
    })
}

/// Why the writer stopped sending.
enum Gone {
    Closed(std::io::Error),
    Stalled,
}

/// Writes all of `bytes`, each write blocked for at most [`STALL`] (the stream's timeout).
fn send(stream: &mut TcpStream, mut bytes: &[u8]) -> Result<(), Gone> {
    use std::io::ErrorKind::{Interrupted, TimedOut, WouldBlock};
    while !bytes.is_empty() {
        match stream.write(bytes) {
            Ok(0) => return Err(Gone::Closed(std::io::ErrorKind::WriteZero.into())),
            Ok(n) => bytes = &bytes[n..],
            Err(e) if e.kind() == Interrupted => {}
            Err(e) if matches!(e.kind(), WouldBlock | TimedOut) => return Err(Gone::Stalled),
            Err(e) => return Err(Gone::Closed(e)),
        }
    }
    Ok(())
}

impl Preview {
    /// Connects to the viewer at `server` (`HOST[:PORT]`), saying on stderr whether it did;
    /// `None` when no viewer answers within [`STALL`] (the render goes on without one).
    pub fn connect(server: &str, note: fn(&str)) -> Option<Preview> {
        let start = Instant::now();
        let address = address(server);
        let Some(mut stream) = connect(&address, STALL) else {
            note(&format!(
                "no viewer at {address}: continuing without preview"
            ));
            return None;
        };
        note(&format!("connected to tev at {address}"));
        let _ = stream.set_write_timeout(Some(STALL));
        let _ = stream.set_nodelay(true);
        let handle = stream.try_clone().ok()?;
        let (tx, rx) = channel::<Vec<u8>>();
        let (ended_tx, ended) = channel::<()>();
        let cut = Arc::new(AtomicBool::new(false));
        let (writer_cut, at) = (cut.clone(), address.clone());
        // Packets waiting together go out in one write (fewer system calls and wake-ups of
        // the viewer). The first failed or stalled write drops the viewer, with a warning
        // (none when the run shut the connection: it says why); the rest is drained unsent.
        let writer = std::thread::spawn(move || {
            let _ended = ended_tx;
            let (mut alive, mut batch) = (true, Vec::new());
            while let Ok(first) = rx.recv() {
                batch.clear();
                batch.extend_from_slice(&first);
                while let Some(next) = (batch.len() < BATCH).then(|| rx.try_recv().ok()).flatten() {
                    batch.extend_from_slice(&next);
                }
                if !alive {
                    continue;
                }
                if let Err(gone) = send(&mut stream, &batch) {
                    alive = false;
                    if !writer_cut.load(Ordering::SeqCst) {
                        note(&match gone {
                            Gone::Stalled => format!(
                                "warning: the viewer at {at} stopped reading for {} s: preview dropped",
                                STALL.as_secs_f32()
                            ),
                            Gone::Closed(e) => {
                                format!("warning: the viewer at {at} went away ({e}): preview dropped")
                            }
                        });
                    }
                }
                // A writer that waits in `recv` is woken by every tile; pausing between
                // batches lets tiles queue without waking anyone (at most every PAUSE).
                std::thread::sleep(PAUSE);
            }
        });
        Some(Preview {
            packets: Some(tx),
            writer: Some(writer),
            ended: Mutex::new(ended),
            stream: handle,
            cut,
            budget: STALL.saturating_sub(start.elapsed()),
            address,
            name: String::new(),
            channels: Vec::new(),
            colors: RGB.len(),
            passes: Passes(Vec::new()),
        })
    }

    /// Starts a new image in the viewer, named `name` (the output's name), of the film's size,
    /// with R, G and B, A when the render has `alpha`, and the channels of `passes`.
    pub fn begin(&mut self, name: &str, (width, height): (u32, u32), alpha: bool, passes: &Passes) {
        self.name = name.to_owned();
        self.channels = RGB.iter().map(|c| c.to_string()).collect();
        self.colors = RGB.len();
        if alpha {
            self.channels.push("A".to_owned());
            self.colors += 1;
        }
        self.channels.extend(aov::channel_names(passes));
        self.passes = passes.clone();
        self.send(create_image(name, width, height, &self.channels));
    }

    /// Shows one finished tile (called from the render's workers).
    pub fn tile(&self, tile: &Tile) {
        let mut values = Vec::with_capacity(tile.pixels.len() * self.channels.len());
        for (i, c) in tile.pixels.iter().enumerate() {
            values.extend(c.to_array());
            values.extend(tile.alpha.get(i));
            if let Some(px) = tile.aovs.get(i) {
                aov::push_values(&self.passes, px, &mut values);
            }
        }
        // Without AOVs (a progressive pass) only the colour channels are sent.
        let channels = match tile.aovs.is_empty() {
            true => &self.channels[..self.colors],
            false => &self.channels[..],
        };
        self.send(update_image(&self.name, channels, &tile.bounds, &values));
    }

    fn send(&self, packet: Vec<u8>) {
        if let Some(tx) = &self.packets {
            let _ = tx.send(packet);
        }
    }
}

impl Drop for Preview {
    /// Lets the writer send what is queued within what is left of [`STALL`], then shuts the
    /// connection (ending a blocked write) and waits for the writer.
    fn drop(&mut self) {
        self.packets.take();
        let ended = self.ended.get_mut().unwrap_or_else(|e| e.into_inner());
        let done = ended.recv_timeout(self.budget);
        if matches!(done, Err(std::sync::mpsc::RecvTimeoutError::Timeout)) {
            self.cut.store(true, Ordering::SeqCst);
            let _ = self.stream.shutdown(Shutdown::Both);
            crate::failure::note(&format!(
                "warning: the viewer at {} was still behind after {} s: the rest of the preview is not sent",
                self.address,
                STALL.as_secs_f32()
            ));
        }
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
