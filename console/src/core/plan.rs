//! The running plan as the console draws it: the net's places and transitions (handed in by
//! whoever can read plans: the console depends on no plan library), the marking the mission
//! module publishes, and its recent firings.

use serde::Serialize;

/// A Petri net's structure, for drawing.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct PlanGraph {
    /// The `mission.pnp` module running it.
    pub module: String,
    /// Places, in the plan's order.
    pub places: Vec<PlaceView>,
    /// Transitions, in the plan's order.
    pub transitions: Vec<TransitionView>,
}

/// One place.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct PlaceView {
    /// Its label (what the marking names).
    pub label: String,
    /// `init`, `goal`, `fail`, `exec` (an action runs while marked) or empty.
    pub role: String,
}

/// One transition.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct TransitionView {
    /// Its label.
    pub label: String,
    /// Input places (indices into [`PlanGraph::places`]).
    pub inputs: Vec<usize>,
    /// Output places.
    pub outputs: Vec<usize>,
}

/// One place's tokens.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Marked {
    /// The place label.
    pub place: String,
    /// Its tokens.
    pub tokens: u32,
}

/// Parses the mission module's `out/marking`: `label` or `label*n`, comma-separated.
pub fn parse_marking(text: &str) -> Vec<Marked> {
    text.split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|entry| match entry.rsplit_once('*') {
            Some((place, n)) => match n.parse() {
                Ok(tokens) => Marked {
                    place: place.to_string(),
                    tokens,
                },
                Err(_) => Marked {
                    place: entry.to_string(),
                    tokens: 1,
                },
            },
            None => Marked {
                place: entry.to_string(),
                tokens: 1,
            },
        })
        .collect()
}

/// A firing as the console saw it: the plan's marking changed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Firing {
    /// Seconds since the console started.
    pub time_s: f64,
    /// Transitions fired so far (`out/fired`).
    pub fired: i64,
    /// The marking after it.
    pub marking: String,
    /// The transitions that may have fired: those whose inputs were all marked before and
    /// not all marked after (empty without the plan's structure).
    pub transitions: Vec<String>,
}

/// Which transitions of `graph` explain the move from marking `before` to `after`: every
/// input place marked before, and some input place no longer marked after.
pub fn fired_between(graph: &PlanGraph, before: &[Marked], after: &[Marked]) -> Vec<String> {
    let tokens = |m: &[Marked], place: usize| {
        let label = &graph.places[place].label;
        m.iter().find(|x| &x.place == label).map_or(0, |x| x.tokens)
    };
    graph
        .transitions
        .iter()
        .filter(|t| !t.inputs.is_empty())
        .filter(|t| t.inputs.iter().all(|&p| tokens(before, p) > 0))
        .filter(|t| {
            t.inputs
                .iter()
                .any(|&p| tokens(after, p) < tokens(before, p))
        })
        .map(|t| t.label.clone())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn place(label: &str) -> PlaceView {
        PlaceView {
            label: label.into(),
            role: String::new(),
        }
    }

    #[test]
    fn the_marking_text_parses_with_and_without_counts() {
        assert_eq!(
            parse_marking("init, go.exec*2,"),
            [
                Marked {
                    place: "init".into(),
                    tokens: 1
                },
                Marked {
                    place: "go.exec".into(),
                    tokens: 2
                }
            ]
        );
        assert!(parse_marking("").is_empty());
        assert_eq!(parse_marking("a*b")[0].place, "a*b");
    }

    #[test]
    fn the_transition_that_consumed_the_marked_inputs_is_named() {
        let graph = PlanGraph {
            module: "mission".into(),
            places: vec![place("init"), place("go.exec"), place("goal")],
            transitions: vec![
                TransitionView {
                    label: "go.start".into(),
                    inputs: vec![0],
                    outputs: vec![1],
                },
                TransitionView {
                    label: "go.end".into(),
                    inputs: vec![1],
                    outputs: vec![2],
                },
            ],
        };
        let before = parse_marking("init");
        let after = parse_marking("go.exec");
        assert_eq!(fired_between(&graph, &before, &after), ["go.start"]);
        assert_eq!(
            fired_between(&graph, &after, &parse_marking("goal")),
            ["go.end"]
        );
        assert!(fired_between(&graph, &after, &after).is_empty());
    }
}
