//! What the console shows, as the JSON shapes of its API, built from an agent's listing and
//! property values by pure functions.

use std::collections::VecDeque;

use petrel_actors::types::Path2;
use petrel_actors::{AgentListing, AnyValue, Image, LaserScan, OccupancyGrid};
use serde::Serialize;
use serde_json::Value;

/// One module with its status and step figures (from its `stats/` properties).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ModuleView {
    /// The module's name.
    pub name: String,
    /// Its type.
    #[serde(rename = "type")]
    pub type_name: String,
    /// `running`, `failed`, ... (`stats/status`).
    pub status: String,
    /// Steps so far.
    pub steps: i64,
    /// Steps per second (from the mean interval; 0 when unknown).
    pub steps_per_s: f64,
    /// Mean step time, microseconds.
    pub mean_step_us: f64,
    /// Last (sampled) step time, microseconds.
    pub last_step_us: f64,
    /// Restarts so far.
    pub restarts: i64,
    /// Failures so far.
    pub failures: i64,
    /// Queue items its inputs lost by lagging (summed).
    pub dropped: i64,
}

/// The modules of `listing` (runtime ones, named `_...`, left out) with the figures found in
/// `stats`: `(key, value)` pairs of `module/stats/...` properties.
pub fn modules(listing: &AgentListing, stats: &[(String, Value)]) -> Vec<ModuleView> {
    listing
        .modules
        .iter()
        .filter(|m| !m.name.starts_with('_'))
        .map(|m| {
            let mut view = ModuleView {
                name: m.name.clone(),
                type_name: m.type_name.clone(),
                ..ModuleView::default()
            };
            let prefix = format!("{}/stats/", m.name);
            for (key, value) in stats {
                let Some(stat) = key.strip_prefix(&prefix) else {
                    continue;
                };
                let int = value.as_i64().unwrap_or(0);
                let float = value.as_f64().unwrap_or(0.0);
                match stat {
                    "status" => view.status = value.as_str().unwrap_or_default().to_string(),
                    "steps" => view.steps = int,
                    "mean_interval_ms" if float > 0.0 => view.steps_per_s = 1000.0 / float,
                    "mean_step_us" => view.mean_step_us = float,
                    "last_step_us" => view.last_step_us = float,
                    "restarts" => view.restarts = int,
                    "failures" => view.failures = int,
                    s if s.starts_with("dropped/") => view.dropped += int,
                    _ => {}
                }
            }
            view
        })
        .collect()
}

/// Whether a listed property is a module's statistic (what [`modules`] reads).
pub fn is_stat(key: &str) -> bool {
    key.split('/').nth(1) == Some("stats")
}

/// One property in the browser.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PropertyView {
    /// `module/path`.
    pub key: String,
    /// `param`, `output`, `queue output`, ...
    pub kind: String,
    /// Its value (or item) type.
    #[serde(rename = "type")]
    pub type_name: String,
    /// What it links to, if linked.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub link: Option<String>,
    /// Whether the console may set it (params and controls).
    pub writable: bool,
}

/// The property browser's rows, in key order.
pub fn properties(listing: &AgentListing) -> Vec<PropertyView> {
    listing
        .properties
        .iter()
        .map(|p| PropertyView {
            key: p.key.clone(),
            kind: p.kind.clone(),
            type_name: p.type_name.clone(),
            link: p.link.clone(),
            writable: crate::core::access::writable_named(&p.kind),
        })
        .collect()
}

/// The link graph: modules as nodes, links as edges between modules.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GraphView {
    /// Module names (runtime ones included: `_supervisor`, `_team`).
    pub modules: Vec<String>,
    /// Links, from the input's module to the target's module.
    pub links: Vec<LinkView>,
}

/// One link.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinkView {
    /// The linked input, `module/path`.
    pub from: String,
    /// Its target, `module/path` (or a `petrel://` URL of another agent).
    pub to: String,
    /// Whether it carries a queue.
    pub queue: bool,
}

