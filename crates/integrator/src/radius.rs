//! A merge radius per block of pixels (`adaptive_radius`, docs/results.md, "A sharper glossy
//! reference"): a pilot's image split by technique puts each `BLOCK` × `BLOCK` (8 × 8) block in
//! one of three classes by BDD=1's share of the block's luminance, and the class fixes the
//! block's scale of the render's radius r.
//!
//! Where the camera side's exact direct light (or BDD=0) makes the image, a larger disk buys
//! little variance for its gathers and its kernel bias; where BDD=1's merges make it (what a
//! glossy surface reflects), it buys much. On the glossy Cornell box the per-block oracle's
//! radius follows that share (correlation 0.48 of log r), and this three-class rule, its
//! parameters chosen on one seed, cut relV by 20–22 % for +1–5 % a pass on others.
//!
//! The map is a function of the scene, the settings and the pilot's own streams, fixed before
//! the passes: every pass stays unbiased for the same kernel-smoothed image and independent of
//! the others, so passes still merge exactly. Both merges of a camera sample (at x₀ and at x₁)
//! use its pixel's radius; the weights' S, N_eff and the A/B table are the pixel's.

use bdpm_bdf::luminance;

use crate::estimates::Techniques;

/// Side of the square pixel blocks that share a radius, pixels.
pub(crate) const BLOCK: u32 = 8;

/// Class bounds on BDD=1's share of a block's luminance: below the first, between, above.
pub(crate) const SHARE_BOUNDS: [f64; 2] = [0.3, 0.6];

/// The radius scale of each class (below, between, above [`SHARE_BOUNDS`]).
pub(crate) const SCALES: [f32; 3] = [0.5, 1.0, 1.4];

/// Added to the render's seed for the pilot's streams (apart from the render's and from
/// `corrected-balance`'s pilot, whose offset differs).
const PILOT_SEED_OFFSET: u64 = 0x5eed_7ad1_0000_0002;

/// The seed of the adaptive radius's pilot of a render with seed `seed`.
pub(crate) fn radius_pilot_seed(seed: u64) -> u64 {
    seed.wrapping_add(PILOT_SEED_OFFSET)
}

/// Each pixel's scale of the merge radius.
#[derive(Clone, Debug, PartialEq)]
pub struct RadiusMap {
    width: u32,
    scales: Vec<f32>,
    blocks: [u32; 3],
}

impl RadiusMap {
    /// The map of a `width` × `height` image from its per-pixel estimates split by technique
    /// (row-major): a block's BDD=1 share is Σ luminance(x1_weighted) / Σ luminance(total) over
    /// its pixels (blocks cut at the image's right and bottom edges included). A black block
    /// keeps the radius.
    pub fn from_techniques(width: u32, height: u32, techniques: &[Techniques]) -> RadiusMap {
        assert_eq!(techniques.len(), width as usize * height as usize);
        let (bw, bh) = (width.div_ceil(BLOCK), height.div_ceil(BLOCK));
        let mut sums = vec![(0.0f64, 0.0f64); (bw * bh) as usize];
        for y in 0..height {
            for x in 0..width {
                let t = &techniques[(y * width + x) as usize];
                let s = &mut sums[((y / BLOCK) * bw + x / BLOCK) as usize];
                s.0 += luminance(t.x1_weighted.as_vec3()) as f64;
                s.1 += luminance(t.total().as_vec3()) as f64;
            }
        }
        let classes: Vec<usize> = sums
            .iter()
            .map(|&(x1, total)| {
                // Black (or non-finite) blocks keep r.
                if total.is_nan() || total <= 0.0 {
                    return 1;
                }
                let share = x1 / total;
                SHARE_BOUNDS.iter().filter(|&&b| share >= b).count()
            })
            .collect();
        let mut blocks = [0u32; 3];
        for &c in &classes {
            blocks[c] += 1;
        }
        let scales = (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| SCALES[classes[((y / BLOCK) * bw + x / BLOCK) as usize]])
            .collect();
        RadiusMap {
            width,
            scales,
            blocks,
        }
    }

    /// Whether the map is of a `width` × `height` image.
    pub fn fits(&self, width: u32, height: u32) -> bool {
        self.width == width && self.scales.len() == width as usize * height as usize
    }

    /// The radius scale of pixel (x, y).
    #[inline]
    pub fn scale(&self, x: u32, y: u32) -> f32 {
        self.scales[(y * self.width + x) as usize]
    }

    /// The largest scale in the map (the photon grid is built for r times it).
    pub fn largest(&self) -> f32 {
        self.scales.iter().copied().fold(0.0, f32::max)
    }

    /// Blocks per class: at ½ r, at r and at 1.4 r.
    pub fn blocks(&self) -> [u32; 3] {
        self.blocks
    }

    /// Memory of the map, bytes.
    pub fn bytes(&self) -> u64 {
        (self.scales.len() * std::mem::size_of::<f32>()) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn split(x1: f64, rest: f64) -> Techniques {
        Techniques {
            direct: DVec3::splat(rest),
            x1_weighted: DVec3::splat(x1),
            ..Techniques::default()
        }
    }

    #[test]
    fn blocks_take_the_scale_of_their_bdd1_share() {
        // 16 × 9 pixels: blocks (0,0) share 0.1, (1,0) 0.45, (0,1) (a cut row) 0.9, (1,1) black.
        let (w, h) = (16, 9);
        let t: Vec<Techniques> = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| match (x / BLOCK, y / BLOCK) {
                (0, 0) => split(0.1, 0.9),
                (1, 0) => split(0.45, 0.55),
                (0, 1) => split(0.9, 0.1),
                _ => Techniques::default(),
            })
            .collect();
        let m = RadiusMap::from_techniques(w, h, &t);
        assert_eq!(m.scale(3, 3), SCALES[0]);
        assert_eq!(m.scale(8, 7), SCALES[1]);
        assert_eq!(m.scale(7, 8), SCALES[2]);
        assert_eq!(m.scale(15, 8), SCALES[1]);
        assert_eq!(m.blocks(), [1, 2, 1]);
        assert_eq!(m.largest(), SCALES[2]);
        assert_eq!(m.bytes(), 16 * 9 * 4);
    }

    #[test]
    fn the_bounds_split_the_shares() {
        for (share, class) in [(0.29, 0), (0.31, 1), (0.59, 1), (0.61, 2)] {
            let t = vec![split(share, 1.0 - share); 64];
            assert_eq!(
                RadiusMap::from_techniques(8, 8, &t).scale(0, 0),
                SCALES[class]
            );
        }
    }
}
