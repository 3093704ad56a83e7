//! Signals that ask the program to stop: SIGINT (Ctrl-C), SIGTERM and SIGHUP.
//!
//! Until [`Interrupt::defer`] is called (while the scene loads, before anything is written) a
//! signal ends the process at once. From then on it only sets the cancel flag, which the
//! renderer checks before every sample and the image writer before every write and before its
//! final rename: the run ends within one sample with no image and no temporary file, or, if
//! the image was already renamed into place, with the new image complete.
//!
//! The exit code is the shells' convention for a process stopped by a signal, 128 + its
//! number: 130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP. On systems without these signals
//! only Ctrl-C is caught, with 130.

use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};
use std::sync::Arc;

use crate::failure::Failure;

/// The exit code of a run stopped by Ctrl-C.
const SIGINT_CODE: u8 = 130;

/// The state a signal handler shares with the main thread.
#[derive(Default)]
struct Shared {
    /// Set by the first signal; read by the renderer and the image writer.
    cancel: AtomicBool,
    /// The number of the last signal received (0: none yet).
    signal: AtomicI32,
    /// Whether a signal only sets `cancel` (true) or ends the process (false).
    deferred: AtomicBool,
}

/// A handle on the interrupting signals, made once at start-up by [`Interrupt::install`].
pub struct Interrupt {
    shared: Arc<Shared>,
}

impl Interrupt {
    /// Catches SIGINT, SIGTERM and SIGHUP from now on. If the handler cannot be installed, the
    /// signals keep their default effect; an image is still never half-written, since it is
    /// renamed into place only when complete.
    pub fn install() -> Interrupt {
        let shared = Arc::new(Shared::default());
        let handler = shared.clone();
        listen(move |signal| {
            handler.signal.store(signal, Ordering::SeqCst);
            if handler.deferred.load(Ordering::SeqCst) {
                handler.cancel.store(true, Ordering::SeqCst);
            } else {
                crate::failure::note(&format!("error: {}; no image written", describe(signal)));
                std::process::exit(exit_code(signal).into());
            }
        });
        Interrupt { shared }
    }

    /// From now on a signal only sets [`Interrupt::flag`]; the caller checks it.
    pub fn defer(&self) {
        self.shared.deferred.store(true, Ordering::SeqCst);
    }

    /// The flag a deferred signal sets.
    pub fn flag(&self) -> &AtomicBool {
        &self.shared.cancel
    }

    /// `Err` once a signal has been received: the run's failure, with no image.
    pub fn check(&self) -> Result<(), Failure> {
        if self.flag().load(Ordering::SeqCst) {
            Err(self.failure())
        } else {
            Ok(())
        }
    }

    /// The failure of a run that a signal stopped.
    pub fn failure(&self) -> Failure {
        let (code, message) = self.report();
        Failure { code, message }
    }

    /// The exit code and message for the signal received.
    pub fn report(&self) -> (u8, String) {
        let signal = self.shared.signal.load(Ordering::SeqCst);
        (
            exit_code(signal),
            format!("{}; no image written", describe(signal)),
        )
    }
}

/// 128 + the signal's number, as shells report a process a signal stopped.
fn exit_code(signal: i32) -> u8 {
    u8::try_from(128 + signal)
        .ok()
        .filter(|_| signal > 0)
        .unwrap_or(SIGINT_CODE)
}

/// "interrupted (SIGTERM)", or plain "interrupted" for Ctrl-C.
fn describe(signal: i32) -> String {
    match signal_name(signal) {
        Some(name) if name != "SIGINT" => format!("interrupted ({name})"),
        _ => "interrupted".to_owned(),
    }
}

#[cfg(unix)]
fn signal_name(signal: i32) -> Option<&'static str> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    match signal {
        SIGINT => Some("SIGINT"),
        SIGTERM => Some("SIGTERM"),
        SIGHUP => Some("SIGHUP"),
        _ => None,
    }
}

#[cfg(not(unix))]
fn signal_name(_signal: i32) -> Option<&'static str> {
    None
}

/// Calls `on_signal` with the signal's number, on a thread of its own (so it may do anything,
/// unlike a signal handler), for every SIGINT, SIGTERM and SIGHUP.
#[cfg(unix)]
fn listen(on_signal: impl Fn(i32) + Send + 'static) {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
        return;
    };
    let _ = std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            for signal in signals.forever() {
                on_signal(signal);
            }
        });
}

/// Calls `on_signal` with SIGINT's number (2) for every Ctrl-C.
#[cfg(not(unix))]
fn listen(on_signal: impl Fn(i32) + Send + 'static) {
    let _ = ctrlc::set_handler(move || on_signal(2));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exit_codes_follow_the_shell_convention() {
        assert_eq!(exit_code(2), 130);
        assert_eq!(exit_code(15), 143);
        assert_eq!(exit_code(1), 129);
        // Unknown: as Ctrl-C.
        assert_eq!(exit_code(0), 130);
        assert_eq!(exit_code(500), 130);
    }

    #[cfg(unix)]
    #[test]
    fn messages_say_interrupted_and_name_other_signals() {
        assert_eq!(describe(2), "interrupted");
        assert_eq!(describe(15), "interrupted (SIGTERM)");
        assert_eq!(describe(1), "interrupted (SIGHUP)");
    }
}
