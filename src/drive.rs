//! The one render driver: every command that renders frames (render, reference, compare,
//! study, verify, stress, bench, aov, `--gpus`, `--mpi`, Python) hands the driver an executor
//! (what renders: one GPU's session, several GPUs, MPI ranks), a budget (frames or time) and
//! observers (progress, checkpoints, the error curve, the live view), and the driver runs the
//! frame loop: it renders in batches toward the budget, lets every observer see each batch,
//! and stops at the budget or at a signal (Ctrl-C), after the frames in flight.

use crate::interrupt::{self, Interrupted, Signal};
use crate::run::Session;
use anyhow::Result;
use std::time::{Duration, Instant};

/// How much to render: a number of frames, or a time on the driver's clock.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Budget {
    /// Frames in all.
    Frames(u64),
    /// Time on the clock.
    Time(Duration),
}

/// A clock that observers may stop while they work off the budget (measuring an error, say).
#[derive(Debug, Clone)]
pub struct Stopwatch {
    running_since: Option<Instant>,
    banked: Duration,
}

impl Stopwatch {
    /// A running clock started now.
    pub fn start() -> Stopwatch {
        Stopwatch::started_at(Instant::now())
    }

    /// A running clock started at `start`.
    pub fn started_at(start: Instant) -> Stopwatch {
        Stopwatch {
            running_since: Some(start),
            banked: Duration::ZERO,
        }
    }

    /// Stops the clock (no-op if stopped).
    pub fn pause(&mut self) {
        if let Some(t) = self.running_since.take() {
            self.banked += t.elapsed();
        }
    }

    /// Runs the clock again (no-op if running).
    pub fn resume(&mut self) {
        self.running_since.get_or_insert_with(Instant::now);
    }

    /// Time on the clock.
    pub fn elapsed(&self) -> Duration {
        self.banked + self.running_since.map_or(Duration::ZERO, |t| t.elapsed())
    }

    /// Seconds on the clock.
    pub fn seconds(&self) -> f64 {
        self.elapsed().as_secs_f64()
    }
}

/// What renders frames for the driver.
pub trait Executor {
    /// Frames submitted so far (the driver counts a frame budget from its value at the start).
    fn frames(&self) -> u64;
    /// Renders at most `max` more frames, and (when `left` is given) no more than fill that
    /// time; may return with frames still in flight.
    fn advance(&mut self, left: Option<Duration>, max: u64) -> Result<()>;
    /// Waits for the frames in flight.
    fn settle(&mut self) -> Result<()>;

    /// Whether the drive is over, before its next batch: by default when `plan`'s budget is
    /// spent (`done` frames rendered in it, the clock's time) or a signal arrived; an
    /// executor whose devices or processes share the budget among themselves decides with
    /// them.
    fn ended(&self, plan: &Plan, done: u64, clock: &Stopwatch) -> Option<Ended> {
        plan.ended(done, clock)
    }
}

impl Executor for Session<'_> {
    fn frames(&self) -> u64 {
        self.frames as u64
    }

    fn advance(&mut self, left: Option<Duration>, max: u64) -> Result<()> {
        self.render_for(left, u32::try_from(max).unwrap_or(u32::MAX))?;
        Ok(())
    }

    fn settle(&mut self) -> Result<()> {
        Session::settle(self)?;
        Ok(())
    }
}

/// Something that watches a drive: it sees the executor after every batch.
pub trait Observer<E: ?Sized> {
    /// Called after every batch with the executor and the clock.
    fn batch(&mut self, exec: &mut E, clock: &mut Stopwatch) -> Result<()>;

    /// The clock's seconds at which this observer next wants to see the executor: the driver
    /// ends its batch there (an error curve's sample times).
    fn due(&self) -> Option<f64> {
        None
    }
}

