//! The pbrt-v4 tokenizer: quoted strings (with pbrt's escapes), brackets, comments and bare
//! words (directive names, numbers, `true`/`false`). Every token carries its line and column
//! (columns count characters, not bytes). One pass over the bytes: the column is kept up to
//! date as the cursor moves, so a file of one enormous line costs no more than many short ones.

use std::path::PathBuf;
use std::sync::Arc;

use crate::{LoadError, Loc, Result};

#[derive(Clone, Debug, PartialEq)]
pub enum Kind {
    /// A bare word: its text is `src[start..end]` of the lexer that made it.
    Word,
    /// A quoted string, unescaped.
    Str(String),
    Open,
    Close,
}

#[derive(Clone, Debug)]
pub struct Token {
    pub kind: Kind,
    pub start: usize,
    pub end: usize,
    pub line: u32,
    pub col: u32,
}

pub struct Lexer {
    pub file: Arc<PathBuf>,
    src: Arc<str>,
    pos: usize,
    line: u32,
    col: u32,
    peeked: Option<Token>,
}

impl Lexer {
    pub fn new(file: Arc<PathBuf>, src: Arc<str>) -> Lexer {
        Lexer {
            file,
            src,
            pos: 0,
            line: 1,
            col: 1,
            peeked: None,
        }
    }

    /// The text of a `Word` token.
    pub fn text(&self, t: &Token) -> &str {
        &self.src[t.start..t.end]
    }

    pub fn loc(&self, t: &Token) -> Loc {
        Loc::new(&self.file, t.line, t.col)
    }

    /// Where the next token would start (the end of the file when there is none).
    pub fn here(&self) -> Loc {
        match &self.peeked {
            Some(t) => self.loc(t),
            None => Loc::new(&self.file, self.line, self.col),
        }
    }

    pub fn peek(&mut self) -> Result<Option<&Token>> {
        if self.peeked.is_none() {
            self.peeked = self.scan()?;
        }
        Ok(self.peeked.as_ref())
    }

    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> Result<Option<Token>> {
        if let Some(t) = self.peeked.take() {
            return Ok(Some(t));
        }
        self.scan()
    }

    /// Move over one byte, keeping line and column (continuation bytes of a UTF-8 sequence do
    /// not start a new column).
    fn bump(&mut self, b: u8) {
        self.pos += 1;
        if b == b'\n' {
            self.line += 1;
            self.col = 1;
        } else if b & 0xC0 != 0x80 {
            self.col += 1;
        }
    }

    fn scan(&mut self) -> Result<Option<Token>> {
        let src = self.src.clone();
        let bytes = src.as_bytes();
        loop {
            let Some(&b) = bytes.get(self.pos) else {
                return Ok(None);
            };
            if b.is_ascii_whitespace() {
                self.bump(b);
            } else if b == b'#' {
                while let Some(&c) = bytes.get(self.pos) {
                    if c == b'\n' {
                        break;
                    }
                    self.bump(c);
                }
            } else {
                break;
            }
        }
        let (line, col, start) = (self.line, self.col, self.pos);
        let b = bytes[self.pos];
        let tok = |kind, end| Token {
            kind,
            start,
            end,
            line,
            col,
        };
        match b {
            b'[' => {
                self.bump(b);
                Ok(Some(tok(Kind::Open, self.pos)))
            }
            b']' => {
                self.bump(b);
                Ok(Some(tok(Kind::Close, self.pos)))
            }
            b'"' => {
                self.bump(b);
                let mut s = String::new();
                let mut run = self.pos;
                loop {
                    let Some(&c) = bytes.get(self.pos) else {
                        return Err(LoadError::new(
                            Loc::new(&self.file, line, col),
                            "unterminated string (the file ends inside it)",
                        ));
                    };
                    match c {
                        b'"' => {
                            s.push_str(&src[run..self.pos]);
                            self.bump(c);
                            return Ok(Some(tok(Kind::Str(s), self.pos)));
                        }
                        b'\n' => {
                            return Err(LoadError::new(
                                Loc::new(&self.file, line, col),
                                "unterminated string (a newline before the closing quote)",
                            ));
                        }
                        b'\\' => {
                            s.push_str(&src[run..self.pos]);
                            let (el, ec) = (self.line, self.col);
                            self.bump(c);
                            let Some(&e) = bytes.get(self.pos) else {
                                return Err(LoadError::new(
                                    Loc::new(&self.file, line, col),
                                    "unterminated string (the file ends inside it)",
                                ));
                            };
                            let out = match e {
                                b'b' => '\u{8}',
                                b'f' => '\u{c}',
                                b'n' => '\n',
                                b'r' => '\r',
                                b't' => '\t',
                                b'\\' => '\\',
                                b'\'' => '\'',
                                b'"' => '"',
                                _ => {
                                    let ch = src[self.pos..].chars().next().unwrap_or('?');
                                    return Err(LoadError::new(
                                        Loc::new(&self.file, el, ec),
                                        format!("unknown escape sequence '\\{ch}' in a string"),
                                    ));
                                }
                            };
                            s.push(out);
                            self.bump(e);
                            run = self.pos;
                        }
                        _ => self.bump(c),
                    }
                }
            }
            _ => {
                while let Some(&c) = bytes.get(self.pos) {
                    if c.is_ascii_whitespace() || matches!(c, b'[' | b']' | b'"' | b'#') {
                        break;
                    }
                    self.bump(c);
                }
                Ok(Some(tok(Kind::Word, self.pos)))
            }
        }
    }
}

