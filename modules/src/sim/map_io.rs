//! Loading worlds from files: the ASCII grid format and ROS map_server PGM + YAML.
//!
//! # ASCII world format (`.txt`)
//!
//! ```text
//! # A small world: two rooms.
//! # resolution: 0.1
//! # origin: 0.0, 0.0
//! # heading: 90
//! ##########
//! #R  .   1#
//! #  ###   #
//! #2      3#
//! ##########
//! ```
//!
//! * Header keys (all optional): `resolution` metres per cell (default 0.1), `origin` world
//!   `x, y` of the grid's lower-left corner (default `0, 0`), `heading` start heading of the
//!   `R` robots in degrees (default 0 = +x).
//! * Header lines come before the grid, start with `# ` and contain at least one character
//!   that is not a grid character (any word does), which tells them apart from a grid row
//!   such as `# R  #`. A header of the form `# word: value` must use one of the keys above;
//!   anything else (e.g. `# A hall with two rooms.`) is a comment.
//! * Grid rows: `#` solid, `.` or space free, `R` robot start, `1`..`9` goals (free cells,
//!   visited in digit order; digits must run 1, 2, .. without gaps or repeats). The first text
//!   row is the top of the world (largest y). Short rows are padded with free cells. Markers
//!   sit at their cell's centre.

use std::path::Path;

use petrel_actors::Pose2;

use super::error::WorldFileError;
use super::grid::Grid;

/// A loaded world: the solid grid plus optional robot starts and goals from the file.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldMap {
    /// Ground-truth grid.
    pub grid: Grid,
    /// Robot start poses (`R` markers, reading order); empty for PGM maps.
    pub starts: Vec<Pose2>,
    /// Goals in visiting order (`1`..`9` markers); empty for PGM maps.
    pub goals: Vec<Pose2>,
}

/// Loads a world by extension: `.txt` (ASCII grid) or `.yaml`/`.yml` (map_server PGM + YAML).
pub fn load_world(path: &Path) -> Result<WorldMap, WorldFileError> {
    match path.extension().and_then(|e| e.to_str()) {
        Some("txt") => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| WorldFileError::file(path, format!("cannot read: {e}")))?;
            parse_ascii(path, &text)
        }
        Some("yaml") | Some("yml") => super::pgm::load_map_yaml(path),
        _ => Err(WorldFileError::file(
            path,
            "unknown world file extension; expected `.txt` (ASCII grid) or `.yaml` (map_server map)",
        )),
    }
}

const DEFAULT_RESOLUTION: f64 = 0.1;

