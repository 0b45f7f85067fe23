//! Small helpers over roxmltree shared by both formats: element references for errors,
//! child lookup and number parsing that reports the element at fault. [`rl`] holds what RL's
//! two formats (rlmdl, rlkin) share.

pub(crate) mod rl;

use std::collections::HashMap;
use std::string::{String, ToString};

use glam::{DMat3, DVec3};
use roxmltree::{Document, Node, ParsingOptions};

use super::error::{ElementRef, LoadError, LoadErrorKind};

/// Parses `text` within `limits` (DTDs allowed: roxmltree bounds entity expansion). The size,
/// the nesting depth and the attributes per element are checked first ([`check`]), so a huge,
/// deeply nested or attribute-laden input is refused before a tree is built.
pub(crate) fn parse<'i>(
    text: &'i str,
    limits: &super::InputLimits,
) -> Result<Document<'i>, LoadError> {
    check(text, limits)?;
    let opt = ParsingOptions {
        allow_dtd: true,
        nodes_limit: limits.max_nodes,
        ..ParsingOptions::default()
    };
    Document::parse_with_options(text, opt).map_err(|e| match e {
        roxmltree::Error::NodesLimitReached => LoadError::new(LoadErrorKind::TooLarge {
            what: "number of XML nodes",
            limit: u64::from(limits.max_nodes),
        }),
        e => LoadError::new(LoadErrorKind::Xml(e.to_string())),
    })
}

/// Refuses `text` above the size limit, element nesting deeper than the depth limit and
/// elements with more attributes than the attribute limit (an error naming line:column of the
/// element at fault). Skips comments, CDATA, processing instructions, the DOCTYPE and quoted
/// attribute values; malformed markup is left for the parser to report. Linear, no allocation.
pub(crate) fn check(text: &str, limits: &super::InputLimits) -> Result<(), LoadError> {
    if text.len() as u64 > limits.max_bytes {
        return Err(LoadError::new(LoadErrorKind::TooLarge {
            what: "size in bytes",
            limit: limits.max_bytes,
        }));
    }
    let b = text.as_bytes();
    let find = |from: usize, pat: &[u8]| {
        b[from.min(b.len())..]
            .windows(pat.len())
            .position(|w| w == pat)
            .map_or(b.len(), |p| from + p + pat.len())
    };
    // The element starting at byte `start`, for an error.
    let element_at = |start: usize| {
        let line_start = b[..start]
            .iter()
            .rposition(|&c| c == b'\n')
            .map_or(0, |p| p + 1);
        let name_len = b[start + 1..]
            .iter()
            .position(|c| c.is_ascii_whitespace() || matches!(c, b'/' | b'>'))
            .unwrap_or(0)
            .min(200);
        let tag = String::from_utf8_lossy(&b[start + 1..start + 1 + name_len]);
        ElementRef {
            tag: tag.into_owned(),
            id: None,
            line: (b[..start].iter().filter(|&&c| c == b'\n').count() + 1) as u32,
            column: (text[line_start..start].chars().count() + 1) as u32,
        }
    };
    let too_large = |start: usize, what: &'static str, limit: usize| {
        LoadError::at(
            element_at(start),
            LoadErrorKind::TooLarge {
                what,
                limit: limit as u64,
            },
        )
    };
    let mut depth = 0usize;
    let mut i = 0;
    while i < b.len() {
        if b[i] != b'<' {
            i += 1;
            continue;
        }
        let rest = &b[i..];
        if rest.starts_with(b"<!--") {
            i = find(i + 4, b"-->");
        } else if rest.starts_with(b"<![CDATA[") {
            i = find(i + 9, b"]]>");
        } else if rest.starts_with(b"<?") {
            i = find(i + 2, b"?>");
        } else if rest.starts_with(b"<!") {
            // DOCTYPE, with an internal subset in brackets.
            let mut brackets = 0usize;
            let mut quote = 0u8;
            i += 2;
            while i < b.len() {
                let c = b[i];
                i += 1;
                match c {
                    _ if quote != 0 && c == quote => quote = 0,
                    _ if quote != 0 => {}
                    b'"' | b'\'' => quote = c,
                    b'[' => brackets += 1,
                    b']' => brackets = brackets.saturating_sub(1),
                    b'>' if brackets == 0 => break,
                    _ => {}
                }
            }
        } else if rest.starts_with(b"</") {
            depth = depth.saturating_sub(1);
            i = find(i + 2, b">");
        } else {
            let start = i;
            let mut quote = 0u8;
            let mut last = 0u8;
            // Every attribute's value is quoted: one opening quote per attribute.
            let mut attributes = 0usize;
            i += 1;
            while i < b.len() {
                let c = b[i];
                i += 1;
                if quote != 0 {
                    if c == quote {
                        quote = 0;
                    }
                } else if c == b'"' || c == b'\'' {
                    quote = c;
                    attributes += 1;
                    if attributes > limits.max_attributes {
                        return Err(too_large(
                            start,
                            "number of attributes of one element",
                            limits.max_attributes,
                        ));
                    }
                } else if c == b'>' {
                    break;
                } else if !c.is_ascii_whitespace() {
                    last = c;
                }
            }
            if last != b'/' {
                depth += 1;
                if depth > limits.max_depth {
                    return Err(too_large(start, "nesting depth", limits.max_depth));
                }
            }
        }
    }
    Ok(())
}

