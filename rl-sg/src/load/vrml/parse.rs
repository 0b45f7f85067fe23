//! VRML97's node syntax, read without a schema: a node is `[DEF name] Type { field value … }`,
//! a value is a run of numbers, a string, a boolean, a node (`Type {…}`, `USE name`, `NULL`)
//! or a bracketed list of one of these. That covers every node type, so unknown nodes
//! (materials, viewpoints, lights) are read and skipped rather than refused; `PROTO`,
//! `EXTERNPROTO` and `Script` (new node types and code) are refused with an error.
//!
//! Limits keep hostile input harmless: nesting depth 64, and the nodes the caller allows
//! (what is left of the scene's [`crate::load::SceneLimits::max_nodes`]).

use std::collections::HashMap;

use rl_core::loader::Clipped;

use super::lexer::{Lexer, Spanned, Token};
use crate::error::{SgError, SgErrorKind};

/// How deep nodes may nest in one file: RL's files nest fewer than ten deep, CAD exports a few
/// dozen; the bound keeps the recursive reader within a 2 MiB thread stack even in a debug build.
const MAX_DEPTH: usize = 64;
/// Most fields of one node: VRML97's largest node has 14; every visit of a node looks its
/// fields up, so a node with a million of them, used a million times, would cost 10¹².
const MAX_FIELDS: usize = 128;

/// A node's index in its file's arena.
pub(crate) type NodeIndex = usize;

/// A field value.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Value {
    /// Numbers (SFFloat, SFVec3f, SFRotation, MFInt32, …).
    Numbers(Vec<f64>),
    /// Booleans.
    Bools(Vec<bool>),
    /// Strings.
    Strings(Vec<String>),
    /// Nodes (SFNode, MFNode; `NULL` is an empty list).
    Nodes(Vec<NodeIndex>),
}

/// A node as written.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Node {
    pub type_name: String,
    pub def: Option<String>,
    pub fields: Vec<(String, Value)>,
    pub line: u32,
    pub column: u32,
}

impl Node {
    pub(crate) fn field(&self, name: &str) -> Option<&Value> {
        self.fields
            .iter()
            .rev()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v)
    }

    /// `type "DEF name"` for messages, with the line.
    pub(crate) fn describe(&self) -> String {
        let ty = Clipped(&self.type_name, Clipped::NAME);
        match &self.def {
            Some(d) => format!("{ty} \"{}\"", Clipped(d, Clipped::NAME)),
            None => ty.to_string(),
        }
    }
}

/// A parsed file: its nodes and the top-level ones.
#[derive(Clone, Debug, Default)]
pub(crate) struct Document {
    pub nodes: Vec<Node>,
    pub roots: Vec<NodeIndex>,
}

struct Parser<'a> {
    lexer: Lexer<'a>,
    max_nodes: usize,
    peeked: Option<Spanned<'a>>,
    doc: Document,
    defs: HashMap<String, NodeIndex>,
    /// Where the last token ended (for "unexpected end" errors).
    last: (u32, u32),
}

/// Parses a VRML97 file: the `#VRML V2.0` header, then nodes (and `ROUTE` statements, which
/// are skipped); at most `max_nodes` of them.
pub(crate) fn parse(text: &str, max_nodes: usize) -> Result<Document, SgError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if !text.starts_with("#VRML V2.0") {
        let first: String = text.chars().take(20).collect();
        return Err(SgError::syntax(format!(
            "not a VRML97 file: it must start with \"#VRML V2.0 utf8\", not {first:?}"
        ))
        .at_position(1, 1));
    }
    let mut p = Parser {
        lexer: Lexer::new(text),
        max_nodes,
        peeked: None,
        doc: Document::default(),
        defs: HashMap::new(),
        last: (1, 1),
    };
    while let Some(t) = p.peek()? {
        match &t.token {
            Token::Ident("ROUTE") => p.route()?,
            Token::Ident("PROTO" | "EXTERNPROTO") => {
                let t = t.clone();
                return Err(p.unsupported(&t, "PROTO and EXTERNPROTO (new node types)"));
            }
            _ => {
                let n = p.node_statement(0)?;
                if let Some(n) = n {
                    p.doc.roots.push(n);
                }
            }
        }
    }
    Ok(p.doc)
}

