//! Reading grid patches back: every message of a patch channel (`TOPIC/_patches`, metadata
//! `petrel.patch_of`) becomes the whole grid it stands for, on the grid's own channel, with
//! its own sequence and times, encoded as the recorder would have written it whole. Replay,
//! `petrel record info` and the playback module then see every write of the grid.

use std::collections::BTreeMap;

use petrel_actors::{AnyValue, OccupancyGrid, TypeInfo};

use crate::encode::{Codec, Stamp};
use crate::grid_patch::paste;
use crate::read::Recording;
use crate::sink::meta;

/// A grid channel being rebuilt: how its messages decode and its latest grid.
struct Rebuilt {
    codec: Codec,
    grid: Option<AnyValue>,
}

/// Turns the patches of `rec` into whole grids on their grid's channel; a patch channel whose
/// every message was rebuilt is dropped from the channels. The first patch that cannot be
/// rebuilt (no whole grid before it, a grid it does not fit) is named in the result, and it
/// and the rest of its channel stay as they are.
pub fn expand(rec: &mut Recording) -> Result<(), String> {
    let ti = TypeInfo::of::<OccupancyGrid>();
    // Patch channel id → grid channel id; grid channel id → its state.
    let mut grid_of: BTreeMap<u16, u16> = BTreeMap::new();
    let mut grids: BTreeMap<u16, Rebuilt> = BTreeMap::new();
    for (&id, ch) in &rec.channels {
        let Some(base_topic) = ch.metadata.get(meta::PATCH_OF) else {
            continue;
        };
        let base = rec
            .channels
            .iter()
            .find(|(_, c)| &c.topic == base_topic && !c.metadata.contains_key(meta::PATCH_OF));
        let codec = base.and_then(|(_, c)| Codec::from_channel(&c.schema, &c.message_encoding, false));
        if let (Some((&base_id, _)), Some(codec)) = (base, codec) {
            grid_of.insert(id, base_id);
            grids.insert(base_id, Rebuilt { codec, grid: None });
        }
    }
    if grid_of.is_empty() {
        return Ok(());
    }
    let mut failed: BTreeMap<u16, String> = BTreeMap::new();
    for m in &mut rec.messages {
        if let Some(state) = grids.get_mut(&m.channel) {
            state.grid = state.codec.decode(&ti, &m.data).ok();
            continue;
        }
        let Some(&base_id) = grid_of.get(&m.channel) else {
            continue;
        };
        if failed.contains_key(&m.channel) {
            continue;
        }
        let state = grids.get_mut(&base_id).expect("every grid channel has a state");
        let rebuilt = rebuild(state, &ti, &m.data, m.publish_ns);
        match rebuilt {
            Ok((grid, data)) => {
                state.grid = Some(grid);
                m.channel = base_id;
                m.data = data;
            }
            Err(e) => {
                failed.insert(m.channel, format!("grid patch {} ({e})", m.sequence));
            }
        }
    }
    for id in grid_of.keys() {
        if !failed.contains_key(id) {
            rec.channels.remove(id);
        }
    }
    match failed.into_iter().next() {
        None => Ok(()),
        Some((id, e)) => Err(format!("channel {id}: cannot rebuild {e}")),
    }
}

/// The whole grid a patch stands for, and its message as the grid's channel carries it.
fn rebuild(
    state: &Rebuilt,
    ti: &TypeInfo,
    patch: &[u8],
    publish_ns: u64,
) -> Result<(AnyValue, Vec<u8>), String> {
    let base = state
        .grid
        .as_ref()
        .and_then(|g| g.downcast_ref::<OccupancyGrid>())
        .ok_or("no whole grid before it")?;
    let patch = state.codec.decode(ti, patch)?;
    let patch = patch
        .downcast_ref::<OccupancyGrid>()
        .ok_or("not a grid")?;
    let grid: AnyValue = std::sync::Arc::new(paste(base, patch)?);
    let mut data = Vec::new();
    state
        .codec
        .encode(ti, &grid, Stamp::from_ns(publish_ns), &mut data)?;
    Ok((grid, data))
}