/// The reference of `node` for error messages (for one error: this counts the lines from the
/// start of the document; [`Lines::elem`] is the way for every element of a file).
pub(crate) fn elem(node: Node) -> ElementRef {
    let pos = node.document().text_pos_at(node.range().start);
    element_ref(node, pos.row, pos.col)
}

fn element_ref(node: Node, line: u32, column: u32) -> ElementRef {
    ElementRef {
        tag: node.tag_name().name().to_string(),
        id: node
            .attribute("id")
            .or_else(|| node.attribute("name"))
            .map(str::to_string),
        line,
        column,
    }
}

/// Where the lines of a document start, and how many characters precede every 256-byte block, so
/// that an element's line and column cost a binary search and two scans of at most 256 bytes instead
/// of a scan from the start of the document or of its line (either made loading quadratic: the
/// first in the file's size, the second in the length of a line, for files on one line).
pub(crate) struct Lines<'i> {
    text: &'i str,
    starts: std::vec::Vec<usize>,
    /// Characters in `text[..k · BLOCK]`, for every block `k`.
    chars_before_block: std::vec::Vec<usize>,
}

/// The block size of [`Lines`]' character counts.
const BLOCK: usize = 256;

/// Whether byte `b` starts a character (is not a UTF-8 continuation byte).
fn starts_char(b: u8) -> bool {
    b & 0xC0 != 0x80
}

impl<'i> Lines<'i> {
    /// The line index of `text`, one pass.
    pub(crate) fn new(text: &'i str) -> Self {
        let mut starts = std::vec![0];
        starts.extend(
            text.bytes()
                .enumerate()
                .filter(|&(_, b)| b == b'\n')
                .map(|(i, _)| i + 1),
        );
        let mut chars_before_block = std::vec![0];
        let mut chars = 0;
        for block in text.as_bytes().chunks(BLOCK) {
            chars += block.iter().filter(|&&b| starts_char(b)).count();
            chars_before_block.push(chars);
        }
        Self {
            text,
            starts,
            chars_before_block,
        }
    }

    /// Characters in `text[..at]` (`at` at a character boundary).
    fn chars_before(&self, at: usize) -> usize {
        let block = at / BLOCK;
        let from = block * BLOCK;
        self.chars_before_block[block]
            + self.text.as_bytes()[from..at]
                .iter()
                .filter(|&&b| starts_char(b))
                .count()
    }

    /// The reference of `node` (of this document), line and column (in characters) from 1.
    pub(crate) fn elem(&self, node: Node) -> ElementRef {
        let at = node.range().start.min(self.text.len());
        let line = self.starts.partition_point(|&s| s <= at).max(1);
        let start = self.starts[line - 1];
        let column = self.chars_before(at) - self.chars_before(start) + 1;
        element_ref(node, line as u32, column as u32)
    }
}

/// An error at `node`.
pub(crate) fn err(node: Node, kind: LoadErrorKind) -> LoadError {
    LoadError::at(elem(node), kind)
}

/// The first child element called `tag`.
pub(crate) fn child<'a, 'i>(node: Node<'a, 'i>, tag: &str) -> Option<Node<'a, 'i>> {
    node.children()
        .find(|c| c.is_element() && c.tag_name().name() == tag)
}

/// All child elements called `tag`, in document order.
pub(crate) fn children<'a, 'i: 'a>(
    node: Node<'a, 'i>,
    tag: &'a str,
) -> impl Iterator<Item = Node<'a, 'i>> + 'a {
    node.children()
        .filter(move |c| c.is_element() && c.tag_name().name() == tag)
}

/// A required attribute.
pub(crate) fn attr<'a>(node: Node<'a, '_>, name: &'static str) -> Result<&'a str, LoadError> {
    node.attribute(name)
        .ok_or_else(|| err(node, LoadErrorKind::MissingAttribute { attribute: name }))
}

