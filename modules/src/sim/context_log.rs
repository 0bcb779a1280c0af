//! Which contexts were active when: switch counts and time per context, for a run's summary
//! and the colours of its trajectory.

/// Switch counts and active time per context, fed with the active list as it changes.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContextLog {
    /// `(name, activations, seconds active, active since)` in order of first activation.
    entries: Vec<(String, u32, f64, Option<f64>)>,
}

impl ContextLog {
    /// Records the active contexts at time `t` (seconds): `active` is a comma-separated list,
    /// as `context.manager` publishes in `out/active`.
    pub fn update(&mut self, t: f64, active: &str) {
        let now: Vec<&str> = active
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .collect();
        for entry in &mut self.entries {
            if let Some(since) = entry.3 {
                if !now.contains(&entry.0.as_str()) {
                    entry.2 += (t - since).max(0.0);
                    entry.3 = None;
                }
            }
        }
        for name in now {
            match self.entries.iter_mut().find(|e| e.0 == name) {
                Some(e) if e.3.is_some() => {}
                Some(e) => {
                    e.1 += 1;
                    e.3 = Some(t);
                }
                None => self.entries.push((name.to_string(), 1, 0.0, Some(t))),
            }
        }
    }

    /// `(name, activations, seconds active)` up to time `t`, in order of first activation.
    pub fn totals(&self, t: f64) -> Vec<(String, u32, f64)> {
        self.entries
            .iter()
            .map(|(n, k, secs, since)| {
                (
                    n.clone(),
                    *k,
                    secs + since.map_or(0.0, |s| (t - s).max(0.0)),
                )
            })
            .collect()
    }

    /// Index (order of first activation) of a context name, if it was ever active.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.entries.iter().position(|e| e.0 == name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_activations_and_time_per_context() {
        let mut log = ContextLog::default();
        log.update(0.0, "");
        log.update(1.0, "dark");
        log.update(2.0, "dark, rough");
        log.update(4.0, "rough");
        log.update(5.0, "");
        log.update(6.0, "dark");
        let totals = log.totals(7.0);
        assert_eq!(
            totals,
            vec![("dark".into(), 2, 4.0), ("rough".into(), 1, 3.0)]
        );
        assert_eq!((log.index("rough"), log.index("lost")), (Some(1), None));
    }
}