/// Any closure over the executor and the clock is an observer.
impl<E: ?Sized, F: FnMut(&mut E, &mut Stopwatch) -> Result<()>> Observer<E> for F {
    fn batch(&mut self, exec: &mut E, clock: &mut Stopwatch) -> Result<()> {
        self(exec, clock)
    }
}

/// A drive's plan: the budget and how batches are cut.
#[derive(Debug, Clone, Copy)]
pub struct Plan {
    /// When to stop.
    pub budget: Budget,
    /// A timed drive renders at least this many frames, however short its time.
    pub min_frames: u64,
    /// No batch holds more frames than this (None: the executor chooses).
    pub step_frames: Option<u64>,
}

impl Plan {
    /// A plan of `budget` with the executor's batches and no minimum.
    pub fn new(budget: Budget) -> Plan {
        Plan {
            budget,
            min_frames: 0,
            step_frames: None,
        }
    }

    /// The plan with at least `n` frames in a timed drive.
    pub fn at_least(self, n: u64) -> Plan {
        Plan { min_frames: n, ..self }
    }

    /// The plan with batches of at most `n` frames.
    pub fn in_steps_of(self, n: u64) -> Plan {
        Plan {
            step_frames: Some(n),
            ..self
        }
    }
}

impl Plan {
    /// Whether a drive of this plan with `done` frames rendered is over on `clock`: its
    /// budget spent, or a signal arrived.
    pub fn ended(&self, done: u64, clock: &Stopwatch) -> Option<Ended> {
        let spent = match self.budget {
            Budget::Frames(n) => done >= n,
            Budget::Time(t) => clock.elapsed() >= t && done >= self.min_frames,
        };
        if spent {
            return Some(Ended::Done);
        }
        interrupt::requested().map(Ended::Signal)
    }
}

/// How a drive ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ended {
    /// The budget was spent.
    Done,
    /// A signal stopped it after the frames in flight.
    Signal(Signal),
}

impl Ended {
    /// For a drive whose partial result means nothing (a verify batch, a benchmark): an
    /// error ([`Interrupted`], saying `what` was dropped) if a signal ended it.
    pub fn whole(self, what: &str) -> Result<()> {
        match self {
            Ended::Done => Ok(()),
            Ended::Signal(signal) => Err(Interrupted {
                signal,
                what: format!("{what} dropped"),
            }
            .into()),
        }
    }
}

