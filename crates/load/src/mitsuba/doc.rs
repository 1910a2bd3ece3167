//! Reading one Mitsuba XML file: `$name` substitution from `<default>`, attribute and
//! property access, and messages that name the file, the line and the element.

use std::collections::HashMap;
use std::path::Path;

use glam::DVec3;
use roxmltree::Node;

use crate::LoadError;

/// The file being read and the `<default>` parameters in force: the source of every message.
pub(crate) struct Xml<'a> {
    /// The file, as messages name it.
    pub(crate) file: &'a Path,
    /// `<default name=… value=…>` values by name.
    pub(crate) defaults: &'a HashMap<String, String>,
}

/// 1-based line of the start of `node`.
pub(crate) fn line(node: Node<'_, '_>) -> u32 {
    node.document().text_pos_at(node.range().start).row
}

/// The element as a reader finds it in the file: `<shape type="ply">`, `<float name="fov">`.
pub(crate) fn what(node: Node<'_, '_>) -> String {
    let mut s = format!("<{}", node.tag_name().name());
    for key in ["type", "name", "id"] {
        if let Some(v) = node.attribute(key) {
            s += &format!(" {key}=\"{v}\"");
            break;
        }
    }
    s + ">"
}

/// The element children of `node` (comments and text left out).
pub(crate) fn elements<'a, 'i>(node: Node<'a, 'i>) -> impl Iterator<Item = Node<'a, 'i>> {
    node.children().filter(Node::is_element)
}

impl Xml<'_> {
    /// An error at `node`: `FILE: line N: <element>: message`.
    pub(crate) fn err(&self, node: Node<'_, '_>, message: impl Into<String>) -> LoadError {
        LoadError::Xml {
            path: self.file.to_path_buf(),
            line: line(node),
            element: what(node),
            message: message.into(),
        }
    }

    /// A warning at `node`, in the same form as an error.
    pub(crate) fn warn(&self, node: Node<'_, '_>, message: impl std::fmt::Display) -> String {
        format!(
            "{}: line {}: {}: {message}",
            self.file.display(),
            line(node),
            what(node)
        )
    }

    /// Attribute `key` of `node` with every `$name` replaced by its `<default>`.
    pub(crate) fn attr(&self, node: Node<'_, '_>, key: &str) -> Result<Option<String>, LoadError> {
        let Some(raw) = node.attribute(key) else {
            return Ok(None);
        };
        let mut out = String::with_capacity(raw.len());
        let mut rest = raw;
        while let Some(at) = rest.find('$') {
            out += &rest[..at];
            let after = &rest[at + 1..];
            let end = after
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(after.len());
            let name = &after[..end];
            let value = self.defaults.get(name).ok_or_else(|| {
                self.err(
                    node,
                    format!(
                        "{key}=\"{raw}\" uses ${name}, but no <default name=\"{name}\" value=…> \
                         is given"
                    ),
                )
            })?;
            out += value;
            rest = &after[end..];
        }
        out += rest;
        Ok(Some(out))
    }

    /// Attribute `key`, required.
    pub(crate) fn need(&self, node: Node<'_, '_>, key: &str) -> Result<String, LoadError> {
        self.attr(node, key)?
            .ok_or_else(|| self.err(node, format!("missing attribute {key}")))
    }

    /// Attribute `key` as numbers separated by commas or spaces, each finite.
    pub(crate) fn numbers(&self, node: Node<'_, '_>, key: &str) -> Result<Vec<f64>, LoadError> {
        let text = self.need(node, key)?;
        text.split(|c: char| c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .map(|s| self.finite(node, key, s))
            .collect()
    }

    /// Attribute `key` as one finite number, or `None` when absent.
    pub(crate) fn number(&self, node: Node<'_, '_>, key: &str) -> Result<Option<f64>, LoadError> {
        match self.attr(node, key)? {
            Some(s) => self.finite(node, key, s.trim()).map(Some),
            None => Ok(None),
        }
    }

    fn finite(&self, node: Node<'_, '_>, key: &str, s: &str) -> Result<f64, LoadError> {
        match s.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(self.err(node, format!("{key}: {s} is not finite (NaN or infinite)"))),
            Err(_) => Err(self.err(node, format!("{key}: \"{s}\" is not a number"))),
        }
    }

    /// A vector written as attributes x, y, z (each defaulting to `default`) or as
    /// `value="x, y, z"` (or one number for all three).
    pub(crate) fn xyz(&self, node: Node<'_, '_>, default: f64) -> Result<DVec3, LoadError> {
        if node.attribute("value").is_some() {
            let v = self.numbers(node, "value")?;
            return match v.as_slice() {
                [a] => Ok(DVec3::splat(*a)),
                [a, b, c] => Ok(DVec3::new(*a, *b, *c)),
                _ => Err(self.err(node, format!("value has {} numbers; expected 3", v.len()))),
            };
        }
        let mut out = [default; 3];
        for (slot, key) in out.iter_mut().zip(["x", "y", "z"]) {
            if let Some(v) = self.number(node, key)? {
                *slot = v;
            }
        }
        Ok(DVec3::from_array(out))
    }

    /// A `value="…"` vector of exactly three numbers as an attribute `key` (lookat's origin).
    pub(crate) fn triple(&self, node: Node<'_, '_>, key: &str) -> Result<DVec3, LoadError> {
        let v = self.numbers(node, key)?;
        match v.as_slice() {
            [a, b, c] => Ok(DVec3::new(*a, *b, *c)),
            _ => Err(self.err(node, format!("{key} has {} numbers; expected 3", v.len()))),
        }
    }
}

