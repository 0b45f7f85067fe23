//! The fake controller's URScript: a compiler and interpreter for the part of the language a
//! program that follows RTDE registers uses (RL's `UniversalRobotsRtde` program, ours, and the
//! like). What is outside it is refused when the program is compiled, as the controller refuses
//! a program that does not compile, naming the line.
//!
//! - Statements: `def name():` … `end` (the program; a script without one is run as one),
//!   assignments (`x = e`, `x[i] = e`, `global`/`local`), `while e:`, `if e:` / `elif e:` /
//!   `else:`, `end`, `break`, `continue`, `return`, `halt`, `pass`, calls.
//! - Expressions: numbers, `True`/`False`, strings, lists `[…]` and poses `p[…]`, names,
//!   indexing, calls with positional and named arguments, `not`, unary `-`, `* / %`, `+ -`,
//!   comparisons, `and`, `or`.
//! - Time: the program runs inside the controller's 2 ms cycle. A motion or waiting call
//!   (`servoj`, `speedj`, `movej`, `stopj`, `sync`, `sleep`) ends the cycle's share; a program
//!   that runs 100 000 statements without one is stopped, as the controller stops a thread
//!   that never yields.

use std::collections::HashMap;
use std::fmt;

/// Statements a cycle may run before the program is taken to be stuck.
const MAX_STATEMENTS_PER_CYCLE: u32 = 100_000;

/// A value.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Value {
    Int(i64),
    Float(f64),
    Bool(bool),
    Str(String),
    List(Vec<Value>),
}

impl Value {
    pub(crate) fn as_f64(&self) -> Option<f64> {
        match self {
            Self::Int(i) => Some(*i as f64),
            Self::Float(f) => Some(*f),
            Self::Bool(b) => Some(f64::from(u8::from(*b))),
            _ => None,
        }
    }

    pub(crate) fn as_i64(&self) -> Option<i64> {
        match self {
            Self::Int(i) => Some(*i),
            Self::Float(f) if f.fract() == 0.0 => Some(*f as i64),
            Self::Bool(b) => Some(i64::from(*b)),
            _ => None,
        }
    }

    pub(crate) fn truthy(&self) -> Result<bool, String> {
        match self {
            Self::Bool(b) => Ok(*b),
            Self::Int(i) => Ok(*i != 0),
            Self::Float(f) => Ok(*f != 0.0),
            other => Err(format!("{other} is not a boolean")),
        }
    }

    /// Six numbers (joint positions, speeds, a pose).
    pub(crate) fn as_six(&self) -> Option<[f64; 6]> {
        let Self::List(v) = self else { return None };
        if v.len() != 6 {
            return None;
        }
        let mut out = [0.0; 6];
        for (o, x) in out.iter_mut().zip(v) {
            *o = x.as_f64()?;
        }
        Some(out)
    }

    pub(crate) fn six(v: [f64; 6]) -> Self {
        Self::List(v.iter().map(|x| Self::Float(*x)).collect())
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Int(i) => write!(f, "{i}"),
            Self::Float(x) => write!(f, "{x}"),
            Self::Bool(b) => f.write_str(if *b { "True" } else { "False" }),
            Self::Str(s) => write!(f, "\"{s}\""),
            Self::List(v) => {
                f.write_str("[")?;
                for (k, x) in v.iter().enumerate() {
                    if k > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{x}")?;
                }
                f.write_str("]")
            }
        }
    }
}

/// A compile error: where and what.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct CompileError {
    pub line: usize,
    pub message: String,
}

impl fmt::Display for CompileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "compile error on line {}: {}", self.line, self.message)
    }
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    Int(i64),
    Float(f64),
    Str(String),
    Op(&'static str),
}

const OPS: [&str; 19] = [
    "==", "!=", "<=", ">=", "<", ">", "=", "+", "-", "*", "/", "%", "(", ")", "[", "]", ",", ":",
    ".",
];

