//! The state of one incoming stream (a remote property some inputs link to): which samples to
//! accept, what was lost, and the status its inputs show in `stats/links/<input>`.
//!
//! Pure: times are passed in, so every transition is tested without a network.

use std::time::Duration;

use petrel_actors::team::{link_state, LinkStatus};
use tokio::time::Instant;

use crate::wire::Attachment;

/// Shortest time between two log lines about one stream's rejected samples.
pub const LOG_EVERY: Duration = Duration::from_secs(1);

/// What to do with a received sample.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Verdict {
    /// Decode and store it.
    Accept,
    /// Drop it (counted; `detail` of the status says why).
    Reject(String),
    /// An older or repeated sample (resent after a reconnection): drop it silently.
    Duplicate,
}

/// One incoming stream.
#[derive(Debug)]
pub struct StreamTracker {
    /// The input's type name: samples must carry it.
    expected_type: &'static str,
    /// The owner's session, once known: samples from another session are an impostor's.
    owner_zid: Option<String>,
    /// The next sequence number expected, and the session numbering it: a session that comes
    /// back after a partition continues its numbering (gaps are counted), a new one starts anew.
    next_seq: Option<(String, u64)>,
    status: LinkStatus,
    last_log: Option<Instant>,
}

impl StreamTracker {
    /// A stream of `source` (`petrel://agent/module/path`) feeding inputs of `expected_type`.
    pub fn new(source: &str, expected_type: &'static str) -> Self {
        StreamTracker {
            expected_type,
            owner_zid: None,
            next_seq: None,
            status: LinkStatus {
                state: link_state::WAITING.into(),
                source: source.to_string(),
                ..LinkStatus::default()
            },
            last_log: None,
        }
    }

    /// The status its inputs show.
    pub fn status(&self) -> &LinkStatus {
        &self.status
    }

    /// Judges a sample by its attachment; the payload is decoded only if accepted, and the
    /// sample counts once [`accept`](Self::accept)ed.
    pub fn judge(&mut self, attachment: &Attachment) -> Verdict {
        if let Some(owner) = &self.owner_zid {
            if *owner != attachment.zid {
                return self.reject(format!(
                    "a sample from session {} while the owner is session {owner} (two agents with one name?)",
                    attachment.zid
                ));
            }
        }
        if attachment.type_name != self.expected_type {
            self.status.state = link_state::BROKEN.into();
            return self.reject(format!(
                "the remote property is a {}, the input a {}",
                attachment.type_name, self.expected_type
            ));
        }
        match &self.next_seq {
            Some((zid, next)) if *zid == attachment.zid && attachment.seq < *next => {
                Verdict::Duplicate
            }
            _ => Verdict::Accept,
        }
    }

    /// Counts a judged and decoded sample: the link is live.
    pub fn accept(&mut self, attachment: &Attachment) {
        if self.owner_zid.is_none() {
            self.owner_zid = Some(attachment.zid.clone());
        }
        if let Some((zid, next)) = &self.next_seq {
            if *zid == attachment.zid {
                self.status.dropped += attachment.seq.saturating_sub(*next) as i64;
            }
        }
        self.next_seq = Some((attachment.zid.clone(), attachment.seq.saturating_add(1)));
        self.status.received += 1;
        self.status.state = link_state::LIVE.into();
        self.status.detail.clear();
    }

    /// The owner opened a queue stream: items come from now on, numbered by its queue (a
    /// stream reopened after a partition goes on with the same numbers, so its gaps count).
    pub fn opened(&mut self, zid: &str) {
        if self.owner_zid.as_deref().is_some_and(|z| z != zid) {
            self.reject(format!("an opening from session {zid}, not the owner's"));
            return;
        }
        self.owner_zid = Some(zid.to_string());
        if self.status.state != link_state::BROKEN {
            self.status.state = link_state::LIVE.into();
        }
    }

    /// The owner says the property cannot be had (unknown, or not a value or output queue).
    pub fn refused(&mut self, why: String) {
        self.status.state = link_state::BROKEN.into();
        self.status.detail = why;
    }

    /// Counts a sample whose attachment or payload could not be read.
    pub fn on_unreadable(&mut self, why: String) -> Verdict {
        self.reject(why)
    }

    fn reject(&mut self, why: String) -> Verdict {
        self.status.rejected += 1;
        self.status.detail.clone_from(&why);
        Verdict::Reject(why)
    }

    /// The owner left the team: its inputs keep the last value and go stale. The next session
    /// to send under its name is taken as the owner (its samples may come before its token).
    pub fn owner_left(&mut self, team: &str) {
        if self.status.state == link_state::LIVE {
            self.status.state = link_state::STALE.into();
            self.status.detail = format!(
                "agent `{}` left team `{team}`; the inputs keep its last value",
                self.owner()
            );
        }
        self.owner_absent(team);
        self.owner_zid = None;
    }

    /// The owner is not in the team (yet): a link that waits says so, since an agent in a
    /// team of another name, or unreachable, looks just like one that has not started.
    pub fn owner_absent(&mut self, team: &str) {
        if self.status.state == link_state::WAITING {
            self.status.detail = format!(
                "agent `{}` is not in team `{team}`: not started yet, in a team of another name, or not reachable (`petrel ls` lists the team)",
                self.owner()
            );
        }
    }