/// The link graph of `listing`.
pub fn graph(listing: &AgentListing) -> GraphView {
    GraphView {
        modules: listing.modules.iter().map(|m| m.name.clone()).collect(),
        links: listing
            .properties
            .iter()
            .filter_map(|p| {
                p.link.as_ref().map(|to| LinkView {
                    from: p.key.clone(),
                    to: to.clone(),
                    queue: p.kind.starts_with("queue"),
                })
            })
            .collect(),
    }
}

/// A one-line summary of a bulky value (grid, image, scan, path) in place of its display:
/// formatting 40,000 grid cells to show the first few costs more than the module that made them.
pub fn bulky_summary(value: &AnyValue) -> Option<String> {
    if let Some(g) = value.downcast_ref::<OccupancyGrid>() {
        return Some(format!(
            "OccupancyGrid {}×{} cells of {} m",
            g.width, g.height, g.resolution
        ));
    }
    if let Some(i) = value.downcast_ref::<Image>() {
        return Some(format!("Image {}×{} {}", i.width, i.height, i.encoding));
    }
    if let Some(l) = value.downcast_ref::<LaserScan>() {
        return Some(format!("LaserScan {} rays", l.ranges.len()));
    }
    if let Some(p) = value.downcast_ref::<Path2>() {
        return Some(format!("Path2 {} points", p.points().len()));
    }
    None
}

/// A remote value's one-line display, from its JSON (what the team transport carries): bulky
/// values summarised as [`bulky_summary`] does, strings without quotes, the rest as compact JSON.
pub fn json_text(type_name: &str, json: Option<&Value>) -> String {
    let Some(json) = json else {
        return String::from("?");
    };
    let n = |field: &str| json[field].as_u64().unwrap_or(0);
    let len = |v: &Value| v.as_array().map_or(0, Vec::len);
    match type_name {
        "OccupancyGrid" => format!(
            "OccupancyGrid {}×{} cells of {} m",
            n("width"),
            n("height"),
            json["resolution"].as_f64().unwrap_or(0.0)
        ),
        "Image" => format!(
            "Image {}×{} {}",
            n("width"),
            n("height"),
            json["encoding"].as_str().unwrap_or_default()
        ),
        "LaserScan" => format!("LaserScan {} rays", len(&json["ranges"])),
        "Path2" => format!("Path2 {} points", len(json)),
        _ => match json {
            Value::String(s) => s.clone(),
            other => other.to_string(),
        },
    }
}

/// The last `capacity` things that happened, oldest first.
#[derive(Debug, Clone)]
pub struct Recent<T> {
    items: VecDeque<T>,
    capacity: usize,
    /// How many were ever pushed (so a client asks only for what is new).
    total: u64,
}

impl<T: Clone> Recent<T> {
    /// An empty history keeping `capacity` items.
    pub fn new(capacity: usize) -> Self {
        Recent {
            items: VecDeque::with_capacity(capacity.min(1024)),
            capacity: capacity.max(1),
            total: 0,
        }
    }

    /// Adds one, forgetting the oldest beyond the capacity.
    pub fn push(&mut self, item: T) {
        if self.items.len() == self.capacity {
            self.items.pop_front();
        }
        self.items.push_back(item);
        self.total += 1;
    }

    /// Items pushed so far, forgotten ones included.
    pub fn total(&self) -> u64 {
        self.total
    }