fn lex(line: &str) -> Result<Vec<Tok>, String> {
    let b = line.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c.is_ascii_whitespace() {
            i += 1;
        } else if c == b'#' {
            break;
        } else if c.is_ascii_alphabetic() || c == b'_' {
            let s = i;
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            out.push(Tok::Ident(line[s..i].to_owned()));
        } else if c.is_ascii_digit() || (c == b'.' && b.get(i + 1).is_some_and(u8::is_ascii_digit))
        {
            let s = i;
            let mut float = false;
            while i < b.len()
                && (b[i].is_ascii_digit()
                    || b[i] == b'.'
                    || b[i] == b'e'
                    || b[i] == b'E'
                    || ((b[i] == b'-' || b[i] == b'+') && matches!(b[i - 1], b'e' | b'E')))
            {
                float |= !b[i].is_ascii_digit();
                i += 1;
            }
            let text = &line[s..i];
            if float {
                out.push(Tok::Float(
                    text.parse().map_err(|_| format!("bad number `{text}`"))?,
                ));
            } else {
                out.push(Tok::Int(
                    text.parse().map_err(|_| format!("bad number `{text}`"))?,
                ));
            }
        } else if c == b'"' || c == b'\'' {
            let s = i + 1;
            i = s;
            while i < b.len() && b[i] != c {
                i += 1;
            }
            if i >= b.len() {
                return Err("unterminated string".into());
            }
            out.push(Tok::Str(line[s..i].to_owned()));
            i += 1;
        } else if let Some(op) = OPS.iter().find(|op| line[i..].starts_with(**op)) {
            out.push(Tok::Op(op));
            i += op.len();
        } else {
            return Err(format!("unexpected character `{}`", c as char));
        }
    }
    Ok(out)
}

/// An expression.
#[derive(Clone, Debug, PartialEq)]
enum Expr {
    Const(Value),
    Var(String),
    List(Vec<Expr>),
    Index(Box<Expr>, Box<Expr>),
    Call(String, Vec<(Option<String>, Expr)>),
    Not(Box<Expr>),
    Neg(Box<Expr>),
    Binary(&'static str, Box<Expr>, Box<Expr>),
}

struct Parser<'t> {
    toks: &'t [Tok],
    at: usize,
}

