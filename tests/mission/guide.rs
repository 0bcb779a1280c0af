//! docs/missions.md cannot rot: every code block of the guide is checked. Blocks naming a
//! shipped file (`file=...`) must be that file, word for word; plans compile and check with no
//! error and no deadlock; rules compile; configs pass `petrel check`; binding fragments,
//! expressions and simulation scripts parse; `petrel plan check` lines run and succeed. And
//! every plan shipped in the repository checks without a deadlock.

use std::path::Path;
use std::process::Command;

use petrel::plans::mission::ActionBindings;
use petrel::plans::{check, compile_text, load_plan, CheckReport, Script};

/// A fenced block: its language, its attributes (`file=...`), its text.
struct Block {
    lang: String,
    attrs: Vec<(String, String)>,
    text: String,
    line: usize,
}

impl Block {
    fn attr(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
}

fn blocks(md: &str) -> Vec<Block> {
    let mut out = Vec::new();
    let mut open: Option<Block> = None;
    for (i, line) in md.lines().enumerate() {
        match (&mut open, line.strip_prefix("```")) {
            (None, Some(info)) => {
                let mut words = info.split_whitespace();
                let lang = words.next().unwrap_or("").to_string();
                let attrs = words
                    .filter_map(|w| w.split_once('='))
                    .map(|(k, v)| (k.to_string(), v.to_string()))
                    .collect();
                open = Some(Block {
                    lang,
                    attrs,
                    text: String::new(),
                    line: i + 1,
                });
            }
            (Some(_), Some("")) => out.push(open.take().unwrap()),
            (Some(b), _) => {
                b.text.push_str(line);
                b.text.push('\n');
            }
            (None, None) => {}
        }
    }
    assert!(open.is_none(), "an unclosed code block");
    out
}

fn no_deadlock(what: &str, r: &CheckReport) {
    assert!(r.is_ok(), "{what}:\n{r}");
    assert!(
        !r.warnings.iter().any(|w| w.code == "deadlock"),
        "{what}:\n{r}"
    );
}

fn petrel(args: &[&str]) -> std::process::Output {
    crate::bounded::output_within_deadline(Command::new(env!("CARGO_BIN_EXE_petrel")).args(args))
}

#[test]
fn every_block_of_the_guide_is_checked() {
    let md = std::fs::read_to_string("docs/missions.md").unwrap();
    let blocks = blocks(&md);
    assert!(blocks.len() >= 15, "found {} blocks", blocks.len());
    let mut checked = 0;
    for b in &blocks {
        let at = format!("docs/missions.md:{} ({})", b.line, b.lang);
        if let Some(file) = b.attr("file") {
            let shipped =
                std::fs::read_to_string(file).unwrap_or_else(|e| panic!("{at}: {file}: {e}"));
            assert_eq!(
                b.text, shipped,
                "{at}: the guide must show {file} as shipped"
            );
        }
        match b.lang.as_str() {
            "plan" => {
                let report = match b.attr("file") {
                    Some(file) => {
                        let rules = Path::new(file).with_extension("er");
                        let rules = rules.is_file().then_some(rules.as_path());
                        check(
                            &load_plan(Path::new(file), rules)
                                .unwrap_or_else(|e| panic!("{at}: {e}"))
                                .plan,
                        )
                    }
                    None => check(
                        &compile_text(&b.text, &at, "guide", None)
                            .unwrap_or_else(|e| panic!("{at}: {e}")),
                    ),
                };
                no_deadlock(&at, &report);
            }
            // A shipped rules file goes with the plan beside it: rules naming actions the plan
            // lacks are refused.
            "rules" => match b.attr("file") {
                Some(file) => {
                    let plan = Path::new(file).with_extension("plan");
                    load_plan(&plan, Some(Path::new(file))).unwrap_or_else(|e| panic!("{at}: {e}"));
                }
                None => {
                    let plan = "goto_A; say_x";
                    compile_text(plan, "p.plan", "p", Some((&b.text, &at)))
                        .unwrap_or_else(|e| panic!("{e}"));
                }
            },
            "ron" => match (b.attr("file"), b.attr("fragment")) {
                (Some(file), _) if b.text.trim_start().contains("Agent(") => {
                    let out = petrel(&["check", file]);
                    assert!(
                        out.status.success(),
                        "{at}: {}",
                        String::from_utf8_lossy(&out.stderr)
                    );
                }
                (Some(_), _) => {} // context rules: checked with their config
                (None, Some("binding")) => {
                    let text = format!("{{\"x\": {}}}", b.text);
                    let v: ron::Value =
                        ron::from_str(&text).unwrap_or_else(|e| panic!("{at}: {e}"));
                    v.into_rust::<ActionBindings>()
                        .unwrap_or_else(|e| panic!("{at}: {e}"));
                }
                (None, Some("actions")) => {
                    let text = format!("{{{}}}", b.text);
                    let v: ron::Value =
                        ron::from_str(&text).unwrap_or_else(|e| panic!("{at}: {e}"));
                    v.into_rust::<ActionBindings>()
                        .unwrap_or_else(|e| panic!("{at}: {e}"));
                }
                other => {
                    panic!("{at}: a ron block must name a file or a fragment kind, found {other:?}")
                }
            },
            "expr" => {
                petrel::actors::expr::parse(b.text.trim()).unwrap_or_else(|e| panic!("{at}: {e}"));
            }
            "script" => {
                Script::parse(&b.text, &at).unwrap_or_else(|e| panic!("{e}"));
            }
            "sh" => {
                for line in b.text.lines() {
                    let Some(args) = line.strip_prefix("petrel plan check configs/") else {
                        continue;
                    };
                    let args: Vec<String> = format!("plan check configs/{args}")
                        .split_whitespace()
                        .map(String::from)
                        .collect();
                    let args: Vec<&str> = args.iter().map(String::as_str).collect();
                    let out = petrel(&args);
                    assert!(
                        out.status.success(),
                        "{at}: {line}: {}",
                        String::from_utf8_lossy(&out.stdout)
                    );
                }
            }
            "text" => {} // output shown to the reader
            other => panic!("{at}: unknown block language `{other}`"),
        }
        checked += 1;
    }
    assert_eq!(checked, blocks.len());
}

#[test]
fn every_shipped_plan_checks_without_a_deadlock() {
    let mut plans = Vec::new();
    for dir in ["configs/plans", "configs/examples", "plans/tests/fixtures"] {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "plan") {
                plans.push(path);
            }
        }
    }
    assert!(plans.len() >= 3, "{plans:?}");
    for plan in plans {
        let rules = plan.with_extension("er");
        let rules = rules.is_file().then_some(rules.as_path());
        let loaded = load_plan(&plan, rules).unwrap_or_else(|e| panic!("{e}"));
        no_deadlock(&plan.display().to_string(), &check(&loaded.plan));
    }
}
