//! `lightgraph verify`: estimators checked against each other. Every estimator renders each
//! scene in batches ([`batches`]); every pair of estimators of the same quantity is compared
//! block by block and as a whole with the films' own noise ([`stats`]); and what each graph
//! declares it cannot sample ([`paths`]) predicts, from the scene's contents, which pairs may
//! differ. An unexpected difference fails, and so does an expected gap that does not appear
//! (the declaration is wrong); a pair the budget cannot decide is said to be so. The method and
//! its power are in docs/verify.md.

pub mod batches;
pub mod paths;
pub mod report;
pub mod stats;

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

/// A class of paths a graph declares it cannot sample, active under its constants.
#[derive(Debug, Clone)]
pub struct Miss {
    /// The class as written.
    pub text: String,
    /// The class parsed.
    pub class: PathClass,
    /// Why the graph cannot sample it.
    pub why: String,
}

/// What a graph claims under its constants (its `coverage`).
#[derive(Debug, Clone)]
pub struct Claims {
    /// The quantity its output estimates.
    pub estimates: String,
    /// The path classes it cannot sample.
    pub misses: Vec<Miss>,
    /// Why its estimate is biased at a finite budget, if it is.
    pub bias: Option<String>,
}

/// What a graph with `constants` claims: the quantity it estimates, the path classes it
/// cannot sample and its bias. A malformed class or condition is an error at its place in the
/// graph file.
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
    let mut misses = Vec::new();
    for m in &coverage.misses {
        if !holds(&m.when)? {
            continue;
        }
        let class = PathClass::parse(&m.paths).map_err(|e| anyhow!("{}: coverage: {e}", at(&m.paths)))?;
        misses.push(Miss {
            text: m.paths.clone(),
            class,
            why: m.why.clone(),
        });
    }
    let bias = match &coverage.biased {
        Some(b) if holds(&b.when)? => Some(b.why.clone()),
        _ => None,
    };
    Ok(Claims {
        estimates: coverage
            .estimates
            .clone()
            .unwrap_or_else(|| DEFAULT_QUANTITY.to_string()),
        misses,
        bias,
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
/// paths.
pub fn expected_gaps(a: (&str, &[Miss]), b: (&str, &[Miss]), kinds: Kinds) -> Vec<Gap> {
    let one_way = |(name, of): (&str, &[Miss]), other: &[Miss]| {
        of.iter()
            .filter(|m| !other.iter().any(|o| o.text == m.text) && m.class.possible_with(kinds))
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
