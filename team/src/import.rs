//! Feeding this agent's remote links: one zenoh subscription per wanted stream (a remote
//! property at one pace), shared by every input linked to it, announced to the owner by a
//! liveliness token under `@want`.

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

use parking_lot::Mutex;
use petrel_actors::team::{LinkStatus, RemoteFeed, RemoteLink, RemoteLinks, StatusWriter};
use petrel_actors::url::PropertyUrl;
use petrel_actors::TypeInfo;
use tokio::time::Instant;
use zenoh::sample::Sample;

use crate::keys::variant;
use crate::tracker::{StreamTracker, Verdict};
use crate::wire::{Attachment, StampClock, ERROR_TYPE, OPEN_TYPE};
use crate::Ctx;

/// One incoming stream and the inputs it feeds.
pub(crate) struct Stream {
    pub owner: String,
    type_info: TypeInfo,
    state: Mutex<StreamState>,
}

struct StreamState {
    tracker: StreamTracker,
    feeds: Vec<(RemoteFeed, StatusWriter)>,
}

impl Stream {
    /// Applies `f` to the tracker and shows the result on every input.
    pub fn update(&self, f: impl FnOnce(&mut StreamTracker)) {
        let mut st = self.state.lock();
        f(&mut st.tracker);
        publish(&st);
    }

    fn on_sample(&self, sample: &Sample) {
        let mut st = self.state.lock();
        let attachment = match sample.attachment() {
            Some(a) => Attachment::decode(&a.to_bytes()).map_err(|e| e.to_string()),
            None => Err("no attachment".to_string()),
        };
        let verdict = match &attachment {
            Ok(a) if a.type_name == OPEN_TYPE => {
                st.tracker.opened(&a.zid);
                Verdict::Duplicate
            }
            Ok(a) if a.type_name == ERROR_TYPE => {
                let why = String::from_utf8_lossy(&sample.payload().to_bytes()).into_owned();
                st.tracker.refused(why.clone());
                Verdict::Reject(why)
            }
            Ok(a) => st.tracker.judge(a),
            Err(why) => st.tracker.on_unreadable(why.clone()),
        };
        let verdict = match (verdict, attachment) {
            (Verdict::Accept, Ok(a)) => {
                match self.type_info.from_json(&sample.payload().to_bytes()) {
                    Ok(value) => {
                        st.tracker.accept(&a);
                        let stamp = StampClock::now().from_unix_ns(a.stamp_ns);
                        for (feed, _) in &st.feeds {
                            match feed {
                                RemoteFeed::Value(v) => v.write(value.clone(), stamp),
                                RemoteFeed::Queue(q) => q.push(value.clone(), stamp),
                            }
                        }
                        Verdict::Accept
                    }
                    Err(e) => st.tracker.on_unreadable(format!(
                        "the payload is not a {}: {e}",
                        self.type_info.name()
                    )),
                }
            }
            (verdict, _) => verdict,
        };
        if let Verdict::Reject(why) = verdict {
            if st.tracker.may_log(Instant::now()) {
                let source = &st.tracker.status().source;
                tracing::warn!(%source, rejected = st.tracker.status().rejected, "remote sample rejected: {why}");
            }
        }
        publish(&st);
    }
}

fn publish(st: &StreamState) {
    let status: &LinkStatus = st.tracker.status();
    for (_, writer) in &st.feeds {
        writer.set(status.clone());
    }
}

/// A stream this agent subscribes to, with what keeps it declared.
struct Wanted {
    stream: Arc<Stream>,
    inputs: Vec<String>,
    _subscriber: zenoh::pubsub::Subscriber<()>,
    _token: zenoh::liveliness::LivelinessToken,
}

/// The streams this agent wants, kept equal to its remote links.
#[derive(Default)]
pub(crate) struct Importer {
    wanted: HashMap<String, Wanted>,
}

impl Importer {
    /// Subscribes to what `links` need and drops what they no longer need.
    pub async fn sync(&mut self, ctx: &Arc<Ctx>, links: Vec<RemoteLink>) {
        let mut groups: BTreeMap<String, Vec<RemoteLink>> = BTreeMap::new();
        for link in links {
            groups.entry(stream_id(&link)).or_default().push(link);
        }
        self.wanted.retain(|id, w| {
            let keep = groups.get(id).is_some_and(|g| {
                g.iter()
                    .map(|l| l.input.as_str())
                    .eq(w.inputs.iter().map(String::as_str))
                    && g[0].feed.type_info() == w.stream.type_info
            });
            if !keep {
                ctx.streams.lock().remove(id);
            }
            keep
        });
        for (id, group) in groups {
            if self.wanted.contains_key(&id) {
                continue;
            }
            match subscribe(ctx, &id, &group).await {
                Ok(wanted) => {
                    ctx.streams.lock().insert(id.clone(), wanted.stream.clone());
                    self.wanted.insert(id, wanted);
                }
                Err(e) => {
                    tracing::error!(stream = %id, error = %e, "cannot subscribe to a remote property")
                }
            }
        }
    }
}

/// `owner/variant/module/path`: inputs linked to one remote property at one pace share it.
fn stream_id(link: &RemoteLink) -> String {
    format!(
        "{}/{}/{}",
        link.source.agent().unwrap_or_default(),
        variant(&link.qos),
        link.source.key()
    )
}

async fn subscribe(ctx: &Arc<Ctx>, id: &str, group: &[RemoteLink]) -> zenoh::Result<Wanted> {
    let first = &group[0];
    let source: &PropertyUrl = &first.source;
    let owner = source.agent().unwrap_or_default().to_string();
    let variant = variant(&first.qos);
    let type_info = first.feed.type_info();
    let mut tracker = StreamTracker::new(&source.to_string(), type_info.name());
    match ctx.membership.lock().zid_of(&owner) {
        Some(zid) => tracker.owner_is(zid),
        None => tracker.owner_absent(&ctx.config.name),
    }
    let stream = Arc::new(Stream {
        owner: owner.clone(),
        type_info,
        state: Mutex::new(StreamState {
            tracker,
            feeds: group
                .iter()
                .map(|l| (l.feed.clone(), l.status.clone()))
                .collect(),
        }),
    });
    stream.update(|_| {});
    let data_key = ctx.keys.data(&variant, &owner, &source.key());
    let s = stream.clone();
    // The subscriber is declared before the token: the owner, seeing the token, may send the
    // current value at once, and zenoh delivers declarations in order.
    let subscriber = ctx
        .session
        .declare_subscriber(data_key)
        .callback(move |sample| s.on_sample(&sample))
        .await?;
    let token_key = ctx.keys.want(&owner, &ctx.agent, &variant, &source.key());
    let token = ctx.session.liveliness().declare_token(token_key).await?;
    tracing::debug!(stream = %id, inputs = group.len(), "subscribed to a remote property");
    Ok(Wanted {
        stream,
        inputs: group.iter().map(|l| l.input.clone()).collect(),
        _subscriber: subscriber,
        _token: token,
    })
}

/// Keeps the subscriptions equal to the agent's remote links, as links change.
pub(crate) async fn follow_links(ctx: Arc<Ctx>, links: Arc<RemoteLinks>) {
    let mut changes = links.watch();
    let mut importer = Importer::default();
    loop {
        changes.borrow_and_update();
        importer.sync(&ctx, links.links()).await;
        if changes.changed().await.is_err() {
            return;
        }
    }
}