impl<'t> Parser<'t> {
    fn peek(&self) -> Option<&'t Tok> {
        self.toks.get(self.at)
    }

    fn next(&mut self) -> Option<&'t Tok> {
        let t = self.toks.get(self.at);
        self.at += 1;
        t
    }

    fn eat_op(&mut self, op: &str) -> bool {
        if self.peek() == Some(&Tok::Op(match_op(op))) {
            self.at += 1;
            true
        } else {
            false
        }
    }

    fn eat_word(&mut self, w: &str) -> bool {
        if matches!(self.peek(), Some(Tok::Ident(s)) if s == w) {
            self.at += 1;
            true
        } else {
            false
        }
    }

    fn expect_op(&mut self, op: &str) -> Result<(), String> {
        if self.eat_op(op) {
            Ok(())
        } else {
            Err(format!("expected `{op}`"))
        }
    }

    fn expr(&mut self) -> Result<Expr, String> {
        let mut l = self.and()?;
        while self.eat_word("or") {
            l = Expr::Binary("or", Box::new(l), Box::new(self.and()?));
        }
        Ok(l)
    }

    fn and(&mut self) -> Result<Expr, String> {
        let mut l = self.not()?;
        while self.eat_word("and") {
            l = Expr::Binary("and", Box::new(l), Box::new(self.not()?));
        }
        Ok(l)
    }

    fn not(&mut self) -> Result<Expr, String> {
        if self.eat_word("not") {
            return Ok(Expr::Not(Box::new(self.not()?)));
        }
        self.comparison()
    }

    fn comparison(&mut self) -> Result<Expr, String> {
        let l = self.sum()?;
        for op in ["==", "!=", "<=", ">=", "<", ">"] {
            if self.eat_op(op) {
                return Ok(Expr::Binary(
                    match_op(op),
                    Box::new(l),
                    Box::new(self.sum()?),
                ));
            }
        }
        Ok(l)
    }

    fn sum(&mut self) -> Result<Expr, String> {
        let mut l = self.product()?;
        loop {
            let op = if self.eat_op("+") {
                "+"
            } else if self.eat_op("-") {
                "-"
            } else {
                return Ok(l);
            };
            l = Expr::Binary(op, Box::new(l), Box::new(self.product()?));
        }
    }

    fn product(&mut self) -> Result<Expr, String> {
        let mut l = self.unary()?;
        loop {
            let op = if self.eat_op("*") {
                "*"
            } else if self.eat_op("/") {
                "/"
            } else if self.eat_op("%") {
                "%"
            } else {
                return Ok(l);
            };
            l = Expr::Binary(op, Box::new(l), Box::new(self.unary()?));
        }
    }

    fn unary(&mut self) -> Result<Expr, String> {
        if self.eat_op("-") {
            return Ok(Expr::Neg(Box::new(self.unary()?)));
        }
        let mut e = self.primary()?;
        while self.eat_op("[") {
            let i = self.expr()?;
            self.expect_op("]")?;
            e = Expr::Index(Box::new(e), Box::new(i));
        }
        Ok(e)
    }

    fn list(&mut self) -> Result<Expr, String> {
        let mut items = Vec::new();
        if !self.eat_op("]") {
            loop {
                items.push(self.expr()?);
                if self.eat_op("]") {
                    break;
                }
                self.expect_op(",")?;
            }
        }
        Ok(Expr::List(items))
    }

    fn primary(&mut self) -> Result<Expr, String> {
        match self.next() {
            Some(Tok::Int(i)) => Ok(Expr::Const(Value::Int(*i))),
            Some(Tok::Float(f)) => Ok(Expr::Const(Value::Float(*f))),
            Some(Tok::Str(s)) => Ok(Expr::Const(Value::Str(s.clone()))),
            Some(Tok::Op("(")) => {
                let e = self.expr()?;
                self.expect_op(")")?;
                Ok(e)
            }
            Some(Tok::Op("[")) => self.list(),
            Some(Tok::Ident(name)) => match name.as_str() {
                "True" => Ok(Expr::Const(Value::Bool(true))),
                "False" => Ok(Expr::Const(Value::Bool(false))),
                // A pose literal: p[x, y, z, rx, ry, rz].
                "p" if self.eat_op("[") => self.list(),
                _ if self.eat_op("(") => {
                    let mut args = Vec::new();
                    if !self.eat_op(")") {
                        loop {
                            let named = match (self.peek(), self.toks.get(self.at + 1)) {
                                (Some(Tok::Ident(n)), Some(Tok::Op("="))) => {
                                    self.at += 2;
                                    Some(n.clone())
                                }
                                _ => None,
                            };
                            args.push((named, self.expr()?));
                            if self.eat_op(")") {
                                break;
                            }
                            self.expect_op(",")?;
                        }
                    }
                    Ok(Expr::Call(name.clone(), args))
                }
                _ => Ok(Expr::Var(name.clone())),
            },
            Some(t) => Err(format!("unexpected {t:?}")),
            None => Err("unexpected end of line".into()),
        }
    }
}

fn match_op(op: &str) -> &'static str {
    OPS.iter().find(|o| **o == op).copied().unwrap_or("")
}

/// One compiled statement.
#[derive(Clone, Debug, PartialEq)]
enum Instr {
    Assign(String, Option<Expr>, Expr),
    Eval(Expr),
    JumpUnless(Expr, usize),
    Jump(usize),
    Stop,
}

/// A compiled program.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Program {
    pub name: String,
    code: Vec<Instr>,
    lines: Vec<usize>,
}

/// Open blocks while compiling.
enum Block {
    While {
        start: usize,
        test: usize,
        breaks: Vec<usize>,
    },
    If {
        test: Option<usize>,
        ends: Vec<usize>,
    },
    Def,
}

