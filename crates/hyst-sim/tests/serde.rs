//! The JSON form of the simulation's options and excitations (feature `serde`): they read
//! back as written, missing options take their defaults, and an unknown key is refused.

use hyst_sim::excitation::{Multisine, Sweep};
use hyst_sim::{Decimation, Integrator, SimOptions};

#[test]
fn options_and_excitations_read_back() {
    let o = SimOptions {
        oversample: 4,
        integrator: Integrator::Trapezoidal,
        decimation: Decimation::Fir(vec![2, 2]),
        ..SimOptions::default()
    };
    let text = serde_json::to_string(&o).unwrap();
    assert_eq!(serde_json::from_str::<SimOptions>(&text).unwrap(), o);
    assert!(text.contains(r#""decimation":{"fir":[2,2]}"#), "{text}");
    let ms = Multisine::benchmark(50.0);
    let t = serde_json::to_string(&ms).unwrap();
    assert_eq!(serde_json::from_str::<Multisine>(&t).unwrap(), ms);
    let sw = Sweep::benchmark();
    let t = serde_json::to_string(&sw).unwrap();
    assert_eq!(serde_json::from_str::<Sweep>(&t).unwrap(), sw);
}

#[test]
fn missing_options_default_and_unknown_ones_are_refused() {
    let o: SimOptions = serde_json::from_str(r#"{"oversample": 8}"#).unwrap();
    assert_eq!(
        o,
        SimOptions {
            oversample: 8,
            ..SimOptions::default()
        }
    );
    let e = serde_json::from_str::<SimOptions>(r#"{"oversampling": 8}"#)
        .unwrap_err()
        .to_string();
    assert!(e.contains("unknown field `oversampling`"), "{e}");
}
