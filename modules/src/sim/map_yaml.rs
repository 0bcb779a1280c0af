//! The YAML half of a ROS map_server map, read with serde-saphyr (panic-free, nesting and
//! size budgets, every value with its line and column).
//!
//! map_server's keys: `image`, `resolution`, `origin: [x, y, yaw]`, `negate`,
//! `occupied_thresh`, `free_thresh` (required, as map_server requires) and `mode` (optional,
//! only `trinary`). petrel's rescue keys, all optional: `victims: [[x, y], ...]`,
//! `dark: [[x0, y0, x1, y1], ...]`, `rough: [[x0, y0, x1, y1], ...]` (metres, map frame).
//! Any YAML spelling works (flow or block lists, flow maps); unknown keys are errors, so
//! typos are caught.

use std::path::{Path, PathBuf};

use petrel_actors::Point2;
use serde::de::{self, Deserializer, Visitor};
use serde::Deserialize;
use serde_saphyr::{Budget, Options, Spanned};

use super::error::WorldFileError;
use super::features::{Rect, WorldFeatures};

/// Deepest nesting accepted in a map YAML file (map_server files nest two levels).
pub const MAX_DEPTH: usize = 16;

/// Map metadata read from a map_server YAML file.
#[derive(Clone, Debug, PartialEq)]
pub struct MapYaml {
    /// Image path, resolved relative to the YAML file.
    pub image: PathBuf,
    /// Metres per pixel.
    pub resolution: f64,
    /// World `(x, y, yaw)` of the lower-left pixel.
    pub origin: [f64; 3],
    /// Whether white means occupied.
    pub negate: bool,
    /// Occupancy above which a pixel is solid.
    pub occupied_thresh: f64,
    /// Occupancy below which a pixel is free.
    pub free_thresh: f64,
    /// Victims and special areas (petrel's own keys).
    pub features: WorldFeatures,
    /// Line and column of each victim in the file, for errors found once the image is read.
    pub victim_positions: Vec<(usize, usize)>,
}

/// map_server writes `negate` as 0/1; YAML booleans are accepted too.
#[derive(Clone, Copy, Debug)]
struct Negate(Option<bool>);

impl<'de> Deserialize<'de> for Negate {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Negate;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("0 or 1")
            }
            fn visit_bool<E: de::Error>(self, v: bool) -> Result<Negate, E> {
                Ok(Negate(Some(v)))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Negate, E> {
                Ok(Negate(match v {
                    0 => Some(false),
                    1 => Some(true),
                    _ => None,
                }))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Negate, E> {
                self.visit_u64(u64::try_from(v).unwrap_or(2))
            }
            fn visit_f64<E: de::Error>(self, _: f64) -> Result<Negate, E> {
                Ok(Negate(None))
            }
            fn visit_str<E: de::Error>(self, _: &str) -> Result<Negate, E> {
                Ok(Negate(None))
            }
        }
        d.deserialize_any(V)
    }
}

/// The file as written; every value keeps its position for the checks below.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMapYaml {
    image: Option<Spanned<String>>,
    resolution: Option<Spanned<f64>>,
    origin: Option<Spanned<Vec<f64>>>,
    negate: Option<Spanned<Negate>>,
    occupied_thresh: Option<Spanned<f64>>,
    free_thresh: Option<Spanned<f64>>,
    mode: Option<Spanned<String>>,
    #[serde(default)]
    victims: Vec<Spanned<Vec<f64>>>,
    #[serde(default)]
    dark: Vec<Spanned<Vec<f64>>>,
    #[serde(default)]
    rough: Vec<Spanned<Vec<f64>>>,
}

