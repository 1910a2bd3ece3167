//! Interrupts (SIGINT, SIGTERM, SIGHUP) during a render: the first one asks the render loop to
//! stop after the pass in flight and write what it has; a second one while the render is still
//! running quits at once without writing anything. While the outputs are being written, further
//! signals are only acknowledged, so that no file is left half-written.
//!
//! The handler cannot tell the signals apart (the `ctrlc` crate does not say which arrived), so
//! an interrupted render always exits with [`EXIT_INTERRUPTED`].
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};

/// Exit code of an interrupted render: 128 + SIGINT, as shells report a Ctrl-C.
pub(crate) const EXIT_INTERRUPTED: u8 = 130;

/// Signals received so far.
static SIGNALS: AtomicU32 = AtomicU32::new(0);
/// Set once the render loop has ended and the outputs are being written.
static WRITING: AtomicBool = AtomicBool::new(false);

/// Installs the handler. Call once, before the work that a signal should be able to stop.
pub(crate) fn install() -> Result<(), String> {
    ctrlc::set_handler(|| {
        let n = SIGNALS.fetch_add(1, Ordering::SeqCst) + 1;
        if WRITING.load(Ordering::SeqCst) {
            eprintln!("\nbdpm: interrupt: the outputs are being written, they will be complete in a moment");
        } else if n == 1 {
            eprintln!(
                "\nbdpm: interrupt: stopping after the pass in flight and writing what was rendered \
                 (interrupt again to quit without writing)"
            );
        } else {
            eprintln!("\nbdpm: second interrupt: quitting without writing any output");
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
