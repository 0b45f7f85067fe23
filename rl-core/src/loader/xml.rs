//! Small helpers over roxmltree shared by both formats: element references for errors,
//! child lookup and number parsing that reports the element at fault.

use std::string::ToString;

use glam::{DMat3, DVec3};
use roxmltree::{Document, Node, ParsingOptions};

use super::error::{ElementRef, LoadError, LoadErrorKind};

/// Parses `text` (DTDs allowed: roxmltree bounds entity expansion).
pub(crate) fn parse(text: &str) -> Result<Document<'_>, LoadError> {
    let opt = ParsingOptions {
        allow_dtd: true,
        ..ParsingOptions::default()
    };
    Document::parse_with_options(text, opt)
        .map_err(|e| LoadError::new(LoadErrorKind::Xml(e.to_string())))
}

/// The reference of `node` for error messages.
pub(crate) fn elem(node: Node) -> ElementRef {
    let pos = node.document().text_pos_at(node.range().start);
    ElementRef {
        tag: node.tag_name().name().to_string(),
        id: node
            .attribute("id")
            .or_else(|| node.attribute("name"))
            .map(str::to_string),
        line: pos.row,
        column: pos.col,
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
