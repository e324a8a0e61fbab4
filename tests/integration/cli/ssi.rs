//! `hyst ssi`: modes, shapes, errors and their files; the refinement's choices; lags, gains, channels; setups merged.

use super::*;

/// A NaN in a column no one analyses does not make the file unreadable (issue 58): the
/// channels chosen are analysed; without --columns the NaN's column is a channel, refused by
/// its row and column.
#[test]
fn a_nan_in_a_column_not_analysed_is_no_error() {
    let text = std::fs::read_to_string(write_two_sines()).unwrap();
    let mut lines = text.lines();
    let mut out = format!("{},note\n", lines.next().unwrap());
    for (k, l) in lines.enumerate() {
        out += &format!("{l},{}\n", if k == 7 { "NaN" } else { "1" });
    }
    let p = write("sine_note.csv", &out);
    let (ok, _, err) = hyst(&[
        "ssi",
        "--input",
        s(&p),
        "--fs",
        "10",
        "--no-refine",
        "--columns",
        "y",
    ]);
    assert!(ok, "{err}");
    let err = ssi_fails(&p, &["--no-refine"]);
    assert!(
        err.contains("row 9, column `note`: value NaN is not finite"),
        "{err}"
    );
}

/// A record with two dead sensors reads as given (issue 76): without --columns the channel
/// that is all NaN and the constant one are left out and named in one line, and the analysis
/// is the one of the live channels named by hand; with no live channel, the error names the
/// dead ones.
#[test]
fn dead_channels_are_left_out_and_named() {
    let mut out = String::from("y,dead,z,flat\n");
    for k in 0..400 {
        let t = k as f64;
        let y = (0.7 * t).sin() + 0.3 * (1.9 * t).cos();
        let z = 0.5 * (0.7 * t).sin() - 0.8 * (1.9 * t).cos();
        out += &format!("{y},NaN,{z},0\n");
    }
    let p = write("dead_sensors.csv", &out);
    let run = |extra: &[&str]| {
        let mut args = vec!["ssi", "--input", s(&p), "--fs", "10", "--no-refine"];
        args.extend_from_slice(extra);
        hyst(&args)
    };
    let (ok, by_default, err) = run(&[]);
    assert!(ok, "{err}");
    assert_eq!(
        err.lines()
            .filter(|l| l.contains("carry no signal"))
            .count(),
        1,
        "{err}"
    );
    assert!(
        err.contains("2 channel(s) carry no signal and are left out: `dead` (no finite value), `flat` (constant 0)"),
        "{err}"
    );
    let (ok, by_hand, err) = run(&["--columns", "y,z"]);
    assert!(ok, "{err}");
    assert!(!err.contains("carry no signal"), "{err}");
    assert_eq!(by_default, by_hand);
    // Named by hand, a constant channel is refused by its column's name.
    let (ok, _, err) = run(&["--columns", "y,flat"]);
    assert!(
        !ok && err.contains("dead_sensors.csv: column `flat` is constant (value 0)"),
        "{err}"
    );
    let dead = write("all_dead.csv", "a,b\nNaN,1\nNaN,1\nNaN,1\n");
    let err = ssi_fails(&dead, &[]);
    assert!(
        err.contains("no channel carries a signal: `a` (no finite value), `b` (constant 1)"),
        "{err}"
    );
}

