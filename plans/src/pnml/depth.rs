//! The element nesting limit for PNML, checked before the XML parser runs.
//!
//! roxmltree (0.20) parses elements recursively and has no nesting limit of its own: a file of
//! 100,000 nested elements overflows the stack of the thread reading it. This scan walks the
//! text once, without recursion, counting open elements the way the XML grammar nests them
//! (comments, CDATA sections, processing instructions and declarations do not nest; `>` and
//! `/` inside quoted attribute values do not end a tag). It only has to see well-formed nesting
//! right: whatever else is wrong with the file, roxmltree reports afterwards, positioned.

use crate::error::{PlanError, MAX_DEPTH};

/// `Err(TooDeep)` at the first start tag nested deeper than [`MAX_DEPTH`] elements.
pub(crate) fn check_depth(text: &str, file: &str) -> Result<(), PlanError> {
    let bytes = text.as_bytes();
    let mut depth = 0usize;
    let mut i = 0;
    // Index just past the first occurrence of `pat` at or after `from` (the end if none).
    let past = |from: usize, pat: &str| {
        text.get(from..)
            .and_then(|rest| rest.find(pat))
            .map_or(text.len(), |k| from + k + pat.len())
    };
    while let Some(k) = text.get(i..).and_then(|rest| rest.find('<')) {
        let at = i + k;
        let rest = &text[at..];
        i = if rest.starts_with("<!--") {
            past(at + 4, "-->")
        } else if rest.starts_with("<![CDATA[") {
            past(at + 9, "]]>")
        } else if rest.starts_with("<?") {
            past(at + 2, "?>")
        } else if rest.starts_with("<!") || rest.starts_with("</") {
            depth = depth.saturating_sub(usize::from(rest.starts_with("</")));
            past(at + 2, ">")
        } else {
            let end = tag_end(bytes, at + 1);
            if bytes.get(end.wrapping_sub(2)) != Some(&b'/') {
                depth += 1;
                if depth > MAX_DEPTH {
                    let (line, column) = crate::text::line_col(text, at);
                    return Err(PlanError::TooDeep {
                        file: file.to_string(),
                        line,
                        column,
                        limit: MAX_DEPTH,
                    });
                }
            }
            end
        };
    }
    Ok(())
}

/// Index just past the `>` closing the start tag whose name begins at `from`, skipping quoted
/// attribute values (the end of the text if the tag never closes).
fn tag_end(bytes: &[u8], from: usize) -> usize {
    let mut quote = None;
    for (j, &b) in bytes.iter().enumerate().skip(from) {
        match (quote, b) {
            (None, b'"' | b'\'') => quote = Some(b),
            (Some(q), _) if b == q => quote = None,
            (None, b'>') => return j + 1,
            _ => {}
        }
    }
    bytes.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn nested(n: usize, inner: &str) -> String {
        format!("{}{inner}{}", "<a x='>/'>".repeat(n), "</a>".repeat(n))
    }

    #[test]
    fn counts_only_real_nesting() {
        assert!(check_depth(&nested(MAX_DEPTH, ""), "f").is_ok());
        let flat = "<r>".to_string()
            + &"<a/><b x=\"/>\"></b><!-- <c> --><![CDATA[<d>]]><?p <e>?>".repeat(1000)
            + "</r>";
        assert!(check_depth(&flat, "f").is_ok());
        let e = check_depth(&nested(MAX_DEPTH + 1, ""), "f").unwrap_err();
        let at = "<a x='>/'>".len() * MAX_DEPTH + 1;
        assert_eq!(
            e.to_string(),
            format!("f:1:{at}: nesting deeper than 256 levels")
        );
    }

    #[test]
    fn lines_and_columns_are_of_the_tag() {
        let text = format!("<r>\n{}", "  <a>\n".repeat(MAX_DEPTH));
        let e = check_depth(&text, "deep.pnml").unwrap_err();
        let line = MAX_DEPTH as u32 + 1;
        assert_eq!(
            e.to_string(),
            format!("deep.pnml:{line}:3: nesting deeper than 256 levels")
        );
    }
}
