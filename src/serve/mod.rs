//! Live view in a browser (`render --serve`): a small HTTP server on a thread of its own that
//! serves the report viewer in live mode and the progressive film as it lands, for watching a
//! render on a machine without a display (through an SSH tunnel, say).
//!
//! Routes: `/` the viewer page; `/status.json` the film's version, size, frames and progress
//! text; `/film.f32` and `/reference.f32` the mean radiance and the reference as little-endian
//! `f32` RGB, row-major, top row first. The page polls the status about once a second and
//! fetches the film when its version changed. A browser that goes away costs nothing.

use crate::report::Report;
use anyhow::{Context, Result};
use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The address `--serve` takes when given without one.
pub const DEFAULT_ADDRESS: &str = "127.0.0.1:8731";

/// The reference's label in the page (a film's label is its path, which ends in `.exr`).
const REFERENCE: &str = "reference";

/// The page's script: fetches the images and polls the status.
const LIVE_JS: &str = include_str!("live.js");

/// The live page of the film `name` of `size` pixels (and the reference, if there is one):
/// the report viewer, its images fetched from the server.
fn page(name: &str, size: (u32, u32), reference: bool) -> String {
    let (w, h) = size;
    let blank = vec![[0.0f32; 3]; w as usize * h as usize];
    let mut report = Report::new(&format!("{name} (live)"));
    report.viewer(name).image(name, w, h, &blank);
    let mut sources = serde_json::json!({ name: { "url": "film.f32", "live": true } });
    if reference {
        report.image(REFERENCE, w, h, &blank);
        sources[REFERENCE] = serde_json::json!({ "url": "reference.f32", "live": false });
    }
    report.to_html_loading(&format!("window.lightgraphLiveSources = {sources};\n{LIVE_JS}"))
}

/// What the server holds of the render: replaced whole at each update.
#[derive(Default)]
struct Snapshot {
    /// Counts the updates; the page fetches the film when it changes.
    version: u64,
    /// The film's size in pixels.
    size: (u32, u32),
    /// The frames the film holds.
    frames: u64,
    /// The progress line (samples/s, error against the reference, ...).
    status: String,
    /// Whether the render is over.
    finished: bool,
    /// The film's mean as little-endian f32 RGB.
    film: Vec<u8>,
    /// The reference's, if the render has one.
    reference: Option<Vec<u8>>,
    /// Whether a page asked for the status (someone is watching).
    watched: bool,
    /// The version of the last film fetched.
    delivered: Option<u64>,
}

/// How long a finished render waits for a watching page to fetch its last film.
const LAST_FILM_WAIT: Duration = Duration::from_secs(10);

/// A running live-view server; stops when dropped, once a watching page has the last film
/// (or after [`LAST_FILM_WAIT`]).
pub struct LiveServer {
    server: Arc<tiny_http::Server>,
    snapshot: Arc<Mutex<Snapshot>>,
    address: SocketAddr,
    interval: Duration,
    last: Option<Instant>,
    thread: Option<JoinHandle<()>>,
}

/// Little-endian bytes of row-major RGB pixels.
fn pixel_bytes(pixels: &[[f32; 3]]) -> Vec<u8> {
    pixels.iter().flatten().flat_map(|v| v.to_le_bytes()).collect()
}

impl LiveServer {
    /// Binds `address` (HOST:PORT; port 0 picks a free one) and starts serving the live view
    /// of a film `name` of `size` pixels, with the reference `reference` if given. Fails at
    /// once, naming the address, when it cannot be bound.
    pub fn start(address: &str, name: &str, size: (u32, u32), reference: Option<&[[f32; 3]]>) -> Result<LiveServer> {
        let server = tiny_http::Server::http(address)
            .map_err(|e| anyhow::anyhow!("--serve {address}: cannot listen there: {e}"))?;
        let bound = server
            .server_addr()
            .to_ip()
            .with_context(|| format!("--serve {address}: not an IP address"))?;
        let page = page(name, size, reference.is_some());
        let snapshot = Arc::new(Mutex::new(Snapshot {
            size,
            film: vec![0; 12 * size.0 as usize * size.1 as usize],
            reference: reference.map(pixel_bytes),
            ..Snapshot::default()
        }));
        let server = Arc::new(server);
        let thread = {
            let (server, snapshot) = (server.clone(), snapshot.clone());
            std::thread::spawn(move || serve(&server, &snapshot, &page))
        };
        Ok(LiveServer {
            server,
            snapshot,
            address: bound,
            interval: Duration::from_secs(1),
            last: None,
            thread: Some(thread),
        })
    }

    /// The address the server listens on (the port chosen where port 0 was asked for).
    pub fn address(&self) -> SocketAddr {
        self.address
    }

    /// The page's URL.
    pub fn url(&self) -> String {
        format!("http://{}/", self.address)
    }

    /// Whether an update is due: the last is at least a second old.
    pub fn due(&self) -> bool {
        self.last.is_none_or(|t| t.elapsed() >= self.interval)
    }

    /// Publishes the film's mean `pixels` after `frames` frames, with the progress line
    /// `status`; `finished` marks the last update.
    pub fn show(&mut self, pixels: &[[f32; 3]], frames: u64, status: &str, finished: bool) {
        self.last = Some(Instant::now());
        let film = pixel_bytes(pixels);
        let mut s = self.snapshot.lock().unwrap_or_else(|e| e.into_inner());
        s.version += 1;
        s.frames = frames;
        s.status = status.to_string();
        s.finished = finished;
        s.film = film;
    }
}

