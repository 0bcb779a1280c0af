//! Who is in a team, for a tool that attached without joining (`petrel console --via`): the
//! members' liveliness tokens, read through the pure [`Membership`] the agents use, so a tool
//! and a member agree on who is in (a name claimed twice counts once).

use std::collections::BTreeSet;
use std::sync::Arc;

use parking_lot::Mutex;
use tokio::sync::watch;
use zenoh::sample::SampleKind;

use crate::membership::Membership;
use crate::{Client, TeamError};

/// The team's members, followed; dropping it stops following.
pub struct Members {
    names: watch::Receiver<BTreeSet<String>>,
    _subscriber: zenoh::pubsub::Subscriber<()>,
}

impl Members {
    /// The agents in the team now.
    pub fn now(&self) -> BTreeSet<String> {
        self.names.borrow().clone()
    }

    /// Waits for the next change of membership.
    pub async fn changed(&mut self) {
        let _ = self.names.changed().await;
    }
}

impl Client {
    /// Follows the members of the team: those in it now (zenoh's liveliness history), then
    /// every join and departure (a killed agent leaves when its session's lease runs out).
    pub async fn members(&self) -> Result<Members, TeamError> {
        let (tx, names) = watch::channel(BTreeSet::new());
        let membership = Arc::new(Mutex::new(Membership::default()));
        let keys = self.keys.clone();
        let subscriber = self
            .session
            .liveliness()
            .declare_subscriber(self.keys.all_alive())
            .history(true)
            .callback(move |sample| {
                let Some((agent, zid)) = keys.parse_alive(sample.key_expr().as_str()) else {
                    return;
                };
                let mut m = membership.lock();
                match sample.kind() {
                    SampleKind::Put => {
                        m.on_alive(agent, zid);
                    }
                    SampleKind::Delete => {
                        m.on_gone(agent, zid);
                    }
                }
                let now: BTreeSet<String> = m.members().0.into_iter().map(|t| t.agent).collect();
                tx.send_if_modified(|names| {
                    let changed = *names != now;
                    *names = now;
                    changed
                });
            })
            .await?;
        Ok(Members {
            names,
            _subscriber: subscriber,
        })
    }
}