/// The index in `index` of what attribute `by` of `node`'s first child `tag` names (an idref,
/// a link name): a missing child is an error at `node`, an unknown name one at `at`.
pub(crate) fn reference(
    node: Node,
    tag: &'static str,
    by: &'static str,
    index: &HashMap<&str, usize>,
    at: Node,
) -> Result<usize, LoadError> {
    let e =
        child(node, tag).ok_or_else(|| err(node, LoadErrorKind::MissingElement { child: tag }))?;
    let name = attr(e, by)?;
    index.get(name).copied().ok_or_else(|| {
        err(
            at,
            LoadErrorKind::UnresolvedReference {
                target: name.to_string(),
            },
        )
    })
}

/// A finite number; `node` and `what` name it in the error.
pub(crate) fn number(node: Node, what: &str, text: &str) -> Result<f64, LoadError> {
    match text.trim().parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(_) => Err(invalid(node, what, text, "not finite")),
        Err(_) => Err(invalid(node, what, text, "not a number")),
    }
}

/// An [`LoadErrorKind::InvalidValue`] at `node`.
pub(crate) fn invalid(node: Node, what: &str, value: &str, reason: &'static str) -> LoadError {
    err(
        node,
        LoadErrorKind::InvalidValue {
            what: what.to_string(),
            value: value.trim().to_string(),
            reason,
        },
    )
}

/// The text of child `tag` as a number, `default` if there is no such child (RL's
/// `number(tag)` with a default).
pub(crate) fn child_number(node: Node, tag: &str, default: f64) -> Result<f64, LoadError> {
    match child(node, tag) {
        Some(c) => number(c, tag, c.text().unwrap_or("")),
        None => Ok(default),
    }
}

/// `x`, `y`, `z` children of `node` (each defaulting to the component of `default`).
pub(crate) fn child_xyz(node: Node, default: DVec3) -> Result<DVec3, LoadError> {
    Ok(DVec3::new(
        child_number(node, "x", default.x)?,
        child_number(node, "y", default.y)?,
        child_number(node, "z", default.z)?,
    ))
}

/// A space-separated triple in attribute `name` (URDF's `xyz`, `rpy`), or `default`.
pub(crate) fn attr_vec3(node: Node, name: &str, default: DVec3) -> Result<DVec3, LoadError> {
    let Some(text) = node.attribute(name) else {
        return Ok(default);
    };
    let mut out = [0.0; 3];
    let mut n = 0;
    for word in text.split_whitespace() {
        if n == 3 {
            return Err(invalid(node, name, text, "expected three numbers"));
        }
        out[n] = number(node, name, word)?;
        n += 1;
    }
    if n != 3 {
        return Err(invalid(node, name, text, "expected three numbers"));
    }
    Ok(DVec3::from_array(out))
}

/// A number in attribute `name`, or `default` when absent.
pub(crate) fn attr_number(node: Node, name: &str, default: f64) -> Result<f64, LoadError> {
    match node.attribute(name) {
        Some(t) => number(node, name, t),
        None => Ok(default),
    }
}

/// `Rz(z)·Ry(y)·Rx(x)`: RL's fixed-axis angles and URDF's roll-pitch-yaw (radians).
pub(crate) fn rot_zyx(x: f64, y: f64, z: f64) -> DMat3 {
    DMat3::from_rotation_z(z) * DMat3::from_rotation_y(y) * DMat3::from_rotation_x(x)
}

/// A unit axis from `v`, or an error at `node` if `v` is (nearly) zero.
pub(crate) fn unit_axis(node: Node, what: &str, v: DVec3) -> Result<DVec3, LoadError> {
    let n = v.length();
    if n > 1e-9 {
        Ok(v / n)
    } else {
        Err(invalid(
            node,
            what,
            &std::format!("{} {} {}", v.x, v.y, v.z),
            "zero axis",
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::format;

    #[test]
    fn line_index_columns_count_characters() {
        // Long lines with multi-byte characters across block boundaries: every element's line
        // and column as a scan from the start of the text finds them.
        let mut text = String::from("<r>\n");
        for k in 0..3000 {
            text.push_str(&format!("<é n=\"ü{k}\"/>"));
            if k % 700 == 699 {
                text.push('\n');
            }
        }
        text.push_str("</r>");
        let doc = Document::parse(&text).unwrap();
        let lines = Lines::new(&text);
        let mut checked = 0;
        for n in doc.descendants().filter(|n| n.is_element()) {
            let at = n.range().start;
            let before = &text[..at];
            let line = before.matches('\n').count() + 1;
            let column = before.rsplit('\n').next().unwrap().chars().count() + 1;
            let e = lines.elem(n);
            assert_eq!((e.line, e.column), (line as u32, column as u32), "{at}");
            checked += 1;
        }
        assert_eq!(checked, 3001);
    }
}
