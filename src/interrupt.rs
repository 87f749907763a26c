//! Interruptions: SIGINT (Ctrl-C) and SIGTERM (what Slurm and Kubernetes send before they
//! stop a job) ask a long run to stop at the end of the frame in flight, keep what it has
//! done and exit non-zero. A second signal of either kind ends the process at once, without
//! writing: the files hold what the last checkpoint wrote (each file is written whole or not
//! at all). Both are said on stderr as they arrive. Only the commands that keep work this way
//! install the handlers (`Cli::keeps_work_on_signal`); the others end at the first signal.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A signal that asked the run to stop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Signal {
    /// SIGINT (Ctrl-C).
    Interrupt,
    /// SIGTERM.
    Terminate,
}

impl Signal {
    /// The signal's name.
    pub fn name(self) -> &'static str {
        match self {
            Signal::Interrupt => "SIGINT",
            Signal::Terminate => "SIGTERM",
        }
    }

    /// The exit status of a process the signal stopped (128 + its number, as shells report).
    pub fn exit_code(self) -> u8 {
        match self {
            Signal::Interrupt => 130,
            Signal::Terminate => 143,
        }
    }
}

/// The error a run returns when a signal stopped it after it kept its work: `what` says what
/// was written.
#[derive(Debug, thiserror::Error)]
#[error("interrupted by {}: {what}", signal.name())]
pub struct Interrupted {
    /// The signal.
    pub signal: Signal,
    /// What the run kept (the files written).
    pub what: String,
}

/// Which signal arrived: 0 none, 1 SIGINT, 2 SIGTERM.
fn received() -> &'static AtomicUsize {
    static RECEIVED: AtomicUsize = AtomicUsize::new(0);
    &RECEIVED
}

/// Installs the handlers (once; later calls do nothing): a thread that takes the signals,
/// says on stderr what each does, records the first and ends the process at the second. Until
/// then signals keep their default action, which ends the process.
pub fn install() -> std::io::Result<()> {
    static INSTALLED: OnceLock<()> = OnceLock::new();
    if INSTALLED.get().is_some() {
        return Ok(());
    }
    use signal_hook::consts::{SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM])?;
    std::thread::Builder::new().name("signals".into()).spawn(move || {
        for number in signals.forever() {
            let signal = match number {
                SIGINT => Signal::Interrupt,
                _ => Signal::Terminate,
            };
            take(signal);
        }
    })?;
    let _ = INSTALLED.set(());
    Ok(())
}

/// Takes a signal: the first is recorded for the run to stop at the end of its frame, the
/// second ends the process with its status, each said on stderr.
fn take(signal: Signal) {
    let value = match signal {
        Signal::Interrupt => 1,
        Signal::Terminate => 2,
    };
    match received().compare_exchange(0, value, Ordering::SeqCst, Ordering::SeqCst) {
        Ok(_) => eprintln!(
            "\n{}: stopping after the frame in flight and writing what the run has (a second Ctrl-C \
             exits at once without writing)",
            signal.name()
        ),
        Err(_) => {
            eprintln!(
                "\nsecond signal ({}): exiting at once without writing; the files on disk hold the last \
                 checkpoint",
                signal.name()
            );
            signal_hook::low_level::exit(i32::from(signal.exit_code()));
        }
    }
}

/// The signal that asked the run to stop, if one did.
pub fn requested() -> Option<Signal> {
    match received().load(Ordering::SeqCst) {
        1 => Some(Signal::Interrupt),
        2 => Some(Signal::Terminate),
        _ => None,
    }
}

/// Asks the runs in progress to stop at the end of the frame in flight, as `signal` arriving
/// would: for hosts that see signals themselves rather than through [`install`]'s handlers
/// (Python, whose interpreter turns Ctrl-C into `KeyboardInterrupt`).
pub fn request(signal: Signal) {
    let value = match signal {
        Signal::Interrupt => 1,
        Signal::Terminate => 2,
    };
    received().store(value, Ordering::SeqCst);
}

/// Forgets a [`request`] once its run has stopped, so that the next run goes on.
pub fn clear() {
    received().store(0, Ordering::SeqCst);
}

/// The exit status for an error: a signal's status for [`Interrupted`], 1 otherwise.
pub fn exit_code(error: &anyhow::Error) -> u8 {
    error.downcast_ref::<Interrupted>().map_or(1, |i| i.signal.exit_code())
}

/// After a run wrote `what`: an [`Interrupted`] error if a signal stopped it (so the command
/// exits with the signal's status), else Ok.
pub fn stopped_by_signal(what: String) -> anyhow::Result<()> {
    match requested() {
        Some(signal) => Err(Interrupted { signal, what }.into()),
        None => Ok(()),
    }
}
