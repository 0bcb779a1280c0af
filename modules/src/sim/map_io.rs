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
//! * Header keys (all optional): `resolution` metres per cell (0.001 to 10, default 0.1), `origin` world
//!   `x, y` of the grid's lower-left corner (default `0, 0`, each within ±1e6 m), `heading` start heading of the
//!   `R` robots in degrees (default 0 = +x); `dark` and `rough` (repeatable) a rectangle
//!   `x0, y0, x1, y1` in metres of dark area or rough floor.
//! * Header lines come before the grid, start with `# ` and contain at least one character
//!   that is not a grid character (any word does), which tells them apart from a grid row
//!   such as `# R  #`. A header of the form `# word: value` must use one of the keys above;
//!   anything else (e.g. `# A hall with two rooms.`) is a comment.
//! * Grid rows: `#` solid, `.` or space free, `R` robot start, `V` a victim (free cell),
//!   `1`..`9` goals (free cells,
//!   visited in digit order; digits must run 1, 2, .. without gaps or repeats). The first text
//!   row is the top of the world (largest y). Short rows are padded with free cells. Markers
//!   sit at their cell's centre.

use std::path::Path;

use petrel_actors::Pose2;

use super::error::WorldFileError;
use super::features::{Rect, WorldFeatures};
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
    /// Victims, dark areas and rough floor (empty unless the file declares them).
    pub features: WorldFeatures,
}

/// Reads a world file's text: a regular file within the world size limit, byte-order mark
/// dropped (a FIFO or `/dev/zero` named by mistake is refused, not read forever).
pub(crate) fn read_world_text(path: &Path) -> Result<String, WorldFileError> {
    use petrel_actors::files;
    files::read_text(path, "world file", files::limits::WORLD)
        .map_err(|e| WorldFileError::file(path, e))
}

