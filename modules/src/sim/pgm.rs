//! ROS map_server maps: a YAML description plus a PGM image (P5 binary or P2 ASCII).
//!
//! The YAML must contain `image`, `resolution`, `origin: [x, y, yaw]`, `negate`,
//! `occupied_thresh` and `free_thresh` (as map_server requires); `mode` is optional and only
//! `trinary` is supported. `image` is relative to the YAML file. A pixel's occupancy is
//! `p = (max - v) / max` (or `v / max` with `negate: 1`): `p > occupied_thresh` is solid,
//! `p < free_thresh` free, anything between (unknown) is treated as solid by the simulator,
//! because a robot must never be able to drive into space the map author left undefined.
//! Only `yaw = 0` is supported (rotated grids would break the axis-aligned ray caster).

use std::path::{Path, PathBuf};

use super::error::{ParamError, WorldFileError};
use super::grid::Grid;
use super::map_io::WorldMap;

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
}

/// Loads a map_server YAML file and the PGM image it names.
pub fn load_map_yaml(path: &Path) -> Result<WorldMap, WorldFileError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| WorldFileError::file(path, format!("cannot read: {e}")))?;
    let meta = parse_map_yaml(path, &text)?;
    let bytes = std::fs::read(&meta.image).map_err(|e| {
        WorldFileError::file(
            &meta.image,
            format!("cannot read image named by {}: {e}", path.display()),
        )
    })?;
    let image = parse_pgm(&meta.image, &bytes)?;
    Ok(WorldMap {
        grid: image_to_grid(&meta, &image)
            .map_err(|e| WorldFileError::file(&meta.image, e.to_string()))?,
        starts: Vec::new(),
        goals: Vec::new(),
    })
}

/// Parses the YAML subset used by map_server files: one `key: value` per line, `#` comments.
pub fn parse_map_yaml(path: &Path, text: &str) -> Result<MapYaml, WorldFileError> {
    let (mut image, mut resolution, mut origin, mut negate, mut occ, mut free) =
        (None, None, None, None, None, None);
    for (i, raw) in text.lines().enumerate() {
        let lineno = i + 1;
        let line = raw.split_once(" #").map_or(raw, |(l, _)| l).trim();
        if line.is_empty() || line.starts_with('#') || line == "---" {
            continue;
        }
        let err = |msg: String| WorldFileError::at(path, lineno, msg);
        let (key, value) = line
            .split_once(':')
            .ok_or_else(|| err(format!("expected `key: value`, got {line:?}")))?;
        let (key, value) = (key.trim(), unquote(value.trim()));
        let num = |what: &str| -> Result<f64, WorldFileError> {
            value
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| err(format!("`{key}`: expected {what}, got {value:?}")))
        };
        match key {
            "image" if value.is_empty() => return Err(err("`image`: expected a file name".into())),
            "image" => image = Some(path.parent().unwrap_or(Path::new("")).join(value)),
            "resolution" => {
                let r = num("metres per pixel")?;
                if r <= 0.0 {
                    return Err(err(format!("`resolution`: expected metres per pixel > 0, got {r}")));
                }
                resolution = Some(r);
            }
            "origin" => {
                let inner = value.strip_prefix('[').and_then(|v| v.strip_suffix(']'));
                let parts: Vec<Option<f64>> = inner
                    .map(|v| v.split(',').map(|p| p.trim().parse::<f64>().ok().filter(|x| x.is_finite())).collect())
                    .unwrap_or_default();
                match parts.as_slice() {
                    [Some(x), Some(y), Some(yaw)] if *yaw == 0.0 => origin = Some([*x, *y, *yaw]),
                    [Some(_), Some(_), Some(yaw)] => {
                        return Err(err(format!("`origin`: rotated maps are not supported; expected yaw 0, got {yaw}")))
                    }
                    _ => return Err(err(format!("`origin`: expected `[x, y, yaw]`, got {value:?}"))),
                }
            }
            "negate" => match value {
                "0" | "false" => negate = Some(false),
                "1" | "true" => negate = Some(true),
                _ => return Err(err(format!("`negate`: expected 0 or 1, got {value:?}"))),
            },
            "occupied_thresh" | "free_thresh" => {
                let t = num("a number in [0, 1]")?;
                if !(0.0..=1.0).contains(&t) {
                    return Err(err(format!("`{key}`: expected a number in [0, 1], got {t}")));
                }
                if key == "free_thresh" { free = Some(t) } else { occ = Some(t) }
            }
            "mode" if value == "trinary" => {}
            "mode" => return Err(err(format!("`mode`: only `trinary` is supported, got {value:?}"))),
            other => {
                return Err(err(format!(
                    "unknown key `{other}`; expected one of image, resolution, origin, negate, occupied_thresh, free_thresh, mode"
                )))
            }
        }
    }
    let missing = |k: &str| WorldFileError::file(path, format!("missing required key `{k}`"));
    let meta = MapYaml {
        image: image.ok_or_else(|| missing("image"))?,
        resolution: resolution.ok_or_else(|| missing("resolution"))?,
        origin: origin.ok_or_else(|| missing("origin"))?,
        negate: negate.ok_or_else(|| missing("negate"))?,
        occupied_thresh: occ.ok_or_else(|| missing("occupied_thresh"))?,
        free_thresh: free.ok_or_else(|| missing("free_thresh"))?,
    };
    if meta.free_thresh >= meta.occupied_thresh {
        return Err(WorldFileError::file(
            path,
            format!(
                "expected free_thresh < occupied_thresh, got {} >= {}",
                meta.free_thresh, meta.occupied_thresh
            ),
        ));
    }
    Ok(meta)
}

