//! PNG rendering of a map with trajectory, planned path, goals and robot.

use std::path::Path;

use image::{Rgb, RgbImage};
use petrel_actors::{OccupancyGrid, Point2, Pose2};

use super::features::Rect;

/// What to draw on top of the map.
#[derive(Clone, Debug, Default)]
pub struct RenderLayers<'a> {
    /// Trajectory, oldest first; drawn blue to orange as time passes, unless coloured.
    pub trajectory: &'a [Point2],
    /// A colour per trajectory point (e.g. the active context); used when as long as it.
    pub trajectory_colours: &'a [[u8; 3]],
    /// Areas tinted over the map (dark rooms, rough floor), with their colour.
    pub areas: &'a [(Rect, [u8; 3])],
    /// A searched map of the map's geometry (`nav.searched`: -1 = not searched): free cells
    /// the camera never searched are tinted, so the picture shows what the search missed.
    pub searched: Option<&'a OccupancyGrid>,
    /// Victims of the world: position and whether they were found (green) or missed (red).
    pub victims: &'a [(Point2, bool)],
    /// Where the robot reported victims (small black dots).
    pub reported: &'a [Point2],
    /// A planned path, drawn thin green.
    pub path: &'a [Point2],
    /// Goals, drawn as numbered-by-order red rings (reached ones filled).
    pub goals: &'a [Pose2],
    /// How many of `goals` have been reached.
    pub reached: usize,
    /// The robot: pose and radius.
    pub robot: Option<(Pose2, f64)>,
    /// More robots' trajectories (a team), each in its own colour, with a disc where it ends
    /// and a black cross over it when the robot stopped there for good (its agent died).
    pub tracks: &'a [Track<'a>],
    /// Pixels per cell; `None` picks the largest of 1..=8 that keeps the image <= 1000 px.
    pub scale: Option<u32>,
}

/// One robot's trajectory in a team picture (see [`RenderLayers::tracks`]).
#[derive(Clone, Debug)]
pub struct Track<'a> {
    /// Positions, oldest first.
    pub points: &'a [Point2],
    /// Its colour.
    pub colour: [u8; 3],
    /// The robot stopped for good where the track ends.
    pub stopped: bool,
}

const FREE: [f64; 3] = [246.0, 244.0, 238.0];
const WALL: [f64; 3] = [38.0, 41.0, 54.0];
const UNKNOWN: Rgb<u8> = Rgb([168, 170, 178]);
/// Free floor the camera has not searched: a pale rose, distinct from free and unknown.
const UNSEARCHED: Rgb<u8> = Rgb([238, 206, 206]);

