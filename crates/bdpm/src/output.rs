//! Image and report files: EXR (mean, √V and standard-error layers, settings as header
//! attributes), a tonemapped sRGB PNG preview, and atomic writes for all of them.
use std::fs;
use std::io::{self, Write as _};
use std::path::{Path, PathBuf};
use std::time::SystemTime;

use bdpm_integrator::Film;
use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, Layer, LayerAttributes,
    SmallVec, Text, WritableImage, read_all_flat_layers_from_file,
};
use glam::DVec3;

use crate::colormap::{Legend, compose, linear_ticks, viridis};

/// The first layer of an EXR file read back: its size, every channel as f64 (any sample
/// type) and its text attributes (`bdpm.` prefix removed). The one EXR reader of the driver.
pub(crate) struct ExrLayer {
    /// Width, pixels.
    pub(crate) width: u32,
    /// Height, pixels.
    pub(crate) height: u32,
    channels: Vec<(String, Vec<f64>)>,
    /// Text header attributes as (key without `bdpm.`, value).
    pub(crate) attributes: Vec<(String, String)>,
}

impl ExrLayer {
    /// Reads the first layer of `path`; errors name the file.
    pub(crate) fn read(path: &Path) -> Result<ExrLayer, String> {
        let image = read_all_flat_layers_from_file(path)
            .map_err(|e| format!("{}: cannot read EXR: {e}", path.display()))?;
        let layer = image
            .layer_data
            .first()
            .ok_or_else(|| format!("{}: EXR has no layer", path.display()))?;
        let channels = layer
            .channel_data
            .list
            .iter()
            .map(|c| {
                let values = match &c.sample_data {
                    FlatSamples::F16(v) => v.iter().map(|x| x.to_f64()).collect(),
                    FlatSamples::F32(v) => v.iter().map(|x| *x as f64).collect(),
                    FlatSamples::U32(v) => v.iter().map(|x| *x as f64).collect(),
                };
                (c.name.to_string(), values)
            })
            .collect();
        let attributes = layer
            .attributes
            .other
            .iter()
            .filter_map(|(k, v)| match v {
                AttributeValue::Text(t) => Some((
                    k.to_string().trim_start_matches("bdpm.").to_string(),
                    t.to_string(),
                )),
                _ => None,
            })
            .collect();
        Ok(ExrLayer {
            width: layer.size.width() as u32,
            height: layer.size.height() as u32,
            channels,
            attributes,
        })
    }

    /// The channel called `name` (e.g. `R`, `noise.G`), if present.
    pub(crate) fn channel(&self, name: &str) -> Option<&[f64]> {
        self.channels
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }
}

/// The files of one render, with the same stem.
#[derive(Clone, Debug)]
pub(crate) struct Outputs {
    pub(crate) exr: PathBuf,
    pub(crate) png: PathBuf,
    /// OUT-noise.png: the false-colour noise map.
    pub(crate) noise_png: PathBuf,
    pub(crate) json: PathBuf,
}

impl Outputs {
    /// OUT.exr, OUT.png, OUT-noise.png and OUT.json for a requested OUT(.exr).
    pub(crate) fn beside(exr: &Path) -> Outputs {
        let exr = exr.with_extension("exr");
        let stem = exr
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        Outputs {
            png: exr.with_extension("png"),
            noise_png: exr.with_file_name(format!("{stem}-noise.png")),
            json: exr.with_extension("json"),
            exr,
        }
    }

    /// Every path, in the order the render writes them.
    pub(crate) fn all(&self) -> [&Path; 4] {
        [&self.exr, &self.png, &self.noise_png, &self.json]
    }
}

/// Suffix of every temporary file the driver writes. A render removes stale ones of its own
/// outputs (left by a process killed while writing) once it holds the output's lock.
const TEMP_SUFFIX: &str = ".bdpm-tmp";

/// The file name of `path` as text ("" if it has none).
fn file_name_of(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The directory `path` is in ("." for a bare file name).
fn dir_of(path: &Path) -> &Path {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    }
}

/// A new temporary file beside `path` (so that the final rename stays on one file system),
/// named `.NAME.<random>.bdpm-tmp`. It is created exclusively (`O_EXCL`) under a name nobody
/// can predict, so that a symlink planted in the directory cannot redirect the write; the
/// previous `.NAME.PID.tmp` names could be guessed. The mode is 0666 less the umask, as
/// `fs::write` would give. Dropped without [`Staged::commit`], the file is removed.
fn temp_beside(path: &Path) -> io::Result<tempfile::NamedTempFile> {
    let mut builder = tempfile::Builder::new();
    let prefix = format!(".{}.", file_name_of(path));
    builder.prefix(&prefix).suffix(TEMP_SUFFIX).rand_bytes(10);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt as _;
        let _ = builder.permissions(fs::Permissions::from_mode(0o666));
    }
    builder.tempfile_in(dir_of(path))
}

