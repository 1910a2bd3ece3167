//! A setting's value as written (a scene file's TOML value, the text of a mode-list entry
//! such as `balance:radius=0.2px` or of a command-line value) and the one conversion of each
//! `[render]` key's value into [`PartialSettings`]: a wrong kind of value ("found a boolean")
//! and a count out of its range are told the same way wherever the value came from, with the
//! bound. The caller names the field its way (`render.radius` in a scene file, the entry in
//! a mode list).

use std::path::PathBuf;

use crate::{
    Mode, Named, NoiseModel, PartialSettings, RadiusInput, Sampler, Setting, metres, number_text,
    parse_name,
};

/// A value as written, before it is known to be of the right kind for its key.
#[derive(Clone, Debug, PartialEq)]
pub enum Written {
    /// A whole number (TOML integer, or text of digits).
    Whole(i128),
    /// Any other number (TOML float, or text such as `2.5` or `1e9`).
    Number(f64),
    /// `true` or `false`.
    Bool(bool),
    /// Text.
    Text(String),
    /// A list (TOML array), element by element.
    List(Vec<Written>),
    /// A table (TOML table or inline table).
    Table,
}

impl Written {
    /// A value typed as text (a mode-list entry's or a command line's): `true` and `false`, a whole
    /// number, another number, or else the text itself.
    pub fn from_text(text: &str) -> Written {
        let t = text.trim();
        match t {
            "true" => Written::Bool(true),
            "false" => Written::Bool(false),
            _ => match (t.parse::<i128>(), t.parse::<f64>()) {
                (Ok(i), _) => Written::Whole(i),
                (_, Ok(x)) => Written::Number(x),
                _ => Written::Text(t.to_string()),
            },
        }
    }

    /// What the value is, for "found …" in messages: `a boolean`, `the text "abc"`.
    pub fn describe(&self) -> String {
        match self {
            Written::Whole(i) => format!("the integer {i}"),
            Written::Number(x) => format!("the number {}", number_text(*x)),
            Written::Bool(_) => "a boolean".to_string(),
            Written::Text(t) => format!("the text \"{t}\""),
            Written::List(l) => format!("a list of {} value(s)", l.len()),
            Written::Table => "a table".to_string(),
        }
    }
}

/// Every key of a scene file's `[render]` table, in the order the docs list them.
pub const RENDER_KEYS: &[&str] = &[
    "resolution",
    "passes",
    "photons",
    "spp",
    "radius",
    "seed",
    "mode",
    "threshold_radius",
    "cache_bins",
    "cache_photons",
    "pixel_table_rays",
    "clamp_weights",
    "pixel_jitter",
    "noise_model",
    "sampler",
    "roulette_depth",
    "light_tracing",
    "direct_boost",
    "adaptive_radius",
    "output",
];

/// A whole number in `[min, max]` (both within `T`), or why not.
fn whole<T: TryFrom<i128>>(v: &Written, (min, max): (u64, u64)) -> Result<T, String> {
    match v {
        Written::Whole(i) if (i128::from(min)..=i128::from(max)).contains(i) => {
            T::try_from(*i).map_err(|_| format!("{i} is outside [{min}, {max}]"))
        }
        Written::Whole(i) => Err(format!("{i} is outside [{min}, {max}]")),
        other => Err(format!(
            "expected a whole number in [{min}, {max}], found {}",
            other.describe()
        )),
    }
}

/// A whole number for `setting`, in its range ([`Setting::range`]).
fn count<T: TryFrom<i128>>(v: &Written, setting: Setting) -> Result<T, String> {
    whole(v, setting.range().unwrap_or((0, u64::MAX)))
}

fn boolean(v: &Written) -> Result<bool, String> {
    match v {
        Written::Bool(b) => Ok(*b),
        other => Err(format!(
            "expected true or false, found {}",
            other.describe()
        )),
    }
}

fn text(v: &Written, what: &str) -> Result<String, String> {
    match v {
        Written::Text(t) => Ok(t.clone()),
        other => Err(format!("expected {what}, found {}", other.describe())),
    }
}

/// A name of a named setting, known to the setting ([`crate::parse_name`]'s message lists
/// the names).
fn name<T: Named>(v: &Written) -> Result<String, String> {
    let setting = T::SETTING;
    let names = T::names().join(", ");
    let given = text(v, &format!("{} name ({names})", setting.article_noun()))?;
    parse_name::<T>(&given).map_err(|e| e.to_string())?;
    Ok(given)
}