#[test]
fn ssi_writes_modes_json_and_svg() {
    let Some(path) = common::data_file("oma/data_sdof.csv") else {
        return;
    };
    let (json, svg) = (tmp("sdof.json"), tmp("sdof.svg"));
    let (ok, out, err) = hyst(&[
        "ssi",
        "--input",
        s(&path),
        "--fs",
        "20",
        "--block-rows",
        "60",
        "--max-order",
        "40",
        "--json",
        s(&json),
        "--svg",
        s(&svg),
        "--refine",
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("mode"), "{out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let modes = v["ssi_modes"].as_array().unwrap();
    let m = modes
        .iter()
        .find(|m| (m["frequency_hz"].as_f64().unwrap() - 1.5).abs() < 0.01)
        .expect("the 1.5 Hz mode");
    // 2 % damping within the estimator's spread (README: σ(ζ) ≈ 5 % of ζ).
    assert!((m["damping_ratio"].as_f64().unwrap() - 0.02).abs() < 0.002);
    for key in ["frequency_std_hz", "damping_std", "members", "shape"] {
        assert!(!m[key].is_null(), "{key}");
    }
    // Each member names a pole of the per-order list: (order, index), one per order; the
    // member poles' mean frequency is the mode's.
    let members = m["members"].as_array().unwrap();
    // The printed line gives the span of orders, the first and last member's.
    let span = format!(
        "({} poles, orders {}–{})",
        members.len(),
        members[0][0],
        members[members.len() - 1][0]
    );
    assert!(out.contains(&span), "{span} not in {out}");
    let mut mean = 0.0;
    for pair in members {
        let (order, index) = (pair[0].as_u64().unwrap(), pair[1].as_u64().unwrap());
        let o = v["diagram"]["orders"]
            .as_array()
            .unwrap()
            .iter()
            .find(|o| o["order"].as_u64() == Some(order))
            .expect("the member's order is listed");
        let p = &o["poles"][index as usize];
        assert_eq!(p["label"], "stable_fd", "{p}");
        mean += p["frequency_hz"].as_f64().unwrap() / members.len() as f64;
    }
    // The mean of the same numbers, summed in another order: rounding only.
    approx::assert_relative_eq!(
        mean,
        m["frequency_hz"].as_f64().unwrap(),
        max_relative = 1e-12
    );
    assert!(v["real_poles"].is_array());
    // The maximum-likelihood refinement (`--refine`): one mode, the 1.5 Hz oscillator;
    // every other SSI mode dropped; the truth (1.5 Hz, 2 %) within 4 standard errors; the
    // record follows the model.
    let r = &v["refined"];
    let kept = r["modes"].as_array().unwrap();
    assert_eq!(kept.len(), 1, "{r}");
    assert_eq!(
        r["dropped"].as_array().unwrap().len(),
        modes.len() - 1,
        "{r}"
    );
    let k = &kept[0];
    let f_err = (k["frequency_hz"].as_f64().unwrap() - 1.5).abs();
    let z_err = (k["damping_ratio"].as_f64().unwrap() - 0.02).abs();
    assert!(f_err < 4.0 * k["frequency_se_hz"].as_f64().unwrap(), "{k}");
    assert!(z_err < 4.0 * k["damping_se"].as_f64().unwrap(), "{k}");
    assert!(
        k["evidence"].as_f64().unwrap() > r["penalty"].as_f64().unwrap(),
        "{k}"
    );
    assert!(r["misfit"].as_f64().unwrap() < 0.05, "{r}");
    assert_eq!(
        r["joint"], false,
        "one channel has no joint likelihood: {r}"
    );
    assert!(out.contains("refined by maximum likelihood"), "{out}");
    let first = &v["diagram"]["orders"][5]["poles"][0];
    assert!(first["label"].is_string() && first["lambda"].is_array());
    assert!(std::fs::read_to_string(&svg).unwrap().starts_with("<svg"));
}

#[test]
fn ssi_without_refinement() {
    let Some(path) = common::data_file("oma/data_sdof.csv") else {
        return;
    };
    let json = tmp("sdof_plain.json");
    let (ok, out, err) = hyst(&[
        "ssi",
        "--input",
        s(&path),
        "--fs",
        "20",
        "--block-rows",
        "60",
        "--json",
        s(&json),
        "--no-refine",
    ]);
    assert!(ok, "{err}");
    assert!(
        !out.contains("refined") && !err.contains("refining"),
        "{out}{err}"
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!(v["refined"].is_null() && !v["ssi_modes"].as_array().unwrap().is_empty());
    // One channel: its shapes are numbers, so neither shapes nor MACs are printed.
    assert!(!out.contains("MAC between"), "{out}");
}

/// With several channels `hyst ssi` prints each mode's shape with its MPC and the MAC
/// between the modes, and writes both to the JSON. Checked here against the formulas
/// computed from the JSON's own shapes: MAC = |aᴴb|²/(|a|²|b|²), MPC from the scatter of
/// the entries' real and imaginary parts (rounding: 1e-12).
#[test]
fn ssi_reports_shapes_mpc_and_mac() {
    let Some(path) = common::data_file("oma/data_3dof.csv") else {
        return;
    };
    let json = tmp("3dof_mac.json");
    let (ok, out, err) = hyst(&[
        "ssi",
        "--input",
        s(&path),
        "--fs",
        "20",
        "--columns",
        "y1,y2,y3",
        "--block-rows",
        "20",
        "--json",
        s(&json),
        "--no-refine",
    ]);
    assert!(ok, "{err}");
    assert!(
        out.contains("MAC between the modes") && out.contains("MPC"),
        "{out}"
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let shapes: Vec<Vec<(f64, f64)>> = v["ssi_modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            m["shape"]
                .as_array()
                .unwrap()
                .iter()
                .map(|c| (c[0].as_f64().unwrap(), c[1].as_f64().unwrap()))
                .collect()
        })
        .collect();
    let mac = v["mac"].as_array().unwrap();
    assert_eq!(mac.len(), shapes.len());
    for (i, a) in shapes.iter().enumerate() {
        // aᴴb = Σ (ar − i ai)(br + i bi).
        for (j, b) in shapes.iter().enumerate() {
            let (mut re, mut im, mut na, mut nb) = (0.0, 0.0, 0.0, 0.0);
            for (&(ar, ai), &(br, bi)) in a.iter().zip(b) {
                re += ar * br + ai * bi;
                im += ar * bi - ai * br;
                na += ar * ar + ai * ai;
                nb += br * br + bi * bi;
            }
            let expected = (re * re + im * im) / (na * nb);
            let got = mac[i][j].as_f64().unwrap();
            assert!(
                (got - expected).abs() < 1e-12,
                "MAC[{i}][{j}] {got} vs {expected}"
            );
        }
        let (sxx, syy, sxy) = a.iter().fold((0.0, 0.0, 0.0), |(xx, yy, xy), &(x, y)| {
            (xx + x * x, yy + y * y, xy + x * y)
        });
        // The scatter matrix's eigenvalues: MPC = ((σ₁ − σ₂)/(σ₁ + σ₂))².
        let half = ((sxx - syy).powi(2) / 4.0 + sxy * sxy).sqrt();
        let (s1, s2) = ((sxx + syy) / 2.0 + half, (sxx + syy) / 2.0 - half);
        let expected = ((s1 - s2) / (s1 + s2)).powi(2);
        let got = v["ssi_modes"][i]["mpc"].as_f64().unwrap();
        assert!(
            (got - expected).abs() < 1e-12,
            "MPC of mode {i}: {got} vs {expected}"
        );
    }
}

/// Three channels are refined (`--refine`) jointly by default and each alone with `--no-joint`; the JSON
/// and the printed header say which, and both find the three modes (with their shapes when
/// joint).
#[test]
fn ssi_joint_and_per_channel_refinement() {
    let Some(path) = common::data_file("oma/data_3dof.csv") else {
        return;
    };
    for (flag, joint, header) in [
        (None, true, "channels jointly"),
        (Some("--no-joint"), false, "each channel's spectrum"),
    ] {
        let json = tmp(&format!("3dof_joint_{joint}.json"));
        let mut args = vec![
            "ssi",
            "--input",
            s(&path),
            "--fs",
            "20",
            "--columns",
            "y1,y2,y3",
            "--block-rows",
            "20",
            "--json",
            s(&json),
            "--refine",
        ];
        args.extend(flag);
        let (ok, out, err) = hyst(&args);
        assert!(ok, "{err}");
        assert!(out.contains(header), "{out}");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        let r = &v["refined"];
        assert_eq!(r["joint"], joint, "{r}");
        assert!(r["combinations"].is_null(), "{r}");
        assert_eq!(r["bands"], 1, "{r}");
        assert_eq!(r["modes"].as_array().unwrap().len(), 3, "{r}");
        // The joint likelihood gives each mode's shape; each channel alone gives none.
        for m in r["modes"].as_array().unwrap() {
            if joint {
                assert_eq!(m["shape"].as_array().map(Vec::len), Some(3), "{m}");
                let se: Vec<f64> = m["shape_se"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|v| v.as_f64().unwrap())
                    .collect();
                // The entry scaled to 1 has none; the others have one.
                assert_eq!(se.iter().filter(|&&v| v == 0.0).count(), 1, "{m}");
                assert!(se.iter().all(|v| v.is_finite() && *v >= 0.0), "{m}");
                assert!(m["mpc"].as_f64().is_some_and(|v| (0.0..=1.0).contains(&v)));
            } else {
                assert!(
                    m["shape"].is_null() && m["shape_se"].is_null() && m["mpc"].is_null(),
                    "{m}"
                );
            }
        }
    }
}

/// `hyst ssi --refine` at 20 Hz with 20 block rows on the channels `columns`, written to `name`.csv,
/// expecting the joint fit through 4 combinations in `bands` bands, as the printed header and
/// the JSON say; returns the JSON's `refined`.
fn ssi_through_combinations(
    name: &str,
    names: &[&str],
    columns: &[&[f64]],
    bands: usize,
) -> serde_json::Value {
    let input = tmp(&format!("{name}.csv"));
    hyst::io::write_csv(&input, names, columns).unwrap();
    let json = tmp(&format!("{name}.json"));
    let (ok, out, err) = hyst(&[
        "ssi",
        "--input",
        s(&input),
        "--fs",
        "20",
        "--block-rows",
        "20",
        "--json",
        s(&json),
        "--refine",
    ]);
    assert!(ok, "{err}");
    let header = match bands {
        1 => "channels jointly, through 4 combinations;".to_string(),
        b => format!("channels jointly, through 4 combinations in each of {b} bands"),
    };
    assert!(out.contains(&header), "{out}");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let r = v["refined"].take();
    assert_eq!(
        (&r["joint"], &r["combinations"], &r["bands"]),
        (&true.into(), &4.into(), &bands.into()),
        "{r}"
    );
    r
}

/// Six channels (the 3-DOF record's three and three sums of them, each with its own 5 %
/// measurement noise): the joint likelihood is fitted through four combinations of the
/// channels, and the JSON and the header say so.
#[test]
fn ssi_many_channels_refined_through_combinations() {
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand_distr::{Distribution, StandardNormal};
    let Some(path) = common::data_file("oma/data_3dof.csv") else {
        return;
    };
    let table = hyst::io::read_csv(&path).unwrap();
    let y: Vec<&[f64]> = ["y1", "y2", "y3"]
        .iter()
        .map(|c| table.column(c).unwrap())
        .collect();
    let sums = [(0, 1), (1, 2), (0, 2)];
    let sd: Vec<f64> = sums
        .iter()
        .map(|&(a, b)| {
            let ss: f64 = (0..table.len()).map(|t| (y[a][t] + y[b][t]).powi(2)).sum();
            (ss / table.len() as f64).sqrt()
        })
        .collect();
    // Drawn row by row, each row's three sums in turn.
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
    let mut extra = vec![Vec::with_capacity(table.len()); sums.len()];
    for row in (0..table.len()).map(|t| [y[0][t], y[1][t], y[2][t]]) {
        for ((&(a, b), sd), col) in sums.iter().zip(&sd).zip(&mut extra) {
            let e: f64 = StandardNormal.sample(&mut rng);
            col.push(row[a] + row[b] + 0.05 * sd * e);
        }
    }
    let columns: Vec<&[f64]> = y
        .iter()
        .copied()
        .chain(extra.iter().map(Vec::as_slice))
        .collect();
    let names = ["y1", "y2", "y3", "s12", "s23", "s13"];
    let r = &ssi_through_combinations("six_channels", &names, &columns, 1);
    let truth = [1.0017, 2.8067, 4.0558];
    let modes = r["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 3, "{r}");
    for (m, f) in modes.iter().zip(truth) {
        let (est, se) = (
            m["frequency_hz"].as_f64().unwrap(),
            m["frequency_se_hz"].as_f64().unwrap(),
        );
        // Within four standard errors of the README's truth.
        assert!((est - f).abs() < 4.0 * se, "{m}");
    }
}

/// Ten channels reading five modes (a fixed-free chain's first five shapes, each mode a
/// sampled continuous oscillator driven by white noise, 5 % measurement noise): more modes
/// than combinations, so the joint likelihood is fitted band by band; the header and the JSON
/// say so, and every mode lands within four standard errors of the truth.
#[test]
fn ssi_many_modes_refined_band_by_band() {
    use std::f64::consts::FRAC_PI_2;
    let (fs, n, channels) = (20.0, 16384, 10);
    let truth = [
        (1.5, 0.02),
        (3.0, 0.03),
        (5.0, 0.03),
        (6.5, 0.02),
        (8.0, 0.03),
    ];
    // Each channel reads the first state of each mode through the chain's shape.
    let shape = |c: usize, r: usize| {
        let x = (c + 1) as f64 / (channels as f64 + 0.5);
        ((2 * r + 1) as f64 * FRAC_PI_2 * x).sin()
    };
    let gains = (0..channels)
        .map(|c| (0..truth.len()).flat_map(|r| [shape(c, r), 0.0]).collect())
        .collect();
    let y = covssi::synth::ModalRecord::new(fs, &truth)
        .with_gains(gains)
        .with_noise(0.05)
        .generate(n, 11);
    let names: Vec<String> = (1..=channels).map(|c| format!("y{c}")).collect();
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    let columns: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
    let r = &ssi_through_combinations("ten_channels_five_modes", &names, &columns, 2);
    let modes = r["modes"].as_array().unwrap();
    assert_eq!(modes.len(), truth.len(), "{r}");
    for (m, &(f, zeta)) in modes.iter().zip(&truth) {
        let get = |key: &str| m[key].as_f64().unwrap();
        // Within four standard errors of the truth: calibrated standard errors (the unit
        // tests measure z RMS 0.98–1.00 for this fit) put a miss at 6e-5 per number.
        assert!(
            (get("frequency_hz") - f).abs() < 4.0 * get("frequency_se_hz"),
            "{m}"
        );
        assert!(
            (get("damping_ratio") - zeta).abs() < 4.0 * get("damping_se"),
            "{m}"
        );
    }
}

#[test]
fn ssi_record_too_short_for_the_lags() {
    let p = write(
        "short.csv",
        &format!(
            "y\n{}",
            (0..30)
                .map(|k| format!("{}\n", (k as f64).sin()))
                .collect::<String>()
        ),
    );
    let err = ssi_fails(&p, &[]);
    assert!(
        err.contains("30 samples are too few") && err.contains("short.csv"),
        "{err}"
    );
}

/// A real record as a new user has it: a headerless `.dat` of time and two channels read
/// (its columns named 0, 1, 2 and said), its time column left out of the channels and
/// giving the rate; `--fs` ten times too large refused naming the column; `--names` names
/// the columns.
#[test]
fn ssi_reads_a_headerless_dat_with_its_time_column() {
    let text: String = (0..3000)
        .map(|k| {
            let t = k as f64 * 0.05;
            format!(
                "{t:.2}  {:.6e}  {:.6e}\n",
                (0.7 * k as f64).sin() + 0.3 * (1.9 * k as f64).cos(),
                (0.7 * k as f64).cos() - 0.2 * (1.9 * k as f64).sin()
            )
        })
        .collect();
    let p = write("headerless.dat", &text);
    let json = tmp("headerless.json");
    let channels_and_rate = || {
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        (v["channels"].clone(), v["fs_hz"].as_f64())
    };
    let (ok, _, err) = hyst(&["ssi", "--input", s(&p), "--no-refine", "--json", s(&json)]);
    assert!(ok, "{err}");
    assert!(
        err.contains("no header line (the first line is numbers): the columns are named 0 to 2"),
        "{err}"
    );
    // Two channels at the time column's 20 Hz (the step 0.05 s).
    assert_eq!(
        channels_and_rate(),
        (serde_json::json!(["1", "2"]), Some(20.0))
    );
    let (ok, _, err) = hyst(&["ssi", "--input", s(&p), "--fs", "200", "--no-refine"]);
    assert!(!ok);
    assert!(
        err.contains("--fs 200 Hz disagrees with the time column `0`"),
        "{err}"
    );
    let (ok, _, err) = hyst(&[
        "ssi",
        "--input",
        s(&p),
        "--names",
        "Time (s),north,east",
        "--no-refine",
        "--json",
        s(&json),
    ]);
    assert!(ok, "{err}");
    assert!(!err.contains("no header line"), "{err}");
    assert_eq!(
        channels_and_rate(),
        (serde_json::json!(["north", "east"]), Some(20.0))
    );
    let (ok, _, err) = hyst(&["ssi", "--input", s(&p), "--names", "a,b"]);
    assert!(!ok);
    assert!(
        err.contains("--names gives 2 name(s) for the file's 3 column(s)"),
        "{err}"
    );
}

/// `--gains`: each channel divided by its reading's factor, as a setup file's `gain`: the
/// 3-DOF record with its first channel's gain −1 (a sensor mounted the other way) gives
/// SSI's shapes with that entry negated (a sign flip is orthogonal: the correlations' SVD
/// and the poles are the same to rounding); a count that differs is refused naming the
/// channels. (The division itself: `io::tests::gains_divide_their_channels_or_are_refused`.)
#[test]
fn ssi_gains_divide_their_channels() {
    let Some(path) = common::data_file("oma/data_3dof.csv") else {
        return;
    };
    let ratios = |gains: &[&str]| {
        let v = ssi_3dof_json(
            &path,
            "gains.json",
            &[&["--no-refine", "--ssi-errors", "0"], gains].concat(),
        );
        v["ssi_modes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|m| {
                let re = |k: usize| m["shape"][k][0].as_f64().unwrap();
                re(0) / re(1)
            })
            .collect::<Vec<f64>>()
    };
    let plain = ratios(&[]);
    let flipped = ratios(&["--gains", "-1,1,1"]);
    assert!(plain.len() >= 3, "{plain:?}");
    assert_eq!(plain.len(), flipped.len());
    for (p, g) in plain.iter().zip(&flipped) {
        // The real parts' ratio (real modes, MPC 1.000), to the rounding of SSI's SVD.
        assert!((g + p).abs() < 1e-8 * p.abs().max(1.0), "{p} {g}");
    }
    // The first line says what was read: channels, samples, rate and its source, rows
    // skipped, gains (the record: 65536 rows of t, y1, y2, y3 at 20 Hz).
    let (ok, out, err) = hyst(
        &[
            ssi_3dof_args(&path),
            vec![
                "--no-refine",
                "--ssi-errors",
                "0",
                "--skip",
                "36",
                "--gains",
                "-1,1,1",
            ],
        ]
        .concat(),
    );
    assert!(ok, "{err}");
    assert_eq!(
        out.lines().next().unwrap(),
        format!(
            "read {}: 3 channel(s) y1, y2, y3; 65500 samples at 20 Hz (from the time column `t`), the first 36 rows skipped; divided by the gains -1, 1, 1",
            path.display()
        )
    );
    let (ok, _, err) = hyst(&[ssi_3dof_args(&path), vec!["--gains", "1,2"]].concat());
    assert!(!ok);
    assert!(
        err.contains("--gains: 2 gain(s) for 3 channel(s) (y1,y2,y3)"),
        "{err}"
    );
}

/// `hyst ssi`'s arguments for the 3-DOF record at 20 Hz, channels y1,y2,y3.
fn ssi_3dof_args(path: &Path) -> Vec<&str> {
    let record = ["--input", s(path), "--fs", "20", "--columns", "y1,y2,y3"];
    std::iter::once("ssi").chain(record).collect()
}

/// `hyst ssi` on the 3-DOF record ([`ssi_3dof_args`]) with `extra` arguments: its JSON
/// report (written to `name` under the tests' scratch folder).
fn ssi_3dof_json(path: &Path, name: &str, extra: &[&str]) -> serde_json::Value {
    let json = tmp(name);
    let mut args = ssi_3dof_args(path);
    args.extend_from_slice(&["--json", s(&json)]);
    args.extend_from_slice(extra);
    let (ok, _, err) = hyst(&args);
    assert!(ok, "{err}");
    serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap()
}

/// A one-column record `y` of 400 samples: two sines.
fn write_two_sines() -> PathBuf {
    write(
        "sine.csv",
        &format!(
            "y\n{}",
            (0..400)
                .map(|k| format!(
                    "{}\n",
                    (0.7 * k as f64).sin() + 0.3 * (1.9 * k as f64).cos()
                ))
                .collect::<String>()
        ),
    )
}

#[test]
fn ssi_option_out_of_range_names_its_flag() {
    let p = write_two_sines();
    for (flag, value, said) in [
        (
            "--dreal",
            "inf",
            "--dreal must be positive and finite, got inf",
        ),
        ("--references", "0,0", "--references names channel 0 twice"),
        (
            "--references",
            "1",
            "--references 1 is out of range: 1 channel(s), numbered from 0",
        ),
        (
            "--decimate",
            "20",
            "sine.csv: columns y, decimated by 20 to 0.5 Hz: 20 samples are too few",
        ),
        ("--df", "-1", "--df must be positive and finite, got -1"),
        ("--dzeta", "0", "--dzeta must be positive and finite, got 0"),
        ("--max-order", "0", "--max-order must be at least 1, got 0"),
        (
            "--block-rows",
            "1",
            "--block-rows must be at least 2, got 1",
        ),
    ] {
        let arg = format!("{flag}={value}");
        let err = ssi_fails(&p, &[&arg]);
        assert!(err.contains(said), "{arg}: {err}");
    }
}

#[test]
fn ssi_lags_as_a_time_or_as_periods() {
    let p = write_two_sines();
    // At 10 Hz, ten periods of 0.5 Hz and 20 s both ask the largest lag 2i − 1 to cover 200
    // samples: i = 101, and the program says so.
    for lag in [
        &["--lag-periods", "10", "0.5"][..],
        &["--lag-seconds", "20"],
    ] {
        let json = tmp("lags.json");
        let mut args = vec!["ssi", "--input", s(&p), "--fs", "10", "--no-refine"];
        args.extend_from_slice(lag);
        args.extend_from_slice(&["--json", s(&json)]);
        let (ok, out, err) = hyst(&args);
        assert!(ok, "{lag:?}: {err}");
        // After the line on what was read, the one on the decimation (none: the record's
        // band reaches 62 % of Nyquist).
        assert!(
            out.starts_with("read ")
                && out
                    .lines()
                    .nth(1)
                    .is_some_and(|l| l.starts_with("not decimated: "))
                && out.contains(
                    "\n101 block rows: correlations up to lag 201 (20.1000 s at 10 Hz)\n"
                ),
            "{lag:?}: {out}"
        );
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        assert_eq!(v["block_rows"], 101, "{lag:?}");
    }
    for (args, said) in [
        (
            &["--lag-seconds", "0.1"][..],
            "--lag-seconds gives 1 block row(s) at 10 Hz; SSI needs at least 2",
        ),
        (
            &["--lag-seconds", "-1"],
            "--lag-seconds must be positive and finite, got -1",
        ),
        (
            &["--lag-periods", "0", "2"],
            "--lag-periods COUNT must be positive and finite, got 0",
        ),
        (
            &["--lag-periods", "10", "inf"],
            "--lag-periods HZ must be positive and finite, got inf",
        ),
        // Beyond any record: too short, not an overflow.
        (&["--lag-seconds", "1e18"], "400 samples are too few"),
        // One way of giving the lags at a time.
        (
            &["--lag-seconds", "2", "--block-rows", "30"],
            "cannot be used with",
        ),
        (
            &["--lag-periods", "10", "1", "--lag-seconds", "2"],
            "cannot be used with",
        ),
        (&["--lag-periods", "10"], "2 values required"),
    ] {
        let err = ssi_fails(&p, args);
        assert!(err.contains(said), "{args:?}: {err}");
    }
}

#[test]
fn ssi_refinement_drops_the_real_poles_of_white_noise() {
    // White noise now and then gives SSI a stable real-pole cluster beside a spurious mode;
    // the refinement weighs both by the record's likelihood and drops them. Over the seeds
    // tried, at least one must show the case, and on every one that does, every real pole
    // must be dropped.
    let mut shown = 0;
    for seed in 0..12 {
        let p = write_white_noise("ssi_noise.csv", seed);
        let json = tmp("ssi_noise.json");
        let (ok, out, err) = hyst(&[
            "ssi",
            "--input",
            s(&p),
            "--fs",
            "750",
            "--block-rows",
            "40",
            "--json",
            s(&json),
            "--refine",
        ]);
        assert!(ok, "{err}");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        let found = v["real_poles"].as_array().unwrap().len();
        if found > 0 {
            shown += 1;
            let refined = &v["refined"];
            assert_eq!(refined["real_poles"].as_array().unwrap().len(), 0, "{out}");
            let dropped = refined["dropped_real_poles"].as_array().unwrap();
            assert_eq!(dropped.len(), found, "seed {seed}: {out}");
            assert!(
                out.contains("dropped the SSI real pole"),
                "seed {seed}: {out}"
            );
        }
    }
    assert!(shown > 0, "no seed gave real poles");
}

#[test]
fn ssi_missing_column() {
    let err = ssi_fails_on_columns("c");
    assert!(err.contains("no column `c`"), "{err}");
}

/// Output only takes responses: `hyst ssi` without --columns on a `u,y` file warns that `u`
/// looks like the force and says how to leave it out; with --columns it says nothing.
#[test]
fn ssi_warns_when_the_default_channels_take_in_the_force() {
    let noise = hyst::sim::excitation::white_noise(4000, 1.0, 3).unwrap();
    let resp = hyst::sim::excitation::white_noise(4000, 1.0, 4).unwrap();
    let text: String = noise
        .iter()
        .zip(&resp)
        .map(|(u, y)| format!("{u},{y}\n"))
        .collect();
    let p = write("uy_for_ssi.csv", &format!("u,y\n{text}"));
    let json = tmp("uy_for_ssi.json");
    let run = |extra: &[&str]| {
        let mut args = vec![
            "ssi",
            "--input",
            s(&p),
            "--fs",
            "100",
            "--no-refine",
            "--json",
            s(&json),
        ];
        args.extend_from_slice(extra);
        hyst(&args)
    };
    let (_, _, err) = run(&[]);
    assert!(
        err.contains("column `u` looks like the input (a force)") && err.contains("--columns y"),
        "{err}"
    );
    let (_, _, err) = run(&["--columns", "y"]);
    assert!(!err.contains("looks like the input"), "{err}");
}

/// `--format` reads a file whatever its extension says; a record that states no rate needs
/// `--fs`, and the error says so; `--shapes-uff` writes one dataset 55 per reported mode,
/// the channels of a CSV as nodes 1, 2, 3.
#[test]
fn format_flag_rate_and_shapes_uff() {
    let noise = std::fs::read_to_string(write_white_noise("noise.csv", 41)).unwrap();
    let misnamed = write("noise_as.npy", &noise);
    let json = tmp("format.json");
    let run = |extra: &[&str]| {
        let mut args = vec!["ssi", "--input", s(&misnamed), "--json", s(&json)];
        args.extend_from_slice(extra);
        hyst(&args)
    };
    let (ok, _, err) = run(&["--fs", "10"]);
    assert!(!ok && err.contains("not a NumPy .npy file"), "{err}");
    let (ok, _, err) = run(&["--fs", "10", "--format", "csv", "--no-refine"]);
    assert!(ok, "{err}");
    let (ok, _, err) = run(&["--format", "csv"]);
    assert!(
        !ok && err.contains("the file does not state its sampling rate"),
        "{err}"
    );
    let Some(path) = common::data_file("oma/data_3dof.csv") else {
        return;
    };
    let uff = tmp("shapes_3dof.uff");
    let (ok, _, err) = hyst(&[
        "ssi",
        "--input",
        s(&path),
        "--fs",
        "20",
        "--json",
        s(&json),
        "--shapes-uff",
        s(&uff),
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    // One dataset per mode of the answer (SSI's by default, with their shapes).
    let reported = v["modes"].as_array().unwrap().len();
    assert_eq!(v["decision"]["source"], "ssi", "{v}");
    let text = std::fs::read_to_string(&uff).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.iter().filter(|l| **l == "    55").count(), reported);
    // Each dataset: 10 header lines, then node number and values per node, then `-1`.
    let nodes: Vec<&str> = lines[10..16].iter().step_by(2).copied().collect();
    assert_eq!(nodes, ["         1", "         2", "         3"]);
}

/// `hyst ssi` without `--json` prints its report and writes nothing (it refused to run).
#[test]
fn ssi_prints_without_json() {
    let p = write_two_sines();
    let (ok, out, err) = hyst(&["ssi", "--input", s(&p), "--fs", "10", "--no-refine"]);
    assert!(ok, "{err}");
    assert!(out.contains("block rows: correlations up to lag"), "{out}");
}

/// Two setups of a two-mode system as CSV records (columns `a`, `b`: references; `r`: the
/// roving channel, a velocity), at `fs` 20 Hz.
fn write_two_setups() -> [PathBuf; 2] {
    use covssi::synth::{ModalRecord, pole};
    let modes = [(1.5, 0.02), (4.0, 0.02)];
    let shape = |node: f64| [(node * 0.3).sin(), (node * 0.9).sin()];
    [(1.0, 3.0), (2.0, 4.0)].map(|(level, node)| {
        let rows: Vec<[f64; 2]> = vec![shape(6.0), shape(5.0), shape(node)];
        let gains = rows
            .iter()
            .enumerate()
            .map(|(c, phi)| {
                (0..2)
                    .flat_map(|j| {
                        // the roving channel reads velocity: its gain is φ λ
                        let p = if c == 2 {
                            pole(modes[j].0, modes[j].1)
                        } else {
                            1.0.into()
                        };
                        let g = level * phi[j] * p;
                        [g.re, -g.im]
                    })
                    .collect()
            })
            .collect();
        let y = ModalRecord::new(20.0, &modes)
            .with_gains(gains)
            .with_noise(0.02)
            .generate(6000, 77 + node as u64);
        let mut text = String::from("a,b,r\n");
        for ((a, b), r) in y[0].iter().zip(&y[1]).zip(&y[2]) {
            text.push_str(&format!("{a},{b},{r}\n"));
        }
        write(&format!("setup_{node}.csv"), &text)
    })
}

#[test]
fn ssi_merges_setups_on_their_references() {
    let [one, two] = write_two_setups();
    let head = "setup,file,column,node,direction,quantity,reference\n";
    // Setup two's references at nodes `ra` and `rb` (setup one's: 6 and 5).
    // Records named from the setup file's folder (they lie beside it).
    let name = |p: &Path| p.file_name().unwrap().to_str().unwrap().to_string();
    let rows = |ra: &str, rb: &str| {
        format!(
            "{head}one,{a},a,6,x,displacement,yes\none,{a},b,5,x,displacement,yes\none,{a},r,3,x,velocity,no\n\
             two,{b},a,{ra},x,displacement,yes\ntwo,{b},b,{rb},x,displacement,yes\ntwo,{b},r,4,x,velocity,no\n",
            a = name(&one),
            b = name(&two)
        )
    };
    let setups = write("setups.csv", &rows("6", "5"));
    let merge = |extra: &[&str]| {
        let mut args = vec!["ssi", "--setups", s(&setups), "--fs", "20"];
        args.extend_from_slice(extra);
        hyst(&args)
    };
    let json = tmp("setups.json");
    let (ok, out, err) = merge(&["--json", s(&json)]);
    assert!(ok, "{err}");
    // An output on one of the setups' records is refused before any is read, the record
    // kept byte for byte.
    let before = std::fs::read(&one).unwrap();
    for flag in ["--json", "--shapes-uff", "--html"] {
        let (ok, _, err) = hyst(&["ssi", "--setups", s(&setups), "--fs", "20", flag, s(&one)]);
        assert!(
            !ok && err.contains(&format!("{flag} {}", s(&one)))
                && err.contains("is the file --setups reads"),
            "{flag}: {err}"
        );
        assert_eq!(std::fs::read(&one).unwrap(), before, "{flag}");
    }
    // Named by absolute paths: refused, unless allowed, and then the same merge.
    let absolute = write(
        "setups_absolute.csv",
        &rows("6", "5")
            .replace(&name(&one), s(&one))
            .replace(&name(&two), s(&two)),
    );
    let (ok, _, err) = hyst(&["ssi", "--setups", s(&absolute), "--fs", "20"]);
    assert!(
        !ok && err.contains("is not inside the setup file's folder")
            && err.contains("--records-anywhere"),
        "{err}"
    );
    let (ok, anywhere, err) = hyst(&[
        "ssi",
        "--setups",
        s(&absolute),
        "--records-anywhere",
        "--fs",
        "20",
    ]);
    assert!(ok, "{err}");
    assert!(
        anywhere.contains("2 setups, each identified alone"),
        "{anywhere}"
    );
    assert!(out.contains("2 setups, each identified alone"), "{out}");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let modes = doc["merged"]["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 2, "{out}");
    for (m, f) in modes.iter().zip([1.5, 4.0]) {
        assert!(
            (m["frequency_hz"].as_f64().unwrap() - f).abs() < 0.02 * f,
            "{m}"
        );
        assert_eq!(m["seen_in"].as_array().unwrap().len(), 2);
    }
    // Each setup's diagram and singular values are left out of the file, and said; asked
    // for, they are there, beside the same merge.
    assert_eq!(doc["diagrams_left_out"], true);
    let first = &doc["setups"][0]["analysis"];
    assert!(first["diagram"]["orders"].as_array().unwrap().is_empty());
    assert!(first["singular_values"].as_array().unwrap().is_empty());
    assert!(!first["ssi_modes"].as_array().unwrap().is_empty());
    let full_json = tmp("setups_diagrams.json");
    let (ok, _, err) = hyst(&[
        "ssi",
        "--setups",
        s(&setups),
        "--fs",
        "20",
        "--json",
        s(&full_json),
        "--json-diagrams",
    ]);
    assert!(ok, "{err}");
    let full: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&full_json).unwrap()).unwrap();
    assert_eq!(full["diagrams_left_out"], false);
    assert!(
        !full["setups"][0]["analysis"]["diagram"]["orders"]
            .as_array()
            .unwrap()
            .is_empty()
    );
    assert_eq!(full["merged"], doc["merged"]);
    // The floors' check needs the nodes' positions: a setup file without a geometry is
    // refused, saying where they come from.
    let (ok, _, err) = merge(&["--rigid-floors"]);
    assert!(
        !ok && err.contains("--rigid-floors needs the nodes' positions"),
        "{err}"
    );
    // With positions but one node a floor, no floor can check its channels: said, not
    // passed over in silence.
    let grid = write(
        "tower_grid.txt",
        "name x y z\n3 0 0 1\n4 0 0 2\n5 0 0 3\n6 0 0 4\n",
    );
    let (ok, out, err) = merge(&["--geometry", s(&grid), "--rigid-floors"]);
    assert!(ok, "{err}");
    assert!(out.contains("--rigid-floors: no floor qualifies"), "{out}");
    // A reference that moved between setups is said, and the other carries the merge.
    let moved = write("setups_moved.csv", &rows("6", "7"));
    let (ok, out, err) = hyst(&["ssi", "--setups", s(&moved), "--fs", "20"]);
    assert!(ok, "{err}");
    assert!(
        out.contains("note: the reference at node 5") && out.contains("it moved"),
        "{out}"
    );
    // A NaN in a column setup one does not use leaves the merge as it was (issue 58).
    let mut spare = String::new();
    for (k, l) in std::fs::read_to_string(&one).unwrap().lines().enumerate() {
        let cell = match k {
            0 => "spare",
            9 => "NaN",
            _ => "0",
        };
        spare += &format!("{l},{cell}\n");
    }
    write("setup_spare.csv", &spare);
    let spared = write(
        "setups_spare.csv",
        &rows("6", "5").replace(&name(&one), "setup_spare.csv"),
    );
    let spared_json = tmp("setups_spare.json");
    let (ok, _, err) = hyst(&[
        "ssi",
        "--setups",
        s(&spared),
        "--fs",
        "20",
        "--json",
        s(&spared_json),
    ]);
    assert!(ok, "{err}");
    let with_nan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&spared_json).unwrap()).unwrap();
    // The same samples in the channels analysed: the same merged modes, to the bit.
    assert_eq!(with_nan["merged"]["modes"], doc["merged"]["modes"]);
    // No reference common to the setups: refused, naming each setup's references.
    let none = write("setups_none.csv", &rows("8", "9"));
    let (ok, _, err) = hyst(&["ssi", "--setups", s(&none), "--fs", "20"]);
    assert!(!ok);
    assert!(
        err.contains("no reference is common to every setup"),
        "{err}"
    );
    // --setups and --input together, and a setups flag the merge has no use for.
    let (ok, _, err) = hyst(&["ssi", "--setups", s(&setups), "--input", s(&one)]);
    assert!(!ok && err.contains("cannot be used with"), "{err}");
    // The setup file is an input: --json may not overwrite it.
    let (ok, _, err) = hyst(&[
        "ssi",
        "--setups",
        s(&setups),
        "--fs",
        "20",
        "--json",
        s(&setups),
    ]);
    assert!(!ok && err.contains("would overwrite the input"), "{err}");
}

/// Two setups cut from one record at 20 Hz, each with its time column: their rates read
/// 20 and 19.999999999999996 Hz (rounding of the times' sums), one rate, so the global
/// estimation runs beside the merge rather than being skipped for "different rates".
#[test]
fn setups_whose_rates_differ_by_rounding_are_estimated_together() {
    let [one, two] = write_two_setups();
    let timed = |path: &Path, first: usize, name: &str| {
        let text = std::fs::read_to_string(path).unwrap();
        let mut lines = text.lines();
        let mut out = format!("t,{}\n", lines.next().unwrap());
        for (k, line) in lines.enumerate() {
            out.push_str(&format!("{:?},{line}\n", (k + first) as f64 * 0.05));
        }
        write(name, &out)
    };
    let (one, two) = (
        timed(&one, 0, "timed_one.csv"),
        timed(&two, 1000, "timed_two.csv"),
    );
    let name = |p: &Path| p.file_name().unwrap().to_str().unwrap().to_string();
    let setups = write(
        "timed_setups.csv",
        &format!(
            "setup,file,column,node,direction,quantity,reference\n\
             one,{a},a,6,x,displacement,yes\none,{a},b,5,x,displacement,yes\none,{a},r,3,x,velocity,no\n\
             two,{b},a,6,x,displacement,yes\ntwo,{b},b,5,x,displacement,yes\ntwo,{b},r,4,x,velocity,no\n",
            a = name(&one),
            b = name(&two)
        ),
    );
    let (ok, out, err) = hyst(&["ssi", "--setups", s(&setups)]);
    assert!(ok, "{err}");
    assert!(!out.contains("global estimation not run"), "{out}");
    assert!(
        out.contains("global estimation (SSI once on all setups' correlations"),
        "{out}"
    );
}

/// A time column with two rows swapped, or 100 rows missing, is said with its row, with or
/// without --fs: the analysis takes samples as equally spaced, so neither is analysed as it
/// is (a gap read the rate 1.2 % low and every frequency with it).
#[test]
fn a_time_column_out_of_order_or_with_a_gap_is_said_with_its_row() {
    let rows: Vec<(f64, f64)> = (0..4000)
        .map(|k| {
            (
                k as f64 / 20.0,
                (k as f64 * 0.37).sin() + 0.3 * (k as f64 * 1.1).cos(),
            )
        })
        .collect();
    let csv = |rows: &[(f64, f64)], name: &str| {
        let mut text = String::from("t,y\n");
        rows.iter()
            .for_each(|(t, y)| text.push_str(&format!("{t:?},{y:?}\n")));
        write(name, &text)
    };
    let mut swapped = rows.clone();
    swapped.swap(40, 41);
    let gapped: Vec<(f64, f64)> = rows[..60].iter().chain(&rows[160..]).copied().collect();
    for (name, rows, says) in [
        (
            "swapped_rows.csv",
            swapped,
            "the time column `t` at row 42 goes from 2.05 to 2: rows out of order",
        ),
        (
            "gapped_rows.csv",
            gapped,
            "the time column `t` at row 61 jumps from 2.95 to 8",
        ),
    ] {
        let path = csv(&rows, name);
        for fs in [None, Some("20")] {
            let mut args = vec!["ssi", "--input", s(&path)];
            args.extend(fs.iter().flat_map(|f| ["--fs", f]));
            let (ok, _, err) = hyst(&args);
            assert!(
                !ok && err.contains(s(&path)) && err.contains(says),
                "{name} {fs:?}: {err}"
            );
        }
    }
}

/// `hyst ssi --setups --decimate 64` on the steel frame (256 Hz): Nyquist at 2 Hz filters
/// every setup's modes out, and the report says so, once for the setups that share a note,
/// as the single-record path does (issue 77: the setups' path was silent).
#[test]
fn setups_say_what_their_decimation_filters_out() {
    let Some(grid) = common::data_file("steelframe/grid.txt") else {
        return;
    };
    let dir = grid.parent().unwrap();
    let (ok, out, err) = hyst(&["ssi", "--setups", s(dir), "--decimate", "64"]);
    assert!(ok, "{err}");
    let notes: Vec<&str> = out
        .lines()
        .filter(|l| l.starts_with("note (setup") && l.contains("decimating by 64"))
        .collect();
    assert!(!notes.is_empty(), "{out}");
    // Each setup named once, in one of the notes.
    for k in 1..=15 {
        let name = format!("measurement_{k}");
        let named = notes
            .iter()
            .filter(|n| n.split([' ', ',', ')']).any(|w| w == name))
            .count();
        assert_eq!(named, 1, "{name}: {notes:?}");
    }
}
