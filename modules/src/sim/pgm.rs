//! ROS map_server maps: a YAML description ([`super::map_yaml`]) plus a PGM image (P5
//! binary or P2 ASCII, decoded by the `image` crate's PNM decoder).
//!
//! A pixel's occupancy is `p = (max - v) / max` (or `v / max` with `negate: 1`):
//! `p > occupied_thresh` is solid, `p < free_thresh` free, anything between (unknown) is
//! treated as solid by the simulator, because a robot must never be able to drive into space
//! the map author left undefined. Only `yaw = 0` is supported (rotated grids would break the
//! axis-aligned ray caster).

use std::path::Path;

use image::codecs::pnm::PnmDecoder;
use image::{ColorType, ImageDecoder};

use super::error::{ParamError, WorldFileError};
use super::grid::Grid;
use super::map_io::WorldMap;
pub use super::map_yaml::{parse_map_yaml, MapYaml};

/// Loads a map_server YAML file and the PGM image it names.
pub fn load_map_yaml(path: &Path) -> Result<WorldMap, WorldFileError> {
    let text = super::map_io::read_world_text(path)?;
    let meta = parse_map_yaml(path, &text)?;
    let limit = petrel_actors::files::limits::WORLD;
    let bytes = petrel_actors::files::read_bytes(&meta.image, "map image", limit).map_err(|e| {
        WorldFileError::file(&meta.image, format!("{e} (named by {})", path.display()))
    })?;
    let image = parse_pgm(&meta.image, &bytes)?;
    let grid = image_to_grid(&meta, &image)
        .map_err(|e| WorldFileError::file(&meta.image, format!("the map's size: {}", e.message)))?;
    let outside = meta
        .features
        .victims
        .iter()
        .zip(&meta.victim_positions)
        .find(|(v, _)| {
            let (col, row) = grid.cell_of(v.0.x, v.0.y);
            grid.is_solid(col, row)
        });
    if let Some((v, &(line, column))) = outside {
        return Err(WorldFileError::at_column(
            path,
            line,
            column,
            format!(
                "victim at ({}, {}) is inside a wall or outside the map; expected free space",
                v.0.x, v.0.y
            ),
        ));
    }
    Ok(WorldMap {
        grid,
        starts: Vec::new(),
        goals: Vec::new(),
        features: meta.features,
    })
}

/// A decoded greyscale image, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct PgmImage {
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Largest pixel value (white): the decoder scales samples to 255 or 65535.
    pub max: u16,
    /// Row-major pixel values, top row first.
    pub pixels: Vec<u16>,
}

