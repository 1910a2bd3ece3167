//! The accumulation file of a partial render (`OUT.accum.exr`, docs/distributed.md): every
//! pass's per-pixel estimates in full f64 precision, with what identifies the render (scene
//! hash, settings hash, seed, the overrides to rebuild the settings) and the pass list.
//!
//! Why per-pass estimates and not sums: the film adds passes into f64 sums in pass order, and
//! f64 addition is not associative, so two partial sums added together give other bits than
//! one render. Replaying the stored estimates in pass order into a fresh film reproduces the
//! single render exactly. Cost: 24 bytes per pixel per pass (before the EXR's lossless
//! compression).
//!
//! Layout: one EXR layer; per pass p, u32 channels `pNNNNNN.{R,G,B}.{hi,lo}` holding the high
//! and low 32 bits of each f64 (EXR has no 64-bit float type); text attributes `accum.*`.
use std::path::{Path, PathBuf};

use exr::prelude::{AnyChannel, AnyChannels, FlatSamples};
use glam::DVec3;

use bdpm_integrator::RenderSettings;
use bdpm_load::{assets_hash, fnv1a};

use crate::cli::Overrides;
use crate::exr::stage_exr_channels;
use crate::files::Staged;

/// The value of `bdpm.accum.format`: bumped when the layout changes.
pub const FORMAT: &str = "bdpm-accumulation-1";

/// Bytes per pixel per pass that an accumulation file's passes take in memory while a
/// command holds them: the pass records (3 × f64) and the copy the writer encodes (6 × u32),
/// or, while reading, the decoded u32 samples and the records built from them. Measured: a
/// merge of 45 passes at 256² peaks at 131.6 MB, 41 B per pixel per pass above a plain render
/// (docs/robustness.md, "Memory of held passes").
pub const BYTES_PER_PIXEL_PASS: u64 = 48;

/// The memory that reading the accumulation file at `path` will take
/// ([`BYTES_PER_PIXEL_PASS`] per pixel per listed pass), from its header alone, so that a
/// merge or resume too large for the memory is refused before it reads.
pub fn held_bytes(path: &Path) -> Result<u64, String> {
    let header = crate::exr::first_header(path)?;
    let passes = header
        .own_attributes
        .other
        .get(&exr::prelude::Text::from("bdpm.accum.passes"))
        .and_then(|v| match v {
            exr::prelude::AttributeValue::Text(t) => Some(t.to_string()),
            _ => None,
        })
        .map(|t| {
            if t.is_empty() {
                0
            } else {
                t.split(',').count() as u64
            }
        })
        .ok_or_else(|| {
            format!(
                "{}: not a bdpm accumulation file (no accum.passes attribute; {GIVE})",
                path.display()
            )
        })?;
    let pixels = (header.layer_size.width() * header.layer_size.height()) as u64;
    Ok(passes
        .saturating_mul(pixels)
        .saturating_mul(BYTES_PER_PIXEL_PASS))
}

/// What to give instead of a file that is not an accumulation file.
const GIVE: &str =
    "give the OUT.accum.exr that render --accumulate, --first-pass or --resume writes";

/// One pass as stored: its global index and what the film and the report need of it.
#[derive(Clone, Debug)]
pub struct PassRecord {
    /// Global pass index (the key of its random streams).
    pub index: u32,
    /// Per-pixel pass estimates, row-major, W·m⁻²·sr⁻¹.
    pub estimates: Vec<DVec3>,
    /// Non-finite samples the pass dropped.
    pub dropped: u64,
    /// Camera samples the pass traced.
    pub samples: u64,
    /// Photons the pass stored.
    pub photons_stored: u64,
}

/// Checks that the image at `path`, whose header attributes are `attributes`, was rendered
/// from the scene whose [`bdpm_load::scene_hash`] is `expected`; `what` names the image's role in the
/// message ("the measured render", "the reference"). An image without the attribute (made by
/// an older bdpm or another program) is refused too when `required`.
pub fn check_scene_hash(
    path: &Path,
    attributes: &[(String, String)],
    expected: &str,
    what: &str,
    required: bool,
) -> Result<(), String> {
    match attributes.iter().find(|(k, _)| k == "scene_hash") {
        Some((_, got)) if got == expected => Ok(()),
        Some((_, got)) => Err(format!(
            "{}: {what} was rendered from another scene (scene hash {got}, this scene's is \
             {expected}: the scene file or a mesh, buffer or image it references differs)",
            path.display()
        )),
        None if required => Err(format!(
            "{}: {what} has no bdpm.scene_hash attribute, so it cannot be checked to be of this \
             scene; render it again with this bdpm",
            path.display()
        )),
        None => Ok(()),
    }
}

