//! `cargo xtask bench storeys`: the storey fit of a three-storey chain from three levels
//! (issue 60's target: at most 2 min on this machine).

use hyst_ident::storeys::{Quantity, StoreyOptions, StoreyStructure, fit_storeys};
use hyst_sim::building::ShearBuilding;

/// Three levels of 300 s at 200 Hz (accelerations, 1 % noise) of the chain the tests use,
/// the element in its second storey; the fit timed once (it takes tens of seconds).
pub fn run() {
    let mut b = ShearBuilding::three_storey_example(Some(1));
    let fine = b.fine_rate().expect("a valid building");
    let records: Vec<Vec<Vec<f64>>> = [300.0, 1200.0, 3600.0]
        .iter()
        .enumerate()
        .map(|(i, sigma)| {
            b.load.rms = sigma * (fine / 8000.0f64).sqrt();
            b.generate(60_000, 61 + i as u64)
                .expect("a stable building")
        })
        .collect();
    let structure = StoreyStructure::new(
        vec![1000.0, 1000.0, 800.0],
        vec![0, 1, 2],
        Quantity::Acceleration,
        200.0,
    );
    let t = std::time::Instant::now();
    let fit = fit_storeys(&records, &structure, &StoreyOptions::default(), &|_| {})
        .expect("the fit runs");
    println!(
        "storey_fit_s_3levels_3floors_300s {:.1} s (target 120 s; element found in {}, truly in storey 2)",
        t.elapsed().as_secs_f64(),
        fit.storey
            .map_or("none".to_string(), |s| format!("storey {}", s + 1))
    );
}
