//! The tidy table of a tracked campaign — one row per record × mode, the columns of
//! `table.csv` — in one place, and written three ways from it: CSV, Parquet (for pandas and
//! polars: `pd.read_parquet`, `pl.read_parquet`) and the store's SQLite table `tracked`.
//!
//! Columns: `record`, `time_s`, `mode` (its name: an estimates table's, else its number
//! counted from 1), `frequency_hz`, `frequency_se_hz`, `damping_ratio`,
//! `damping_se`, `mac`, `misfit_flag`, `z`, `innovation`, `alarm` (`up`, `down` or empty),
//! `extrapolated`, then one per covariate. An empty cell (Parquet and SQL: null) is a value
//! the record does not have; NaN is a number that is not one (a MAC without shapes, a
//! covariate missing for that record; SQLite, which has no NaN, stores it as null).

use std::path::Path;
use std::sync::Arc;

use hyst_monitor::TrackReport;
use parquet::basic::{ConvertedType, Repetition, Type as Physical};
use parquet::data_type::{BoolType, ByteArray, ByteArrayType, DoubleType, Int64Type};
use parquet::file::writer::SerializedFileWriter;
use parquet::schema::types::Type;

use crate::io::IoError;

/// One column's values.
#[derive(Debug, Clone, PartialEq)]
pub enum Values {
    /// Text in every row.
    Text(Vec<String>),
    /// Text, or an empty cell.
    OptText(Vec<Option<String>>),
    /// Whole numbers.
    Int(Vec<i64>),
    /// Yes or no.
    Bool(Vec<bool>),
    /// Seconds (written as they are, `3600`, in the CSV).
    Seconds(Vec<f64>),
    /// Numbers in every row (NaN a value).
    Float(Vec<f64>),
    /// Numbers, or an empty cell.
    OptFloat(Vec<Option<f64>>),
}

impl Values {
    fn len(&self) -> usize {
        match self {
            Values::Text(v) => v.len(),
            Values::OptText(v) => v.len(),
            Values::Int(v) => v.len(),
            Values::Bool(v) => v.len(),
            Values::Seconds(v) | Values::Float(v) => v.len(),
            Values::OptFloat(v) => v.len(),
        }
    }

    /// Row `i` as the CSV writes it.
    fn csv_cell(&self, i: usize) -> String {
        match self {
            Values::Text(v) => v[i].clone(),
            Values::OptText(v) => v[i].clone().unwrap_or_default(),
            Values::Int(v) => v[i].to_string(),
            Values::Bool(v) => v[i].to_string(),
            Values::Seconds(v) => format!("{}", v[i]),
            Values::Float(v) => format!("{:e}", v[i]),
            Values::OptFloat(v) => v[i].map_or(String::new(), |x| format!("{x:e}")),
        }
    }

    /// Row `i` as SQLite stores it.
    fn sql_value(&self, i: usize) -> rusqlite::types::Value {
        use rusqlite::types::Value as V;
        match self {
            Values::Text(v) => V::Text(v[i].clone()),
            Values::OptText(v) => v[i].clone().map_or(V::Null, V::Text),
            Values::Int(v) => V::Integer(v[i]),
            Values::Bool(v) => V::Integer(i64::from(v[i])),
            Values::Seconds(v) | Values::Float(v) => V::Real(v[i]),
            Values::OptFloat(v) => v[i].map_or(V::Null, V::Real),
        }
    }

    /// The SQL column type.
    fn sql_type(&self) -> &'static str {
        match self {
            Values::Text(_) | Values::OptText(_) => "TEXT",
            Values::Int(_) | Values::Bool(_) => "INTEGER",
            _ => "REAL",
        }
    }
}

/// A named column.
#[derive(Debug, Clone, PartialEq)]
pub struct Column {
    /// Its header.
    pub name: String,
    /// Its values, one per row.
    pub values: Values,
}

/// The tidy table of a tracked campaign.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TrackTable {
    /// The columns, all of one length.
    pub columns: Vec<Column>,
}

