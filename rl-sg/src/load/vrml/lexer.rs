//! VRML97's lexical grammar (ISO/IEC 14772-1, annex A.2): identifiers, numbers, strings,
//! brackets; commas are white space, `#` starts a comment.

use rl_core::loader::Clipped;

use crate::error::SgError;

/// A token and where it starts.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Token<'a> {
    /// An identifier or keyword (`Transform`, `DEF`, `TRUE`, a field name).
    Ident(&'a str),
    /// A number (VRML's integers and floats, hexadecimal integers too).
    Number(f64),
    /// A quoted string, escapes resolved.
    String(String),
    /// `{`, `}`, `[`, `]` or `.` (in `ROUTE a.b TO c.d`).
    Punct(char),
}

/// A token with its position: byte offset, line and column (from 1).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Spanned<'a> {
    pub token: Token<'a>,
    pub offset: usize,
    pub line: u32,
    pub column: u32,
}

/// Splits `text` into tokens, or says where it cannot.
pub(crate) struct Lexer<'a> {
    text: &'a str,
    pos: usize,
    line: u32,
    line_start: usize,
    /// The last position whose column was counted, and that column: the next one is counted
    /// from there, so columns cost one pass over each line however many tokens it holds.
    column_at: (usize, u32),
    /// Bytes walked to count columns (for the test that this stays linear).
    column_work: usize,
}

fn is_id_first(c: char) -> bool {
    !(c.is_ascii_digit() || is_id_excluded(c) || c == '+' || c == '-')
}

fn is_id_rest(c: char) -> bool {
    !is_id_excluded(c)
}

/// Characters that never occur in identifiers (annex A.2: control characters, space, `"`, `#`,
/// `'`, `,`, `.`, `[`, `\`, `]`, `{`, `}`, DEL).
fn is_id_excluded(c: char) -> bool {
    (c as u32) <= 0x20
        || matches!(
            c,
            '"' | '#' | '\'' | ',' | '.' | '[' | '\\' | ']' | '{' | '}' | '\u{7f}'
        )
}

impl<'a> Lexer<'a> {
    pub(crate) fn new(text: &'a str) -> Self {
        Self {
            text,
            pos: 0,
            line: 1,
            line_start: 0,
            column_at: (0, 1),
            column_work: 0,
        }
    }

    /// Bytes walked so far to count columns: at most the text's length.
    #[cfg(test)]
    pub(crate) fn column_work(&self) -> usize {
        self.column_work
    }

    fn error(&mut self, at: usize, message: impl Into<String>) -> SgError {
        let (line, column) = self.position(at);
        SgError::syntax(message).at_position(line, column)
    }

    /// Line and column (from 1) of byte `at` (on the current line, at or after the last
    /// position asked for), counting characters from the last position counted.
    fn position(&mut self, at: usize) -> (u32, u32) {
        let at = at.max(self.line_start);
        let (mut from, mut col) = self.column_at;
        if from < self.line_start || from > at {
            (from, col) = (self.line_start, 1);
        }
        let walked = &self.text[from..at];
        self.column_work += walked.len();
        col = col.saturating_add(walked.chars().count() as u32);
        self.column_at = (at, col);
        (self.line, col)
    }

    fn skip_space(&mut self) {
        let bytes = self.text.as_bytes();
        while self.pos < bytes.len() {
            match bytes[self.pos] {
                b'\n' => {
                    self.pos += 1;
                    self.line += 1;
                    self.line_start = self.pos;
                }
                b' ' | b'\t' | b'\r' | b',' => self.pos += 1,
                b'#' => {
                    while self.pos < bytes.len() && bytes[self.pos] != b'\n' {
                        self.pos += 1;
                    }
                }
                _ => break,
            }
        }
    }

