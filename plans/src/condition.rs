//! Guard conditions in PNP's prefix syntax.
//!
//! ```text
//! COND := ATOM | ( not COND ) | ( and COND COND* ) | ( or COND COND* )
//! ```
//! The outer parentheses may be left out at top level (`not x`, `and a b`).
//! Keywords are `and`/`or`/`not` in lower or upper case. An atom starts with
//! a letter and continues with letters, digits and `-@._#{,}<>"+^/`.
//! Unlike the reference, a one-operand `and`/`or` is accepted, and an empty
//! condition (the guard `[]`) is always true.

use std::fmt;

/// A condition tree over atoms of type `A` (`String` when parsed, resolved
/// atoms inside a [`crate::Plan`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Cond<A> {
    /// Always true (the empty guard `[]`).
    True,
    /// An atom.
    Atom(A),
    /// Negation.
    Not(Box<Cond<A>>),
    /// Conjunction of one or more operands.
    And(Vec<Cond<A>>),
    /// Disjunction of one or more operands.
    Or(Vec<Cond<A>>),
}

impl<A> Cond<A> {
    /// Rebuilds the tree with every atom transformed by `f`.
    pub fn try_map<B, E>(&self, f: &mut impl FnMut(&A) -> Result<B, E>) -> Result<Cond<B>, E> {
        Ok(match self {
            Cond::True => Cond::True,
            Cond::Atom(a) => Cond::Atom(f(a)?),
            Cond::Not(c) => Cond::Not(Box::new(c.try_map(f)?)),
            Cond::And(cs) => Cond::And(cs.iter().map(|c| c.try_map(f)).collect::<Result<_, E>>()?),
            Cond::Or(cs) => Cond::Or(cs.iter().map(|c| c.try_map(f)).collect::<Result<_, E>>()?),
        })
    }

    /// Calls `f` on every atom, left to right.
    pub fn for_each_atom(&self, f: &mut impl FnMut(&A)) {
        match self {
            Cond::True => {}
            Cond::Atom(a) => f(a),
            Cond::Not(c) => c.for_each_atom(f),
            Cond::And(cs) | Cond::Or(cs) => cs.iter().for_each(|c| c.for_each_atom(f)),
        }
    }

    /// Evaluates the tree, asking `value` for atoms (short-circuit, left to right).
    pub fn eval(&self, value: &mut impl FnMut(&A) -> bool) -> bool {
        match self {
            Cond::True => true,
            Cond::Atom(a) => value(a),
            Cond::Not(c) => !c.eval(value),
            Cond::And(cs) => cs.iter().all(|c| c.eval(value)),
            Cond::Or(cs) => cs.iter().any(|c| c.eval(value)),
        }
    }
}

impl<A: fmt::Display> fmt::Display for Cond<A> {
    /// Writes the prefix syntax, with parentheses around every compound.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let list = |f: &mut fmt::Formatter<'_>, op: &str, cs: &[Cond<A>]| {
            write!(f, "({op}")?;
            for c in cs {
                write!(f, " {c}")?;
            }
            write!(f, ")")
        };
        match self {
            Cond::True => Ok(()),
            Cond::Atom(a) => write!(f, "{a}"),
            Cond::Not(c) => write!(f, "(not {c})"),
            Cond::And(cs) => list(f, "and", cs),
            Cond::Or(cs) => list(f, "or", cs),
        }
    }
}

/// A condition parse error: 1-based character column inside the text, and
/// what was expected.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CondError {
    /// 1-based character column in the condition text.
    pub column: usize,
    /// What was found and what was expected.
    pub message: String,
}

impl fmt::Display for CondError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "column {}: {}", self.column, self.message)
    }
}

fn is_atom_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || "-@._#{,}<>\"+^/".contains(c)
}

#[derive(Debug, PartialEq)]
enum Tok {
    Open,
    Close,
    Word(String),
}

fn lex(text: &str) -> Result<Vec<(usize, Tok)>, CondError> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_whitespace() {
            i += 1;
        } else if c == '(' || c == ')' {
            out.push((i + 1, if c == '(' { Tok::Open } else { Tok::Close }));
            i += 1;
        } else if c.is_alphabetic() {
            let start = i;
            while i < chars.len() && (is_atom_char(chars[i]) || chars[i].is_alphabetic()) {
                i += 1;
            }
            out.push((start + 1, Tok::Word(chars[start..i].iter().collect())));
        } else {
            return Err(CondError {
                column: i + 1,
                message: format!(
                    "unexpected '{c}'; expected an atom (starting with a letter), '(' or ')'"
                ),
            });
        }
    }
    Ok(out)
}

fn keyword(w: &str) -> Option<&'static str> {
    match w {
        "and" | "AND" => Some("and"),
        "or" | "OR" => Some("or"),
        "not" | "NOT" => Some("not"),
        _ => None,
    }
}

struct Parser {
    toks: Vec<(usize, Tok)>,
    pos: usize,
    end_col: usize,
    /// Parentheses open around the current token: the parser recurses once per level, so the
    /// level is bounded by [`crate::MAX_DEPTH`].
    depth: usize,
}

impl Parser {
    fn col(&self) -> usize {
        self.toks.get(self.pos).map_or(self.end_col, |t| t.0)
    }

