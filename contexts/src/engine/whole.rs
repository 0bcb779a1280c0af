//! Whether an expression can only give whole numbers: a context `set` of an `i64` property
//! from one that may give a fraction (`speed * 2` with an `f64` speed) fails at run time, at
//! every switch, whenever it does. `petrel check` refuses it instead, as a typed language
//! refuses an `f64` stored in an integer.

use petrel_actors::expr::{parse, Ast, AstKind, BinOp, Func};

use super::Schema;

/// What in `src` may give a fraction (`` `speed` is an f64 ``), if anything does; `None` too
/// when `src` does not parse (the expression checker reports that with its position).
pub(super) fn fraction_source(src: &str, schema: &dyn Schema) -> Option<String> {
    let ast = parse(src).ok()?;
    fraction(src, &ast, schema)
}

fn fraction(src: &str, ast: &Ast, schema: &dyn Schema) -> Option<String> {
    let written = || src.get(ast.span.start..ast.span.end).unwrap_or(src).trim();
    match &ast.kind {
        AstKind::Num(n) if n.fract() != 0.0 => {
            Some(format!("`{}` is not a whole number", written()))
        }
        AstKind::Num(_) | AstKind::Bool(_) | AstKind::Str(_) | AstKind::Not(_) => None,
        AstKind::Path(path) => match schema.property(path) {
            Some((info, _)) if info.is::<i64>() => None,
            Some((info, _)) => Some(format!(
                "`{path}` is a{} {}",
                article(info.name()),
                info.name()
            )),
            // An unknown property is reported by the expression checker.
            None => None,
        },
        AstKind::Field(..) => match field_is_whole(ast, schema) {
            Some(true) => None,
            _ => Some(format!("`{}` may hold a fraction", written())),
        },
        AstKind::Neg(a) => fraction(src, a, schema),
        AstKind::Bin(BinOp::Div, ..) => Some(format!("`{}` divides", written())),
        AstKind::Bin(BinOp::Add | BinOp::Sub | BinOp::Mul, a, b) => {
            fraction(src, a, schema).or_else(|| fraction(src, b, schema))
        }
        // Comparisons and logic give booleans, which the type checker refuses here.
        AstKind::Bin(..) => None,
        AstKind::Call(Func::Abs | Func::Min | Func::Max | Func::Clamp, args) => {
            args.iter().find_map(|a| fraction(src, a, schema))
        }
        AstKind::Call(Func::Age | Func::Elapsed, _) => {
            Some(format!("`{}` counts seconds, with fractions", written()))
        }
        AstKind::Call(Func::Len | Func::Held, _) => None,
    }
}

/// Whether `base.name` (possibly nested) holds a whole number in the property's current
/// value; `None` when that cannot be told.
fn field_is_whole(ast: &Ast, schema: &dyn Schema) -> Option<bool> {
    let mut names = Vec::new();
    let mut at = ast;
    while let AstKind::Field(base, name) = &at.kind {
        names.push(name.as_str());
        at = base;
    }
    let AstKind::Path(path) = &at.kind else {
        return None;
    };
    let (info, sample) = schema.property(path)?;
    let mut value = info.to_dynamic(&sample).ok()?;
    for name in names.iter().rev() {
        let ron::Value::Map(map) = value else {
            return None;
        };
        value = map.get(&ron::Value::String(name.to_string()))?.clone();
    }
    match value {
        ron::Value::Number(n) => Some(!matches!(n, ron::Number::F32(_) | ron::Number::F64(_))),
        _ => None,
    }
}

fn article(name: &str) -> &'static str {
    match name.starts_with(['a', 'e', 'i', 'o', 'u', 'f']) {
        true => "n",
        false => "",
    }
}
