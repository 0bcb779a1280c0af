//! `vision.team_victims`: the victims every robot of a team confirmed, merged into one list.

use petrel_actors::team::Message;
use petrel_actors::types::Path2;
use petrel_actors::{Context, Input, Module, Output, Point2, Ports, QueueReader, Range, Schedule};

use crate::sim::error::positive;
use crate::vision::{Report, TeamVictims};

/// `vision.team_victims`: wraps [`TeamVictims`]; robots' `vision.victim_mapper`s send it
/// their victims (`params/report_to`).
pub struct TeamVictimsModule {
    inbox: QueueReader<Message>,
    merge_radius: Input<f64>,
    clock: Input<f64>,
    victims: Output<Path2>,
    found: Output<i64>,
    saved: Output<TeamVictims>,
    core: Option<TeamVictims>,
}

impl Module for TeamVictimsModule {
    const TYPE: &'static str = "vision.team_victims";
    const DESCRIPTION: &'static str =
        "Merges the victims the robots of a team report (messages `x y id`: a later report with the same id revises the robot's estimate) into one list: who found which.";

    fn declare(ports: &mut Ports) -> Self {
        let module = TeamVictimsModule {
            inbox: ports.queue_in(
                "in/inbox",
                "victims reported by robots' vision.victim_mapper (`x y id`: map frame, metres, then the robot's id for the victim; without the id a report cannot be revised)",
            ),
            merge_radius: ports.param_in(
                "params/merge_radius",
                1.0,
                Range::new(0.01, 100.0),
                "reports this close are one victim, m",
            ),
            clock: ports.input(
                "in/clock",
                -1.0,
                "simulated time, s, to say when each victim was found (link it to the world's out/simTime); negative (unlinked): not said",
            ),
            victims: ports.output(
                "out/victims",
                Path2::default(),
                "the team's victims, in the order found",
            ),
            found: ports.output("out/found", 0, "the team's victims"),
            saved: ports.state("state/list", TeamVictims::default(), "the list with every robot's latest report: a restarted module goes on from it"),
            core: None,
        };
        // Read only by `init`: a running agent refuses new values for these.
        ports.read_at_start(&["params/merge_radius"]);
        module
    }

    fn schedule(&self) -> Schedule {
        Schedule::new().on_items(&self.inbox)
    }

    async fn init(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let radius = self.merge_radius.value();
        positive("merge_radius", radius).map_err(|e| super::param_error(e, &[]))?;
        self.core = Some(TeamVictims::new(radius).resume(&self.saved.get()));
        Ok(())
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let core = super::initialized(&mut self.core);
        for item in self.inbox.drain() {
            let robot = item.from.split('/').next().unwrap_or(&item.from);
            let Some((p, id)) = parse(&item.body) else {
                tracing::warn!(from = %item.from, body = %item.body, "not a victim report; expected `x y` in metres, then the robot's id for the victim if it may revise it");
                continue;
            };
            let t = self.clock.value();
            let when = match t >= 0.0 {
                true => format!(" at t = {t:.1} s"),
                false => String::new(),
            };
            let m = ctx.module();
            match core.report(robot, id, p) {
                Report::New(i) => petrel_actors::outln!(
                    "[{m}] victim {} at ({:.2}, {:.2}), found by {robot}{when}",
                    i + 1,
                    p.0.x,
                    p.0.y
                ),
                Report::Known(i) => {
                    let v = &core.victims()[i];
                    petrel_actors::outln!(
                        "[{m}] victim {} at ({:.2}, {:.2}) from {} reports, the last by {robot}{when}",
                        i + 1,
                        v.position().0.x,
                        v.position().0.y,
                        v.reports()
                    );
                }
                // Estimates improve as robots come closer: frequent, so not on the console.
                Report::Revised(i) => {
                    let v = &core.victims()[i];
                    tracing::info!(
                        victim = i + 1,
                        x = v.position().0.x,
                        y = v.position().0.y,
                        by = robot,
                        "victim revised"
                    );
                }
                Report::Merged { kept, gone } => {
                    let v = &core.victims()[kept];
                    petrel_actors::outln!(
                        "[{m}] victim {} is victim {}, at ({:.2}, {:.2}) from {} reports: {robot} revised its report{when}",
                        gone + 1,
                        kept + 1,
                        v.position().0.x,
                        v.position().0.y,
                        v.reports()
                    );
                }
            }
        }
        let found = core.victims().len() as i64;
        self.found.set_if_changed(found);
        let list: Vec<Point2> = core.victims().iter().map(|v| v.position()).collect();
        self.victims.set_if_changed(list.into());
        if *self.saved.get() != *core {
            self.saved.set(core.clone());
        }
        Ok(())
    }

    async fn cleanup(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        if ctx.restarting() {
            return Ok(());
        }
        if let Some(core) = &self.core {
            petrel_actors::outln!("\n{}", core.summary());
        }
        Ok(())
    }
}

/// `x y` (two finite numbers), then optionally the reporter's id for the victim.
fn parse(body: &str) -> Option<(Point2, Option<u64>)> {
    let mut parts = body.split_whitespace();
    let mut number = || parts.next()?.parse::<f64>().ok().filter(|v| v.is_finite());
    let p = Point2::new(number()?, number()?);
    let id = match parts.next() {
        None => None,
        Some(id) => Some(id.parse::<u64>().ok()?),
    };
    parts.next().is_none().then_some((p, id))
}

#[cfg(test)]
mod tests {
    #[test]
    fn reports_are_two_numbers_and_an_optional_id() {
        use super::parse;
        let p = petrel_actors::Point2::new(1.5, -2.0);
        assert_eq!(parse("1.5 -2"), Some((p, None)));
        assert_eq!(parse(" 1.5  -2 7 "), Some((p, Some(7))));
        for bad in [
            "",
            "1.5",
            "1.5 x",
            "1.5 -2 -1",
            "1.5 -2 7 8",
            "NaN 1",
            "1 inf 3",
            "1 2 3.5",
        ] {
            assert_eq!(parse(bad), None, "{bad:?}");
        }
    }
}