fn unquote(v: &str) -> &str {
    for q in ['"', '\''] {
        if let Some(inner) = v.strip_prefix(q).and_then(|v| v.strip_suffix(q)) {
            return inner;
        }
    }
    v
}

/// A decoded greyscale image, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct PgmImage {
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Largest pixel value (white).
    pub max: u16,
    /// Row-major pixel values, top row first.
    pub pixels: Vec<u16>,
}

/// Parses a P5 (binary, 8 or 16 bit) or P2 (ASCII) PGM image.
pub fn parse_pgm(path: &Path, bytes: &[u8]) -> Result<PgmImage, WorldFileError> {
    let mut t = Tokens {
        bytes,
        pos: 0,
        line: 1,
        path,
    };
    let magic = t.next("the magic number P5 or P2")?;
    let ascii = match magic.1.as_str() {
        "P5" => false,
        "P2" => true,
        m => {
            return Err(WorldFileError::at(
                path,
                magic.0,
                format!("expected the magic number P5 or P2, got {m:?}"),
            ))
        }
    };
    let width = t.number("the image width")?;
    let height = t.number("the image height")?;
    let max = t.number("the maximum grey value")?;
    if width == 0 || height == 0 || max == 0 || max > 65535 {
        return Err(WorldFileError::at(path, t.line, format!("expected width, height > 0 and 0 < max <= 65535, got {width} x {height}, max {max}")));
    }
    // Every pixel takes at least one byte of the file, so a header claiming more pixels than
    // there are bytes is truncated; checking first avoids allocating for absurd headers.
    let n = width
        .checked_mul(height)
        .filter(|&n| n <= bytes.len())
        .ok_or_else(|| {
            WorldFileError::file(
                path,
                format!(
                    "truncated image data: {width} x {height} pixels do not fit in {} bytes",
                    bytes.len()
                ),
            )
        })?;
    let mut pixels = Vec::with_capacity(n);
    if ascii {
        for _ in 0..n {
            let v = t.number("a pixel value")?;
            if v > max {
                return Err(WorldFileError::at(
                    path,
                    t.line,
                    format!("expected a pixel value <= {max}, got {v}"),
                ));
            }
            pixels.push(v as u16);
        }
    } else {
        let data = &bytes[(t.pos + 1).min(bytes.len())..]; // one whitespace byte ends the header
        let wide = max > 255;
        let need = n * if wide { 2 } else { 1 };
        if data.len() < need {
            return Err(WorldFileError::file(
                path,
                format!(
                    "truncated image data: expected {need} bytes for {width} x {height}, got {}",
                    data.len()
                ),
            ));
        }
        if wide {
            pixels.extend(
                data[..need]
                    .chunks_exact(2)
                    .map(|c| u16::from_be_bytes([c[0], c[1]])),
            );
        } else {
            pixels.extend(data[..need].iter().map(|&b| b as u16));
        }
    }
    Ok(PgmImage {
        width,
        height,
        max: max as u16,
        pixels,
    })
}

/// Header/ASCII tokenizer that skips whitespace and `#` comments and tracks line numbers.
struct Tokens<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: usize,
    path: &'a Path,
}

impl Tokens<'_> {
    fn next(&mut self, what: &str) -> Result<(usize, String), WorldFileError> {
        loop {
            match self.bytes.get(self.pos) {
                Some(b'#') => {
                    while self.bytes.get(self.pos).is_some_and(|&b| b != b'\n') {
                        self.pos += 1;
                    }
                }
                Some(b'\n') => {
                    self.line += 1;
                    self.pos += 1;
                }
                Some(b) if b.is_ascii_whitespace() => self.pos += 1,
                Some(_) => break,
                None => {
                    return Err(WorldFileError::at(
                        self.path,
                        self.line,
                        format!("unexpected end of file; expected {what}"),
                    ))
                }
            }
        }
        let start = self.pos;
        while self
            .bytes
            .get(self.pos)
            .is_some_and(|b| !b.is_ascii_whitespace())
        {
            self.pos += 1;
        }
        Ok((
            self.line,
            String::from_utf8_lossy(&self.bytes[start..self.pos]).into_owned(),
        ))
    }

    fn number(&mut self, what: &str) -> Result<usize, WorldFileError> {
        let (line, tok) = self.next(what)?;
        tok.parse().map_err(|_| {
            WorldFileError::at(self.path, line, format!("expected {what}, got {tok:?}"))
        })
    }
}

