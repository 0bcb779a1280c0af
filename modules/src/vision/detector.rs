//! Victim detection in grey images: victims wear a checkerboard, so a victim is a run of image
//! columns whose pixels alternate strongly from row to row.
//!
//! Per column of the region of interest, the mean absolute difference between vertically
//! adjacent pixels over its most textured rows is the column's *texture*. Walls, floor and
//! ceiling are smooth, so most columns hold only noise: the noise floor is the median
//! column's texture, or the column's own noise where that is higher (dark, amplified parts of
//! an image), and a column is a victim column when it rises above the floor by more than
//! `threshold` grey levels, all the way from the horizon to the victim's foot. Runs of at least
//! [`MIN_COLUMNS`] such columns are detections; the bearing comes from the run's centre
//! column, the range from the row where the textured band that runs down from the horizon
//! ends (where the victim meets the floor, seen from a camera [`CAMERA_HEIGHT`] above it). Nothing is faked: a dark image has little
//! contrast left, a blurred one has its squares averaged away, and both are missed. `deblur`
//! sharpens first (unsharp masking, a real convolution per pixel), which restores some
//! contrast that mild blur took and also amplifies noise.

use serde::{Deserialize, Serialize};

use crate::sim::camera::{CAMERA_HEIGHT, CHECKER, VICTIM_RADIUS};

/// Fewest adjacent textured columns that make a detection.
pub const MIN_COLUMNS: usize = 3;
/// A column's noise texture, in multiples of its lower-quartile row-to-row difference (pure
/// noise averages about 2.5 of it over a window; the most textured window more). The lower
/// quartile, not the median: a near victim fills most of its columns' rows, and the shot
/// noise of its bright squares, amplified in the dark, would raise a median to its own
/// texture.
const NOISE_FACTOR: f64 = 4.2;
/// Rows over which a column's texture is averaged (a victim 3.5 m away is 12 rows high).
const WINDOW: usize = 10;
/// Textured runs this close (columns) are one victim: checker squares leave gaps.
const MERGE_GAP: usize = 4;
/// Untextured rows inside a victim, in checker squares, beyond which its textured band has
/// ended (its squares' edges are textured; blur may fade one).
const FOOT_GAP_SQUARES: f64 = 1.5;

/// Detector parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct DetectorParams {
    /// Texture above the noise floor that marks a victim column, grey levels (default 12).
    pub threshold: f64,
    /// Sharpening amount before detection, 0 = off (default 0).
    pub deblur: f64,
    /// Region of interest as fractions of the image `[x0, y0, x1, y1]`, top-left origin
    /// (default: the lower half, where victims on the floor appear).
    pub roi: [f64; 4],
    /// Horizontal field of view of the camera, radians.
    pub fov: f64,
}

impl Default for DetectorParams {
    fn default() -> Self {
        DetectorParams {
            threshold: 12.0,
            deblur: 0.0,
            roi: [0.0, 0.5, 1.0, 1.0],
            fov: 60f64.to_radians(),
        }
    }
}

impl DetectorParams {
    /// Checks every parameter; the error names the parameter.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.threshold > 0.0 && self.threshold <= 255.0) {
            return Err(format!(
                "`params/threshold`: expected grey levels in (0, 255], got {}",
                self.threshold
            ));
        }
        if !(0.0..=4.0).contains(&self.deblur) {
            return Err(format!(
                "`params/deblur`: expected an amount in [0, 4], got {}",
                self.deblur
            ));
        }
        let [x0, y0, x1, y1] = self.roi;
        if !(0.0 <= x0 && x0 < x1 && x1 <= 1.0 && 0.0 <= y0 && y0 < y1 && y1 <= 1.0) {
            return Err(format!("`params/roi`: expected fractions [x0, y0, x1, y1] with 0 <= x0 < x1 <= 1 and 0 <= y0 < y1 <= 1, got {:?}", self.roi));
        }
        if !(self.fov > 0.0 && self.fov < std::f64::consts::PI) {
            return Err(format!(
                "`params/fov_deg`: expected degrees in (0, 180), got {}",
                self.fov.to_degrees()
            ));
        }
        Ok(())
    }
}

/// One victim seen in one image.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Detection {
    /// Direction in the camera frame, radians (left positive).
    pub bearing: f64,
    /// Distance from the camera to the victim's centre, metres.
    pub range: f64,
    /// How far above the threshold the texture was, 0..1.
    pub confidence: f64,
}

/// The detections of one image, as a property (`vision.victim_detector`'s `out/detections`).
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct Detections(pub Vec<Detection>);

impl petrel_actors::PropertyType for Detections {
    const TYPE_NAME: &'static str = "vision.Detections";
}

