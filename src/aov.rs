//! Feature buffers (`--aov`): albedo, normal, depth and position at each sample's first
//! non-specular hit, averaged over the pixel's samples that hit something, rendered by the
//! graph `aov` (graphs/aov.ron, shaders/aov/aov.wgsl) beside the estimator. The estimator's
//! kernels carry none of this code: the AOVs are sessions of their own, one per quantity,
//! over the same frames (same seed, sample count and camera jitter as path tracing).
//!
//! Conventions: albedo is the material's diffuse reflectance (glTF: its base colour), textures
//! applied; normal the world-space shading normal on the side the camera ray arrived from,
//! averaged and renormalised; depth the distance travelled from the camera to the hit (the
//! ray's length for a direct hit; through mirrors and glass, the whole chain's); position the
//! world position. Samples that escape count for none of them: each is averaged over the
//! pixel's samples that hit (the coverage); a pixel none of whose samples hit holds 0.

use crate::drive::{Budget, Plan, Stopwatch, drive};
use crate::run::{LoadedScene, Session, SessionOptions, load_graph};
use anyhow::{Result, bail};
use lightgraph_engine::{ConstValue, Gpu};
use std::collections::BTreeMap;

/// A feature buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Aov {
    /// Diffuse reflectance or base colour (R, G, B).
    Albedo,
    /// Unit shading normal facing the camera ray (X, Y, Z).
    Normal,
    /// Distance travelled from the camera (Z).
    Depth,
    /// World position (X, Y, Z).
    Position,
}

impl Aov {
    /// Every feature buffer, in the order of `AOV_KIND`.
    pub const ALL: [Aov; 4] = [Aov::Albedo, Aov::Normal, Aov::Depth, Aov::Position];

    /// The buffers of a comma-separated list such as `albedo,normal,depth,position`.
    pub fn parse_list(text: &str) -> Result<Vec<Aov>> {
        let mut out = Vec::new();
        for word in text.split(',').map(str::trim).filter(|w| !w.is_empty()) {
            let Some(aov) = Aov::ALL.into_iter().find(|a| a.name() == word) else {
                bail!("--aov {text}: unknown buffer '{word}' (known: albedo, normal, depth, position)");
            };
            if !out.contains(&aov) {
                out.push(aov);
            }
        }
        if out.is_empty() {
            bail!("--aov {text}: name at least one buffer (albedo, normal, depth, position)");
        }
        Ok(out)
    }

    /// The buffer's name, also its layer's in the EXR.
    pub fn name(self) -> &'static str {
        match self {
            Aov::Albedo => "albedo",
            Aov::Normal => "normal",
            Aov::Depth => "depth",
            Aov::Position => "position",
        }
    }

    /// The channels of its layer.
    pub fn channels(self) -> &'static [&'static str] {
        match self {
            Aov::Albedo => &["R", "G", "B"],
            Aov::Depth => &["Z"],
            Aov::Normal | Aov::Position => &["X", "Y", "Z"],
        }
    }

    /// Its `AOV_KIND` in the graph `aov`.
    fn kind(self) -> u32 {
        self as u32
    }
}

/// The sessions that render the feature buffers of a run: depth (with the coverage) always,
/// and each other buffer asked for.
pub struct AovRender<'g> {
    sessions: Vec<(Aov, Session<'g>)>,
    asked: Vec<Aov>,
    /// Scene centre minus radius: the origin of the encoded positions.
    position_origin: [f32; 3],
}

impl<'g> AovRender<'g> {
    /// Sessions of the graph `aov` for `aovs` on `scene`, with the run's size, samples per
    /// frame, seed and (if it sets one) maximum path length.
    pub fn new(gpu: &'g Gpu, scene: &LoadedScene, run: &SessionOptions, aovs: &[Aov]) -> Result<AovRender<'g>> {
        let graph = load_graph("aov")?;
        let mut sessions = Vec::new();
        for aov in Aov::ALL.into_iter().filter(|a| *a == Aov::Depth || aovs.contains(a)) {
            let mut constants: BTreeMap<String, ConstValue> = run
                .constants
                .iter()
                .filter(|(name, _)| name.as_str() == "MAX_PATH_LENGTH")
                .map(|(k, v)| (k.clone(), *v))
                .collect();
            constants.insert("AOV_KIND".into(), ConstValue::U32(aov.kind()));
            let options = SessionOptions {
                constants,
                layout: Default::default(),
                ..run.clone()
            };
            sessions.push((aov, Session::new(gpu, &graph, "AOVsk", scene, options)?));
        }
        let info = &scene.compiled.info;
        Ok(AovRender {
            sessions,
            asked: aovs.to_vec(),
            position_origin: info.center.map(|c| c - info.radius),
        })
    }

    /// Renders frames `first .. first + count` (those of the run) into every buffer.
    pub fn render(&mut self, first: u32, count: u32) -> Result<()> {
        for (_, session) in &mut self.sessions {
            session.first_frame = first;
            let budget = Budget::Frames(count.saturating_sub(session.frames) as u64);
            drive(session, Plan::new(budget), &mut Stopwatch::start(), &mut [])?.whole("the feature buffers")?;
        }
        Ok(())
    }

    /// The layers asked for, decoded: (`layer.channel`, one value per pixel).
    pub fn layers(&self) -> Result<Vec<(String, Vec<f32>)>> {
        let mean = |aov: Aov| -> Result<Vec<[f32; 3]>> {
            let (_, session) = self
                .sessions
                .iter()
                .find(|(a, _)| *a == aov)
                .expect("a session per buffer");
            Ok(session.image()?.mean)
        };
        let depth = mean(Aov::Depth)?;
        let mut out = Vec::new();
        for &aov in &self.asked {
            let encoded = mean(aov)?;
            let decoded: Vec<[f32; 3]> = encoded
                .iter()
                .zip(&depth)
                .map(|(m, d)| self.decode(aov, *m, d[1]))
                .collect();
            for (c, channel) in aov.channels().iter().enumerate() {
                out.push((
                    format!("{}.{channel}", aov.name()),
                    decoded.iter().map(|v| v[c]).collect(),
                ));
            }
        }
        Ok(out)
    }

    /// The value of `aov` from its pixel mean `m` over all samples and the pixel's coverage.
    fn decode(&self, aov: Aov, m: [f32; 3], coverage: f32) -> [f32; 3] {
        if coverage <= 0.0 {
            return [0.0; 3];
        }
        let hit = m.map(|v| v / coverage);
        match aov {
            Aov::Albedo => hit,
            Aov::Depth => [hit[0], 0.0, 0.0],
            Aov::Normal => {
                let n = hit.map(|v| 2.0 * v - 1.0);
                let length = n.iter().map(|v| v * v).sum::<f32>().sqrt();
                if length > 0.0 { n.map(|v| v / length) } else { [0.0; 3] }
            }
            Aov::Position => [0, 1, 2].map(|c| hit[c] + self.position_origin[c]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_parse_and_unknown_buffers_are_named() {
        let all = Aov::parse_list("albedo, normal,depth,position,albedo").unwrap();
        assert_eq!(all, Aov::ALL.to_vec());
        let e = Aov::parse_list("albedo,speed").unwrap_err().to_string();
        assert!(e.contains("unknown buffer 'speed'"), "{e}");
        assert!(Aov::parse_list(",").is_err());
    }
}
