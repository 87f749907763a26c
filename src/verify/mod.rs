//! `lightgraph verify`: estimators checked against each other. Every estimator renders each
//! scene in batches ([`batches`]); every pair of estimators of the same quantity is compared
//! block by block and as a whole with the films' own noise ([`stats`]); and what each graph
//! declares it cannot sample ([`paths`]) predicts, from the scene's contents, which pairs may
//! differ. An unexpected difference fails, and so does an expected gap that does not appear
//! (the declaration is wrong); a pair the budget cannot decide is said to be so. The method and
//! its power are in docs/verify.md.

pub mod batches;
pub mod paths;
pub mod preset;
pub mod report;
pub mod stats;

use crate::run::{Run, specialization};
use anyhow::{Result, anyhow};
use lightgraph_engine::expr::Expr;
use lightgraph_engine::{ConstValue, Graph, Location};
use paths::{Kinds, PathClass};
use stats::{PairTest, Verdict};
use std::collections::BTreeMap;

/// The scenes `verify` checks when none are named: SmallVCM's five boxes (every lobe of its
/// materials; area, point and directional lights and a background) and Mitsuba's.
pub const DEFAULT_SCENES: &str = "cornell-diffuse,cornell-glossy-sun,cornell-glossy-mirrorball,cornell-glossy-point,cornell-glossy-background,cornell-mitsuba";

/// The estimators `verify` checks when none are named: every built-in graph of radiance in
/// its default layout, and VCM in both of its halves' other modes (connections alone,
/// LVC-BPT; merges alone, PBPM), and Metropolised VCM also without merges (Metropolised
/// LVC-BPT).
pub const DEFAULT_ESTIMATORS: &str = "pt,lt,bpt-naive,bpt-streaming,bpt-lvc,ppm,sppm,pbpm,vcm,vcm@VCM_MERGE=false,vcm@VCM_CONNECT=false,pssmlt,mmlt,mvcm,mvcm@VCM_MERGE=false,appm";

/// The quantity a graph estimates when its `coverage` names none.
pub const DEFAULT_QUANTITY: &str = "radiance";

/// A class of paths a graph declares something of (that it cannot sample them, or that their
/// estimate is biased at a finite budget), active under its constants.
#[derive(Debug, Clone)]
pub struct ClassClaim {
    /// The class as written.
    pub text: String,
    /// The class parsed.
    pub class: PathClass,
    /// Why, as the graph says it.
    pub why: String,
}

/// What a graph claims under its constants (its `coverage`).
#[derive(Debug, Clone)]
pub struct Claims {
    /// The quantity its output estimates.
    pub estimates: String,
    /// The path classes it cannot sample.
    pub misses: Vec<ClassClaim>,
    /// The path classes whose estimate is biased at a finite budget.
    pub biased: Vec<ClassClaim>,
    /// The most segments its paths have (its `MAX_PATH_LENGTH`; unlimited without one).
    pub segments: u32,
}

impl Claims {
    /// Whether a path of `class` has vertices of `kinds` alone and at most `segments` segments.
    fn reaches(class: &PathClass, kinds: Kinds, segments: u32) -> bool {
        class.possible_with(kinds) && class.min_segments() <= segments
    }

    /// Whether the estimate is biased on a scene whose paths have the vertex kinds `kinds`: a
    /// class declared biased has paths there that the graph samples.
    pub fn biased_with(&self, kinds: Kinds) -> bool {
        self.biased
            .iter()
            .any(|b| Claims::reaches(&b.class, kinds, self.segments))
    }
}

/// The constants a run renders with: its graph's, the scene's (its path-length limit), the
/// command line's (`--max-path-length`, `--set`), as the kernels see them.
pub fn run_constants(run: &Run) -> BTreeMap<String, ConstValue> {
    specialization(&run.graph, &run.scene.scene, &run.options, Default::default()).constants
}

