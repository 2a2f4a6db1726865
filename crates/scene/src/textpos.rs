//! Line and column of byte offsets in a document, in linear time over a whole parse.
//!
//! roxmltree's `Document::text_pos_at` scans from the start of the text on every call, so a
//! loader that locates each element (for its diagnostics) was quadratic in the file size. This
//! index keeps the byte offset of every line start (one pass); a lookup is a binary search for
//! the line and a character count from the line start. The count resumes from the previous
//! lookup when it is on the same line further right, so a document read in order (the loaders
//! walk elements in document order) costs linear time even when it is all on one line.

use std::cell::Cell;
use std::path::Path;
use std::sync::Arc;

use crate::{LoadError, Loc, Result};

/// 1-based line and column (in characters) of byte offsets in one text.
pub struct TextIndex<'t> {
    text: &'t str,
    line_starts: Vec<usize>,
    /// The last lookup: (byte offset, 0-based line, 1-based column).
    last: Cell<(usize, usize, u32)>,
}

impl<'t> TextIndex<'t> {
    pub fn new(text: &'t str) -> Self {
        let mut line_starts = vec![0];
        line_starts.extend(
            text.bytes()
                .enumerate()
                .filter(|&(_, b)| b == b'\n')
                .map(|(i, _)| i + 1),
        );
        TextIndex {
            text,
            line_starts,
            last: Cell::new((0, 0, 1)),
        }
    }

    /// (line, column), both 1-based; the column counts characters. An offset past the end or
    /// inside a character is moved back to the nearest character boundary.
    pub fn pos(&self, byte: usize) -> (u32, u32) {
        let mut byte = byte.min(self.text.len());
        while !self.text.is_char_boundary(byte) {
            byte -= 1;
        }
        let line = self.line_starts.partition_point(|&s| s <= byte) - 1;
        let (last_byte, last_line, last_col) = self.last.get();
        let (from, col0) = if last_line == line && last_byte <= byte {
            (last_byte, last_col)
        } else {
            (self.line_starts[line], 1)
        };
        let col = col0 + self.text[from..byte].chars().count() as u32;
        self.last.set((byte, line, col));
        (line as u32 + 1, col)
    }
}

/// Read a regular file as UTF-8, locating the first invalid byte when it is not.
pub fn read_text(path: &Path, at: &Loc) -> Result<String> {
    let bytes = crate::read_file(path).map_err(|e| {
        LoadError::new(at.clone(), format!("cannot read '{}': {e}", path.display()))
    })?;
    match String::from_utf8(bytes) {
        Ok(s) => Ok(s),
        Err(e) => {
            let good = e.utf8_error().valid_up_to();
            let bytes = e.into_bytes();
            // Valid prefix, so this cannot fail.
            let prefix = std::str::from_utf8(&bytes[..good]).unwrap_or("");
            let (line, col) = TextIndex::new(prefix).pos(prefix.len());
            Err(LoadError::new(
                Loc::new(&Arc::new(path.to_path_buf()), line, col),
                format!(
                    "not a text file: invalid UTF-8 byte 0x{:02x} (expected a scene in UTF-8 text)",
                    bytes[good]
                ),
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The straightforward definition the index must agree with.
    fn naive(text: &str, pos: usize) -> (u32, u32) {
        let before = &text[..pos];
        let line = before.matches('\n').count() + 1;
        let start = before.rfind('\n').map_or(0, |i| i + 1);
        (line as u32, before[start..].chars().count() as u32 + 1)
    }

    #[test]
    fn agrees_with_the_definition_in_any_order() {
        let text = "<a>\n  <bé x=\"1\"/>\r\n\n<ü>ß</ü>\n";
        let offsets: Vec<usize> = (0..=text.len())
            .filter(|&i| text.is_char_boundary(i))
            .collect();
        let index = TextIndex::new(text);
        // In order, in reverse and interleaved: the resumed count must not leak across lines.
        for &i in offsets.iter().chain(offsets.iter().rev()) {
            assert_eq!(index.pos(i), naive(text, i), "offset {i}");
        }
        for (k, &i) in offsets.iter().enumerate() {
            let j = offsets[(k * 7) % offsets.len()];
            assert_eq!(index.pos(i), naive(text, i));
            assert_eq!(index.pos(j), naive(text, j));
        }
    }

    #[test]
    fn offsets_inside_a_character_or_past_the_end_are_clamped() {
        let text = "ab\nçd";
        let index = TextIndex::new(text);
        assert_eq!(index.pos(4), (2, 1)); // inside 'ç' → its start
        assert_eq!(index.pos(100), (2, 3));
        assert_eq!(TextIndex::new("").pos(0), (1, 1));
    }
}