/// Renders with `exec` until `plan`'s budget is spent on `clock` or a signal arrives, letting
/// every observer see each batch; waits for the frames in flight before it returns.
pub fn drive<E: Executor + ?Sized>(
    exec: &mut E,
    plan: Plan,
    clock: &mut Stopwatch,
    observers: &mut [&mut dyn Observer<E>],
) -> Result<Ended> {
    let first = exec.frames();
    let ended = loop {
        let (done, seconds) = (exec.frames() - first, clock.seconds());
        if let Some(ended) = exec.ended(&plan, done, clock) {
            break ended;
        }
        let until = observers
            .iter()
            .filter_map(|o| o.due())
            .chain(match plan.budget {
                Budget::Time(t) => Some(t.as_secs_f64()),
                Budget::Frames(_) => None,
            })
            .reduce(f64::min);
        let left = until.map(|u| Duration::from_secs_f64((u - seconds).max(1e-3)));
        let max = match plan.budget {
            Budget::Frames(n) => n - done,
            Budget::Time(_) => u64::MAX,
        };
        exec.advance(left, plan.step_frames.map_or(max, |s| s.min(max)))?;
        for o in observers.iter_mut() {
            o.batch(exec, clock)?;
        }
    };
    exec.settle()?;
    Ok(ended)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An executor of frames that take `per_frame` of the clock each, rendered at once.
    struct Fake {
        frames: u64,
        batches: Vec<u64>,
        max_batch: u64,
    }

    impl Executor for Fake {
        fn frames(&self) -> u64 {
            self.frames
        }
        fn advance(&mut self, _left: Option<Duration>, max: u64) -> Result<()> {
            let n = max.min(self.max_batch);
            self.frames += n;
            self.batches.push(n);
            Ok(())
        }
        fn settle(&mut self) -> Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_frame_budget_renders_exactly_its_frames_in_the_steps_asked() {
        let mut fake = Fake {
            frames: 3,
            batches: Vec::new(),
            max_batch: 4,
        };
        let mut seen = 0;
        let mut count = |_: &mut Fake, _: &mut Stopwatch| -> Result<()> {
            seen += 1;
            Ok(())
        };
        let plan = Plan::new(Budget::Frames(10)).in_steps_of(3);
        let ended = drive(&mut fake, plan, &mut Stopwatch::start(), &mut [&mut count]).unwrap();
        assert_eq!(ended, Ended::Done);
        assert_eq!(fake.frames, 13, "ten frames after the three before");
        assert_eq!(fake.batches, vec![3, 3, 3, 1]);
        assert_eq!(seen, 4, "the observer sees every batch");
    }

    #[test]
    fn a_spent_time_budget_still_renders_the_minimum() {
        let mut fake = Fake {
            frames: 0,
            batches: Vec::new(),
            max_batch: 1,
        };
        let plan = Plan::new(Budget::Time(Duration::ZERO)).at_least(2);
        drive(&mut fake, plan, &mut Stopwatch::start(), &mut []).unwrap();
        assert_eq!(fake.frames, 2);
        let mut none = Fake {
            frames: 0,
            batches: Vec::new(),
            max_batch: 1,
        };
        drive(
            &mut none,
            Plan::new(Budget::Time(Duration::ZERO)),
            &mut Stopwatch::start(),
            &mut [],
        )
        .unwrap();
        assert_eq!(none.frames, 0);
    }

    /// An observer that wants to see the executor at 0.5 s of a clock that does not run.
    struct Due(Vec<Option<Duration>>);

    impl Observer<Probe> for Due {
        fn batch(&mut self, exec: &mut Probe, _: &mut Stopwatch) -> Result<()> {
            self.0.push(exec.left);
            Ok(())
        }
        fn due(&self) -> Option<f64> {
            Some(0.5)
        }
    }

    /// An executor that records the time it was given, one frame a batch.
    struct Probe {
        frames: u64,
        left: Option<Duration>,
    }

    impl Executor for Probe {
        fn frames(&self) -> u64 {
            self.frames
        }
        fn advance(&mut self, left: Option<Duration>, _max: u64) -> Result<()> {
            self.left = left;
            self.frames += 1;
            Ok(())
        }
        fn settle(&mut self) -> Result<()> {
            Ok(())
        }
    }

    #[test]
    fn batches_end_where_an_observer_is_due() {
        let mut clock = Stopwatch::start();
        clock.pause();
        let mut probe = Probe { frames: 0, left: None };
        let mut due = Due(Vec::new());
        drive(&mut probe, Plan::new(Budget::Frames(2)), &mut clock, &mut [&mut due]).unwrap();
        // The clock ran for a moment before it stopped.
        assert_eq!(due.0.len(), 2);
        for left in &due.0 {
            let left = left.expect("a time").as_secs_f64();
            assert!((0.499..=0.5).contains(&left), "{left}");
        }
        let mut timed = Probe { frames: 0, left: None };
        let plan = Plan::new(Budget::Time(Duration::from_secs(3))).in_steps_of(1);
        // A stopped clock never spends the time: stop by frames through the observer's error.
        let mut stop = |p: &mut Probe, _: &mut Stopwatch| -> Result<()> {
            anyhow::ensure!(p.frames < 2, "stop");
            Ok(())
        };
        assert!(drive(&mut timed, plan, &mut clock, &mut [&mut stop]).is_err());
        let left = timed.left.expect("a time").as_secs_f64();
        assert!(
            (2.999..=3.0).contains(&left),
            "the budget's end when none is due: {left}"
        );
    }
}