fn ensure_parent(path: &Path) -> io::Result<()> {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => fs::create_dir_all(dir),
        _ => Ok(()),
    }
}

/// A finished file waiting under a temporary name beside its target: [`Staged::commit`]
/// renames it into place; dropping it removes it, leaving the target untouched.
pub(crate) struct Staged {
    file: tempfile::NamedTempFile,
    target: PathBuf,
}

impl Staged {
    /// The final path.
    pub(crate) fn target(&self) -> &Path {
        &self.target
    }

    /// Renames the file into place: the target is replaced whole.
    pub(crate) fn commit(self) -> Result<(), String> {
        self.file
            .persist(&self.target)
            .map(drop)
            .map_err(|e| format!("cannot move the finished file into place: {}", e.error))
    }
}

/// Runs `write` on a new temporary file beside `path` and flushes it to disk, so that a full
/// disk shows here and not after the rename.
pub(crate) fn stage(
    path: &Path,
    write: impl FnOnce(&mut fs::File) -> Result<(), String>,
) -> Result<Staged, String> {
    let mut file =
        temp_beside(path).map_err(|e| format!("cannot create a temporary file beside it: {e}"))?;
    write(file.as_file_mut())?;
    file.as_file()
        .sync_all()
        .map_err(|e| format!("cannot write: {e}"))?;
    Ok(Staged {
        file,
        target: path.to_path_buf(),
    })
}

/// [`stage`] for bytes already in memory.
pub(crate) fn stage_bytes(path: &Path, bytes: &[u8]) -> Result<Staged, String> {
    stage(path, |f| {
        f.write_all(bytes).map_err(|e| format!("cannot write: {e}"))
    })
}

/// Runs `write` on a temporary file beside `path`, then renames it over `path`: an existing
/// file is either left whole or replaced whole, never half-written.
pub(crate) fn write_via_temp(
    path: &Path,
    write: impl FnOnce(&mut fs::File) -> Result<(), String>,
) -> Result<(), String> {
    ensure_parent(path).map_err(|e| format!("cannot create the directory: {e}"))?;
    stage(path, write)?.commit()
}

/// Writes bytes atomically (temporary file, then rename).
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), String> {
    write_via_temp(path, |f| {
        f.write_all(bytes).map_err(|e| format!("cannot write: {e}"))
    })
}

/// Checks that `path` can be written as an output file: it is not a directory, a device, a
/// FIFO or a socket (a symlink is judged by what it points to; the rename replaces the link
/// itself, never its target).
fn check_output_name(path: &Path, what: &str) -> Result<(), String> {
    match fs::metadata(path) {
        Ok(m) if m.is_dir() => Err(format!(
            "{}: {what} is a directory; give a file name such as {}",
            path.display(),
            path.join("render.exr").display()
        )),
        Ok(m) if !m.is_file() => Err(format!(
            "{}: {what} is not a regular file (a device, FIFO or socket); bdpm writes several \
             files beside the name given, so give a file name in a writable directory",
            path.display()
        )),
        _ => Ok(()),
    }
}

/// A render's claim on its output: an exclusive advisory lock (`flock`) on the hidden file
/// `.OUT.exr.lock` beside the EXR, held from before the render starts until its files are in
/// place, so that a second render to the same output stops at once with a clear message
/// instead of interleaving its files with the first one's. The lock file is removed on drop;
/// the kernel releases the lock itself if the process dies, so a stale lock file never blocks.
pub(crate) struct OutputLock {
    file: fs::File,
    path: PathBuf,
}

