//! The font of everything drawn (legends, colour bars, the lab's plots): DejaVu Sans, embedded
//! in the binary (the `dejavu` crate), so that no system font is needed.
use std::sync::Once;

use plotters::style::FontStyle;

/// Registers DejaVu Sans as plotters' "sans-serif" (once), for text in bitmaps: call it
/// before drawing text with plotters' bitmap backend.
pub fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // DejaVu Sans is a valid TrueType font; a failure here would only lose the PNG text.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}
