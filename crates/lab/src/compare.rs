//! `bdpm compare A.exr B.exr`: are two renders the same image? It says whether the mean
//! radiance channels are bit-identical (the check that an optimisation kept the image bits),
//! how far apart the image means are, and, where both files carry their standard error, the
//! fraction of pixels that agree within k combined standard errors (the check that two modes or
//! two builds estimate the same image).
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args;

use bdpm_output::cli::{CliResult, positive, whole};
use bdpm_output::say;
use bdpm_output::stats::luminance;

use crate::reference::read_exr;
use crate::study::{luminances, mean, reference_variance, rel_mean, rel_mse, rmse, without_floor};

/// Arguments of this subcommand.
#[derive(Args, Debug)]
pub struct CompareArgs {
    /// First EXR (as written by `bdpm render`).
    a: PathBuf,
    /// Second EXR, of the same size.
    b: PathBuf,
    /// Agreement threshold in combined standard errors √(σ_a² + σ_b²) per pixel.
    #[arg(long, default_value_t = 4.0, allow_negative_numbers = true, value_parser = positive)]
    sigmas: f64,
    /// Exit with code 1 unless the mean radiance channels are bit-identical.
    #[arg(long)]
    require_identical: bool,
    /// Also compare the means of BLOCK × BLOCK pixel blocks (luminance): each block's relative
    /// difference and its z-score against the combined standard error of the block means
    /// (both files need stderr). Tells a bias (many blocks off by many standard errors, of one
    /// sign) from noise.
    #[arg(long, value_name = "BLOCK", allow_negative_numbers = true, value_parser = whole::<u32>)]
    blocks: Option<u32>,
    /// Also say how much of the squared error (luminance, the second file as reference, its
    /// own error included) the N pixels of largest squared error hold, and where they lie:
    /// whether a few pixels decide the rel. RMSE.
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = whole::<usize>)]
    worst: Option<usize>,
}

/// Where the squared error of an image against a reference is concentrated: the share of
/// Σ (a − b)² that the `n` pixels of largest (a − b)² hold, and the bounding box of those
/// pixels, (first column, first row, last column, last row), for an image `width` wide.
/// `None` when there is no error at all or no pixel.
pub(crate) fn worst_pixels(
    a: &[f64],
    b: &[f64],
    width: usize,
    n: usize,
) -> Option<(f64, [usize; 4])> {
    let mut e: Vec<(f64, usize)> = a
        .iter()
        .zip(b)
        .enumerate()
        .map(|(i, (x, y))| ((x - y) * (x - y), i))
        .collect();
    let total: f64 = e.iter().map(|&(v, _)| v).sum();
    if total.is_nan() || total <= 0.0 || n == 0 || width == 0 {
        return None;
    }
    e.sort_by(|x, y| y.0.total_cmp(&x.0));
    let top = &e[..n.min(e.len())];
    let share = top.iter().map(|&(v, _)| v).sum::<f64>() / total;
    let mut bbox = [usize::MAX, usize::MAX, 0, 0];
    for &(_, i) in top {
        let (x, y) = (i % width, i / width);
        bbox = [
            bbox[0].min(x),
            bbox[1].min(y),
            bbox[2].max(x),
            bbox[3].max(y),
        ];
    }
    Some((share, bbox))
}

/// What a comparison found, per channel over pixel luminance (Rec. 709).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Comparison {
    /// Pixels compared.
    pub(crate) pixels: usize,
    /// Pixels whose R, G, B (as stored, f32) differ in any bit.
    pub(crate) differing: usize,
    /// Largest |a − b| of a channel, W·m⁻²·sr⁻¹.
    pub(crate) max_abs_diff: f64,
    /// Image-mean luminance of each file, W·m⁻²·sr⁻¹.
    pub(crate) mean: (f64, f64),
    /// Fraction of pixels with |a − b| ≤ k·√(σ_a² + σ_b²) in luminance, when both have stderr.
    pub(crate) within: Option<f64>,
}

