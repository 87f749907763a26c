//! Classes of light paths in Heckbert's notation: how a graph declares what it cannot sample
//! (`coverage: (misses: [(paths: "Ld S X* E")])`) and how `lightgraph verify` predicts from a
//! scene's contents whether such paths exist there.
//!
//! A class is a regular expression over a path's vertices read from the light to the eye:
//! `Ld` a delta light (point, spot, directional: no path can hit it), `La` a light a path can
//! hit (emissive triangles, a background, an environment map), `L` either, `S` a specular
//! (delta) scattering, `G` a glossy one (a non-delta lobe other than the Lambertian), `D` a
//! diffuse one, `X` any scattering, `E` the eye. Letters follow one another (spaces are
//! optional), `|` separates alternatives, `( )` groups, and `+`, `*`, `?` repeat what they
//! follow.

use anyhow::{Result, bail};
use lightgraph_scenes::CompiledScene;
use lightgraph_scenes::gpu::{GpuMaterial, light_kind, material_flags};

/// Vertex kinds as bits of a [`Kinds`] set.
pub mod kind {
    /// A delta light.
    pub const LIGHT_DELTA: u8 = 1;
    /// A light a path can hit.
    pub const LIGHT_HIT: u8 = 2;
    /// A specular (delta) scattering.
    pub const SPECULAR: u8 = 4;
    /// A glossy scattering.
    pub const GLOSSY: u8 = 8;
    /// A diffuse scattering.
    pub const DIFFUSE: u8 = 16;
    /// The eye.
    pub const EYE: u8 = 32;
    /// Either light.
    pub const LIGHT: u8 = LIGHT_DELTA | LIGHT_HIT;
    /// Any scattering.
    pub const SCATTERING: u8 = SPECULAR | GLOSSY | DIFFUSE;
}

/// A set of vertex kinds (bits of [`kind`]).
pub type Kinds = u8;

/// A parsed path class.
#[derive(Debug, Clone, PartialEq)]
pub enum PathClass {
    /// One vertex of these kinds.
    Vertex(Kinds),
    /// These in order.
    Sequence(Vec<PathClass>),
    /// One of these.
    Either(Vec<PathClass>),
    /// The class repeated: at least `min` (0 or 1) times, at most once when `once`.
    Repeat {
        /// What repeats.
        class: Box<PathClass>,
        /// Fewest repetitions, 0 or 1.
        min: u8,
        /// At most one (`?`).
        once: bool,
    },
}

impl PathClass {
    /// Parses `text`, which must read from a light to the eye.
    pub fn parse(text: &str) -> Result<PathClass> {
        let mut p = Parser {
            chars: text.chars().filter(|c| !c.is_whitespace()).collect(),
            at: 0,
        };
        let class = p.either()?;
        if p.at < p.chars.len() {
            bail!("unexpected '{}' in path class '{text}'", p.chars[p.at]);
        }
        let PathClass::Sequence(items) = &class else {
            bail!("path class '{text}' is not a path from a light to the eye, e.g. 'Ld S X* E'");
        };
        let ends = (items.first(), items.last());
        let from_light = matches!(ends.0, Some(PathClass::Vertex(k)) if k & !kind::LIGHT == 0);
        let to_eye = matches!(ends.1, Some(PathClass::Vertex(k)) if *k == kind::EYE);
        if !(from_light && to_eye) {
            bail!("path class '{text}' must read from a light (L, Ld, La) to the eye (E), e.g. 'Ld S X* E'");
        }
        Ok(class)
    }

    /// The fewest segments (vertices less one) of a path of the class.
    pub fn min_segments(&self) -> u32 {
        self.min_vertices().saturating_sub(1)
    }

    fn min_vertices(&self) -> u32 {
        match self {
            PathClass::Vertex(_) => 1,
            PathClass::Sequence(items) => items.iter().map(PathClass::min_vertices).sum(),
            PathClass::Either(items) => items.iter().map(PathClass::min_vertices).min().unwrap_or(0),
            PathClass::Repeat { class, min, .. } => *min as u32 * class.min_vertices(),
        }
    }

    /// Whether some path of the class has vertices of the kinds in `present` alone.
    pub fn possible_with(&self, present: Kinds) -> bool {
        match self {
            PathClass::Vertex(k) => k & present != 0,
            PathClass::Sequence(items) => items.iter().all(|c| c.possible_with(present)),
            PathClass::Either(items) => items.iter().any(|c| c.possible_with(present)),
            PathClass::Repeat { class, min, .. } => *min == 0 || class.possible_with(present),
        }
    }
}

struct Parser {
    chars: Vec<char>,
    at: usize,
}

impl Parser {
    fn peek(&self) -> Option<char> {
        self.chars.get(self.at).copied()
    }

    /// alternatives := sequence ('|' sequence)*
    fn either(&mut self) -> Result<PathClass> {
        let mut options = vec![self.sequence()?];
        while self.peek() == Some('|') {
            self.at += 1;
            options.push(self.sequence()?);
        }
        Ok(match options.len() {
            1 => options.pop().expect("one option"),
            _ => PathClass::Either(options),
        })
    }

    /// sequence := repeated+
    fn sequence(&mut self) -> Result<PathClass> {
        let mut items = Vec::new();
        while self.peek().is_some_and(|c| c != '|' && c != ')') {
            items.push(self.repeated()?);
        }
        match items.len() {
            0 => bail!("an empty alternative in a path class"),
            _ => Ok(PathClass::Sequence(items)),
        }
    }

    /// repeated := atom ('+' | '*' | '?')*
    fn repeated(&mut self) -> Result<PathClass> {
        let mut class = self.atom()?;
        while let Some(c @ ('+' | '*' | '?')) = self.peek() {
            self.at += 1;
            class = PathClass::Repeat {
                class: Box::new(class),
                min: (c == '+') as u8,
                once: c == '?',
            };
        }
        Ok(class)
    }

