//! roxmltree helpers shared by the URDF, SRDF and rlsg readers: errors that name the element
//! and its line, attribute parsing.

use glam::DVec3;
use rl_core::loader::{Clipped, InputLimits, LoadErrorKind, check_xml};
use roxmltree::{Document, Node, ParsingOptions};

use crate::error::{SgError, SgErrorKind};

/// Parses `text` within rl-core's input limits ([`InputLimits::DEFAULT`]: size, nesting depth,
/// attributes per element, nodes; DTDs allowed: roxmltree bounds entity expansion).
pub(crate) fn parse(text: &str) -> Result<Document<'_>, SgError> {
    let limits = InputLimits::DEFAULT;
    check(text, &limits)?;
    let opt = ParsingOptions {
        allow_dtd: true,
        nodes_limit: limits.max_nodes,
        ..ParsingOptions::default()
    };
    Document::parse_with_options(text, opt).map_err(|e| match e {
        roxmltree::Error::NodesLimitReached => SgError::new(SgErrorKind::TooLarge {
            what: "number of XML nodes",
            limit: u64::from(limits.max_nodes),
        }),
        e => {
            let p = e.pos();
            SgError::syntax(e.to_string()).at_position(p.row, p.col)
        }
    })
}

/// rl-core's check of XML `text` against `limits` ([`check_xml`]), its error as an [`SgError`]
/// at the element's line and column.
pub(crate) fn check(text: &str, limits: &InputLimits) -> Result<(), SgError> {
    check_xml(text, limits).map_err(|e| {
        let kind = match e.kind {
            LoadErrorKind::TooLarge { what, limit } => SgErrorKind::TooLarge { what, limit },
            other => SgErrorKind::Syntax(other.to_string()),
        };
        let err = SgError::new(kind);
        match e.element {
            Some(el) => err
                .at(format!("<{}>", Clipped(&el.tag, Clipped::NAME)))
                .at_position(el.line, el.column),
            None => err,
        }
    })
}

/// The root element of `doc`, which must be `<robot>`; `what` names the format for the error
/// ("a URDF", "an SRDF").
pub(crate) fn robot_root<'a, 'i>(
    doc: &'a Document<'i>,
    what: &str,
) -> Result<Node<'a, 'i>, SgError> {
    let robot = doc.root_element();
    if robot.tag_name().name() == "robot" {
        return Ok(robot);
    }
    Err(at(
        robot,
        SgError::new(SgErrorKind::UnsupportedFormat {
            format: format!("<{}>: not {what} <robot>", robot.tag_name().name()),
        }),
    ))
}

/// `<tag name="…">` of `node`, for messages.
pub(crate) fn describe(node: Node) -> String {
    let tag = Clipped(node.tag_name().name(), Clipped::NAME);
    match node.attribute("name").or_else(|| node.attribute("id")) {
        Some(n) => format!("<{tag} name=\"{}\">", Clipped(n, Clipped::NAME)),
        None => format!("<{tag}>"),
    }
}

/// Places `e` at `node` (its line and column, its description unless one is set).
pub(crate) fn at(node: Node, e: SgError) -> SgError {
    let p = node.document().text_pos_at(node.range().start);
    e.at(describe(node)).at_position(p.row, p.col)
}

/// The first child element called `tag`.
pub(crate) fn child<'a, 'i>(node: Node<'a, 'i>, tag: &str) -> Option<Node<'a, 'i>> {
    node.children()
        .find(|c| c.is_element() && c.tag_name().name() == tag)
}

/// All child elements called `tag`.
pub(crate) fn children<'a, 'i: 'a>(
    node: Node<'a, 'i>,
    tag: &'a str,
) -> impl Iterator<Item = Node<'a, 'i>> + 'a {
    node.children()
        .filter(move |c| c.is_element() && c.tag_name().name() == tag)
}

/// A required attribute.
pub(crate) fn attr<'a>(node: Node<'a, '_>, name: &str) -> Result<&'a str, SgError> {
    node.attribute(name)
        .ok_or_else(|| at(node, SgError::missing(format!("attribute \"{name}\""))))
}

/// A finite number.
pub(crate) fn number(node: Node, what: &str, text: &str) -> Result<f64, SgError> {
    match text.trim().parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(_) => Err(at(node, SgError::invalid(what, text.trim(), "not finite"))),
        Err(_) => Err(at(
            node,
            SgError::invalid(what, text.trim(), "not a number"),
        )),
    }
}

/// A required numeric attribute.
pub(crate) fn number_attr(node: Node, name: &str) -> Result<f64, SgError> {
    number(node, name, attr(node, name)?)
}

/// `n` numbers separated by spaces.
pub(crate) fn numbers<const N: usize>(
    node: Node,
    what: &str,
    text: &str,
) -> Result<[f64; N], SgError> {
    let mut out = [0.0; N];
    let mut it = text.split_whitespace();
    for o in &mut out {
        let t = it
            .next()
            .ok_or_else(|| at(node, SgError::invalid(what, text.trim(), "too few numbers")))?;
        *o = number(node, what, t)?;
    }
    if it.next().is_some() {
        return Err(at(
            node,
            SgError::invalid(what, text.trim(), "too many numbers"),
        ));
    }
    Ok(out)
}

/// An optional attribute of three numbers, `default` when absent.
pub(crate) fn vec3_attr(node: Node, name: &str, default: DVec3) -> Result<DVec3, SgError> {
    match node.attribute(name) {
        Some(t) => Ok(DVec3::from_array(numbers::<3>(node, name, t)?)),
        None => Ok(default),
    }
}
