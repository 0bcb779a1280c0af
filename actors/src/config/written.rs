//! Which fields a config text writes, so that an overlay replaces exactly those.

/// The fields a config text writes: agent-level names, and `module/field` for each module
/// (read as a dynamic RON value; the text already parsed as a config, so this cannot fail in
/// practice, and an unreadable text simply writes nothing).
pub(super) fn written_fields(text: &str) -> std::collections::BTreeSet<String> {
    let mut out = std::collections::BTreeSet::new();
    let Ok(ron::Value::Map(agent)) = ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str::<ron::Value>(text)
    else {
        return out;
    };
    for (k, v) in agent.iter() {
        let ron::Value::String(k) = k else { continue };
        out.insert(k.clone());
        if k != "modules" {
            continue;
        }
        let ron::Value::Seq(modules) = v else {
            continue;
        };
        for m in modules {
            let ron::Value::Map(m) = m else { continue };
            let name = m.iter().find_map(|(k, v)| match (k, v) {
                (ron::Value::String(k), ron::Value::String(n)) if k == "name" => Some(n.clone()),
                _ => None,
            });
            let Some(name) = name else { continue };
            for k in m.keys() {
                if let ron::Value::String(k) = k {
                    out.insert(format!("{name}/{k}"));
                }
            }
        }
    }
    out
}