/// What a graph with `constants` claims: the quantity it estimates, the path classes it
/// cannot sample and those it estimates with a bias, and its path-length limit
/// (`MAX_PATH_LENGTH`). A malformed class or condition is an error at its place in the graph
/// file.
pub fn claims(graph: &Graph, constants: &BTreeMap<String, ConstValue>) -> Result<Claims> {
    let coverage = &graph.declared.file.coverage;
    let text = graph.vfs.read(&graph.file).unwrap_or_default();
    let at = |name: &str| Location::of_name(&graph.file, &text, name);
    let mut vars: BTreeMap<String, f64> = graph.constants.iter().map(|(k, v)| (k.clone(), v.as_f64())).collect();
    vars.extend(constants.iter().map(|(k, v)| (k.clone(), v.as_f64())));
    let holds = |when: &Option<String>| -> Result<bool> {
        let Some(when) = when else { return Ok(true) };
        let value = Expr::parse(when)
            .and_then(|e| e.eval(&vars))
            .map_err(|e| anyhow!("{}: coverage: when: '{when}': {e}", at(when)))?;
        Ok(value != 0.0)
    };
    let active = |decls: Vec<(&String, &Option<String>, &String)>| -> Result<Vec<ClassClaim>> {
        let mut out = Vec::new();
        for (paths, when, why) in decls {
            if holds(when)? {
                let class = PathClass::parse(paths).map_err(|e| anyhow!("{}: coverage: {e}", at(paths)))?;
                out.push(ClassClaim {
                    text: paths.clone(),
                    class,
                    why: why.clone(),
                });
            }
        }
        Ok(out)
    };
    let misses = active(coverage.misses.iter().map(|m| (&m.paths, &m.when, &m.why)).collect())?;
    let biased = active(coverage.biased.iter().map(|b| (&b.paths, &b.when, &b.why)).collect())?;
    Ok(Claims {
        estimates: coverage
            .estimates
            .clone()
            .unwrap_or_else(|| DEFAULT_QUANTITY.to_string()),
        misses,
        biased,
        segments: vars.get("MAX_PATH_LENGTH").map_or(u32::MAX, |&n| n as u32),
    })
}

/// A class of paths one estimator cannot sample and another can, which may make them differ.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub struct Gap {
    /// The estimator that misses the paths.
    pub estimator: String,
    /// The class, as its graph declares it.
    pub class: String,
}

impl std::fmt::Display for Gap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} misses {}", self.estimator, self.class)
    }
}

/// The gaps that may make two estimators differ on a scene whose paths have the vertex kinds
/// `kinds`: the classes one of them misses and the other does not, where the scene has such
/// paths within the other's path-length limit.
pub fn expected_gaps(a: (&str, &Claims), b: (&str, &Claims), kinds: Kinds) -> Vec<Gap> {
    let one_way = |(name, of): (&str, &Claims), other: &Claims| {
        of.misses
            .iter()
            .filter(|m| {
                !other.misses.iter().any(|o| o.text == m.text) && Claims::reaches(&m.class, kinds, other.segments)
            })
            .map(|m| Gap {
                estimator: name.to_string(),
                class: m.text.clone(),
            })
            .collect::<Vec<_>>()
    };
    let mut gaps = one_way(a, b.1);
    gaps.extend(one_way(b, a.1));
    gaps
}

/// The gaps predicted somewhere in `pairs` that no pair showed: a declaration that claims more
/// than the graph misses (which would excuse real errors). A gap shows in a pair that differs
/// where all the gaps predicted for it are of one estimator.
pub fn unconfirmed_gaps(pairs: &[PairResult]) -> Vec<Gap> {
    let predicted: std::collections::BTreeSet<&Gap> = pairs.iter().flat_map(|p| &p.gaps).collect();
    let shown = |g: &Gap| {
        pairs.iter().any(|p| {
            p.test.verdict == Verdict::Differ && p.gaps.contains(g) && p.gaps.iter().all(|o| o.estimator == g.estimator)
        })
    };
    predicted.into_iter().filter(|g| !shown(g)).cloned().collect()
}

