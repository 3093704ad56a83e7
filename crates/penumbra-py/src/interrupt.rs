//! Running library work from Python so that Ctrl-C stops it: the work runs on a scoped
//! thread with the GIL released while the calling thread polls `Python::check_signals` every
//! [`POLL`]; on a signal it sets the work's cancel flag, waits for the work to stop, and
//! raises the signal's exception (`KeyboardInterrupt` for Ctrl-C).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Mutex};
use std::time::Duration;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

/// How often the calling thread checks for signals while the work runs.
pub const POLL: Duration = Duration::from_millis(20);

/// Runs `work(cancel)` on a thread of its own with the GIL released, and returns its result,
/// or the exception of a signal that arrived meanwhile (after `cancel` was set and the work
/// returned).
pub fn interruptible<T: Send>(
    py: Python<'_>,
    work: impl FnOnce(&AtomicBool) -> T + Send,
) -> PyResult<T> {
    let cancel = AtomicBool::new(false);
    std::thread::scope(|scope| {
        let (tx, rx) = mpsc::channel::<T>();
        let cancel = &cancel;
        let worker = scope.spawn(move || {
            // The receiver only goes away after this thread is joined.
            let _ = tx.send(work(cancel));
        });
        // A receiver is not `Sync`: the mutex lets the GIL-free closure borrow it.
        let rx = Mutex::new(rx);
        let outcome = loop {
            let received = py.detach(|| match rx.lock() {
                Ok(rx) => rx.recv_timeout(POLL),
                Err(_) => Err(mpsc::RecvTimeoutError::Disconnected),
            });
            match received {
                Ok(out) => break py.check_signals().map(|()| out),
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    if let Err(e) = py.check_signals() {
                        cancel.store(true, Ordering::Relaxed);
                        break Err(e);
                    }
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    break Err(PyRuntimeError::new_err(
                        "the worker thread ended without a result",
                    ))
                }
            }
        };
        // Workers stop at their next chunk once cancelled; wait without holding the GIL.
        py.detach(|| worker.join())
            .map_err(|_| PyRuntimeError::new_err("the worker thread panicked"))?;
        outcome
    })
}
