//! Left-to-right positions for compiled nets, so the PNML opens readably in
//! JARP: a node's column is its distance from `init`, its row its rank among
//! the nodes of that column.

use std::collections::{HashMap, VecDeque};

use crate::build::RawNet;
use crate::model::Position;

pub(crate) fn layout(net: &mut RawNet) {
    let mut succ: HashMap<&str, Vec<&str>> = HashMap::new();
    for a in &net.arcs {
        succ.entry(a.source.as_str())
            .or_default()
            .push(a.target.as_str());
    }
    let mut depth: HashMap<String, usize> = HashMap::new();
    let mut queue = VecDeque::new();
    for p in net.places.iter().filter(|p| p.initial > 0) {
        depth.insert(p.id.clone(), 0);
        queue.push_back(p.id.as_str());
    }
    while let Some(n) = queue.pop_front() {
        let d = depth[n];
        for &s in succ.get(n).map(Vec::as_slice).unwrap_or_default() {
            if !depth.contains_key(s) {
                depth.insert(s.to_string(), d + 1);
                queue.push_back(s);
            }
        }
    }
    let far = depth.values().max().map_or(0, |d| d + 1);
    let mut rows: HashMap<usize, usize> = HashMap::new();
    let mut place = |id: &str| {
        let d = depth.get(id).copied().unwrap_or(far);
        let row = rows.entry(d).or_insert(0);
        *row += 1;
        Some(Position {
            x: 60.0 + 70.0 * d as f64,
            y: 60.0 * *row as f64,
        })
    };
    for p in &mut net.places {
        p.position = place(&p.id);
    }
    for t in &mut net.transitions {
        t.position = place(&t.id);
    }
}