/// Loads a world by extension: `.txt` (ASCII grid) or `.yaml`/`.yml` (map_server PGM + YAML).
pub fn load_world(path: &Path) -> Result<WorldMap, WorldFileError> {
    match path.extension().and_then(|e| e.to_str()) {
        Some("txt") => {
            let text = read_world_text(path)?;
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
    let mut features = WorldFeatures::default();
    // The single-valued keys given so far, with their line: a second one is an error, not
    // a silent override.
    let mut given: Vec<(&'static str, usize)> = Vec::new();
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
            if let Some(header_line) = header_text(line) {
                let mut header = Header {
                    file,
                    lineno,
                    resolution: &mut resolution,
                    origin: &mut origin,
                    heading_deg: &mut heading_deg,
                    features: &mut features,
                    given: &mut given,
                };
                header.parse(header_line)?;
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
            "no grid rows; expected rows of '#', '.', ' ', 'R', 'V', '1'..'9'",
        ));
    }

    let width = rows
        .iter()
        .map(|(_, r)| r.chars().count())
        .max()
        .unwrap_or(0);
    let height = rows.len();
    // A world file has no `size` parameter: its rows and columns are the size.
    let mut grid = Grid::new(width, height, resolution, origin.0, origin.1)
        .map_err(|e| WorldFileError::file(file, format!("the world's size: {}", e.message)))?;
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
                'V' => features.victims.push(petrel_actors::Point2::new(cx, cy)),
                '1'..='9' => {
                    let k = ch as usize - '1' as usize;
                    if goals[k].is_some() {
                        return Err(WorldFileError::at_column(file, *lineno, col as usize + 1, format!("goal '{ch}' appears twice; expected each goal digit once")));
                    }
                    goals[k] = Some(Pose2::new(cx, cy, 0.0));
                }
                other => {
                    return Err(WorldFileError::at_column(
                        file,
                        *lineno,
                        col as usize + 1,
                        format!(
                            "unexpected character {other:?}; expected '#', '.', ' ', 'R', 'V' or '1'..'9'"
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
        features,
    })
}

/// The header text after `# ` if `line` is a header line (see the module docs).
fn header_text(line: &str) -> Option<&str> {
    let rest = line.strip_prefix("# ")?;
    let is_grid_char = |c: char| matches!(c, '#' | '.' | ' ' | 'R' | 'V' | '1'..='9');
    rest.contains(|c: char| !is_grid_char(c))
        .then_some(rest.trim_end())
}

/// One header line being read, with the values it may set.
struct Header<'a> {
    file: &'a Path,
    lineno: usize,
    resolution: &'a mut f64,
    origin: &'a mut (f64, f64),
    heading_deg: &'a mut f64,
    features: &'a mut WorldFeatures,
    given: &'a mut Vec<(&'static str, usize)>,
}

/// Column of the header value: after `# `, the key and the colon, then spaces.
fn value_column(line_after_hash: &str, value: &str) -> usize {
    let offset = line_after_hash.len() - value.len();
    line_after_hash[..offset].chars().count() + 3
}

impl Header<'_> {
    fn error(&self, column: usize, message: String) -> WorldFileError {
        WorldFileError::at_column(self.file, self.lineno, column, message)
    }

    /// Numbers of a comma-separated header value, exactly `count` of them.
    fn numbers(
        &self,
        key: &str,
        value: &str,
        column: usize,
        what: &str,
        count: usize,
    ) -> Result<Vec<f64>, WorldFileError> {
        let parts: Vec<&str> = value.split(',').collect();
        if parts.len() != count {
            return Err(self.error(column, format!("`{key}`: expected {what}, got {value:?}")));
        }
        parts
            .iter()
            .map(|p| {
                p.trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| {
                        self.error(column, format!("`{key}`: expected {what}, got {value:?}"))
                    })
            })
            .collect()
    }

    fn parse(&mut self, header: &str) -> Result<(), WorldFileError> {
        let Some((key, value)) = header.split_once(':') else {
            return Ok(());
        };
        let key = key.trim();
        if key.contains(char::is_whitespace) {
            return Ok(()); // free-text comment that happens to contain a colon
        }
        let value = value.trim();
        let column = value_column(header, value);
        if let Some(once) = ["resolution", "origin", "heading"]
            .into_iter()
            .find(|k| *k == key)
        {
            if let Some((_, first)) = self.given.iter().find(|(k, _)| *k == once) {
                return Err(self.error(
                    3,
                    format!("`{once}` is given twice (first on line {first}); expected it once"),
                ));
            }
            self.given.push((once, self.lineno));
        }
        match key {
            "resolution" => {
                let r = self.numbers(key, value, column, "a number of metres per cell", 1)?[0];
                if !super::grid::RESOLUTION.contains(&r) {
                    return Err(self.error(column, format!("`resolution`: expected metres per cell in 0.001..=10, got {}", petrel_actors::short_number(r))));
                }
                *self.resolution = r;
            }
            "origin" => {
                let v = self.numbers(key, value, column, "`x, y` in metres", 2)?;
                if let Some(problem) = super::grid::origin_problem(v[0], v[1]) {
                    return Err(self.error(column, format!("`origin`: {problem}")));
                }
                *self.origin = (v[0], v[1]);
            }
            "heading" => *self.heading_deg = self.numbers(key, value, column, "degrees", 1)?[0],
            "dark" | "rough" => {
                let v = self.numbers(key, value, column, "`x0, y0, x1, y1` in metres", 4)?;
                let rect = Rect::from_corners([v[0], v[1], v[2], v[3]])
                    .map_err(|e| self.error(column, format!("`{key}`: {e}")))?;
                if key == "dark" {
                    self.features.dark.push(rect);
                } else {
                    self.features.rough.push(rect);
                }
            }
            other => {
                return Err(self.error(
                    3,
                    format!("unknown header key `{other}`; expected one of resolution, origin, heading, dark, rough"),
                ))
            }
        }
        Ok(())
    }
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
        assert_eq!(
            parse("###\n#x#\n").unwrap_err(),
            "w.txt:2:2: unexpected character 'x'; expected '#', '.', ' ', 'R', 'V' or '1'..'9'"
        );
        assert_eq!(
            parse("# resolution: -2\n#\n").unwrap_err(),
            "w.txt:1:15: `resolution`: expected metres per cell in 0.001..=10, got -2"
        );
        assert_eq!(
            parse("# resolution: 1e300\n#\n").unwrap_err(),
            "w.txt:1:15: `resolution`: expected metres per cell in 0.001..=10, got 1e300"
        );
        assert_eq!(
            parse("# origin: 1e308, 0\n#\n").unwrap_err(),
            "w.txt:1:11: `origin`: expected `x, y` in metres within -1e6..=1e6 (a thousand kilometres), got 1e308, 0"
        );
        assert!(parse("# origin: -1e6, 1e6\n#\n").is_ok());
        assert_eq!(
            parse("# resolution: fine\n#\n").unwrap_err(),
            "w.txt:1:15: `resolution`: expected a number of metres per cell, got \"fine\""
        );
        assert_eq!(
            parse("# resolution: 0.1\n# origin: 0, 0\n# resolution: 0.2\n#\n").unwrap_err(),
            "w.txt:3:3: `resolution` is given twice (first on line 1); expected it once"
        );
        assert_eq!(
            parse("# resolutoin: 0.1\n#\n").unwrap_err(),
            "w.txt:1:3: unknown header key `resolutoin`; expected one of resolution, origin, heading, dark, rough"
        );
        assert_eq!(
            parse("# origin: 1\n#\n").unwrap_err(),
            "w.txt:1:11: `origin`: expected `x, y` in metres, got \"1\""
        );
        assert_eq!(
            parse("#1#\n#1#\n").unwrap_err(),
            "w.txt:2:2: goal '1' appears twice; expected each goal digit once"
        );
        assert_eq!(parse("#1#\n#3#\n").unwrap_err(), "w.txt: goal '3' is present but goal '2' is missing; goals must be numbered 1, 2, .. without gaps");
        assert_eq!(parse("###\n\n###\n").unwrap_err(), "w.txt:2: empty line inside the grid; expected a grid row (use '.' or spaces for free cells)");
        assert_eq!(
            parse("# only a comment\n").unwrap_err(),
            "w.txt: no grid rows; expected rows of '#', '.', ' ', 'R', 'V', '1'..'9'"
        );
        let e = load_world(Path::new("/nonexistent/w.txt"))
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "/nonexistent/w.txt: cannot read world file: it does not exist"
        );
        let e = load_world(Path::new("w.png")).unwrap_err().to_string();
        assert!(e.contains("unknown world file extension"), "{e}");
    }

    #[test]
    fn victims_dark_and_rough_areas_are_read_with_positioned_errors() {
        let w = parse("# dark: 0, 0, 1.5, 2\n# rough: 1, 1, 2, 2\n#  dark:  2, 2, 3, 3\n#####\n#RV #\n#  V#\n#####\n").unwrap();
        assert_eq!(w.features.dark.len(), 2);
        assert_eq!(
            w.features.rough,
            vec![Rect::from_corners([1.0, 1.0, 2.0, 2.0]).unwrap()]
        );
        let v: Vec<(f64, f64)> = w.features.victims.iter().map(|p| (p.0.x, p.0.y)).collect();
        assert_eq!(
            v,
            vec![(0.25, 0.25), (0.35000000000000003, 0.15000000000000002)]
        );
        assert!(w.features.is_dark(1.0, 1.0) && w.features.is_rough(1.5, 1.5));
        // Victims sit on free cells: the grid under them is not solid.
        assert!(!w.grid.is_solid(2, 2));
        assert_eq!(
            parse("# dark: 0, 0, 1\n#\n").unwrap_err(),
            "w.txt:1:9: `dark`: expected `x0, y0, x1, y1` in metres, got \"0, 0, 1\""
        );
        assert_eq!(
            parse("#\n").map(|_| ()).and(parse("#  rough: 2, 0, 1, 1\n#\n").map(|_| ())).unwrap_err(),
            "w.txt:1:11: `rough`: expected x0 < x1 and y0 < y1 (lower-left then upper-right corner), got [2, 0, 1, 1]"
        );
        // A world without the new keys has none of them.
        assert_eq!(
            parse("###\n#R#\n###\n").unwrap().features,
            WorldFeatures::default()
        );
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
