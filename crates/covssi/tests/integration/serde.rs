//! The JSON form of the options and results (feature `serde`): every result reads back as
//! it was written, a pole's label is its status's name, and an unknown option is refused.

use covssi::synth::ModalRecord;
use covssi::{AnalysisOptions, BlockRows, ModalAnalysis, SsiOptions, analyze};

fn analysis() -> ModalAnalysis {
    let y = ModalRecord::new(20.0, &[(1.5, 0.02), (4.0, 0.03)])
        .with_gains(vec![
            vec![1.0, 0.0, 0.5, 0.0],
            vec![0.4, 0.1, -1.0, 0.0],
            vec![-0.2, 0.0, 0.8, 0.3],
        ])
        .with_noise(0.05)
        .generate(8192, 21);
    let v: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
    // Fixed block rows: the JSON's form is the subject here, not the defaults (with those
    // read from the record SSI also keeps a third, weak mode, and the indices move).
    let opts = AnalysisOptions::default()
        .with_ssi(SsiOptions {
            block_rows: BlockRows::Count(20),
            max_order: Some(20),
            ..SsiOptions::default()
        })
        .with_refine(Some(covssi::RefineOptions::default()));
    analyze(&v, 20.0, &opts).unwrap()
}

#[test]
fn an_analysis_reads_back_as_written() {
    let a = analysis();
    assert!(a.refined.as_ref().is_some_and(|r| r.modes.len() == 2));
    let text = serde_json::to_string(&a).unwrap();
    let back: ModalAnalysis = serde_json::from_str(&text).unwrap();
    assert_eq!(back, a);
    // SSI's fields at the top level, its clusters as `ssi_modes` and the answer as `modes`
    // (one list of modes, issue 76), complex numbers as [re, im].
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let m = &v["ssi_modes"][0];
    assert_eq!(
        v["modes"].as_array().unwrap().len(),
        a.decision.modes.len(),
        "{v}"
    );
    assert!(v["decision"].get("modes").is_none(), "{v}");
    assert_eq!(m["lambda"][0].as_f64(), Some(a.ssi.modes[0].lambda.re));
    assert_eq!(m["lambda"][1].as_f64(), Some(a.ssi.modes[0].lambda.im));
    assert_eq!(v["refined"]["modes"][0]["ssi_mode"].as_u64(), Some(0));
}

#[test]
fn a_pole_s_label_is_its_status_name() {
    let a = analysis();
    let v = serde_json::to_value(&a).unwrap();
    let mut seen = std::collections::BTreeSet::new();
    for (o, order) in a.ssi.diagram.orders.iter().enumerate() {
        for (p, pole) in order.poles.iter().enumerate() {
            let json = &v["diagram"]["orders"][o]["poles"][p];
            assert_eq!(json["label"].as_str(), Some(pole.status.name()), "{json}");
            seen.insert(pole.status.name());
        }
    }
    // Stable and rejected poles both met.
    assert!(seen.iter().any(|s| s.starts_with("stable")), "{seen:?}");
    assert!(seen.iter().any(|s| s.starts_with("rejected")), "{seen:?}");
}

#[test]
fn options_read_with_defaults_and_refuse_unknown_keys() {
    let o: AnalysisOptions =
        serde_json::from_str(r#"{"ssi": {"block_rows": {"count": 30}}, "refine": null}"#).unwrap();
    let expected = AnalysisOptions::default()
        .with_ssi(SsiOptions {
            block_rows: covssi::BlockRows::Count(30),
            ..SsiOptions::default()
        })
        .with_refine(None);
    assert_eq!(o, expected);
    let e = serde_json::from_str::<AnalysisOptions>(r#"{"ssi": {"block_row": 30}}"#)
        .unwrap_err()
        .to_string();
    assert!(e.contains("unknown field `block_row`"), "{e}");
    assert!(e.contains("block_rows"), "{e}");
}
