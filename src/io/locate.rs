//! Where each key of a TOML document is: field paths mapped to 1-based line and column.

use std::cell::OnceCell;
use std::collections::{HashMap, HashSet};
use toml::Spanned;
use toml::de::{DeTable, DeValue};

pub use super::Position;

/// Line and column of byte `offset` in `text` (clamped to the text). This scans `text`; for
/// many offsets into one text, build [`Lines`] once.
pub fn position(text: &str, offset: usize) -> Position {
    Lines::new(text).position(offset)
}

/// Where each line of a text starts, so that a byte offset becomes a line and column in
/// O(log lines) (O(line length) on a line with non-ASCII characters, whose columns count
/// characters).
#[derive(Clone, Debug)]
pub struct Lines<'a> {
    text: &'a str,
    /// Byte offset of the start of each line.
    starts: Vec<usize>,
}

impl<'a> Lines<'a> {
    /// The line starts of `text`, found in one pass.
    pub fn new(text: &'a str) -> Self {
        let starts = std::iter::once(0)
            .chain(
                text.bytes()
                    .enumerate()
                    .filter(|&(_, b)| b == b'\n')
                    .map(|(i, _)| i + 1),
            )
            .collect();
        Lines { text, starts }
    }

    /// Line and column of byte `offset` (clamped to the text; inside a character, of that
    /// character).
    pub fn position(&self, offset: usize) -> Position {
        let mut offset = offset.min(self.text.len());
        while !self.text.is_char_boundary(offset) {
            offset -= 1;
        }
        // The last line starting at or before `offset` (line starts are increasing).
        let line = self.starts.partition_point(|&start| start <= offset);
        let start = self.starts[line - 1];
        let before = &self.text[start..offset];
        let column = if before.is_ascii() {
            before.len()
        } else {
            before.chars().count()
        };
        Position {
            line,
            column: column + 1,
        }
    }
}

/// Positions of every key in a document, by field path: `rod.length`, `tendon[2].routing.x`
/// (array elements numbered from 1, as in the file's order).
#[derive(Clone, Debug, Default)]
pub struct Locator {
    keys: HashMap<String, Position>,
    /// The keys of each line (by line number), with their columns: built at the first
    /// [`Locator::key_at`], which only a file with problems needs.
    lines: OnceCell<HashMap<usize, Vec<(usize, String)>>>,
    tables: HashSet<String>,
}

impl Locator {
    /// Records every key of `root` (in time linear in the size of `text`).
    pub fn new(text: &str, root: &DeTable<'_>) -> Self {
        let mut locator = Locator::default();
        locator.table(&Lines::new(text), "", root);
        locator
    }

    fn table(&mut self, text: &Lines<'_>, prefix: &str, table: &DeTable<'_>) {
        for (key, value) in table.iter() {
            let path = if prefix.is_empty() {
                key.get_ref().to_string()
            } else {
                format!("{prefix}.{}", key.get_ref())
            };
            self.keys
                .entry(path.clone())
                .or_insert_with(|| text.position(key.span().start));
            self.value(text, &path, value);
        }
    }

    fn value(&mut self, text: &Lines<'_>, path: &str, value: &Spanned<DeValue<'_>>) {
        match value.get_ref() {
            DeValue::Table(t) => {
                self.tables.insert(path.to_string());
                self.table(text, path, t);
            }
            DeValue::Array(items) => {
                for (i, item) in items.iter().enumerate() {
                    let element = format!("{path}[{}]", i + 1);
                    self.keys.insert(element.clone(), text.position(item.span().start));
                    self.value(text, &element, item);
                }
            }
            _ => {}
        }
    }

    /// Whether the value at `path` is a table (inline or not).
    pub fn is_table(&self, path: &str) -> bool {
        self.tables.contains(path)
    }

    /// Position of `path`, or of its nearest enclosing key that is in the file.
    pub fn find(&self, path: &str) -> Option<Position> {
        let mut path = path;
        loop {
            if let Some(p) = self.keys.get(path) {
                return Some(*p);
            }
            let cut = path.rfind(['.', '['])?;
            path = &path[..cut];
        }
    }

    /// The path of the last key at or before `at` on the same line (the key a value error
    /// belongs to), if any.
    pub fn key_at(&self, at: Position) -> Option<String> {
        let lines = self.lines.get_or_init(|| {
            let mut lines: HashMap<usize, Vec<(usize, String)>> = HashMap::new();
            for (path, p) in &self.keys {
                lines.entry(p.line).or_default().push((p.column, path.clone()));
            }
            lines
        });
        lines
            .get(&at.line)?
            .iter()
            .filter(|(column, _)| *column <= at.column)
            .max_by_key(|(column, path)| (*column, path.len()))
            .map(|(_, path)| path.clone())
    }
}

/// A [`Locator`] built at its first use by parsing the text again: only a file with
/// problems needs one, so a valid file (of 10^5 tendons, say) never pays for the key paths.
pub(crate) struct LazyLocator<'a> {
    text: &'a str,
    locator: OnceCell<Locator>,
}

impl<'a> LazyLocator<'a> {
    /// The locator of `text` (which must be the text already parsed), not yet built.
    pub(crate) fn new(text: &'a str) -> Self {
        LazyLocator {
            text,
            locator: OnceCell::new(),
        }
    }

    /// The locator, built now if this is its first use.
    pub(crate) fn get(&self) -> &Locator {
        self.locator.get_or_init(|| {
            let (root, _) = DeTable::parse_recoverable(self.text);
            Locator::new(self.text, root.get_ref())
        })
    }
}