    /// atom := letter | '(' alternatives ')'
    fn atom(&mut self) -> Result<PathClass> {
        let c = self.peek().expect("sequence checked for more");
        self.at += 1;
        let vertex = |k| Ok(PathClass::Vertex(k));
        match c {
            '(' => {
                let inner = self.either()?;
                if self.peek() != Some(')') {
                    bail!("a '(' without its ')' in a path class");
                }
                self.at += 1;
                Ok(inner)
            }
            'L' => match self.peek() {
                Some('d') => {
                    self.at += 1;
                    vertex(kind::LIGHT_DELTA)
                }
                Some('a') => {
                    self.at += 1;
                    vertex(kind::LIGHT_HIT)
                }
                _ => vertex(kind::LIGHT),
            },
            'S' => vertex(kind::SPECULAR),
            'G' => vertex(kind::GLOSSY),
            'D' => vertex(kind::DIFFUSE),
            'X' => vertex(kind::SCATTERING),
            'E' => vertex(kind::EYE),
            other => bail!("'{other}' is not a vertex of a path class (L, Ld, La, S, G, D, X, E)"),
        }
    }
}

/// The vertex kinds `scene`'s paths can have: its lights' kinds, the lobes of its materials,
/// and the eye.
pub fn scene_kinds(scene: &CompiledScene) -> Kinds {
    let mut kinds = kind::EYE;
    for light in &scene.lights {
        kinds |= match light.kind {
            light_kind::POINT | light_kind::SPOT | light_kind::DIRECTIONAL => kind::LIGHT_DELTA,
            _ => kind::LIGHT_HIT,
        };
    }
    for m in &scene.materials {
        kinds |= material_kinds(m);
    }
    kinds
}

/// The scattering kinds of a material's lobes.
fn material_kinds(m: &GpuMaterial) -> Kinds {
    let any = |c: [f32; 3]| c.iter().any(|&x| x > 0.0);
    if m.flags & material_flags::PBR == 0 {
        let mut k = 0;
        if any(m.diffuse) {
            k |= kind::DIFFUSE;
        }
        if any(m.phong) {
            k |= kind::GLOSSY;
        }
        if m.ior > 0.0 || any(m.mirror) {
            k |= kind::SPECULAR;
        }
        return k;
    }
    // glTF metallic-roughness: a diffuse base unless wholly metal or transmissive, and a
    // specular layer that is smooth (delta) at roughness 0 (a texture scales the factor).
    let mut k = if m.roughness > 0.0 {
        kind::GLOSSY
    } else {
        kind::SPECULAR
    };
    let textured = m.base_color_texture >= 0 || m.metallic_roughness_texture >= 0;
    if (m.metallic < 1.0 && m.transmission < 1.0 && any(m.diffuse)) || textured {
        k |= kind::DIFFUSE;
    }
    k
}

/// The names of the vertex kinds in `kinds`, for reports.
pub fn describe(kinds: Kinds) -> String {
    let names = [
        (kind::LIGHT_DELTA, "Ld"),
        (kind::LIGHT_HIT, "La"),
        (kind::SPECULAR, "S"),
        (kind::GLOSSY, "G"),
        (kind::DIFFUSE, "D"),
        (kind::EYE, "E"),
    ];
    names
        .iter()
        .filter(|(k, _)| kinds & k != 0)
        .map(|(_, n)| *n)
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use kind::*;

    #[test]
    fn classes_parse_and_need_their_mandatory_vertices() {
        let pt = PathClass::parse("Ld S X* E").unwrap();
        assert!(pt.possible_with(LIGHT_DELTA | SPECULAR | EYE));
        assert!(!pt.possible_with(LIGHT_DELTA | DIFFUSE | GLOSSY | EYE));
        assert!(!pt.possible_with(LIGHT_HIT | SPECULAR | DIFFUSE | EYE));
        let bpt = PathClass::parse("Ld S+ ((D|G) S+)+ E").unwrap();
        assert!(bpt.possible_with(LIGHT_DELTA | SPECULAR | GLOSSY | EYE));
        assert!(!bpt.possible_with(LIGHT_DELTA | SPECULAR | EYE));
        let lt = PathClass::parse("L X* S E").unwrap();
        assert!(lt.possible_with(LIGHT_HIT | SPECULAR | EYE));
        assert!(!lt.possible_with(LIGHT_HIT | DIFFUSE | EYE));
        let optional = PathClass::parse("La G? E").unwrap();
        assert!(optional.possible_with(LIGHT_HIT | EYE));
    }

    #[test]
    fn a_class_knows_its_shortest_path() {
        for (text, segments) in [
            ("La E", 1),
            ("Ld S X* E", 2),
            ("L X* S E", 2),
            ("Ld S+ ((D|G) S+)+ E", 4),
            ("L X* (D|G) X* E", 2),
            ("La (S S | D) G? E", 2),
        ] {
            assert_eq!(PathClass::parse(text).unwrap().min_segments(), segments, "{text}");
        }
    }

    #[test]
    fn malformed_classes_say_what_is_wrong() {
        for (text, says) in [
            ("E S Ld", "must read from a light"),
            ("Ld Q E", "'Q' is not a vertex"),
            ("Ld (S E", "without its ')'"),
            ("Ld S | E", "from a light"),
            ("Ld S) E", "unexpected ')'"),
            ("Ld || E", "empty alternative"),
        ] {
            let e = PathClass::parse(text).unwrap_err().to_string();
            assert!(e.contains(says), "{text}: {e}");
        }
    }
}