/// Compares the mean channels (and, if present, the standard errors) of two images.
pub(crate) fn compare(
    a: &[glam::DVec3],
    b: &[glam::DVec3],
    se: Option<(&[glam::DVec3], &[glam::DVec3])>,
    sigmas: f64,
) -> Comparison {
    let bits = |v: &glam::DVec3| v.as_vec3().to_array().map(f32::to_bits);
    let differing = a.iter().zip(b).filter(|(x, y)| bits(x) != bits(y)).count();
    let max_abs_diff = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).abs().max_element())
        .fold(0.0, f64::max);
    let image_mean =
        |v: &[glam::DVec3]| v.iter().map(|c| luminance(*c)).sum::<f64>() / v.len().max(1) as f64;
    let within = se.map(|(sa, sb)| {
        let ok = (0..a.len())
            .filter(|&i| {
                let d = (luminance(a[i]) - luminance(b[i])).abs();
                let s = (luminance(sa[i]).powi(2) + luminance(sb[i]).powi(2)).sqrt();
                d <= sigmas * s
            })
            .count();
        ok as f64 / a.len().max(1) as f64
    });
    Comparison {
        pixels: a.len(),
        differing,
        max_abs_diff,
        mean: (image_mean(a), image_mean(b)),
        within,
    }
}

/// The error of an image against a reference, over pixel luminance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ErrorFigures {
    /// RMSE / the reference's image mean.
    pub(crate) rel_rmse: f64,
    /// Mean over pixels of (I − R)²/(R² + ε), ε = 0.01·mean(R)².
    pub(crate) rel_mse: f64,
    /// The image's mean squared error is no more than the reference's own variance: the
    /// reference cannot resolve the difference, and both figures are the floor of
    /// [`without_floor`] (1 % of the reference's error), not a measurement.
    pub(crate) below_reference: bool,
}

/// Rel. RMSE and relMSE of `image` against `reference` (luminance per pixel), with the
/// reference's own variance (from its per-channel standard errors, when given) subtracted as
/// `bdpm study` does. `None` for a black reference.
pub(crate) fn error_against(
    image: &[f64],
    reference: &[f64],
    reference_stderr: Option<&[glam::DVec3]>,
) -> Option<ErrorFigures> {
    let ref_mean = mean(reference);
    if ref_mean.is_nan() || ref_mean <= 0.0 {
        return None;
    }
    let var = reference_variance(reference_stderr, reference.len());
    let (measured, floor) = (rmse(image, reference).powi(2), mean(&var));
    if measured == 0.0 {
        // Equal images: no error to measure, whatever the reference's own (the floor below
        // stands in for a difference too small to resolve, and there is none).
        return Some(ErrorFigures {
            rel_rmse: 0.0,
            rel_mse: 0.0,
            below_reference: false,
        });
    }
    let mse = without_floor(measured, floor);
    Some(ErrorFigures {
        rel_rmse: mse.sqrt() / ref_mean,
        rel_mse: without_floor(rel_mse(image, reference), rel_mean(&var, reference)),
        below_reference: floor > 0.0 && measured <= floor,
    })
}

/// One block of [`block_differences`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BlockDifference {
    /// (mean of a − mean of b) / mean of b over the block's pixels.
    pub(crate) relative: f64,
    /// (mean of a − mean of b) / √(SE_a² + SE_b²) of the block means.
    pub(crate) z: f64,
}

/// Differences of the luminance means of `block` × `block` pixel blocks of two images of
/// `width` columns (partial blocks at the right and bottom edges included), with per-pixel
/// standard errors of each (independent pixels). Blocks where `b`'s mean is not positive are
/// left out.
pub(crate) fn block_differences(
    (a, b): (&[f64], &[f64]),
    (se_a, se_b): (&[f64], &[f64]),
    width: usize,
    block: usize,
) -> Vec<BlockDifference> {
    let height = a.len() / width.max(1);
    let mut out = Vec::new();
    for by in (0..height).step_by(block) {
        for bx in (0..width).step_by(block) {
            let (mut sa, mut sb, mut va, mut n) = (0.0, 0.0, 0.0, 0.0);
            for y in by..(by + block).min(height) {
                for x in bx..(bx + block).min(width) {
                    let i = y * width + x;
                    sa += a[i];
                    sb += b[i];
                    va += se_a[i] * se_a[i] + se_b[i] * se_b[i];
                    n += 1.0;
                }
            }
            if sb > 0.0 {
                out.push(BlockDifference {
                    relative: (sa - sb) / sb,
                    z: (sa - sb) / n / (va.sqrt() / n),
                });
            }
        }
    }
    out
}

/// Prints the first image's error against the second as reference.
fn say_error(e: &ErrorFigures, reference_has_stderr: bool) {
    say!(
        "the first against the second as reference: rel. RMSE {:.3}%, relMSE {:.4e}{}",
        100.0 * e.rel_rmse,
        e.rel_mse,
        if e.rel_rmse == 0.0 {
            " (the images are equal)"
        } else if e.below_reference {
            " (no more than the second's own error, which is subtracted: shown at the floor, \
             1 % of the second's variance; the second is too noisy to measure this error)"
        } else if reference_has_stderr {
            " (the second's own error subtracted)"
        } else {
            " (the second has no stderr layer: its own error is included)"
        }
    );
}

