//! The render settings live in `bdpm-settings` (one type and one validation for the loader,
//! the integrator and the driver); this module adds what only the integrator needs.

/// Where in the pixel a camera sample goes: the jittered offset, or the centre.
#[inline]
pub(crate) fn pixel_offset(u: [f32; 2], jitter: bool) -> [f32; 2] {
    if jitter { u } else { [0.5, 0.5] }
}