/// Renders `grid` (ROS convention) and `layers` into an RGB image.
pub fn render(grid: &OccupancyGrid, layers: &RenderLayers) -> RgbImage {
    let (w, h) = (grid.width.max(1), grid.height.max(1));
    let scale = layers
        .scale
        .unwrap_or_else(|| (1000 / w.max(h)).clamp(1, 8))
        .max(1);
    let mut img = RgbImage::new(w * scale, h * scale);
    let searched = layers.searched.filter(|s| {
        (s.width, s.height, s.data.len()) == (grid.width, grid.height, grid.data.len())
    });
    let unsearched = |col: u32, row: u32| {
        searched.is_some_and(|s| s.data[row as usize * s.width as usize + col as usize] < 0)
    };
    for row in 0..h {
        for col in 0..w {
            // Read defensively: a malformed grid (short data) renders as unknown, not a panic.
            let value = grid
                .data
                .get(row as usize * grid.width as usize + col as usize)
                .copied();
            let colour = match value {
                Some(v) if (0..50).contains(&v) && unsearched(col, row) => UNSEARCHED,
                Some(v) if v >= 0 => {
                    let t = v.min(100) as f64 / 100.0;
                    // Dark walls, light free space, with a visible step at 50 %.
                    let t = if t >= 0.5 { 0.75 + 0.25 * t } else { 0.5 * t };
                    Rgb(std::array::from_fn(|i| {
                        (FREE[i] + (WALL[i] - FREE[i]) * t) as u8
                    }))
                }
                _ => UNKNOWN,
            };
            let top = (h - 1 - row) * scale;
            for dy in 0..scale {
                for dx in 0..scale {
                    img.put_pixel(col * scale + dx, top + dy, colour);
                }
            }
        }
    }
    let px_per_m = scale as f64 / grid.resolution;
    let to_px = |x: f64, y: f64| {
        (
            (x - grid.origin.x()) * px_per_m,
            (h * scale) as f64 - (y - grid.origin.y()) * px_per_m,
        )
    };
    let thick = (scale as f64 * 0.6).max(1.2);

    for (rect, tint) in layers.areas {
        let (x0, y0) = to_px(rect.x0, rect.y1);
        let (x1, y1) = to_px(rect.x1, rect.y0);
        for y in y0.max(0.0) as u32..(y1.max(0.0) as u32).min(img.height()) {
            for x in x0.max(0.0) as u32..(x1.max(0.0) as u32).min(img.width()) {
                let p = img.get_pixel_mut(x, y);
                *p = Rgb(std::array::from_fn(|i| {
                    (p.0[i] as f64 * 0.65 + tint[i] as f64 * 0.35) as u8
                }));
            }
        }
    }

    for pair in layers.path.windows(2) {
        line(
            &mut img,
            to_px(pair[0].0.x, pair[0].0.y),
            to_px(pair[1].0.x, pair[1].0.y),
            thick * 0.5,
            Rgb([40, 170, 80]),
        );
    }
    let n = layers.trajectory.len().max(2) as f64;
    let coloured = layers.trajectory_colours.len() == layers.trajectory.len();
    for (i, pair) in layers.trajectory.windows(2).enumerate() {
        let t = i as f64 / (n - 2.0).max(1.0);
        let c = match coloured {
            true => Rgb(layers.trajectory_colours[i + 1]),
            false => Rgb([
                (30.0 + 225.0 * t) as u8,
                (90.0 + 50.0 * t) as u8,
                (220.0 - 200.0 * t) as u8,
            ]),
        };
        line(
            &mut img,
            to_px(pair[0].0.x, pair[0].0.y),
            to_px(pair[1].0.x, pair[1].0.y),
            thick,
            c,
        );
    }
    for track in layers.tracks {
        for pair in track.points.windows(2) {
            let (a, b) = (
                to_px(pair[0].0.x, pair[0].0.y),
                to_px(pair[1].0.x, pair[1].0.y),
            );
            line(&mut img, a, b, thick, Rgb(track.colour));
        }
        if let Some(end) = track.points.last() {
            let c = to_px(end.0.x, end.0.y);
            let r = (0.25 * px_per_m).max(4.0);
            disc(&mut img, c, r, Rgb(track.colour));
            if track.stopped {
                let black = Rgb([0, 0, 0]);
                line(
                    &mut img,
                    (c.0 - r, c.1 - r),
                    (c.0 + r, c.1 + r),
                    thick,
                    black,
                );
                line(
                    &mut img,
                    (c.0 - r, c.1 + r),
                    (c.0 + r, c.1 - r),
                    thick,
                    black,
                );
            }
        }
    }
    let ring = (0.3 * px_per_m).max(4.0);
    for (i, g) in layers.goals.iter().enumerate() {
        let c = to_px(g.x(), g.y());
        disc(&mut img, c, ring, Rgb([205, 30, 45]));
        let inner = if i < layers.reached {
            ring * 0.35
        } else {
            ring * 0.7
        };
        disc(&mut img, c, inner, Rgb([255, 255, 255]));
        // Goal order as small dots under the ring: one dot per index.
        for k in 0..=i {
            disc(
                &mut img,
                (c.0 - ring + k as f64 * ring * 0.6, c.1 + ring * 1.5),
                (ring * 0.2).max(1.5),
                Rgb([205, 30, 45]),
            );
        }
    }
    for (v, found) in layers.victims {
        let c = to_px(v.0.x, v.0.y);
        let colour = if *found {
            Rgb([20, 160, 60])
        } else {
            Rgb([215, 30, 40])
        };
        disc(&mut img, c, ring, colour);
        disc(&mut img, c, ring * 0.6, Rgb([255, 255, 255]));
    }
    for r in layers.reported {
        disc(
            &mut img,
            to_px(r.0.x, r.0.y),
            (ring * 0.3).max(2.0),
            Rgb([0, 0, 0]),
        );
    }
    if let Some((pose, radius)) = layers.robot {
        let c = to_px(pose.x(), pose.y());
        let r = (radius * px_per_m).max(3.0);
        disc(&mut img, c, r, Rgb([0, 128, 128]));
        let tip = (c.0 + r * pose.theta().cos(), c.1 - r * pose.theta().sin());
        line(&mut img, c, tip, (r * 0.25).max(1.0), Rgb([255, 255, 255]));
    }
    img
}

