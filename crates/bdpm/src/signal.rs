//! Interrupts (SIGINT, SIGTERM, SIGHUP) during a render: the first one asks the render loop to
//! stop after the pass in flight and write what it has, or, while the renderer is being
//! prepared (radiance cache, pixel table, pilots), the preparation to stop within a chunk of its
//! work, writing nothing; a second one while the render is still running quits at once without
//! writing anything. While the outputs are being written, further
//! signals are only acknowledged, so that no file is left half-written.
//!
//! The handler cannot tell the signals apart (the `ctrlc` crate does not say which arrived), so
//! an interrupted render always exits with [`EXIT_INTERRUPTED`].
use bdpm_output::say_err;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};

/// Exit code of an interrupted render: 128 + SIGINT, as shells report a Ctrl-C.
pub(crate) const EXIT_INTERRUPTED: u8 = 130;

/// Signals received so far.
static SIGNALS: AtomicU32 = AtomicU32::new(0);
/// Set once the render loop has ended and the outputs are being written.
static WRITING: AtomicBool = AtomicBool::new(false);
/// Set while the renderer is being prepared (radiance cache, pixel table, pilots), which an
/// interrupt stops without writing anything.
static PREPARING: AtomicBool = AtomicBool::new(false);

/// What an interrupt does to the running command, for the handler's message.
#[derive(Clone, Copy)]
pub(crate) enum Stop {
    /// A render: stop after the pass in flight and write what was rendered.
    AfterPass,
    /// A merge: stop and write nothing (the parts hold every pass; a merge rerun from them
    /// loses nothing).
    WithoutWriting,
}

/// Installs the handler. Call once, before the work that a signal should be able to stop.
/// The handler writes through [`say_err!`], which drops its message on a closed standard
/// error instead of panicking: a panic would end the handler's thread, and a second interrupt
/// would then no longer quit.
pub(crate) fn install(stop: Stop) -> Result<(), String> {
    ctrlc::set_handler(move || {
        let n = SIGNALS.fetch_add(1, Ordering::SeqCst) + 1;
        if WRITING.load(Ordering::SeqCst) {
            say_err!(
                "\nbdpm: interrupt: the outputs are being written, they will be complete in a moment"
            );
        } else if n == 1 && PREPARING.load(Ordering::SeqCst) {
            say_err!(
                "\nbdpm: interrupt: stopping the preparation; nothing was rendered, so nothing will \
                 be written (interrupt again to quit at once)"
            );
        } else if n == 1 {
            match stop {
                Stop::AfterPass => say_err!(
                    "\nbdpm: interrupt: stopping after the pass in flight and writing what was \
                     rendered (interrupt again to quit without writing)"
                ),
                Stop::WithoutWriting => say_err!(
                    "\nbdpm: interrupt: stopping the merge without writing any output (its parts \
                     are unchanged)"
                ),
            }
        } else {
            say_err!("\nbdpm: second interrupt: quitting without writing any output");
            std::process::exit(EXIT_INTERRUPTED.into());
        }
    })
    .map_err(|e| format!("cannot install the interrupt handler: {e}"))
}

/// Whether a signal has arrived.
pub(crate) fn requested() -> bool {
    SIGNALS.load(Ordering::SeqCst) > 0
}

/// Marks the start of writing outputs: from now on a signal no longer quits the process.
pub(crate) fn begin_writing() {
    WRITING.store(true, Ordering::SeqCst);
}

/// Marks the start (`true`) or end of the renderer's preparation, for the handler's message.
pub(crate) fn set_preparing(on: bool) {
    PREPARING.store(on, Ordering::SeqCst);
}
