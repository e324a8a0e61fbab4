//! Numbers out of the JSON the Python comparison scripts print (pyOMA2's results): a missing
//! or non-numeric entry becomes NaN, which the comparisons then show as such.

use covssi::Complex64 as C64;

/// Complex numbers written as `[re, im]` pairs.
pub(crate) fn complex(v: &serde_json::Value) -> Vec<C64> {
    v.as_array()
        .map(|a| {
            a.iter()
                .map(|p| {
                    C64::new(
                        p[0].as_f64().unwrap_or(f64::NAN),
                        p[1].as_f64().unwrap_or(f64::NAN),
                    )
                })
                .collect()
        })
        .unwrap_or_default()
}

/// Real numbers.
pub(crate) fn numbers(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .map(|a| a.iter().map(|x| x.as_f64().unwrap_or(f64::NAN)).collect())
        .unwrap_or_default()
}
