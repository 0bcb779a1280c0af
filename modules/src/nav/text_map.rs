//! Maps drawn as text, for the nav cores' tests.

use petrel_actors::{OccupancyGrid, Pose2};

/// A map from text rows (top first): `#` occupied, `.` free, `?` unknown; cells of
/// `resolution` metres, the bottom-left cell's corner at `origin`.
pub(crate) fn text_map(rows: &[&str], resolution: f64, origin: (f64, f64)) -> OccupancyGrid {
    let (w, h) = (rows[0].len(), rows.len());
    let mut data = vec![0i8; w * h];
    for (t, row) in rows.iter().enumerate() {
        let r = h - 1 - t;
        for (c, ch) in row.chars().enumerate() {
            data[r * w + c] = match ch {
                '#' => 100,
                '?' => -1,
                _ => 0,
            };
        }
    }
    OccupancyGrid {
        width: w as u32,
        height: h as u32,
        resolution,
        origin: Pose2::new(origin.0, origin.1, 0.0),
        data: data.into(),
    }
}
