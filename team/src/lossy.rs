//! Degraded copies of big payloads for links that ask for `lossy: true` (maps and images sent
//! for display): half the resolution each way, a quarter of the bytes.

use std::sync::Arc;

use petrel_actors::{AnyValue, Image, OccupancyGrid};

/// The value to send on a lossy link: images and grids halved, anything else as it is.
pub fn degrade(value: &AnyValue) -> AnyValue {
    if let Some(image) = value.downcast_ref::<Image>() {
        return Arc::new(halve_image(image));
    }
    if let Some(grid) = value.downcast_ref::<OccupancyGrid>() {
        return Arc::new(halve_grid(grid));
    }
    value.clone()
}

fn halve_image(image: &Image) -> Image {
    let (w, h) = (image.width as usize, image.height as usize);
    let channels = image.data.len().checked_div(w * h).unwrap_or(1).max(1);
    let (nw, nh) = (w / 2, h / 2);
    let mut data = Vec::with_capacity(nw * nh * channels);
    for y in 0..nh {
        for x in 0..nw {
            for c in 0..channels {
                let at = |dx: usize, dy: usize| {
                    image
                        .data
                        .get(((2 * y + dy) * w + 2 * x + dx) * channels + c)
                        .copied()
                        .unwrap_or(0) as u16
                };
                data.push(((at(0, 0) + at(1, 0) + at(0, 1) + at(1, 1)) / 4) as u8);
            }
        }
    }
    Image {
        width: nw as u32,
        height: nh as u32,
        data: data.into(),
        ..image.clone()
    }
}

fn halve_grid(grid: &OccupancyGrid) -> OccupancyGrid {
    let (w, h) = (grid.width as usize, grid.height as usize);
    let (nw, nh) = (w / 2, h / 2);
    let mut data = Vec::with_capacity(nw * nh);
    for y in 0..nh {
        for x in 0..nw {
            // The most occupied of four cells: a halved map never hides an obstacle.
            let cells = [(0, 0), (1, 0), (0, 1), (1, 1)].map(|(dx, dy)| {
                grid.data
                    .get((2 * y + dy) * w + 2 * x + dx)
                    .copied()
                    .unwrap_or(-1)
            });
            data.push(cells.into_iter().max().unwrap_or(-1));
        }
    }
    OccupancyGrid {
        width: nw as u32,
        height: nh as u32,
        resolution: grid.resolution * 2.0,
        data: data.into(),
        ..grid.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_keep_obstacles_and_images_average() {
        let grid = OccupancyGrid {
            width: 4,
            height: 2,
            resolution: 0.1,
            data: vec![0, 0, -1, -1, 0, 100, -1, 0].into(),
            ..OccupancyGrid::default()
        };
        let half = halve_grid(&grid);
        assert_eq!((half.width, half.height, half.resolution), (2, 1, 0.2));
        assert_eq!(&*half.data, &[100, 0]);
        let image = Image {
            width: 2,
            height: 2,
            data: vec![0, 100, 200, 100].into(),
            ..Image::default()
        };
        let half = halve_image(&image);
        assert_eq!((half.width, half.height, &*half.data), (1, 1, &[100u8][..]));
    }
}
