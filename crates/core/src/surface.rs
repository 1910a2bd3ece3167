//! A surface point as shading and the MIS weights see it, and the point light: plain data
//! that the scene makes and the photon tracer, the radiance cache and the weights read.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

use crate::Frame;

/// A surface point prepared for shading from the side of `wo`: normals flipped towards `wo`
/// (surfaces are two-sided), and the shading frame.
#[derive(Clone, Copy, Debug)]
pub struct Shading {
    /// Position, metres.
    pub p: Vec3,
    /// Geometric normal on the side of `wo`.
    pub ng: Vec3,
    /// Shading frame whose normal is the shading normal on the side of `wo`.
    pub frame: Frame,
    /// Material index.
    pub material: u32,
    /// Triangle index.
    pub prim: u32,
    /// Barycentric coordinates (b1, b2) of `p` in the triangle (where texture coordinates
    /// are interpolated).
    pub bary: Vec2,
}

/// An isotropic point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// Position, metres.
    pub position: Vec3,
    /// Emitted flux Φ per RGB channel, W.
    pub flux: Vec3,
}

impl PointLight {
    /// Radiant intensity Φ/(4π), W·sr⁻¹ per channel.
    pub fn intensity(&self) -> Vec3 {
        self.flux / (4.0 * PI)
    }
}

/// Lights whose visibility a [`WeightVertex`] records (bit `l` of [`WeightVertex::lights`]);
/// lights beyond these are tested with a shadow ray where they are needed.
pub const MASKED_LIGHTS: usize = 32;

/// What the weights know about a candidate x₁: where it is, which way it faces, what it is made
/// of and which lights it sees. Built only by [`WeightVertex::at`] (with the
/// visibility bits from the scene), for camera vertices and photon vertices alike.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeightVertex {
    /// Position, m.
    pub p: Vec3,
    /// Unit geometric normal on the side the vertex was reached from (the side x₀ sees for a
    /// camera vertex, the side the light arrived from for a photon vertex).
    pub n: Vec3,
    /// Material index.
    pub material: u32,
    /// Triangle index.
    pub prim: u32,
    /// Barycentric coordinates of `p` in the triangle (for a textured material's kd).
    pub bary: Vec2,
    /// Bit `l` set iff light `l < MASKED_LIGHTS` lies on the side of `n` and nothing blocks the
    /// segment to it; 0 where visibility was not computed.
    pub lights: u32,
}

impl WeightVertex {
    /// The vertex at a shading point, with the given light-visibility bits (from
    /// the scene's visibility test at the same point, or 0 where the weights never read them).
    #[inline]
    pub fn at(sh: &Shading, lights: u32) -> WeightVertex {
        WeightVertex {
            p: sh.p,
            n: sh.ng,
            material: sh.material,
            prim: sh.prim,
            bary: sh.bary,
            lights,
        }
    }
}
