//! What identifies a scene across renders: the hash of its file (without the `[render]`
//! table) and of the files it references, which every image header carries, so that a
//! reference, a measured render or a partial render is checked to be of the same scene.
//! Here because it reads scene files as the loader does (TOML, and the glTF files' buffer and
//! image URIs).

use std::path::{Path, PathBuf};

use crate::LoadError;

/// 64-bit FNV-1a: a stable hash (unlike `DefaultHasher`, whose output may change between Rust
/// releases), for the identity of a render and for naming cached references.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ *b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// Feeds `bytes` into a running FNV-1a hash `h`, length first (so that moving bytes from one
/// file to the next changes the hash).
fn fnv1a_more(h: u64, bytes: &[u8]) -> u64 {
    let h = (bytes.len() as u64).to_le_bytes().iter().fold(h, |h, b| {
        (h ^ *b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    });
    bytes.iter().fold(h, |h, b| {
        (h ^ *b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// FNV-1a over the bytes of the files a scene references: each glTF file (as the loader
/// opened it, [`crate::LoadReport::gltf_files`]) and the external buffers and images it
/// names (resolved against its directory), in order; hex. A file that cannot be read is
/// hashed as its name and "unreadable", so that it still differs from any content.
pub fn assets_hash(gltf_files: &[PathBuf]) -> String {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for file in gltf_files {
        let Ok(bytes) = std::fs::read(file) else {
            h = fnv1a_more(h, file.to_string_lossy().as_bytes());
            h = fnv1a_more(h, b"unreadable");
            continue;
        };
        h = fnv1a_more(h, &bytes);
        let Ok(doc) = gltf::Gltf::from_slice(&bytes) else {
            continue;
        };
        let dir = file.parent().unwrap_or(Path::new("."));
        let buffers = doc.buffers().filter_map(|b| match b.source() {
            gltf::buffer::Source::Uri(uri) => Some(uri.to_string()),
            gltf::buffer::Source::Bin => None,
        });
        // From the JSON: the crate's `Image::source` panics on an image with a bufferView but
        // no mimeType, or with neither a bufferView nor a uri (the loader accepts the first).
        let images = doc
            .as_json()
            .images
            .iter()
            .filter(|i| i.buffer_view.is_none())
            .filter_map(|i| i.uri.clone());
        for uri in buffers.chain(images) {
            if uri.starts_with("data:") {
                continue;
            }
            let path = dir.join(crate::files::percent_decode(&uri).unwrap_or_else(|| uri.clone()));
            match std::fs::read(&path) {
                Ok(b) => h = fnv1a_more(h, &b),
                Err(_) => {
                    h = fnv1a_more(h, uri.as_bytes());
                    h = fnv1a_more(h, b"unreadable");
                }
            }
        }
    }
    format!("{h:016x}")
}

/// The scene identity that every image header carries (`bdpm.scene_hash`): FNV-1a of the
/// scene file's content and the [`assets_hash`] of the files it references, hex. The content
/// is the file as TOML without its `[render]` table, comments and layout (the bytes, for a
/// file that is not TOML): two renders with the same scene hash rendered the same scene,
/// wherever its files were and whatever their render settings, so that a reference or a
/// measured render made with other settings (scenes/preprint/) is accepted.
pub fn scene_hash(scene: &Path, gltf_files: &[PathBuf]) -> Result<String, LoadError> {
    let bytes = std::fs::read(scene).map_err(|source| LoadError::Read {
        path: scene.to_path_buf(),
        source,
    })?;
    Ok(combined_hash(
        &format!("{:016x}", fnv1a(&scene_content(&bytes))),
        &assets_hash(gltf_files),
    ))
}

/// What of a scene file [`scene_hash`] covers (see there).
fn scene_content(bytes: &[u8]) -> Vec<u8> {
    let parsed = std::str::from_utf8(bytes)
        .ok()
        .and_then(|t| t.parse::<toml::Table>().ok());
    match parsed {
        Some(mut table) => {
            table.remove("render");
            toml::to_string(&table).map_or_else(|_| bytes.to_vec(), String::into_bytes)
        }
        None => bytes.to_vec(),
    }
}

fn combined_hash(scene_file: &str, assets: &str) -> String {
    format!(
        "{:016x}",
        fnv1a(format!("{scene_file}+{assets}").as_bytes())
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scene_hash_ignores_render_settings_comments_and_layout() {
        let a = b"# a box\n[render]\npasses = 3\n\n[[light]]\nposition = [0.0, 1.0, 0.0]\n";
        let b = b"[render]\npasses = 9\nradius = \"1px\"\n[[light]]\nposition = [0.0,  1.0, 0.0]\n";
        let c = b"[render]\npasses = 3\n[[light]]\nposition = [0.0, 2.0, 0.0]\n";
        assert_eq!(scene_content(a), scene_content(b));
        assert_ne!(scene_content(a), scene_content(c));
        assert_eq!(scene_content(b"not = [toml"), b"not = [toml".to_vec());
    }

    #[test]
    fn fnv_hash_is_stable() {
        assert_eq!(fnv1a(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
    }
}
