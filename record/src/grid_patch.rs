//! Occupancy grids recorded as patches, without actors or files: a mapper writes its whole
//! grid at every scan (200 grids of 40,000 cells per virtual second of `configs/navigate.ron`)
//! although a scan changes about 130 cells, inside a rectangle of about 15 % of the grid. The
//! recorder writes such a write as the rectangle of cells that changed since the previous write
//! (a grid of its own, its origin at the rectangle's corner, on the channel `TOPIC/_patches`),
//! and the whole grid now and then ([`GridPatcher`]). Every write is in the file, with its own
//! sequence and times; [`paste`] puts the grid back together when a recording is read.

use std::sync::Arc;
use std::time::Duration;

use petrel_actors::{OccupancyGrid, Pose2};

/// The whole grid again once the patches since the last whole one hold this many grids' worth
/// of cells: a reader rebuilding a grid never reads more than this many times its size.
pub const FULL_EVERY_GRIDS: u64 = 4;

/// The whole grid again once this much publish time has passed since the last whole one, so a
/// viewer that shows only the grid channel (Foxglove's 3D panel) lags by at most this.
pub const FULL_EVERY: Duration = Duration::from_secs(1);

/// The suffix of a grid channel's topic that names its patch channel.
pub const PATCH_SUFFIX: &str = "/_patches";

/// A rectangle of cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    /// First column.
    pub col: u32,
    /// First row.
    pub row: u32,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
}

impl Rect {
    fn cells(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height)
    }
}

/// Whether `a` and `b` lie on the same cells (size, resolution, origin): only then is one a
/// patch of the other.
pub fn same_geometry(a: &OccupancyGrid, b: &OccupancyGrid) -> bool {
    a.width == b.width
        && a.height == b.height
        && a.resolution == b.resolution
        && a.origin == b.origin
        && a.data.len() == b.data.len()
}

/// The smallest rectangle holding every cell where `new` differs from `old` (grids of the same
/// geometry), or `None` when no cell does.
pub fn changed_rect(old: &OccupancyGrid, new: &OccupancyGrid) -> Option<Rect> {
    let w = new.width as usize;
    if w == 0 || old.data.len() != new.data.len() {
        return None;
    }
    // Whole rows compare as slices (a `memcmp`); only rows that differ are searched by cell.
    let rows = old.data.chunks_exact(w).zip(new.data.chunks_exact(w));
    let (mut first_row, mut last_row) = (usize::MAX, 0);
    let (mut first_col, mut last_col) = (usize::MAX, 0);
    for (r, (a, b)) in rows.enumerate() {
        if a == b {
            continue;
        }
        first_row = first_row.min(r);
        last_row = r;
        let first = a.iter().zip(b).position(|(x, y)| x != y).unwrap_or(0);
        let last = a.iter().zip(b).rposition(|(x, y)| x != y).unwrap_or(0);
        first_col = first_col.min(first);
        last_col = last_col.max(last);
    }
    (first_row != usize::MAX).then(|| Rect {
        col: first_col as u32,
        row: first_row as u32,
        width: (last_col - first_col + 1) as u32,
        height: (last_row - first_row + 1) as u32,
    })
}

/// The cells of `rect` (inside `grid`) as a grid of their own: same resolution and heading,
/// its origin the world pose of the rectangle's corner.
pub fn cut(grid: &OccupancyGrid, rect: Rect) -> OccupancyGrid {
    let w = grid.width as usize;
    let (c0, c1) = (rect.col as usize, (rect.col + rect.width) as usize);
    let data: Arc<[i8]> = (rect.row as usize..(rect.row + rect.height) as usize)
        .flat_map(|r| &grid.data[r * w + c0..r * w + c1])
        .copied()
        .collect();
    let offset = Pose2::new(
        f64::from(rect.col) * grid.resolution,
        f64::from(rect.row) * grid.resolution,
        0.0,
    );
    OccupancyGrid {
        width: rect.width,
        height: rect.height,
        resolution: grid.resolution,
        origin: Pose2(grid.origin.0 * offset.0),
        data,
    }
}