fn calls(e: &Expr, f: &mut impl FnMut(&str) -> Result<(), String>) -> Result<(), String> {
    match e {
        Expr::Call(name, args) => {
            f(name)?;
            for (_, a) in args {
                calls(a, f)?;
            }
            Ok(())
        }
        Expr::List(v) => v.iter().try_for_each(|x| calls(x, f)),
        Expr::Index(a, b) | Expr::Binary(_, a, b) => {
            calls(a, f)?;
            calls(b, f)
        }
        Expr::Not(a) | Expr::Neg(a) => calls(a, f),
        Expr::Const(_) | Expr::Var(_) => Ok(()),
    }
}

/// Compiles a script; `known` says whether a function exists.
pub(crate) fn compile(text: &str, known: &dyn Fn(&str) -> bool) -> Result<Program, CompileError> {
    let mut code: Vec<Instr> = Vec::new();
    let mut lines = Vec::new();
    let mut blocks: Vec<Block> = Vec::new();
    let mut name = String::from("script");
    let mut had_def = false;
    let mut closed = false;
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let err = |message: String| CompileError { line, message };
        let toks = lex(raw).map_err(err)?;
        if toks.is_empty() {
            continue;
        }
        if closed {
            return Err(err("statements after the program's end".into()));
        }
        let mut p = Parser { toks: &toks, at: 0 };
        let first = match &toks[0] {
            Tok::Ident(s) => s.as_str(),
            _ => "",
        };
        let mut emit = |i: Instr, code: &mut Vec<Instr>| {
            code.push(i);
            lines.push(line);
        };
        match first {
            "def" | "sec" => {
                p.at = 1;
                let Some(Tok::Ident(n)) = p.next() else {
                    return Err(err("expected a name".into()));
                };
                if had_def || !blocks.is_empty() || !code.is_empty() {
                    return Err(err(
                        "functions inside the program are not simulated by the fake".into(),
                    ));
                }
                p.expect_op("(").map_err(err)?;
                p.expect_op(")")
                    .map_err(|_| err("parameters are not simulated by the fake".into()))?;
                p.expect_op(":").map_err(err)?;
                name = n.clone();
                had_def = true;
                blocks.push(Block::Def);
            }
            "thread" | "run" | "join" | "kill" | "enter_critical" | "exit_critical" => {
                return Err(err(format!("`{first}` is not simulated by the fake")));
            }
            "while" => {
                p.at = 1;
                let e = p.expr().map_err(err)?;
                p.expect_op(":").map_err(err)?;
                let start = code.len();
                emit(Instr::JumpUnless(e, usize::MAX), &mut code);
                blocks.push(Block::While {
                    start,
                    test: start,
                    breaks: Vec::new(),
                });
            }
            "if" => {
                p.at = 1;
                let e = p.expr().map_err(err)?;
                p.expect_op(":").map_err(err)?;
                let test = code.len();
                emit(Instr::JumpUnless(e, usize::MAX), &mut code);
                blocks.push(Block::If {
                    test: Some(test),
                    ends: Vec::new(),
                });
            }
            "elif" | "else" => {
                let Some(Block::If { test, ends }) = blocks.last_mut() else {
                    return Err(err(format!("`{first}` outside an `if`")));
                };
                let Some(t) = test.take() else {
                    return Err(err(format!("`{first}` after `else`")));
                };
                ends.push(code.len());
                code.push(Instr::Jump(usize::MAX));
                lines.push(line);
                let here = code.len();
                if let Instr::JumpUnless(_, to) = &mut code[t] {
                    *to = here;
                }
                p.at = 1;
                if first == "elif" {
                    let e = p.expr().map_err(err)?;
                    let test = code.len();
                    code.push(Instr::JumpUnless(e, usize::MAX));
                    lines.push(line);
                    if let Some(Block::If { test: t, .. }) = blocks.last_mut() {
                        *t = Some(test);
                    }
                }
                p.expect_op(":").map_err(err)?;
            }
            "end" => {
                p.at = 1;
                match blocks.pop() {
                    Some(Block::While {
                        start,
                        test,
                        breaks,
                    }) => {
                        emit(Instr::Jump(start), &mut code);
                        let here = code.len();
                        if let Instr::JumpUnless(_, to) = &mut code[test] {
                            *to = here;
                        }
                        for b in breaks {
                            code[b] = Instr::Jump(here);
                        }
                    }
                    Some(Block::If { test, ends }) => {
                        let here = code.len();
                        if let Some(t) = test
                            && let Instr::JumpUnless(_, to) = &mut code[t]
                        {
                            *to = here;
                        }
                        for e in ends {
                            code[e] = Instr::Jump(here);
                        }
                    }
                    Some(Block::Def) => closed = true,
                    None => return Err(err("`end` without a block".into())),
                }
            }
            "break" | "continue" => {
                p.at = 1;
                let Some(w) = blocks.iter_mut().rev().find_map(|b| match b {
                    Block::While { start, breaks, .. } => Some((start, breaks)),
                    _ => None,
                }) else {
                    return Err(err(format!("`{first}` outside a loop")));
                };
                if first == "break" {
                    w.1.push(code.len());
                    emit(Instr::Jump(usize::MAX), &mut code);
                } else {
                    let start = *w.0;
                    emit(Instr::Jump(start), &mut code);
                }
            }
            "return" | "halt" => {
                p.at = 1;
                if first == "halt" {
                    // `halt` and `halt()`.
                    let _ = p.eat_op("(") && p.eat_op(")");
                }
                emit(Instr::Stop, &mut code);
            }
            "pass" => p.at = 1,
            _ => {
                let (scope, target_at) = if matches!(first, "global" | "local") {
                    (true, 1)
                } else {
                    (false, 0)
                };
                // `x = e` or `x[i] = e`, else an expression.
                let assign = match (toks.get(target_at), toks.get(target_at + 1)) {
                    (Some(Tok::Ident(_)), Some(Tok::Op("="))) => true,
                    (Some(Tok::Ident(_)), Some(Tok::Op("["))) => toks.contains(&Tok::Op("=")),
                    _ => false,
                };
                if assign || scope {
                    p.at = target_at;
                    let Some(Tok::Ident(target)) = p.next() else {
                        return Err(err("expected a name".into()));
                    };
                    let index = if p.eat_op("[") {
                        let i = p.expr().map_err(err)?;
                        p.expect_op("]").map_err(err)?;
                        Some(i)
                    } else {
                        None
                    };
                    p.expect_op("=").map_err(err)?;
                    let value = p.expr().map_err(err)?;
                    if let Some(i) = &index {
                        calls(i, &mut |n| check_known(n, known)).map_err(err)?;
                    }
                    calls(&value, &mut |n| check_known(n, known)).map_err(err)?;
                    emit(Instr::Assign(target.clone(), index, value), &mut code);
                } else {
                    let e = p.expr().map_err(err)?;
                    calls(&e, &mut |n| check_known(n, known)).map_err(err)?;
                    emit(Instr::Eval(e), &mut code);
                }
            }
        }
        if p.at < toks.len() {
            return Err(err(format!("unexpected {:?}", toks[p.at])));
        }
    }
    let last = text.lines().count();
    if let Some(b) = blocks.last() {
        let what = match b {
            Block::Def => "the program",
            Block::While { .. } => "a `while`",
            Block::If { .. } => "an `if`",
        };
        return Err(CompileError {
            line: last,
            message: format!("{what} has no `end`"),
        });
    }
    code.push(Instr::Stop);
    lines.push(last);
    Ok(Program { name, code, lines })
}

