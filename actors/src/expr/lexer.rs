//! Tokens of the expression language, each with the byte span it came from.

use super::{ExprError, Span};

/// One token.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Tok {
    /// A number; durations (`500ms`, `2s`, `1.5s`) are numbers of seconds.
    Num(f64),
    /// A string literal, escapes resolved.
    Str(String),
    /// A property address: `module/path` or `petrel://agent/module/path`.
    Path(String),
    /// A bare word: keyword or function name.
    Word(String),
    /// Punctuation or an operator: `+ - * / ( ) , . < <= > >= == != && || !`.
    Op(&'static str),
}

const OPS: [&str; 17] = [
    "<=", ">=", "==", "!=", "&&", "||", "+", "-", "*", "/", "(", ")", ",", ".", "<", ">", "!",
];

fn is_word(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// Splits `src` into tokens.
pub(crate) fn lex(src: &str) -> Result<Vec<(Tok, Span)>, ExprError> {
    let b = src.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i] as char;
        if c.is_ascii_whitespace() {
            i += 1;
            continue;
        }
        let start = i;
        if c.is_ascii_digit() {
            while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
                i += 1;
            }
            // An exponent (`1e3`, `2.5e-3`): `e` then digits, with an optional sign.
            if i < b.len() && matches!(b[i], b'e' | b'E') {
                let sign = usize::from(matches!(b.get(i + 1), Some(b'+' | b'-')));
                if b.get(i + 1 + sign).is_some_and(u8::is_ascii_digit) {
                    i += 1 + sign;
                    while i < b.len() && b[i].is_ascii_digit() {
                        i += 1;
                    }
                }
            }
            let n: f64 = src[start..i]
                .parse()
                .ok()
                .filter(|n: &f64| n.is_finite())
                .ok_or_else(|| {
                    ExprError::at(src, start, format!("bad number `{}`", &src[start..i]))
                })?;
            let unit_start = i;
            while i < b.len() && is_word(b[i] as char) {
                i += 1;
            }
            let n = match &src[unit_start..i] {
                "" => n,
                "s" => n,
                "ms" => n / 1000.0,
                u => {
                    return Err(ExprError::at(
                        src,
                        unit_start,
                        format!("unknown unit `{u}`; expected `s` or `ms` after a number"),
                    ))
                }
            };
            out.push((Tok::Num(n), Span::new(start, i)));
        } else if c == '"' {
            let (s, end) = string(src, i)?;
            i = end;
            out.push((Tok::Str(s), Span::new(start, i)));
        } else if is_word(c) {
            if src[i..].starts_with(crate::url::SCHEME) {
                i += crate::url::SCHEME.len();
            }
            i = path_end(b, i);
            let text = &src[start..i];
            let tok = if text.contains('/') {
                Tok::Path(text.to_string())
            } else {
                Tok::Word(text.to_string())
            };
            out.push((tok, Span::new(start, i)));
        } else if let Some(op) = OPS.iter().find(|op| src[i..].starts_with(**op)) {
            i += op.len();
            out.push((Tok::Op(op), Span::new(start, i)));
        } else {
            let ch = src[i..].chars().next().unwrap_or(c);
            return Err(ExprError::at(
                src,
                i,
                format!("unexpected character `{ch}`"),
            ));
        }
    }
    Ok(out)
}

/// The end of a word or path starting at `i`: words joined by `/` with no space (so `a/b` is a
/// path and `a / b` a division). Segments may hold `-`, as property names may.
fn path_end(b: &[u8], mut i: usize) -> usize {
    loop {
        while i < b.len() && (is_word(b[i] as char) || b[i] == b'-') {
            i += 1;
        }
        if i + 1 < b.len() && b[i] == b'/' && is_word(b[i + 1] as char) {
            i += 1;
        } else {
            return i;
        }
    }
}

/// Reads the string literal opening at `start`; returns it and the offset after its quote.
fn string(src: &str, start: usize) -> Result<(String, usize), ExprError> {
    let mut s = String::new();
    let mut chars = src[start + 1..].char_indices();
    while let Some((k, c)) = chars.next() {
        match c {
            '"' => return Ok((s, start + 1 + k + 1)),
            '\\' => match chars.next() {
                Some((_, 'n')) => s.push('\n'),
                Some((_, 't')) => s.push('\t'),
                Some((_, c @ ('"' | '\\'))) => s.push(c),
                _ => {
                    return Err(ExprError::at(
                        src,
                        start + 1 + k,
                        "bad escape; expected \\\", \\\\, \\n or \\t",
                    ))
                }
            },
            c => s.push(c),
        }
    }
    Err(ExprError::at(src, start, "unterminated string"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toks(src: &str) -> Vec<Tok> {
        lex(src).unwrap().into_iter().map(|(t, _)| t).collect()
    }

    #[test]
    fn paths_words_numbers_durations_and_operators() {
        assert_eq!(
            toks("hw/out/odometry.x >= 1.5 && !ok"),
            vec![
                Tok::Path("hw/out/odometry".into()),
                Tok::Op("."),
                Tok::Word("x".into()),
                Tok::Op(">="),
                Tok::Num(1.5),
                Tok::Op("&&"),
                Tok::Op("!"),
                Tok::Word("ok".into()),
            ]
        );
        assert_eq!(
            toks("500ms 2s 1.5s"),
            vec![Tok::Num(0.5), Tok::Num(2.0), Tok::Num(1.5)]
        );
        assert_eq!(
            toks("petrel://r1/a/out/x-y / b/v"),
            vec![
                Tok::Path("petrel://r1/a/out/x-y".into()),
                Tok::Op("/"),
                Tok::Path("b/v".into())
            ]
        );
        assert_eq!(toks(r#""a\"b""#), vec![Tok::Str("a\"b".into())]);
    }

    #[test]
    fn errors_have_positions() {
        let e = lex("a/b > 2h").unwrap_err();
        assert_eq!((e.line, e.column), (1, 8));
        assert!(e.message.contains("unknown unit `h`"), "{e}");
        // Exponents are numbers, not units.
        assert_eq!(
            toks("1e3 2.5e-3ms 4E+1"),
            vec![Tok::Num(1000.0), Tok::Num(2.5e-6), Tok::Num(40.0)]
        );
        assert!(lex("1e").unwrap_err().message.contains("unknown unit `e`"));
        assert!(lex("1e999")
            .unwrap_err()
            .message
            .contains("bad number `1e999`"));
        let e = lex("x\n  # 1").unwrap_err();
        assert_eq!((e.line, e.column), (2, 3));
        let e = lex("\"open").unwrap_err();
        assert!(e.message.contains("unterminated"), "{e}");
    }
}
