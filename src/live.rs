//! The live views of a progressive render, updated together: tev (`--tev`, [`crate::tev`]) and
//! the browser (`--serve`, [`crate::serve`]).

use crate::serve::LiveServer;
use crate::tev::LiveView;

/// The live views asked for; none is a view that shows nothing.
#[derive(Default)]
pub struct Live {
    /// The image in a running tev.
    pub tev: Option<LiveView>,
    /// The browser's live view.
    pub server: Option<LiveServer>,
}

impl Live {
    /// Whether any view is due an update.
    pub fn due(&self) -> bool {
        self.tev.as_ref().is_some_and(LiveView::due) || self.server.as_ref().is_some_and(LiveServer::due)
    }

    /// Shows the film's mean `pixels` after `frames` frames with the progress line `status`
    /// in every view; `finished` marks the render's last update.
    pub fn show(&mut self, pixels: &[[f32; 3]], frames: u64, status: &str, finished: bool) {
        if let Some(v) = &mut self.tev {
            v.show(pixels);
        }
        if let Some(s) = &mut self.server {
            s.show(pixels, frames, status, finished);
        }
    }
}
