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
}

impl Outputs {
    /// OUT.exr, OUT.png, OUT-noise.png and OUT.json for a requested OUT(.exr).
    pub fn beside(exr: &Path) -> Outputs {
        let exr = exr.with_extension("exr");
        let stem = stem_of(&exr, "");
        Outputs {
            png: exr.with_extension("png"),
            noise_png: exr.with_file_name(format!("{stem}-noise.png")),
            json: exr.with_extension("json"),
            exr,
        }
    }

    /// Every path, in the order the render writes them.
    pub fn all(&self) -> [&Path; 4] {
        [&self.exr, &self.png, &self.noise_png, &self.json]
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
pub fn claim(
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
pub fn commit_all(staged: Vec<Staged>) -> Result<(), String> {
    for s in staged {
        let target = s.target().to_path_buf();
        s.commit()
            .map_err(|e| format!("{}: {e}", target.display()))?;
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