impl<'a> Parser<'a> {
    fn peek(&mut self) -> Result<Option<&Spanned<'a>>, SgError> {
        if self.peeked.is_none() {
            self.peeked = self.lexer.next_token()?;
        }
        Ok(self.peeked.as_ref())
    }

    fn next(&mut self) -> Result<Spanned<'a>, SgError> {
        let t = match self.peeked.take() {
            Some(t) => t,
            None => self.lexer.next_token()?.ok_or_else(|| {
                SgError::syntax("unexpected end of file").at_position(self.last.0, self.last.1)
            })?,
        };
        self.last = (t.line, t.column);
        Ok(t)
    }

    fn error(t: &Spanned, message: impl Into<String>) -> SgError {
        SgError::syntax(message).at_position(t.line, t.column)
    }

    fn unsupported(&self, t: &Spanned, what: &str) -> SgError {
        SgError::unsupported(what.to_string()).at_position(t.line, t.column)
    }

    fn expect(&mut self, c: char) -> Result<(), SgError> {
        let t = self.next()?;
        if t.token == Token::Punct(c) {
            Ok(())
        } else {
            Err(Self::error(
                &t,
                format!("expected '{c}', found {}", show(&t.token)),
            ))
        }
    }

    /// `ROUTE a.b TO c.d` (events only matter to animation): skipped.
    fn route(&mut self) -> Result<(), SgError> {
        self.next()?;
        for expected in ["node", ".", "event", "TO", "node", ".", "event"] {
            let t = self.next()?;
            let ok = matches!(
                (&t.token, expected),
                (Token::Punct('.'), ".")
                    | (Token::Ident("TO"), "TO")
                    | (Token::Ident(_), "node" | "event")
            );
            if !ok {
                return Err(Self::error(
                    &t,
                    format!("in ROUTE: expected {expected}, found {}", show(&t.token)),
                ));
            }
        }
        Ok(())
    }

    /// `[DEF name] Type {…}`, `USE name` or `NULL` (`None`).
    fn node_statement(&mut self, depth: usize) -> Result<Option<NodeIndex>, SgError> {
        let t = self.next()?;
        match t.token {
            Token::Ident("NULL") => Ok(None),
            Token::Ident("USE") => {
                let n = self.next()?;
                let Token::Ident(name) = n.token else {
                    return Err(Self::error(&n, "expected a name after USE"));
                };
                self.defs.get(name).copied().map(Some).ok_or_else(|| {
                    Self::error(&n, format!("USE of \"{name}\", which no DEF names before"))
                })
            }
            Token::Ident("DEF") => {
                let n = self.next()?;
                let Token::Ident(name) = n.token else {
                    return Err(Self::error(&n, "expected a name after DEF"));
                };
                let ty = self.next()?;
                let node = self.node(ty, Some(name.to_string()), depth)?;
                self.defs.insert(name.to_string(), node);
                Ok(Some(node))
            }
            Token::Ident(_) => self.node(t, None, depth).map(Some),
            _ => Err(Self::error(
                &t,
                format!("expected a node, found {}", show(&t.token)),
            )),
        }
    }

    /// `Type { fields }`, `ty` already read.
    fn node(
        &mut self,
        ty: Spanned<'a>,
        def: Option<String>,
        depth: usize,
    ) -> Result<NodeIndex, SgError> {
        if depth >= MAX_DEPTH {
            return Err(Self::error(
                &ty,
                format!("nodes nested deeper than {MAX_DEPTH}"),
            ));
        }
        let Token::Ident(type_name) = ty.token else {
            return Err(Self::error(
                &ty,
                format!("expected a node type, found {}", show(&ty.token)),
            ));
        };
        if matches!(type_name, "Script" | "PROTO" | "EXTERNPROTO") {
            return Err(self.unsupported(&ty, &format!("{type_name} nodes")));
        }
        if self.doc.nodes.len() >= self.max_nodes {
            return Err(SgError::new(SgErrorKind::TooLarge {
                what: "number of VRML nodes (in all files of the scene)",
                limit: self.max_nodes as u64,
            })
            .at_position(ty.line, ty.column));
        }
        self.expect('{')?;
        let mut fields = Vec::new();
        loop {
            let t = self.next()?;
            match t.token {
                Token::Punct('}') => break,
                Token::Ident("ROUTE") => {
                    self.peeked = Some(t);
                    self.route()?;
                }
                Token::Ident(name) => {
                    if fields.len() >= MAX_FIELDS {
                        return Err(SgError::new(SgErrorKind::TooLarge {
                            what: "number of fields of one node",
                            limit: MAX_FIELDS as u64,
                        })
                        .at_position(t.line, t.column));
                    }
                    let v = self.value(name, depth + 1)?;
                    fields.push((name.to_string(), v));
                }
                _ => {
                    return Err(Self::error(
                        &t,
                        format!("expected a field name or '}}', found {}", show(&t.token)),
                    ));
                }
            }
        }
        self.doc.nodes.push(Node {
            type_name: type_name.to_string(),
            def,
            fields,
            line: ty.line,
            column: ty.column,
        });
        Ok(self.doc.nodes.len() - 1)
    }

    /// A field's value.
    fn value(&mut self, field: &str, depth: usize) -> Result<Value, SgError> {
        let t = match self.peek()? {
            Some(t) => t.clone(),
            None => {
                return Err(SgError::syntax(format!("field \"{field}\" has no value"))
                    .at_position(self.last.0, self.last.1));
            }
        };
        match &t.token {
            Token::Number(_) => {
                let mut v = Vec::new();
                while let Some(Spanned {
                    token: Token::Number(x),
                    ..
                }) = self.peek()?
                {
                    v.push(*x);
                    self.next()?;
                }
                Ok(Value::Numbers(v))
            }
            Token::String(_) => {
                let Token::String(s) = self.next()?.token else {
                    unreachable!()
                };
                Ok(Value::Strings(vec![s]))
            }
            Token::Ident("TRUE" | "FALSE") => {
                let b = self.next()?.token == Token::Ident("TRUE");
                Ok(Value::Bools(vec![b]))
            }
            Token::Ident("IS") => Err(self.unsupported(&t, "IS (PROTO interfaces)")),
            Token::Ident(_) => Ok(Value::Nodes(
                self.node_statement(depth)?.into_iter().collect(),
            )),
            Token::Punct('[') => {
                self.next()?;
                self.list(field, depth)
            }
            _ => Err(Self::error(
                &t,
                format!(
                    "field \"{field}\": expected a value, found {}",
                    show(&t.token)
                ),
            )),
        }
    }

    /// The rest of `[ … ]`: all numbers, all strings, all booleans or all nodes.
    fn list(&mut self, field: &str, depth: usize) -> Result<Value, SgError> {
        let mut numbers = Vec::new();
        let mut strings = Vec::new();
        let mut bools = Vec::new();
        let mut nodes = Vec::new();
        loop {
            let t = match self.peek()? {
                Some(t) => t.clone(),
                None => {
                    return Err(
                        SgError::syntax(format!("field \"{field}\": unterminated '['"))
                            .at_position(self.last.0, self.last.1),
                    );
                }
            };
            let (line, column) = (t.line, t.column);
            match t.token {
                Token::Punct(']') => {
                    self.next()?;
                    break;
                }
                Token::Number(x) => {
                    numbers.push(x);
                    self.next()?;
                }
                Token::String(s) => {
                    strings.push(s);
                    self.next()?;
                }
                Token::Ident("TRUE") | Token::Ident("FALSE") => {
                    bools.push(t.token == Token::Ident("TRUE"));
                    self.next()?;
                }
                Token::Ident(_) => nodes.extend(self.node_statement(depth)?),
                _ => {
                    return Err(Self::error(
                        &t,
                        format!("field \"{field}\": unexpected {} in a list", show(&t.token)),
                    ));
                }
            }
            let kinds = [
                !numbers.is_empty(),
                !strings.is_empty(),
                !bools.is_empty(),
                !nodes.is_empty(),
            ];
            if kinds.iter().filter(|k| **k).count() > 1 {
                return Err(SgError::syntax(format!(
                    "field \"{field}\": a list mixes values of different types"
                ))
                .at_position(line, column));
            }
        }
        Ok(if !strings.is_empty() {
            Value::Strings(strings)
        } else if !bools.is_empty() {
            Value::Bools(bools)
        } else if !nodes.is_empty() {
            Value::Nodes(nodes)
        } else {
            Value::Numbers(numbers)
        })
    }
}