/// Prints the differences of `block` × `block` blocks' means (`--blocks`), which need both
/// files' standard errors.
fn say_blocks(
    a: &crate::reference::Reference,
    b: &crate::reference::Reference,
    (a_lum, b_lum): (&[f64], &[f64]),
    block: u32,
) -> CliResult<()> {
    let (Some(sa), Some(sb)) = (a.stderr.as_deref(), b.stderr.as_deref()) else {
        return Err(format!(
            "--blocks needs the stderr layer in both files; {} has none",
            if a.stderr.is_none() { &a.path } else { &b.path }.display()
        ));
    };
    let d = block_differences(
        (a_lum, b_lum),
        (&luminances(sa), &luminances(sb)),
        a.width as usize,
        block as usize,
    );
    let nb = d.len().max(1) as f64;
    let mean_rel = d.iter().map(|x| x.relative).sum::<f64>() / nb;
    let rms_z = (d.iter().map(|x| x.z * x.z).sum::<f64>() / nb).sqrt();
    let beyond = d.iter().filter(|x| x.z.abs() > 3.0).count();
    let worst = d
        .iter()
        .max_by(|x, y| x.z.abs().total_cmp(&y.z.abs()))
        .copied();
    say!(
        "{}x{} blocks ({}): mean relative difference {:+.3}%, rms z {:.2} (1 for noise alone), {} beyond 3 standard errors{}",
        block,
        block,
        d.len(),
        100.0 * mean_rel,
        rms_z,
        beyond,
        worst.map_or(String::new(), |w| format!(
            "; largest |z| {:.1} at {:+.2}%",
            w.z.abs(),
            100.0 * w.relative
        ))
    );
    Ok(())
}

