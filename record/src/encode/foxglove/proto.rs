//! `foxglove.Grid`, `foxglove.LaserScan`, `foxglove.PoseInFrame` and `foxglove.RawImage` as
//! protobuf messages (schema encoding `protobuf`, [`super::descriptor`]): grid cells and image
//! pixels go as raw bytes and numbers as little-endian doubles, where JSON needs base64 text
//! and a decimal per float.

use std::sync::Arc;

use petrel_actors::{Image, LaserScan, OccupancyGrid, Pose2};

use crate::encode::protobuf::{
    bytes, double, doubles, fixed32, message, read_doubles, uint, Reader, Value,
};
use crate::encode::ros2::{heading, image_step, quaternion};
use crate::encode::Stamp;

/// `foxglove.PackedElementField`'s `INT8`.
const INT8: u64 = 2;

fn timestamp(out: &mut Vec<u8>, field: u32, stamp: Stamp) {
    message(out, field, |o| {
        uint(o, 1, u64::from(stamp.sec));
        uint(o, 2, u64::from(stamp.nsec));
    });
}

fn pose(out: &mut Vec<u8>, field: u32, p: &Pose2) {
    let [x, y, z, w] = quaternion(p.theta());
    message(out, field, |o| {
        message(o, 1, |v| {
            double(v, 1, p.x());
            double(v, 2, p.y());
        });
        message(o, 2, |q| {
            double(q, 1, x);
            double(q, 2, y);
            double(q, 3, z);
            double(q, 4, w);
        });
        double(o, 100, p.theta());
    });
}

fn read_pose(data: &[u8]) -> Result<Pose2, String> {
    let (mut xyz, mut q, mut theta) = ([0.0; 3], [0.0; 4], None);
    Reader::new(data).each(|field, value| {
        match field {
            1 => read_doubles_into(value.len()?, &mut xyz)?,
            2 => read_doubles_into(value.len()?, &mut q)?,
            100 => theta = Some(value.f64()?),
            _ => {}
        }
        Ok(())
    })?;
    Ok(Pose2::new(
        xyz[0],
        xyz[1],
        theta.unwrap_or_else(|| heading(q)),
    ))
}

/// Fields 1..=N of a message of doubles (a `Vector3`, a `Quaternion`) into `into`.
fn read_doubles_into(data: &[u8], into: &mut [f64]) -> Result<(), String> {
    Reader::new(data).each(|field, value| {
        if let Some(slot) = into.get_mut((field as usize).wrapping_sub(1)) {
            *slot = value.f64()?;
        }
        Ok(())
    })
}

/// Encodes a grid as `foxglove.Grid` with one `INT8` field, `occupancy`.
pub fn grid(out: &mut Vec<u8>, g: &OccupancyGrid, stamp: Stamp, frame: &str) {
    // Cells are `INT8`: their bytes, without a copy before the message's.
    let cells: &[u8] = bytemuck::cast_slice(&g.data);
    out.reserve(cells.len() + 160);
    timestamp(out, 1, stamp);
    bytes(out, 2, frame.as_bytes());
    pose(out, 3, &g.origin);
    fixed32(out, 4, g.width);
    message(out, 5, |o| {
        double(o, 1, g.resolution);
        double(o, 2, g.resolution);
    });
    fixed32(out, 6, g.width);
    fixed32(out, 7, 1);
    message(out, 8, |o| {
        bytes(o, 1, b"occupancy");
        uint(o, 3, INT8);
    });
    bytes(out, 9, cells);
}

/// Decodes a `foxglove.Grid` of one `INT8` field per cell.
pub fn read_grid(data: &[u8]) -> Result<OccupancyGrid, String> {
    let (mut columns, mut row_stride, mut cell_stride) = (0, 0, 0);
    let (mut cell_size, mut origin, mut cells) = ([0.0; 2], Pose2::default(), &[][..]);
    Reader::new(data)
        .each(|field, value| {
            match field {
                3 => origin = read_pose(value.len()?)?,
                4 => columns = value.u32()?,
                5 => read_doubles_into(value.len()?, &mut cell_size)?,
                6 => row_stride = value.u32()?,
                7 => cell_stride = value.u32()?,
                9 => cells = value.len()?,
                _ => {}
            }
            Ok(())
        })
        .map_err(|e| format!("expected a foxglove.Grid protobuf message: {e}"))?;
    if cell_stride != 1 || row_stride != columns {
        return Err(format!(
            "expected a grid of one byte per cell (cell_stride 1, row_stride = column_count {columns}), got cell_stride {cell_stride} and row_stride {row_stride}"
        ));
    }
    let height = super::rows(columns, cells.len())?;
    Ok(OccupancyGrid {
        width: columns,
        height,
        resolution: cell_size[0],
        origin,
        data: cells.iter().map(|&c| c as i8).collect::<Vec<_>>().into(),
    })
}

