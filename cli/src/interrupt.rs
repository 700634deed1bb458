//! Ctrl-C (SIGINT), and SIGTERM / SIGHUP, which schedulers such as Slurm send before they kill
//! a job (cancel, requeue, preemption, time limit): the first one stops the render within about
//! a second (between passes, or inside a pass for an integrator that polls its cancel flag: the
//! unfinished samples of that pass are dropped) and saves the partial image; a second one exits at once with
//! code 130 (outputs already written stay intact: every file is written to a temporary name and
//! renamed into place).

use furnace_render::CancelFlag;
use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};

/// Whether Ctrl-C has been pressed (cheap to poll between passes).
#[derive(Debug, Clone, Default)]
pub struct Interrupt {
    presses: Arc<AtomicU32>,
    /// Raised at the first press, for integrators that stop inside a pass.
    flag: CancelFlag,
}

impl Interrupt {
    /// Installs the process's handler of SIGINT (Ctrl-C), SIGTERM and SIGHUP. If that fails (another handler is
    /// installed), warns and returns an `Interrupt` that is never set: Ctrl-C then ends the
    /// process the default way.
    pub fn install() -> Self {
        let interrupt = Self::default();
        let presses = Arc::clone(&interrupt.presses);
        let flag = interrupt.flag.clone();
        let installed = ctrlc::set_handler(move || {
            // The handler runs on ctrlc's own thread, not in signal context: printing is fine.
            if presses.fetch_add(1, Ordering::SeqCst) == 0 {
                flag.raise();
                eprintln!("\ninterrupted: stopping the render, then saving (Ctrl-C again to quit at once)");
            } else {
                eprintln!("\ninterrupted twice: quitting without saving this render");
                // Nothing runs after this: remove the temporary files of a write in progress.
                furnace_post::remove_temporaries_in_flight();
                exit_now(130);
            }
        });
        if let Err(e) = installed {
            eprintln!("warning: Ctrl-C will not save a partial render: {e}");
        }
        interrupt
    }

    /// Whether Ctrl-C has been pressed since [`Interrupt::install`].
    pub fn requested(&self) -> bool {
        self.presses.load(Ordering::SeqCst) > 0
    }

    /// The flag the first press raises, to give an integrator
    /// ([`furnace_render::Integrator::set_cancel_flag`]).
    pub fn flag(&self) -> CancelFlag {
        self.flag.clone()
    }
}

/// Ends the process at once with `code`, running no exit handlers: other threads may be inside a
/// GPU driver, whose own exit handlers would tear it down under them.
fn exit_now(code: i32) -> ! {
    #[cfg(unix)]
    #[allow(unsafe_code)]
    // SAFETY: `_exit` takes no pointers, is async-signal-safe and does not return; the output
    // written so far is unbuffered (stderr) or complete (files are renamed into place whole).
    unsafe {
        libc::_exit(code)
    }
    #[cfg(not(unix))]
    std::process::exit(code)
}
