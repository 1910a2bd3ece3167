//! What a render's EXR header records of how it was made, for the commands that continue or
//! examine it (`predict RENDER.exr`, `render --resume`; `merge` reads the same record from
//! the accumulation files' identity): the scene file and the settings flags. And the one rule
//! for a command's own flags over that record: a flag the record holds must say the same, a
//! flag it lacks is added (and the command's checks of the settings themselves, the
//! accumulation identity or `predict`'s header comparison, refuse it if it changes them).
use std::path::{Path, PathBuf};

use crate::cli::{CliResult, Overrides};

/// Header attribute (without the `bdpm.` prefix) holding the scene file's path, absolute where
/// it could be resolved.
pub const SCENE: &str = "scene";
/// Header attribute holding the settings flags ([`Overrides::to_args`]) as a JSON list of
/// strings.
pub const OVERRIDES: &str = "overrides";

/// The scene file and the settings flags a render was made with, as its header records them.
#[derive(Clone, Debug, PartialEq)]
pub struct Recorded {
    /// The scene file, as recorded (absolute where the render could resolve it).
    pub scene: PathBuf,
    /// The settings flags given on the command line, as arguments (`--threads` and
    /// `--passes` excluded: they do not shape the image's estimator).
    pub overrides: Vec<String>,
}

impl Recorded {
    /// The header attributes (without the `bdpm.` prefix) that record `self`.
    pub fn attributes(&self) -> Vec<(String, String)> {
        // A list of strings always serialises.
        let flags = serde_json::to_string(&self.overrides).unwrap_or_else(|_| "[]".into());
        vec![
            (SCENE.into(), self.scene.to_string_lossy().into_owned()),
            (OVERRIDES.into(), flags),
        ]
    }

    /// The record in the text attributes of the EXR at `path` (keys without the `bdpm.`
    /// prefix, as [`crate::exr::ExrLayer`] reads them): `None` when the file has none (a
    /// render of a bdpm older than the record), an error naming the file when it is malformed.
    pub fn from_attributes(
        path: &Path,
        attributes: &[(String, String)],
    ) -> CliResult<Option<Recorded>> {
        let get = |key: &str| {
            attributes
                .iter()
                .find(|(k, _)| k == key)
                .map(|(_, v)| v.as_str())
        };
        let (Some(scene), Some(flags)) = (get(SCENE), get(OVERRIDES)) else {
            return Ok(None);
        };
        let overrides: Vec<String> = serde_json::from_str(flags).map_err(|_| {
            format!(
                "{}: bdpm.{OVERRIDES} is not a JSON list of strings: {flags}",
                path.display()
            )
        })?;
        // Checked now, so that a damaged record is named as such and not as a bad flag.
        Overrides::from_args(&overrides).map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(Some(Recorded {
            scene: PathBuf::from(scene),
            overrides,
        }))
    }
}

/// One flag with its value (`None` for `--no-jitter`), from arguments made by
/// [`Overrides::to_args`].
fn pairs(args: &[String]) -> Vec<(&str, Option<&str>)> {
    let mut out = Vec::new();
    let mut rest = args.iter();
    let mut next = rest.next();
    while let Some(flag) = next {
        next = rest.next();
        // A value never starts with "--" (`--radius -1px` is refused before it is recorded).
        let value = next.filter(|v| !v.starts_with("--")).map(String::as_str);
        if value.is_some() {
            next = rest.next();
        }
        out.push((flag.as_str(), value));
    }
    out
}

/// A flag and its value as typed.
fn typed(flag: &str, value: Option<&str>) -> String {
    value.map_or_else(|| flag.to_string(), |v| format!("{flag} {v}"))
}

/// The settings flags of a command that continues or examines the render recorded in
/// `source` (`recorded`: its flags as arguments): the recorded flags, with each of
/// `explicit`'s added. A flag given both ways must have the same value as written (`--radius
/// 0.5px` is not `--radius 0.50px`), else the error names the file and both values.
/// `--passes` and `--threads` are the command's own and are taken from `explicit`.
pub fn over_recorded(
    source: &Path,
    recorded: &[String],
    explicit: &Overrides,
) -> CliResult<Overrides> {
    let theirs = pairs(recorded);
    let ours = explicit.to_args();
    let mut args = recorded.to_vec();
    for (flag, value) in pairs(&ours) {
        match theirs.iter().find(|(f, _)| *f == flag) {
            Some((_, v)) if *v == value => {}
            Some((_, v)) => {
                return Err(format!(
                    "{}: {} contradicts the settings it was rendered with ({}); leave the flag \
                     out (the recorded settings are used) or start a new render",
                    source.display(),
                    typed(flag, value),
                    typed(flag, *v)
                ));
            }
            None => {
                args.push(flag.to_string());
                args.extend(value.map(str::to_string));
            }
        }
    }
    let mut merged =
        Overrides::from_args(&args).map_err(|e| format!("{}: {e}", source.display()))?;
    merged.passes = explicit.passes;
    merged.threads = explicit.threads;
    Ok(merged)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    /// The recorded flags are kept, an explicit one that agrees is accepted, a new one is
    /// added, and `--passes` and `--threads` come from the command.
    #[test]
    fn explicit_flags_join_the_recorded_ones() {
        let recorded = args(&["--mode", "optimal", "--radius", "0.5px", "--no-jitter"]);
        let explicit = Overrides {
            mode: Some("optimal".into()),
            spp: Some(3),
            passes: Some(7),
            threads: Some(2),
            ..Default::default()
        };
        let merged = over_recorded(Path::new("r.exr"), &recorded, &explicit).unwrap();
        assert_eq!(merged.mode.as_deref(), Some("optimal"));
        assert_eq!(merged.radius.as_deref(), Some("0.5px"));
        assert!(merged.no_jitter);
        assert_eq!(
            (merged.spp, merged.passes, merged.threads),
            (Some(3), Some(7), Some(2))
        );
        let none = over_recorded(Path::new("r.exr"), &[], &Overrides::default()).unwrap();
        assert!(none.to_args().is_empty());
    }

    /// A flag that says otherwise than the record is refused, naming the file and both values.
    #[test]
    fn a_contradicting_flag_is_refused() {
        let recorded = args(&["--mode", "optimal", "--resolution", "16x16"]);
        let explicit = Overrides {
            resolution: Some((32, 16)),
            ..Default::default()
        };
        let e = over_recorded(Path::new("r.exr"), &recorded, &explicit).unwrap_err();
        assert_eq!(
            e,
            "r.exr: --resolution 32x16 contradicts the settings it was rendered with \
             (--resolution 16x16); leave the flag out (the recorded settings are used) or start \
             a new render"
        );
    }

    /// The record survives the header's text attributes; a file without one has none, and a
    /// damaged one is an error naming the file.
    #[test]
    fn the_record_round_trips_through_attributes() {
        let r = Recorded {
            scene: PathBuf::from("/scenes/a b.toml"),
            overrides: args(&["--mode", "balance", "--no-jitter"]),
        };
        let path = Path::new("r.exr");
        assert_eq!(
            Recorded::from_attributes(path, &r.attributes()).unwrap(),
            Some(r)
        );
        assert_eq!(Recorded::from_attributes(path, &[]).unwrap(), None);
        let bad = [
            (SCENE.to_string(), "s.toml".to_string()),
            (OVERRIDES.to_string(), "--mode".to_string()),
        ];
        let e = Recorded::from_attributes(path, &bad).unwrap_err();
        assert!(
            e.starts_with("r.exr: bdpm.overrides is not a JSON list"),
            "{e}"
        );
    }
}
