//! [`ElementName`]: how messages name an element of a drawing.

use std::fmt;

/// An element of the drawing, as a message names it: `path#wall-3 (line 12)` when it has an
/// id, `line[17] (line 40)` when it has none (the 17th `<line>` of the document, from 1).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct ElementName {
    /// The element's tag, without a namespace prefix (`path`, `rect`, `g`, ...).
    pub tag: String,
    /// Its `id` attribute, if it has one.
    pub id: Option<String>,
    /// Its position among the document's elements with the same tag, from 1.
    pub nth: usize,
    /// The line of the document its start tag is on, from 1.
    pub line: u32,
}

/// `text` with its control characters escaped (`\n` as the two characters `\` `n`): every
/// message is one line, whatever the drawing's ids or the XML parser's words hold.
pub fn one_line(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

impl fmt::Display for ElementName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.id {
            // An id may hold a line break (`&#10;`).
            Some(id) => write!(f, "{}#{} (line {})", self.tag, one_line(id), self.line),
            None => write!(f, "{}[{}] (line {})", self.tag, self.nth, self.line),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn named_by_id_or_by_tag_and_position() {
        let mut name = ElementName {
            tag: "path".into(),
            id: Some("wall-3".into()),
            nth: 4,
            line: 12,
        };
        assert_eq!(name.to_string(), "path#wall-3 (line 12)");
        name.id = None;
        assert_eq!(name.to_string(), "path[4] (line 12)");
        name.id = Some("two\nlines".into());
        assert_eq!(name.to_string(), "path#two\\nlines (line 12)");
    }
}