    fn err<T>(&self, message: impl Into<String>) -> Result<T, CondError> {
        Err(CondError {
            column: self.col(),
            message: message.into(),
        })
    }

    /// COND: an atom or a parenthesised compound.
    fn cond(&mut self) -> Result<Cond<String>, CondError> {
        match self.toks.get(self.pos) {
            Some((_, Tok::Word(w))) => {
                if keyword(w).is_some() {
                    return self.err(format!("'{w}' must follow '('"));
                }
                let w = w.clone();
                self.pos += 1;
                Ok(Cond::Atom(w))
            }
            Some((_, Tok::Open)) => {
                if self.depth == crate::MAX_DEPTH {
                    return self.err(format!("nesting deeper than {} levels", crate::MAX_DEPTH));
                }
                self.depth += 1;
                self.pos += 1;
                let c = self.compound()?;
                self.depth -= 1;
                match self.toks.get(self.pos) {
                    Some((_, Tok::Close)) => {
                        self.pos += 1;
                        Ok(c)
                    }
                    _ => self.err("expected ')'"),
                }
            }
            Some((_, Tok::Close)) => self.err("unexpected ')'; expected a condition"),
            None => self.err("unexpected end; expected a condition"),
        }
    }

    /// `not C` / `and C C*` / `or C C*`, without the parentheses.
    fn compound(&mut self) -> Result<Cond<String>, CondError> {
        let op = match self.toks.get(self.pos) {
            Some((_, Tok::Word(w))) => keyword(w),
            _ => None,
        };
        let Some(op) = op else {
            return self.err("expected 'and', 'or' or 'not' after '('");
        };
        self.pos += 1;
        let first = self.cond()?;
        if op == "not" {
            return Ok(Cond::Not(Box::new(first)));
        }
        let mut ops = vec![first];
        while matches!(self.toks.get(self.pos), Some((_, Tok::Word(_) | Tok::Open))) {
            ops.push(self.cond()?);
        }
        Ok(if op == "and" {
            Cond::And(ops)
        } else {
            Cond::Or(ops)
        })
    }
}

/// Parses a condition (the text inside a guard's brackets).
///
/// Empty or blank text is [`Cond::True`].
pub fn parse_condition(text: &str) -> Result<Cond<String>, CondError> {
    let toks = lex(text)?;
    let end_col = text.chars().count() + 1;
    let mut p = Parser {
        toks,
        pos: 0,
        end_col,
        depth: 0,
    };
    let cond = match p.toks.first() {
        None => return Ok(Cond::True),
        Some((_, Tok::Word(w))) if keyword(w).is_some() => p.compound()?,
        _ => p.cond()?,
    };
    if p.pos < p.toks.len() {
        return p.err("expected the end of the condition (combine several with 'and' / 'or')");
    }
    Ok(cond)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn atom(s: &str) -> Cond<String> {
        Cond::Atom(s.to_string())
    }

    #[test]
    fn forms() {
        assert_eq!(parse_condition("").unwrap(), Cond::True);
        assert_eq!(parse_condition("  ").unwrap(), Cond::True);
        assert_eq!(parse_condition("x").unwrap(), atom("x"));
        assert_eq!(
            parse_condition("not x").unwrap(),
            Cond::Not(Box::new(atom("x")))
        );
        assert_eq!(
            parse_condition("(NOT x)").unwrap(),
            Cond::Not(Box::new(atom("x")))
        );
        assert_eq!(
            parse_condition("and a b").unwrap(),
            Cond::And(vec![atom("a"), atom("b")])
        );
        assert_eq!(
            parse_condition("(or a)").unwrap(),
            Cond::Or(vec![atom("a")])
        );
        assert_eq!(
            parse_condition("(AND personhere (not closetotarget))").unwrap(),
            Cond::And(vec![
                atom("personhere"),
                Cond::Not(Box::new(atom("closetotarget")))
            ])
        );
        assert_eq!(
            parse_condition("a-b@c._#{1,2}<>\"+^/d").unwrap(),
            atom("a-b@c._#{1,2}<>\"+^/d")
        );
        assert_eq!(parse_condition("A.finished").unwrap(), atom("A.finished"));
    }

    #[test]
    fn errors() {
        assert_eq!(parse_condition("(and a b").unwrap_err().column, 9);
        assert!(parse_condition("a b")
            .unwrap_err()
            .message
            .contains("end of the condition"));
        assert_eq!(parse_condition("1x").unwrap_err().column, 1);
        assert!(parse_condition("(a b)").is_err());
        assert!(parse_condition("(not)").is_err());
        assert!(parse_condition("and").is_err());
        assert!(parse_condition("x)").is_err());
    }

    #[test]
    fn display_round_trip() {
        let c = parse_condition("and a (or b (not c))").unwrap();
        assert_eq!(c.to_string(), "(and a (or b (not c)))");
        assert_eq!(parse_condition(&c.to_string()).unwrap(), c);
    }

    #[test]
    fn eval_short_circuits() {
        let c = parse_condition("or a b").unwrap();
        let mut asked = Vec::new();
        assert!(c.eval(&mut |a: &String| {
            asked.push(a.clone());
            a == "a"
        }));
        assert_eq!(asked, ["a"]);
    }
}
