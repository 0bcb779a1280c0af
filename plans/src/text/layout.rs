//! Left-to-right positions for compiled nets, so the PNML opens readably in
//! JARP: a node's column is its distance from `init`, its row its rank among
//! the nodes of that column.

use std::collections::{HashMap, VecDeque};

use crate::build::{ArcEnd, RawNet};
use crate::model::Position;

pub(crate) fn layout(net: &mut RawNet) {
    // Nodes by number: places, then transitions; arcs as successor lists.
    let np = net.places.len();
    let n = np + net.transitions.len();
    // Ids are looked up only for arcs that name them (the compiler's arcs are numbered).
    let mut ids: Option<HashMap<&str, usize>> = None;
    let mut node = |end: &ArcEnd| match end {
        ArcEnd::Place(i) => Some(*i),
        ArcEnd::Transition(i) => Some(np + i),
        ArcEnd::Id(id) => ids
            .get_or_insert_with(|| {
                let places = net.places.iter().map(|p| p.id.as_str());
                let transitions = net.transitions.iter().map(|t| t.id.as_str());
                places
                    .chain(transitions)
                    .enumerate()
                    .map(|(i, id)| (id, i))
                    .collect()
            })
            .get(&**id)
            .copied(),
    };
    let mut succ: Vec<Vec<usize>> = vec![Vec::new(); n];
    for a in &net.arcs {
        if let (Some(s), Some(t)) = (node(&a.source), node(&a.target)) {
            succ[s].push(t);
        }
    }
    let mut depth = vec![usize::MAX; n];
    let mut queue = VecDeque::new();
    for (i, p) in net.places.iter().enumerate() {
        if p.initial > 0 && depth[i] == usize::MAX {
            depth[i] = 0;
            queue.push_back(i);
        }
    }
    while let Some(i) = queue.pop_front() {
        for &s in &succ[i] {
            if depth[s] == usize::MAX {
                depth[s] = depth[i] + 1;
                queue.push_back(s);
            }
        }
    }
    let far = depth
        .iter()
        .filter(|&&d| d != usize::MAX)
        .max()
        .map_or(0, |d| d + 1);
    let mut rows = vec![0usize; far + 1];
    let mut place = |i: usize| {
        let d = depth[i].min(far);
        rows[d] += 1;
        Some(Position {
            x: 60.0 + 70.0 * d as f64,
            y: 60.0 * rows[d] as f64,
        })
    };
    for (i, p) in net.places.iter_mut().enumerate() {
        p.position = place(i);
    }
    for (j, t) in net.transitions.iter_mut().enumerate() {
        t.position = place(np + j);
    }
}
