//! Result tables as CSV text, written through the `csv` crate (which quotes a field that
//! holds a comma, a quote or a line break), every number by the one formatter
//! [`number`].
//!
//! ```
//! let mut table = tdcr::io::csv_table::CsvTable::new(["s", "note"]);
//! table.row([tdcr::io::number(0.5), "a, b".to_string()]);
//! assert_eq!(table.finish(), "s,note\n0.5,\"a, b\"\n");
//! ```

/// A CSV text being written: the header, then one record per row, lines ending in `\n`.
pub struct CsvTable {
    writer: csv::Writer<Vec<u8>>,
}

impl CsvTable {
    /// A table with these column names.
    pub fn new<I, S>(header: I) -> CsvTable
    where
        I: IntoIterator<Item = S>,
        S: AsRef<[u8]>,
    {
        // flexible: a row may have other than the header's number of fields (the writer
        // would otherwise refuse it, and the row would be lost).
        let mut table = CsvTable::rows_only();
        table.row(header);
        table
    }

    /// A table without a header: more rows of a table whose header was written before (a
    /// file written as it is computed).
    pub fn rows_only() -> CsvTable {
        CsvTable {
            writer: csv::WriterBuilder::new().flexible(true).from_writer(Vec::new()),
        }
    }

    /// Appends one row of fields (numbers already written by [`number`]).
    pub fn row<I, S>(&mut self, fields: I)
    where
        I: IntoIterator<Item = S>,
        S: AsRef<[u8]>,
    {
        // Writing into memory cannot fail, and a flexible writer accepts any field count.
        let _ = self.writer.write_record(fields);
    }

    /// Appends one row of numbers.
    pub fn numbers(&mut self, values: impl IntoIterator<Item = f64>) {
        self.row(values.into_iter().map(number));
    }

    /// The text written.
    pub fn finish(self) -> String {
        let bytes = self
            .writer
            .into_inner()
            .unwrap_or_else(|e| e.into_inner().get_ref().clone());
        // Every field came in as text, so the bytes are UTF-8.
        String::from_utf8_lossy(&bytes).into_owned()
    }
}

/// A number as every result file writes it: the shortest text that reads back to the same
/// f64, in exponent form when it is very small or very large (`1.0844e-28` rather than 28
/// zeros); `NaN`, `inf` and `-inf` for the non-finite ones.
pub fn number(x: f64) -> String {
    let magnitude = x.abs();
    if x != 0.0 && x.is_finite() && !(1e-4..1e15).contains(&magnitude) {
        format!("{x:e}")
    } else {
        x.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_back_exactly_and_fields_are_quoted_when_needed() {
        for x in [
            0.1,
            1.0 / 3.0,
            1.0844e-28,
            2.5e17,
            -0.0,
            1e-4,
            9.99e14,
            f64::MIN_POSITIVE,
        ] {
            assert_eq!(number(x).parse::<f64>().unwrap().to_bits(), x.to_bits(), "{x}");
        }
        assert_eq!(number(1.0844e-28), "1.0844e-28");
        assert_eq!(number(2.94), "2.94");
        assert_eq!(number(3.0), "3");
        let mut table = CsvTable::new(["a", "b"]);
        table.numbers([1.5, f64::NAN]);
        table.row(["x \"y\"", "line\nbreak"]);
        assert_eq!(table.finish(), "a,b\n1.5,NaN\n\"x \"\"y\"\"\",\"line\nbreak\"\n");
    }
}