/// What makes two partial renders parts of the same render.
#[derive(Clone, Debug, PartialEq)]
pub struct Identity {
    /// The scene file, absolute where it could be resolved.
    pub scene: PathBuf,
    /// FNV-1a of the scene file's bytes, hex.
    pub scene_hash: String,
    /// [`assets_hash`] of the files the scene references; `None` when read from a file of an
    /// older bdpm that did not record it.
    pub assets_hash: Option<String>,
    /// [`settings_hash`]: FNV-1a of the settings' serialised form (pass count excluded), hex;
    /// covers seed, resolution, mode, ….
    pub settings_hash: String,
    /// Master seed (also inside the settings hash; kept readable for error messages).
    pub seed: u64,
    /// The command-line overrides that produced the settings, as arguments.
    pub overrides: Vec<String>,
}

impl Identity {
    /// The identity of a render of `scene` with `settings` made with `overrides`.
    /// `gltf_files` are the glTF files the scene loaded ([`bdpm_load::LoadReport::gltf_files`]).
    pub fn of(
        scene: &Path,
        gltf_files: &[PathBuf],
        settings: &RenderSettings,
        overrides: &Overrides,
    ) -> Result<Identity, String> {
        let bytes =
            std::fs::read(scene).map_err(|e| format!("{}: cannot read: {e}", scene.display()))?;
        Ok(Identity {
            scene: std::fs::canonicalize(scene).unwrap_or_else(|_| scene.to_path_buf()),
            scene_hash: format!("{:016x}", fnv1a(&bytes)),
            assets_hash: Some(assets_hash(gltf_files)),
            settings_hash: settings_hash(settings),
            seed: settings.seed,
            overrides: overrides.to_args(),
        })
    }

    /// `None` when `other` is a part of the same render; else what differs, in words.
    pub fn mismatch(&self, other: &Identity) -> Option<String> {
        if self.scene_hash != other.scene_hash {
            Some(format!(
                "its scene file differs (hash {} against {})",
                other.scene_hash, self.scene_hash
            ))
        } else if let (Some(a), Some(b)) = (&self.assets_hash, &other.assets_hash)
            && a != b
        {
            Some(format!(
                "a mesh, buffer or image file its scene references has changed (assets hash {b} \
                 against {a})"
            ))
        } else if self.seed != other.seed {
            Some(format!(
                "its seed differs ({} against {})",
                other.seed, self.seed
            ))
        } else if self.settings_hash != other.settings_hash {
            let (theirs, ours) = (flags(&other.overrides), flags(&self.overrides));
            let only = |a: &[String], b: &[String]| {
                let v: Vec<&str> = a
                    .iter()
                    .filter(|x| !b.contains(x))
                    .map(String::as_str)
                    .collect();
                if v.is_empty() {
                    "no flag".to_string()
                } else {
                    v.join(" ")
                }
            };
            let told = if theirs == ours {
                String::new()
            } else {
                format!(
                    ": it was rendered with {}, this run has {}",
                    only(&theirs, &ours),
                    only(&ours, &theirs)
                )
            };
            Some(format!(
                "its settings differ (settings hash {} against {}){told}",
                other.settings_hash, self.settings_hash
            ))
        } else {
            None
        }
    }
}

/// Command-line overrides as made by [`Overrides::to_args`], one flag with its value per
/// item (`--resolution 32x32`, `--no-jitter`).
fn flags(args: &[String]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for a in args {
        match out.last_mut() {
            Some(last) if !a.starts_with("--") && !last.contains(' ') => {
                last.push(' ');
                last.push_str(a);
            }
            _ => out.push(a.clone()),
        }
    }
    out
}

