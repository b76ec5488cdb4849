//! Where each key of a TOML document is: field paths mapped to 1-based line and column.

use std::collections::{HashMap, HashSet};
use toml::Spanned;
use toml::de::{DeTable, DeValue};

/// A 1-based line and column in the source text.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Position {
    /// Line, from 1.
    pub line: usize,
    /// Column in characters, from 1.
    pub column: usize,
}

/// Line and column of byte `offset` in `text` (clamped to the text).
pub fn position(text: &str, offset: usize) -> Position {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    Position {
        line,
        column: before[start..].chars().count() + 1,
    }
}

/// Positions of every key in a document, by field path: `rod.length`, `tendon[2].routing.x`
/// (array elements numbered from 1, as in the file's order).
#[derive(Clone, Debug, Default)]
pub struct Locator {
    keys: HashMap<String, Position>,
    tables: HashSet<String>,
}

impl Locator {
    /// Records every key of `root`.
    pub fn new(text: &str, root: &DeTable<'_>) -> Self {
        let mut locator = Locator::default();
        locator.table(text, "", root);
        locator
    }

    fn table(&mut self, text: &str, prefix: &str, table: &DeTable<'_>) {
        for (key, value) in table.iter() {
            let path = if prefix.is_empty() {
                key.get_ref().to_string()
            } else {
                format!("{prefix}.{}", key.get_ref())
            };
            self.keys
                .entry(path.clone())
                .or_insert_with(|| position(text, key.span().start));
            self.value(text, &path, value);
        }
    }

    fn value(&mut self, text: &str, path: &str, value: &Spanned<DeValue<'_>>) {
        match value.get_ref() {
            DeValue::Table(t) => {
                self.tables.insert(path.to_string());
                self.table(text, path, t);
            }
            DeValue::Array(items) => {
                for (i, item) in items.iter().enumerate() {
                    let element = format!("{path}[{}]", i + 1);
                    self.keys.insert(element.clone(), position(text, item.span().start));
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
        self.keys
            .iter()
            .filter(|(_, p)| p.line == at.line && p.column <= at.column)
            .max_by_key(|(path, p)| (p.column, path.len()))
            .map(|(path, _)| path.clone())
    }
}
