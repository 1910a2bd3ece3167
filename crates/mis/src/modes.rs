//! The table of weighting modes: each mode's name and the [`Heuristic`] its name parses to,
//! written once, from which [`Heuristic::ALL_NAMES`], [`Heuristic::name`],
//! [`Heuristic::parse`] and `FromStr` are generated.

use std::fmt;
use std::str::FromStr;

use crate::{DEFAULT_THRESHOLD_RADIUS, Heuristic};

/// Generates the name table, `name` and `parse` from one list of
/// `"name" => Variant { field: default, … }` rows (in the order of method.md §4).
macro_rules! modes {
    ($($name:literal => $variant:ident $({ $($field:ident: $default:expr),* })?,)*) => {
        impl Heuristic {
            /// Every name [`Heuristic::parse`] accepts, in the order of method.md §4.
            pub const ALL_NAMES: &'static [&'static str] = &[$($name),*];

            /// The mode's name as used on the command line and in reports.
            pub fn name(&self) -> &'static str {
                match self {
                    $(Heuristic::$variant { .. } => $name,)*
                }
            }

            /// The inverse of [`Heuristic::name`]: `threshold` gets
            /// [`DEFAULT_THRESHOLD_RADIUS`], the `optimal*` modes get no weight clamp.
            /// Unknown names give `None` (`str::parse` gives an [`UnknownMode`] instead).
            pub fn parse(name: &str) -> Option<Heuristic> {
                match name {
                    $($name => Some(Heuristic::$variant $({ $($field: $default),* })?),)*
                    _ => None,
                }
            }
        }
    };
}

modes! {
    "bdd0" => Bdd0,
    "bdd1" => Bdd1,
    "threshold" => Threshold { radius: DEFAULT_THRESHOLD_RADIUS },
    "algebraic-direct" => AlgebraicDirect,
    "algebraic" => Algebraic,
    "optimal" => Optimal { clamp_weights: false },
    "optimal-split" => OptimalSplit { clamp_weights: false },
    "optimal-path" => OptimalPath { clamp_weights: false },
    "balance" => Balance,
    "power" => Power,
    "camis" => Camis,
}

/// A name that is not a weighting mode; its message lists the valid names.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownMode(pub String);

impl fmt::Display for UnknownMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "unknown mode '{}'; expected one of {}",
            self.0,
            Heuristic::ALL_NAMES.join(", ")
        )
    }
}

impl std::error::Error for UnknownMode {}

impl FromStr for Heuristic {
    type Err = UnknownMode;

    /// [`Heuristic::parse`], with an error that lists the valid names.
    fn from_str(s: &str) -> Result<Heuristic, UnknownMode> {
        Heuristic::parse(s).ok_or_else(|| UnknownMode(s.to_string()))
    }
}