/// FNV-1a, hex, of the settings' serialised form (serde, compact JSON: every field under its
/// name in declaration order, the mode, noise model and sampler as their names). A stable
/// basis: it changes when a setting or its name changes, not when `Debug` formatting does.
fn serialised_hash(settings: &RenderSettings) -> String {
    // Plain numbers, strings and options: serialising cannot fail.
    let json = serde_json::to_string(settings).expect("the settings serialise to JSON");
    format!("{:016x}", fnv1a(json.as_bytes()))
}

/// The settings hash of the run identity (`accum.settings_hash`): every setting but the pass
/// count (zeroed before hashing), which is not part of what a part renders (each pass depends
/// on (seed, pass index, …) only), so parts with other pass counts merge and a render resumes
/// with more passes.
pub fn settings_hash(settings: &RenderSettings) -> String {
    serialised_hash(&RenderSettings {
        passes: 0,
        ..settings.clone()
    })
}

/// The settings hash with the seed zeroed as well: the same for two renders that estimate the
/// same image with the same estimator (header attribute `bdpm.estimator_hash`, checked by
/// `predict --measured`).
pub fn estimator_hash(settings: &RenderSettings) -> String {
    serialised_hash(&RenderSettings {
        passes: 0,
        seed: 0,
        ..settings.clone()
    })
}

/// Pass indices as ranges, e.g. `0-3,6,8-9`.
pub fn ranges(passes: &[u32]) -> String {
    let mut out: Vec<String> = Vec::new();
    let mut i = 0;
    while i < passes.len() {
        let mut j = i;
        while j + 1 < passes.len() && passes[j + 1] == passes[j] + 1 {
            j += 1;
        }
        out.push(if i == j {
            passes[i].to_string()
        } else {
            format!("{}-{}", passes[i], passes[j])
        });
        i = j + 1;
    }
    out.join(",")
}

fn list<T: ToString>(values: impl Iterator<Item = T>) -> String {
    values.map(|v| v.to_string()).collect::<Vec<_>>().join(",")
}

/// Stages the accumulation file at `path`: the passes (in the order given, which the callers
/// keep ascending) and the identity, plus `extra` header attributes. The passes are taken by
/// value and each is freed once its channels are built, so that the records and the
/// writer's copy of them are not both held whole.
pub fn stage(
    path: &Path,
    size: (u32, u32),
    identity: &Identity,
    passes: Vec<PassRecord>,
    extra: &[(String, String)],
) -> Result<Staged, String> {
    let mut channels = Vec::with_capacity(passes.len() * 6);
    let mut meta = Vec::with_capacity(passes.len());
    for p in passes {
        for (c, name) in ["R", "G", "B"].iter().enumerate() {
            let bits = || p.estimates.iter().map(move |e| e[c].to_bits());
            let hi = bits().map(|b| (b >> 32) as u32).collect();
            let lo = bits().map(|b| b as u32).collect();
            let base = format!("p{:06}.{name}", p.index);
            channels.push(AnyChannel::new(
                format!("{base}.hi").as_str(),
                FlatSamples::U32(hi),
            ));
            channels.push(AnyChannel::new(
                format!("{base}.lo").as_str(),
                FlatSamples::U32(lo),
            ));
        }
        meta.push((p.index, p.dropped, p.samples, p.photons_stored));
    }
    let mut attrs = extra.to_vec();
    let overrides = serde_json::to_string(&identity.overrides).map_err(|e| e.to_string())?;
    attrs.extend([
        ("accum.format".to_string(), FORMAT.to_string()),
        (
            "accum.scene".into(),
            identity.scene.to_string_lossy().into_owned(),
        ),
        ("accum.scene_hash".into(), identity.scene_hash.clone()),
        (
            "accum.assets_hash".into(),
            identity.assets_hash.clone().unwrap_or_default(),
        ),
        ("accum.settings_hash".into(), identity.settings_hash.clone()),
        ("accum.seed".into(), identity.seed.to_string()),
        ("accum.overrides".into(), overrides),
        ("accum.passes".into(), list(meta.iter().map(|p| p.0))),
        ("accum.dropped".into(), list(meta.iter().map(|p| p.1))),
        ("accum.samples".into(), list(meta.iter().map(|p| p.2))),
        (
            "accum.photons_stored".into(),
            list(meta.iter().map(|p| p.3)),
        ),
    ]);
    stage_exr_channels(path, size, channels, &attrs)
}

