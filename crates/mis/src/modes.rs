//! The table of weighting modes: each mode's name and the [`Heuristic`] its name parses to,
//! written once, from which [`Heuristic::ALL_NAMES`], [`Heuristic::name`],
//! [`Heuristic::parse`], `FromStr` and the parameter-free [`HeuristicKind`] are generated.

use std::fmt;
use std::str::FromStr;

use crate::{DEFAULT_THRESHOLD_RADIUS, Heuristic};

/// Generates the name table, `name`, `parse`, [`HeuristicKind`] and the conversions between
/// the two enums from one list of `"name" => Variant { field: default, … }` rows (in the
/// order of method.md §4).
macro_rules! modes {
    ($($name:literal => $variant:ident $({ $($field:ident: $default:expr),* })?,)*) => {
        /// A weighting mode without its parameters: which [`Heuristic`] variant, not its
        /// threshold radius or weight clamp. Render settings hold this and keep the
        /// parameters in settings of their own, so that each has one source.
        /// Non-exhaustive like [`Heuristic`].
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        #[non_exhaustive]
        pub enum HeuristicKind {
            $(
                #[doc = concat!("[`Heuristic::", stringify!($variant), "`], named `", $name, "`.")]
                $variant,
            )*
        }

        impl HeuristicKind {
            /// The mode's name as used on the command line and in reports.
            pub fn name(self) -> &'static str {
                match self {
                    $(HeuristicKind::$variant => $name,)*
                }
            }

            /// The inverse of [`HeuristicKind::name`]; unknown names give `None`.
            pub fn parse(name: &str) -> Option<HeuristicKind> {
                match name {
                    $($name => Some(HeuristicKind::$variant),)*
                    _ => None,
                }
            }

            /// The heuristic with [`Heuristic::parse`]'s parameters: `threshold` gets
            /// [`DEFAULT_THRESHOLD_RADIUS`], the `optimal*` modes get no weight clamp.
            pub fn heuristic(self) -> Heuristic {
                match self {
                    $(HeuristicKind::$variant => Heuristic::$variant $({ $($field: $default),* })?,)*
                }
            }
        }

        impl Heuristic {
            /// Every name [`Heuristic::parse`] accepts, in the order of method.md §4.
            pub const ALL_NAMES: &'static [&'static str] = &[$($name),*];

            /// Which mode this is, without its parameters.
            pub fn kind(&self) -> HeuristicKind {
                match self {
                    $(Heuristic::$variant { .. } => HeuristicKind::$variant,)*
                }
            }

            /// The mode's name as used on the command line and in reports.
            pub fn name(&self) -> &'static str {
                self.kind().name()
            }

            /// The inverse of [`Heuristic::name`]: `threshold` gets
            /// [`DEFAULT_THRESHOLD_RADIUS`], the `optimal*` modes get no weight clamp.
            /// Unknown names give `None` (`str::parse` gives an [`UnknownMode`] instead).
            pub fn parse(name: &str) -> Option<Heuristic> {
                HeuristicKind::parse(name).map(HeuristicKind::heuristic)
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
    "corrected-balance" => CorrectedBalance,
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
