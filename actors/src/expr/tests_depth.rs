//! The nesting limit: deep expressions are refused with a positioned error, never a stack
//! overflow. Each parse runs on a thread with a 2 MiB stack (a tokio worker's: room for
//! `MAX_DEPTH` levels in a debug build, a hundredth of what 100,000 levels would need without
//! the limit), so a parser that recursed once per level would crash the test rather than pass.

use super::*;

/// Parses `src` on a thread with a 2 MiB stack; `Ok` is the tree's height, counted with an
/// explicit stack (a recursive walk of a too-deep tree would itself overflow).
fn parse_small(src: String) -> Result<usize, ExprError> {
    std::thread::Builder::new()
        .stack_size(2048 * 1024)
        .spawn(move || parse(&src).map(|ast| height(&ast)))
        .expect("the test thread starts")
        .join()
        .expect("the parser does not panic")
}

fn height(ast: &Ast) -> usize {
    let mut stack = vec![(ast, 1)];
    let mut max = 0;
    while let Some((a, h)) = stack.pop() {
        max = max.max(h);
        match &a.kind {
            AstKind::Field(x, _) | AstKind::Neg(x) | AstKind::Not(x) => stack.push((x, h + 1)),
            AstKind::Bin(_, x, y) => stack.extend([(&**x, h + 1), (&**y, h + 1)]),
            AstKind::Call(_, args) => stack.extend(args.iter().map(|x| (x, h + 1))),
            _ => {}
        }
    }
    max
}

fn too_deep(line: u32, column: usize) -> ExprError {
    ExprError {
        line,
        column: column as u32,
        message: "nesting deeper than 256 levels".into(),
    }
}

#[test]
fn parentheses() {
    let nest = |n: usize| format!("{}1{}", "(".repeat(n), ")".repeat(n));
    assert_eq!(parse_small(nest(MAX_DEPTH)), Ok(1));
    assert_eq!(parse_small(nest(100_000)), Err(too_deep(1, MAX_DEPTH + 1)));
    assert_eq!(
        parse_small(format!("1 +\n  {}", nest(MAX_DEPTH + 1))),
        Err(too_deep(2, 3 + MAX_DEPTH - 1)),
        "the '+' is one level, so the 256th '(' is the first too many"
    );
}

#[test]
fn prefix_operators_and_calls() {
    let nots = |n: usize| format!("{}true", "not ".repeat(n));
    assert_eq!(parse_small(nots(MAX_DEPTH)), Ok(MAX_DEPTH + 1));
    assert_eq!(
        parse_small(nots(100_000)),
        Err(too_deep(1, 4 * MAX_DEPTH + 1))
    );
    let negs = |n: usize| format!("{}1", "-".repeat(n));
    assert_eq!(parse_small(negs(MAX_DEPTH)), Ok(MAX_DEPTH + 1));
    assert_eq!(parse_small(negs(100_000)), Err(too_deep(1, MAX_DEPTH + 1)));
    let abs = |n: usize| format!("{}1{}", "abs(".repeat(n), ")".repeat(n));
    assert_eq!(parse_small(abs(MAX_DEPTH)), Ok(MAX_DEPTH + 1));
    assert_eq!(
        parse_small(abs(100_000)),
        Err(too_deep(1, 4 * MAX_DEPTH + 1))
    );
}

#[test]
fn long_chains_build_deep_trees_and_count_too() {
    // `1+1+...` is parsed in a loop, but its tree is as deep as the chain is long, and the
    // checker, the evaluator and dropping the tree recurse over it.
    let sum = |n: usize| format!("1{}", "+1".repeat(n));
    assert_eq!(parse_small(sum(MAX_DEPTH)), Ok(MAX_DEPTH + 1));
    let chain = ExprError {
        message: "nesting deeper than 256 levels (each operator of a chain counts one level)"
            .into(),
        ..too_deep(1, 2 * MAX_DEPTH + 2)
    };
    assert_eq!(parse_small(sum(100_000)), Err(chain));
    let fields = |n: usize| format!("a/b{}", ".x".repeat(n));
    assert_eq!(parse_small(fields(MAX_DEPTH)), Ok(MAX_DEPTH + 1));
    assert_eq!(
        parse_small(fields(100_000)),
        Err(too_deep(1, 4 + 2 * MAX_DEPTH))
    );
}

#[test]
fn an_expression_at_the_limit_checks_and_evaluates() {
    let src = format!("{}a/out/x{} > 1", "(".repeat(200), " + 1)".repeat(200));
    let result = std::thread::Builder::new()
        .stack_size(2048 * 1024)
        .spawn(move || {
            let mut env = TypeEnv::new();
            env.insert("a/out/x", Ty::Num);
            let mut set = ExprSet::new();
            let id = set.add(&src, &env, Some(&Ty::Bool))?;
            set.evaluate(tokio::time::Instant::now());
            Ok::<_, ExprError>(set.value(id).is_some())
        })
        .expect("the test thread starts")
        .join()
        .expect("checking does not overflow");
    assert_eq!(result, Ok(true));
}