fn show(t: &Token) -> String {
    match t {
        Token::Ident(s) => format!("\"{s}\""),
        Token::Number(x) => format!("the number {x}"),
        Token::String(s) => format!("the string {s:?}"),
        Token::Punct(c) => format!("'{c}'"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Document, SgError> {
        super::parse(text, 1_000_000)
    }

    #[test]
    fn nodes_fields_def_and_use() {
        let d = parse(
            "#VRML V2.0 utf8\nDEF a Transform { translation 1 2 3 children [ DEF s Shape { geometry Box { size 1 1 1 } } USE s ] }\nROUTE a.x TO b.y",
        )
        .unwrap();
        assert_eq!(d.roots.len(), 1);
        let root = &d.nodes[d.roots[0]];
        assert_eq!(
            (root.type_name.as_str(), root.def.as_deref()),
            ("Transform", Some("a"))
        );
        assert_eq!(
            root.field("translation"),
            Some(&Value::Numbers(vec![1.0, 2.0, 3.0]))
        );
        let Some(Value::Nodes(kids)) = root.field("children") else {
            panic!()
        };
        assert_eq!(kids.len(), 2);
        assert_eq!(kids[0], kids[1], "USE shares the DEF'd node");
    }

    #[test]
    fn bad_input_is_an_error_with_a_position() {
        for (text, line) in [
            ("#VRML V2.0 utf8\nShape {\n geometry USE nothing }", 3),
            ("#VRML V2.0 utf8\nShape { geometry Box { size 1 1 1 }", 2),
            ("#VRML V2.0 utf8\nTransform { children [ 1 \"a\" ] }", 2),
            ("#VRML V2.0 utf8\nPROTO X [] {}", 2),
            ("#VRML V2.0 utf8\nShape { appearance }", 2),
        ] {
            let e = parse(text).unwrap_err();
            assert!(
                e.position.is_some_and(|p| p.0 >= 1 && p.0 <= line),
                "{text}: {e}"
            );
        }
        assert!(parse("VRML 1.0").is_err());
        let deep = format!("#VRML V2.0 utf8\n{}", "Group { children [ ".repeat(300));
        assert!(parse(&deep).unwrap_err().to_string().contains("deeper"));
    }
}
