//! The plain data and small helpers that every bdpm crate shares, with no geometry, BDF or
//! scene behind them, so that a crate needing only these (the photon tracer, the grid, the
//! radiance cache) compiles without the BVH or the material models:
//! - [`Rng`] and [`Domain`]: deterministic random streams keyed by (seed, domain, indices), so
//!   that every sample is a pure function of its keys whatever the thread count;
//! - [`Frame`] and the [`sampling`] warps (uniform sphere, concentric disk);
//! - [`Shading`] and [`WeightVertex`]: a surface point as shading and the MIS weights see it;
//!   [`PointLight`];
//! - [`luminance`] (Rec. 709), [`prefetch`] and [`human_bytes`].
//!
//! Units: positions and distances in metres, flux in W per RGB channel, solid angles in sr.
//!
//! ```
//! use bdpm_core::{Domain, Frame, Rng, sampling};
//! use glam::Vec3;
//!
//! // The same keys give the same numbers, on any thread.
//! let u = Rng::new(42, Domain::Other, [3, 7, 0]).uniform2();
//! assert_eq!(u, Rng::new(42, Domain::Other, [3, 7, 0]).uniform2());
//! // A direction on the unit sphere, taken to a frame around a normal and back.
//! let d = sampling::uniform_sphere(u);
//! let frame = Frame::from_normal(Vec3::Y);
//! assert!((frame.to_world(frame.to_local(d)) - d).length() < 1e-5);
//! ```

mod frame;
mod prefetch;
mod rng;
pub mod sampling;
mod surface;

pub use frame::Frame;
pub use prefetch::prefetch;
pub use rng::{Domain, Rng};
pub use surface::{MASKED_LIGHTS, PointLight, Shading, WeightVertex};

/// Rec. 709 luminance weights of linear RGB, the one definition of luminance that all of
/// bdpm uses (f32 here, f64 in the tools).
pub const LUMINANCE_WEIGHTS: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// Rec. 709 luminance of a linear RGB colour ([`LUMINANCE_WEIGHTS`] in f32).
pub fn luminance(c: glam::Vec3) -> f32 {
    let [r, g, b] = LUMINANCE_WEIGHTS;
    c.dot(glam::Vec3::new(r as f32, g as f32, b as f32))
}

/// `bytes` for people: `1.5 GiB`, `320.0 MiB`, `12.0 KiB` (binary units, one decimal).
pub fn human_bytes(bytes: u64) -> String {
    let b = bytes as f64;
    let (value, unit) = if b >= (1u64 << 40) as f64 {
        (b / (1u64 << 40) as f64, "TiB")
    } else if b >= (1u64 << 30) as f64 {
        (b / (1u64 << 30) as f64, "GiB")
    } else if b >= (1u64 << 20) as f64 {
        (b / (1u64 << 20) as f64, "MiB")
    } else {
        (b / 1024.0, "KiB")
    };
    format!("{value:.1} {unit}")
}

#[cfg(test)]
mod luminance_tests {
    use super::*;

    /// The f32 weights are the f64 ones rounded, bit for bit the literals they replaced.
    #[test]
    fn f32_weights_are_the_f64_weights_rounded() {
        let [r, g, b] = LUMINANCE_WEIGHTS;
        assert_eq!([r as f32, g as f32, b as f32], [0.2126f32, 0.7152, 0.0722]);
        assert_eq!(luminance(glam::Vec3::X), 0.2126f32);
    }
}

// The README (the crate's page on crates.io) as a hidden item, so that `cargo test --doc`
// compiles and runs its example; the crate documentation above stays as it is.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
