//! What several of these tests share: the shared data's records and a fit's estimates
//! against their expected values.

pub use hyst_testkit::{data_file, rel_rms};

/// Columns `u` and `y` of a shared data file.
pub fn load_uy(rel: &str) -> Option<(Vec<f64>, Vec<f64>)> {
    let p = data_file(rel)?;
    let t = hyst_io::read_csv(&p).expect("shared data must parse");
    Some((
        t.column("u").unwrap().to_vec(),
        t.column("y").unwrap().to_vec(),
    ))
}

/// Each of a fit's free parameters, in order, is the named one and lies within `max_z` of its
/// standard errors of the expected value; prints every z, each line after `label`.
pub fn assert_estimates_near(
    label: &str,
    estimates: &[hyst_ident::residual::Estimate],
    expected: &[(&str, f64)],
    max_z: f64,
) {
    assert_eq!(estimates.len(), expected.len(), "{estimates:?}");
    for (e, &(name, value)) in estimates.iter().zip(expected) {
        assert_eq!(e.name, name);
        let z = (e.value - value) / e.se;
        eprintln!("{label}{name}: {:.5} ± {:.5} (z = {z:+.2})", e.value, e.se);
        assert!(
            z.abs() < max_z,
            "{name}: {} ± {} against {value}",
            e.value,
            e.se
        );
    }
}
