//! The drawing's text before usvg reads it: every element without an `id` is given one (usvg
//! keeps ids, and drops the `data-flatland-*` attributes and classes this crate reads), so each
//! path of usvg's tree leads back to its element, its attributes and its line. An empty group
//! is placed first inside the root: its transform in usvg's tree is the root's (viewBox and
//! `transform`), which the importer undoes to work in the root's user units.

use std::collections::hash_map::Entry;
use std::collections::{HashMap, HashSet};

use usvg::roxmltree::{Document, Node, ParsingOptions};

use crate::attributes::{self, OwnAttributes};
use crate::name::one_line;
use crate::{ElementName, SvgError, WarningKind};

/// Elements whose content is drawn only where something refers to it.
const NOT_DRAWN_HERE: [&str; 6] = ["defs", "symbol", "clipPath", "mask", "pattern", "marker"];
/// Elements usvg turns into paths.
const SHAPES: [&str; 7] = [
    "rect", "circle", "ellipse", "line", "polyline", "polygon", "path",
];

/// One element of the drawing.
#[derive(Clone, Debug)]
pub struct SourceElement {
    /// How messages name it.
    pub name: ElementName,
    /// Its own `data-flatland-*` attributes.
    pub own: OwnAttributes,
    /// For a `use`: the element it refers to.
    pub referenced: Option<usize>,
    /// A shape drawn where it stands (not inside `defs`, a `symbol`, a clip path, ...).
    pub drawn_here: bool,
}

/// The elements of a drawing and usvg's tree of it.
pub struct Source {
    /// Every element, in document order.
    pub elements: Vec<SourceElement>,
    /// Element index by id (the drawing's own ids and the ones given here).
    pub by_id: HashMap<String, usize>,
    /// The id of the empty group whose transform is the root's.
    pub origin_id: String,
    /// `text` elements drawn (skipped by the importer).
    pub texts: Vec<ElementName>,
    /// `image` elements drawn (skipped by the importer).
    pub images: Vec<ElementName>,
    /// What the document itself gets wrong (bad transforms, broken references, repeated ids).
    pub warnings: Vec<(usize, WarningKind)>,
    /// usvg's tree of the drawing.
    pub tree: usvg::Tree,
}

/// Reads `bytes` as SVG text: XML errors and invalid attributes are errors with a position.
pub fn read(bytes: &[u8]) -> Result<Source, SvgError> {
    let text = std::str::from_utf8(bytes).map_err(|e| SvgError::NotText {
        line: 1 + bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count(),
    })?;
    let options = || ParsingOptions {
        allow_dtd: true,
        ..ParsingOptions::default()
    };
    let doc = Document::parse_with_options(text, options()).map_err(xml_error)?;
    let (annotated, prefix) = annotate(text, &doc);
    let doc = Document::parse_with_options(&annotated, options()).map_err(xml_error)?;
    let mut catalogue = Catalogue::default();
    // Where each line starts (roxmltree's own position lookup scans from the top each time).
    let newlines: Vec<usize> = annotated.match_indices('\n').map(|(at, _)| at).collect();
    for node in doc.descendants().filter(Node::is_element) {
        let line = 1 + newlines.partition_point(|&at| at < node.range().start) as u32;
        catalogue.add(node, line, &prefix)?;
    }
    catalogue.link_uses(&doc);
    let tree = usvg::Tree::from_xmltree(&doc, &usvg::Options::default())
        .map_err(|e| SvgError::NotSvg(e.to_string()))?;
    Ok(Source {
        elements: catalogue.elements,
        by_id: catalogue.by_id,
        origin_id: format!("{prefix}origin"),
        texts: catalogue.texts,
        images: catalogue.images,
        warnings: catalogue.warnings,
        tree,
    })
}

/// The elements met so far and what they get wrong.
#[derive(Default)]
struct Catalogue {
    elements: Vec<SourceElement>,
    by_id: HashMap<String, usize>,
    /// Elements so far per tag.
    nth: HashMap<String, usize>,
    /// Element index by roxmltree node.
    index_of: HashMap<usize, usize>,
    texts: Vec<ElementName>,
    images: Vec<ElementName>,
    warnings: Vec<(usize, WarningKind)>,
}

impl Catalogue {
    /// Adds `node`, on `line`; ids starting with `prefix` are the importer's, not the
    /// drawing's.
    fn add(&mut self, node: Node<'_, '_>, line: u32, prefix: &str) -> Result<(), SvgError> {
        let index = self.elements.len();
        let tag = node.tag_name().name().to_string();
        let count = self.nth.entry(tag.clone()).or_default();
        *count += 1;
        let id = node.attribute("id").map(str::to_string);
        let name = ElementName {
            tag: tag.clone(),
            id: id.clone().filter(|id| !id.starts_with(prefix)),
            nth: *count,
            line,
        };
        let own = attributes::read(node, &name)?;
        let hidden_here = node
            .ancestors()
            .any(|a| NOT_DRAWN_HERE.contains(&a.tag_name().name()));
        match tag.as_str() {
            "text" if !hidden_here => self.texts.push(name.clone()),
            "image" if !hidden_here => self.images.push(name.clone()),
            _ => {}
        }
        if let Some(id) = id {
            // The first element with an id wins, as in usvg.
            match self.by_id.entry(id) {
                Entry::Occupied(_) => self.warnings.push((index, WarningKind::DuplicateId)),
                Entry::Vacant(slot) => {
                    slot.insert(index);
                }
            }
        }
        if let Some(value) = node.attribute("transform").filter(|v| !usable_transform(v)) {
            let value = value.to_string();
            self.warnings
                .push((index, WarningKind::BadTransform { value }));
        }
        self.index_of.insert(node.id().get_usize(), index);
        self.elements.push(SourceElement {
            name,
            own,
            referenced: None,
            drawn_here: SHAPES.contains(&tag.as_str()) && !hidden_here,
        });
        Ok(())
    }