/// The text of a file as UTF-8, or an error at the line and column of the first bad byte.
pub fn utf8(bytes: Vec<u8>, file: &Arc<PathBuf>) -> Result<String> {
    String::from_utf8(bytes).map_err(|e| {
        let bytes = e.as_bytes();
        let at = e.utf8_error().valid_up_to();
        let (line, col) = line_col(&bytes[..at]);
        LoadError::new(
            Loc::new(file, line, col),
            "the file is not valid UTF-8 text (pbrt files are text)",
        )
    })
}

/// 1-based line and column just after `prefix` (which is valid UTF-8).
fn line_col(prefix: &[u8]) -> (u32, u32) {
    let mut line = 1u32;
    let mut col = 1u32;
    for &b in prefix {
        if b == b'\n' {
            line = line.saturating_add(1);
            col = 1;
        } else if b & 0xC0 != 0x80 {
            col = col.saturating_add(1);
        }
    }
    (line, col)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lex(s: &str) -> Result<Vec<(Kind, String, u32, u32)>> {
        let mut l = Lexer::new(Arc::new(PathBuf::from("t.pbrt")), Arc::from(s));
        let mut out = Vec::new();
        while let Some(t) = l.next()? {
            out.push((t.kind.clone(), l.text(&t).to_string(), t.line, t.col));
        }
        Ok(out)
    }

    #[test]
    fn tokens_with_positions() {
        let t = lex("Shape \"sphere\" # comment\n  \"float radius\" [ 2.5 ]").unwrap();
        assert_eq!(t[0].0, Kind::Word);
        assert_eq!(t[0].1, "Shape");
        assert_eq!(t[1].0, Kind::Str("sphere".into()));
        assert_eq!((t[1].2, t[1].3), (1, 7));
        assert_eq!(t[2].0, Kind::Str("float radius".into()));
        assert_eq!((t[2].2, t[2].3), (2, 3));
        assert_eq!(t[3].0, Kind::Open);
        assert_eq!(t[4].1, "2.5");
        assert_eq!((t[4].2, t[4].3), (2, 20));
        assert_eq!(t[5].0, Kind::Close);
    }

    #[test]
    fn escapes_and_unicode_columns() {
        let t = lex("\"é\\\"x\\n\" w").unwrap();
        assert_eq!(t[0].0, Kind::Str("é\"x\n".into()));
        // The word after a string holding one two-byte character and escapes.
        assert_eq!((t[1].2, t[1].3), (1, 10));
    }

    #[test]
    fn unterminated_strings_point_at_their_start() {
        let e = lex("Shape\n  \"sphere").unwrap_err();
        assert_eq!((e.loc.line, e.loc.col), (2, 3));
        assert!(e.message.contains("unterminated"), "{e}");
        let e = lex("\"a\nb\"").unwrap_err();
        assert_eq!((e.loc.line, e.loc.col), (1, 1));
        let e = lex("\"a\\q\"").unwrap_err();
        assert!(e.message.contains("escape"), "{e}");
    }

    #[test]
    fn invalid_utf8_is_located() {
        let e = utf8(b"ab\ncd\xff".to_vec(), &Arc::new(PathBuf::from("x"))).unwrap_err();
        assert_eq!((e.loc.line, e.loc.col), (2, 3));
    }
}