/// Encodes a scan as `foxglove.LaserScan` (with petrel's `range_max`).
pub fn laser_scan(out: &mut Vec<u8>, scan: &LaserScan, stamp: Stamp, frame: &str) {
    let n = scan.ranges.len();
    out.reserve(n * 8 + 120);
    timestamp(out, 1, stamp);
    bytes(out, 2, frame.as_bytes());
    pose(out, 3, &Pose2::default());
    double(out, 4, scan.angle_min);
    let end = scan.angle_min + scan.angle_increment * n.saturating_sub(1) as f64;
    double(out, 5, end);
    doubles(out, 6, &scan.ranges);
    double(out, 100, scan.range_max);
}

/// Decodes a `foxglove.LaserScan`.
pub fn read_laser_scan(data: &[u8]) -> Result<LaserScan, String> {
    let (mut start, mut end, mut range_max, mut ranges) = (0.0, 0.0, 0.0, Vec::new());
    Reader::new(data)
        .each(|field, value| {
            match field {
                4 => start = value.f64()?,
                5 => end = value.f64()?,
                // Packed, or (as proto readers must also accept) one double per field.
                6 => match value {
                    Value::Len(b) => ranges.extend(read_doubles(b)?),
                    v => ranges.push(v.f64()?),
                },
                100 => range_max = value.f64()?,
                _ => {}
            }
            Ok(())
        })
        .map_err(|e| format!("expected a foxglove.LaserScan protobuf message: {e}"))?;
    let increment = match ranges.len() {
        0 | 1 => 0.0,
        n => (end - start) / (n - 1) as f64,
    };
    Ok(LaserScan {
        angle_min: start,
        angle_increment: increment,
        range_max,
        ranges: ranges.into(),
    })
}

/// Encodes a pose as `foxglove.PoseInFrame`.
pub fn pose_in_frame(out: &mut Vec<u8>, p: &Pose2, stamp: Stamp, frame: &str) {
    timestamp(out, 1, stamp);
    bytes(out, 2, frame.as_bytes());
    pose(out, 3, p);
}

/// Decodes a `foxglove.PoseInFrame`.
pub fn read_pose_in_frame(data: &[u8]) -> Result<Pose2, String> {
    let mut p = Pose2::default();
    Reader::new(data)
        .each(|field, value| {
            if field == 3 {
                p = read_pose(value.len()?)?;
            }
            Ok(())
        })
        .map_err(|e| format!("expected a foxglove.PoseInFrame protobuf message: {e}"))?;
    Ok(p)
}

/// Encodes an image as `foxglove.RawImage`.
pub fn raw_image(out: &mut Vec<u8>, img: &Image, stamp: Stamp, frame: &str) {
    out.reserve(img.data.len() + 80);
    timestamp(out, 1, stamp);
    bytes(out, 7, frame.as_bytes());
    fixed32(out, 2, img.width);
    fixed32(out, 3, img.height);
    bytes(out, 4, img.encoding.as_bytes());
    fixed32(out, 5, image_step(img));
    bytes(out, 6, &img.data);
}

/// Decodes a `foxglove.RawImage`.
pub fn read_raw_image(data: &[u8]) -> Result<Image, String> {
    let (mut width, mut height, mut encoding, mut pixels) = (0, 0, String::new(), &[][..]);
    Reader::new(data)
        .each(|field, value| {
            match field {
                2 => width = value.u32()?,
                3 => height = value.u32()?,
                4 => {
                    encoding = String::from_utf8(value.len()?.to_vec())
                        .map_err(|e| format!("expected a UTF-8 encoding name: {e}"))?
                }
                6 => pixels = value.len()?,
                _ => {}
            }
            Ok(())
        })
        .map_err(|e| format!("expected a foxglove.RawImage protobuf message: {e}"))?;
    Ok(Image {
        width,
        height,
        encoding,
        data: Arc::from(pixels),
    })
}
