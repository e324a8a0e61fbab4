//! A library report with the record it came from: what each command of the `hyst` program
//! prints (through `Display`) and writes as JSON (through serde), the record's name first.

use std::fmt;

use serde::Serialize;

/// `report` made from the record `record` (a file's path, or a description of a built-in
/// one). In JSON the report's fields sit beside `record`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FileReport<T> {
    /// Where the data came from.
    pub record: String,
    /// The library's report.
    #[serde(flatten)]
    pub report: T,
}

impl<T> FileReport<T> {
    /// `report` made from `record`.
    pub fn new(record: impl Into<String>, report: T) -> Self {
        FileReport {
            record: record.into(),
            report,
        }
    }

    /// Write the report as pretty JSON to `path`; an error names the file.
    pub fn write_json(&self, path: &std::path::Path) -> Result<(), crate::io::IoError>
    where
        T: Serialize,
    {
        write_json(self, path)
    }
}

/// Write `value` as pretty JSON to `path`; an error names the file.
pub fn write_json<V: Serialize>(
    value: &V,
    path: &std::path::Path,
) -> Result<(), crate::io::IoError> {
    let file_error = |source: std::io::Error| crate::io::IoError::File {
        path: path.to_path_buf(),
        source,
    };
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).map_err(file_error)?);
    serde_json::to_writer_pretty(&mut w, value).map_err(|e| file_error(e.into()))?;
    std::io::Write::flush(&mut w).map_err(file_error)
}

impl<T: fmt::Display> fmt::Display for FileReport<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "record: {}", self.record)?;
        self.report.fmt(f)
    }
}

/// The modes a `hyst ssi --json` document (or `hyst.ssi(..).to_json()`) reports, as
/// tracking takes a reference: the refined ones when its refinement holds, else SSI's.
/// What is wrong with `text` is said (not JSON; not such a document, with serde's reason).
pub fn reference_modes(text: &str) -> Result<Vec<crate::monitor::ModeEstimate>, String> {
    let mut doc: serde_json::Value =
        serde_json::from_str(text).map_err(|e| format!("not JSON: {e}"))?;
    if let Some(map) = doc.as_object_mut() {
        map.remove("record");
    }
    let analysis: covssi::ModalAnalysis = serde_json::from_value(doc)
        .map_err(|e| format!("not a `hyst ssi --json` document: {e}"))?;
    Ok(crate::monitor::reported_modes(&analysis))
}
