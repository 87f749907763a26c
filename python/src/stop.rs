//! Ctrl-C while the GPU works: the work runs on a thread of its own with the interpreter
//! released while the caller's thread checks for signals every 100 ms. A signal
//! asks the work to stop at the end of the frame in flight, as the CLI's Ctrl-C does (the
//! library's interrupt flag); the work keeps what it has done (a session its film, a reference
//! or a comparison its files) and the caller gets the signal's exception (`KeyboardInterrupt`
//! for Ctrl-C) saying what was kept, never a panic or a lost film.

use ::lightgraph::interrupt::{self, Interrupted, Signal};
use pyo3::exceptions::PyKeyboardInterrupt;
use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::Thread;
use std::time::{Duration, Instant};

/// How often the caller's thread looks for signals.
const POLL: Duration = Duration::from_millis(100);

/// How a piece of work ended.
pub enum Ended<T> {
    /// It finished, with its result.
    Done(anyhow::Result<T>),
    /// A signal stopped it: the signal's exception and what the work returned when it stopped.
    Stopped(PyErr, anyhow::Result<T>),
}

/// Runs `work` on its own thread with the interpreter released, asking it to stop (through
/// the library's interrupt flag, which every run checks between frames) when a signal's
/// handler raises; returns how it ended, the flag cleared again.
pub fn run<T: Send>(py: Python<'_>, work: impl FnOnce() -> anyhow::Result<T> + Send) -> Ended<T> {
    let done = AtomicBool::new(false);
    let caller = std::thread::current();
    std::thread::scope(|scope| {
        let worker = scope.spawn(|| {
            let _wake = Wake(&done, caller);
            work()
        });
        let mut raised: Option<PyErr> = None;
        while !worker.is_finished() {
            py.detach(|| {
                let started = Instant::now();
                while !done.load(Ordering::SeqCst) && started.elapsed() < POLL {
                    std::thread::park_timeout(POLL.saturating_sub(started.elapsed()));
                }
            });
            if raised.is_none()
                && let Err(e) = py.check_signals()
            {
                interrupt::request(Signal::Interrupt);
                raised = Some(e);
            }
        }
        let result = worker
            .join()
            .unwrap_or_else(|panic| Err(anyhow::anyhow!("the work panicked: {}", panic_text(&panic))));
        match raised {
            Some(e) => {
                interrupt::clear();
                Ended::Stopped(e, result)
            }
            None => Ended::Done(result),
        }
    })
}

/// Marks the work done and wakes the caller's thread when the work ends (returning or
/// panicking).
struct Wake<'a>(&'a AtomicBool, Thread);

impl Drop for Wake<'_> {
    fn drop(&mut self) {
        self.0.store(true, Ordering::SeqCst);
        self.1.unpark();
    }
}

/// `work` run by [`run`], its errors as `lightgraph.Error`; a signal's exception when one
/// stopped it (for Ctrl-C, `KeyboardInterrupt` with what the work kept).
pub fn interruptible<T: Send>(py: Python<'_>, work: impl FnOnce() -> anyhow::Result<T> + Send) -> PyResult<T> {
    match run(py, work) {
        Ended::Done(result) => result.map_err(crate::err),
        Ended::Stopped(e, result) => {
            let kept = match &result {
                Ok(_) => "it had finished".to_string(),
                Err(e) => match e.downcast_ref::<Interrupted>() {
                    Some(i) => i.what.clone(),
                    None => format!("it failed: {e:#}"),
                },
            };
            Err(stopped(py, e, &kept))
        }
    }
}

/// The signal's exception `e`; a `KeyboardInterrupt` says `kept` (what the work kept).
pub fn stopped(py: Python<'_>, e: PyErr, kept: &str) -> PyErr {
    match e.is_instance_of::<PyKeyboardInterrupt>(py) {
        true => PyKeyboardInterrupt::new_err(format!("stopped at Ctrl-C: {kept}")),
        false => e,
    }
}

/// A panic's message.
fn panic_text(panic: &Box<dyn std::any::Any + Send>) -> String {
    match (panic.downcast_ref::<&str>(), panic.downcast_ref::<String>()) {
        (Some(s), _) => s.to_string(),
        (_, Some(s)) => s.clone(),
        _ => "no message".to_string(),
    }
}