/// How a pair's verdict stands against the prediction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Agree where they should, or differ where a declared gap says they may.
    AsPredicted,
    /// They differ where nothing declared says they may: one of them is wrong.
    UnexpectedDifference,
    /// They agree where a declared gap says they may differ: the scene's paths of that class
    /// carry too little light to see here (a gap never seen in any pair is an error of the
    /// declaration: [`unconfirmed_gaps`]).
    GapNotSeen,
    /// The budget was too small to tell.
    Undecided,
}

impl Outcome {
    /// Of a verdict and whether a gap was expected.
    pub fn of(verdict: Verdict, gap_expected: bool) -> Outcome {
        match (verdict, gap_expected) {
            (Verdict::Agree, false) | (Verdict::Differ, true) => Outcome::AsPredicted,
            (Verdict::Differ, false) => Outcome::UnexpectedDifference,
            (Verdict::Agree, true) => Outcome::GapNotSeen,
            (Verdict::Undecided, _) => Outcome::Undecided,
        }
    }

    /// The word reports use.
    pub fn word(self) -> &'static str {
        match self {
            Outcome::AsPredicted => "ok",
            Outcome::UnexpectedDifference => "FAIL: unexpected difference",
            Outcome::GapNotSeen => "ok (gap not seen here)",
            Outcome::Undecided => "undecided",
        }
    }
}

/// One pair's result on one scene.
#[derive(Debug, Clone)]
pub struct PairResult {
    /// The scene.
    pub scene: String,
    /// The two estimators' labels.
    pub a: String,
    /// The second.
    pub b: String,
    /// The gaps that may make them differ here.
    pub gaps: Vec<Gap>,
    /// Blocks across the image (for naming a block by its column and row).
    pub grid_width: u32,
    /// The test.
    pub test: PairTest,
    /// The verdict against the prediction.
    pub outcome: Outcome,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::RunOptions;

    /// Coverage conditions and the path-length limit are the run's: the scene file's own
    /// `max_path_length` where no option gives one (not the graph's default), and
    /// `--max-path-length` over it.
    #[test]
    fn claims_see_the_runs_path_length_limit() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let dir = std::env::temp_dir().join(format!("lightgraph-claims-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let text = std::fs::read_to_string(root.join("scenes/cornell/cornell-diffuse.ron")).unwrap();
        let scene = dir.join("diffuse-short.ron");
        std::fs::write(&scene, text.replacen("max_path_length: 10", "max_path_length: 3", 1)).unwrap();
        // A graph that claims a gap only on paths of fewer than 5 segments.
        let graph = dir.join("pt-short.ron");
        let pt = std::fs::read_to_string(root.join("graphs/pt.ron")).unwrap();
        let short = pt.replacen(
            "(paths: \"Ld S X* E\",",
            "(paths: \"La E\", when: \"MAX_PATH_LENGTH < 5\",",
            1,
        );
        assert_ne!(pt, short);
        std::fs::write(&graph, short).unwrap();
        let claims_of = |max_path_length: Option<u32>| {
            let options = RunOptions {
                scene: Some(scene.display().to_string()),
                max_path_length,
                ..Default::default()
            };
            let run = Run::load(&options.spec(&graph.display().to_string(), None, 1)).unwrap();
            // What verify evaluated before: the command line's constants over the graph's.
            let options_alone = claims(&run.graph, &run.options.constants).unwrap();
            (claims(&run.graph, &run_constants(&run)).unwrap(), options_alone)
        };
        let (scenes, options_alone) = claims_of(None);
        assert_eq!(scenes.segments, 3);
        assert_eq!(scenes.misses.len(), 1, "the gap under the scene's limit");
        assert_eq!(options_alone.segments, 10, "the graph's default, not the scene's limit");
        assert!(options_alone.misses.is_empty());
        let (option, _) = claims_of(Some(7));
        assert_eq!(option.segments, 7);
        assert!(option.misses.is_empty(), "no gap at 7 segments");
    }
}