/// Parses the ASCII world format; `file` only names the source in errors.
pub fn parse_ascii(file: &Path, text: &str) -> Result<WorldMap, WorldFileError> {
    let mut resolution = DEFAULT_RESOLUTION;
    let mut origin = (0.0, 0.0);
    let mut heading_deg = 0.0;
    // (line number, row text) of each grid row, top first.
    let mut rows: Vec<(usize, &str)> = Vec::new();
    let mut blank_after_grid: Option<usize> = None;

    for (i, raw) in text.lines().enumerate() {
        let lineno = i + 1;
        let line = raw.strip_suffix('\r').unwrap_or(raw);
        if rows.is_empty() {
            if line.trim().is_empty() {
                continue;
            }
            if let Some(header) = header_text(line) {
                parse_header(
                    file,
                    lineno,
                    header,
                    &mut resolution,
                    &mut origin,
                    &mut heading_deg,
                )?;
                continue;
            }
        }
        if line.trim().is_empty() {
            blank_after_grid.get_or_insert(lineno);
            continue;
        }
        if let Some(blank) = blank_after_grid {
            return Err(WorldFileError::at(
                file,
                blank,
                "empty line inside the grid; expected a grid row (use '.' or spaces for free cells)",
            ));
        }
        rows.push((lineno, line));
    }
    if rows.is_empty() {
        return Err(WorldFileError::file(
            file,
            "no grid rows; expected rows of '#', '.', ' ', 'R', '1'..'9'",
        ));
    }

    let width = rows
        .iter()
        .map(|(_, r)| r.chars().count())
        .max()
        .unwrap_or(0);
    let height = rows.len();
    let mut grid = Grid::new(width, height, resolution, origin.0, origin.1)
        .map_err(|e| WorldFileError::file(file, e.to_string()))?;
    let mut starts = Vec::new();
    let mut goals: [Option<Pose2>; 9] = [None; 9];
    let heading = heading_deg.to_radians();
    for (r, (lineno, line)) in rows.iter().enumerate() {
        let row = (height - 1 - r) as i64;
        for (col, ch) in line.chars().enumerate() {
            let col = col as i64;
            let (cx, cy) = grid.cell_center(col, row);
            match ch {
                '#' => grid.set(col, row, true),
                '.' | ' ' => {}
                'R' => starts.push(Pose2::new(cx, cy, heading)),
                '1'..='9' => {
                    let k = ch as usize - '1' as usize;
                    if goals[k].is_some() {
                        return Err(WorldFileError::at(file, *lineno, format!("goal '{ch}' appears twice; expected each goal digit once")));
                    }
                    goals[k] = Some(Pose2::new(cx, cy, 0.0));
                }
                other => {
                    return Err(WorldFileError::at(
                        file,
                        *lineno,
                        format!(
                            "unexpected character {other:?} at column {}; expected '#', '.', ' ', 'R' or '1'..'9'",
                            col + 1
                        ),
                    ))
                }
            }
        }
    }
    let count = goals.iter().take_while(|g| g.is_some()).count();
    if let Some(missing_after) = goals[count..].iter().position(|g| g.is_some()) {
        return Err(WorldFileError::file(
            file,
            format!("goal '{}' is present but goal '{}' is missing; goals must be numbered 1, 2, .. without gaps", count + missing_after + 1, count + 1),
        ));
    }
    let goals = goals
        .iter()
        .take(count)
        .map(|g| g.expect("counted"))
        .collect();
    Ok(WorldMap {
        grid,
        starts,
        goals,
    })
}

/// The header text after `# ` if `line` is a header line (see the module docs).
fn header_text(line: &str) -> Option<&str> {
    let rest = line.strip_prefix("# ")?;
    let is_grid_char = |c: char| matches!(c, '#' | '.' | ' ' | 'R' | '1'..='9');
    rest.contains(|c: char| !is_grid_char(c))
        .then_some(rest.trim())
}