fn check_known(name: &str, known: &dyn Fn(&str) -> bool) -> Result<(), String> {
    if known(name) {
        Ok(())
    } else {
        Err(format!("name '{name}' is not defined"))
    }
}

/// What a function call did.
pub(crate) enum Called {
    /// Returned a value at once.
    Value(Value),
    /// Blocks the program for this many cycles (then returns nothing).
    Cycles(u32),
    /// Blocks the program until the host says its motion is done.
    Motion,
}

/// The controller, as the program sees it.
pub(crate) trait Host {
    /// Calls function `name`.
    fn call(
        &mut self,
        name: &str,
        args: &[Value],
        named: &[(String, Value)],
    ) -> Result<Called, String>;
    /// Whether the motion a call started is done.
    fn motion_done(&self) -> bool;
}

/// What waits.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Wait {
    No,
    Cycles(u32),
    Motion,
}

/// A running program.
#[derive(Clone, Debug)]
pub(crate) struct Runtime {
    pub program: Program,
    pc: usize,
    vars: HashMap<String, Value>,
    wait: Wait,
}

/// How a cycle ended.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Cycle {
    /// Still running.
    Running,
    /// Reached its end (or `halt`).
    Finished,
    /// Stopped with a runtime error: the line and why.
    Failed(usize, String),
}

