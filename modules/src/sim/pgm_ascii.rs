//! The samples of a P2 (ASCII) PGM image, checked before it is decoded: the decoder reads the
//! first width x height numbers and ignores the rest, and names neither a line nor the sample
//! that is not a number. A map with extra or missing samples was drawn for other dimensions.

use std::path::Path;

use super::error::WorldFileError;

/// Checks that P2 `text` holds exactly one sample (a whole number up to its maxval) per pixel;
/// the header (`P2`, width, height, maxval, with `#` comments) is the decoder's to judge, and
/// is skipped here when it does not parse.
pub(super) fn check_p2_samples(path: &Path, text: &str) -> Result<(), WorldFileError> {
    // Tokens with their 1-based line, comments dropped.
    let tokens = text.lines().enumerate().flat_map(|(i, line)| {
        let line_text = line.split('#').next().unwrap_or("");
        line_text.split_ascii_whitespace().map(move |t| (i + 1, t))
    });
    let mut tokens = tokens.skip(1); // `P2`
    let mut header = [0u64; 3];
    for field in &mut header {
        match tokens.next().and_then(|(_, t)| t.parse().ok()) {
            Some(v) => *field = v,
            None => return Ok(()),
        }
    }
    let [width, height, maxval] = header;
    let pixels = width.saturating_mul(height);
    let mut count = 0u64;
    let mut last_line = 1;
    for (line, token) in tokens {
        last_line = line;
        count += 1;
        if count > pixels {
            return Err(WorldFileError::at(
                path,
                line,
                format!("more samples than the {width} x {height} pixels the header gives ({pixels}); expected exactly one per pixel"),
            ));
        }
        match token.parse::<u64>() {
            Ok(v) if v <= maxval => {}
            Ok(v) => {
                return Err(WorldFileError::at(
                    path,
                    line,
                    format!("sample {count} is {v}, above the image's maxval {maxval}"),
                ))
            }
            Err(_) => {
                return Err(WorldFileError::at(
                    path,
                    line,
                    format!(
                        "sample {count} is `{token}`; expected a whole number from 0 to {maxval}"
                    ),
                ))
            }
        }
    }
    if count < pixels {
        return Err(WorldFileError::at(
            path,
            last_line,
            format!("{count} samples for the {width} x {height} pixels the header gives ({pixels}); expected one per pixel"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::check_p2_samples;
    use std::path::Path;

    fn problem(text: &str) -> String {
        check_p2_samples(Path::new("m.pgm"), text)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    }

    #[test]
    fn one_number_per_pixel_no_more_no_less() {
        assert_eq!(problem("P2\n# c\n3 1\n255\n0 255 128\n"), "");
        assert!(problem("P2 2 1 255\n0 1\n2 3\n")
            .contains("m.pgm:3: more samples than the 2 x 1 pixels"));
        assert!(problem("P2 2 2 255\n0 1\n2\n").contains("3 samples for the 2 x 2 pixels"));
        assert!(problem("P2 2 1 255\n254 abc\n")
            .contains("m.pgm:2: sample 2 is `abc`; expected a whole number from 0 to 255"));
        assert!(
            problem("P2 2 1 15\n0 16\n").contains("sample 2 is 16, above the image's maxval 15")
        );
    }
}