/// Converts an image to the simulator's grid with map_server's trinary thresholds.
///
/// Fails only if the image is too large for a [`Grid`].
pub fn image_to_grid(meta: &MapYaml, image: &PgmImage) -> Result<Grid, ParamError> {
    let mut grid = Grid::new(
        image.width,
        image.height,
        meta.resolution,
        meta.origin[0],
        meta.origin[1],
    )?;
    let max = image.max as f64;
    for (i, &v) in image.pixels.iter().enumerate() {
        let (col, top_row) = (i % image.width, i / image.width);
        let p = if meta.negate {
            v as f64 / max
        } else {
            (max - v as f64) / max
        };
        if p >= meta.free_thresh {
            grid.set(col as i64, (image.height - 1 - top_row) as i64, true);
        }
    }
    Ok(grid)
}

#[cfg(test)]
mod tests {
    use super::*;

    const YAML: &str = "image: w.pgm\nresolution: 0.5\norigin: [-1.0, 2.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";

    #[test]
    fn p2_and_p5_decode_to_the_same_grid_with_top_row_last() {
        let meta = parse_map_yaml(Path::new("/m/w.yaml"), YAML).unwrap();
        assert_eq!(meta.image, PathBuf::from("/m/w.pgm"));
        let p2 = parse_pgm(
            Path::new("a"),
            b"P2\n# comment\n3 2\n255\n0 255 128\n255 255 0\n",
        )
        .unwrap();
        let mut p5 = b"P5 3 2 255\n".to_vec();
        p5.extend([0u8, 255, 128, 255, 255, 0]);
        let p5 = parse_pgm(Path::new("b"), &p5).unwrap();
        assert_eq!(p2, p5);
        let g = image_to_grid(&meta, &p2).unwrap();
        // Top image row is grid row 1: black (solid), white (free), grey (unknown -> solid).
        assert!(g.is_solid(0, 1) && !g.is_solid(1, 1) && g.is_solid(2, 1));
        assert!(!g.is_solid(0, 0) && g.is_solid(2, 0));
        assert_eq!(g.origin(), (-1.0, 2.0));
    }

    #[test]
    fn bad_yaml_and_pgm_name_file_line_and_expectation() {
        let p = Path::new("m.yaml");
        let e = |t: &str| parse_map_yaml(p, t).unwrap_err().to_string();
        assert_eq!(
            e(&YAML.replace("0.5", "big")),
            "m.yaml:2: `resolution`: expected metres per pixel, got \"big\""
        );
        assert_eq!(
            e(&YAML.replace("[-1.0, 2.0, 0.0]", "[1, 2]")),
            "m.yaml:3: `origin`: expected `[x, y, yaw]`, got \"[1, 2]\""
        );
        assert_eq!(
            e(&YAML.replace("negate: 0", "negate: maybe")),
            "m.yaml:4: `negate`: expected 0 or 1, got \"maybe\""
        );
        assert_eq!(
            e(&YAML.replace("free_thresh: 0.196", "free_thresh: 0.9")),
            "m.yaml: expected free_thresh < occupied_thresh, got 0.9 >= 0.65"
        );
        assert_eq!(
            e(&YAML.replace("negate: 0\n", "")),
            "m.yaml: missing required key `negate`"
        );
        assert!(e(&format!("{YAML}colour: red\n")).starts_with("m.yaml:7: unknown key `colour`"));
        let g = |b: &[u8]| parse_pgm(Path::new("i.pgm"), b).unwrap_err().to_string();
        assert_eq!(
            g(b"P6 1 1 255\n\0"),
            "i.pgm:1: expected the magic number P5 or P2, got \"P6\""
        );
        assert_eq!(
            g(b"P2\n2 x\n"),
            "i.pgm:2: expected the image height, got \"x\""
        );
        assert_eq!(
            g(b"P2\n1 1\n255\n300\n"),
            "i.pgm:4: expected a pixel value <= 255, got 300"
        );
        assert_eq!(
            g(b"P5 2 2 255\n\0\0"),
            "i.pgm: truncated image data: expected 4 bytes for 2 x 2, got 2"
        );
        assert_eq!(
            g(b"P2\n"),
            "i.pgm:2: unexpected end of file; expected the image width"
        );
    }
}
