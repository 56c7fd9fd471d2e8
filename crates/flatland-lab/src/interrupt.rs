//! Ctrl-C for every command: one flag, set by a handler installed once in `main`.
//!
//! Long loops poll [`requested`] (the training loop through its progress callback, the kernel
//! grid between chunks, the bench between runs, `results` between experiments) and end with an
//! [`Interrupted`] error that says what was kept; `main` prints it and exits with 130.
//!
//! Some phases cannot poll: a reference grid being computed, the least-squares refit, one
//! baseline run. So the handler also waits a grace period (0.7 s): if no loop has taken the
//! interrupt by then, it exits itself, printing the command's last [`keep`] note (what is on disk
//! right now). Writes go through [`writing`], which the handler waits for, so an exit never cuts a
//! file in half or leaves a temporary file behind. A second Ctrl-C exits at once (still after a
//! running write). [`train_to_end`] trains a fit under the same flag.

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::time::Duration;

/// Exit code of an interrupted command (128 + SIGINT), as shells report it.
pub const EXIT_CODE: i32 = 130;

/// How long a command may take to notice Ctrl-C before the handler ends it.
const GRACE: Duration = Duration::from_millis(700);

static REQUESTED: AtomicBool = AtomicBool::new(false);
/// Who ends the process after Ctrl-C: nobody yet, the command, or the handler.
static OWNER: AtomicU8 = AtomicU8::new(NOBODY);
const NOBODY: u8 = 0;
const COMMAND: u8 = 1;
const HANDLER: u8 = 2;
/// Held while a file is written; the handler takes it before exiting.
static WRITE: Mutex<()> = Mutex::new(());
/// What the command has kept so far, for the handler's message.
static KEPT: Mutex<String> = Mutex::new(String::new());

/// Ctrl-C during a command: `kept` says what is on disk (a checkpoint, rows so far, nothing).
#[derive(Debug)]
pub struct Interrupted {
    /// What was saved, in words.
    pub kept: String,
}

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "interrupted: {}", self.kept)
    }
}

impl std::error::Error for Interrupted {}

/// Installs the Ctrl-C handler (once, at start).
pub fn install() {
    let installed = ctrlc::set_handler(|| {
        if REQUESTED.swap(true, Ordering::SeqCst) {
            exit_now("interrupted again: stopped at once");
        }
        std::thread::sleep(GRACE);
        if OWNER
            .compare_exchange(NOBODY, HANDLER, Ordering::SeqCst, Ordering::SeqCst)
            .is_ok()
        {
            let kept = KEPT.lock().map(|k| k.clone()).unwrap_or_default();
            exit_now(&format!("interrupted: {}", or_nothing(&kept)));
        }
    });
    if let Err(e) = installed {
        eprintln!("warning: Ctrl-C handler not installed ({e}); Ctrl-C will stop without saving");
    }
}

/// Waits for a running write, prints `message` and exits with [`EXIT_CODE`].
fn exit_now(message: &str) -> ! {
    let _write = WRITE.lock();
    eprintln!("{message}");
    std::process::exit(EXIT_CODE);
}

fn or_nothing(kept: &str) -> &str {
    if kept.is_empty() {
        "nothing was saved"
    } else {
        kept
    }
}

/// Whether Ctrl-C was pressed. A `true` answer makes the caller responsible for stopping (the
/// handler will not end the process under it).
pub fn requested() -> bool {
    if !REQUESTED.load(Ordering::SeqCst) {
        return false;
    }
    match OWNER.compare_exchange(NOBODY, COMMAND, Ordering::SeqCst, Ordering::SeqCst) {
        Ok(_) => true,
        Err(owner) if owner == COMMAND => true,
        // The handler is already ending the process: let it.
        Err(_) => loop {
            std::thread::park();
        },
    }
}

/// `Err(Interrupted)` carrying the last [`keep`] note when Ctrl-C was pressed.
pub fn check() -> Result<(), Interrupted> {
    if requested() { Err(stopped()) } else { Ok(()) }
}

/// The [`Interrupted`] error with the last [`keep`] note.
pub fn stopped() -> Interrupted {
    let kept = KEPT.lock().map(|k| k.clone()).unwrap_or_default();
    Interrupted {
        kept: or_nothing(&kept).to_owned(),
    }
}

/// Records what is on disk now, should the command be stopped from here on.
pub fn keep(note: impl Into<String>) {
    if let Ok(mut k) = KEPT.lock() {
        *k = note.into();
    }
}

/// Runs a write so that Ctrl-C never exits in the middle of it.
pub fn writing<T>(write: impl FnOnce() -> T) -> T {
    let _guard = WRITE
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    write()
}

/// Trains `fit` to its end and finishes it (the refit, the final errors), stopping within a
/// progress period on Ctrl-C.
pub fn train_to_end(fit: &mut kernel_fit::Fit) -> anyhow::Result<kernel_fit::FitSummary> {
    fit.train(1000, |_| {
        if requested() {
            std::ops::ControlFlow::Break(())
        } else {
            std::ops::ControlFlow::Continue(())
        }
    });
    check()?;
    Ok(fit.finish()?)
}
