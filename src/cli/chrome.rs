//! The Chrome trace event format (what Perfetto and `chrome://tracing` open), as text: pure
//! functions from what happened to one JSON object each, written one per line in the array
//! form.

use serde_json::{json, Map, Value};

/// The process id every event carries: one `petrel run` is one process.
const PID: u32 = 1;

/// Names track `tid` (a module, `agent/module`): a `thread_name` metadata event.
pub(crate) fn track_name(tid: u64, name: &str) -> String {
    json!({"ph": "M", "name": "thread_name", "pid": PID, "tid": tid, "args": {"name": name}})
        .to_string()
}

/// A span of `dur_us` from `ts_us` on track `tid` (a module's step).
pub(crate) fn complete(name: &str, tid: u64, ts_us: f64, dur_us: f64) -> String {
    json!({"ph": "X", "name": name, "pid": PID, "tid": tid, "ts": ts_us, "dur": dur_us}).to_string()
}

/// A moment on track `tid` (a restart, a context switch, a plan firing), with its fields.
pub(crate) fn instant(name: &str, tid: u64, ts_us: f64, args: &[(String, String)]) -> String {
    let args: Map<String, Value> = args
        .iter()
        .map(|(k, v)| (k.clone(), Value::from(v.as_str())))
        .collect();
    json!({"ph": "i", "s": "t", "name": name, "pid": PID, "tid": tid, "ts": ts_us, "args": args})
        .to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn events_are_chrome_trace_objects() {
        let parse = |s: String| serde_json::from_str::<Value>(&s).unwrap();
        let m = parse(track_name(3, "robot/planner"));
        assert_eq!(
            (m["ph"].as_str(), m["args"]["name"].as_str()),
            (Some("M"), Some("robot/planner"))
        );
        let x = parse(complete("step", 3, 1.5, 20.25));
        assert_eq!(
            (x["ph"].as_str(), x["tid"].as_u64(), x["dur"].as_f64()),
            (Some("X"), Some(3), Some(20.25))
        );
        let i = parse(instant(
            "context \"slow\" activated",
            3,
            7.0,
            &[("context".into(), "slow".into())],
        ));
        assert_eq!(i["name"].as_str(), Some("context \"slow\" activated"));
        assert_eq!((i["ph"].as_str(), i["s"].as_str()), (Some("i"), Some("t")));
        assert_eq!(i["args"]["context"].as_str(), Some("slow"));
    }
}