/// Where `patch` lies in `base`: its origin's cell, from its pose (rounded: the recorded poses
/// are the corner's, a float's error away from a cell corner). An error says why it does not fit.
pub fn place(base: &OccupancyGrid, patch: &OccupancyGrid) -> Result<Rect, String> {
    let res = base.resolution;
    if !(res > 0.0) || (patch.resolution - res).abs() > res * 1e-6 {
        return Err(format!(
            "a patch of cells of {} m in a grid of cells of {} m",
            patch.resolution, res
        ));
    }
    if (patch.origin.theta() - base.origin.theta()).abs() > 1e-6 {
        return Err("a patch turned against its grid".into());
    }
    let local = base.origin.0.inverse() * patch.origin.0;
    let (col, row) = (
        (local.translation.x / res).round(),
        (local.translation.y / res).round(),
    );
    let fits = col >= 0.0
        && row >= 0.0
        && col + f64::from(patch.width) <= f64::from(base.width)
        && row + f64::from(patch.height) <= f64::from(base.height);
    if !fits || patch.data.len() as u64 != u64::from(patch.width) * u64::from(patch.height) {
        return Err(format!(
            "a patch of {}x{} cells at cell ({col}, {row}) outside a grid of {}x{}",
            patch.width, patch.height, base.width, base.height
        ));
    }
    Ok(Rect {
        col: col as u32,
        row: row as u32,
        width: patch.width,
        height: patch.height,
    })
}

/// `base` with `patch`'s cells in place of its own.
pub fn paste(base: &OccupancyGrid, patch: &OccupancyGrid) -> Result<OccupancyGrid, String> {
    let rect = place(base, patch)?;
    let mut data = base.data.to_vec();
    let (w, pw) = (base.width as usize, patch.width as usize);
    if pw > 0 {
        for (i, cells) in patch.data.chunks_exact(pw).enumerate() {
            let start = (rect.row as usize + i) * w + rect.col as usize;
            data[start..start + pw].copy_from_slice(cells);
        }
    }
    Ok(OccupancyGrid {
        data: data.into(),
        ..base.clone()
    })
}

/// How one grid write is recorded.
#[derive(Debug, PartialEq)]
pub enum GridWrite {
    /// The whole grid, on the grid's channel.
    Full,
    /// These cells, on the patch channel.
    Patch(OccupancyGrid),
}

/// Decides, write by write, whether a grid channel records the whole grid or a patch of the
/// cells changed since the previous write; one per grid channel and file (a file starts with
/// a whole grid, so each file of a split recording reads alone).
#[derive(Debug, Default)]
pub struct GridPatcher {
    /// The previous write.
    last: Option<OccupancyGrid>,
    /// Cells written as patches since the last whole grid.
    patched_cells: u64,
    /// Publish time of the last whole grid, ns.
    full_ns: u64,
}

impl GridPatcher {
    /// How to record `grid`, published at `publish_ns`.
    pub fn next(&mut self, grid: &OccupancyGrid, publish_ns: u64) -> GridWrite {
        let write = self.choose(grid, publish_ns);
        match &write {
            GridWrite::Full => {
                self.patched_cells = 0;
                self.full_ns = publish_ns;
            }
            GridWrite::Patch(p) => self.patched_cells += u64::from(p.width * p.height),
        }
        self.last = Some(grid.clone());
        write
    }