fn parse_header(
    file: &Path,
    lineno: usize,
    header: &str,
    resolution: &mut f64,
    origin: &mut (f64, f64),
    heading_deg: &mut f64,
) -> Result<(), WorldFileError> {
    let Some((key, value)) = header.split_once(':') else {
        return Ok(());
    };
    let key = key.trim();
    if key.contains(char::is_whitespace) {
        return Ok(()); // free-text comment that happens to contain a colon
    }
    let value = value.trim();
    let number = |text: &str, what: &str| -> Result<f64, WorldFileError> {
        text.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| {
                WorldFileError::at(
                    file,
                    lineno,
                    format!("`{key}`: expected {what}, got {text:?}"),
                )
            })
    };
    match key {
        "resolution" => {
            let r = number(value, "a number of metres per cell")?;
            if r <= 0.0 {
                return Err(WorldFileError::at(
                    file,
                    lineno,
                    format!("`resolution`: expected metres per cell > 0, got {r}"),
                ));
            }
            *resolution = r;
        }
        "origin" => {
            let parts: Vec<&str> = value.split(',').collect();
            if parts.len() != 2 {
                return Err(WorldFileError::at(
                    file,
                    lineno,
                    format!("`origin`: expected `x, y` in metres, got {value:?}"),
                ));
            }
            *origin = (
                number(parts[0], "x in metres")?,
                number(parts[1], "y in metres")?,
            );
        }
        "heading" => *heading_deg = number(value, "degrees")?,
        other => {
            return Err(WorldFileError::at(
                file,
                lineno,
                format!(
                    "unknown header key `{other}`; expected one of resolution, origin, heading"
                ),
            ))
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<WorldMap, String> {
        parse_ascii(Path::new("w.txt"), text).map_err(|e| e.to_string())
    }

    #[test]
    fn parses_headers_markers_and_orientation() {
        let w = parse("# A test world.\n# R  # is a grid row, this is not\n# resolution: 0.5\n# origin: 1, -1\n# heading: 90\n#####\n#R 2#\n#1..#\n#####\n").unwrap();
        assert_eq!(
            (w.grid.width(), w.grid.height(), w.grid.resolution()),
            (5, 4, 0.5)
        );
        assert_eq!(w.grid.origin(), (1.0, -1.0));
        // `R` is on text row 1 = grid row 2, column 1.
        let s = w.starts[0];
        assert!((s.x() - 1.75).abs() < 1e-12 && (s.y() - 0.25).abs() < 1e-12);
        assert!((s.theta() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert_eq!(w.goals.len(), 2);
        assert!((w.goals[0].y() - -0.25).abs() < 1e-12 && (w.goals[1].x() - 2.75).abs() < 1e-12);
        assert!(w.grid.is_solid(0, 0) && !w.grid.is_solid(2, 2));
    }

    #[test]
    fn short_rows_are_padded_free_and_default_resolution_is_used() {
        let w = parse("# R #\n#\n###\n").unwrap();
        assert_eq!(w.starts.len(), 1, "`# R #` is a grid row, not a comment");
        assert_eq!(w.grid.resolution(), DEFAULT_RESOLUTION);
        assert!(!w.grid.is_solid(2, 1));
    }

    #[test]
    fn bad_files_name_line_and_expectation() {
        assert_eq!(parse("###\n#x#\n").unwrap_err(), "w.txt:2: unexpected character 'x' at column 2; expected '#', '.', ' ', 'R' or '1'..'9'");
        assert_eq!(
            parse("# resolution: -2\n#\n").unwrap_err(),
            "w.txt:1: `resolution`: expected metres per cell > 0, got -2"
        );
        assert_eq!(
            parse("# resolution: fine\n#\n").unwrap_err(),
            "w.txt:1: `resolution`: expected a number of metres per cell, got \"fine\""
        );
        assert_eq!(
            parse("# resolutoin: 0.1\n#\n").unwrap_err(),
            "w.txt:1: unknown header key `resolutoin`; expected one of resolution, origin, heading"
        );
        assert_eq!(
            parse("# origin: 1\n#\n").unwrap_err(),
            "w.txt:1: `origin`: expected `x, y` in metres, got \"1\""
        );
        assert_eq!(
            parse("#1#\n#1#\n").unwrap_err(),
            "w.txt:2: goal '1' appears twice; expected each goal digit once"
        );
        assert_eq!(parse("#1#\n#3#\n").unwrap_err(), "w.txt: goal '3' is present but goal '2' is missing; goals must be numbered 1, 2, .. without gaps");
        assert_eq!(parse("###\n\n###\n").unwrap_err(), "w.txt:2: empty line inside the grid; expected a grid row (use '.' or spaces for free cells)");
        assert_eq!(
            parse("# only a comment\n").unwrap_err(),
            "w.txt: no grid rows; expected rows of '#', '.', ' ', 'R', '1'..'9'"
        );
        let e = load_world(Path::new("/nonexistent/w.txt"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("/nonexistent/w.txt: cannot read:"), "{e}");
        let e = load_world(Path::new("w.png")).unwrap_err().to_string();
        assert!(e.contains("unknown world file extension"), "{e}");
    }

    #[test]
    fn shipped_worlds_load() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/worlds");
        let c = load_world(&dir.join("cluttered.txt")).unwrap();
        assert_eq!(
            (c.grid.width(), c.grid.height(), c.grid.resolution()),
            (100, 100, 0.2)
        );
        assert_eq!((c.starts.len(), c.goals.len()), (1, 3));
        let w = load_world(&dir.join("warehouse.yaml")).unwrap();
        assert_eq!(
            (w.grid.width(), w.grid.height(), w.grid.resolution()),
            (400, 400, 0.05)
        );
        // The grey (unknown, value 205) patch in the office corner is solid; the aisle is free.
        let (col, row) = w.grid.cell_of(0.7, 19.2);
        assert!(w.grid.is_solid(col, row));
        let (col, row) = w.grid.cell_of(9.75, 8.5);
        assert!(!w.grid.is_solid(col, row));
    }
}
