//! The costly parts of Foxglove JSON written without serde's generic paths, as the same bytes:
//! float arrays (zmij's shortest round-trip text, as serde_json writes them, `null` for NaN and
//! infinities, one reservation per array instead of serde's per-element writes) and base64.

/// base64 of grid cells and image pixels: the crate's SIMD engine (AVX2 or NEON, detected once
/// at run time, scalar otherwise), the same text as its scalar `STANDARD` engine at several
/// times its speed; the grids' base64 was the largest part of a Foxglove recording's encoding.
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
pub(super) static BASE64: std::sync::LazyLock<base64::engine::simd::Simd> =
    std::sync::LazyLock::new(|| {
        base64::engine::simd::Simd::standard(base64::engine::general_purpose::PAD)
    });
#[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
pub(super) static BASE64: base64::engine::GeneralPurpose =
    base64::engine::general_purpose::STANDARD;

/// The most bytes zmij writes for one `f64` (`-2.2250738585072014e-308` is 24).
const MAX_F64_TEXT: usize = 24;

/// Writes `x` as serde_json does.
pub(super) fn write_f64(out: &mut Vec<u8>, x: f64) {
    if x.is_finite() {
        out.extend_from_slice(zmij::Buffer::new().format_finite(x).as_bytes());
    } else {
        out.extend_from_slice(b"null");
    }
}

/// Writes `xs` as a JSON array, as serde_json writes a `Vec<f64>`.
pub(super) fn write_f64_array(out: &mut Vec<u8>, xs: &[f64]) {
    out.reserve(2 + xs.len() * (MAX_F64_TEXT + 1));
    out.push(b'[');
    let mut text = zmij::Buffer::new();
    for (i, &x) in xs.iter().enumerate() {
        if i > 0 {
            out.push(b',');
        }
        if x.is_finite() {
            out.extend_from_slice(text.format_finite(x).as_bytes());
        } else {
            out.extend_from_slice(b"null");
        }
    }
    out.push(b']');
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_are_the_bytes_serde_json_writes() {
        let xs = [
            0.0,
            -0.0,
            1.0,
            -1.5,
            0.1,
            1.0 / 3.0,
            1e16,
            1.5e-7,
            123456789.125,
            f64::MAX,
            f64::MIN_POSITIVE,
            -2.2250738585072014e-308,
            5e-324,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        let mut mixed: Vec<f64> = xs.to_vec();
        mixed.extend((0..500).map(|i| (i as f64 * 0.37).sin() * 10f64.powi(i % 40 - 20)));
        for array in [&[][..], &xs[..1], &mixed[..]] {
            let mut ours = Vec::new();
            write_f64_array(&mut ours, array);
            assert_eq!(
                String::from_utf8(ours).unwrap(),
                serde_json::to_string(array).unwrap()
            );
        }
        for &x in &mixed {
            let mut ours = Vec::new();
            write_f64(&mut ours, x);
            assert_eq!(ours, serde_json::to_vec(&x).unwrap(), "{x:e}");
        }
    }

    #[test]
    fn a_scan_is_the_json_serde_writes_for_it() {
        use super::super::{FoxLaserScan, Pose, Pose2, Stamp};
        use petrel_actors::LaserScan;
        for ranges in [
            vec![],
            vec![2.5],
            vec![1.0, f64::INFINITY, 0.30000000000000004, f64::NAN],
        ] {
            let scan = LaserScan {
                angle_min: -1.5707963267948966,
                angle_increment: 0.017453292519943295,
                range_max: 8.0,
                ranges: ranges.clone().into(),
            };
            let stamp = Stamp {
                sec: 1_764_000_000,
                nsec: 123_456_789,
            };
            let mut ours = Vec::new();
            super::super::laser_scan(&mut ours, &scan, stamp, "laser");
            let n = ranges.len();
            let serde = serde_json::to_vec(&FoxLaserScan {
                timestamp: stamp.into(),
                frame_id: "laser".into(),
                pose: Pose::of(&Pose2::default()),
                start_angle: scan.angle_min,
                end_angle: scan.angle_min + scan.angle_increment * n.saturating_sub(1) as f64,
                ranges,
                intensities: Vec::new(),
                range_max: 8.0,
            })
            .unwrap();
            assert_eq!(
                String::from_utf8(ours).unwrap(),
                String::from_utf8(serde).unwrap()
            );
        }
    }

    #[test]
    fn base64_is_the_text_of_the_standard_engine() {
        use base64::Engine;
        let bytes: Vec<u8> = (0..5000_u32).map(|i| (i * 7919 % 251) as u8).collect();
        for len in (0..100).chain([1000, 4096, 4097, 4999, 5000]) {
            let ours = super::BASE64.encode(&bytes[..len]);
            let standard = base64::engine::general_purpose::STANDARD.encode(&bytes[..len]);
            assert_eq!(ours, standard, "{len} bytes");
            assert_eq!(super::BASE64.decode(&ours).unwrap(), &bytes[..len]);
        }
    }
}
