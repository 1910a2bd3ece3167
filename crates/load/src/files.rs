//! Reading the files a scene names: regular files only, opened without blocking and read to
//! a size limit, so that a FIFO cannot hang the loader and a device such as `/dev/zero`
//! cannot exhaust memory. Every error says what is wrong with the file, without naming it
//! (callers name the file and the field).

use std::fs;
use std::io::Read as _;
use std::path::{Component, Path, PathBuf};

/// Why a file could not be read: the system's error, kept whole for a caller that reports it
/// as one, or what is wrong with the file. `what` names the kind of file ("scene file",
/// "glTF file", "glTF buffer").
#[derive(Debug, thiserror::Error)]
pub(crate) enum ReadError {
    /// The system refused to open or read it.
    #[error("cannot read: {0}")]
    Io(#[from] std::io::Error),
    /// A directory.
    #[error("is a directory, not a {0}")]
    Directory(&'static str),
    /// A FIFO, socket or device.
    #[error("is not a regular file (a FIFO, socket or device), so it cannot be a {0}")]
    NotRegular(&'static str),
    /// Larger than the limit for its kind, bytes.
    #[error("is {len} bytes, more than the {limit}-byte limit for a {what}")]
    TooLarge {
        len: u64,
        limit: u64,
        what: &'static str,
    },
}

/// Reads at most `limit` bytes of the regular file at `path`; a larger file is an error.
/// `what` names the kind of file in messages ("scene file", "glTF file", "glTF buffer").
pub(crate) fn read_regular(
    path: &Path,
    limit: u64,
    what: &'static str,
) -> Result<Vec<u8>, ReadError> {
    let file = open_regular(path, limit, what)?;
    let mut bytes = Vec::with_capacity(file.metadata()?.len() as usize);
    // One byte past the limit shows a file that grew after the check.
    let _ = file.take(limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(bytes.len() as u64, limit, what));
    }
    Ok(bytes)
}

/// Opens the regular file at `path` for reading, without blocking, refusing a directory, a
/// FIFO, a socket, a device or a file of more than `limit` bytes. A caller that streams it
/// reads at most `limit + 1` bytes (`take`), so that a file grown since is seen.
pub(crate) fn open_regular(
    path: &Path,
    limit: u64,
    what: &'static str,
) -> Result<fs::File, ReadError> {
    // Checked before opening: opening a FIFO for reading blocks until a writer appears.
    let meta = fs::metadata(path)?;
    check_kind(&meta, what)?;
    let mut options = fs::OpenOptions::new();
    let _ = options.read(true);
    #[cfg(unix)]
    {
        // Should the name be swapped for a FIFO after the check, the open does not block.
        use std::os::unix::fs::OpenOptionsExt as _;
        let _ = options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path)?;
    let meta = file.metadata()?;
    check_kind(&meta, what)?;
    if meta.len() > limit {
        return Err(too_large(meta.len(), limit, what));
    }
    Ok(file)
}

fn check_kind(meta: &fs::Metadata, what: &'static str) -> Result<(), ReadError> {
    if meta.is_dir() {
        return Err(ReadError::Directory(what));
    }
    if !meta.is_file() {
        return Err(ReadError::NotRegular(what));
    }
    Ok(())
}

fn too_large(len: u64, limit: u64, what: &'static str) -> ReadError {
    ReadError::TooLarge { len, limit, what }
}

/// Resolves a glTF buffer URI against the glTF file's directory `dir`, confined to it: the
/// URI is percent-decoded as RFC 3986 asks, and must be a relative path with no `..`
/// component and no scheme (`file:`, `http:`), and what it names, symlinks followed, must
/// lie inside `dir`. This keeps a glTF file from reading `/etc/passwd` as vertex data.
pub(crate) fn confined_uri(dir: &Path, uri: &str) -> Result<PathBuf, String> {
    let decoded = percent_decode(uri).ok_or_else(|| {
        format!("URI '{uri}' has a malformed percent escape or is not UTF-8 once decoded")
    })?;
    let has_scheme = decoded
        .split_once(':')
        .is_some_and(|(head, _)| !head.contains('/') && !head.contains('\\'));
    if has_scheme {
        return Err(format!(
            "URI '{uri}' has a scheme; only relative file paths and base64 data URIs are supported"
        ));
    }
    let relative = Path::new(&decoded);
    if decoded.is_empty()
        || decoded.starts_with(['/', '\\'])
        || relative.is_absolute()
        || relative
            .components()
            .any(|c| !matches!(c, Component::Normal(_) | Component::CurDir))
    {
        return Err(format!(
            "URI '{uri}' is not a relative path inside the glTF file's directory (absolute paths and '..' are refused)"
        ));
    }
    let path = dir.join(relative);
    // Symlinks are followed only as far as they stay inside the directory.
    if let (Ok(real_dir), Ok(real)) = (fs::canonicalize(dir), fs::canonicalize(&path))
        && !real.starts_with(&real_dir)
    {
        return Err(format!(
            "URI '{uri}' leads (through a symlink) to {}, outside the glTF file's directory",
            real.display()
        ));
    }
    Ok(path)
}

/// Decodes `%XX` escapes; `None` for a malformed escape or bytes that are not UTF-8.
pub(crate) fn percent_decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = s.get(i + 1..i + 3)?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uris_are_decoded_and_confined() {
        let dir = Path::new("models");
        assert_eq!(
            confined_uri(dir, "a%20b.bin").expect("plain"),
            dir.join("a b.bin")
        );
        assert!(confined_uri(dir, "sub/./x.bin").is_ok());
        for bad in [
            "/etc/passwd",
            "../secret.bin",
            "sub/../../x.bin",
            "%2e%2e/x.bin",
            "file:///etc/passwd",
            "http://example.com/x.bin",
            "",
            "%zz",
        ] {
            assert!(confined_uri(dir, bad).is_err(), "{bad} accepted");
        }
    }
}