impl TrackTable {
    /// The table of `report`.
    pub fn of(report: &TrackReport) -> TrackTable {
        let rows = &report.rows;
        let col = |name: &str, values: Values| Column {
            name: name.into(),
            values,
        };
        let floats = |f: fn(&hyst_monitor::TrackRow) -> f64| rows.iter().map(f).collect();
        let opts = |f: fn(&hyst_monitor::TrackRow) -> Option<f64>| rows.iter().map(f).collect();
        let mut columns = vec![
            col(
                "record",
                Values::Text(rows.iter().map(|r| r.name.clone()).collect()),
            ),
            col("time_s", Values::Seconds(floats(|r| r.time))),
            col(
                "mode",
                Values::Text(rows.iter().map(|r| report.mode_name(r.mode)).collect()),
            ),
            col("frequency_hz", Values::Float(floats(|r| r.frequency_hz))),
            col(
                "frequency_se_hz",
                Values::OptFloat(opts(|r| r.frequency_se_hz)),
            ),
            col("damping_ratio", Values::Float(floats(|r| r.damping_ratio))),
            col("damping_se", Values::OptFloat(opts(|r| r.damping_se))),
            col("mac", Values::Float(floats(|r| r.mac))),
            col(
                "misfit_flag",
                Values::Bool(rows.iter().map(|r| r.misfit_flag).collect()),
            ),
            col("z", Values::OptFloat(opts(|r| r.z))),
            col("innovation", Values::OptFloat(opts(|r| r.innovation))),
            col(
                "alarm",
                Values::OptText(
                    rows.iter()
                        .map(|r| r.alarm.map(|s| format!("{s:?}").to_lowercase()))
                        .collect(),
                ),
            ),
            col(
                "extrapolated",
                Values::Bool(rows.iter().map(|r| r.extrapolated).collect()),
            ),
        ];
        for (j, name) in report.covariate_names.iter().enumerate() {
            let v = rows
                .iter()
                .map(|r| r.covariates.get(j).copied().unwrap_or(f64::NAN))
                .collect();
            columns.push(col(name, Values::Float(v)));
        }
        TrackTable { columns }
    }

    /// The number of rows.
    pub fn rows(&self) -> usize {
        self.columns.first().map_or(0, |c| c.values.len())
    }

    /// Write the table as CSV to `path`.
    pub fn write_csv(&self, path: &Path) -> Result<(), IoError> {
        let err = |e: csv::Error| IoError::File {
            path: path.to_path_buf(),
            source: e.into(),
        };
        let mut w = csv::Writer::from_path(path).map_err(err)?;
        w.write_record(self.columns.iter().map(|c| c.name.as_str()))
            .map_err(err)?;
        for i in 0..self.rows() {
            w.write_record(self.columns.iter().map(|c| c.values.csv_cell(i)))
                .map_err(err)?;
        }
        w.flush().map_err(|e| IoError::File {
            path: path.to_path_buf(),
            source: e,
        })
    }

    /// Write the table as Parquet to `path` (one row group, through a temporary file
    /// renamed over it, so a reader never sees half a file).
    pub fn write_parquet(&self, path: &Path) -> Result<(), IoError> {
        let tmp = path.with_extension("parquet.tmp");
        let err = |e: parquet::errors::ParquetError| IoError::File {
            path: tmp.clone(),
            source: std::io::Error::other(e),
        };
        let file = std::fs::File::create(&tmp).map_err(|source| IoError::File {
            path: tmp.clone(),
            source,
        })?;
        let mut w = SerializedFileWriter::new(file, self.parquet_schema().map_err(err)?, {
            Arc::new(parquet::file::properties::WriterProperties::builder().build())
        })
        .map_err(err)?;
        let mut group = w.next_row_group().map_err(err)?;
        for c in &self.columns {
            let mut cw = group
                .next_column()
                .map_err(err)?
                .ok_or_else(|| err(parquet::errors::ParquetError::General("schema".into())))?;
            write_parquet_column(&mut cw, &c.values).map_err(err)?;
            cw.close().map_err(err)?;
        }
        group.close().map_err(err)?;
        w.close().map_err(err)?;
        std::fs::rename(&tmp, path).map_err(|source| IoError::File {
            path: path.to_path_buf(),
            source,
        })
    }

    /// The Parquet schema: each column its type, optional where a cell may be empty.
    fn parquet_schema(&self) -> parquet::errors::Result<Arc<Type>> {
        let fields = self
            .columns
            .iter()
            .map(|c| {
                let (physical, text, optional) = match &c.values {
                    Values::Text(_) => (Physical::BYTE_ARRAY, true, false),
                    Values::OptText(_) => (Physical::BYTE_ARRAY, true, true),
                    Values::Int(_) => (Physical::INT64, false, false),
                    Values::Bool(_) => (Physical::BOOLEAN, false, false),
                    Values::Seconds(_) | Values::Float(_) => (Physical::DOUBLE, false, false),
                    Values::OptFloat(_) => (Physical::DOUBLE, false, true),
                };
                let mut b =
                    Type::primitive_type_builder(&c.name, physical).with_repetition(if optional {
                        Repetition::OPTIONAL
                    } else {
                        Repetition::REQUIRED
                    });
                if text {
                    b = b.with_converted_type(ConvertedType::UTF8);
                }
                b.build().map(Arc::new)
            })
            .collect::<parquet::errors::Result<Vec<_>>>()?;
        Type::group_type_builder("tracked")
            .with_fields(fields)
            .build()
            .map(Arc::new)
    }

