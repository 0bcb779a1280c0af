//! A mission's serve side: calls from other agents carried out on this agent's actions, and
//! the conditions they watch sent back (serve mode), or only the watches answered (run mode).

use petrel_actors::Input;

use super::bound::Bound;
use super::config::Flags;
use super::env::{mission_env, MissionEnv};
use super::run::{Run, StepTime};

impl Run {
    /// Serve mode, one round: calls from the inbox carried out on this agent's actions,
    /// coordinators that left have their actions stopped, then answers and watched conditions
    /// go out. Returns whether any call was made or what is served changed (a watch, a
    /// coordinator leaving or back): what `state/memory` keeps.
    pub fn serve_round(
        &mut self,
        t: StepTime,
        flags: &Input<Flags>,
        inbox: &petrel_actors::QueueReader<petrel_actors::team::Message>,
    ) -> bool {
        let now = t.now;
        self.refresh(now);
        let present = self.team.members_changed();
        let agent = self.team.agent.clone();
        let serve = &mut self.team.serve;
        let mut calls = Vec::new();
        let mut served = present.is_some();
        for item in inbox.drain() {
            match serve.receive(&item.from, &item.body) {
                Ok(Some(call)) => calls.push(call),
                Ok(None) => served = true,
                Err(e) => tracing::warn!(from = %item.from, "message ignored: {e}"),
            }
        }
        if let Some(present) = present {
            for local in serve.members(present.iter().map(String::as_str)) {
                tracing::warn!(action = %local, "its coordinator left the team: action stopped");
                calls.push((local, crate::label::CallKind::Interrupt));
            }
        }
        let full = |local: &str| format!("{agent}#{local}");
        let mut env = mission_env!(self, t, flags, true);
        use crate::exec::Environment;
        use crate::label::CallKind;
        let pending = &mut self.team.pending;
        let called = !calls.is_empty() || served;
        for (local, kind) in calls {
            let name = full(&local);
            if !env.bound.actions.contains_key(&name) {
                tracing::warn!(action = %name, call = %kind, "not an action of this agent in the plan: it fails");
                continue;
            }
            if let Some(i) = pending.iter().position(|(p, _)| *p == name) {
                // Stopped before it could start: nothing to undo.
                pending.remove(i);
                if !matches!(kind, CallKind::Start | CallKind::Resume) {
                    continue;
                }
            }
            let starts = matches!(kind, CallKind::Start | CallKind::Resume);
            if let Some(busy) = starts.then(|| sharing(env.bound, &name)).flatten() {
                tracing::info!(action = %name, waits_for = %busy, "called by the team plan; starts when the action using the same modules ends");
                pending.push((name, kind));
                continue;
            }
            tracing::info!(action = %name, call = %kind, "called by the team plan");
            env.call(&name, kind);
        }
        // Starts that waited for an action that has ended since.
        while let Some(i) = pending
            .iter()
            .position(|(p, _)| sharing(env.bound, p).is_none())
        {
            let (name, kind) = pending.remove(i);
            tracing::info!(action = %name, call = %kind, "starts now");
            env.call(&name, kind);
        }
        // Starts reset their expressions' time origins: evaluate before answering.
        env.bound.exprs.evaluate_into(now, &mut self.changed);
        // Both questions read the same environment, one at a time.
        let env = std::cell::RefCell::new(env);
        serve.poll(
            |local| {
                let name = full(local);
                let mut env = env.borrow_mut();
                if pending.iter().any(|(p, _)| *p == name) {
                    return (false, false);
                }
                match env.bound.actions.contains_key(&name) {
                    true => (env.action_finished(&name), env.action_failed(&name)),
                    false => (false, true),
                }
            },
            |local| condition_of(&mut env.borrow_mut(), &full(local), local),
        );
        called
    }

    /// Run mode: sends other agents the conditions of this one they watch, when they changed
    /// (calls, which only serve mode carries out, are answered as failed).
    pub fn answer_watches(&mut self, t: StepTime, flags: &Input<Flags>) {
        if !self.team.serve.has_watchers() {
            return;
        }
        self.refresh(t.now);
        let agent = self.team.agent.clone();
        let mut env = mission_env!(self, t, flags, true);
        self.team.serve.poll(
            |_| (false, true),
            |local| condition_of(&mut env, &format!("{agent}#{local}"), local),
        );
    }
}

/// Another running action that switches a module `name` switches too, if any.
fn sharing(bound: &Bound, name: &str) -> Option<String> {
    let modules: Vec<&str> = bound
        .actions
        .get(name)?
        .enable
        .iter()
        .map(|h| h.key())
        .collect();
    bound
        .actions
        .iter()
        .find(|(other, a)| {
            *other != name && a.active() && a.enable.iter().any(|h| modules.contains(&h.key()))
        })
        .map(|(other, _)| other.clone())
}

/// This agent's condition `local` (bound as `agent#local` or as `local`).
fn condition_of(env: &mut MissionEnv<'_>, full: &str, local: &str) -> Option<bool> {
    use crate::exec::Environment;
    match env.bound.conditions.contains_key(full) {
        true => env.condition(full),
        false => env.condition(local),
    }
}
