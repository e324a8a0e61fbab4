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

/// A `hyst ssi --json` document written before the answer was its `modes` (issue 76): its
/// `modes` then held SSI's clusters and `decision.modes` the answer; moved to `ssi_modes`
/// and `modes`. A document in today's layout (it has `ssi_modes`) is left as it is.
fn upgrade_layout(map: &mut serde_json::Map<String, serde_json::Value>) {
    if map.contains_key("ssi_modes") {
        return;
    }
    let answer = map
        .get_mut("decision")
        .and_then(serde_json::Value::as_object_mut)
        .and_then(|d| d.remove("modes"));
    if let (Some(answer), Some(ssi)) = (answer, map.remove("modes")) {
        map.insert("ssi_modes".into(), ssi);
        map.insert("modes".into(), answer);
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
        upgrade_layout(map);
    }
    let analysis: covssi::ModalAnalysis = serde_json::from_value(doc)
        .map_err(|e| format!("not a `hyst ssi --json` document: {e}"))?;
    Ok(crate::monitor::reported_modes(&analysis))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A document in the layout before issue 76 (`modes` SSI's clusters, `decision.modes`
    /// the answer) gives the reference today's does; an unknown key is refused.
    #[test]
    fn a_document_of_the_earlier_layout_reads_as_todays() {
        let y = covssi::synth::ModalRecord::new(20.0, &[(1.5, 0.02), (4.0, 0.03)])
            .with_gains(vec![vec![1.0, 0.0, 0.5, 0.0], vec![0.3, 0.0, -1.0, 0.0]])
            .with_noise(0.05)
            .generate(8192, 76);
        let views: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
        let mut opts = covssi::AnalysisOptions::default();
        opts.ssi.max_order = Some(20);
        let a = covssi::analyze(&views, 20.0, &opts).unwrap();
        assert!(!a.decision.modes.is_empty());
        let doc = serde_json::to_value(FileReport::new("r.csv", &a)).unwrap();
        let today = reference_modes(&doc.to_string()).unwrap();
        assert_eq!(today.len(), a.decision.modes.len());
        let mut old = doc.clone();
        let map = old.as_object_mut().unwrap();
        let answer = map.remove("modes").unwrap();
        let ssi = map.remove("ssi_modes").unwrap();
        map.insert("modes".into(), ssi);
        map["decision"]
            .as_object_mut()
            .unwrap()
            .insert("modes".into(), answer);
        assert_eq!(reference_modes(&old.to_string()).unwrap(), today);
        let mut unknown = doc;
        unknown["surprise"] = 1.into();
        let e = reference_modes(&unknown.to_string()).unwrap_err();
        assert!(e.contains("unknown field `surprise`"), "{e}");
    }
}
