//! Nesting limits: every reader refuses input nested deeper than `MAX_DEPTH` with a positioned
//! error instead of overflowing the stack. Each deep input runs on a thread with a small stack
//! (1 MiB: room for `MAX_DEPTH` levels in a debug build, a hundredth of what the deep inputs
//! would need without the limit), so a reader that recursed once per level would crash the
//! test rather than pass.
mod common;

use common::*;
use petrel_plans::{compile_text, parse_condition, parse_pnml, PlanError, MAX_DEPTH};

/// Runs `f` on a thread with a 1 MiB stack and returns its result.
fn small_stack<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    std::thread::Builder::new()
        .stack_size(1024 * 1024)
        .spawn(f)
        .expect("the test thread starts")
        .join()
        .expect("the reader does not panic")
}

fn compile(src: String) -> Result<(), String> {
    small_stack(move || {
        compile_text(&src, "deep.plan", "deep", None)
            .map(|_| ())
            .map_err(|e| e.to_string())
    })
}

#[test]
fn text_plan_blocks() {
    let nest = |n: usize| format!("a;\nb;\n  {}c{}", "{".repeat(n), "}".repeat(n));
    assert_eq!(compile(nest(MAX_DEPTH)), Ok(()));
    let e = compile(nest(50_000)).unwrap_err();
    // The 257th '{' is column 2 + 257 of line 3.
    assert_eq!(e, "deep.plan:3:259: nesting deeper than 256 levels");
    let e = compile(nest(MAX_DEPTH + 1)).unwrap_err();
    assert_eq!(e, "deep.plan:3:259: nesting deeper than 256 levels");
}

#[test]
fn text_plan_parallel_branches_and_conditionals() {
    let par = |n: usize| format!("{}a{}", "{ b } || {".repeat(n), "}".repeat(n));
    assert_eq!(compile(par(MAX_DEPTH)), Ok(()));
    let e = compile(par(50_000)).unwrap_err();
    let col = "{ b } || {".len() * MAX_DEPTH + 1;
    assert_eq!(
        e,
        format!("deep.plan:1:{col}: nesting deeper than 256 levels")
    );

    let choice = |n: usize| format!("{}a{}", "<x ? ".repeat(n), " >".repeat(n));
    assert_eq!(compile(choice(MAX_DEPTH)), Ok(()));
    let e = compile(choice(50_000)).unwrap_err();
    let col = "<x ? ".len() * MAX_DEPTH + 1;
    assert_eq!(
        e,
        format!("deep.plan:1:{col}: nesting deeper than 256 levels")
    );
}

fn not_chain(n: usize) -> String {
    format!("{}x{}", "(not ".repeat(n), ")".repeat(n))
}

#[test]
fn conditions() {
    let e = small_stack(|| parse_condition(&not_chain(100_000))).unwrap_err();
    assert_eq!(e.column, "(not ".len() * MAX_DEPTH + 1);
    assert_eq!(e.message, "nesting deeper than 256 levels");
    assert!(small_stack(|| parse_condition(&not_chain(MAX_DEPTH))).is_ok());

    // In a conditional of a text plan, an inline rule and a rules file.
    let e = compile(format!("a;\n<{} ? b>", not_chain(100_000))).unwrap_err();
    let col = 2 + "(not ".len() * MAX_DEPTH;
    assert_eq!(
        e,
        format!("deep.plan:2:{col}: bad condition: nesting deeper than 256 levels")
    );
    let e = compile(format!(
        "a ! *if* {} *do* skip_action !",
        not_chain(100_000)
    ))
    .unwrap_err();
    let col = "a ! *if* ".len() + "(not ".len() * MAX_DEPTH + 1;
    assert_eq!(
        e,
        format!("deep.plan:1:{col}: bad condition: nesting deeper than 256 levels")
    );
    let rules = format!("*if* {} *during* a *do* skip_action\n", not_chain(100_000));
    let e = small_stack(move || {
        compile_text("a", "p.plan", "p", Some((&rules, "deep.er"))).map(|_| ())
    })
    .unwrap_err()
    .to_string();
    let col = "*if* ".len() + "(not ".len() * MAX_DEPTH + 1;
    assert_eq!(
        e,
        format!("deep.er:1:{col}: bad condition: nesting deeper than 256 levels")
    );
}

