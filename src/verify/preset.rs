//! The power settings of `lightgraph verify` by name: `--preset lavapipe` for a software
//! rasteriser's budgets (the integration tests'), `--preset gpu` for a GPU's
//! (docs/performance.md's runs of every estimator against every other). A preset fills in
//! what the command line leaves out; an option given explicitly wins (docs/verify.md).

use super::batches::{Amount, Budget};
use std::time::Duration;

/// A named set of power settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Preset {
    /// Lavapipe (Mesa's software Vulkan): 32 x 32 pixels, 2 samples per pixel, 128 frames
    /// in 16 batches, blocks of 8, the power to see 7% of the image mean and 25% in the
    /// blocks holding 75% of the light.
    Lavapipe,
    /// A GPU: 256 x 256 pixels, 4 s an estimator and scene in 16 batches, blocks of 16, the
    /// power to see 1% of the image mean and 10% in the blocks holding 90% of the light.
    Gpu,
}

/// The settings that decide a run's budget and its test's power.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Power {
    /// Image size (`None`: each scene's own).
    pub res: Option<(u32, u32)>,
    /// Samples per pixel a frame (`None`: the renderer's default).
    pub spp: Option<u32>,
    /// Rendering time or frames of each estimator on each scene.
    pub amount: Amount,
    /// Batches a run is split into.
    pub batches: u32,
    /// Side of the blocks compared, in pixels.
    pub block: u32,
    /// Relative difference of the image means the test must see for "agree".
    pub detect_mean: f64,
    /// Relative difference of a block the test must see ...
    pub detect_block: f64,
    /// ... in the blocks holding this fraction of the light.
    pub coverage: f64,
}

/// `verify`'s settings without a preset: 10 s each, the scenes' sizes, 16 batches, blocks of
/// 16, the power to see 1% of the image mean and 10% in the blocks holding 90% of the light.
pub const DEFAULT: Power = Power {
    res: None,
    spp: None,
    amount: Amount::Time(Duration::from_secs(10)),
    batches: 16,
    block: 16,
    detect_mean: 0.01,
    detect_block: 0.1,
    coverage: 0.9,
};

impl Preset {
    /// The preset `--preset` names `name` (`lavapipe` or `gpu`); else the names it takes.
    pub fn named(name: &str) -> Result<Preset, String> {
        <Preset as clap::ValueEnum>::from_str(name, false).map_err(|_| {
            let names: Vec<String> = <Preset as clap::ValueEnum>::value_variants()
                .iter()
                .filter_map(clap::ValueEnum::to_possible_value)
                .map(|v| format!("'{}'", v.get_name()))
                .collect();
            format!("it must be one of {}", names.join(", "))
        })
    }

    /// The preset's settings.
    pub fn power(self) -> Power {
        match self {
            Preset::Lavapipe => Power {
                res: Some((32, 32)),
                spp: Some(2),
                amount: Amount::Frames(128),
                batches: 16,
                block: 8,
                detect_mean: 0.07,
                detect_block: 0.25,
                coverage: 0.75,
            },
            Preset::Gpu => Power {
                res: Some((256, 256)),
                amount: Amount::Time(Duration::from_secs(4)),
                ..DEFAULT
            },
        }
    }
}

/// The settings given on a command line, each `None` where it is left out.
#[derive(Debug, Clone, Copy, Default)]
pub struct Given {
    /// `--res`.
    pub res: Option<(u32, u32)>,
    /// `--spp`.
    pub spp: Option<u32>,
    /// `--time` or `--frames`.
    pub amount: Option<Amount>,
    /// `--batches`.
    pub batches: Option<u32>,
    /// `--block`.
    pub block: Option<u32>,
    /// `--detect-mean`.
    pub detect_mean: Option<f64>,
    /// `--detect-block`.
    pub detect_block: Option<f64>,
    /// `--coverage`.
    pub coverage: Option<f64>,
}

impl Given {
    /// The settings a run uses: each given one, else the preset's, else the default's.
    pub fn resolve(&self, preset: Option<Preset>) -> Power {
        let base = preset.map_or(DEFAULT, Preset::power);
        Power {
            res: self.res.or(base.res),
            spp: self.spp.or(base.spp),
            amount: self.amount.unwrap_or(base.amount),
            batches: self.batches.unwrap_or(base.batches),
            block: self.block.unwrap_or(base.block),
            detect_mean: self.detect_mean.unwrap_or(base.detect_mean),
            detect_block: self.detect_block.unwrap_or(base.detect_block),
            coverage: self.coverage.unwrap_or(base.coverage),
        }
    }
}

impl Power {
    /// The budget of each run.
    pub fn budget(&self) -> Budget {
        Budget {
            amount: self.amount,
            batches: self.batches,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_preset_fills_in_what_is_not_given_and_an_explicit_option_wins() {
        let lavapipe = Given::default().resolve(Some(Preset::Lavapipe));
        assert_eq!(lavapipe.res, Some((32, 32)));
        assert_eq!(lavapipe.spp, Some(2));
        assert!(matches!(lavapipe.amount, Amount::Frames(128)));
        assert_eq!((lavapipe.batches, lavapipe.block), (16, 8));
        assert_eq!(
            (lavapipe.detect_mean, lavapipe.detect_block, lavapipe.coverage),
            (0.07, 0.25, 0.75)
        );
        let given = Given {
            amount: Some(Amount::Time(Duration::from_secs(3))),
            block: Some(4),
            detect_mean: Some(0.5),
            ..Given::default()
        };
        let mixed = given.resolve(Some(Preset::Lavapipe));
        assert!(matches!(mixed.amount, Amount::Time(t) if t == Duration::from_secs(3)));
        assert_eq!((mixed.block, mixed.detect_mean), (4, 0.5));
        assert_eq!((mixed.res, mixed.detect_block), (Some((32, 32)), 0.25));
        let gpu = Given::default().resolve(Some(Preset::Gpu));
        assert_eq!(gpu.res, Some((256, 256)));
        assert!(matches!(gpu.amount, Amount::Time(t) if t == Duration::from_secs(4)));
        // Without a preset, the defaults.
        assert_eq!(Given::default().resolve(None), DEFAULT);
    }

    #[test]
    fn a_preset_is_named_as_the_command_line_names_it() {
        assert_eq!(Preset::named("lavapipe"), Ok(Preset::Lavapipe));
        assert_eq!(Preset::named("gpu"), Ok(Preset::Gpu));
        assert_eq!(Preset::named("GPU"), Err("it must be one of 'lavapipe', 'gpu'".into()));
    }
}
