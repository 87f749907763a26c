//! Self-contained HTML reports: one file that opens from disk with no server or network,
//! holding a command's text and tables, its images as float data (tone-mapped in the page,
//! with exposure, A/B flip, a split slider, relative error, `verify`'s t-maps and a
//! pixel-exact zoom) and its plots with their uncertainty. The page's code is ours
//! (`viewer.js`, `plot.js`, `load.js`, `viewer.css`, included at build time); it draws a
//! manifest ([`Report::manifest`]) and gets each image's floats from a loader, so the same
//! viewer can show data that arrives otherwise. Large images go beside the file
//! ([`Report::write`]), loaded by `<script src>` (which works from disk where fetch() does not).

mod markdown;

pub use markdown::{Block, blocks};

use anyhow::{Context, Result};
use base64::Engine;
use serde::Serialize;
use std::path::{Path, PathBuf};

const VIEWER_JS: &str = include_str!("viewer.js");
const PLOT_JS: &str = include_str!("plot.js");
const LOAD_JS: &str = include_str!("load.js");
const VIEWER_CSS: &str = include_str!("viewer.css");

/// Images with more pixels than this go into a file beside the report unless told
/// ([`Report::inline_limit`]).
pub const INLINE_PIXELS: usize = 256 * 256;

/// One image of a report: its floats, its file name beside the page, and what the manifest
/// says of it.
struct ImageData {
    info: ImageInfo,
    file: String,
    rgb: Vec<[f32; 3]>,
}

/// An image as the manifest names it.
#[derive(Debug, Clone, Serialize)]
pub struct ImageInfo {
    /// Its key in the page: unique to the report (`KEY-image-N`), so that several reports
    /// in one page (a notebook's) keep their data apart.
    pub id: String,
    /// Its label in the viewer.
    pub label: String,
    /// Width and height in pixels.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// The script beside the report that holds its data, relative to the report; `None`
    /// when the page holds it.
    pub src: Option<String>,
}

/// A map of block t-scores between two images of a viewer (`verify`'s blocks).
#[derive(Debug, Clone, Serialize)]
pub struct TMap {
    /// Label of the first image (t > 0 where it is brighter).
    pub a: String,
    /// Label of the second image.
    pub b: String,
    /// Side of a block in pixels.
    pub block: u32,
    /// Blocks across and down.
    pub grid: (u32, u32),
    /// Each block's t-score, row by row.
    pub t: Vec<f64>,
    /// Whether each block's difference is significant.
    pub rejected: Vec<bool>,
    /// The critical |t|.
    pub critical: f64,
}

/// One line of a plot: points (x, y) with the interval [lo, hi] around y, when known.
#[derive(Debug, Clone, Serialize)]
pub struct Line {
    /// Legend label.
    pub label: String,
    /// Points (x, y, lo, hi), in x order.
    pub points: Vec<(f64, f64, Option<f64>, Option<f64>)>,
    /// Drawn dashed, without markers (a level such as a noise floor).
    pub dashed: bool,
}

/// A plot: lines with bands of their uncertainty, hover for the values.
#[derive(Debug, Clone, Serialize)]
pub struct Plot {
    /// Title.
    pub title: String,
    /// X axis label.
    pub x_label: String,
    /// Y axis label.
    pub y_label: String,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// The lines.
    pub lines: Vec<Line>,
    /// What the bands are.
    pub note: String,
}

/// One part of the page, in order.
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
enum Item {
    Markdown {
        blocks: Vec<Block>,
    },
    Viewer {
        title: String,
        images: Vec<String>,
        tmaps: Vec<TMap>,
    },
    Plot(Plot),
}

/// The page's description: title and parts; images by id (see [`ImageInfo`]).
#[derive(Debug, Clone, Serialize)]
pub struct Manifest {
    title: String,
    items: Vec<Item>,
    images: Vec<ImageInfo>,
}

/// A report being put together: text, image viewers and plots, in order.
pub struct Report {
    key: String,
    title: String,
    items: Vec<Item>,
    images: Vec<ImageData>,
    inline_limit: usize,
}

impl Report {
    /// An empty report called `title`.
    pub fn new(title: &str) -> Report {
        Report {
            key: unique_key(),
            title: title.to_string(),
            items: Vec::new(),
            images: Vec::new(),
            inline_limit: INLINE_PIXELS,
        }
    }

