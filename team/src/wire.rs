//! What travels with each sample besides its JSON payload: the attachment.
//!
//! The attachment is UTF-8 text, `key=value` pairs separated by `;`, so any zenoh client reads
//! it with a split: `v=1;seq=42;stamp_ns=1732312345000000000;type=Pose2;zid=7f3a...`.
//! - `seq`: the owner's sequence number for the stream (queue items: the queue's own numbers),
//!   so readers count what was lost;
//! - `stamp_ns`: the write stamp (when the owner's module wrote the value), Unix ns;
//! - `type`: the petrel type name (`petrel modules describe` shows them);
//! - `zid`: the owner's zenoh session, so a second agent using a taken name is told apart.

use std::time::{Duration, SystemTime, UNIX_EPOCH};

use tokio::time::Instant;

/// The `type` of a sample saying that the property cannot be had; its payload says why.
pub const ERROR_TYPE: &str = "@error";

/// The `type` of the first sample of a queue stream: the owner publishes from now on (a
/// queue's readers get the items pushed after it), so the link is live before any item.
pub const OPEN_TYPE: &str = "@open";

/// The version of the attachment layout.
pub const WIRE_VERSION: u32 = 1;

/// The metadata of one sample.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Attachment {
    /// The owner's sequence number for this stream.
    pub seq: u64,
    /// The write stamp, ns since the Unix epoch.
    pub stamp_ns: u64,
    /// The petrel type name of the payload.
    pub type_name: String,
    /// The owner's zenoh session id.
    pub zid: String,
}

/// Why an attachment was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("bad attachment: {0}")]
pub struct AttachmentError(pub String);

impl Attachment {
    /// The text form.
    pub fn encode(&self) -> String {
        format!(
            "v={WIRE_VERSION};seq={};stamp_ns={};type={};zid={}",
            self.seq, self.stamp_ns, self.type_name, self.zid
        )
    }

    /// Reads the text form; unknown keys are ignored (later versions may add some).
    pub fn decode(bytes: &[u8]) -> Result<Attachment, AttachmentError> {
        let err = |m: String| AttachmentError(m);
        let text = std::str::from_utf8(bytes).map_err(|_| err("not UTF-8".into()))?;
        if text.len() > 1024 {
            return Err(err(format!("{} bytes (at most 1024)", text.len())));
        }
        let (mut version, mut seq, mut stamp, mut type_name, mut zid) =
            (None, None, None, None, None);
        for pair in text.split(';') {
            let (k, v) = pair
                .split_once('=')
                .ok_or_else(|| err(format!("`{pair}` is not key=value")))?;
            let number = |v: &str| {
                v.parse::<u64>()
                    .map_err(|_| err(format!("`{k}={v}` is not a number")))
            };
            match k {
                "v" => version = Some(number(v)?),
                "seq" => seq = Some(number(v)?),
                "stamp_ns" => stamp = Some(number(v)?),
                "type" => type_name = Some(v.to_string()),
                "zid" => zid = Some(v.to_string()),
                _ => {}
            }
        }
        match version {
            Some(v) if v == WIRE_VERSION as u64 => {}
            Some(v) => {
                return Err(err(format!(
                    "wire version {v}, this petrel reads {WIRE_VERSION}"
                )))
            }
            None => return Err(err("no `v=`".into())),
        }
        let missing = |what: &str| err(format!("no `{what}=`"));
        Ok(Attachment {
            seq: seq.ok_or_else(|| missing("seq"))?,
            stamp_ns: stamp.ok_or_else(|| missing("stamp_ns"))?,
            type_name: type_name.ok_or_else(|| missing("type"))?,
            zid: zid.ok_or_else(|| missing("zid"))?,
        })
    }
}

/// Converts between the runtime's monotonic stamps and Unix time on the wire.
#[derive(Debug, Clone, Copy)]
pub struct StampClock {
    instant: Instant,
    unix: Duration,
}

impl StampClock {
    /// A conversion taken now.
    pub fn now() -> Self {
        StampClock {
            instant: Instant::now(),
            unix: SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .unwrap_or_default(),
        }
    }

    /// `stamp` as Unix ns.
    pub fn to_unix_ns(&self, stamp: Instant) -> u64 {
        let unix = match self.instant.checked_duration_since(stamp) {
            Some(ago) => self.unix.saturating_sub(ago),
            None => self.unix + stamp.duration_since(self.instant),
        };
        u64::try_from(unix.as_nanos()).unwrap_or(u64::MAX)
    }

    /// A local stamp for Unix ns `ns`, never later than now (clocks of two machines differ:
    /// a value must never look written in the future).
    pub fn from_unix_ns(&self, ns: u64) -> Instant {
        let ago = self.unix.saturating_sub(Duration::from_nanos(ns));
        self.instant.checked_sub(ago).unwrap_or(self.instant)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attachments_round_trip_and_bad_ones_say_why() {
        let a = Attachment {
            seq: 42,
            stamp_ns: 1_732_000_000_000_000_000,
            type_name: "Pose2".into(),
            zid: "7f3a".into(),
        };
        assert_eq!(Attachment::decode(a.encode().as_bytes()), Ok(a));
        for (bad, why) in [
            (&b"\xff"[..], "UTF-8"),
            (b"v=1;seq=x;stamp_ns=1;type=f64;zid=a", "not a number"),
            (b"v=1;stamp_ns=1;type=f64;zid=a", "no `seq=`"),
            (b"v=9;seq=1;stamp_ns=1;type=f64;zid=a", "wire version 9"),
            (b"garbage", "not key=value"),
        ] {
            let e = Attachment::decode(bad).unwrap_err().to_string();
            assert!(e.contains(why), "{e}");
        }
        assert!(Attachment::decode("v=1;".repeat(400).as_bytes()).is_err());
    }

    #[test]
    fn stamps_survive_the_trip_and_never_land_in_the_future() {
        let clock = StampClock::now();
        let written = clock.instant - Duration::from_millis(250);
        let ns = clock.to_unix_ns(written);
        let back = clock.from_unix_ns(ns);
        let diff = back.max(written) - back.min(written);
        assert!(diff < Duration::from_micros(1), "{diff:?}");
        let future = clock.to_unix_ns(clock.instant + Duration::from_secs(5));
        assert_eq!(clock.from_unix_ns(future), clock.instant);
    }
}
