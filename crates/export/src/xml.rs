//! A small element tree for Mitsuba's scene description and its text through quick-xml, which
//! escapes attribute values (material names may hold any character) and indents.

use std::fmt::Write as _;

use glam::DVec3;
use quick_xml::Writer;
use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, BytesText, Event};

/// One XML element: a tag, its attributes in order, and its children.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Element {
    tag: &'static str,
    attrs: Vec<(&'static str, String)>,
    children: Vec<Node>,
}

/// A child of an [`Element`].
#[derive(Clone, Debug, PartialEq)]
enum Node {
    Element(Element),
    Comment(String),
}

impl Element {
    /// `<tag>` without attributes.
    pub(crate) fn new(tag: &'static str) -> Element {
        Element {
            tag,
            attrs: Vec::new(),
            children: Vec::new(),
        }
    }

    /// `<tag type="kind">`: a Mitsuba plugin.
    pub(crate) fn plugin(tag: &'static str, kind: &str) -> Element {
        Element::new(tag).attr("type", kind)
    }

    /// Adds an attribute.
    pub(crate) fn attr(mut self, name: &'static str, value: impl Into<String>) -> Element {
        self.attrs.push((name, value.into()));
        self
    }

    /// Adds a child element.
    pub(crate) fn child(mut self, child: Element) -> Element {
        self.children.push(Node::Element(child));
        self
    }

    /// Adds a comment.
    pub(crate) fn comment(mut self, text: &str) -> Element {
        self.children.push(Node::Comment(comment_text(text)));
        self
    }

    /// `<float name=".." value=".."/>`.
    pub(crate) fn float(self, name: &str, value: f64) -> Element {
        self.child(named("float", name).attr("value", num(value)))
    }

    /// `<integer name=".." value=".."/>`.
    pub(crate) fn integer(self, name: &str, value: impl Into<String>) -> Element {
        self.child(named("integer", name).attr("value", value))
    }

    /// `<string name=".." value=".."/>`.
    pub(crate) fn string(self, name: &str, value: &str) -> Element {
        self.child(named("string", name).attr("value", value))
    }

    /// `<boolean name=".." value=".."/>`.
    pub(crate) fn boolean(self, name: &str, value: bool) -> Element {
        self.child(named("boolean", name).attr("value", value.to_string()))
    }

    /// `<rgb name=".." value="r, g, b"/>`, each value with the digits of [`num`]: an f32's
    /// shortest where it is one, else an f64's (a value the export computed, such as the lobe
    /// stand-in's kd/(1 − w), comes back exactly when the import undoes it in f64).
    pub(crate) fn rgb(self, name: &str, value: impl Into<DVec3>) -> Element {
        self.child(named("rgb", name).attr("value", triple(value.into())))
    }

    /// The document: an XML declaration, a comment, then this element.
    pub(crate) fn document(&self, comment: &str) -> Vec<u8> {
        let mut writer = Writer::new_with_indent(Vec::new(), b' ', 4);
        let ok = writer
            .write_event(Event::Decl(BytesDecl::new("1.0", Some("utf-8"), None)))
            .and_then(|()| {
                writer.write_event(Event::Comment(BytesText::from_escaped(comment_text(
                    comment,
                ))))
            })
            .and_then(|()| self.write(&mut writer));
        // Writing into a Vec<u8> has no IO error to report.
        debug_assert!(ok.is_ok());
        let mut bytes = writer.into_inner();
        bytes.push(b'\n');
        bytes
    }

    fn write(&self, writer: &mut Writer<Vec<u8>>) -> std::io::Result<()> {
        let start = BytesStart::new(self.tag)
            .with_attributes(self.attrs.iter().map(|(k, v)| (*k, v.as_str())));
        if self.children.is_empty() {
            return writer.write_event(Event::Empty(start));
        }
        writer.write_event(Event::Start(start))?;
        for child in &self.children {
            match child {
                Node::Element(e) => e.write(writer)?,
                Node::Comment(c) => {
                    writer.write_event(Event::Comment(BytesText::from_escaped(c.as_str())))?
                }
            }
        }
        writer.write_event(Event::End(BytesEnd::new(self.tag)))
    }
}

/// A comment's text on one line, " text ", without the "--" that XML forbids in it (it
/// becomes "- -"); written as it is (a comment's text is not escaped in XML).
fn comment_text(text: &str) -> String {
    let mut text = text.replace(['\n', '\r'], " ");
    while text.contains("--") {
        text = text.replace("--", "- -");
    }
    format!(" {} ", text.trim_end_matches('-'))
}

/// `<tag name="..">`.
pub(crate) fn named(tag: &'static str, name: &str) -> Element {
    Element::new(tag).attr("name", name)
}

/// A number as the shortest text that reads back to the same f32 where it is one (Mitsuba
/// reads its scene in single precision), else to the same f64.
pub(crate) fn num(value: f64) -> String {
    // -0 reads as 0 in both renderers; "-0" in a file only puzzles a reader.
    let value = if value == 0.0 { 0.0 } else { value };
    let single = value as f32;
    if f64::from(single) == value {
        format!("{single}")
    } else {
        format!("{value}")
    }
}

/// "x, y, z".
pub(crate) fn triple(v: impl Into<DVec3>) -> String {
    let mut s = String::new();
    for (i, c) in v.into().to_array().into_iter().enumerate() {
        let _ = write!(s, "{}{}", if i > 0 { ", " } else { "" }, num(c));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attributes_are_escaped_and_comments_stay_comments() {
        let doc = Element::new("scene")
            .comment("a -- b")
            .string("filename", "a\"<&>.ply")
            .document("top");
        let text = String::from_utf8(doc).unwrap();
        assert!(
            text.contains("value=\"a&quot;&lt;&amp;&gt;.ply\""),
            "{text}"
        );
        assert!(text.contains("<!-- a - - b -->"), "{text}");
        assert_eq!(num(0.1f32 as f64), "0.1");
        assert_eq!(triple(glam::Vec3::new(1.0, 0.5, -2.0)), "1, 0.5, -2");
    }
}