/// A partial render read back.
pub struct Accumulation {
    /// The file it came from.
    pub path: PathBuf,
    /// Image size, pixels.
    pub size: (u32, u32),
    /// Which render it is part of.
    pub identity: Identity,
    /// Its passes, ascending by index.
    pub passes: Vec<PassRecord>,
}

/// Reads an accumulation file; every error is one line naming the file. Besides the
/// attributes, the channels are checked: exactly the six u32 channels of each listed pass
/// (a channel re-saved as float or half has lost the f64's bits, and a merge of it would not
/// be the render it claims to be), and every estimate finite (a NaN or infinite bit pattern
/// is refused naming the pass and the pixel; the renderer drops non-finite samples, so none
/// is ever written).
pub fn read(path: &Path) -> Result<Accumulation, String> {
    let image = exr::prelude::read_all_flat_layers_from_file(path)
        .map_err(|e| format!("{}: cannot read EXR: {e}", path.display()))?;
    let bad = |what: &str| format!("{}: not a bdpm accumulation file ({what})", path.display());
    let mut layers = image.layer_data.into_iter();
    let layer = layers.next().ok_or_else(|| bad("no layer"))?;
    if layers.next().is_some() {
        return Err(bad("more than one layer"));
    }
    let attributes: Vec<(String, String)> = layer
        .attributes
        .other
        .iter()
        .filter_map(|(k, v)| match v {
            exr::prelude::AttributeValue::Text(t) => Some((
                k.to_string().trim_start_matches("bdpm.").to_string(),
                t.to_string(),
            )),
            _ => None,
        })
        .collect();
    let (width, height) = (layer.size.width(), layer.size.height());
    let header = read_header(&attributes, &bad)?;
    let mut words = channel_words(layer.channel_data, header.indices.len(), &bad)?;
    let mut passes = Vec::with_capacity(header.indices.len());
    for (i, &index) in header.indices.iter().enumerate() {
        let mut channels = Vec::with_capacity(6);
        for name in ["R", "G", "B"] {
            for half in ["hi", "lo"] {
                let c = format!("p{index:06}.{name}.{half}");
                channels.push(
                    words
                        .remove(&c)
                        .ok_or_else(|| bad(&format!("pass {index} has no channel {c}")))?,
                );
            }
        }
        passes.push(PassRecord {
            index,
            estimates: pass_estimates(path, index, &channels, (width, height))?,
            dropped: header.dropped[i],
            samples: header.samples[i],
            photons_stored: header.photons[i],
        });
    }
    Ok(Accumulation {
        path: path.to_path_buf(),
        size: (width as u32, height as u32),
        identity: header.identity,
        passes,
    })
}

/// What an accumulation file's attributes say: which render it is part of, and per pass its
/// index and counts.
struct Header {
    identity: Identity,
    indices: Vec<u32>,
    dropped: Vec<u64>,
    samples: Vec<u64>,
    photons: Vec<u64>,
}

/// Reads the `accum.*` attributes (`bdpm.` prefix removed); `bad` makes the message of a
/// file that is not an accumulation file.
fn read_header(
    attributes: &[(String, String)],
    bad: &dyn Fn(&str) -> String,
) -> Result<Header, String> {
    let attr = |k: &str| {
        attributes
            .iter()
            .find(|(n, _)| n == k)
            .map(|(_, v)| v.as_str())
            .ok_or_else(|| bad(&format!("no {k} attribute; {GIVE}")))
    };
    let format = attr("accum.format")?;
    if format != FORMAT {
        return Err(bad(&format!(
            "format '{format}', this bdpm reads '{FORMAT}'"
        )));
    }
    fn numbers<T: std::str::FromStr>(s: &str) -> Option<Vec<T>> {
        if s.is_empty() {
            return Some(Vec::new());
        }
        s.split(',').map(|x| x.parse().ok()).collect()
    }
    let field = |k: &str| -> Result<Vec<u64>, String> {
        numbers(attr(k)?).ok_or_else(|| bad(&format!("{k} is not a list of numbers")))
    };
    let indices: Vec<u32> = numbers(attr("accum.passes")?)
        .ok_or_else(|| bad("accum.passes is not a list of pass numbers"))?;
    let (dropped, samples, photons) = (
        field("accum.dropped")?,
        field("accum.samples")?,
        field("accum.photons_stored")?,
    );
    if [dropped.len(), samples.len(), photons.len()] != [indices.len(); 3] {
        return Err(bad("the per-pass lists differ in length"));
    }
    if indices.windows(2).any(|w| w[0] >= w[1]) {
        return Err(bad("accum.passes is not strictly ascending"));
    }
    let overrides: Vec<String> = serde_json::from_str(attr("accum.overrides")?)
        .map_err(|_| bad("accum.overrides is not a JSON list of strings"))?;
    let seed = attr("accum.seed")?
        .parse()
        .map_err(|_| bad("accum.seed is not a number"))?;
    let identity = Identity {
        scene: PathBuf::from(attr("accum.scene")?),
        scene_hash: attr("accum.scene_hash")?.to_string(),
        assets_hash: attr("accum.assets_hash")
            .ok()
            .filter(|h| !h.is_empty())
            .map(str::to_string),
        settings_hash: attr("accum.settings_hash")?.to_string(),
        seed,
        overrides,
    };
    Ok(Header {
        identity,
        indices,
        dropped,
        samples,
        photons,
    })
}