/// Renders and writes a PNG file (to a temporary file renamed into place).
pub fn save_png(path: &Path, grid: &OccupancyGrid, layers: &RenderLayers) -> std::io::Result<()> {
    let mut png = Vec::new();
    render(grid, layers)
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(std::io::Error::other)?;
    // Whole or not at all: a full disk or a kill mid-write never leaves half a picture.
    petrel_actors::files::write_atomically(path, &png)
}

fn disc(img: &mut RgbImage, (cx, cy): (f64, f64), r: f64, colour: Rgb<u8>) {
    let (x0, x1) = ((cx - r).floor().max(0.0) as i64, (cx + r).ceil() as i64);
    let (y0, y1) = ((cy - r).floor().max(0.0) as i64, (cy + r).ceil() as i64);
    for y in y0..=y1.min(img.height() as i64 - 1) {
        for x in x0..=x1.min(img.width() as i64 - 1) {
            let (dx, dy) = (x as f64 + 0.5 - cx, y as f64 + 0.5 - cy);
            if dx * dx + dy * dy <= r * r {
                img.put_pixel(x as u32, y as u32, colour);
            }
        }
    }
}

fn line(img: &mut RgbImage, a: (f64, f64), b: (f64, f64), width: f64, colour: Rgb<u8>) {
    let len = (b.0 - a.0).hypot(b.1 - a.1);
    let steps = (len * 2.0).ceil().max(1.0) as usize;
    for i in 0..=steps {
        let t = i as f64 / steps as f64;
        disc(
            img,
            (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t),
            width / 2.0,
            colour,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_cells_upside_up_and_draws_layers() {
        let data: Vec<i8> = vec![100, 0, -1, 0, 0, 0];
        let grid = OccupancyGrid {
            width: 3,
            height: 2,
            resolution: 1.0,
            origin: Pose2::default(),
            data: data.into(),
        };
        let img = render(
            &grid,
            &RenderLayers {
                scale: Some(10),
                ..RenderLayers::default()
            },
        );
        assert_eq!(img.dimensions(), (30, 20));
        // Cell (0, 0) is the bottom-left: dark; cell (2, 0) unknown grey; top row free.
        assert_eq!(*img.get_pixel(5, 15), Rgb([38, 41, 54]));
        assert_eq!(*img.get_pixel(25, 15), UNKNOWN);
        assert_eq!(*img.get_pixel(5, 5), Rgb([246, 244, 238]));
        // With a searched map: the free cells not searched are tinted, walls and unknown not.
        let searched = OccupancyGrid {
            data: vec![-1, 0, -1, -1, 0, 0].into(),
            ..grid.clone()
        };
        let img = render(
            &grid,
            &RenderLayers {
                scale: Some(10),
                searched: Some(&searched),
                ..RenderLayers::default()
            },
        );
        assert_eq!(
            *img.get_pixel(5, 15),
            Rgb([38, 41, 54]),
            "a wall stays a wall"
        );
        assert_eq!(
            *img.get_pixel(15, 15),
            Rgb([246, 244, 238]),
            "searched floor"
        );
        assert_eq!(*img.get_pixel(25, 15), UNKNOWN);
        assert_eq!(*img.get_pixel(5, 5), UNSEARCHED, "floor not searched");
        let traj = [Point2::new(0.5, 1.5), Point2::new(2.5, 1.5)];
        let layers = RenderLayers {
            trajectory: &traj,
            robot: Some((Pose2::new(2.5, 0.5, 0.0), 0.3)),
            scale: Some(10),
            ..RenderLayers::default()
        };
        let img = render(&grid, &layers);
        assert_ne!(
            *img.get_pixel(15, 5),
            Rgb([246, 244, 238]),
            "trajectory drawn"
        );
        assert_eq!(*img.get_pixel(23, 15), Rgb([0, 128, 128]), "robot drawn");
    }
}
