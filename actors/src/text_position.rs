//! Where a byte offset is in a text, as an editor shows it: the one line:column function of
//! every error petrel prints (configs, rules, expressions, plans, worlds).

/// 1-based line and column of byte `offset` in `text`, the column counted in characters (so
/// `é` or `→` before it count one each, as in an editor). An offset past the end is the end; an
/// offset inside a character is that character.
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut at = offset.min(text.len());
    while !text.is_char_boundary(at) {
        at -= 1;
    }
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().unwrap_or("").chars().count() + 1;
    (line, column)
}

/// The byte offset of 1-based `line` and `column` (in characters, as [`line_column`] counts
/// them), if `text` has that place: the inverse of [`line_column`], for positions other
/// parsers give (RON's).
pub(crate) fn offset_of(text: &str, line: usize, column: usize) -> Option<usize> {
    let start: usize = (text.split_inclusive('\n'))
        .take(line.checked_sub(1)?)
        .map(str::len)
        .sum();
    let (i, _) = text
        .get(start..)?
        .char_indices()
        .nth(column.checked_sub(1)?)?;
    Some(start + i)
}

/// The starts of a text's lines, for many [`line_column`] lookups in one text: each costs a
/// binary search and the characters of one line, not the whole text before it (a 100,000-action
/// plan names the line of every action).
pub struct LineIndex {
    starts: Vec<usize>,
}

impl LineIndex {
    /// Indexes `text`'s lines.
    pub fn new(text: &str) -> Self {
        let starts = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(i, _)| i + 1))
            .collect();
        LineIndex { starts }
    }

    /// The 1-based line of byte `offset`: a binary search, whatever the line's length.
    pub fn line(&self, offset: usize) -> usize {
        self.starts.partition_point(|&s| s <= offset)
    }

    /// [`line_column`] of byte `offset` in `text`, the text this index was made from (the
    /// column costs the characters before it on its line).
    pub fn line_column(&self, text: &str, offset: usize) -> (usize, usize) {
        let mut at = offset.min(text.len());
        while !text.is_char_boundary(at) {
            at -= 1;
        }
        let line = self.starts.partition_point(|&s| s <= at);
        let start = self.starts[line - 1];
        (line, text[start..at].chars().count() + 1)
    }
}

#[cfg(test)]
mod tests {
    use super::{line_column, offset_of, LineIndex};

    #[test]
    fn the_index_agrees_with_the_plain_function_everywhere() {
        let text = "ab\nçé→x\n\nlast é";
        let index = LineIndex::new(text);
        for offset in 0..=text.len() + 2 {
            let expected = line_column(text, offset);
            assert_eq!(index.line_column(text, offset), expected, "{offset}");
            let clamped = offset.min(text.len());
            if text.is_char_boundary(clamped) {
                assert_eq!(index.line(clamped), expected.0, "{offset}");
            }
        }
    }

    #[test]
    fn offsets_come_back_from_their_line_and_column() {
        let text = "ab\nçé→x\n\nlast é";
        for (offset, _) in text.char_indices() {
            let (line, column) = line_column(text, offset);
            assert_eq!(offset_of(text, line, column), Some(offset), "{offset}");
        }
        assert_eq!(offset_of(text, 0, 1), None);
        assert_eq!(offset_of(text, 1, 0), None);
        assert_eq!(offset_of(text, 9, 1), None);
    }

    #[test]
    fn columns_count_characters_and_lines_start_at_one() {
        let text = "ab\nçé→x\n";
        assert_eq!(line_column(text, 0), (1, 1));
        assert_eq!(line_column(text, 2), (1, 3));
        assert_eq!(line_column(text, 3), (2, 1));
        let x = text.find('x').unwrap();
        assert_eq!(
            line_column(text, x),
            (2, 4),
            "three characters, seven bytes before x"
        );
    }

    #[test]
    fn offsets_past_the_end_or_inside_a_character_never_panic() {
        let text = "é";
        assert_eq!(line_column(text, 1), (1, 1));
        assert_eq!(line_column(text, 99), (1, 2));
        assert_eq!(line_column("", 5), (1, 1));
    }
}