/// Parses a map_server YAML file; `path` names it in errors and anchors `image`.
pub fn parse_map_yaml(path: &Path, text: &str) -> Result<MapYaml, WorldFileError> {
    let mut budget = Budget::default();
    budget.max_depth = MAX_DEPTH;
    let mut options = Options::default();
    options.budget = Some(budget);
    options.with_snippet = false;
    let raw: RawMapYaml =
        serde_saphyr::from_str_with_options(text, options).map_err(|e| yaml_error(path, &e))?;
    let at = |s: &serde_saphyr::Location, msg: String| {
        WorldFileError::at_column(path, s.line() as usize, s.column() as usize, msg)
    };
    let missing = |k: &str| WorldFileError::file(path, format!("missing required key `{k}`"));
    let image = raw.image.ok_or_else(|| missing("image"))?;
    if image.value.trim().is_empty() {
        return Err(at(
            &image.referenced,
            "`image`: expected a file name".into(),
        ));
    }
    let resolution = raw.resolution.ok_or_else(|| missing("resolution"))?;
    if !super::grid::RESOLUTION.contains(&resolution.value) {
        return Err(at(
            &resolution.referenced,
            format!(
                "`resolution`: expected metres per pixel in 0.001..=10, got {}",
                petrel_actors::short_number(resolution.value)
            ),
        ));
    }
    let origin = raw.origin.ok_or_else(|| missing("origin"))?;
    if let [x, y, _] = origin.value.as_slice() {
        if let Some(problem) = super::grid::origin_problem(*x, *y) {
            return Err(at(&origin.referenced, format!("`origin`: {problem}")));
        }
    }
    let origin_value = match origin.value.as_slice() {
        [x, y, yaw] if [x, y, yaw].iter().all(|v| v.is_finite()) && *yaw == 0.0 => [*x, *y, 0.0],
        [_, _, yaw] if yaw.is_finite() => {
            return Err(at(
                &origin.referenced,
                format!(
                    "`origin`: rotated maps are not supported; expected yaw 0, got {}",
                    petrel_actors::short_number(*yaw)
                ),
            ))
        }
        other => {
            return Err(at(
                &origin.referenced,
                format!("`origin`: expected `[x, y, yaw]`, got {other:?}"),
            ))
        }
    };
    let negate = raw.negate.ok_or_else(|| missing("negate"))?;
    let negate_value = negate
        .value
        .0
        .ok_or_else(|| at(&negate.referenced, "`negate`: expected 0 or 1".into()))?;
    let threshold = |key: &str, t: Option<Spanned<f64>>| -> Result<f64, WorldFileError> {
        let t = t.ok_or_else(|| missing(key))?;
        if !(0.0..=1.0).contains(&t.value) {
            return Err(at(
                &t.referenced,
                format!(
                    "`{key}`: expected a number in [0, 1], got {}",
                    petrel_actors::short_number(t.value)
                ),
            ));
        }
        Ok(t.value)
    };
    let occupied_thresh = threshold("occupied_thresh", raw.occupied_thresh)?;
    let free_thresh = threshold("free_thresh", raw.free_thresh)?;
    if free_thresh >= occupied_thresh {
        return Err(WorldFileError::file(
            path,
            format!(
                "expected free_thresh < occupied_thresh, got {free_thresh} >= {occupied_thresh}"
            ),
        ));
    }
    if let Some(mode) = raw.mode.filter(|m| m.value != "trinary") {
        return Err(at(
            &mode.referenced,
            format!("`mode`: only `trinary` is supported, got {:?}", mode.value),
        ));
    }
    let mut features = WorldFeatures::default();
    let victim_positions = raw
        .victims
        .iter()
        .map(|v| (v.referenced.line() as usize, v.referenced.column() as usize))
        .collect();
    for v in &raw.victims {
        match v.value.as_slice() {
            [x, y] if x.is_finite() && y.is_finite() => features.victims.push(Point2::new(*x, *y)),
            other => {
                return Err(at(
                    &v.referenced,
                    format!("`victims`: expected `[x, y]` in metres, got {other:?}"),
                ))
            }
        }
    }
    for (key, list, out) in [
        ("dark", &raw.dark, &mut features.dark),
        ("rough", &raw.rough, &mut features.rough),
    ] {
        for r in list {
            let corners: [f64; 4] = r.value.as_slice().try_into().map_err(|_| {
                at(
                    &r.referenced,
                    format!(
                        "`{key}`: expected `[x0, y0, x1, y1]` in metres, got {:?}",
                        r.value
                    ),
                )
            })?;
            out.push(
                Rect::from_corners(corners)
                    .map_err(|e| at(&r.referenced, format!("`{key}`: {e}")))?,
            );
        }
    }
    Ok(MapYaml {
        image: path
            .parent()
            .unwrap_or(Path::new(""))
            .join(image.value.trim()),
        resolution: resolution.value,
        origin: origin_value,
        negate: negate_value,
        occupied_thresh,
        free_thresh,
        features,
        victim_positions,
    })
}

/// serde-saphyr's error as `file:line:column: message` (its own text ends in the position).
fn yaml_error(path: &Path, e: &serde_saphyr::Error) -> WorldFileError {
    let text = match e {
        // The library names its own limits (`budget breached: Nodes { nodes: 250001 }`).
        serde_saphyr::Error::Budget { breach, location } => {
            let message = budget_breach(breach);
            return match location.line() > 0 {
                true => WorldFileError::at_column(
                    path,
                    location.line() as usize,
                    location.column() as usize,
                    message,
                ),
                false => WorldFileError::file(path, message),
            };
        }
        _ => e.without_snippet().to_string(),
    };
    let text = match text.starts_with("recursion limit exceeded") {
        true => {
            format!("nested too deeply: a map file nests lists and keys at most {MAX_DEPTH} levels")
        }
        false => text,
    };
    // The library's advice is to its programmers (an option of its parser), not to a person
    // writing a map file.
    let text = match text.split_once(", set DuplicateKeyPolicy") {
        Some((said, _)) => format!("{said}: each key once"),
        None => text,
    };
    match e.location().filter(|l| l.line() > 0) {
        Some(l) => {
            let suffix = format!(" at line {}, column {}", l.line(), l.column());
            let message = text.strip_suffix(&suffix).unwrap_or(&text).to_string();
            WorldFileError::at_column(path, l.line() as usize, l.column() as usize, message)
        }
        None => WorldFileError::file(path, text),
    }
}

/// What a map file went beyond, in words: the parser's limits on its size, which no map
/// file comes near.
fn budget_breach(breach: &serde_saphyr::budget::BudgetBreach) -> String {
    use serde_saphyr::budget::BudgetBreach as B;
    let limits = Budget::default();
    let (what, limit) = match breach {
        B::Nodes { .. } => ("values (keys, lists and numbers)", limits.max_nodes),
        B::Events { .. } => ("parser events", limits.max_events),
        B::Depth { .. } => ("levels of nesting", MAX_DEPTH),
        B::Aliases { .. } => ("aliases (`*name`)", limits.max_aliases),
        B::Anchors { .. } => ("anchors (`&name`)", limits.max_anchors),
        B::Documents { .. } => ("documents (`---`)", limits.max_documents),
        B::MergeKeys { .. } => ("merge keys (`<<`)", limits.max_merge_keys),
        other => return format!("the file is too large for a map file ({other:?})"),
    };
    format!("the file has more than {limit} {what}, the most a map file may have")
}

#[cfg(test)]
mod tests;
