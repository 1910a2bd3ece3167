//! Construction errors.

use std::fmt;

use glam::Vec3;

/// Why a [`crate::Bdf`] could not be built. Each variant names the offending parameter
/// and carries its value, so that a scene loader can report it as is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BdfError {
    /// A channel of an albedo (`which` is `"kd"` or `"gr"`) is NaN or infinite.
    NotFinite {
        /// The parameter's name.
        which: &'static str,
        /// The value as given.
        value: Vec3,
    },
    /// A channel of an albedo (`which` is `"kd"` or `"gr"`) is outside [0, 1].
    AlbedoOutOfRange {
        /// The parameter's name.
        which: &'static str,
        /// The value as given.
        value: Vec3,
    },
    /// kd + gr exceeds 1 in some channel, so the surface would reflect more than it receives.
    EnergyGain {
        /// The Lambert albedo.
        kd: Vec3,
        /// The lobe albedo.
        gr: Vec3,
    },
    /// The lobe width Δ is not finite or not in [0.05°, 90°] (given in radians).
    LobeWidth {
        /// Δ as given, in radians.
        delta: f32,
    },
}

impl fmt::Display for BdfError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::NotFinite { which, value } => {
                write!(f, "{which} = {value} has a non-finite channel")
            }
            Self::AlbedoOutOfRange { which, value } => {
                write!(f, "{which} = {value} has a channel outside [0, 1]")
            }
            Self::EnergyGain { kd, gr } => write!(
                f,
                "kd + gr = {} exceeds 1 in some channel (kd = {kd}, gr = {gr}); \
                 the surface would create energy",
                kd + gr
            ),
            Self::LobeWidth { delta } => write!(
                f,
                "lobe width delta = {delta} rad ({}°) is not in [0.05°, 90°]",
                delta.to_degrees()
            ),
        }
    }
}

impl std::error::Error for BdfError {}
