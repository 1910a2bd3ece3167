//! The one error type of the loader: every variant names the file, and where it can the
//! field, so that a message fits on one line and points at the fix.

use std::path::PathBuf;

use bdpm_scene::SceneError;
use bdpm_settings::SettingsError;

/// Why a scene could not be loaded.
///
/// `Display` gives one line of the form `FILE: FIELD: WHAT`, for example
/// `scenes/x.toml: material.red.kd: 1.2 is outside [0, 1]`.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The scene file itself could not be read.
    #[error("{path}: cannot read: {source}")]
    Read {
        /// The scene file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// The TOML is malformed, a key is unknown, or a value has the wrong type.
    #[error("{path}: line {line}, column {column}: {message}")]
    Syntax {
        /// The scene file.
        path: PathBuf,
        /// 1-based line of the offending text.
        line: usize,
        /// 1-based column (in characters) of the offending text.
        column: usize,
        /// What the TOML parser or the schema objected to.
        message: String,
    },
    /// A value is well-formed TOML but not acceptable (out of range, missing, unknown name).
    #[error("{path}: {field}: {message}")]
    Invalid {
        /// The scene file.
        path: PathBuf,
        /// Dotted path of the field, such as `material.red.kd` or `shape[3].radius`.
        field: String,
        /// What is wrong with it.
        message: String,
    },
    /// A setting given beside the scene file ([`crate::load_scene_overridden`]) is not
    /// acceptable, or the final settings, the file's with those put over them, do not go
    /// together. The error says which setting ([`SettingsError::setting`]), so that a caller
    /// names it its own way (a command line by its option).
    #[error("{path}: render.{} as overridden: {source}", source.setting().key())]
    Override {
        /// The scene file.
        path: PathBuf,
        /// What is wrong, and with which setting.
        source: SettingsError,
    },
    /// The camera cannot take the resolution the overrides ask for.
    #[error("{path}: render.resolution as overridden: {source}")]
    Resolution {
        /// The scene file.
        path: PathBuf,
        /// Why the camera refused it.
        source: SceneError,
    },
    /// A glTF file referenced by a shape could not be read or is not acceptable.
    #[error("{path} (from {field}): {message}")]
    Gltf {
        /// The glTF file (or the external buffer it names).
        path: PathBuf,
        /// The scene-file field that referenced it, such as `shape[2].file`.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// An element of a Mitsuba XML scene is malformed, not supported or not acceptable.
    #[error("{path}: line {line}: {element}: {message}")]
    Xml {
        /// The XML file (the scene or a file it includes).
        path: PathBuf,
        /// 1-based line where the element starts.
        line: u32,
        /// The element as written, such as `<shape type="ply">` or `<float name="fov">`.
        element: String,
        /// What is wrong, and what to do.
        message: String,
    },
    /// An OBJ or PLY file named by a shape could not be read or is not acceptable.
    #[error("{scene}: {field}: {path}: {message}")]
    MeshFile {
        /// The scene file.
        scene: PathBuf,
        /// The scene-file field that named it, such as `shape[2].file`.
        field: String,
        /// The mesh file, as opened (joined to the scene file's directory).
        path: PathBuf,
        /// What is wrong, with the line or element where the file tells it.
        message: String,
    },
}