/// What one image gave.
#[derive(Clone, Debug, PartialEq)]
pub struct DetectorOutput {
    /// Victims seen.
    pub detections: Vec<Detection>,
    /// Mean grey level, 0..1.
    pub brightness: f64,
    /// Mean absolute Laplacian of the (sharpened) image, grey levels: falls with blur.
    pub sharpness: f64,
}

/// Detects victims in a `w` x `h` mono8 image; `None` if the buffer is not that size.
pub fn detect(pixels: &[u8], w: usize, h: usize, p: &DetectorParams) -> Option<DetectorOutput> {
    if w < 3 || h < 3 || pixels.len() != w * h {
        return None;
    }
    let mut img: Vec<f32> = pixels.iter().map(|&v| v as f32).collect();
    let brightness = img.iter().map(|&v| v as f64).sum::<f64>() / (w * h) as f64 / 255.0;
    if p.deblur > 0.0 {
        img = sharpen(&img, w, h, p.deblur as f32);
    }
    let sharpness = laplacian_mean(&img, w, h);
    let [x0, y0, x1, y1] = p.roi;
    let (c0, c1) = ((x0 * w as f64) as usize, ((x1 * w as f64) as usize).min(w));
    let (r0, r1) = (
        (y0 * h as f64) as usize,
        ((y1 * h as f64) as usize).min(h - 1),
    );
    let diff = |r: usize, c: usize| (img[r * w + c] - img[(r + 1) * w + c]).abs() as f64;
    // A victim fills only some rows of the region: a column's texture is that of its most
    // textured run of WINDOW rows, so a small victim is not averaged away by the floor.
    let window = WINDOW.min(r1 - r0).max(1);
    let raw: Vec<f64> = (c0..c1)
        .map(|c| {
            let diffs: Vec<f64> = (r0..r1).map(|r| diff(r, c)).collect();
            let mut sum: f64 = diffs[..window].iter().sum();
            let mut best = sum;
            for i in window..diffs.len() {
                sum += diffs[i] - diffs[i - window];
                best = best.max(sum);
            }
            best / window as f64
        })
        .collect();
    // Checker squares make the texture of neighbouring columns differ: smooth over three.
    let texture: Vec<f64> = (0..raw.len())
        .map(|i| {
            let window = &raw[i.saturating_sub(1)..(i + 2).min(raw.len())];
            window.iter().sum::<f64>() / window.len() as f64
        })
        .collect();
    // The noise floor: the texture most columns have (the median) or, where noise is
    // stronger (a dark, amplified part of the image beside a saturated one), the column's own
    // noise: its typical row-to-row difference, which a victim covering part of the column
    // does not move much.
    let mut sorted = texture.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
    let own_noise: Vec<f64> = (c0..c1)
        .map(|c| {
            let mut d: Vec<f64> = (r0..r1).map(|r| diff(r, c)).collect();
            d.sort_by(f64::total_cmp);
            NOISE_FACTOR * d.get(d.len() / 4).copied().unwrap_or(0.0)
        })
        .collect();
    let floor_of: Vec<f64> = (0..texture.len())
        .map(|i| {
            let window = &own_noise[i.saturating_sub(1)..(i + 2).min(own_noise.len())];
            median.max(window.iter().sum::<f64>() / window.len() as f64)
        })
        .collect();
    let threshold = p.threshold;
    let focal = w as f64 / 2.0 / (p.fov / 2.0).tan();
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let mut c = 0;
    while c < texture.len() {
        if texture[c] - floor_of[c] <= threshold {
            c += 1;
            continue;
        }
        let start = c;
        while c < texture.len() && texture[c] - floor_of[c] > threshold {
            c += 1;
        }
        match runs.last_mut() {
            Some(last) if start - last.1 <= MERGE_GAP => last.1 = c,
            _ => runs.push((start, c)),
        }
    }
    let mut detections = Vec::new();
    for (start, c) in runs {
        // A victim cut by the image border is left for a later frame, where it is whole (its
        // centre and so its bearing would be wrong, and the border columns are the least
        // reliable: sharpening cannot reach them).
        if c - start < MIN_COLUMNS || start == 0 || c == texture.len() {
            continue;
        }
        let cols = (start + c0)..(c + c0);
        let floor = floor_of[start..c].iter().sum::<f64>() / (c - start) as f64;
        let excess = texture[start..c].iter().map(|t| t - floor).sum::<f64>() / (c - start) as f64;
        // Row by row across the run: checker edges stand out, rows inside a square hold only
        // noise. The foot is the last row standing out from the columns' floor (a lower
        // reference takes noisy rows of floor for feet). The band is measured against the
        // noise a row holds, the median row, where that is below the floor: the floor is the
        // most textured window, and a near victim's tall squares leave so few edges in its
        // band that their mean would not stand out from it in a dark, amplified image.
        let row_lo = (h / 2).max(r0);
        let row_texture: Vec<f64> = (row_lo..r1)
            .map(|r| cols.clone().map(|cc| diff(r, cc)).sum::<f64>() / cols.len() as f64)
            .collect();
        let mut sorted_rows = row_texture.clone();
        sorted_rows.sort_by(f64::total_cmp);
        let row_noise = floor.min(
            sorted_rows
                .get(sorted_rows.len() / 2)
                .copied()
                .unwrap_or(floor),
        );
        let textured = |r: usize| row_texture[r - row_lo] > floor + threshold;
        let Some(bottom) = foot_row(textured, row_lo, r1, h / 2, cols.len()) else {
            continue;
        };
        let below_horizon = bottom as f64 + 1.0 - h as f64 / 2.0;
        if below_horizon < 3.0 {
            continue;
        }
        // A victim is textured all the way from the horizon (the camera's height, its top)
        // down to its foot; an edge or a corner is textured in a row or two.
        let band = &row_texture[(h / 2).saturating_sub(row_lo)..bottom - row_lo];
        let band_texture = band.iter().sum::<f64>() / band.len().max(1) as f64;
        if band_texture - row_noise <= threshold {
            continue;
        }
        let centre = (cols.start + cols.end) as f64 / 2.0;
        let bearing = ((w as f64 / 2.0 - centre) / focal).atan();
        let axial = focal * CAMERA_HEIGHT / below_horizon;
        detections.push(Detection {
            bearing,
            range: axial / bearing.cos() + VICTIM_RADIUS,
            confidence: ((excess - threshold) / threshold).clamp(0.0, 1.0),
        });
    }
    Some(DetectorOutput {
        detections,
        brightness,
        sharpness,
    })
}

