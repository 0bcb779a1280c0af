//! Loads, checks and simulates every reference plan of `../shared/pnp/`
//! (beside the workspace; `PETREL_PNP_REFERENCE` overrides the directory).
//! The files are read in place, never copied. Skipped when absent.

use std::path::PathBuf;

use petrel_plans::{check, load_plan, parse_pnml, simulate, to_dot, write_pnml, Script};

fn reference_dir() -> Option<PathBuf> {
    let dir = match std::env::var_os("PETREL_PNP_REFERENCE") {
        Some(d) => PathBuf::from(d),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/pnp"),
    };
    dir.is_dir().then_some(dir)
}

#[test]
fn every_reference_plan_loads_checks_and_simulates() {
    let Some(dir) = reference_dir() else {
        eprintln!("no reference plans; skipped");
        return;
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .chain(std::fs::read_dir(dir.join("text")).into_iter().flatten())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "pnml" || e == "plan"))
        .collect();
    files.sort();
    assert!(!files.is_empty());
    let script = Script::parse("", "empty").unwrap();
    for f in &files {
        let rules = f.with_extension("er");
        let rules = rules.is_file().then_some(rules);
        let l = load_plan(f, rules.as_deref()).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        let report = check(&l.plan);
        let _ = to_dot(&l.plan);
        let again = parse_pnml(&write_pnml(&l.plan), "again", "again").unwrap();
        assert_eq!(again.transitions().len(), l.plan.transitions().len());
        let mut out = Vec::new();
        let _status = simulate(&l.plan, &script, 100, &mut out).unwrap();
        let lines = String::from_utf8(out).unwrap();
        assert!(lines.lines().count() >= 2);
        eprintln!(
            "{}: {} -> {} errors, {} warnings; {}",
            f.file_name().unwrap().to_string_lossy(),
            l.plan.name(),
            report.errors.len(),
            report.warnings.len(),
            lines.lines().last().unwrap()
        );
    }
}