    /// The owner is (again) the session `zid`.
    pub fn owner_is(&mut self, zid: &str) {
        self.owner_zid = Some(zid.to_string());
        if self.status.state == link_state::WAITING {
            self.status.detail = format!(
                "agent `{}` is in the team; no value from it yet",
                self.owner()
            );
        }
    }

    /// The agent the stream comes from, as its source names it.
    fn owner(&self) -> &str {
        let source = &self.status.source;
        let rest = source.strip_prefix("petrel://").unwrap_or(source);
        rest.split('/').next().unwrap_or(rest)
    }

    /// Whether a rejection may be logged now (at most once per [`LOG_EVERY`]).
    pub fn may_log(&mut self, now: Instant) -> bool {
        match self.last_log {
            Some(last) if now.saturating_duration_since(last) < LOG_EVERY => false,
            _ => {
                self.last_log = Some(now);
                true
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    impl StreamTracker {
        fn on_sample(&mut self, a: &Attachment) -> Verdict {
            let v = self.judge(a);
            if v == Verdict::Accept {
                self.accept(a);
            }
            v
        }
    }

    fn att(seq: u64, type_name: &str, zid: &str) -> Attachment {
        Attachment {
            seq,
            stamp_ns: 0,
            type_name: type_name.into(),
            zid: zid.into(),
        }
    }

    #[test]
    fn a_waiting_stream_says_whether_its_owner_is_in_the_team() {
        let mut t = StreamTracker::new("petrel://a/m/out/x", "f64");
        t.owner_absent("crew");
        assert_eq!(t.status().state, "waiting");
        assert!(
            t.status().detail.starts_with(
                "agent `a` is not in team `crew`: not started yet, in a team of another name"
            ),
            "{:?}",
            t.status()
        );
        t.owner_is("z1");
        assert_eq!(
            t.status().detail,
            "agent `a` is in the team; no value from it yet"
        );
        assert_eq!(t.on_sample(&att(0, "f64", "z1")), Verdict::Accept);
        assert_eq!(t.status().detail, "");
        t.owner_left("crew");
        assert_eq!(t.status().state, "stale");
        assert_eq!(
            t.status().detail,
            "agent `a` left team `crew`; the inputs keep its last value"
        );
    }

    #[test]
    fn a_stream_goes_live_counts_gaps_and_ignores_repeats() {
        let mut t = StreamTracker::new("petrel://a/m/out/x", "f64");
        assert_eq!(t.status().state, "waiting");
        t.owner_is("z1");
        assert_eq!(t.on_sample(&att(0, "f64", "z1")), Verdict::Accept);
        assert_eq!(t.status().state, "live");
        assert_eq!(t.on_sample(&att(3, "f64", "z1")), Verdict::Accept);
        assert_eq!(t.status().dropped, 2);
        assert_eq!(t.on_sample(&att(2, "f64", "z1")), Verdict::Duplicate);
        assert_eq!(t.status().received, 2);
    }

    #[test]
    fn wrong_types_break_the_link_and_impostors_are_refused() {
        let mut t = StreamTracker::new("petrel://a/m/out/x", "f64");
        t.owner_is("z1");
        assert!(
            matches!(t.on_sample(&att(0, "Pose2", "z1")), Verdict::Reject(w) if w.contains("Pose2") && w.contains("f64"))
        );
        assert_eq!(t.status().state, "broken");
        let mut t = StreamTracker::new("petrel://a/m/out/x", "f64");
        t.owner_is("z1");
        assert!(matches!(
            t.on_sample(&att(0, "f64", "z9")),
            Verdict::Reject(_)
        ));
        assert_eq!((t.status().rejected, t.status().received), (1, 0));
        assert_eq!(t.status().state, "waiting");
    }

    #[test]
    fn a_departed_owner_makes_the_link_stale_until_its_new_session_sends() {
        let mut t = StreamTracker::new("petrel://a/m/out/x", "f64");
        t.owner_is("z1");
        t.on_sample(&att(10, "f64", "z1"));
        t.owner_left("crew");
        assert_eq!(t.status().state, "stale");
        assert_eq!(
            t.on_sample(&att(0, "f64", "z2")),
            Verdict::Accept,
            "samples may precede the token"
        );
        t.owner_is("z2");
        assert_eq!(t.status().state, "live");
        t.owner_left("crew");
        t.owner_is("z3");
        assert_eq!(
            t.on_sample(&att(0, "f64", "z3")),
            Verdict::Accept,
            "a new session starts at 0"
        );
        assert_eq!((t.status().state.as_str(), t.status().dropped), ("live", 0));
        assert!(
            matches!(t.on_sample(&att(1, "f64", "z2")), Verdict::Reject(_)),
            "z3 owns the name now"
        );
    }

    #[test]
    fn a_session_back_from_a_partition_has_its_losses_counted() {
        let mut t = StreamTracker::new("petrel://a/m/out/q", "f64");
        t.owner_is("z1");
        t.on_sample(&att(4, "f64", "z1"));
        t.owner_left("crew");
        t.owner_is("z1");
        assert_eq!(t.on_sample(&att(9, "f64", "z1")), Verdict::Accept);
        assert_eq!(
            t.status().dropped,
            4,
            "items 5..=8 were lost during the partition"
        );
    }

    #[test]
    fn logs_are_rate_limited() {
        let mut t = StreamTracker::new("x", "f64");
        let t0 = Instant::now();
        assert!(t.may_log(t0));
        assert!(!t.may_log(t0 + Duration::from_millis(999)));
        assert!(t.may_log(t0 + Duration::from_millis(1000)));
    }
}