impl OutputLock {
    /// Takes the lock of the output whose EXR is `exr`, or says who holds it.
    fn acquire(exr: &Path) -> Result<OutputLock, String> {
        let path = exr.with_file_name(format!(".{}.lock", file_name_of(exr)));
        // A holder that finishes unlinks the file; if that happens between our open and our
        // lock, we hold a lock on a file nobody else will see, so we check and try again.
        for _ in 0..16 {
            let file = open_lock_file(&path)
                .map_err(|e| format!("{}: cannot create the lock file: {e}", path.display()))?;
            match file.try_lock() {
                Ok(()) => {}
                Err(fs::TryLockError::WouldBlock) => {
                    return Err(format!(
                        "{}: another bdpm render is writing this output (it holds {}); wait for it \
                         to finish or choose another -o",
                        exr.display(),
                        path.display()
                    ));
                }
                Err(fs::TryLockError::Error(e)) => {
                    return Err(format!("{}: cannot lock: {e}", path.display()));
                }
            }
            if same_file(&file, &path) {
                return Ok(OutputLock { file, path });
            }
        }
        Err(format!(
            "{}: the lock file keeps being replaced; is another program removing it?",
            path.display()
        ))
    }
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        // Removed while still locked, so that a waiting process sees either our locked file
        // or no file (the check in `acquire` handles the race).
        let _ = fs::remove_file(&self.path);
        let _ = self.file.unlock();
    }
}

/// Opens (creating if needed) a lock file without following a symlink at its name.
fn open_lock_file(path: &Path) -> io::Result<fs::File> {
    let mut options = fs::OpenOptions::new();
    let _ = options.read(true).write(true).create(true).truncate(false);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt as _;
        let _ = options.mode(0o600).custom_flags(libc::O_NOFOLLOW);
    }
    options.open(path)
}

/// Whether the open `file` is still the file at `path` (not unlinked or replaced).
#[cfg(unix)]
fn same_file(file: &fs::File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt as _;
    match (file.metadata(), fs::symlink_metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_file(_file: &fs::File, path: &Path) -> bool {
    path.is_file()
}

/// Removes the temporary files of `outputs` (our naming pattern, regular files only) that
/// are older than `started`: leftovers of a render killed while writing. Called with the
/// output's lock held, so no live render of this output owns them.
fn remove_stale_temps(outputs: &Outputs, started: SystemTime) {
    let dir = dir_of(&outputs.exr);
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    let prefixes: Vec<String> = outputs
        .all()
        .iter()
        .map(|p| format!(".{}.", file_name_of(p)))
        .collect();
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if !name.ends_with(TEMP_SUFFIX) || !prefixes.iter().any(|p| name.starts_with(p)) {
            continue;
        }
        let stale = entry
            .metadata()
            .is_ok_and(|m| m.file_type().is_file() && m.modified().is_ok_and(|t| t < started));
        if stale {
            let _ = fs::remove_file(entry.path());
        }
    }
}

/// Makes sure that a render's outputs can be written before any work is done: the requested
/// name and each of the four files is not a directory or a device, the directory exists (it
/// is created) and accepts a new file (a probe temporary file is created and removed), and no
/// other render holds the output. Returns the lock, to be held until the files are in place;
/// stale temporaries older than `started` are removed.
pub(crate) fn claim(
    requested: &Path,
    outputs: &Outputs,
    started: SystemTime,
) -> Result<OutputLock, String> {
    if requested.file_name().is_none() {
        return Err(format!(
            "{}: the output names no file; give a name such as out/render.exr",
            requested.display()
        ));
    }
    check_output_name(requested, "the output")?;
    for p in outputs.all() {
        check_output_name(p, "an output file")?;
    }
    let dir = dir_of(&outputs.exr);
    if fs::metadata(dir).is_ok_and(|m| !m.is_dir()) {
        return Err(format!(
            "{}: the output directory is a file, not a directory",
            dir.display()
        ));
    }
    ensure_parent(&outputs.exr)
        .map_err(|e| format!("{}: cannot create the output directory: {e}", dir.display()))?;
    drop(temp_beside(&outputs.exr).map_err(|e| {
        format!(
            "{}: cannot write in the output directory: {e}",
            dir.display()
        )
    })?);
    let lock = OutputLock::acquire(&outputs.exr)?;
    remove_stale_temps(outputs, started);
    Ok(lock)
}

/// Renames staged files into place in order. The caller puts the EXR last: it is the commit
/// point of the set, and its `bdpm.run_id` matches the report's `run_id` only once every file
/// of the run is in place. If a rename fails, the files not yet renamed are removed.
pub(crate) fn commit_all(staged: Vec<Staged>) -> Result<(), String> {
    for s in staged {
        let target = s.target().to_path_buf();
        s.commit()
            .map_err(|e| format!("{}: {e}", target.display()))?;
    }
    Ok(())
}

/// An identifier for one run, written into the EXR header and the JSON report so that a
/// reader can tell files of the same run from a mix: 64 random bits as hex.
pub(crate) fn run_id() -> String {
    use std::hash::{BuildHasher as _, Hasher as _};
    let mut h = std::hash::RandomState::new().build_hasher();
    h.write_u32(std::process::id());
    h.write_u128(
        SystemTime::now()
            .duration_since(SystemTime::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos()),
    );
    format!("{:016x}", h.finish())
}

fn channel(name: &str, values: impl Iterator<Item = f32>) -> AnyChannel<FlatSamples> {
    AnyChannel::new(name, FlatSamples::F32(values.collect()))
}

/// Sample type of an EXR's colour and layer channels (`--exr-precision`); the accumulation
/// file is always exact and does not use this.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Precision {
    /// 32-bit float (the default).
    #[default]
    Float,
    /// 16-bit half float: half the size, about 3 significant digits, overflows above 65504.
    Half,
}

