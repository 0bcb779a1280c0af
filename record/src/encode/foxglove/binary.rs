//! Bytes in Foxglove JSON messages (grid cells, image pixels) are base64: written with the
//! base64 crate's SIMD engine, the same text as its scalar `STANDARD` engine.

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

#[cfg(test)]
mod tests {
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
