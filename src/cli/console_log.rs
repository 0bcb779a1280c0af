//! The tracing log as the web console's log tail: a layer that hands each event at info and
//! above to the console's [`LogTail`](petrel_console::LogTail) while a console runs (and
//! costs one lock check when none does).

use tracing::{Event, Level, Subscriber};
use tracing_subscriber::layer::Context;
use tracing_subscriber::Layer;

use super::record_log::Text;

/// The layer; `logging::init` adds it.
pub(crate) struct ConsoleLogLayer;

impl<S: Subscriber> Layer<S> for ConsoleLogLayer {
    fn on_event(&self, event: &Event<'_>, _ctx: Context<'_, S>) {
        let meta = event.metadata();
        if *meta.level() > Level::INFO {
            return;
        }
        let Some(tail) = super::console::log_tail() else {
            return;
        };
        let mut text = Text::default();
        event.record(&mut text);
        tail.push(meta.level().as_str(), meta.target(), text.0);
    }
}