    /// The kept items, oldest first.
    pub fn items(&self) -> Vec<T> {
        self.items.iter().cloned().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use petrel_actors::{ModuleListing, PropertyListing};

    fn listing() -> AgentListing {
        let prop = |key: &str, kind: &str, link: Option<&str>| PropertyListing {
            key: key.into(),
            kind: kind.into(),
            type_name: "f64".into(),
            link: link.map(str::to_string),
        };
        AgentListing {
            modules: vec![
                ModuleListing {
                    name: "sensor".into(),
                    type_name: "demo.signal".into(),
                },
                ModuleListing {
                    name: "_supervisor".into(),
                    type_name: "runtime".into(),
                },
            ],
            properties: vec![
                prop("filter/in/value", "input", Some("sensor/out/value")),
                prop("filter/in/items", "queue input", Some("sensor/out/items")),
                prop("sensor/params/period_s", "param", None),
                prop("sensor/control/fault", "control", None),
                prop("sensor/out/value", "output", None),
                prop("sensor/stats/steps", "stats", None),
            ],
        }
    }

    #[test]
    fn module_rows_read_their_stats_and_leave_runtime_modules_out() {
        let stats = vec![
            ("sensor/stats/status".into(), Value::from("running")),
            ("sensor/stats/steps".into(), Value::from(12)),
            ("sensor/stats/mean_interval_ms".into(), Value::from(50.0)),
            ("sensor/stats/dropped/in/a".into(), Value::from(2)),
            ("sensor/stats/dropped/in/b".into(), Value::from(3)),
            ("sensors/stats/steps".into(), Value::from(99)),
        ];
        let rows = modules(&listing(), &stats);
        assert_eq!(rows.len(), 1);
        let r = &rows[0];
        assert_eq!((r.status.as_str(), r.steps, r.dropped), ("running", 12, 5));
        assert_eq!(r.steps_per_s, 20.0);
        assert!(is_stat("sensor/stats/steps") && !is_stat("sensor/out/stats"));
    }

    #[test]
    fn only_params_and_controls_are_offered_for_editing() {
        let rows = properties(&listing());
        let writable: Vec<&str> = rows
            .iter()
            .filter(|p| p.writable)
            .map(|p| p.key.as_str())
            .collect();
        assert_eq!(writable, ["sensor/params/period_s", "sensor/control/fault"]);
    }

    #[test]
    fn the_graph_has_one_edge_per_link_and_marks_queues() {
        let g = graph(&listing());
        assert_eq!(g.modules, ["sensor", "_supervisor"]);
        assert_eq!(
            g.links,
            [
                LinkView {
                    from: "filter/in/value".into(),
                    to: "sensor/out/value".into(),
                    queue: false
                },
                LinkView {
                    from: "filter/in/items".into(),
                    to: "sensor/out/items".into(),
                    queue: true
                },
            ]
        );
    }

    #[test]
    fn bulky_values_are_summarised_without_formatting_their_contents() {
        let grid: AnyValue = std::sync::Arc::new(OccupancyGrid {
            width: 200,
            height: 100,
            resolution: 0.05,
            origin: Default::default(),
            data: vec![0i8; 20_000].into(),
        });
        assert_eq!(
            bulky_summary(&grid).as_deref(),
            Some("OccupancyGrid 200×100 cells of 0.05 m")
        );
        let path: AnyValue = std::sync::Arc::new(Path2::default());
        assert_eq!(bulky_summary(&path).as_deref(), Some("Path2 0 points"));
        assert_eq!(
            bulky_summary(&(std::sync::Arc::new(1.5f64) as AnyValue)),
            None
        );
    }

    #[test]
    fn remote_values_are_shown_from_their_json_with_bulky_ones_summarised() {
        let grid =
            serde_json::json!({"width": 200, "height": 100, "resolution": 0.05, "data": [0]});
        assert_eq!(
            json_text("OccupancyGrid", Some(&grid)),
            "OccupancyGrid 200×100 cells of 0.05 m"
        );
        let path = serde_json::json!([{"x": 1.0, "y": 2.0}, {"x": 3.0, "y": 2.0}]);
        assert_eq!(json_text("Path2", Some(&path)), "Path2 2 points");
        assert_eq!(json_text("String", Some(&Value::from("ok"))), "ok");
        assert_eq!(json_text("f64", Some(&Value::from(1.5))), "1.5");
        assert_eq!(json_text("f64", None), "?");
    }

    #[test]
    fn recent_keeps_the_newest_and_counts_all() {
        let mut r = Recent::new(2);
        for i in 0..5 {
            r.push(i);
        }
        assert_eq!((r.items(), r.total()), (vec![3, 4], 5));
    }
}