    /// Images above `pixels` go beside the file [`Report::write`] writes (default
    /// [`INLINE_PIXELS`]).
    pub fn inline_limit(&mut self, pixels: usize) -> &mut Report {
        self.inline_limit = pixels;
        self
    }

    /// Adds Markdown text (headings, paragraphs, lists, tables).
    pub fn markdown(&mut self, text: &str) -> &mut Report {
        self.items.push(Item::Markdown { blocks: blocks(text) });
        self
    }

    /// Starts an image viewer called `title`: the images added next are shown in it, each
    /// comparable with each other (they should share a size).
    pub fn viewer(&mut self, title: &str) -> &mut Report {
        self.items.push(Item::Viewer {
            title: title.to_string(),
            images: Vec::new(),
            tmaps: Vec::new(),
        });
        self
    }

    /// Adds an image (row-major, top row first) to the current viewer (a new one, called
    /// after the image, when none is open).
    pub fn image(&mut self, label: &str, width: u32, height: u32, rgb: &[[f32; 3]]) -> &mut Report {
        assert_eq!(
            rgb.len(),
            width as usize * height as usize,
            "image {label}: size and data differ"
        );
        let file = format!("image-{}.js", self.images.len());
        let id = format!("{}-image-{}", self.key, self.images.len());
        self.open_viewer(label).0.push(id.clone());
        let info = ImageInfo {
            id,
            label: label.to_string(),
            width,
            height,
            src: None,
        };
        self.images.push(ImageData {
            info,
            file,
            rgb: rgb.to_vec(),
        });
        self
    }

    /// Adds a t-map between two images of the current viewer.
    pub fn tmap(&mut self, map: TMap) -> &mut Report {
        self.open_viewer(&map.a).1.push(map);
        self
    }

    /// The current viewer's image ids and t-maps (a new viewer called `title` if none is open).
    fn open_viewer(&mut self, title: &str) -> (&mut Vec<String>, &mut Vec<TMap>) {
        if !matches!(self.items.last(), Some(Item::Viewer { .. })) {
            self.viewer(title);
        }
        match self.items.last_mut() {
            Some(Item::Viewer { images, tmaps, .. }) => (images, tmaps),
            _ => unreachable!("a viewer was just opened"),
        }
    }

    /// Adds a plot.
    pub fn plot(&mut self, plot: Plot) -> &mut Report {
        self.items.push(Item::Plot(plot));
        self
    }

    /// The manifest the page draws; images above `inline_limit` pixels name a script in
    /// `beside` (a folder relative to the page), when given.
    pub fn manifest(&self, beside: Option<&str>) -> Manifest {
        let images = self
            .images
            .iter()
            .map(|image| ImageInfo {
                src: beside
                    .filter(|_| self.is_beside(image))
                    .map(|dir| format!("{dir}/{}", image.file)),
                ..image.info.clone()
            })
            .collect();
        Manifest {
            title: self.title.clone(),
            items: self.items.clone(),
            images,
        }
    }

    fn is_beside(&self, image: &ImageData) -> bool {
        image.rgb.len() > self.inline_limit
    }

    /// The page with every image in it (for a notebook, or anywhere one string must do).
    pub fn to_html(&self) -> String {
        self.page(&self.manifest(None), |_| true, "")
    }

    /// The page with no image data but the script `loader`, which defines
    /// `window.lightgraphLoader` to get the images elsewhere (`render --serve`'s live view).
    pub fn to_html_loading(&self, loader: &str) -> String {
        self.page(&self.manifest(None), |_| false, loader)
    }

    /// Writes the page to `path`; images above the inline limit go into `<stem>.data/`
    /// beside it (one script each), which must travel with the page.
    pub fn write(&self, path: &Path) -> Result<()> {
        let dir = data_dir(path);
        let name = dir
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default();
        let manifest = self.manifest(Some(&percent_encode(&name)));
        if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
        }
        for image in self.images.iter().filter(|i| self.is_beside(i)) {
            std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
            let file = dir.join(&image.file);
            std::fs::write(&file, data_script(image)).with_context(|| format!("writing {}", file.display()))?;
        }
        let html = self.page(&manifest, |i| !self.is_beside(i), "");
        std::fs::write(path, html).with_context(|| format!("writing {}", path.display()))
    }

    /// The HTML page of `manifest` with the data of the images `inline` selects, and the
    /// script `extra` (after the loader's, before the viewer's).
    fn page(&self, manifest: &Manifest, inline: impl Fn(&ImageData) -> bool, extra: &str) -> String {
        let json = serde_json::to_string(manifest).expect("a manifest is plain data");
        let data: String = self
            .images
            .iter()
            .filter(|i| inline(i))
            .map(|i| format!("<script>{}</script>\n", data_script(i)))
            .collect();
        format!(
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>\n\
             <style>\n{VIEWER_CSS}</style>\n</head>\n<body>\n<script>\n{LOAD_JS}</script>\n<script>\n{extra}</script>\n\
             <script>\n{PLOT_JS}</script>\n<script>\n{VIEWER_JS}</script>\n{data}<div class=\"lightgraph-report\">\n\
             <script type=\"application/json\">{}</script>\n<script>{MOUNT}</script>\n</div>\n</body>\n</html>\n",
            escape_html(&self.title),
            json.replace("</", "<\\/")
        )
    }
}

