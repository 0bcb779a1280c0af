//! Left-to-right positions for compiled nets, so the PNML opens readably in
//! JARP: a node's column is its distance from `init`, its row its rank among
//! the nodes of that column.

use std::collections::{HashMap, VecDeque};

use crate::build::{ArcEnd, RawNet};
use crate::model::Position;

pub(crate) fn layout(net: &mut RawNet) {
    // Nodes by number: places, then transitions.
    let np = net.places.len();
    let n = np + net.transitions.len();
    // Ids are looked up only for arcs that name them (the compiler's arcs are numbered).
    let mut ids: Option<HashMap<&str, usize>> = None;
    let (names, places, transitions) = (&net.names, &net.places, &net.transitions);
    let mut node = |end: ArcEnd| match end {
        ArcEnd::Place(i) => Some(i as usize),
        ArcEnd::Transition(i) => Some(np + i as usize),
        ArcEnd::Named(k) => ids
            .get_or_insert_with(|| {
                let places = places.iter().map(|p| p.id.as_str());
                let transitions = transitions.iter().map(|t| t.id.as_str());
                places
                    .chain(transitions)
                    .enumerate()
                    .map(|(i, id)| (id, i))
                    .collect()
            })
            .get(&*names[k as usize])
            .copied(),
    };
    let arcs: Vec<(u32, u32)> = net
        .arcs
        .iter()
        .filter_map(|a| Some((node(a.source)? as u32, node(a.target)? as u32)))
        .collect();
    let succ = Successors::new(n, &arcs);
    drop(arcs);
    let mut depth = vec![u32::MAX; n];
    let mut queue = VecDeque::new();
    for (i, p) in net.places.iter().enumerate() {
        if p.initial > 0 && depth[i] == u32::MAX {
            depth[i] = 0;
            queue.push_back(i);
        }
    }
    while let Some(i) = queue.pop_front() {
        for &s in succ.of(i) {
            let s = s as usize;
            if depth[s] == u32::MAX {
                depth[s] = depth[i] + 1;
                queue.push_back(s);
            }
        }
    }
    // Nodes never reached go in one column past the last.
    let far = depth
        .iter()
        .filter(|&&d| d != u32::MAX)
        .max()
        .map_or(0, |d| d + 1);
    let mut rows = vec![0usize; far as usize + 1];
    let mut place = |i: usize| {
        let d = depth[i].min(far) as usize;
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

/// Successor lists in one array (compressed rows): a list per node would be a heap block per
/// node, which for a long plan's half a million nodes outweighs the net itself.
struct Successors {
    /// Node `i`'s successors are `to[start[i]..start[i + 1]]`.
    start: Vec<u32>,
    to: Vec<u32>,
}

impl Successors {
    fn new(n: usize, arcs: &[(u32, u32)]) -> Self {
        let mut start = vec![0u32; n + 1];
        for &(s, _) in arcs {
            start[s as usize + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut to = vec![0u32; arcs.len()];
        // Arcs keep their order within a node's list: the order rows are given in.
        for &(s, t) in arcs {
            to[fill[s as usize] as usize] = t;
            fill[s as usize] += 1;
        }
        Successors { start, to }
    }

    fn of(&self, i: usize) -> &[u32] {
        &self.to[self.start[i] as usize..self.start[i + 1] as usize]
    }
}
