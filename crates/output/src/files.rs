//! Output files and their atomic writing: temporary files beside the target renamed into
//! place, output sets committed EXR last, and the lock that keeps two renders off one output.
use std::fs;
use std::io::{self, Write as _};
use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// The files of one render, with the same stem.
#[derive(Clone, Debug)]
pub struct Outputs {
    /// OUT.exr: the image and its layers; written last, the commit point of the set.
    pub exr: PathBuf,
    /// OUT.png: the tonemapped preview.
    pub png: PathBuf,
    /// OUT-noise.png: the false-colour noise map.
    pub noise_png: PathBuf,
    /// OUT.json: the run report.
    pub json: PathBuf,
    /// OUT.accum.exr: the accumulation file, written only with `--accumulate`,
    /// `--first-pass`, `--resume` and by `bdpm merge`.
    pub accum: PathBuf,
}

impl Outputs {
    /// OUT.exr, OUT.png, OUT-noise.png, OUT.json and OUT.accum.exr for a requested OUT(.exr).
    pub fn beside(exr: &Path) -> Outputs {
        let exr = exr.with_extension("exr");
        let stem = stem_of(&exr, "");
        Outputs {
            png: exr.with_extension("png"),
            noise_png: exr.with_file_name(format!("{stem}-noise.png")),
            json: exr.with_extension("json"),
            accum: exr.with_extension("accum.exr"),
            exr,
        }
    }

    /// The four files every render writes, in the order the render writes them.
    pub fn all(&self) -> [&Path; 4] {
        [&self.exr, &self.png, &self.noise_png, &self.json]
    }

    /// The files this render writes: [`Outputs::all`], and the accumulation file when
    /// `accumulate`.
    pub fn members(&self, accumulate: bool) -> Vec<&Path> {
        let mut v = self.all().to_vec();
        if accumulate {
            v.push(&self.accum);
        }
        v
    }
}