/// An extra EXR layer: name, its three channel names and per-pixel values.
pub(crate) type ExtraLayer<'a> = (&'a str, [&'a str; 3], Vec<DVec3>);

/// Channel names of an RGB layer.
pub(crate) const RGB: [&str; 3] = ["R", "G", "B"];

fn rgb_channels(
    prefix: &str,
    names: [&str; 3],
    data: &[DVec3],
    precision: Precision,
    out: &mut Vec<AnyChannel<FlatSamples>>,
) {
    for (c, name) in names.iter().enumerate() {
        let full = if prefix.is_empty() {
            name.to_string()
        } else {
            format!("{prefix}.{name}")
        };
        let values = data.iter().map(|v| v[c]);
        let samples = match precision {
            Precision::Float => FlatSamples::F32(values.map(|x| x as f32).collect()),
            Precision::Half => FlatSamples::F16(values.map(exr::prelude::f16::from_f64).collect()),
        };
        out.push(AnyChannel::new(full.as_str(), samples));
    }
}

/// Writes the film as a float32 EXR: default R, G, B = mean radiance (W·m⁻²·sr⁻¹); layer
/// `noise` = √(per-pass variance) (the preprint's √V); layer `stderr` = standard error of the
/// mean. `attributes` go into the header as text.
pub(crate) fn write_exr(
    path: &Path,
    film: &Film,
    attributes: &[(String, String)],
) -> Result<(), String> {
    let channels = film_channels(film, &[], Precision::Float);
    write_channels(path, (film.width(), film.height()), channels, attributes)
}

/// The film's mean, `noise` and `stderr` RGB layers, then `extra`, at `precision`.
fn film_channels(
    film: &Film,
    extra: &[ExtraLayer<'_>],
    precision: Precision,
) -> Vec<AnyChannel<FlatSamples>> {
    let mean = film.mean();
    let noise: Vec<DVec3> = film
        .pass_variance()
        .into_iter()
        .map(|v| v.map(f64::sqrt))
        .collect();
    let stderr = film.standard_error();
    let mut channels = Vec::new();
    rgb_channels("", RGB, &mean, precision, &mut channels);
    rgb_channels("noise", RGB, &noise, precision, &mut channels);
    rgb_channels("stderr", RGB, &stderr, precision, &mut channels);
    for (name, names, data) in extra {
        rgb_channels(name, *names, data, precision, &mut channels);
    }
    channels
}

/// Stages the film's EXR (see [`write_exr`]) plus `extra` layers (e.g. the technique or
/// first-hit layers) at `precision`, as a temporary file beside `path` (see [`stage`]).
pub(crate) fn stage_exr_with_layers(
    path: &Path,
    film: &Film,
    attributes: &[(String, String)],
    extra: &[ExtraLayer<'_>],
    precision: Precision,
) -> Result<Staged, String> {
    let channels = film_channels(film, extra, precision);
    stage(path, |f| {
        encode_channels(f, (film.width(), film.height()), channels, attributes)
    })
}

/// Stages an EXR of arbitrary `channels` (any sample type) beside `path`, e.g. the
/// accumulation file's u32 channels (see [`crate::accum`]).
pub(crate) fn stage_exr_channels(
    path: &Path,
    size: (u32, u32),
    channels: Vec<AnyChannel<FlatSamples>>,
    attributes: &[(String, String)],
) -> Result<Staged, String> {
    stage(path, |f| encode_channels(f, size, channels, attributes))
}

/// Writes a float32 EXR with one channel, e.g. the weight map's `w0`.
pub(crate) fn write_exr_single(
    path: &Path,
    size: (u32, u32),
    name: &str,
    values: &[f64],
    attributes: &[(String, String)],
) -> Result<(), String> {
    let channels = vec![channel(name, values.iter().map(|v| *v as f32))];
    write_channels(path, size, channels, attributes)
}

/// Writes a float32 EXR with several single-value channels (name, per-pixel values).
pub(crate) fn write_exr_channels(
    path: &Path,
    size: (u32, u32),
    named: &[(&str, &[f64])],
    attributes: &[(String, String)],
) -> Result<(), String> {
    let channels = named
        .iter()
        .map(|(name, values)| channel(name, values.iter().map(|v| *v as f32)))
        .collect();
    write_channels(path, size, channels, attributes)
}

/// Writes `channels` as one EXR layer with `attributes` as `bdpm.*` text header attributes.
fn write_channels(
    path: &Path,
    size: (u32, u32),
    channels: Vec<AnyChannel<FlatSamples>>,
    attributes: &[(String, String)],
) -> Result<(), String> {
    write_via_temp(path, |f| encode_channels(f, size, channels, attributes))
}

/// Encodes `channels` as one EXR layer into `file` (through the open handle: the file is
/// never reopened by name).
fn encode_channels(
    file: &mut fs::File,
    (width, height): (u32, u32),
    channels: Vec<AnyChannel<FlatSamples>>,
    attributes: &[(String, String)],
) -> Result<(), String> {
    let mut attrs = LayerAttributes::named("bdpm");
    for (k, v) in attributes {
        attrs.other.insert(
            Text::from(format!("bdpm.{k}").as_str()),
            AttributeValue::Text(Text::from(v.as_str())),
        );
    }
    let layer = Layer::new(
        (width as usize, height as usize),
        attrs,
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(SmallVec::from_vec(channels)),
    );
    let image = Image::from_layer(layer);
    let mut writer = io::BufWriter::new(file);
    image
        .write()
        .to_buffered(&mut writer)
        .map_err(|e| format!("cannot write EXR: {e}"))?;
    writer.flush().map_err(|e| format!("cannot write EXR: {e}"))
}

/// Linear → sRGB transfer function, in [0, 1].
fn srgb(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Exposure that maps the 99th-percentile luminance to 1: robust to a few hot pixels such as
/// the Cornell ceiling spot, and deterministic.
fn auto_exposure(mean: &[DVec3]) -> f64 {
    let mut lum: Vec<f64> = mean
        .iter()
        .map(|c| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z)
        .filter(|l| l.is_finite() && *l > 0.0)
        .collect();
    if lum.is_empty() {
        return 1.0;
    }
    lum.sort_by(f64::total_cmp);
    let p = lum[((lum.len() - 1) as f64 * 0.99) as usize];
    if p > 0.0 { 1.0 / p } else { 1.0 }
}

/// Encodes an 8-bit RGB PNG in memory, so that an encoder error cannot leave a half-written
/// temporary file, and a write error is reported (not lost in a drop).
pub(crate) fn encode_png_rgb8(width: u32, height: u32, rgb: &[u8]) -> Result<Vec<u8>, String> {
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc
            .write_header()
            .map_err(|e| format!("cannot write PNG: {e}"))?;
        w.write_image_data(rgb)
            .map_err(|e| format!("cannot write PNG: {e}"))?;
        w.finish().map_err(|e| format!("cannot write PNG: {e}"))?;
    }
    Ok(bytes)
}

/// Writes an 8-bit RGB image atomically.
pub(crate) fn write_png_rgb8(
    path: &Path,
    width: u32,
    height: u32,
    rgb: &[u8],
) -> Result<(), String> {
    write_atomic(path, &encode_png_rgb8(width, height, rgb)?)
}

/// The tonemapped preview of the mean as PNG bytes: auto exposure, clamp, sRGB.
pub(crate) fn encode_png(film: &Film) -> Result<Vec<u8>, String> {
    let mean = film.mean();
    let k = auto_exposure(&mean);
    let rgb: Vec<u8> = mean
        .iter()
        .flat_map(|c| [c.x, c.y, c.z])
        .map(|v| (srgb(v * k) * 255.0 + 0.5) as u8)
        .collect();
    encode_png_rgb8(film.width(), film.height(), &rgb)
}

/// Writes the tonemapped preview of the mean atomically (see [`encode_png`]).
pub(crate) fn write_png(path: &Path, film: &Film) -> Result<(), String> {
    write_atomic(path, &encode_png(film)?)
}

/// Rec. 709 luminance of a linear RGB value.
pub(crate) fn luminance(c: DVec3) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// The 99th percentile of the finite positive values (0 if there are none): the top of a
/// colour scale that a few hot pixels cannot stretch.
pub(crate) fn robust_max(values: &[f64]) -> f64 {
    let mut v: Vec<f64> = values
        .iter()
        .copied()
        .filter(|x| x.is_finite() && *x > 0.0)
        .collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * 0.99).round() as usize]
}

/// The noise map as PNG bytes: `noise` (√V of the pixel luminance per pass, W·m⁻²·sr⁻¹) in viridis
/// on a linear scale from 0 to its 99th percentile (brighter pixels clamp to the top colour),
/// with the colour bar and its scale drawn on the image. With fewer than two passes V is
/// unknown; the map is then flat and the legend says so.
pub(crate) fn encode_noise_png(
    (width, height): (u32, u32),
    noise: &[f64],
    passes: u32,
) -> Result<Vec<u8>, String> {
    let max = robust_max(noise);
    let colours: Vec<[u8; 3]> = noise
        .iter()
        .map(|v| viridis(if max > 0.0 { v / max } else { 0.0 }))
        .collect();
    let mut title = vec![
        "noise sqrt V".to_string(),
        "W m-2 sr-1".into(),
        "linear, max p99".into(),
    ];
    if passes < 2 {
        title.push(format!("{passes} pass: V unknown"));
    }
    let legend = Legend {
        title,
        ticks: linear_ticks(max),
    };
    let layout = compose(width, height, &colours, &legend, viridis);
    let c = &layout.canvas;
    encode_png_rgb8(c.width, c.height, &c.rgb)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("bdpm-output-{tag}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).expect("create scratch dir");
        dir
    }

    fn hidden(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .expect("read dir")
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with('.'))
            .collect();
        v.sort();
        v
    }

    /// Temporary names are unpredictable and distinct, and follow the pattern that stale-temp
    /// removal matches.
    #[test]
    fn temporary_names_are_random_and_exclusive() {
        let dir = scratch("names");
        let target = dir.join("x.exr");
        let a = temp_beside(&target).expect("temp a");
        let b = temp_beside(&target).expect("temp b");
        let (na, nb) = (file_name_of(a.path()), file_name_of(b.path()));
        assert_ne!(na, nb);
        for n in [&na, &nb] {
            assert!(n.starts_with(".x.exr.") && n.ends_with(TEMP_SUFFIX), "{n}");
            assert!(!n.contains(&std::process::id().to_string()), "{n}");
        }
        drop((a, b));
        assert!(hidden(&dir).is_empty(), "{:?}", hidden(&dir));
        let _ = fs::remove_dir_all(&dir);
    }

    /// A failure while staging the third file of a set leaves every target as it was and no
    /// temporary file behind: nothing is renamed until all files are complete.
    #[test]
    fn a_failed_stage_leaves_the_old_set_whole() {
        let dir = scratch("set");
        let names = ["x.png", "x.json", "x.exr"];
        for n in names {
            fs::write(dir.join(n), b"old").expect("write old");
        }
        let result = (|| -> Result<(), String> {
            let png = stage_bytes(&dir.join("x.png"), b"new")?;
            let json = stage_bytes(&dir.join("x.json"), b"new")?;
            let exr = stage(&dir.join("x.exr"), |_| Err("disk full".to_string()))?;
            commit_all(vec![png, json, exr])
        })();
        assert_eq!(result, Err("disk full".to_string()));
        for n in names {
            assert_eq!(fs::read(dir.join(n)).expect("read"), b"old", "{n}");
        }
        assert!(hidden(&dir).is_empty(), "{:?}", hidden(&dir));
        let _ = fs::remove_dir_all(&dir);
    }

    /// The lock refuses a second holder, and is removed (and free) once dropped.
    #[test]
    fn the_output_lock_is_exclusive() {
        let dir = scratch("lock");
        let exr = dir.join("x.exr");
        let first = OutputLock::acquire(&exr).expect("first lock");
        let second = OutputLock::acquire(&exr)
            .err()
            .expect("second lock refused");
        assert!(second.contains("another bdpm render"), "{second}");
        drop(first);
        assert!(hidden(&dir).is_empty(), "{:?}", hidden(&dir));
        drop(OutputLock::acquire(&exr).expect("lock after release"));
        let _ = fs::remove_dir_all(&dir);
    }
}