    /// Each `use` to the element it refers to; a warning for those that refer to nothing.
    fn link_uses(&mut self, doc: &Document<'_>) {
        for node in doc.descendants().filter(|n| n.has_tag_name("use")) {
            let href = node
                .attributes()
                .find(|a| a.name() == "href")
                .map(|a| a.value().trim());
            let e = self.index_of[&node.id().get_usize()];
            let target = href
                .and_then(|h| h.strip_prefix('#'))
                .and_then(|t| self.by_id.get(t));
            match target {
                Some(&target) => self.elements[e].referenced = Some(target),
                None => {
                    let href = href.unwrap_or_default().to_string();
                    self.warnings
                        .push((e, WarningKind::BrokenReference { href }));
                }
            }
        }
    }
}

/// Whether usvg takes `value` as the transform it says and it keeps shapes shapes: it parses,
/// and in f32 (as usvg keeps it) it is finite and invertible. usvg reads one that does not
/// parse, is not finite or scales an axis to nothing as no transform at all.
fn usable_transform(value: &str) -> bool {
    value.parse::<svgtypes::Transform>().is_ok_and(|t| {
        let c = [t.a, t.b, t.c, t.d, t.e, t.f].map(|x| f64::from(x as f32));
        let det = c[0] * c[3] - c[1] * c[2];
        let axis = |x: f64, y: f64| x.hypot(y) > f64::from(f32::EPSILON);
        c.iter().all(|x| x.is_finite()) && axis(c[0], c[1]) && axis(c[2], c[3]) && det != 0.0
    })
}

fn xml_error(e: usvg::roxmltree::Error) -> SvgError {
    let pos = e.pos();
    // roxmltree's messages hold the position ("... at 2:1 ..."); ours leads with it.
    // It may also quote the character it met, a line break included.
    let message = one_line(
        &e.to_string()
            .replace(&format!(" at {}:{}", pos.row, pos.col), ""),
    );
    SvgError::Xml {
        line: pos.row,
        column: pos.col,
        message,
    }
}

/// `text` with an `id` added to every element without one (`PREFIX` and its index) and an empty
/// group `PREFIXorigin` first in the root; the prefix is one no id of the drawing starts with.
fn annotate(text: &str, doc: &Document<'_>) -> (String, String) {
    let ids: HashSet<&str> = doc
        .descendants()
        .filter_map(|n| n.attribute("id"))
        .collect();
    let mut prefix = String::from("flatland-");
    while ids.iter().any(|id| id.starts_with(&prefix)) {
        prefix.push('x');
    }
    let mut inserts: Vec<(usize, String)> = Vec::new();
    for (index, node) in doc.descendants().filter(Node::is_element).enumerate() {
        if node.attribute("id").is_some() {
            continue;
        }
        let start = node.range().start;
        // Elements expanded from a DTD entity have no start tag of their own here.
        let Some(tag) = text.get(start..).and_then(|t| t.strip_prefix('<')) else {
            continue;
        };
        let qname_len = tag
            .find(|c: char| c.is_whitespace() || c == '/' || c == '>')
            .unwrap_or(tag.len());
        if !tag[..qname_len].ends_with(node.tag_name().name()) {
            continue;
        }
        inserts.push((start + 1 + qname_len, format!(" id=\"{prefix}{index}\"")));
    }
    if let Some(first) = doc.root_element().first_child() {
        inserts.push((first.range().start, format!("<g id=\"{prefix}origin\"/>")));
    }
    inserts.sort_by_key(|&(at, _)| at);
    let mut out = String::with_capacity(text.len() + inserts.len() * 24);
    let mut from = 0;
    for (at, insert) in inserts {
        out.push_str(&text[from..at]);
        out.push_str(&insert);
        from = at;
    }
    out.push_str(&text[from..]);
    (out, prefix)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_element_gets_an_id_and_keeps_its_name() {
        let svg = "<svg xmlns=\"http://www.w3.org/2000/svg\">\n<rect width=\"1\" height=\"1\"/>\n<svg:rect xmlns:svg=\"http://www.w3.org/2000/svg\" id=\"flatland-1\"/><line/></svg>";
        let source = read(svg.as_bytes()).unwrap();
        let names: Vec<String> = source.elements.iter().map(|e| e.name.to_string()).collect();
        // The drawing's own id starts with "flatland-", so the given ones start "flatland-x".
        assert_eq!(source.origin_id, "flatland-xorigin");
        assert_eq!(
            names,
            [
                "svg[1] (line 1)",
                "g[1] (line 1)",
                "rect[1] (line 2)",
                "rect#flatland-1 (line 3)",
                "line[1] (line 3)"
            ]
        );
        assert_eq!(source.by_id.len(), 5);
    }

    #[test]
    fn xml_errors_give_the_position_once() {
        let err = read(b"<svg><rect></svg>").err().unwrap().to_string();
        assert!(err.starts_with("1:"), "{err}");
        assert!(!err.contains(" at 1:"), "{err}");
        let err = read(b"<svg>\n\xff</svg>").err().unwrap().to_string();
        assert_eq!(
            err,
            "line 2: the drawing is not UTF-8 text (an .svgz must be unpacked first)"
        );
    }
}
