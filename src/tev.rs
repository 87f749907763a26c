//! Live view in tev (<https://github.com/Tom94/tev>): the progressive image streamed over tev's
//! IPC protocol, a TCP connection carrying packets of a little-endian `u32` length (the
//! whole packet's, these four bytes included), a type byte and the fields. Two packets are
//! used: *create image* (type 4: grab-focus byte, name, width, height, channel count, channel
//! names; strings NUL-terminated, integers `i32`) and *update image* (type 6, tev's "v3":
//! grab-focus byte, name, channel count, channel names, the region's x, y, width and height,
//! then per channel its offset and stride in floats (`i64`) into the `f32` data that follows).
//! Updates go in tiles of [`TILE`] × [`TILE`] pixels, as tev's own Python client sends them.
//! A tev that is not running, or goes away, costs one warning and never the render.

use std::io::Write;
use std::net::{TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

/// tev's default address.
pub const DEFAULT_ADDRESS: &str = "127.0.0.1:14158";

/// Tile edge of the update packets, in pixels.
pub const TILE: u32 = 128;

/// Type byte of the create-image packet.
pub const CREATE_IMAGE: u8 = 4;

/// Type byte of the update-image packet (tev's "update image v3").
pub const UPDATE_IMAGE: u8 = 6;

/// The channels sent: the radiance.
const CHANNELS: [&str; 3] = ["R", "G", "B"];

/// How long a connection attempt may take before tev counts as absent.
const CONNECT_TIMEOUT: Duration = Duration::from_secs(2);

/// A packet under construction: the length is filled in by [`Packet::finish`].
struct Packet(Vec<u8>);

impl Packet {
    fn new(kind: u8) -> Packet {
        let mut bytes = vec![0u8; 4];
        bytes.push(kind);
        Packet(bytes)
    }

    fn byte(mut self, v: u8) -> Packet {
        self.0.push(v);
        self
    }

    fn text(mut self, s: &str) -> Packet {
        self.0.extend_from_slice(s.as_bytes());
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

    fn finish(mut self) -> Vec<u8> {
        let n = self.0.len() as u32;
        self.0[..4].copy_from_slice(&n.to_le_bytes());
        self.0
    }
}

/// The create-image packet of an image `name` of `size` pixels with the channels R, G, B.
pub fn create_image(name: &str, size: (u32, u32), grab_focus: bool) -> Vec<u8> {
    let mut p = Packet::new(CREATE_IMAGE)
        .byte(grab_focus as u8)
        .text(name)
        .i32(size.0 as i32)
        .i32(size.1 as i32)
        .i32(CHANNELS.len() as i32);
    for c in CHANNELS {
        p = p.text(c);
    }
    p.finish()
}

/// The update-image packets that send `pixels` (row-major RGB, `size` pixels) of image
/// `name`, one per tile of at most [`TILE`] × [`TILE`] pixels.
pub fn update_image(name: &str, size: (u32, u32), pixels: &[[f32; 3]]) -> Vec<Vec<u8>> {
    let mut packets = Vec::new();
    for y0 in (0..size.1).step_by(TILE as usize) {
        for x0 in (0..size.0).step_by(TILE as usize) {
            let (w, h) = (TILE.min(size.0 - x0), TILE.min(size.1 - y0));
            let mut p = Packet::new(UPDATE_IMAGE).byte(0).text(name).i32(CHANNELS.len() as i32);
            for c in CHANNELS {
                p = p.text(c);
            }
            p = p.i32(x0 as i32).i32(y0 as i32).i32(w as i32).i32(h as i32);
            // Interleaved RGB: channel c starts at float c, and every channel's next pixel
            // is 3 floats on.
            for c in 0..CHANNELS.len() {
                p = p.i64(c as i64);
            }
            for _ in CHANNELS {
                p = p.i64(CHANNELS.len() as i64);
            }
            for y in y0..y0 + h {
                let row = (y * size.0) as usize;
                for pixel in &pixels[row + x0 as usize..row + (x0 + w) as usize] {
                    for v in pixel {
                        p.0.extend_from_slice(&v.to_le_bytes());
                    }
                }
            }
            packets.push(p.finish());
        }
    }
    packets
}

/// A live view: an image in a running tev, updated at most every `interval`.
pub struct LiveView {
    stream: Option<TcpStream>,
    name: String,
    size: (u32, u32),
    interval: Duration,
    last: Option<Instant>,
}

impl LiveView {
    /// The live view at `address` (none when not asked for) of an image `name` of `size`
    /// pixels, shown about once a second.
    pub fn open(address: Option<&str>, name: &str, size: (u32, u32)) -> Option<LiveView> {
        Some(LiveView::connect(address?, name, size, Duration::from_secs(1)))
    }

    /// Connects to tev at `address` and creates the image `name` of `size` pixels there. Without
    /// a tev there (or when it cannot be reached) warns once and returns a view that shows
    /// nothing.
    pub fn connect(address: &str, name: &str, size: (u32, u32), interval: Duration) -> LiveView {
        let mut view = LiveView {
            stream: None,
            name: name.to_string(),
            size,
            interval,
            last: None,
        };
        match open(address) {
            Ok(stream) => {
                view.stream = Some(stream);
                view.send(&[create_image(name, size, true)]);
            }
            Err(e) => eprintln!("warning: no tev at {address} ({e}); rendering without the live view"),
        }
        view
    }

    /// Whether an update is due: the view is live and the last update is at least the
    /// interval old.
    pub fn due(&self) -> bool {
        self.stream.is_some() && self.last.is_none_or(|t| t.elapsed() >= self.interval)
    }

    /// Sends `pixels` (row-major RGB of the view's size) now.
    pub fn show(&mut self, pixels: &[[f32; 3]]) {
        if self.stream.is_none() {
            return;
        }
        self.last = Some(Instant::now());
        let packets = update_image(&self.name, self.size, pixels);
        self.send(&packets);
    }

    /// Writes `packets`; a failure warns once and ends the view.
    fn send(&mut self, packets: &[Vec<u8>]) {
        let Some(stream) = &mut self.stream else {
            return;
        };
        if let Err(e) = packets.iter().try_for_each(|p| stream.write_all(p)) {
            eprintln!("warning: tev went away ({e}); rendering on without the live view");
            self.stream = None;
        }
    }
}

/// A TCP connection to `address`, with a bounded wait.
fn open(address: &str) -> std::io::Result<TcpStream> {
    let mut last = std::io::Error::new(std::io::ErrorKind::NotFound, "the address resolves to nothing");
    for addr in address.to_socket_addrs()? {
        match TcpStream::connect_timeout(&addr, CONNECT_TIMEOUT) {
            Ok(s) => {
                s.set_nodelay(true)?;
                return Ok(s);
            }
            Err(e) => last = e,
        }
    }
    Err(last)
}
