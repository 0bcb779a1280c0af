//! `sim.fault`: the fault scenario of a team, from the config: the agent holding this module
//! dies at a set simulated time, as if its process were killed (`kill -9`).

use petrel_actors::{Context, Input, Module, Ports, Range, Schedule, EXIT_DIED};

/// `sim.fault`: kills its own agent at `params/die_at_s` (see [`EXIT_DIED`]).
pub struct SimFault {
    clock: Input<f64>,
    die_at_s: Input<f64>,
    fired: bool,
}

impl Module for SimFault {
    const TYPE: &'static str = "sim.fault";
    const DESCRIPTION: &'static str =
        "Kills its agent at a set simulated time, as kill -9 of its process would: it leaves the team without a goodbye, the rest of the run goes on.";

    fn declare(ports: &mut Ports) -> Self {
        SimFault {
            clock: ports.input(
                "in/clock",
                0.0,
                "simulated time, s (link it to the world's out/simTime)",
            ),
            die_at_s: ports.param_in(
                "params/die_at_s",
                0.0,
                Range::new(0.0, 1e7),
                "simulated time at which this agent dies, s; 0 = never",
            ),
            fired: false,
        }
    }

    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.clock)
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let (t, at) = (self.clock.value(), self.die_at_s.value());
        if self.fired || at <= 0.0 || t < at {
            return Ok(());
        }
        self.fired = true;
        petrel_actors::outln!(
            "[{}] t = {t:6.1} s  agent {} dies (params/die_at_s = {at})",
            ctx.module(),
            ctx.agent()
        );
        ctx.stop_agent(EXIT_DIED, format!("killed by sim.fault at t = {t:.1} s"));
        Ok(())
    }
}
