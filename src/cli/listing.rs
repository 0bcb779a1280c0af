//! What `petrel ls` prints: tables a person reads, computed from records and `@info` answers.

use std::fmt::Write;

use petrel_team::discovery::Record;
use petrel_team::AgentInfo;

/// The agents of the recorded runs: name, team, process, where to reach it.
pub(crate) fn agents(records: &[Record]) -> String {
    let rows: Vec<[String; 4]> = records
        .iter()
        .flat_map(|r| {
            r.agents.iter().map(move |a| {
                [
                    a.agent.clone(),
                    a.team.clone(),
                    r.pid.to_string(),
                    a.connect.join(" "),
                ]
            })
        })
        .collect();
    if rows.is_empty() {
        return "no `petrel run` is running on this machine for this user\n".into();
    }
    table(["AGENT", "TEAM", "PID", "REACH"], &rows)
}

/// One agent: each module with its type, then its properties with kind, type and link.
pub(crate) fn agent(info: &AgentInfo) -> String {
    let mut out = format!("agent {} (team {})\n", info.agent, info.team);
    for module in &info.modules {
        let type_name = info.types.get(module).map(String::as_str).unwrap_or("?");
        let _ = writeln!(out, "\n{module} ({type_name})");
        let prefix = format!("{module}/");
        let rows: Vec<[String; 4]> = info
            .properties
            .iter()
            .filter_map(|p| Some((p.key.strip_prefix(&prefix)?, p)))
            .map(|(path, p)| {
                let link = p
                    .link
                    .as_ref()
                    .map(|l| format!("<- {l}"))
                    .unwrap_or_default();
                [
                    format!("  {path}"),
                    p.kind.clone(),
                    p.type_name.clone(),
                    link,
                ]
            })
            .collect();
        out.push_str(&table(["", "", "", ""], &rows));
    }
    out
}

/// Columns padded to their widest cell; a header row unless every heading is empty; no
/// trailing spaces.
pub(crate) fn table<const N: usize>(headings: [&str; N], rows: &[[String; N]]) -> String {
    let mut widths = headings.map(str::len);
    for row in rows {
        for (w, cell) in widths.iter_mut().zip(row) {
            *w = (*w).max(cell.chars().count());
        }
    }
    let mut out = String::new();
    let mut line = |cells: Vec<&str>| {
        let mut text = String::new();
        // Padded by hand: a format width is limited to 65,535 and panics beyond.
        for (cell, w) in cells.iter().zip(widths) {
            text.push_str(cell);
            text.extend(std::iter::repeat_n(
                ' ',
                w.saturating_sub(cell.chars().count()) + 2,
            ));
        }
        out.push_str(text.trim_end());
        out.push('\n');
    };
    if headings.iter().any(|h| !h.is_empty()) {
        line(headings.to_vec());
    }
    for row in rows {
        line(row.iter().map(String::as_str).collect());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use petrel_actors::PropertyListing;
    use petrel_team::discovery::Reachable;

    #[test]
    fn agents_are_one_row_each() {
        let records = [Record {
            pid: 42,
            started: None,
            agents: vec![Reachable {
                agent: "robot".into(),
                team: "local.42.robot".into(),
                connect: vec!["tcp/127.0.0.1:40000".into()],
            }],
        }];
        assert_eq!(
            agents(&records),
            "AGENT  TEAM            PID  REACH\n\
             robot  local.42.robot  42   tcp/127.0.0.1:40000\n"
        );
        assert!(agents(&[]).starts_with("no `petrel run`"));
    }

    #[test]
    fn an_agent_lists_its_modules_and_their_properties() {
        let property = |key: &str, kind: &str, link: Option<&str>| PropertyListing {
            key: key.into(),
            kind: kind.into(),
            type_name: "f64".into(),
            link: link.map(Into::into),
        };
        let info = AgentInfo {
            agent: "filter".into(),
            zid: "z".into(),
            team: "demo".into(),
            pid: None,
            host: None,
            modules: vec!["scale".into()],
            types: [("scale".to_string(), "demo.scale".to_string())].into(),
            properties: vec![
                property(
                    "scale/in/value",
                    "input",
                    Some("petrel://sensor/signal/out/value"),
                ),
                property("scale/params/factor", "param", None),
            ],
        };
        assert_eq!(
            agent(&info),
            "agent filter (team demo)\n\nscale (demo.scale)\n  \
             in/value       input  f64  <- petrel://sensor/signal/out/value\n  \
             params/factor  param  f64\n"
        );
    }
}
