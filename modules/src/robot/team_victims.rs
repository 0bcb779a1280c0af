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
    core: Option<TeamVictims>,
}

impl Module for TeamVictimsModule {
    const TYPE: &'static str = "vision.team_victims";
    const DESCRIPTION: &'static str =
        "Merges the victims the robots of a team report (messages `x y`) into one list: who found which.";

    fn declare(ports: &mut Ports) -> Self {
        TeamVictimsModule {
            inbox: ports.queue_in(
                "in/inbox",
                "victims reported by robots' vision.victim_mapper (`x y`, map frame)",
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
            core: None,
        }
    }

    fn schedule(&self) -> Schedule {
        Schedule::new().on_items(&self.inbox)
    }

    async fn init(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let radius = self.merge_radius.value();
        positive("merge_radius", radius).map_err(|e| super::param_error(e, &[]))?;
        self.core = Some(TeamVictims::new(radius));
        Ok(())
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let core = super::initialized(&mut self.core);
        for item in self.inbox.drain() {
            let robot = item.from.split('/').next().unwrap_or(&item.from);
            let Some(p) = parse(&item.body) else {
                tracing::warn!(from = %item.from, body = %item.body, "not a victim report; expected `x y` in metres");
                continue;
            };
            let t = self.clock.value();
            let when = match t >= 0.0 {
                true => format!(" at t = {t:.1} s"),
                false => String::new(),
            };
            match core.report(robot, p) {
                Report::New(i) => {
                    petrel_actors::outln!(
                        "[{}] victim {} at ({:.2}, {:.2}), found by {robot}{when}",
                        ctx.module(),
                        i + 1,
                        p.0.x,
                        p.0.y
                    );
                    self.found.set(i as i64 + 1);
                }
                Report::Known(i) => {
                    let v = &core.victims()[i];
                    petrel_actors::outln!(
                        "[{}] victim {} at ({:.2}, {:.2}) from {} reports, the last by {robot}{when}",
                        ctx.module(),
                        i + 1,
                        v.position.0.x,
                        v.position.0.y,
                        v.reports
                    );
                }
            }
        }
        let list: Vec<Point2> = core.victims().iter().map(|v| v.position).collect();
        if list[..] != self.victims.get().0[..] {
            self.victims.set(list.into());
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

/// `x y`, two finite numbers.
fn parse(body: &str) -> Option<Point2> {
    let mut parts = body.split_whitespace().map(str::parse::<f64>);
    match (parts.next(), parts.next(), parts.next()) {
        (Some(Ok(x)), Some(Ok(y)), None) if x.is_finite() && y.is_finite() => {
            Some(Point2::new(x, y))
        }
        _ => None,
    }
}