/// The victim's foot: the lowest row of the textured band that runs down from `from`, rows
/// `from..to`, where `textured` says whether a row's texture stands out; `horizon` is the
/// horizon's row and `width` the run's width in columns.
///
/// The band is followed down rather than the lowest textured row taken: a checkerboard is
/// textured at every edge between squares, so a gap of untextured rows longer than a square
/// or so is the floor in front of the victim. A noisy row of floor further down (sharpening
/// amplifies noise) would otherwise be taken for the foot, and the victim placed metres short
/// of where it is: two such frames made a seventh, false victim in a rescue team's run.
///
/// How many rows a square spans depends on the victim's distance, which is what the foot
/// tells; two lower bounds serve instead, the larger taken: the run's width (a victim is
/// `2 * VICTIM_RADIUS` wide, a square `CHECKER` high, so a run of a whole victim gives its
/// squares' height; a victim partly hidden gives less), and the depth below the horizon the
/// band has reached (the foot is at least that low, so the victim at most that far).
fn foot_row(
    textured: impl Fn(usize) -> bool,
    from: usize,
    to: usize,
    horizon: usize,
    width: usize,
) -> Option<usize> {
    let by_width = CHECKER / (2.0 * VICTIM_RADIUS) * width as f64;
    let mut foot: Option<usize> = None;
    for r in from..to {
        if textured(r) {
            foot = Some(r);
            continue;
        }
        let Some(end) = foot else { continue };
        let by_depth = CHECKER / CAMERA_HEIGHT * (end + 1).saturating_sub(horizon) as f64;
        let square_rows = by_width.max(by_depth);
        if (r - end) as f64 > 1.0 + (FOOT_GAP_SQUARES * square_rows).ceil() {
            break;
        }
    }
    foot
}

/// Unsharp masking: `img + amount * (img - 3x3 mean)`.
fn sharpen(img: &[f32], w: usize, h: usize, amount: f32) -> Vec<f32> {
    let mut out = img.to_vec();
    for r in 1..h - 1 {
        for c in 1..w - 1 {
            let mut sum = 0.0;
            for dr in 0..3 {
                let row = (r + dr - 1) * w;
                sum += img[row + c - 1] + img[row + c] + img[row + c + 1];
            }
            let v = img[r * w + c];
            out[r * w + c] = (v + amount * (v - sum / 9.0)).clamp(0.0, 255.0);
        }
    }
    out
}

/// Mean absolute 4-neighbour Laplacian over the interior.
fn laplacian_mean(img: &[f32], w: usize, h: usize) -> f64 {
    let mut sum = 0.0f64;
    for r in 1..h - 1 {
        for c in 1..w - 1 {
            let i = r * w + c;
            let lap = 4.0 * img[i] - img[i - 1] - img[i + 1] - img[i - w] - img[i + w];
            sum += lap.abs() as f64;
        }
    }
    sum / ((w - 2) * (h - 2)) as f64
}

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_mapping;