/// The file name of `path` without its extension, as text (`fallback` if it has none): the
/// stem that names a command's default outputs.
pub fn stem_of(path: &Path, fallback: &str) -> String {
    path.file_stem().map_or_else(
        || fallback.to_string(),
        |s| s.to_string_lossy().into_owned(),
    )
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
pub struct Staged {
    file: tempfile::NamedTempFile,
    target: PathBuf,
}

impl Staged {
    /// The final path.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Renames the file into place: the target is replaced whole.
    pub fn commit(self) -> Result<(), String> {
        self.file
            .persist(&self.target)
            .map(drop)
            .map_err(|e| format!("cannot move the finished file into place: {}", e.error))
    }
}

/// Runs `write` on a new temporary file beside `path` and flushes it to disk, so that a full
/// disk shows here and not after the rename.
pub fn stage(
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
pub fn stage_bytes(path: &Path, bytes: &[u8]) -> Result<Staged, String> {
    stage(path, |f| {
        f.write_all(bytes).map_err(|e| format!("cannot write: {e}"))
    })
}

/// Runs `write` on a temporary file beside `path`, then renames it over `path`: an existing
/// file is either left whole or replaced whole, never half-written.
pub fn write_via_temp(
    path: &Path,
    write: impl FnOnce(&mut fs::File) -> Result<(), String>,
) -> Result<(), String> {
    ensure_parent(path).map_err(|e| format!("cannot create the directory: {e}"))?;
    stage(path, write)?.commit()
}

/// Writes bytes atomically (temporary file, then rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), String> {
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
pub struct OutputLock {
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
/// are older than `started`: leftovers of a render killed while writing, the accumulation
/// file's included (a render without `--accumulate` still cleans what an earlier one with it
/// left). Called with the output's lock held, so no live render of this output owns them.
fn remove_stale_temps(outputs: &Outputs, started: SystemTime) {
    let dir = dir_of(&outputs.exr);
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    let prefixes: Vec<String> = outputs
        .members(true)
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

/// The directory entry a rename to `path` replaces: the canonical directory joined with the
/// file name (the last component is not followed: a rename replaces a symlink, not its
/// target). `None` when the directory does not exist yet.
fn entry_of(path: &Path) -> Option<PathBuf> {
    let dir = fs::canonicalize(dir_of(path)).ok()?;
    Some(dir.join(path.file_name()?))
}

/// Whether writing `member` (by a rename) would destroy the file read from `input`: the
/// same directory entry, or `input` is a symlink that leads to it.
fn clobbers(member: &Path, input: &Path) -> bool {
    let Some(m) = entry_of(member) else {
        return false;
    };
    entry_of(input).as_ref() == Some(&m) || fs::canonicalize(input).ok().as_ref() == Some(&m)
}

/// Refuses an output set that would overwrite a file the same command reads (`inputs`: the
/// parts of a merge, the measured render of `predict`, the reference of `study`, the scene).
/// `members` are the files the command writes. An accumulation file that the output's own
/// accumulation file replaces (`--resume` or a merge into one of its parts, "in place") is
/// allowed: the new file holds every pass of the old one.
pub fn refuse_inputs(members: &[&Path], inputs: &[&Path], extends: &[&Path]) -> CheckResult {
    for m in members {
        for i in inputs {
            if clobbers(m, i) && !extends.iter().any(|e| clobbers(e, i) && e == m) {
                return Err(format!(
                    "{}: this output would overwrite {}, which this command reads; choose \
                     another -o",
                    m.display(),
                    i.display()
                ));
            }
        }
    }
    Ok(())
}

/// The result of an output check: a one-line error naming the file.
pub type CheckResult = Result<(), String>;

/// Refuses an output whose files would replace another render's: a name ending in
/// `.accum.exr` (the accumulation file of the set without it), `X-noise.exr` when `X.exr`
/// exists (its preview `X-noise.png` is X's noise map), and `X.exr` when `X-noise.exr`
/// exists (the other way round).
fn refuse_other_sets(outputs: &Outputs) -> CheckResult {
    let stem = stem_of(&outputs.exr, "");
    if let Some(base) = stem.strip_suffix(".accum") {
        return Err(format!(
            "{}: names ending in .accum.exr are accumulation files (this one of the output {}); \
             give the render's own name, e.g. -o {}",
            outputs.exr.display(),
            outputs.exr.with_file_name(format!("{base}.exr")).display(),
            outputs.exr.with_file_name(format!("{base}.exr")).display()
        ));
    }
    if let Some(base) = stem.strip_suffix("-noise") {
        let other = outputs.exr.with_file_name(format!("{base}.exr"));
        if fs::symlink_metadata(&other).is_ok() {
            return Err(format!(
                "{}: its preview {} is the noise map of the output {}; choose another -o",
                outputs.exr.display(),
                outputs.png.display(),
                other.display()
            ));
        }
    }
    let other = outputs.exr.with_file_name(format!("{stem}-noise.exr"));
    if fs::symlink_metadata(&other).is_ok() {
        return Err(format!(
            "{}: its noise map {} is the preview of the output {}; choose another -o",
            outputs.exr.display(),
            outputs.noise_png.display(),
            other.display()
        ));
    }
    Ok(())
}

/// Makes sure that a render's outputs can be written before any work is done: the requested
/// name and each file of the set (`accumulate`: the accumulation file too) is not a
/// directory or a device, replaces no other render's file and no file the command reads
/// (`inputs`; see [`refuse_inputs`]), the directory exists (it is created) and accepts a
/// temporary file under each member's name (so that a name too long for the file system
/// shows now, not after the render), and no other render holds the output. Returns the
/// lock, to be held until the files are in place; stale temporaries older than `started` are
/// removed.
pub fn claim(
    requested: &Path,
    outputs: &Outputs,
    accumulate: bool,
    inputs: &[&Path],
    started: SystemTime,
) -> Result<OutputLock, String> {
    if requested.file_name().is_none() {
        return Err(format!(
            "{}: the output names no file; give a name such as out/render.exr",
            requested.display()
        ));
    }
    check_output_name(requested, "the output")?;
    let members = outputs.members(accumulate);
    for p in &members {
        check_output_name(p, "an output file")?;
    }
    refuse_other_sets(outputs)?;
    refuse_inputs(&members, inputs, &[&outputs.accum])?;
    let dir = dir_of(&outputs.exr);
    if fs::metadata(dir).is_ok_and(|m| !m.is_dir()) {
        return Err(format!(
            "{}: the output directory is a file, not a directory",
            dir.display()
        ));
    }
    ensure_parent(&outputs.exr)
        .map_err(|e| format!("{}: cannot create the output directory: {e}", dir.display()))?;
    for p in &members {
        drop(temp_beside(p).map_err(|e| {
            format!(
                "{}: cannot write a temporary file for it in the output directory: {e}",
                p.display()
            )
        })?);
    }
    let lock = OutputLock::acquire(&outputs.exr)?;
    remove_stale_temps(outputs, started);
    Ok(lock)
}

/// A copy of the file at `target` under a temporary name beside it (a hard link where the
/// file system allows, else a byte copy), removed when dropped; `None` when there is no file.
fn keep_old(target: &Path) -> io::Result<Option<tempfile::TempPath>> {
    let Ok(meta) = fs::symlink_metadata(target) else {
        return Ok(None);
    };
    if !meta.is_file() {
        return Ok(None);
    }
    let path = temp_beside(target)?.into_temp_path();
    // The temporary name is unpredictable, so nobody can take it between the removal and
    // the link; `hard_link` does not follow a symlink at the new name either.
    fs::remove_file(&path)?;
    if fs::hard_link(target, &path).is_err() {
        let mut to = fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&path)?;
        let _ = io::copy(&mut fs::File::open(target)?, &mut to)?;
        to.sync_all()?;
    }
    Ok(Some(path))
}

/// Renames staged files into place in order. The caller puts the EXR last: it is the commit
/// point of the set, and its `bdpm.run_id` matches the report's `run_id` only once every file
/// of the run is in place. The old files are kept under temporary names until every rename
/// has succeeded: if one fails (a directory or an immutable file at its name), the files
/// already renamed are put back as they were (or removed where there was none), so the set
/// is the old one, never a mix; the message says if that restoring failed too.
pub fn commit_all(staged: Vec<Staged>) -> Result<(), String> {
    let mut olds = Vec::with_capacity(staged.len());
    for s in &staged {
        olds.push(keep_old(s.target()).map_err(|e| {
            format!(
                "{}: cannot keep the previous file while the new set is moved into place: {e}",
                s.target().display()
            )
        })?);
    }
    let mut done: Vec<(PathBuf, Option<tempfile::TempPath>)> = Vec::new();
    for (s, old) in staged.into_iter().zip(olds) {
        let target = s.target().to_path_buf();
        if let Err(e) = s.commit() {
            let mut lost = Vec::new();
            for (t, old) in done.into_iter().rev() {
                let restored = match old {
                    Some(o) => o.persist(&t).map_err(|e| e.error),
                    None => fs::remove_file(&t),
                };
                if restored.is_err() {
                    lost.push(t.display().to_string());
                }
            }
            return Err(if lost.is_empty() {
                format!(
                    "{}: {e}; the previous files of the output are back in place",
                    target.display()
                )
            } else {
                format!(
                    "{}: {e}; and cannot put back the previous {}: the output is a mix of two \
                     renders (compare their bdpm.run_id)",
                    target.display(),
                    lost.join(", ")
                )
            });
        }
        done.push((target, old));
    }
    Ok(())
}

/// An identifier for one run, written into the EXR header and the JSON report so that a
/// reader can tell files of the same run from a mix: 64 random bits as hex.
pub fn run_id() -> String {
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

    /// A rename that fails in the middle of the commit (a directory at the EXR's name) puts
    /// the files already renamed back: the old set stays whole, a new file where there was
    /// none is removed, and no temporary file is left.
    #[test]
    fn a_failed_commit_rolls_back_to_the_old_set() {
        let dir = scratch("rollback");
        for n in ["x.png", "x.json"] {
            fs::write(dir.join(n), b"old").expect("write old");
        }
        fs::create_dir_all(dir.join("x.exr").join("inside")).expect("directory at x.exr");
        let staged = ["x.png", "x-noise.png", "x.json", "x.exr"]
            .iter()
            .map(|n| stage_bytes(&dir.join(n), b"new").expect("stage"))
            .collect();
        let e = commit_all(staged).expect_err("the EXR's rename fails");
        assert!(e.contains("x.exr") && e.contains("back in place"), "{e}");
        for n in ["x.png", "x.json"] {
            assert_eq!(fs::read(dir.join(n)).expect("read"), b"old", "{n}");
        }
        assert!(!dir.join("x-noise.png").exists());
        assert!(hidden(&dir).is_empty(), "{:?}", hidden(&dir));
        // With no failure the new set replaces the old one and the kept copies are removed.
        fs::remove_dir_all(dir.join("x.exr")).expect("remove directory");
        let staged = ["x.png", "x.exr"]
            .iter()
            .map(|n| stage_bytes(&dir.join(n), b"new").expect("stage"))
            .collect();
        commit_all(staged).expect("commit");
        for n in ["x.png", "x.exr"] {
            assert_eq!(fs::read(dir.join(n)).expect("read"), b"new", "{n}");
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