/// A merge radius: metres as a number, or text ([`crate::RadiusSpec::parse`]), checked as
/// written ([`RadiusInput::spec`]).
fn radius(v: &Written) -> Result<RadiusInput, String> {
    let r = match v {
        Written::Whole(i) => RadiusInput::Metres(*i as f64),
        Written::Number(x) => RadiusInput::Metres(*x),
        Written::Text(t) => RadiusInput::Text(t.clone()),
        other => {
            return Err(format!(
                "expected a length in metres (0.01) or pixel footprints (\"0.2px\"), found {}",
                other.describe()
            ));
        }
    };
    r.spec().map_err(|e| e.to_string())?;
    Ok(r)
}

/// A length in metres, checked as written ([`metres`]).
fn length(v: &Written, example: &str) -> Result<f64, String> {
    let x = match v {
        Written::Whole(i) => *i as f64,
        Written::Number(x) => *x,
        other => {
            return Err(format!(
                "expected a length in metres ({example}), found {}",
                other.describe()
            ));
        }
    };
    metres(x).map_err(|e| e.to_string())?;
    Ok(x)
}

/// `[width, height]`: two whole numbers, each in its range; an error names the element.
fn resolution(v: &Written) -> Result<Vec<u32>, ValueError> {
    let whole_list = |message: String| ValueError {
        field: "resolution".into(),
        message,
    };
    match v {
        Written::List(l) if l.len() == 2 => l
            .iter()
            .zip([Setting::Width, Setting::Height])
            .map(|(side, setting)| {
                count(side, setting).map_err(|message| ValueError {
                    field: setting.key().into(),
                    message,
                })
            })
            .collect(),
        Written::List(l) => Err(whole_list(format!(
            "{} values given; expected [width, height] in pixels",
            l.len()
        ))),
        other => Err(whole_list(format!(
            "expected [width, height] in pixels, found {}",
            other.describe()
        ))),
    }
}

/// Why a value as written cannot be put into [`PartialSettings`] ([`PartialSettings::set`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ValueError {
    /// The field, as a scene file's `[render]` table names it: the key, or an element of it
    /// (`resolution[1]`).
    pub field: String,
    /// What is wrong, with the bound; the field not named.
    pub message: String,
}

impl std::fmt::Display for ValueError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl PartialSettings {
    /// Sets the `[render]` key `key` to `value` as written, checking it as written: its
    /// kind, a count's range, a name, a length ([`metres`]), a radius ([`RadiusInput::spec`]);
    /// [`PartialSettings::apply`] checks the result in single precision. The error says what
    /// is wrong and the bound, and which field (the caller names it its way); an unknown key
    /// lists the keys ([`RENDER_KEYS`]).
    pub fn set(&mut self, key: &str, value: &Written) -> Result<(), ValueError> {
        let v = value;
        if key == "resolution" {
            self.resolution = Some(resolution(v)?);
            return Ok(());
        }
        self.set_scalar(key, v).map_err(|message| ValueError {
            field: key.to_string(),
            message,
        })
    }

    /// [`PartialSettings::set`] of every key but `resolution`.
    fn set_scalar(&mut self, key: &str, v: &Written) -> Result<(), String> {
        match key {
            "passes" => self.passes = Some(count(v, Setting::Passes)?),
            "photons" => self.photons = Some(count(v, Setting::Photons)?),
            "spp" => self.spp = Some(count(v, Setting::Spp)?),
            "radius" => self.radius = Some(radius(v)?),
            "seed" => self.seed = Some(whole(v, (0, u64::MAX))?),
            "mode" => self.mode = Some(name::<Mode>(v)?),
            "threshold_radius" => self.threshold_radius = Some(length(v, "0.2")?),
            "cache_bins" => self.cache_bins = Some(count(v, Setting::CacheBins)?),
            "cache_photons" => self.cache_photons = Some(count(v, Setting::CachePhotons)?),
            "pixel_table_rays" => {
                self.pixel_table_rays = Some(count(v, Setting::PixelTableRays)?);
            }
            "clamp_weights" => self.clamp_weights = Some(boolean(v)?),
            "pixel_jitter" => self.pixel_jitter = Some(boolean(v)?),
            "noise_model" => self.noise_model = Some(name::<NoiseModel>(v)?),
            "sampler" => self.sampler = Some(name::<Sampler>(v)?),
            "roulette_depth" => self.roulette_depth = Some(whole(v, (0, u32::MAX.into()))?),
            "light_tracing" => self.light_tracing = Some(boolean(v)?),
            "direct_boost" => self.direct_boost = Some(count(v, Setting::DirectBoost)?),
            "adaptive_radius" => self.adaptive_radius = Some(boolean(v)?),
            "output" => self.output = Some(PathBuf::from(text(v, "a file path")?)),
            _ => {
                return Err(format!(
                    "unknown key; expected one of {}",
                    RENDER_KEYS.join(", ")
                ));
            }
        }
        Ok(())
    }
}