/// The channels of `passes` passes by name, as u32 words; each is moved out once into its
/// pass by the caller, so that the decoded file and the records built from it are not both
/// held whole.
fn channel_words(
    channels: AnyChannels<FlatSamples>,
    passes: usize,
    bad: &dyn Fn(&str) -> String,
) -> Result<std::collections::HashMap<String, Vec<u32>>, String> {
    let expected = passes * 6;
    let found = channels.list.len();
    if found != expected {
        return Err(bad(&format!(
            "{found} channels for {passes} passes, which have {expected}"
        )));
    }
    let mut words: std::collections::HashMap<String, Vec<u32>> = Default::default();
    for c in channels.list {
        let name = c.name.to_string();
        match c.sample_data {
            FlatSamples::U32(v) => {
                let _ = words.insert(name, v);
            }
            FlatSamples::F16(_) | FlatSamples::F32(_) => {
                return Err(bad(&format!(
                    "channel {name} holds floating-point samples, not the u32 halves of an f64 \
                     (was the file re-saved by another program?)"
                )));
            }
        }
    }
    Ok(words)
}

/// The estimates of pass `index` from its six channels (the high and low words of R, G and
/// B, `width`×`height` samples each), every one finite.
fn pass_estimates(
    path: &Path,
    index: u32,
    channels: &[Vec<u32>],
    (width, height): (usize, usize),
) -> Result<Vec<DVec3>, String> {
    let pixels = width * height;
    if channels.len() != 6 || channels.iter().any(|c| c.len() != pixels) {
        return Err(format!(
            "{}: not a bdpm accumulation file (pass {index}'s channels do not hold one sample \
             per pixel)",
            path.display()
        ));
    }
    let word = |c: usize, px: usize| {
        f64::from_bits(((channels[2 * c][px] as u64) << 32) | channels[2 * c + 1][px] as u64)
    };
    let mut estimates = Vec::with_capacity(pixels);
    for px in 0..pixels {
        let e = DVec3::new(word(0, px), word(1, px), word(2, px));
        if !e.is_finite() {
            return Err(format!(
                "{}: pass {index} holds a non-finite estimate ({}, {}, {}) at pixel ({}, {}) \
                 (x, y from the top left): the file is damaged",
                path.display(),
                e.x,
                e.y,
                e.z,
                px % width,
                px / width
            ));
        }
        estimates.push(e);
    }
    Ok(estimates)
}