/// Runs `bdpm compare`.
pub(crate) fn run(args: CompareArgs) -> CliResult<ExitCode> {
    // The flags first, so that a bad one is refused before the files are read.
    if args.worst == Some(0) {
        return Err("--worst must be at least 1 pixel".into());
    }
    if args.blocks == Some(0) {
        return Err("--blocks must be at least 1 pixel".into());
    }
    let a = read_exr(&args.a)?;
    let b = read_exr(&args.b)?;
    if (a.width, a.height) != (b.width, b.height) {
        return Err(format!(
            "{} is {}x{} but {} is {}x{}",
            args.a.display(),
            a.width,
            a.height,
            args.b.display(),
            b.width,
            b.height
        ));
    }
    if !(args.sigmas.is_finite() && args.sigmas > 0.0) {
        return Err(format!("--sigmas {} must be positive", args.sigmas));
    }
    let se = a.stderr.as_deref().zip(b.stderr.as_deref());
    let c = compare(&a.mean, &b.mean, se, args.sigmas);
    let identical = c.differing == 0;
    say!(
        "{}x{} pixels: {}",
        a.width,
        a.height,
        if identical {
            "mean radiance bit-identical".to_string()
        } else {
            format!(
                "{} of {} pixels differ, largest channel difference {:.4e} W·m⁻²·sr⁻¹",
                c.differing, c.pixels, c.max_abs_diff
            )
        }
    );
    let rel = if c.mean.1 != 0.0 {
        format!("{:+.3}%", 100.0 * (c.mean.0 / c.mean.1 - 1.0))
    } else {
        "n/a".into()
    };
    say!(
        "image-mean luminance: {:.6e} vs {:.6e} W·m⁻²·sr⁻¹ (first vs second {rel})",
        c.mean.0,
        c.mean.1
    );
    let (a_lum, b_lum) = (luminances(&a.mean), luminances(&b.mean));
    if let Some(e) = error_against(&a_lum, &b_lum, b.stderr.as_deref()) {
        say_error(&e, b.stderr.is_some());
    }
    if let Some(block) = args.blocks {
        say_blocks(&a, &b, (&a_lum, &b_lum), block)?;
    }
    if let Some(n) = args.worst
        && let Some((share, [x0, y0, x1, y1])) = worst_pixels(&a_lum, &b_lum, a.width as usize, n)
    {
        say!(
            "the {n} pixels of largest squared error hold {:.1}% of it (columns {x0}-{x1}, rows {y0}-{y1})",
            100.0 * share
        );
    }
    match c.within {
        Some(f) => say!(
            "{:.2}% of pixels within {} combined standard errors",
            100.0 * f,
            args.sigmas
        ),
        None => say!("no per-pixel standard errors in both files: no statistical check"),
    }
    Ok(if args.require_identical && !identical {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn error_against_a_reference_subtracts_its_variance() {
        let r = [1.0, 1.0];
        // Squared errors 0.04 and 0.16: MSE 0.1; the reference's variance 0.01 per pixel.
        let e = error_against(&[1.2, 0.6], &r, None).unwrap();
        assert!((e.rel_rmse - 0.1f64.sqrt()).abs() < 1e-12);
        let se = [DVec3::splat(0.1); 2];
        let e = error_against(&[1.2, 0.6], &r, Some(&se)).unwrap();
        assert!((e.rel_rmse - 0.09f64.sqrt()).abs() < 1e-9);
        // ε = 0.01: relMSE = (0.1 − 0.01)/1.01.
        assert!((e.rel_mse - 0.09 / 1.01).abs() < 1e-9);
        assert!(!e.below_reference);
        assert_eq!(error_against(&[1.0], &[0.0], None), None);
        // An image within the reference's own error: reported as the floor and flagged.
        let e = error_against(&[1.05, 0.95], &r, Some(&se)).unwrap();
        assert!(e.below_reference);
        assert!((e.rel_rmse - (0.01f64 * 0.01).sqrt()).abs() < 1e-9);
        // An image equal to the reference has no error, with or without the reference's.
        for se in [Some(&se[..]), None] {
            let e = error_against(&r, &r, se).unwrap();
            assert_eq!(
                (e.rel_rmse, e.rel_mse, e.below_reference),
                (0.0, 0.0, false)
            );
        }
    }

    #[test]
    fn worst_pixels_share_and_place() {
        // 3 × 2 pixels; squared errors 0, 1, 4 / 0, 0, 5: total 10; the two worst (5 at
        // (2, 1) and 4 at (2, 0)) hold 90 %.
        let b = [0.0; 6];
        let a = [0.0, 1.0, 2.0, 0.0, 0.0, -(5.0f64.sqrt())];
        let (share, bbox) = worst_pixels(&a, &b, 3, 2).unwrap();
        assert!((share - 0.9).abs() < 1e-12);
        assert_eq!(bbox, [2, 0, 2, 1]);
        let (share, bbox) = worst_pixels(&a, &b, 3, 3).unwrap();
        assert!((share - 1.0).abs() < 1e-12);
        assert_eq!(bbox, [1, 0, 2, 1]);
        assert_eq!(worst_pixels(&b, &b, 3, 2), None);
        assert_eq!(worst_pixels(&a, &b, 3, 0), None);
    }

    #[test]
    fn block_differences_of_a_biased_image() {
        // 4 × 2 pixels, blocks of 2: two blocks; the left one 10 % high.
        let b = vec![1.0; 8];
        let a = vec![1.1, 1.1, 1.0, 1.0, 1.1, 1.1, 1.0, 1.0];
        let se = vec![0.01; 8];
        let d = block_differences((&a, &b), (&se, &se), 4, 2);
        assert_eq!(d.len(), 2);
        assert!((d[0].relative - 0.1).abs() < 1e-12);
        // Block SE: √(4·2·10⁻⁴)/4 = 0.00707; difference 0.1 → z ≈ 14.1.
        assert!((d[0].z - 0.1 / (8e-4f64.sqrt() / 4.0)).abs() < 1e-9);
        assert_eq!(d[1].relative, 0.0);
    }

    #[test]
    fn identical_images_compare_identical() {
        let a = vec![DVec3::new(0.1, 0.2, 0.3); 4];
        let c = compare(&a, &a, Some((&a, &a)), 4.0);
        assert_eq!(c.differing, 0);
        assert_eq!(c.max_abs_diff, 0.0);
        assert_eq!(c.within, Some(1.0));
    }

    #[test]
    fn a_one_ulp_change_is_seen_and_judged_by_the_standard_error() {
        let a = vec![DVec3::splat(1.0); 4];
        let mut b = a.clone();
        b[2].y = f64::from(f32::from_bits(1.0f32.to_bits() + 1));
        b[3].x = 2.0;
        let se = vec![DVec3::splat(0.1); 4];
        let c = compare(&a, &b, Some((&se, &se)), 4.0);
        assert_eq!(c.differing, 2);
        assert_eq!(c.max_abs_diff, 1.0);
        // Pixel 3 is off by ~0.21 in luminance, 1.5 combined σ at σ = 0.1: within 4σ; pixel 2 too.
        assert_eq!(c.within, Some(1.0));
        let tight = vec![DVec3::splat(0.01); 4];
        assert_eq!(
            compare(&a, &b, Some((&tight, &tight)), 4.0).within,
            Some(0.75)
        );
    }
}
