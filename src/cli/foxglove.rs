//! `petrel run --foxglove ADDR`: the Foxglove live view (petrel-console's server side of the
//! Foxglove WebSocket protocol) with the channels of a recording: petrel-record's topic names,
//! schemas and encoders, so what Foxglove shows live is what `--record` writes.

use std::net::SocketAddr;
use std::sync::Arc;

use petrel_actors::{outln, Agent, AnyValue, TypeInfo};
use petrel_console::live::{ChannelEncoder, LiveChannel, LiveEncoders, LiveLog};
use petrel_console::{ConsoleOptions, FoxgloveServer};
use petrel_record::encode::foxglove;
use petrel_record::{select, Codec, Format, LogRecord, Stamp};

/// The recorder's encoders, in `format`.
struct RecordEncoders {
    format: Format,
}

/// One channel's codec, as the recorder would pick it.
struct Encoder {
    codec: Codec,
    type_info: TypeInfo,
}

impl ChannelEncoder for Encoder {
    fn encode(&self, value: &AnyValue, stamp_ns: u64, out: &mut Vec<u8>) -> Result<(), String> {
        self.codec
            .encode(&self.type_info, value, Stamp::from_ns(stamp_ns), out)
    }
}

impl LiveEncoders for RecordEncoders {
    fn channel(
        &self,
        agent: &str,
        key: &str,
        type_info: &TypeInfo,
        first: Option<&AnyValue>,
    ) -> Option<(LiveChannel, Arc<dyn ChannelEncoder>)> {
        // A queue with no item yet: a value of another type makes the recorder's choice for a
        // type without a standard message fall on `{"value": ...}`, which holds any JSON.
        let none: AnyValue = Arc::new(());
        let codec = Codec::for_value(self.format, type_info, first.unwrap_or(&none));
        live_channel(select::topic(agent, key), codec, *type_info)
    }

    fn log(&self) -> Option<(LiveChannel, Arc<dyn ChannelEncoder>)> {
        let topic = select::log_topic(self.format).to_string();
        live_channel(topic, Codec::log(self.format), TypeInfo::of::<LogRecord>())
    }
}

/// Channel `topic` of values of type `type_info`, encoded by `codec`.
fn live_channel(
    topic: String,
    codec: Codec,
    type_info: TypeInfo,
) -> Option<(LiveChannel, Arc<dyn ChannelEncoder>)> {
    let schema = codec.schema(type_info.name());
    let channel = LiveChannel {
        topic,
        encoding: schema.message_encoding.to_string(),
        schema: foxglove::websocket_schema(&schema)?,
        schema_name: schema.name,
        schema_encoding: schema.encoding.to_string(),
    };
    Some((channel, Arc::new(Encoder { codec, type_info })))
}

/// Starts the live view on `addr` for `agents`, printing where Foxglove connects (and a
/// generated token).
pub(crate) async fn start(
    addr: SocketAddr,
    format: Option<Format>,
    agents: &[Agent],
) -> Result<FoxgloveServer, String> {
    let sources = agents
        .iter()
        .map(|a| (a.name().to_string(), a.blackboard().clone()))
        .collect();
    // The recording's encodings: protobuf grids, scans, poses and images by default (their
    // schemas base64 in `advertise`, as the protocol carries binary schemas).
    let encoders = Arc::new(RecordEncoders {
        format: format.unwrap_or_default(),
    });
    let log = LiveLog::default();
    let options = ConsoleOptions { addr, token: None };
    let server = FoxgloveServer::start(options, sources, encoders, Some(log.clone()))
        .await
        .map_err(|e| e.to_string().replacen("--console", "--foxglove", 1))?;
    super::record_log::install_live(Some(log));
    outln!("foxglove: {}", server.url());
    if let (Some(token), true) = server.token() {
        eprintln!(
            "foxglove: {} is not loopback, so Foxglove needs the token in the address: {token}",
            server.local_addr().ip()
        );
    }
    Ok(server)
}
