//! The team scaling plot (docs/team-scaling.png), drawn pixel by pixel with the `image`
//! crate the world picture uses: four panels (victims found, wall time, CPU per simulated
//! second, transport bytes per second), each a line over 1, 2, 4 and 8 robots (evenly spaced:
//! a log2 axis) from 0 to its largest value, with grid lines at quarters. Values and labels
//! are in BENCHMARKS.md's table; the picture shows the shapes.

use std::path::Path;

use image::{Rgb, RgbImage};

const PANEL: (u32, u32) = (360, 240);
const MARGIN: u32 = 30;
const COLOURS: [[u8; 3]; 4] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [148, 103, 189],
];

/// Writes the four `series` (one value per team size) as a 2 x 2 grid of panels.
pub fn save(path: &Path, series: &[Vec<f64>; 4]) -> std::io::Result<()> {
    let mut img = RgbImage::from_pixel(PANEL.0 * 2, PANEL.1 * 2, Rgb([255, 255, 255]));
    for (i, values) in series.iter().enumerate() {
        let origin = ((i as u32 % 2) * PANEL.0, (i as u32 / 2) * PANEL.1);
        panel(&mut img, origin, values, Rgb(COLOURS[i]));
    }
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(std::io::Error::other)?;
    std::fs::write(path, png)
}

fn panel(img: &mut RgbImage, (ox, oy): (u32, u32), values: &[f64], colour: Rgb<u8>) {
    let (w, h) = (PANEL.0 - 2 * MARGIN, PANEL.1 - 2 * MARGIN);
    let (x0, y0) = (ox + MARGIN, oy + MARGIN);
    let grey = Rgb([220, 220, 220]);
    for q in 0..=4 {
        let y = y0 + h - h * q / 4;
        hline(
            img,
            x0,
            x0 + w,
            y,
            if q == 0 { Rgb([0, 0, 0]) } else { grey },
        );
    }
    for x in y0..=y0 + h {
        img.put_pixel(x0, x, Rgb([0, 0, 0]));
    }
    let max = values
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    if max <= 0.0 {
        return;
    }
    let step = w / (values.len().max(2) as u32 - 1);
    let at = |i: usize, v: f64| {
        let x = (x0 + step * i as u32) as f64;
        let y = (y0 + h) as f64 - v / max * h as f64 * 0.95;
        (x, y)
    };
    for (i, pair) in values.windows(2).enumerate() {
        if pair.iter().all(|v| v.is_finite()) {
            segment(img, at(i, pair[0]), at(i + 1, pair[1]), colour);
        }
    }
    for (i, v) in values.iter().enumerate() {
        let x = x0 + step * i as u32;
        for t in 0..6 {
            img.put_pixel(x, y0 + h + t, Rgb([0, 0, 0]));
        }
        if v.is_finite() {
            let (cx, cy) = at(i, *v);
            for dy in -3i32..=3 {
                for dx in -3i32..=3 {
                    if dx * dx + dy * dy <= 9 {
                        put(img, cx as i32 + dx, cy as i32 + dy, colour);
                    }
                }
            }
        }
    }
}

fn hline(img: &mut RgbImage, x0: u32, x1: u32, y: u32, colour: Rgb<u8>) {
    for x in x0..=x1 {
        img.put_pixel(x, y, colour);
    }
}

fn segment(img: &mut RgbImage, a: (f64, f64), b: (f64, f64), colour: Rgb<u8>) {
    let n = ((b.0 - a.0).abs().max((b.1 - a.1).abs()) * 2.0).ceil() as i32;
    for s in 0..=n {
        let t = s as f64 / n.max(1) as f64;
        let (x, y) = (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
        for d in -1..=1 {
            put(img, x as i32, y as i32 + d, colour);
        }
    }
}

fn put(img: &mut RgbImage, x: i32, y: i32, colour: Rgb<u8>) {
    if x >= 0 && y >= 0 && (x as u32) < img.width() && (y as u32) < img.height() {
        img.put_pixel(x as u32, y as u32, colour);
    }
}