impl Runtime {
    pub(crate) fn new(program: Program) -> Self {
        Self {
            program,
            pc: 0,
            vars: HashMap::new(),
            wait: Wait::No,
        }
    }

    /// The line running now.
    pub(crate) fn line(&self) -> usize {
        self.program.lines.get(self.pc).copied().unwrap_or(0)
    }

    /// Runs the program's share of one cycle.
    pub(crate) fn cycle(&mut self, host: &mut dyn Host) -> Cycle {
        match self.wait {
            Wait::Cycles(n) if n > 1 => {
                self.wait = Wait::Cycles(n - 1);
                return Cycle::Running;
            }
            Wait::Motion if !host.motion_done() => return Cycle::Running,
            _ => self.wait = Wait::No,
        }
        for _ in 0..MAX_STATEMENTS_PER_CYCLE {
            let line = self.line();
            let Some(instr) = self.program.code.get(self.pc).cloned() else {
                return Cycle::Finished;
            };
            self.pc += 1;
            let r = match instr {
                Instr::Stop => return Cycle::Finished,
                Instr::Jump(to) => {
                    self.pc = to;
                    Ok(())
                }
                Instr::JumpUnless(e, to) => self.eval(&e, host).and_then(|v| v.truthy()).map(|t| {
                    if !t {
                        self.pc = to;
                    }
                }),
                Instr::Assign(name, index, e) => self.assign(&name, index.as_ref(), &e, host),
                Instr::Eval(e) => self.eval(&e, host).map(|_| ()),
            };
            if let Err(why) = r {
                return Cycle::Failed(line, why);
            }
            if self.wait != Wait::No {
                return Cycle::Running;
            }
        }
        Cycle::Failed(
            self.line(),
            "the program ran 100000 statements in one cycle without a motion or sync()".into(),
        )
    }

    fn assign(
        &mut self,
        name: &str,
        index: Option<&Expr>,
        e: &Expr,
        host: &mut dyn Host,
    ) -> Result<(), String> {
        let v = self.eval(e, host)?;
        match index {
            None => {
                self.vars.insert(name.to_owned(), v);
            }
            Some(i) => {
                let i = self.eval(i, host)?;
                let k = i
                    .as_i64()
                    .ok_or_else(|| format!("index {i} is not an integer"))?;
                let Some(Value::List(list)) = self.vars.get_mut(name) else {
                    return Err(format!("'{name}' is not a list"));
                };
                let n = list.len();
                let slot = usize::try_from(k)
                    .ok()
                    .and_then(|k| list.get_mut(k))
                    .ok_or_else(|| format!("index {k} out of range for '{name}' of {n}"))?;
                *slot = v;
            }
        }
        Ok(())
    }

