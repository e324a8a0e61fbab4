//! `hyst levels`: one Bouc-Wen model from records at several levels.

use super::*;

/// The benchmark under a white force of RMS `rms` (N) with measurement noise `noise` (m),
/// written by `hyst simulate`: one steady-state period of `samples` samples of a periodic
/// force, or (not `periodic`) `samples` samples from rest.
fn bouc_wen_white_record(
    name: &str,
    periodic: bool,
    rms: &str,
    samples: &str,
    seed: &str,
    noise: &str,
) -> PathBuf {
    let out = tmp(name);
    let mut args = vec!["simulate", "--system", "benchmark", "--excitation", "white"];
    if periodic {
        args.push("--periodic");
    }
    args.extend([
        "--rms",
        rms,
        "--samples",
        samples,
        "--seed",
        seed,
        "--noise",
        noise,
        "--out",
        s(&out),
    ]);
    let (ok, _, err) = hyst(&args);
    assert!(ok, "{err}");
    out
}

/// A record the levels cannot use is named in the error (the first of them, as the records
/// are identified in order): one under a multisine (no Zener spectral fit: the stationary
/// model does not hold), and one that is constant.
#[test]
fn levels_name_the_record_they_cannot_use() {
    let multisine = tmp("levels_multisine.csv");
    let (ok, _, err) = hyst(&[
        "simulate",
        "--system",
        "benchmark",
        "--excitation",
        "multisine",
        "--rms",
        "50",
        "--samples",
        "32768",
        "--seed",
        "3",
        "--out",
        s(&multisine),
    ]);
    assert!(ok, "{err}");
    let white = write_white_noise("levels_white.csv", 5);
    let (ok, _, err) = hyst(&[
        "levels",
        "--data",
        s(&multisine),
        s(&white),
        "--fs",
        "750",
        "--mass",
        "2",
    ]);
    assert!(!ok);
    assert!(
        err.contains(&format!("{}: ", multisine.display()))
            && err.contains("no Zener spectral fit")
            && err.contains("broadband random force"),
        "{err}"
    );
    let constant = write(
        "levels_constant.csv",
        &format!("y\n{}", "1.5\n".repeat(4096)),
    );
    let (ok, _, err) = hyst(&[
        "levels",
        "--data",
        s(&constant),
        s(&white),
        "--fs",
        "750",
        "--mass",
        "2",
    ]);
    assert!(!ok);
    assert!(err.contains(&format!("{}: ", constant.display())), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn levels_gives_one_bouc_wen_model_of_several_records() {
    let records: Vec<PathBuf> = [("10", "1"), ("50", "2"), ("90", "3")]
        .iter()
        .map(|(rms, seed)| {
            // As measured: from rest, the first 4096 samples (5.5 s) skipped below.
            bouc_wen_white_record(
                &format!("bw_levels_{rms}.csv"),
                false,
                rms,
                "69632",
                seed,
                "7.4e-6",
            )
        })
        .collect();
    let val = bouc_wen_white_record("bw_levels_val.csv", true, "50", "8192", "4", "0");
    let json = tmp("bw_levels.json");
    let svg_dir = tmp("bw_levels_svg");
    let mut args = vec!["levels", "--data"];
    args.extend(records.iter().map(|p| s(p)));
    args.extend([
        "--fs",
        "750",
        "--mass",
        "2",
        "--validate",
        s(&val),
        "--periodic",
        "--json",
        s(&json),
        "--svg-dir",
        s(&svg_dir),
        "--skip",
        "4096",
        "--by-simulation",
    ]);
    let (ok, out, err) = hyst(&args);
    assert!(ok, "{err}");
    assert!(out.contains("Bouc-Wen of all levels: c "), "{out}");
    assert!(!out.contains("warning"), "{out}");
    for f in ["levels_kinf.svg", "levels_omega.svg"] {
        let svg = std::fs::read_to_string(svg_dir.join(f)).unwrap();
        assert!(
            svg.contains("the model&apos;s statistical linearization"),
            "{f}"
        );
    }
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["levels"].as_array().map(Vec::len), Some(3));
    // The model's own linearization at each level lies near the Zener identified there.
    for lv in v["levels"].as_array().unwrap() {
        let (got, own, se) = (
            lv["fit"]["k_inf"].as_f64().unwrap(),
            lv["model_zener"]["k_inf"].as_f64().unwrap(),
            lv["fit"]["se"][2].as_f64().unwrap(),
        );
        // Three levels, three parameters fitted to six numbers: each within 4 SE.
        assert!((got - own).abs() < 4.0 * se, "{lv}");
    }
    let statistical = &v["models"]["statistical"];
    let sigma_z = |i: usize| statistical["moments"][i]["sigma_z"].as_f64().unwrap();
    assert!(sigma_z(2) > sigma_z(0));
    let m = &statistical["oscillator"];
    // Standard errors in the order (c, k, α, βγ, βδ).
    let se_of = |se: &serde_json::Value, key: &str| {
        let i = ["c", "k", "alpha", "beta_gamma", "beta_delta"]
            .iter()
            .position(|k| *k == key)
            .unwrap();
        se[i].as_f64().unwrap()
    };
    // The benchmark's α = 5e4 N/m, βγ = 800 and βδ = −1100 1/m. Each within four of its
    // standard errors plus the Gaussian closure's own bias, which the 2¹⁷-sample sweep
    // measures (docs/results.md: α +6 %, βγ −8 %, βδ +20 %; allowed here 10, 10 and 25 %).
    for (key, truth, bias) in [
        ("alpha", 5e4, 0.10),
        ("beta_gamma", 800.0, 0.10),
        ("beta_delta", -1100.0, 0.25),
    ] {
        let (got, se) = (param(m, key).unwrap(), se_of(&statistical["se"], key));
        assert!(
            (got - truth).abs() < 4.0 * se + bias * truth.abs(),
            "{key}: {got} ± {se} against {truth}"
        );
    }
    // The validation record at 50 N: six sets of seeds gave 1.5-3.8 % with records of this
    // length (the per-level mapped models give 2.1-4.6 % on the sweep's longer records).
    let eps = v["validation"][0]["statistical"]["epsilon"]
        .as_f64()
        .unwrap();
    assert!(eps > 0.0 && eps < 0.05, "{eps}");
    // The model fitted by simulation validates better than the statistical one (five
    // nine-level sweeps and the three-level test: 0.0-0.8 % against 0.9-3.4 %).
    assert!(out.contains("Bouc-Wen by simulation: c "), "{out}");
    assert!(
        param(&v["models"]["by_simulation"]["oscillator"], "alpha").is_some(),
        "{v}"
    );
    let eps_sim = v["validation"][0]["by_simulation"]["epsilon"]
        .as_f64()
        .unwrap();
    assert!(eps_sim < eps, "{eps_sim} vs {eps}");
    // Simulated as the records were made (from rest), every parameter within four of its
    // standard errors of the benchmark's; c = 10 N s/m included, which simulating them as
    // periodic records biases by about -2.3 N s/m (docs/paper-deviations.md).
    let sim = &v["models"]["by_simulation"];
    for (key, truth) in [
        ("c", 10.0),
        ("k", 5e4),
        ("alpha", 5e4),
        ("beta_gamma", 800.0),
        ("beta_delta", -1100.0),
    ] {
        let (got, se) = (
            param(&sim["oscillator"], key).unwrap(),
            se_of(&sim["se"], key),
        );
        assert!(
            (got - truth).abs() < 4.0 * se,
            "by simulation, {key}: {got} ± {se} against {truth}"
        );
    }
    // With the exponent free (the statistical fit only): ν printed with its standard error
    // and in the JSON, and the benchmark's ν = 1 within four of them. Measured: 0.85 ± 0.05;
    // the Gaussian closure reads ν low once the levels reach 90 N, as it reads α and βδ off
    // (0.91 ± 0.03 over five levels of 10-90 N, 1.03 ± 0.06 over 10-50 N; docs/results.md).
    let json_nu = tmp("bw_levels_nu.json");
    let mut args = vec!["levels", "--data"];
    args.extend(records.iter().map(|p| s(p)));
    args.extend([
        "--fs",
        "750",
        "--mass",
        "2",
        "--skip",
        "4096",
        "--fit-exponent",
        "--json",
        s(&json_nu),
    ]);
    let (ok, out, err) = hyst(&args);
    assert!(ok, "{err}");
    assert!(out.contains("exponent ν "), "{out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json_nu).unwrap()).unwrap();
    let statistical = &v["models"]["statistical"];
    let (nu, nu_se) = (
        param(&statistical["oscillator"], "nu").unwrap(),
        statistical["nu_se"].as_f64().unwrap(),
    );
    eprintln!("levels --fit-exponent: ν = {nu} ± {nu_se}");
    assert!((nu - 1.0).abs() < 4.0 * nu_se, "ν = {nu} ± {nu_se}");
    // `hyst levels` on two records at 750 Hz, mass 2, with more arguments.
    let two_levels = |a: &PathBuf, b: &PathBuf, more: &[&str]| {
        let mut args = vec!["levels", "--data", s(a), s(b), "--fs", "750", "--mass", "2"];
        args.extend(more);
        hyst(&args)
    };
    // Two records cannot give ν beside α, βγ, βδ, and the user is told.
    let (ok, _, err) = two_levels(&records[0], &records[2], &["--fit-exponent"]);
    assert!(
        !ok && err.contains("three or more are needed to fit the exponent"),
        "{err}"
    );
    // Two records at the same level do not separate the three unknowns, and the user is told.
    let again = bouc_wen_white_record("bw_levels_90b.csv", false, "90", "69632", "9", "7.4e-6");
    let (ok, out, err) = two_levels(&records[2], &again, &[]);
    assert!(ok, "{err}");
    assert!(
        out.contains("warning: the levels do not determine"),
        "{out}"
    );
    // A record that is no oscillator's response (white noise) gives no level, and the
    // file is named.
    let (ok, _, err) = two_levels(&records[0], &write_white_noise("levels_noise.csv", 5), &[]);
    assert!(!ok);
    assert!(err.contains("levels_noise.csv"), "{err}");
    // A --skip that leaves nothing names the record, as `hyst ident`'s does.
    let (ok, _, err) = two_levels(&records[0], &records[1], &["--skip", "69632"]);
    assert!(!ok);
    assert!(
        err.contains("--skip 69632 leaves none of the 69632 rows of")
            && err.contains("bw_levels_10.csv"),
        "{err}"
    );
    let (ok, _, err) = hyst(&[
        "levels",
        "--data",
        s(&records[0]),
        "--fs",
        "750",
        "--mass",
        "2",
    ]);
    assert!(!ok);
    assert!(err.contains("2 values required"), "{err}");
}

/// `hyst simulate --structure` of the fit in `json` under a force no level had, against the
/// true structure's accelerations under it (the same arithmetic, another structure: the
/// generator's own).
fn the_fitted_structure_simulates_a_measured_force(json: &std::path::Path) {
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let truth = hyst_sim::building::ShearBuilding::three_storey_example(Some(1));
    // 60 s at 200 Hz: white samples of 190 N (density 180 N²/Hz, the middle level's).
    let (n, steps) = (12_000, 20);
    let mut rng = rand::rngs::StdRng::seed_from_u64(8_400_601);
    let normal = Normal::new(0.0, 190.0).unwrap();
    let forces: Vec<Vec<f64>> = (0..3)
        .map(|_| (0..n).map(|_| normal.sample(&mut rng)).collect())
        .collect();
    // From rest one sample before, linear between samples (as the command drives its model).
    let loads: Vec<Vec<f64>> = forces
        .iter()
        .map(|f| {
            (0..=n * steps)
                .map(|i| {
                    let (k, r) = (i / steps, (i % steps) as f64 / steps as f64);
                    let before = if k == 0 { 0.0 } else { f[k - 1] };
                    let after = f[k.min(n - 1)];
                    before + r * (after - before)
                })
                .collect()
        })
        .collect();
    let y = truth.respond(&loads, steps, 0).unwrap();
    let mut text = String::from("f1,f2,f3,a1,a2,a3\n");
    for t in 0..n {
        let row: Vec<String> = forces.iter().chain(&y).map(|c| c[t].to_string()).collect();
        text.push_str(&(row.join(",") + "\n"));
    }
    let record = write("storey_forced.csv", &text);
    let out = tmp("storey_simulated.csv");
    let (ok, printed, err) = hyst(&[
        "simulate",
        "--structure",
        s(json),
        "--input",
        s(&record),
        "--fs",
        "200",
        "--forces",
        "f1,f2,f3",
        "--out",
        s(&out),
        "--measured",
        s(&record),
        "--compare-skip",
        "2000",
    ]);
    assert!(ok, "{err}");
    let header = std::fs::read_to_string(&out).unwrap();
    assert!(header.starts_with("f1,f2,f3,a1,a2,a3\n"), "{header:.40}");
    let shares: Vec<f64> = printed
        .lines()
        .filter_map(|l| {
            l.trim_end()
                .strip_suffix(" %")?
                .rsplit(' ')
                .next()?
                .parse()
                .ok()
        })
        .collect();
    // The fit from 150 s records predicts each floor's acceleration to about 10 % of its
    // deviation (a 1 % error in a frequency dephases a lightly damped mode within tens of
    // cycles); a channel read from the wrong floor or a force on the wrong one errs by
    // 60 % or more.
    assert_eq!(shares.len(), 3, "{printed}");
    assert!(shares.iter().all(|v| *v < 30.0), "{printed}");
    // The oscillator's flags are not the structure's.
    let (ok, _, err) = hyst(&[
        "simulate",
        "--structure",
        s(json),
        "--input",
        s(&record),
        "--fs",
        "200",
        "--forces",
        "f1,f2",
        "--out",
        s(&out),
    ]);
    assert!(
        !ok && err.contains("2 force column(s) given; the fit loads 3"),
        "{err}"
    );
    let (ok, _, err) = hyst(&["simulate", "--forces", "f1", "--out", s(&out)]);
    assert!(!ok && err.contains("go with --structure"), "{err}");
    // An edited fit is refused before it is simulated, naming its field (issue 77: an
    // element in storey 9 of 3 panicked, a warm-up of 10¹² samples aborted on its memory).
    let fit: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    type Edit = fn(&mut serde_json::Value);
    let edits: [(&str, Edit); 3] = [
        ("hysteresis.storey", |v| {
            v["storey"] = 9.into();
            v["building"]["hysteresis"]["storey"] = 9.into();
        }),
        ("reading.warm_up", |v| {
            v["reading"]["warm_up"] = 1_000_000_000_000u64.into()
        }),
        ("building.stiffnesses[0]", |v| {
            let k = v["building"]["stiffnesses"][0].as_f64().unwrap();
            v["building"]["stiffnesses"][0] = (k / 10.0).into();
        }),
    ];
    for (field, edit) in edits {
        let mut v = fit.clone();
        edit(&mut v);
        let edited = write("storey_fit_edited.json", &v.to_string());
        let (ok, _, err) = hyst(&[
            "simulate",
            "--structure",
            s(&edited),
            "--input",
            s(&record),
            "--fs",
            "200",
            "--forces",
            "f1,f2,f3",
            "--out",
            s(&out),
        ]);
        assert!(
            !ok && err.contains(field) && !err.contains("panicked"),
            "{field}: {err}"
        );
    }
}

/// Three levels of a three-storey shear chain with a Bouc-Wen element in its second storey
/// (the project's building generator: this tests the command's plumbing; the route is
/// judged on an independent generator in hyst-ident's `storeys` tests), accelerations in
/// columns a1..a3 at 200 Hz.
fn storey_records(seconds: f64) -> Vec<PathBuf> {
    let mut b = hyst_sim::building::ShearBuilding::three_storey_example(Some(1));
    let fine = b.fine_rate().unwrap();
    [300.0, 1200.0, 3600.0]
        .iter()
        .enumerate()
        .map(|(i, sigma)| {
            // The same density σ²/8000 N²/Hz as the independent generator's levels.
            b.load.rms = sigma * (fine / 8000.0f64).sqrt();
            let y = b
                .generate((seconds * 200.0) as usize, 8_300_501 + i as u64)
                .unwrap();
            let mut text = String::from("a1,a2,a3\n");
            for ((a, b), c) in y[0].iter().zip(&y[1]).zip(&y[2]) {
                text.push_str(&format!("{a},{b},{c}\n"));
            }
            write(&format!("storey_level_{i}.csv"), &text)
        })
        .collect()
}

#[test]
fn levels_with_masses_locate_the_storey_and_write_the_fit() {
    let data = storey_records(150.0);
    let json = tmp("storey_fit.json");
    let mut args = vec![
        "levels",
        "--fs",
        "200",
        "--masses",
        "1000,1000,800",
        "--data",
    ];
    args.extend(data.iter().map(|p| s(p)));
    args.extend(["--json", s(&json), "--predict", "2"]);
    let (ok, out, err) = hyst(&args);
    assert!(ok, "{err}");
    assert!(out.contains("Hysteretic element: storey 2"), "{out}");
    assert!(
        out.contains("Predicted at 2.000 × the loudest level's force"),
        "{out}"
    );
    assert!(out.contains("runner-up"), "{out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    // The JSON counts storeys from 0 (the library's type), the text from 1.
    assert_eq!(v["storey"], 1, "{v}");
    assert_eq!(v["candidates"].as_array().unwrap().len(), 4);
    let names: Vec<&str> = v["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "k1", "k2", "k3", "zeta1", "zeta2", "zeta3", "q1", "q2", "q3", "b", "a", "beta",
            "gamma"
        ]
    );
    let predicted = &v["predictions"][0];
    let q3 = v["force_densities"][2].as_f64().unwrap();
    // Twice the loudest level's force: four times its density.
    assert!((predicted["force_density"].as_f64().unwrap() / q3 - 4.0).abs() < 1e-9);
    assert_eq!(
        predicted["drift_rms"].as_array().unwrap().len(),
        3,
        "{predicted}"
    );
    the_fitted_structure_simulates_a_measured_force(&json);
    let levels: Vec<&str> = data.iter().map(|p| s(p)).collect();
    super::hostile::storey_surfaces_refuse_by_name(&json, &tmp("storey_forced.csv"), &levels);
    // The model's amplitude curves beside the measured ones (a check that needs no truth):
    // its own records at the three levels analysed alike, each measured point against the
    // model's curve at its amplitude.
    let curves = tmp("storey_curves.json");
    let mut args = vec![
        "amplitude",
        "--fs",
        "200",
        "--measured",
        "acceleration",
        "--input",
    ];
    args.extend(data.iter().map(|p| s(p)));
    args.extend(["--model", s(&json), "--json", s(&curves)]);
    let (ok, out, err) = hyst(&args);
    assert!(ok, "{err}");
    assert!(
        out.contains("The model's curves against the measured"),
        "{out}"
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&curves).unwrap()).unwrap();
    assert_eq!(v["model"]["records"].as_array().unwrap().len(), 3);
    let z: Vec<f64> = v["agreement"]["modes"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|m| {
            let f = m["frequency_z"].as_array().unwrap().clone();
            f.into_iter()
                .chain(m["damping_z"].as_array().unwrap().clone())
        })
        .map(|z| z.as_f64().unwrap())
        .collect();
    let inside = z.iter().filter(|z| z.abs() <= 2.0).count() as f64 / z.len() as f64;
    // The model was fitted to these records: its curves within two standard errors of
    // about 95 % of the points (130 of 136 on this seed); under 80 % would say the model or
    // the comparison is wrong (a binomial of ~130 at 95 % falls below 88 % under 0.1 % of
    // the time).
    assert!(
        z.len() > 50 && inside > 0.8,
        "{inside} of {}\n{out}",
        z.len()
    );
    let (ok, _, err) = hyst(&[
        "amplitude",
        "--fs",
        "200",
        "--input",
        s(&data[0]),
        "--model",
        s(&json),
    ]);
    assert!(!ok && err.contains("was fitted to 3 records"), "{err}");
    // Records beside the model that are not its levels as it read them are refused before
    // any is analysed (issue 77: each was compared as if it matched): in reverse order,
    // said to read displacements, or with the channels on other floors.
    let reversed: Vec<&str> = data.iter().rev().map(|p| s(p)).collect();
    let beside = |more: &[&str], inputs: &[&str]| {
        let mut args = vec!["amplitude", "--fs", "200", "--model", s(&json)];
        args.extend(more);
        args.push("--input");
        args.extend(inputs);
        hyst(&args)
    };
    let inputs: Vec<&str> = data.iter().map(|p| s(p)).collect();
    let (ok, _, err) = beside(&[], &reversed);
    assert!(
        !ok && err.contains("does not read as the fit's level 1, but as its level 3"),
        "{err}"
    );
    let (ok, _, err) = beside(&["--measured", "displacement"], &inputs);
    assert!(
        !ok && err.contains("--measured displacement") && err.contains("records of acceleration"),
        "{err}"
    );
    let (ok, _, err) = beside(&["--floors", "3,2,1"], &inputs);
    assert!(
        !ok && err.contains("--floors [3, 2, 1]") && err.contains("floors [1, 2, 3]"),
        "{err}"
    );
    // Bad input is named: a floor counted from 0, a sensor above the top, one level.
    let (ok, _, err) = hyst(&[
        "levels",
        "--fs",
        "200",
        "--masses",
        "1000,1000,800",
        "--floors",
        "0,1,2",
        "--data",
        s(&data[0]),
        s(&data[1]),
    ]);
    assert!(
        !ok && err.contains("--floors: floors count from 1"),
        "{err}"
    );
    let (ok, _, err) = hyst(&[
        "levels",
        "--fs",
        "200",
        "--masses",
        "1000,1000",
        "--data",
        s(&data[0]),
        s(&data[1]),
    ]);
    assert!(
        !ok && err.contains("channel 3 is said to be on floor 3; the structure has 2 floors"),
        "{err}"
    );
    // The three-storey structure with these flags more, on two levels: refused, saying why.
    // A floor loaded twice and one sensor read as three floors were fitted (issue 77).
    let refusals = [
        (["--mass", "2"], "--mass"),
        (["--load-floors", "3,3"], "load floor 3: named twice"),
        (["--channels", "a1,a1,a1"], "--channels names `a1` twice"),
    ];
    for (more, why) in refusals {
        let mut args = vec!["levels", "--fs", "200", "--masses", "1000,1000,800"];
        args.extend(more);
        args.extend(["--data", s(&data[0]), s(&data[1])]);
        let (ok, _, err) = hyst(&args);
        assert!(!ok && err.contains(why), "{more:?}: {err}");
    }
    // A fit that did not reach its records (a first floor 1000 times too heavy: the model's
    // mode 1 sits at 3.7 Hz against 2.5 Hz measured) is said as such, its document written
    // but refused as a model, and the run fails; 40 s of two levels suffice to show it.
    let short: Vec<PathBuf> = data[..2]
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let text = std::fs::read_to_string(p).unwrap();
            let head: Vec<&str> = text.lines().take(8001).collect();
            write(&format!("storey_short_{i}.csv"), &(head.join("\n") + "\n"))
        })
        .collect();
    let far = tmp("storey_far.json");
    let (ok, out, err) = hyst(&[
        "levels",
        "--fs",
        "200",
        "--masses",
        "1e6,1000,800",
        "--data",
        s(&short[0]),
        s(&short[1]),
        "--json",
        s(&far),
        "--predict",
        "2",
    ]);
    assert!(!ok && err.contains("did not reach its records"), "{err}");
    assert!(out.contains("Hysteretic element: not located"), "{out}");
    assert!(
        out.contains("level 1 mode 1 at") && !out.contains(": an element"),
        "{out}"
    );
    assert!(out.contains("Not predicted at 2"), "{out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&far).unwrap()).unwrap();
    assert_eq!(v["agreement"]["verdict"], "far", "{v}");
    let (ok, _, err) = hyst(&[
        "simulate",
        "--structure",
        s(&far),
        "--input",
        s(&tmp("storey_forced.csv")),
        "--fs",
        "200",
        "--forces",
        "f1,f2,f3",
        "--out",
        s(&tmp("storey_far_sim.csv")),
    ]);
    assert!(!ok && err.contains("agreement.verdict"), "{err}");
}
