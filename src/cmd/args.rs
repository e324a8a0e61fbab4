//! Typed values of the command line's flags, parsed by clap through `FromStr`.

use std::fmt;
use std::str::FromStr;

/// Rows `A:B` of a record (0-based, `B` excluded), as `--estimate` and `--test` take them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct RowRange {
    /// First row.
    pub(crate) start: usize,
    /// One past the last row.
    pub(crate) end: usize,
}

impl FromStr for RowRange {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("`{s}` is not A:B with 0 <= A < B (rows)");
        let (a, b) = s.split_once(':').ok_or_else(bad)?;
        let (start, end): (usize, usize) = (
            a.trim().parse().map_err(|_| bad())?,
            b.trim().parse().map_err(|_| bad())?,
        );
        if start >= end {
            return Err(bad());
        }
        Ok(RowRange { start, end })
    }
}

impl fmt::Display for RowRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.start, self.end)
    }
}

impl RowRange {
    /// The range as `(start, end)` when it lies within a record of `len` rows; else an error
    /// naming the flag.
    pub(crate) fn within(self, flag: &str, len: usize) -> Result<(usize, usize), super::Error> {
        if self.end > len {
            return Err(super::fail(format!(
                "{flag} `{self}` ends past the record's {len} rows"
            )));
        }
        Ok((self.start, self.end))
    }
}

/// A frequency band `LO:HI` in Hz with 0 ≤ LO < HI.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Band {
    /// Lower edge (Hz).
    pub(crate) low_hz: f64,
    /// Upper edge (Hz).
    pub(crate) high_hz: f64,
}

impl FromStr for Band {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("`{s}` is not LO:HI with 0 <= LO < HI (Hz)");
        let (a, b) = s.split_once(':').ok_or_else(bad)?;
        let (low_hz, high_hz): (f64, f64) = (
            a.trim().parse().map_err(|_| bad())?,
            b.trim().parse().map_err(|_| bad())?,
        );
        if !(low_hz.is_finite() && high_hz.is_finite() && low_hz >= 0.0 && low_hz < high_hz) {
            return Err(bad());
        }
        Ok(Band { low_hz, high_hz })
    }
}

impl fmt::Display for Band {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.low_hz, self.high_hz)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_and_bands_parse_or_say_why() {
        assert_eq!(
            " 10 : 20".parse::<RowRange>(),
            Ok(RowRange { start: 10, end: 20 })
        );
        for bad in ["20:10", "5", "a:b", "-1:3", "3:3"] {
            let e = bad.parse::<RowRange>().unwrap_err();
            assert!(e.contains(&format!("`{bad}` is not A:B")), "{e}");
        }
        assert_eq!(
            "5:150.1".parse::<Band>(),
            Ok(Band {
                low_hz: 5.0,
                high_hz: 150.1
            })
        );
        for bad in ["150:5", "6.8-7.8", "-1:2", "1:inf", "NaN:2"] {
            let e = bad.parse::<Band>().unwrap_err();
            assert!(e.contains(&format!("`{bad}` is not LO:HI")), "{e}");
        }
        let r = RowRange { start: 0, end: 500 };
        assert!(
            r.within("--test", 200)
                .unwrap_err()
                .to_string()
                .contains("--test `0:500` ends past the record's 200 rows")
        );
    }
}

/// The columns of the records `hyst ident` and `hyst levels` read, and the rows they skip.
#[derive(clap::Args, Debug)]
pub(crate) struct RecordColumns {
    /// Column of the output (displacement).
    #[arg(long, default_value = "y")]
    pub(crate) output_column: String,
    /// Column of the input force (only used by --validate files).
    #[arg(long, default_value = "u")]
    pub(crate) input_column: String,
    /// Skip this many leading rows of each --data record (e.g. a start-up transient).
    #[arg(long, default_value_t = 0)]
    pub(crate) skip: usize,
}