    fn choose(&self, grid: &OccupancyGrid, publish_ns: u64) -> GridWrite {
        let Some(last) = self.last.as_ref().filter(|l| same_geometry(l, grid)) else {
            return GridWrite::Full;
        };
        let cells = grid.data.len() as u64;
        if publish_ns.saturating_sub(self.full_ns) >= FULL_EVERY.as_nanos() as u64 {
            return GridWrite::Full;
        }
        // An unchanged grid is still a write: one cell says so.
        let rect = changed_rect(last, grid).unwrap_or(Rect {
            col: 0,
            row: 0,
            width: 1,
            height: 1,
        });
        // A patch of more than half the grid saves less than a reader's rebuilding costs.
        if rect.cells() * 2 > cells || self.patched_cells + rect.cells() > FULL_EVERY_GRIDS * cells
        {
            return GridWrite::Full;
        }
        GridWrite::Patch(cut(grid, rect))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(width: u32, height: u32, origin: Pose2) -> OccupancyGrid {
        OccupancyGrid {
            width,
            height,
            resolution: 0.1,
            origin,
            data: (0..width * height).map(|i| (i % 101) as i8).collect(),
        }
    }

    fn with(g: &OccupancyGrid, cells: &[(u32, u32, i8)]) -> OccupancyGrid {
        let mut data = g.data.to_vec();
        for &(c, r, v) in cells {
            data[(r * g.width + c) as usize] = v;
        }
        OccupancyGrid {
            data: data.into(),
            ..g.clone()
        }
    }

    #[test]
    fn the_changed_rectangle_holds_every_changed_cell_and_no_more() {
        let a = grid(30, 20, Pose2::default());
        assert_eq!(changed_rect(&a, &a), None);
        let b = with(&a, &[(3, 4, -1), (17, 9, -1), (5, 12, -1)]);
        assert_eq!(
            changed_rect(&a, &b),
            Some(Rect {
                col: 3,
                row: 4,
                width: 15,
                height: 9
            })
        );
    }

    #[test]
    fn a_cut_patch_pastes_back_into_the_previous_grid_even_turned_and_moved() {
        for origin in [
            Pose2::default(),
            Pose2::new(-10.05, 3.3, 0.0),
            Pose2::new(2.0, -7.5, 0.7),
        ] {
            let a = grid(30, 20, origin);
            let b = with(&a, &[(0, 0, -1), (29, 19, 100), (12, 7, 55)]);
            let patch = cut(&b, changed_rect(&a, &b).unwrap());
            assert_eq!((patch.width, patch.height), (30, 20));
            assert_eq!(paste(&a, &patch).unwrap(), b);
            let c = with(&b, &[(12, 7, 3), (14, 9, 4)]);
            let patch = cut(&c, changed_rect(&b, &c).unwrap());
            assert_eq!((patch.width, patch.height), (3, 3));
            assert_eq!(paste(&b, &patch).unwrap(), c, "{origin:?}");
        }
    }

    #[test]
    fn a_patch_that_does_not_fit_is_refused_not_pasted() {
        let a = grid(30, 20, Pose2::default());
        let mut patch = cut(
            &a,
            Rect {
                col: 25,
                row: 0,
                width: 5,
                height: 2,
            },
        );
        patch.origin = Pose2::new(2.8, 0.0, 0.0);
        assert!(paste(&a, &patch).unwrap_err().contains("outside"));
        patch.origin = Pose2::new(2.5, 0.0, 0.0);
        patch.resolution = 0.2;
        assert!(paste(&a, &patch).unwrap_err().contains("cells of"));
    }

    #[test]
    fn the_patcher_writes_whole_grids_first_on_new_geometry_and_when_patches_add_up() {
        let mut p = GridPatcher::default();
        let a = grid(100, 100, Pose2::default());
        assert_eq!(p.next(&a, 0), GridWrite::Full);
        let mut last = a;
        let mut fulls = Vec::new();
        // Patches of 20x20 cells (400 of 10,000): 4 grids' worth after 100 of them.
        for i in 1..=110u64 {
            let g = with(&last, &[(10, 10, i as i8), (29, 29, i as i8)]);
            match p.next(&g, i) {
                GridWrite::Full => fulls.push(i),
                GridWrite::Patch(patch) => assert_eq!(paste(&last, &patch).unwrap(), g),
            }
            last = g;
        }
        assert_eq!(fulls, [101]);
        // An unchanged grid is a write too.
        assert!(matches!(p.next(&last, 111), GridWrite::Patch(_)));
        // After a second of publish time, or on a grid of another size: whole.
        assert_eq!(p.next(&last, 101 + 1_000_000_000), GridWrite::Full);
        assert_eq!(
            p.next(&grid(10, 10, Pose2::default()), 1_000_000_100),
            GridWrite::Full
        );
        // A change over more than half the grid: whole.
        let small = grid(10, 10, Pose2::default());
        let spread = with(&small, &[(0, 0, -1), (9, 9, -1)]);
        assert_eq!(p.next(&spread, 1_000_000_200), GridWrite::Full);
    }
}