/// The page's last script: draws the manifest before it into the element around it.
const MOUNT: &str = "LightgraphViewer.mount(document.currentScript.parentElement, \
                     JSON.parse(document.currentScript.previousElementSibling.textContent), lightgraphLoader);";

/// A key no other report of this process, or of another made at another time, has.
fn unique_key() -> String {
    static COUNT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = COUNT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    format!("r{:x}-{n}", nanos ^ (u128::from(std::process::id()) << 64))
}

/// The folder beside a report at `path` that holds its large images: `<stem>.data`.
pub fn data_dir(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    path.with_file_name(format!("{stem}.data"))
}

/// The script that hands an image's data to the page: base64 of its little-endian f32 RGB.
fn data_script(image: &ImageData) -> String {
    let bytes: Vec<u8> = image
        .rgb
        .iter()
        .flat_map(|p| p.iter().flat_map(|c| c.to_le_bytes()))
        .collect();
    let encoded = base64::engine::general_purpose::STANDARD.encode(bytes);
    format!("lightgraphData(\"{}\", \"{encoded}\");", image.info.id)
}

/// `text` with HTML's special characters escaped.
fn escape_html(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// A file name as a relative URL: everything but letters, digits and `-_.~` percent-encoded.
fn percent_encode(name: &str) -> String {
    name.bytes()
        .map(|b| match b {
            b'a'..=b'z' | b'A'..=b'Z' | b'0'..=b'9' | b'-' | b'_' | b'.' | b'~' => (b as char).to_string(),
            _ => format!("%{b:02X}"),
        })
        .collect()
}

/// The report's path for an output file: `X.exr` gives `X.html`.
pub fn beside(out: &Path) -> PathBuf {
    out.with_extension("html")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report() -> Report {
        let mut r = Report::new("a <test>");
        r.markdown("# Hi\n\n| a | b |\n|---|---|\n| </script> | 2 |\n");
        r.viewer("scene").image("x", 2, 1, &[[1.0, 2.0, 3.0], [0.5, 0.25, 0.0]]);
        r
    }

    #[test]
    fn the_page_holds_its_code_manifest_and_data_and_nothing_that_closes_a_script_early() {
        let html = report().to_html();
        assert!(html.contains("<title>a &lt;test&gt;</title>"));
        assert!(html.contains("LightgraphViewer.mount"));
        // The data: 1.0f32 is 00 00 80 3F, so the base64 starts with AACAPwAAAEAAAEBA.
        assert!(html.contains("-image-0\", \"AACAPwAAAEAAAEBA"), "{html}");
        let manifest = html.split("type=\"application/json\">").nth(1).unwrap();
        let manifest = manifest.split("</script>").next().unwrap();
        assert!(manifest.contains("<\\/script>"));
        assert!(!html.contains("http://") && !html.contains("https://"));
    }

    #[test]
    fn large_images_go_beside_the_page() {
        let dir = std::env::temp_dir().join(format!("lightgraph-report-unit-{}", std::process::id()));
        let path = dir.join("my report.html");
        let mut r = report();
        r.inline_limit(1).write(&path).unwrap();
        let html = std::fs::read_to_string(&path).unwrap();
        assert!(html.contains("\"src\":\"my%20report.data/image-0.js\""), "{html}");
        assert!(!html.contains("AACAPw"));
        let script = std::fs::read_to_string(dir.join("my report.data/image-0.js")).unwrap();
        assert!(script.starts_with("lightgraphData(\"r") && script.contains("-image-0\", \"AACAPw"));
        std::fs::remove_dir_all(dir).unwrap();
    }
}
