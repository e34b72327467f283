//! Finding where things are in a graph file's text, so every error can name a line.

use std::fmt;
use std::path::{Path, PathBuf};

/// A file position, 1-based, printed as `file:line:col`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    /// The graph file.
    pub file: PathBuf,
    /// 1-based line.
    pub line: usize,
    /// 1-based column (in bytes).
    pub col: usize,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file.display(), self.line, self.col)
    }
}

/// The text of a graph file, with look-ups from names to positions.
#[derive(Clone, Debug)]
pub struct SourceText {
    /// The graph file the text came from.
    pub file: PathBuf,
    /// The file's whole text.
    pub text: String,
}

impl SourceText {
    /// The text of `file`, for locating names in it.
    pub fn new(file: impl AsRef<Path>, text: impl Into<String>) -> Self {
        Self {
            file: file.as_ref().to_path_buf(),
            text: text.into(),
        }
    }

    /// Location of a byte offset.
    pub(crate) fn at_offset(&self, offset: usize) -> Location {
        let offset = offset.min(self.text.len());
        let before = &self.text[..offset];
        let line = before.matches('\n').count() + 1;
        let col = offset - before.rfind('\n').map_or(0, |i| i + 1) + 1;
        Location {
            file: self.file.clone(),
            line,
            col,
        }
    }

    /// Location of a 1-based line and column (as ron reports them).
    pub fn at(&self, line: usize, col: usize) -> Location {
        Location {
            file: self.file.clone(),
            line,
            col,
        }
    }

    /// Byte offset of the declaration `name: "NAME"` (a pass or a resource), if present.
    fn declaration(&self, name: &str) -> Option<usize> {
        let quoted = format!("\"{name}\"");
        let mut from = 0;
        while let Some(i) = self.text[from..].find(&quoted) {
            let at = from + i;
            let head = self.text[..at].trim_end();
            if head.ends_with(':') && head[..head.len() - 1].trim_end().ends_with("name") {
                return Some(at);
            }
            from = at + quoted.len();
        }
        None
    }

    /// Where a pass or resource named `name` is declared (start of file if not found).
    pub(crate) fn of_declaration(&self, name: &str) -> Location {
        self.at_offset(self.declaration(name).unwrap_or(0))
    }

    /// Where pass `pass` mentions `word` (a resource name in its reads/writes, a shader
    /// path, ...); falls back to the pass declaration.
    pub(crate) fn in_pass(&self, pass: &str, word: &str) -> Location {
        let Some(start) = self.declaration(pass) else {
            return self.at_offset(0);
        };
        // The pass's text runs until the next `name:` declaration.
        let rest = &self.text[start + pass.len() + 2..];
        let end = rest
            .find("name:")
            .map_or(self.text.len(), |i| start + pass.len() + 2 + i);
        let quoted = format!("\"{word}\"");
        // `"slot=word"`: point at the slot's entry.
        let named = format!("={word}\"");
        let text = &self.text[start..end];
        let offset = text
            .find(&quoted)
            .or_else(|| text.find(&named).map(|i| text[..i].rfind('"').unwrap_or(i)))
            .map_or(start, |i| start + i);
        self.at_offset(offset)
    }

    /// The name of the pass whose text contains `offset` (for parse errors).
    pub(crate) fn pass_around(&self, offset: usize) -> Option<String> {
        let before = &self.text[..offset.min(self.text.len())];
        let i = before.rfind("Pass(")?;
        let after = &self.text[i..];
        let n = after.find("name:")?;
        let q1 = i + n + after[n..].find('"')? + 1;
        let q2 = q1 + self.text[q1..].find('"')?;
        Some(self.text[q1..q2].to_string())
    }

    /// Byte offset of a 1-based line and column.
    pub fn offset_of(&self, line: usize, col: usize) -> usize {
        let mut offset = 0;
        for (i, l) in self.text.split_inclusive('\n').enumerate() {
            if i + 1 == line {
                // `col` counts characters (ron's columns), not bytes.
                let within = l
                    .char_indices()
                    .nth(col.saturating_sub(1))
                    .map_or(l.len(), |(b, _)| b);
                return offset + within;
            }
            offset += l.len();
        }
        self.text.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_count_characters_not_bytes() {
        let t = SourceText::new(Path::new("g.ron"), "Pass(name: \"é\", kind: ??)");
        // Column 15 is the comma; counted as bytes it would be the quote before it (é is
        // two bytes), and a column inside é would not be a char boundary.
        let off = t.offset_of(1, 15);
        assert!(t.text.is_char_boundary(off));
        assert_eq!(&t.text[off..off + 1], ",");
        assert!(t.pass_around(off).is_some());
    }

    const TEXT: &str = "Graph(\n  passes: [\n    Pass(name: \"a\", reads: [\"x\"]),\n    Pass(\n      name: \"b\",\n      reads: [\"x\", \"y\"],\n    ),\n  ],\n)\n";

    #[test]
    fn finds_declarations_and_mentions() {
        let s = SourceText::new("g.ron", TEXT);
        assert_eq!(s.of_declaration("b").line, 5);
        assert_eq!(s.in_pass("b", "y").line, 6);
        assert_eq!(s.in_pass("b", "y").col, 20);
        // "x" is mentioned by both passes: the one inside pass b is found.
        assert_eq!(s.in_pass("b", "x").line, 6);
        assert_eq!(s.in_pass("a", "x").line, 3);
    }

    #[test]
    fn names_the_pass_around_an_offset() {
        let s = SourceText::new("g.ron", TEXT);
        assert_eq!(s.pass_around(s.offset_of(6, 10)).as_deref(), Some("b"));
        assert_eq!(s.pass_around(s.offset_of(1, 1)), None);
    }
}
