//! Freezing a running agent: the whole blackboard written as a RON agent config.
//!
//! A snapshot lists every module with its type, the value of every settable property (inputs
//! and parameters that are not linked, outputs, state, `enabled`), its links and queue
//! capacities, and the settings the config gave beyond properties (supervision, groups,
//! recording; each module's group, restart policy, watchdog and stop timeout). It is a complete
//! config (`petrel run snapshot.ron` resumes the agent) and a valid
//! overlay over the original config (`petrel run base.ron --overlay snapshot.ron`).

use std::fmt::Write;

use crate::blackboard::Registry;
use crate::ports::PropertyKind;

/// Writes `registry` as RON config text.
pub(crate) fn write(registry: &Registry) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "// Snapshot of agent `{}`, written by petrel.",
        registry.agent()
    );
    let _ = writeln!(
        out,
        "// Run it with `petrel run FILE`, or lay it over a config with `--overlay FILE`."
    );
    let _ = writeln!(out, "Agent(\n    name: {:?},", registry.agent());
    if let Some(team) = registry.team() {
        let _ = writeln!(out, "    team: {},", team.to_ron());
    }
    for field in registry.agent_settings() {
        let _ = writeln!(out, "    {field},");
    }
    // The wall clock now: a run from this snapshot goes on from it (`AgentConfig::clock_s`).
    let clock = crate::expr::Clock::Wall.secs(tokio::time::Instant::now());
    let _ = writeln!(out, "    clock_s: {clock:?},");
    let _ = writeln!(out, "    modules: [");
    for module in registry.modules() {
        let prefix = format!("{module}/");
        let mut values = Vec::new();
        let mut links = Vec::new();
        let mut capacities = Vec::new();
        for (key, entry) in registry.entries().filter(|(k, _)| k.starts_with(&prefix)) {
            let path = &key[prefix.len()..];
            if let Some(capacity) = Registry::input_capacity(entry) {
                capacities.push(format!("{path:?}: {capacity}"));
            }
            if let Some(remote) = &entry.remote {
                links.push(format!("{path:?}: {}", remote.to_ron()));
                continue;
            }
            if let Some(target) = registry.link_of(key) {
                links.push(format!("{path:?}: {target:?}"));
                continue;
            }
            match entry.decl.kind {
                PropertyKind::Stats | PropertyKind::Control | PropertyKind::QueueIn => {}
                PropertyKind::QueueOut => {
                    if let crate::ports::Handle::QueueOut(core) = &entry.handle {
                        capacities.push(format!("{path:?}: {}", core.capacity()));
                    }
                }
                _ => {
                    let Some(cell) = Registry::own_cell(entry) else {
                        continue;
                    };
                    match cell.type_info.to_ron(&cell.value()) {
                        Ok(text) => values.push(format!("{path:?}: {text}")),
                        Err(e) => values.push(format!("// not serializable: {path:?} ({e})")),
                    }
                }
            }
        }
        let _ = writeln!(
            out,
            "        (\n            name: {module:?},\n            type: {:?},",
            registry.module_type(module).unwrap_or_default()
        );
        for field in registry.module_settings(module) {
            let _ = writeln!(out, "            {field},");
        }
        for (field, items) in [
            ("values", values),
            ("links", links),
            ("capacities", capacities),
        ] {
            if items.is_empty() {
                continue;
            }
            let _ = writeln!(out, "            {field}: {{");
            for item in items {
                let sep = if item.starts_with("//") { "" } else { "," };
                let _ = writeln!(out, "                {item}{sep}");
            }
            let _ = writeln!(out, "            }},");
        }
        let _ = writeln!(out, "        ),");
    }
    out.push_str("    ],\n)\n");
    out
}