/// The named properties of a plugin element, read one by one, so that those left unread can
/// be reported.
pub(crate) struct Props<'a, 'i> {
    node: Node<'a, 'i>,
    read: std::cell::RefCell<Vec<String>>,
}

impl<'a, 'i> Props<'a, 'i> {
    /// The properties of plugin `node`.
    pub(crate) fn new(node: Node<'a, 'i>) -> Self {
        Props {
            node,
            read: std::cell::RefCell::new(Vec::new()),
        }
    }

    /// The plugin element.
    pub(crate) fn node(&self) -> Node<'a, 'i> {
        self.node
    }

    /// The child element with `name="…"`, marked as read.
    pub(crate) fn get(&self, name: &str) -> Option<Node<'a, 'i>> {
        self.read.borrow_mut().push(name.to_string());
        elements(self.node).find(|c| c.attribute("name") == Some(name))
    }

    /// Marks `names` as read without reading them (properties bdpm has no use for and that
    /// change nothing it renders).
    pub(crate) fn ignore(&self, names: &[&str]) {
        self.read
            .borrow_mut()
            .extend(names.iter().map(|s| s.to_string()));
    }

    /// One warning for each named property nobody read; `plugin` says whose.
    pub(crate) fn unread(&self, x: &Xml<'_>, plugin: &str, warnings: &mut Vec<String>) {
        let read = self.read.borrow();
        for c in elements(self.node) {
            let Some(name) = c.attribute("name") else {
                continue;
            };
            // Mitsuba's own writer names nested plugins by their role (name="bsdf").
            let role = matches!(
                c.tag_name().name(),
                "bsdf" | "emitter" | "sampler" | "film" | "rfilter" | "ref"
            );
            if !role && !read.iter().any(|r| r == name) {
                warnings.push(x.warn(
                    c,
                    format!("ignored: bdpm's mapping of {plugin} has no use for it"),
                ));
            }
        }
    }
}

/// Property `name` of `p` as `read` makes it of its element, or `default` when absent.
pub(crate) fn property<T>(
    p: &Props<'_, '_>,
    name: &str,
    default: T,
    read: impl FnOnce(Node<'_, '_>) -> Result<T, LoadError>,
) -> Result<T, LoadError> {
    match p.get(name) {
        Some(n) => read(n),
        None => Ok(default),
    }
}

impl Xml<'_> {
    /// The one number of a `<float>` or `<integer>` element `n` (its `value`).
    pub(crate) fn scalar(&self, n: Node<'_, '_>) -> Result<f64, LoadError> {
        self.number(n, "value")?
            .ok_or_else(|| self.err(n, "missing attribute value"))
    }

    /// A float property, or `default` when absent.
    pub(crate) fn float(
        &self,
        p: &Props<'_, '_>,
        name: &str,
        default: f64,
    ) -> Result<f64, LoadError> {
        property(p, name, default, |n| match n.tag_name().name() {
            "float" | "integer" => self.scalar(n),
            other => Err(self.err(n, format!("expected <float>, found <{other}>"))),
        })
    }

    /// A string property, or `None` when absent.
    pub(crate) fn string(
        &self,
        p: &Props<'_, '_>,
        name: &str,
    ) -> Result<Option<String>, LoadError> {
        p.get(name).map(|n| self.need(n, "value")).transpose()
    }

    /// A boolean property, or `default` when absent.
    pub(crate) fn boolean(
        &self,
        p: &Props<'_, '_>,
        name: &str,
        default: bool,
    ) -> Result<bool, LoadError> {
        property(p, name, default, |n| {
            match self.need(n, "value")?.as_str() {
                "true" => Ok(true),
                "false" => Ok(false),
                other => Err(self.err(n, format!("value \"{other}\" is not true or false"))),
            }
        })
    }
}
