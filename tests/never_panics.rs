//! Bad input never panics: random texts assembled from each language's own tokens go through
//! every parser a user's files reach (expressions, plan conditions, text plans and execution
//! rules, PNML, agent configs, context rules). Each must answer with a value or an error.
//! Deterministic (a fixed seed), so a failure names an input that can be replayed.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

/// xorshift64: enough to shuffle tokens, no dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    /// Up to `max` tokens of `atoms`, concatenated.
    fn text(&mut self, atoms: &[&str], max: u64) -> String {
        let len = self.next() % max;
        (0..len)
            .map(|_| atoms[(self.next() % atoms.len() as u64) as usize])
            .collect()
    }
}

const EXPR: &[&str] = &[
    "a/out/v",
    " ",
    "(",
    ")",
    ">",
    "<=",
    "==",
    "!=",
    " and ",
    " or ",
    "not ",
    "!",
    "1",
    "2.5",
    "-",
    "+",
    "*",
    "/",
    "held(",
    ",",
    "2s",
    "age(",
    "abs(",
    "clamp(",
    "min(",
    "ü",
    "\"",
    "x\"",
    ".",
    "true",
    "500ms",
    "petrel://r/a/out/v",
    "&&",
    "||",
    "\n",
    "1e400",
    "99999999999999999999",
];
const PLAN: &[&str] = &[
    "a",
    "b_1",
    ";",
    "|",
    "||",
    "{",
    "}",
    "<",
    ">",
    "?",
    ":",
    "*",
    "(",
    ")",
    "#",
    "\n",
    " ",
    "ü",
    "30",
    "GOTO ",
    "L:",
    "=",
    "-",
    "not ",
    "and ",
    "*if* ",
    "*do* ",
    "*during* ",
    "fail_plan",
    "restart_action",
    "skip_action",
    "restart_plan",
    ".",
    ",",
    "\"",
];
const RON: &[&str] = &[
    "Agent(",
    "name:",
    "\"r\"",
    ",",
    "modules:",
    "[",
    "]",
    "(",
    ")",
    "type:",
    "\"demo.counter\"",
    "values:",
    "{",
    "}",
    "\"params/period_ms\"",
    ":",
    "10",
    "links:",
    "\"in/value\"",
    "\"a/out/value\"",
    "team:",
    "listen:",
    "\"tcp/127.0.0.1:7447\"",
    "remote_write:",
    "\"*/params/**\"",
    "lease_ms:",
    "from:",
    "\"petrel://b/m/out/x\"",
    "mode:",
    "on_change",
    "periodic",
    "min_interval_ms:",
    "ms:",
    "reliability:",
    "best_effort",
    "lossy:",
    "ü",
    "\n",
    "//",
    "/*",
    "contexts:",
    "Contexts(",
    "when:",
    "\"x > \"",
    "set:",
    "1.5",
    "-",
    "true",
    "until:",
    "min_dwell_ms:",
    "priority:",
    "relink:",
    "sticky:",
];
const PNML: &[&str] = &[
    "<pnml>",
    "</pnml>",
    "<net id=\"n\">",
    "</net>",
    "<place id=\"p\">",
    "</place>",
    "<transition id=\"t\">",
    "</transition>",
    "<arc id=\"a\" source=\"p\" target=\"t\">",
    "</arc>",
    "<name><value>",
    "</value></name>",
    "a.exec",
    "<initialMarking><value>",
    "Default,1",
    "1",
    "</value></initialMarking>",
    "<inscription><value>",
    "ü",
    "&amp;",
    "&",
    "<",
    ">",
    "\"",
    " ",
];

/// Runs `parse` on `input`; a panic fails the test naming the parser and the input.
fn no_panic(what: &str, input: &str, parse: impl FnOnce()) {
    if catch_unwind(AssertUnwindSafe(parse)).is_err() {
        panic!("{what} panicked on {input:?}");
    }
}

#[test]
fn random_inputs_get_answers_not_panics() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    for _ in 0..20_000 {
        let src = rng.text(EXPR, 20);
        no_panic("expression parser", &src, || {
            if let Ok(ast) = petrel::actors::expr::parse(&src) {
                let _ = petrel::actors::expr::never_true(&src, &ast);
            }
        });
        no_panic("plan condition parser", &src, || {
            let _ = petrel::plans::parse_condition(&src);
        });
        let plan = rng.text(PLAN, 24);
        no_panic("text plan compiler", &plan, || {
            let _ = petrel::plans::compile_text(&plan, "f.plan", "f", None);
        });
        no_panic("execution rules", &plan, || {
            let _ = petrel::plans::compile_text("a; b", "f.plan", "f", Some((&plan, "r.er")));
        });
        let ron = rng.text(RON, 30);
        no_panic("config parser", &ron, || {
            let _ = petrel::actors::ConfigFile::parse("f.ron", &ron);
        });
        no_panic("context rules parser", &ron, || {
            let _ = petrel::contexts::LoadedRules::parse(Path::new("r.ron"), &ron);
        });
        let pnml = rng.text(PNML, 30);
        no_panic("PNML reader", &pnml, || {
            let _ = petrel::plans::parse_pnml(&pnml, "f.pnml", "f");
        });
    }
}