    fn eval(&mut self, e: &Expr, host: &mut dyn Host) -> Result<Value, String> {
        Ok(match e {
            Expr::Const(v) => v.clone(),
            Expr::Var(n) => self
                .vars
                .get(n)
                .cloned()
                .ok_or_else(|| format!("variable '{n}' is not initialized"))?,
            Expr::List(items) => Value::List(
                items
                    .iter()
                    .map(|x| self.eval(x, host))
                    .collect::<Result<_, _>>()?,
            ),
            Expr::Index(l, i) => {
                let l = self.eval(l, host)?;
                let i = self.eval(i, host)?;
                let Value::List(v) = &l else {
                    return Err(format!("{l} cannot be indexed"));
                };
                let k = i
                    .as_i64()
                    .ok_or_else(|| format!("index {i} is not an integer"))?;
                usize::try_from(k)
                    .ok()
                    .and_then(|k| v.get(k))
                    .cloned()
                    .ok_or_else(|| format!("index {k} out of range"))?
            }
            Expr::Not(a) => Value::Bool(!self.eval(a, host)?.truthy()?),
            Expr::Neg(a) => match self.eval(a, host)? {
                Value::Int(i) => Value::Int(-i),
                Value::Float(f) => Value::Float(-f),
                v => return Err(format!("cannot negate {v}")),
            },
            Expr::Binary(op, a, b) => {
                let a = self.eval(a, host)?;
                if *op == "and" && !a.truthy()? {
                    return Ok(Value::Bool(false));
                }
                if *op == "or" && a.truthy()? {
                    return Ok(Value::Bool(true));
                }
                let b = self.eval(b, host)?;
                binary(op, &a, &b)?
            }
            Expr::Call(name, args) => {
                let mut positional = Vec::new();
                let mut named = Vec::new();
                for (n, x) in args {
                    let v = self.eval(x, host)?;
                    match n {
                        Some(n) => named.push((n.clone(), v)),
                        None => positional.push(v),
                    }
                }
                match host.call(name, &positional, &named)? {
                    Called::Value(v) => v,
                    Called::Cycles(n) => {
                        self.wait = Wait::Cycles(n.max(1));
                        Value::Bool(true)
                    }
                    Called::Motion => {
                        self.wait = Wait::Motion;
                        Value::Bool(true)
                    }
                }
            }
        })
    }
}