/// Checks that `parts` are parts of one render with disjoint pass sets, and returns them as
/// one (all their passes sorted by index, named after the part holding the lowest pass) with
/// the parts' files in pass order: neither depends on the order of the parts. Errors are one
/// line naming the offending file.
pub fn combine(parts: Vec<Accumulation>) -> Result<(Accumulation, Vec<PathBuf>), String> {
    let first_pass = |p: &Accumulation| p.passes.first().map_or(u32::MAX, |r| r.index);
    let reference = parts
        .iter()
        .min_by_key(|p| first_pass(p))
        .ok_or("no parts to merge")?;
    for p in &parts {
        if let Some(why) = reference.identity.mismatch(&p.identity) {
            return Err(format!(
                "{}: not a part of the same render as {}: {why}",
                p.path.display(),
                reference.path.display()
            ));
        }
        if p.size != reference.size {
            return Err(format!(
                "{}: image size {}x{} differs from {}x{} of {}",
                p.path.display(),
                p.size.0,
                p.size.1,
                reference.size.0,
                reference.size.1,
                reference.path.display()
            ));
        }
    }
    for (i, p) in parts.iter().enumerate() {
        let same = |q: &Accumulation| {
            std::fs::canonicalize(&q.path).ok() == std::fs::canonicalize(&p.path).ok()
        };
        if parts[..i].iter().any(same) {
            return Err(format!(
                "{}: given twice; name each part once",
                p.path.display()
            ));
        }
    }
    let mut owner: std::collections::BTreeMap<u32, &Path> = Default::default();
    for p in &parts {
        let shared: Vec<u32> = p
            .passes
            .iter()
            .map(|r| r.index)
            .filter(|i| owner.contains_key(i))
            .collect();
        if let Some(o) = shared.last().and_then(|i| owner.get(i)) {
            return Err(format!(
                "{}: passes {} are also in {}",
                p.path.display(),
                ranges(&shared),
                o.display()
            ));
        }
        owner.extend(p.passes.iter().map(|r| (r.index, p.path.as_path())));
    }
    let (path, size, identity) = (
        reference.path.clone(),
        reference.size,
        reference.identity.clone(),
    );
    let mut sources: Vec<(u32, PathBuf)> = parts
        .iter()
        .map(|p| (first_pass(p), p.path.clone()))
        .collect();
    sources.sort();
    let mut passes: Vec<PassRecord> = parts.into_iter().flat_map(|p| p.passes).collect();
    passes.sort_by_key(|p| p.index);
    let merged = Accumulation {
        path,
        size,
        identity,
        passes,
    };
    Ok((merged, sources.into_iter().map(|(_, p)| p).collect()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The identity hashes the serialised settings: a setting that shapes the image changes
    /// them, the pass count (and for the estimator hash the seed) does not, and the value for
    /// the defaults is pinned, so that a change of the serialised form (a renamed or reordered
    /// field) is seen here first: it makes older accumulation files another run
    /// (docs/distributed.md).
    #[test]
    fn the_settings_hashes_follow_the_serialised_settings() {
        use bdpm_integrator::{Mode, Sampler};
        let base = RenderSettings::default();
        let json = serde_json::to_string(&RenderSettings {
            passes: 0,
            ..base.clone()
        })
        .unwrap();
        assert_eq!(
            settings_hash(&base),
            format!("{:016x}", fnv1a(json.as_bytes()))
        );
        assert_eq!(settings_hash(&base), "113737363703d83e");
        let changed = |f: &dyn Fn(&mut RenderSettings)| {
            let mut s = base.clone();
            f(&mut s);
            (settings_hash(&s), estimator_hash(&s))
        };
        let (settings, estimator) = (settings_hash(&base), estimator_hash(&base));
        assert_eq!(
            changed(&|s| s.passes = 99),
            (settings.clone(), estimator.clone())
        );
        let (s, e) = changed(&|s| s.seed = 2);
        assert_ne!(s, settings);
        assert_eq!(e, estimator);
        let relevant: [&dyn Fn(&mut RenderSettings); 10] = [
            &|s| s.spp = 5,
            &|s| s.light_tracing = true,
            &|s| s.adaptive_radius = true,
            &|s| s.mode = Mode::Path,
            &|s| s.threshold_radius = 0.3,
            &|s| s.clamp_weights = true,
            &|s| s.radius_px = Some(1.0),
            &|s| s.sampler = Sampler::Independent,
            &|s| s.direct_boost = 1,
            &|s| s.direct_boost = 4,
        ];
        for f in relevant {
            let (s, e) = changed(f);
            assert!(s != settings && e != estimator);
        }
    }

    #[test]
    fn ranges_compress_runs() {
        assert_eq!(ranges(&[0, 1, 2, 3, 6, 8, 9]), "0-3,6,8-9");
        assert_eq!(ranges(&[]), "");
    }
}