#[test]
fn pnml_elements() {
    let deep = |n: usize, tag: &str, inner: &str| {
        format!(
            "<pnml><net id=\"n\">{}{inner}{}</net></pnml>",
            format!("<{tag}>").repeat(n),
            format!("</{tag}>").repeat(n)
        )
    };
    let parse = |text: String| {
        small_stack(move || parse_pnml(&text, "deep.pnml", "deep").map(|p| p.places().len()))
    };
    // pnml and net are levels 1 and 2, so the 255th nested element is level 257.
    let e = parse(deep(100_000, "x", "")).unwrap_err();
    let col = "<pnml><net id=\"n\">".len() + "<x>".len() * 254 + 1;
    assert!(
        matches!(e, PlanError::TooDeep { line: 1, column, limit: 256, .. } if column as usize == col),
        "{e:?}"
    );
    assert_eq!(
        e.to_string(),
        format!("deep.pnml:1:{col}: nesting deeper than 256 levels")
    );
    // Pages are read recursively by the plan reader itself; at the limit they still load.
    assert!(matches!(
        parse(deep(100_000, "page", "")),
        Err(PlanError::TooDeep { .. })
    ));
    // The place's name/value are levels 256 and 257.
    let place = "<place id=\"p\"><name><value>goal</value></name></place>";
    assert_eq!(parse(deep(MAX_DEPTH - 5, "page", place)).unwrap(), 1);
    assert!(matches!(
        parse(deep(MAX_DEPTH - 4, "page", place)),
        Err(PlanError::TooDeep { .. })
    ));
}

#[test]
fn pnml_guards() {
    let text = pnml(
        &[("P", 1), ("goal", 0)],
        &[&format!("[{}]", not_chain(100_000))],
        &[("n0", "t0", 1), ("t0", "n1", 1)],
    );
    let e = small_stack(move || parse_pnml(&text, "g.pnml", "g").map(|_| ())).unwrap_err();
    let col = "(not ".len() * MAX_DEPTH + 1;
    assert!(
        matches!(&e, PlanError::Guard { id, message, .. }
            if id == "t0" && *message == format!("column {col}: nesting deeper than 256 levels")),
        "{e:?}"
    );
}

/// Writes `c0.pnml` .. `c{levels - 1}.pnml` into `dir`, each plan's one action the next file
/// (the last one's an action `leaf`): sub-plans nested `levels` deep.
fn sub_plan_chain(dir: &std::path::Path, levels: usize) -> std::path::PathBuf {
    for i in 0..levels {
        let action = match i + 1 == levels {
            true => "leaf".to_string(),
            false => format!("c{}", i + 1),
        };
        let plan = compile_text(&action, "c.plan", &format!("c{i}"), None).unwrap();
        let pnml = petrel_plans::write_pnml(&plan);
        std::fs::write(dir.join(format!("c{i}.pnml")), pnml).unwrap();
    }
    dir.join("c0.pnml")
}

#[test]
fn sub_plan_chains() {
    let dir = tempfile::tempdir().unwrap();
    // As deep as allowed: loads, checks and runs to its goal on the small stack.
    let top = sub_plan_chain(dir.path(), MAX_DEPTH);
    let status = small_stack(move || {
        let loaded = petrel_plans::load_plan(&top, None).map_err(|e| e.to_string())?;
        let report = petrel_plans::check(&loaded.plan);
        assert!(report.is_ok(), "{report}");
        let script = petrel_plans::Script::parse("", "s").unwrap();
        let mut out = Vec::new();
        let steps = 4 * MAX_DEPTH as u64 + 10;
        petrel_plans::simulate(&loaded.plan, &script, steps, &mut out).map_err(|e| e.to_string())
    });
    assert_eq!(status, Ok(petrel_plans::PlanStatus::Goal));
    // One level more is refused, naming the chain.
    let dir = tempfile::tempdir().unwrap();
    let top = sub_plan_chain(dir.path(), MAX_DEPTH + 2);
    let e = small_stack(move || {
        petrel_plans::load_plan(&top, None)
            .map(|_| ())
            .map_err(|e| e.to_string())
    });
    let e = e.unwrap_err();
    assert!(
        e.contains(&format!(
            "sub-plans nest deeper than {MAX_DEPTH} levels (c0 -> c1 -> c2 -> ... ->"
        )),
        "{e}"
    );
}