impl Drop for LiveServer {
    fn drop(&mut self) {
        let waiting_since = Instant::now();
        while waiting_since.elapsed() < LAST_FILM_WAIT {
            let s = self.snapshot.lock().unwrap_or_else(|e| e.into_inner());
            if !s.watched || s.delivered == Some(s.version) {
                break;
            }
            drop(s);
            std::thread::sleep(Duration::from_millis(20));
        }
        self.server.unblock();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Answers requests until the server is unblocked.
fn serve(server: &tiny_http::Server, snapshot: &Mutex<Snapshot>, page: &str) {
    for request in server.incoming_requests() {
        let response = respond(request.url(), snapshot, page);
        // A browser that closed the connection is no concern of the render's.
        let _ = request.respond(response);
    }
}

/// A response with `body` of content type `kind`, never cached.
fn response(body: Vec<u8>, kind: &str) -> tiny_http::Response<std::io::Cursor<Vec<u8>>> {
    let header = |k: &str, v: &str| tiny_http::Header::from_bytes(k.as_bytes(), v.as_bytes()).expect("a valid header");
    tiny_http::Response::from_data(body)
        .with_header(header("Content-Type", kind))
        .with_header(header("Cache-Control", "no-store"))
}

/// A 404 response.
fn not_found() -> tiny_http::Response<std::io::Cursor<Vec<u8>>> {
    response(b"not found".to_vec(), "text/plain").with_status_code(404)
}

/// The response to a GET of `url`.
fn respond(url: &str, snapshot: &Mutex<Snapshot>, page: &str) -> tiny_http::Response<std::io::Cursor<Vec<u8>>> {
    let path = url.split('?').next().unwrap_or(url);
    let mut s = snapshot.lock().unwrap_or_else(|e| e.into_inner());
    match path {
        "/" | "/index.html" => response(page.as_bytes().to_vec(), "text/html; charset=utf-8"),
        "/status.json" => {
            s.watched = true;
            response(status_json(&s).into_bytes(), "application/json")
        }
        "/film.f32" => {
            s.delivered = Some(s.version);
            response(s.film.clone(), "application/octet-stream")
        }
        "/reference.f32" => match &s.reference {
            Some(reference) => response(reference.clone(), "application/octet-stream"),
            None => not_found(),
        },
        "/favicon.ico" => response(Vec::new(), "image/x-icon").with_status_code(204),
        _ => not_found(),
    }
}

/// The status as JSON.
fn status_json(s: &Snapshot) -> String {
    serde_json::json!({
        "version": s.version,
        "width": s.size.0,
        "height": s.size.1,
        "frames": s.frames,
        "status": s.status,
        "finished": s.finished,
        "reference": s.reference.is_some(),
    })
    .to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn get(url: &str) -> (u16, Vec<u8>) {
        let agent: ureq::Agent = ureq::Agent::config_builder().http_status_as_error(false).build().into();
        let mut r = agent.get(url).call().expect("the server answers");
        let status = r.status().as_u16();
        (status, r.body_mut().read_to_vec().expect("a body"))
    }

    #[test]
    fn serves_the_page_the_status_and_the_film_as_it_changes() {
        let mut server = LiveServer::start("127.0.0.1:0", "film", (2, 1), Some(&[[1.0, 2.0, 3.0]; 2])).unwrap();
        let url = server.url();
        let (status, page) = get(&url);
        assert_eq!(status, 200);
        let page = String::from_utf8(page).unwrap();
        assert!(
            page.contains("lightgraphLiveSources") && page.contains("reference.f32"),
            "{page}"
        );
        assert_eq!(
            get(&format!("{url}film.f32")).1,
            vec![0; 24],
            "a blank film before the first frame"
        );
        let status: serde_json::Value = serde_json::from_slice(&get(&format!("{url}status.json")).1).unwrap();
        assert_eq!(
            (status["version"].as_u64(), status["width"].as_u64()),
            (Some(0), Some(2))
        );
        server.show(&[[0.5, 0.25, 0.125], [4.0, 5.0, 6.0]], 7, "frame 7", false);
        let status: serde_json::Value = serde_json::from_slice(&get(&format!("{url}status.json")).1).unwrap();
        assert_eq!(
            (status["version"].as_u64(), status["frames"].as_u64()),
            (Some(1), Some(7))
        );
        assert_eq!(status["status"], "frame 7");
        let film = get(&format!("{url}film.f32")).1;
        let floats: Vec<f32> = film
            .chunks(4)
            .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
            .collect();
        assert_eq!(floats, [0.5, 0.25, 0.125, 4.0, 5.0, 6.0]);
        assert_eq!(get(&format!("{url}reference.f32")).1.len(), 24);
        assert_eq!(get(&format!("{url}nothing")).0, 404);
    }

    #[test]
    fn an_address_in_use_is_an_error_naming_it() {
        let first = LiveServer::start("127.0.0.1:0", "film", (1, 1), None).unwrap();
        let taken = first.address().to_string();
        let e = LiveServer::start(&taken, "film", (1, 1), None)
            .err()
            .expect("the port is taken");
        assert!(e.to_string().contains(&taken), "{e}");
    }
}
