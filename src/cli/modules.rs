//! `petrel modules` and `petrel modules describe TYPE`.

use std::process::ExitCode;

use petrel_actors::ModuleRegistry;

use super::stdout::sayln;

pub(crate) fn list(registry: &ModuleRegistry) -> ExitCode {
    let width = registry.types().map(|t| t.name().len()).max().unwrap_or(0);
    for t in registry.types() {
        sayln!("{:<width$}  {}", t.name(), t.description());
    }
    sayln!("\n`petrel modules describe TYPE` lists a type's properties.");
    ExitCode::SUCCESS
}

pub(crate) fn describe(registry: &ModuleRegistry, type_name: &str) -> ExitCode {
    let Some(t) = registry.get(type_name) else {
        let near = registry.nearest(type_name);
        let hint = if near.is_empty() {
            String::new()
        } else {
            format!("; did you mean {}?", near.join(", "))
        };
        // Control characters are shown by their code: printed raw, `sim.world\x01` looked
        // like the type it was told it is not.
        let shown: String = type_name
            .chars()
            .map(|c| match c.is_control() {
                true => format!("U+{:04X}", u32::from(c)),
                false => c.to_string(),
            })
            .collect();
        eprintln!("error: unknown module type `{shown}`{hint} (`petrel modules` lists them)");
        return ExitCode::from(super::EXIT_BAD_INPUT);
    };
    sayln!("{}: {}\n", t.name(), t.description());
    // The module's own properties first, then those the runtime adds to every module.
    let (own, runtime): (Vec<_>, Vec<_>) = t
        .properties()
        .into_iter()
        .partition(|p| !p.kind.is_builtin());
    let rows: Vec<[String; 6]> = own
        .iter()
        .chain(&runtime)
        .map(|p| {
            [
                p.path.clone(),
                p.kind.to_string(),
                p.type_info.name().to_string(),
                p.accepts().unwrap_or_default(),
                p.default_text(),
                match p.is_read_at_start() {
                    true => format!("{} (read at start: not settable while running)", p.doc),
                    false => p.doc.clone(),
                },
            ]
        })
        .collect();
    let header = ["property", "kind", "type", "range", "default", "doc"].map(String::from);
    let widths: Vec<usize> = (0..5)
        .map(|i| {
            rows.iter()
                .chain([&header])
                .map(|r| r[i].chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    for row in std::iter::once(&header).chain(&rows) {
        let padded: Vec<String> = row[..5]
            .iter()
            .zip(&widths)
            .map(|(cell, w)| format!("{cell:<w$}"))
            .collect();
        sayln!("  {}  {}", padded.join("  "), row[5]);
    }
    ExitCode::SUCCESS
}
