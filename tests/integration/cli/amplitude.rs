//! `hyst amplitude`: its options named by their flags.

use super::*;

/// `hyst amplitude`'s options out of range are named by their flags, before any record is
/// read (the input here does not exist).
#[test]
fn amplitude_options_are_named_by_their_flags_before_reading() {
    for (flag, value, says) in [
        ("--levels", "0", "--levels 0 is out of range: at least 1"),
        (
            "--cycles",
            "0.1",
            "--cycles 0.1 is out of range: between 0.5 and 50",
        ),
        ("--groups", "1", "--groups 1 is out of range: at least 2"),
        ("--band", "2", "--band 2 is out of range"),
        ("--period", "0", "--period 0 is out of range"),
    ] {
        let (ok, _, err) = hyst(&[
            "amplitude",
            "--input",
            "/nonexistent/record.csv",
            "--fs",
            "20",
            flag,
            value,
        ]);
        assert!(!ok);
        assert!(err.contains(says), "{flag}: {err}");
    }
}