/// Decodes a P5 (binary, 8 or 16 bit) or P2 (ASCII) PGM image.
pub fn parse_pgm(path: &Path, bytes: &[u8]) -> Result<PgmImage, WorldFileError> {
    // The decoder reads any PNM; a map is grey, and saying so names the real problem.
    match bytes.get(..2) {
        Some(b"P5") | Some(b"P2") => {}
        _ => {
            let magic = String::from_utf8_lossy(&bytes[..bytes.len().min(2)]).into_owned();
            return Err(WorldFileError::at_column(
                path,
                1,
                1,
                format!("expected the magic number P5 or P2 (a greyscale PGM), got {magic:?}"),
            ));
        }
    }
    if bytes.starts_with(b"P2") {
        // ASCII: each sample is checked, with its line (the decoder skips extra ones).
        let text = String::from_utf8_lossy(bytes);
        super::pgm_ascii::check_p2_samples(path, &text)?;
    }
    let err = |e: image::ImageError| WorldFileError::file(path, format!("cannot decode PGM: {e}"));
    let decoder = PnmDecoder::new(std::io::Cursor::new(bytes)).map_err(err)?;
    let (width, height) = decoder.dimensions();
    let (width, height) = (width as usize, height as usize);
    // Every pixel takes at least one byte of the file: a header claiming more pixels than
    // there are bytes is truncated, and refusing it avoids allocating for absurd headers.
    if width
        .checked_mul(height)
        .is_none_or(|n| n > bytes.len() || n > Grid::MAX_CELLS)
    {
        return Err(WorldFileError::file(
            path,
            format!(
                "truncated image data: {width} x {height} pixels do not fit in {} bytes",
                bytes.len()
            ),
        ));
    }
    let color = decoder.color_type();
    let mut buf = vec![0u8; decoder.total_bytes() as usize];
    decoder.read_image(&mut buf).map_err(err)?;
    let (max, pixels) = match color {
        ColorType::L8 => (255, buf.iter().map(|&b| b as u16).collect()),
        ColorType::L16 => (
            u16::MAX,
            buf.chunks_exact(2)
                .map(|c| u16::from_ne_bytes([c[0], c[1]]))
                .collect(),
        ),
        other => {
            return Err(WorldFileError::file(
                path,
                format!("expected a greyscale image, got {other:?}"),
            ))
        }
    };
    Ok(PgmImage {
        width,
        height,
        max,
        pixels,
    })
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
    use std::path::PathBuf;

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
        // 16-bit and a small maxval are scaled to the same occupancy.
        let mut wide = b"P5 3 1 65535\n".to_vec();
        wide.extend([0u8, 0, 255, 255, 128, 0]);
        let wide = parse_pgm(Path::new("c"), &wide).unwrap();
        assert_eq!((wide.max, wide.pixels[1]), (u16::MAX, u16::MAX));
        let small = parse_pgm(Path::new("d"), b"P2 2 1 15 0 15\n").unwrap();
        assert_eq!(small.pixels, vec![0, 255]);
    }

    #[test]
    fn bad_pgm_names_file_and_expectation() {
        let g = |b: &[u8]| parse_pgm(Path::new("i.pgm"), b).unwrap_err().to_string();
        assert_eq!(
            g(b"P6 1 1 255\n\0\0\0"),
            "i.pgm:1:1: expected the magic number P5 or P2 (a greyscale PGM), got \"P6\""
        );
        assert!(g(b"P2\n2 x\n").starts_with("i.pgm: cannot decode PGM:"));
        assert_eq!(
            g(b"P2\n1 1\n255\n300\n"),
            "i.pgm:4: sample 1 is 300, above the image's maxval 255"
        );
        assert!(g(b"P5 2 2 255\n\0\0").starts_with("i.pgm: cannot decode PGM:"));
        assert_eq!(
            g(b"P5 100000 100000 255\n\0"),
            "i.pgm: truncated image data: 100000 x 100000 pixels do not fit in 22 bytes"
        );
    }

    #[test]
    fn a_victim_inside_a_wall_is_refused_at_its_line_and_column() {
        let dir = std::env::temp_dir().join(format!("petrel-pgm-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // 2 x 1 pixels of 0.5 m: the left one black (solid), the right one white (free).
        std::fs::write(dir.join("w.pgm"), b"P2 2 1 255 0 255\n").unwrap();
        let yaml = dir.join("w.yaml");
        let base = YAML.replace("[-1.0, 2.0, 0.0]", "[0, 0, 0]");
        std::fs::write(&yaml, format!("{base}victims: [[0.75, 0.25]]\n")).unwrap();
        let w = load_world_yaml_ok(&yaml);
        assert_eq!(w.features.victims.len(), 1);
        std::fs::write(
            &yaml,
            format!("{base}victims: [[0.75, 0.25], [0.25, 0.25]]\n"),
        )
        .unwrap();
        let e = load_map_yaml(&yaml).unwrap_err();
        assert_eq!((e.line, e.column), (Some(7), Some(25)), "{e}");
        assert!(e.message.contains("inside a wall"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    fn load_world_yaml_ok(path: &Path) -> WorldMap {
        load_map_yaml(path).unwrap()
    }
}