fn binary(op: &str, a: &Value, b: &Value) -> Result<Value, String> {
    use Value::{Bool, Float, Int};
    let bad = || format!("cannot apply `{op}` to {a} and {b}");
    Ok(match op {
        "and" | "or" => Bool(b.truthy()?),
        "==" | "!=" => {
            let eq = match (a.as_f64(), b.as_f64()) {
                (Some(x), Some(y)) if !matches!((a, b), (Bool(_), Bool(_))) => x == y,
                _ => a == b,
            };
            Bool(eq == (op == "=="))
        }
        "<" | "<=" | ">" | ">=" => {
            let (x, y) = (a.as_f64().ok_or_else(bad)?, b.as_f64().ok_or_else(bad)?);
            Bool(match op {
                "<" => x < y,
                "<=" => x <= y,
                ">" => x > y,
                _ => x >= y,
            })
        }
        _ => match (a, b) {
            (Int(x), Int(y)) => match op {
                "+" => Int(x.wrapping_add(*y)),
                "-" => Int(x.wrapping_sub(*y)),
                "*" => Int(x.wrapping_mul(*y)),
                "/" if *y != 0 => Int(x / y),
                "%" if *y != 0 => Int(x.rem_euclid(*y)),
                _ => return Err("division by zero".into()),
            },
            _ => {
                let (x, y) = (a.as_f64().ok_or_else(bad)?, b.as_f64().ok_or_else(bad)?);
                Float(match op {
                    "+" => x + y,
                    "-" => x - y,
                    "*" => x * y,
                    "/" => x / y,
                    _ => x % y,
                })
            }
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Toy {
        log: Vec<String>,
        regs: [f64; 8],
        int0: i64,
    }

    impl Host for Toy {
        fn call(
            &mut self,
            name: &str,
            args: &[Value],
            named: &[(String, Value)],
        ) -> Result<Called, String> {
            self.log.push(format!("{name}{args:?}{named:?}"));
            Ok(match name {
                "read_input_float_register" => {
                    Called::Value(Value::Float(self.regs[args[0].as_i64().unwrap() as usize]))
                }
                "read_input_integer_register" => Called::Value(Value::Int(self.int0)),
                "get_actual_joint_positions" => Called::Value(Value::six([0.0; 6])),
                "servoj" => Called::Cycles(1),
                _ => Called::Value(Value::Bool(true)),
            })
        }
        fn motion_done(&self) -> bool {
            true
        }
    }

    fn known(n: &str) -> bool {
        [
            "read_input_float_register",
            "read_input_integer_register",
            "get_actual_joint_positions",
            "servoj",
            "rtde_set_watchdog",
            "textmsg",
        ]
        .contains(&n)
    }

    /// RL's program (`UniversalRobotsRtde::start`, 8 ms).
    const RL: &str = "def robotics_library():\n\tq = get_actual_joint_positions()\n\tqd = get_actual_joint_speeds()\n";

    #[test]
    fn rls_follower_runs_one_servoj_a_cycle_until_its_register_drops() {
        let text = "def robotics_library():\n\tq = get_actual_joint_positions()\n\trtde_set_watchdog(\"input_double_register_0\", 1, \"pause\")\n\twhile (1 == read_input_integer_register(0)):\n\t\tq[0] = read_input_float_register(0)\n\t\tq[5] = read_input_float_register(5)\n\t\tservoj(q, 0, 0, 0.008, 0.03, 2000)\n\tend\nend\n";
        let p = compile(text, &known).unwrap();
        assert_eq!(p.name, "robotics_library");
        let mut host = Toy {
            log: Vec::new(),
            regs: [0.5, 0., 0., 0., 0., -0.25, 0., 0.],
            int0: 1,
        };
        let mut rt = Runtime::new(p);
        assert_eq!(rt.cycle(&mut host), Cycle::Running);
        assert!(
            host.log
                .last()
                .unwrap()
                .starts_with("servoj[List([Float(0.5)"),
            "{:?}",
            host.log
        );
        assert_eq!(rt.cycle(&mut host), Cycle::Running);
        host.int0 = 0;
        assert_eq!(rt.cycle(&mut host), Cycle::Finished);
        let servos = host.log.iter().filter(|l| l.starts_with("servoj")).count();
        assert_eq!(servos, 2);
    }

    #[test]
    fn unknown_functions_and_bad_syntax_do_not_compile() {
        let e = compile(RL, &known).unwrap_err();
        assert_eq!(e.line, 3);
        assert!(e.message.contains("get_actual_joint_speeds"), "{e}");
        assert!(compile("def a():\n  x = (1 + \nend\n", &known).is_err());
        assert_eq!(
            compile("def a():\n  while True:\n  x = 1\nend\n", &known)
                .unwrap_err()
                .line,
            4
        );
        assert!(compile("end\n", &known).is_err());
        assert!(compile("def a():\n  thread t():\n  end\nend\n", &known).is_err());
    }

    #[test]
    fn expressions_and_control_flow() {
        let text = "def t():\n  x = 0\n  n = 0\n  while x < 10:\n    x = x + 1\n    if x % 2 == 0:\n      continue\n    elif x > 7:\n      break\n    else:\n      n = n + 1\n    end\n  end\n  textmsg(x, n, -2.5 * 2, not False, [1, 2][1], p[1, 2, 3, 0, 0, 0][2])\nend\n";
        let p = compile(text, &known).unwrap();
        let mut host = Toy {
            log: Vec::new(),
            regs: [0.0; 8],
            int0: 0,
        };
        let mut rt = Runtime::new(p);
        assert_eq!(rt.cycle(&mut host), Cycle::Finished);
        assert_eq!(
            host.log.last().unwrap(),
            "textmsg[Int(9), Int(4), Float(-5.0), Bool(true), Int(2), Int(3)][]"
        );
    }

    #[test]
    fn a_loop_without_a_motion_fails_and_errors_name_their_line() {
        let p = compile("def t():\n  while True:\n    x = 1\n  end\nend\n", &known).unwrap();
        let mut host = Toy {
            log: Vec::new(),
            regs: [0.0; 8],
            int0: 0,
        };
        assert!(matches!(
            Runtime::new(p).cycle(&mut host),
            Cycle::Failed(_, _)
        ));
        let p = compile("def t():\n  x = [1, 2]\n  y = x[5]\nend\n", &known).unwrap();
        assert_eq!(
            Runtime::new(p).cycle(&mut host),
            Cycle::Failed(3, "index 5 out of range".into())
        );
    }
}