    /// The next token, `None` at the end.
    pub(crate) fn next_token(&mut self) -> Result<Option<Spanned<'a>>, SgError> {
        self.skip_space();
        let start = self.pos;
        let Some(c) = self.text[start..].chars().next() else {
            return Ok(None);
        };
        let (line, column) = self.position(start);
        let token = match c {
            '{' | '}' | '[' | ']' => {
                self.pos += 1;
                Token::Punct(c)
            }
            '"' => Token::String(self.string(start)?),
            '.' if !self.text[start + 1..].starts_with(|d: char| d.is_ascii_digit()) => {
                self.pos += 1;
                Token::Punct('.')
            }
            c if c.is_ascii_digit() || matches!(c, '+' | '-' | '.') => {
                Token::Number(self.number(start)?)
            }
            c if is_id_first(c) => {
                let end = self.text[start..]
                    .char_indices()
                    .find(|&(_, ch)| !is_id_rest(ch))
                    .map_or(self.text.len(), |(i, _)| start + i);
                self.pos = end;
                Token::Ident(&self.text[start..end])
            }
            other => return Err(self.error(start, format!("unexpected character {other:?}"))),
        };
        Ok(Some(Spanned {
            token,
            offset: start,
            line,
            column,
        }))
    }

    fn number(&mut self, start: usize) -> Result<f64, SgError> {
        let rest = &self.text[start..];
        let end = rest
            .char_indices()
            .find(|&(_, ch)| !(ch.is_ascii_alphanumeric() || matches!(ch, '+' | '-' | '.')))
            .map_or(rest.len(), |(i, _)| i);
        let word = &rest[..end];
        self.pos = start + end;
        let (sign, digits) = match word.strip_prefix('-') {
            Some(d) => (-1.0, d),
            None => (1.0, word.strip_prefix('+').unwrap_or(word)),
        };
        let value = if let Some(hex) = digits
            .strip_prefix("0x")
            .or_else(|| digits.strip_prefix("0X"))
        {
            u64::from_str_radix(hex, 16).ok().map(|v| v as f64)
        } else if digits.starts_with(|c: char| c.is_ascii_digit() || c == '.')
            && !digits.contains(|c: char| c.is_ascii_alphabetic() && c != 'e' && c != 'E')
        {
            digits.parse::<f64>().ok()
        } else {
            None
        };
        match value {
            Some(v) if v.is_finite() => Ok(sign * v),
            _ => Err(self.error(
                start,
                format!("\"{}\" is not a number", Clipped(word, Clipped::NAME)),
            )),
        }
    }

    fn string(&mut self, start: usize) -> Result<String, SgError> {
        let mut out = String::new();
        let mut chars = self.text[start + 1..].char_indices();
        loop {
            match chars.next() {
                None => return Err(self.error(start, "unterminated string")),
                Some((i, '"')) => {
                    self.pos = start + 1 + i + 1;
                    return Ok(out);
                }
                Some((_, '\\')) => match chars.next() {
                    Some((_, c)) => out.push(c),
                    None => return Err(self.error(start, "unterminated string")),
                },
                Some((_, '\n')) => {
                    out.push('\n');
                    self.line += 1;
                    self.line_start = start + 1 + chars.offset();
                }
                Some((_, c)) => out.push(c),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tokens(text: &str) -> Vec<Token<'_>> {
        let mut l = Lexer::new(text);
        let mut out = Vec::new();
        while let Some(t) = l.next_token().unwrap() {
            out.push(t.token);
        }
        out
    }

    #[test]
    fn identifiers_numbers_and_strings() {
        assert_eq!(
            tokens(
                "DEF unimation-puma560 Transform { translation 0,-1.5e-3 .5 } # c\n url \"a\\\"b\""
            ),
            vec![
                Token::Ident("DEF"),
                Token::Ident("unimation-puma560"),
                Token::Ident("Transform"),
                Token::Punct('{'),
                Token::Ident("translation"),
                Token::Number(0.0),
                Token::Number(-1.5e-3),
                Token::Number(0.5),
                Token::Punct('}'),
                Token::Ident("url"),
                Token::String("a\"b".into()),
            ]
        );
        assert_eq!(
            tokens("0x1F a.b"),
            vec![
                Token::Number(31.0),
                Token::Ident("a"),
                Token::Punct('.'),
                Token::Ident("b")
            ]
        );
    }

    #[test]
    fn errors_name_line_and_column() {
        let mut l = Lexer::new("Shape {\n  x 1.2.3\n}");
        let e = loop {
            match l.next_token() {
                Ok(Some(_)) => continue,
                Ok(None) => panic!("no error"),
                Err(e) => break e,
            }
        };
        assert_eq!(e.position, Some((2, 5)), "{e}");
        assert!(Lexer::new("\"open").next_token().is_err());
    }

    #[test]
    fn columns_cost_one_pass_over_a_long_line() {
        // 40 000 points on one line, as CAD exports write an IndexedFaceSet: counting every
        // token's column from the line's start walked 4·10⁹ bytes (15.2 s); counting from the
        // previous token walks the line once.
        let line: String = (0..40_000).map(|i| format!("{i}.5 ")).collect();
        for text in [line.clone(), format!("{line}\n{line}")] {
            let mut l = Lexer::new(&text);
            let mut last = None;
            while let Some(t) = l.next_token().unwrap() {
                last = Some(t);
            }
            assert!(
                l.column_work() <= text.len(),
                "{} bytes walked for columns in a text of {}",
                l.column_work(),
                text.len()
            );
            let last = last.unwrap();
            let lines = text.lines().count() as u32;
            let at = text.rfind("39999.5").unwrap();
            let col = text[..at].rsplit('\n').next().unwrap().chars().count() as u32 + 1;
            assert_eq!((last.line, last.column), (lines, col));
        }
        // Columns count characters, not bytes, and restart on every line (strings too).
        let mut l = Lexer::new("\"é\nx\" ä b\n  c");
        let cols: Vec<(u32, u32)> = std::iter::from_fn(|| l.next_token().unwrap())
            .map(|t| (t.line, t.column))
            .collect();
        assert_eq!(cols, vec![(1, 1), (2, 4), (2, 6), (3, 3)]);
    }
}