    /// Replace the SQL table `name` in `conn` with this table.
    pub(crate) fn write_sql(
        &self,
        conn: &rusqlite::Connection,
        name: &str,
    ) -> rusqlite::Result<()> {
        let quote = |s: &str| format!("\"{}\"", s.replace('"', "\"\""));
        conn.execute(&format!("DROP TABLE IF EXISTS {}", quote(name)), [])?;
        if self.columns.is_empty() {
            return Ok(());
        }
        let defs: Vec<String> = self
            .columns
            .iter()
            .map(|c| format!("{} {}", quote(&c.name), c.values.sql_type()))
            .collect();
        conn.execute(
            &format!("CREATE TABLE {} ({})", quote(name), defs.join(", ")),
            [],
        )?;
        let marks = vec!["?"; self.columns.len()].join(", ");
        let mut insert = conn.prepare(&format!("INSERT INTO {} VALUES ({marks})", quote(name)))?;
        for i in 0..self.rows() {
            insert.execute(rusqlite::params_from_iter(
                self.columns.iter().map(|c| c.values.sql_value(i)),
            ))?;
        }
        Ok(())
    }
}

/// One column's values into its Parquet column writer; an empty cell is a definition level
/// of 0.
fn write_parquet_column(
    cw: &mut parquet::file::writer::SerializedColumnWriter<'_>,
    values: &Values,
) -> parquet::errors::Result<usize> {
    fn levels<T>(v: &[Option<T>]) -> Vec<i16> {
        v.iter().map(|x| i16::from(x.is_some())).collect()
    }
    match values {
        Values::Text(v) => {
            let b: Vec<ByteArray> = v.iter().map(|s| ByteArray::from(s.as_str())).collect();
            cw.typed::<ByteArrayType>().write_batch(&b, None, None)
        }
        Values::OptText(v) => {
            let b: Vec<ByteArray> = v.iter().flatten().map(|s| s.as_str().into()).collect();
            cw.typed::<ByteArrayType>()
                .write_batch(&b, Some(&levels(v)), None)
        }
        Values::Int(v) => cw.typed::<Int64Type>().write_batch(v, None, None),
        Values::Bool(v) => cw.typed::<BoolType>().write_batch(v, None, None),
        Values::Seconds(v) | Values::Float(v) => {
            cw.typed::<DoubleType>().write_batch(v, None, None)
        }
        Values::OptFloat(v) => {
            let d: Vec<f64> = v.iter().flatten().copied().collect();
            cw.typed::<DoubleType>()
                .write_batch(&d, Some(&levels(v)), None)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parquet::file::reader::{FileReader, SerializedFileReader};

    fn table() -> TrackTable {
        let col = |name: &str, values| Column {
            name: name.into(),
            values,
        };
        TrackTable {
            columns: vec![
                col("record", Values::Text(vec!["a".into(), "b".into()])),
                col("time_s", Values::Seconds(vec![0.0, 3600.0])),
                col("mode", Values::Int(vec![0, 1])),
                col("z", Values::OptFloat(vec![None, Some(-1.5)])),
                col("alarm", Values::OptText(vec![Some("up".into()), None])),
                col("extrapolated", Values::Bool(vec![false, true])),
                col("temperature \"air\"", Values::Float(vec![f64::NAN, 2.5])),
            ],
        }
    }

    /// The three writers give the same cells: CSV as text, Parquet read back row by row
    /// (nulls where the CSV is empty), SQL queried back.
    #[test]
    fn csv_parquet_and_sql_hold_the_same_cells() {
        let dir = std::env::temp_dir().join(format!("hyst-table-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let t = table();
        t.write_csv(&dir.join("t.csv")).unwrap();
        assert_eq!(
            std::fs::read_to_string(dir.join("t.csv")).unwrap(),
            "record,time_s,mode,z,alarm,extrapolated,\"temperature \"\"air\"\"\"\n\
             a,0,0,,up,false,NaN\n\
             b,3600,1,-1.5e0,,true,2.5e0\n"
        );
        t.write_parquet(&dir.join("t.parquet")).unwrap();
        let r =
            SerializedFileReader::new(std::fs::File::open(dir.join("t.parquet")).unwrap()).unwrap();
        assert_eq!(r.metadata().file_metadata().num_rows(), 2);
        let rows: Vec<String> = r
            .get_row_iter(None)
            .unwrap()
            .map(|row| row.unwrap().to_string())
            .collect();
        assert_eq!(
            rows[1],
            "{record: \"b\", time_s: 3600.0, mode: 1, z: -1.5E0, alarm: null, extrapolated: true, temperature \"air\": 2.5}"
        );
        assert!(rows[0].contains("z: null, alarm: \"up\""), "{}", rows[0]);
        let conn = rusqlite::Connection::open_in_memory().unwrap();
        t.write_sql(&conn, "tracked").unwrap();
        t.write_sql(&conn, "tracked").unwrap();
        let (n, z, alarm): (i64, Option<f64>, Option<String>) = conn
            .query_row(
                "SELECT count(*), max(z), max(alarm) FROM tracked",
                [],
                |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)),
            )
            .unwrap();
        assert_eq!((n, z, alarm.as_deref()), (2, Some(-1.5), Some("up")));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
