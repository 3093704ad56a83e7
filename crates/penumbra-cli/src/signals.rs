//! Ctrl-C. While loading it ends the process at once (nothing is written yet); while rendering
//! it asks the renderer to stop, which then leaves no image either. All signal handling of the
//! command lives here.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use crate::failure::{note, Failure};

/// The interrupt state shared with the Ctrl-C handler.
pub struct Interrupt {
    cancel: Arc<AtomicBool>,
    rendering: Arc<AtomicBool>,
}

impl Interrupt {
    /// Installs the handler. If it cannot be installed, Ctrl-C keeps its default effect; the
    /// output is still never half-written since it is renamed into place only when complete.
    pub fn install() -> Interrupt {
        let cancel = Arc::new(AtomicBool::new(false));
        let rendering = Arc::new(AtomicBool::new(false));
        {
            let (cancel, rendering) = (cancel.clone(), rendering.clone());
            let _ = ctrlc::set_handler(move || {
                if rendering.load(Ordering::SeqCst) {
                    cancel.store(true, Ordering::SeqCst);
                } else {
                    note("error: interrupted; no image written");
                    std::process::exit(130);
                }
            });
        }
        Interrupt { cancel, rendering }
    }

    /// From now on Ctrl-C sets the cancel flag instead of ending the process.
    pub fn start_rendering(&self) {
        self.rendering.store(true, Ordering::SeqCst);
    }

    /// The flag the renderer polls.
    pub fn cancel_flag(&self) -> &AtomicBool {
        &self.cancel
    }

    /// An interrupt was asked for.
    pub fn is_set(&self) -> bool {
        self.cancel.load(Ordering::SeqCst)
    }

    /// `Err` when interrupted: exit code 130, no image.
    pub fn check(&self) -> Result<(), Failure> {
        if self.is_set() {
            Err(interrupted())
        } else {
            Ok(())
        }
    }
}

/// The failure of an interrupted run.
pub fn interrupted() -> Failure {
    Failure {
        code: 130,
        message: "interrupted; no image written".into(),
    }
}
