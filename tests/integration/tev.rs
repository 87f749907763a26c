//! `--tev`: the live view's packets, decoded by a loopback listener standing in for tev, hold
//! the image the render writes; a tev that is not there costs a warning, not the render.

use crate::cli::{lightgraph, temp_dir};
use lightgraph::film::Film;
use std::io::Read;
use std::net::TcpListener;

/// A decoded packet: its type and fields.
#[derive(Debug)]
enum Packet {
    Create {
        name: String,
        size: (i32, i32),
        channels: Vec<String>,
    },
    Update {
        name: String,
        channels: Vec<String>,
        region: [i32; 4],
        offsets: Vec<i64>,
        strides: Vec<i64>,
        data: Vec<f32>,
    },
}

/// Reads tev's fields from a byte stream, as tev does.
struct Reader<'a>(&'a [u8]);

impl Reader<'_> {
    fn take(&mut self, n: usize) -> &[u8] {
        let (head, rest) = self.0.split_at(n);
        self.0 = rest;
        head
    }
    fn i32(&mut self) -> i32 {
        i32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn i64(&mut self) -> i64 {
        i64::from_le_bytes(self.take(8).try_into().unwrap())
    }
    fn text(&mut self) -> String {
        let end = self.0.iter().position(|&b| b == 0).expect("a NUL-terminated string");
        let s = String::from_utf8(self.take(end).to_vec()).unwrap();
        self.take(1);
        s
    }
}

/// Splits `bytes` into packets (u32 length including itself, type byte, fields).
fn decode(mut bytes: &[u8]) -> Vec<Packet> {
    let mut packets = Vec::new();
    while !bytes.is_empty() {
        let length = u32::from_le_bytes(bytes[..4].try_into().unwrap()) as usize;
        let mut r = Reader(&bytes[4..length]);
        bytes = &bytes[length..];
        let kind = r.take(1)[0];
        let _grab_focus = r.take(1)[0];
        let name = r.text();
        packets.push(match kind {
            4 => {
                let size = (r.i32(), r.i32());
                let n = r.i32();
                let channels = (0..n).map(|_| r.text()).collect();
                Packet::Create { name, size, channels }
            }
            6 => {
                let n = r.i32() as usize;
                let channels = (0..n).map(|_| r.text()).collect();
                let region = [r.i32(), r.i32(), r.i32(), r.i32()];
                let offsets = (0..n).map(|_| r.i64()).collect();
                let strides = (0..n).map(|_| r.i64()).collect();
                let data =
                    r.0.chunks(4)
                        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
                        .collect();
                Packet::Update {
                    name,
                    channels,
                    region,
                    offsets,
                    strides,
                    data,
                }
            }
            other => panic!("unexpected packet type {other}"),
        });
    }
    packets
}

#[test]
fn the_live_view_streams_the_image_the_render_writes() {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let received = std::thread::spawn(move || {
        let (mut stream, _) = listener.accept().unwrap();
        let mut bytes = Vec::new();
        stream.read_to_end(&mut bytes).unwrap();
        bytes
    });
    let dir = temp_dir("tev");
    let out = dir.join("live.exr");
    let o = out.to_str().unwrap();
    // 200 x 140 pixels: four tiles of at most 128 x 128.
    let args = [
        "render",
        "--scene",
        "cornell-diffuse",
        "--res",
        "200x140",
        "--frames",
        "2",
        "--out",
        o,
    ];
    let run = lightgraph(&[&args[..], &["--tev", &address]].concat());
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let packets = decode(&received.join().unwrap());
    match &packets[0] {
        Packet::Create { name, size, channels } => {
            assert_eq!((name.as_str(), *size), (o, (200, 140)));
            assert_eq!(channels, &["R", "G", "B"]);
        }
        p => panic!("the first packet is not a create-image: {p:?}"),
    }
    // The last update of every pixel is the final image.
    let mut image = vec![[f32::NAN; 3]; 200 * 140];
    let mut tiles = 0;
    for p in &packets[1..] {
        let Packet::Update {
            name,
            channels,
            region: [x0, y0, w, h],
            offsets,
            strides,
            data,
        } = p
        else {
            panic!("a second create-image: {p:?}");
        };
        assert_eq!((name.as_str(), channels.len()), (o, 3));
        assert!(
            *w <= 128 && *h <= 128 && x0 + w <= 200 && y0 + h <= 140,
            "tile {x0},{y0} {w}x{h}"
        );
        assert_eq!(data.len(), (w * h * 3) as usize);
        tiles += 1;
        for y in 0..*h {
            for x in 0..*w {
                let i = (y * w + x) as usize;
                let pixel = &mut image[((y0 + y) * 200 + x0 + x) as usize];
                for c in 0..3 {
                    pixel[c] = data[(offsets[c] + i as i64 * strides[c]) as usize];
                }
            }
        }
    }
    assert!(tiles >= 4 && tiles % 4 == 0, "{tiles} tiles");
    let film = Film::read(&out).unwrap();
    let mut worst = 0f32;
    for (a, b) in image.iter().zip(film.mean()) {
        for c in 0..3 {
            worst = worst.max((a[c] - b[c]).abs() / b[c].abs().max(1e-3));
        }
    }
    // The film is the same samples summed in f64: float rounding apart (NaN: a pixel never sent).
    assert!(worst < 1e-5, "the live view differs from the film by {worst:e}");
    assert!(
        film.mean().iter().flatten().any(|&v| v > 0.0),
        "a black image proves nothing"
    );
}

#[test]
fn a_missing_tev_costs_a_warning_not_the_render() {
    // A port nothing listens on: bind one, then close it.
    let address = TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .to_string();
    let dir = temp_dir("no-tev");
    let out = dir.join("x.exr");
    let args = [
        "render",
        "--scene",
        "cornell-diffuse",
        "--res",
        "8x8",
        "--frames",
        "1",
        "--tev",
        &address,
    ];
    let run = lightgraph(&[&args[..], &["--out", out.to_str().unwrap()]].concat());
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert_eq!(stderr.matches("warning: no tev at").count(), 1, "{stderr}");
    assert!(out.is_file());
}
