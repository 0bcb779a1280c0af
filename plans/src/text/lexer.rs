//! A pull lexer for text plans. The parser can also take raw text up to a
//! delimiter (conditions, inline rules), which keeps condition atoms free to
//! contain characters that are punctuation in plans.

/// A token.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Tok {
    /// An action name, number, label or keyword.
    Word(String),
    /// One of `; | || < > ? : { } !`.
    Punct(&'static str),
    /// End of input.
    End,
}

pub(crate) struct Lexer<'a> {
    pub src: &'a str,
    pub pos: usize,
}

pub(crate) fn is_word_char(c: char) -> bool {
    c.is_alphanumeric() || "_-.#@/+^*".contains(c)
}

impl<'a> Lexer<'a> {
    pub fn new(src: &'a str) -> Self {
        Lexer { src, pos: 0 }
    }

    fn skip_blank(&mut self) {
        loop {
            let rest = &self.src[self.pos..];
            let trimmed = rest.trim_start();
            self.pos += rest.len() - trimmed.len();
            // Only a '#' needs the look back to the line start (which would make lexing a
            // long one-line plan quadratic if done for every token).
            let at_line_start = || {
                self.src[..self.pos]
                    .rsplit('\n')
                    .next()
                    .unwrap_or("")
                    .trim()
                    .is_empty()
            };
            if trimmed.starts_with('#') && at_line_start() {
                self.pos += trimmed.find('\n').unwrap_or(trimmed.len());
            } else {
                return;
            }
        }
    }

    /// The next token and its byte offset; `Err(offset)` on a character that
    /// starts no token.
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> Result<(usize, Tok), usize> {
        self.skip_blank();
        let start = self.pos;
        let rest = &self.src[start..];
        let Some(c) = rest.chars().next() else {
            return Ok((start, Tok::End));
        };
        if rest.starts_with("||") {
            self.pos += 2;
            return Ok((start, Tok::Punct("||")));
        }
        for p in [";", "|", "<", ">", "?", ":", "{", "}", "!"] {
            if rest.starts_with(p) {
                self.pos += 1;
                return Ok((start, Tok::Punct(p)));
            }
        }
        if is_word_char(c) {
            let len = rest.find(|c| !is_word_char(c)).unwrap_or(rest.len());
            self.pos += len;
            return Ok((start, Tok::Word(rest[..len].to_string())));
        }
        Err(start)
    }

    /// Raw text up to (not including) the first `delim` (which conditions
    /// never contain); consumes the delimiter. Returns the text and its byte
    /// offset, or `None` at end of input.
    pub fn raw_until(&mut self, delim: char) -> Option<(usize, &'a str)> {
        let start = self.pos;
        let i = self.src[start..].find(delim)?;
        self.pos = start + i + delim.len_utf8();
        Some((start, &self.src[start..start + i]))
    }
}
