use super::*;
use proptest::prelude::*;

fn c(re: f64, im: f64) -> C64 {
    C64::new(re, im)
}

fn channel(node: &str, direction: [f64; 3], quantity: Quantity, reference: bool) -> SetupChannel {
    SetupChannel {
        node: node.into(),
        direction,
        quantity,
        gain: 1.0,
        reference,
    }
}

fn pole(f: f64, z: f64) -> C64 {
    2.0 * std::f64::consts::PI * f * c(-z, (1.0 - z * z).sqrt())
}

/// A mode whose displacement at each channel is `truth(channel)`, read in the channels' units
/// and gains, at an arbitrary complex scale, scaled to its largest entry as SSI reports.
fn observed(
    channels: &[SetupChannel],
    truth: &dyn Fn(&SetupChannel) -> f64,
    f: f64,
    scale: C64,
) -> ReportedMode {
    let lambda = pole(f, 0.02);
    let raw: Vec<C64> = channels
        .iter()
        .map(|ch| scale * truth(ch) * ch.gain * lambda.powi(ch.quantity.power()))
        .collect();
    let top = *raw
        .iter()
        .max_by(|a, b| a.norm().total_cmp(&b.norm()))
        .unwrap();
    ReportedMode {
        frequency_hz: f,
        frequency_se_hz: Some(0.001),
        damping_ratio: 0.02,
        damping_se: Some(0.002),
        shape: Some(raw.iter().map(|v| v / top).collect()),
        shape_from_ssi: false,
        shape_se: Some(
            raw.iter()
                .map(|v| if *v == top { 0.0 } else { 0.01 })
                .collect(),
        ),
        ssi_mode: None,
    }
}

/// A node's true motion (x, y, z) in a mode.
fn motion(node: &str) -> [f64; 3] {
    match node {
        "ref" => [1.0, -0.4, 0.0],
        "1" => [0.3, 0.2, 0.05],
        "2" => [0.6, -0.1, 0.02],
        _ => [-0.2, 0.5, 0.1],
    }
}

fn along(ch: &SetupChannel) -> f64 {
    let m = motion(&ch.node);
    let d = unit(ch.direction);
    (0..3).map(|k| m[k] * d[k]).sum()
}

/// Three setups: two reference accelerometers (x, −y) and three skewed velocity beams at a
/// roving node, each setup at its own excitation scale.
fn roving_setups() -> Vec<SetupModes> {
    let beams = [[0.87, 0.48, -0.15], [0.16, 0.98, -0.13], [0.49, 0.72, 0.49]];
    let scales = [c(2.0, 0.5), c(-0.3, 1.1), c(0.7, -0.2)];
    ["1", "2", "3"]
        .iter()
        .zip(scales)
        .map(|(node, scale)| {
            let mut channels: Vec<SetupChannel> = beams
                .iter()
                .map(|&d| channel(node, d, Quantity::Velocity, false))
                .collect();
            channels.push(channel(
                "ref",
                [1.0, 0.0, 0.0],
                Quantity::Acceleration,
                true,
            ));
            channels.push(channel(
                "ref",
                [0.0, -1.0, 0.0],
                Quantity::Acceleration,
                true,
            ));
            channels[4].gain = -2.0;
            let mode = observed(&channels, &along, 3.0, scale);
            SetupModes {
                name: format!("setup {node}"),
                channels,
                modes: vec![mode],
            }
        })
        .collect()
}

#[test]
fn noise_free_setups_merge_to_the_true_motion_of_every_node() {
    let merged = merge(&roving_setups(), &MergeOptions::default()).unwrap();
    assert_eq!(merged.modes.len(), 1);
    assert_eq!(merged.dofs.iter().filter(|d| d.reference).count(), 2);
    let m = &merged.modes[0];
    assert_eq!(m.seen_in.len(), 3);
    // The merged shape is scaled to its largest entry (node ref, x = 1); every node's motion
    // is then the truth to rounding.
    for node in &m.nodes {
        let truth = motion(&node.node);
        for (k, (motion, truth)) in node.motion.iter().zip(truth).enumerate() {
            match motion {
                Some(u) => assert!((u - c(truth, 0.0)).norm() < 1e-9, "{node:?}"),
                // the reference node has no z channel
                None => assert!(node.node == "ref" && k == 2, "{node:?}"),
            }
        }
    }
    // Three setups of equal errors: the frequency's error is one setup's over √3.
    assert!((m.frequency_se_hz.unwrap() - 0.001 / 3f64.sqrt()).abs() < 1e-12);
    assert_eq!(m.scatter_ratio, Some(0.0));
}

#[test]
fn a_mode_seen_in_one_setup_keeps_that_setups_errors() {
    let mut setups = roving_setups();
    let other = observed(&setups[1].channels, &along, 7.0, c(1.0, 0.0));
    setups[1].modes.push(other);
    let merged = merge(&setups, &MergeOptions::default()).unwrap();
    assert_eq!(merged.modes.len(), 2);
    let lone = &merged.modes[1];
    assert_eq!(lone.seen_in.len(), 1);
    assert_eq!(lone.frequency_se_hz, Some(0.001));
    assert_eq!(lone.damping_se, Some(0.002));
    assert_eq!(lone.scatter_ratio, None);
    // Only setup 2's roving node has entries.
    let roving_with_entries: Vec<&str> = merged
        .dofs
        .iter()
        .zip(&lone.shape)
        .filter(|(d, v)| !d.reference && v.is_some())
        .map(|(d, _)| d.node.as_str())
        .collect();
    assert_eq!(roving_with_entries, ["2", "2", "2"]);
}

/// A setup none of whose modes matches another's (here its mode at twice the frequency,
/// as a record read at half its rate gives) is merged alone and said, with the frequencies
/// each setup saw; setups that share their mode are not.
#[test]
fn a_setup_sharing_no_mode_is_said_with_its_frequencies() {
    let merged = merge(&roving_setups(), &MergeOptions::default()).unwrap();
    assert!(
        merged.notes.iter().all(|n| !n.contains("shares no mode")),
        "{:?}",
        merged.notes
    );
    let mut setups = roving_setups();
    setups[2].modes = vec![observed(&setups[2].channels, &along, 6.0, c(1.0, 0.0))];
    let merged = merge(&setups, &MergeOptions::default()).unwrap();
    let said: Vec<&String> = merged
        .notes
        .iter()
        .filter(|n| n.contains("shares no mode"))
        .collect();
    assert_eq!(said.len(), 1, "{:?}", merged.notes);
    assert!(
        said[0].contains("setup `setup 3`")
            && said[0].contains("6.000")
            && said[0].contains("3.000"),
        "{}",
        said[0]
    );
}

#[test]
fn setups_that_disagree_beyond_their_errors_widen_the_error() {
    let mut setups = roving_setups();
    // 3.000, 3.010, 3.020 Hz against errors of 0.001: χ²/(n−1) = 100.
    for (i, s) in setups.iter_mut().enumerate() {
        s.modes[0].frequency_hz = 3.0 + 0.01 * i as f64;
    }
    let m = &merge(&setups, &MergeOptions::default()).unwrap().modes[0];
    let ratio = m.scatter_ratio.unwrap();
    assert!((ratio - 10.0).abs() < 1e-9, "{ratio}");
    assert!((m.frequency_se_hz.unwrap() - 10.0 * 0.001 / 3f64.sqrt()).abs() < 1e-12);
    assert!((m.frequency_hz - 3.01).abs() < 1e-12);
}

#[test]
fn setups_without_a_common_reference_are_refused_by_name() {
    let mut setups = roving_setups();
    for ch in &mut setups[2].channels {
        ch.reference = false;
    }
    let err = merge(&setups, &MergeOptions::default()).unwrap_err();
    let text = err.to_string();
    assert!(
        matches!(err, MergeError::NoCommonReference { .. }),
        "{text}"
    );
    assert!(text.contains("`setup 3`: []"), "{text}");
}

#[test]
fn a_reference_that_moves_is_said_and_the_others_carry_the_merge() {
    let mut setups = roving_setups();
    // Setup 3's y reference was put on node "4".
    setups[2].channels[4].node = "4".into();
    setups[2].modes = vec![observed(&setups[2].channels, &along, 3.0, c(0.7, -0.2))];
    let merged = merge(&setups, &MergeOptions::default()).unwrap();
    assert_eq!(merged.dofs.iter().filter(|d| d.reference).count(), 1);
    assert!(
        merged
            .notes
            .iter()
            .any(|n| n.contains("node ref") && n.contains("setup 3")),
        "{:?}",
        merged.notes
    );
    let m = &merged.modes[0];
    let node = m.nodes.iter().find(|n| n.node == "2").unwrap();
    assert!((node.motion[0].unwrap() - c(0.6, 0.0)).norm() < 1e-9);
}

#[test]
fn bad_channels_and_options_are_named() {
    let mut setups = roving_setups();
    setups[1].channels[0].direction = [0.0; 3];
    let err = merge(&setups, &MergeOptions::default()).unwrap_err();
    assert_eq!(
        err.to_string(),
        "setup `setup 2`, channel 0: direction [0.0, 0.0, 0.0] is not a nonzero vector"
    );
    // A gain of 1e-300 made every shape entry infinite and every MAC NaN (issue 77); -1e-9
    // (nano-units, a sign) is a gain.
    let mut tiny = roving_setups();
    tiny[1].channels[0].gain = 1e-300;
    let err = merge(&tiny, &MergeOptions::default()).unwrap_err();
    assert!(
        err.to_string()
            .contains("channel 0: gain 1e-300 is more than 12 decades from 1"),
        "{err}"
    );
    tiny[1].channels[0].gain = -1e-9;
    assert!(!matches!(
        merge(&tiny, &MergeOptions::default()),
        Err(MergeError::Channel { .. })
    ));
    // One axis of one node read twice in a setup (here the other way round, 0.5° off):
    // refused, naming both channels; 1° off is another axis.
    let turned = |[x, y, z]: [f64; 3], deg: f64| {
        let (c, s) = (deg.to_radians().cos(), deg.to_radians().sin());
        [c * x - s * y, s * x + c * y, z]
    };
    let mut twice = roving_setups();
    let beam = twice[2].channels[0].direction;
    twice[2].channels[1].direction = turned(beam.map(|v| -v), 0.5);
    let err = merge(&twice, &MergeOptions::default()).unwrap_err();
    assert_eq!(
        err.to_string(),
        "setup `setup 3`, channel 1: it measures node 3 along the axis channel 0 measures: give each node and axis once"
    );
    let (mut a, mut b) = (twice[2].channels[0].clone(), twice[2].channels[0].clone());
    b.direction = turned(beam, 1.0);
    assert!(!same_axis(&a, &b), "1° apart is another axis");
    a.node = "4".into();
    b.direction = beam;
    assert!(!same_axis(&a, &b), "another node");
    let opts = MergeOptions {
        frequency_tolerance: 0.0,
        ..MergeOptions::default()
    };
    assert!(merge(&roving_setups(), &opts).is_err());
    assert_eq!(
        merge(&[], &MergeOptions::default()),
        Err(MergeError::NoSetups)
    );
}

#[test]
fn errors_shrink_as_the_setups_errors_do() {
    // The merged errors are first order in the setups': a tenth of the errors, a tenth of
    // the merged ones.
    let merged = |factor: f64| {
        let mut setups = roving_setups();
        for s in &mut setups {
            for e in s.modes[0].shape_se.as_mut().unwrap() {
                *e *= factor;
            }
        }
        merge(&setups, &MergeOptions::default()).unwrap().modes[0].clone()
    };
    let (a, b) = (merged(1.0), merged(0.1));
    for (x, y) in a.shape_se.iter().zip(&b.shape_se) {
        let (x, y) = (x.unwrap(), y.unwrap());
        // The entry every setup was scaled to 1 by has no error of its own (floored at 1e-9).
        if x < 1e-6 {
            continue;
        }
        assert!((y - 0.1 * x).abs() <= 1e-9 * x.max(1e-12), "{x} {y}");
    }
}

proptest! {
    /// Specification: a setup's mode shape is known only up to a complex factor, so merging
    /// must not depend on it.
    #[test]
    fn the_merge_does_not_depend_on_each_setups_scale(
        re in prop::collection::vec(-3.0f64..3.0, 3),
        im in prop::collection::vec(-3.0f64..3.0, 3),
    ) {
        let base = merge(&roving_setups(), &MergeOptions::default()).unwrap();
        let mut setups = roving_setups();
        for ((s, re), im) in setups.iter_mut().zip(&re).zip(&im) {
            let k = c(*re, *im);
            prop_assume!(k.norm() > 0.1);
            let shape = s.modes[0].shape.as_mut().unwrap();
            shape.iter_mut().for_each(|v| *v *= k);
            let se = s.modes[0].shape_se.as_mut().unwrap();
            se.iter_mut().for_each(|e| *e *= k.norm());
        }
        let scaled = merge(&setups, &MergeOptions::default()).unwrap();
        for (a, b) in base.modes[0].shape.iter().zip(&scaled.modes[0].shape) {
            prop_assert!((a.unwrap() - b.unwrap()).norm() < 1e-9);
        }
        for (a, b) in base.modes[0].shape_se.iter().zip(&scaled.modes[0].shape_se) {
            prop_assert!((a.unwrap() - b.unwrap()).abs() < 1e-9 * a.unwrap().max(1e-9));
        }
    }
}

#[test]
fn a_mode_without_a_shape_is_left_out_and_said() {
    let mut setups = roving_setups();
    let mut shapeless = observed(&setups[0].channels, &along, 7.0, c(1.0, 0.0));
    shapeless.shape = None;
    shapeless.shape_se = None;
    setups[0].modes.insert(0, shapeless);
    let merged = merge(&setups, &MergeOptions::default()).unwrap();
    assert_eq!(merged.modes.len(), 1);
    assert!(
        merged
            .notes
            .iter()
            .any(|n| n.contains("7.0000 Hz has no shape")),
        "{:?}",
        merged.notes
    );
    // The merged mode names setup 1's mode by its place among the modes given.
    let seen = merged.modes[0]
        .seen_in
        .iter()
        .find(|s| s.setup == 0)
        .unwrap();
    assert_eq!(seen.mode, 1);
}

/// Two halves of a structure sharing two references at a mode's nodes: the references'
/// entries are within their errors of zero, so their MAC is noise and cannot split the mode;
/// where the references do move, parts that disagree still keep two modes apart.
#[test]
fn references_a_mode_does_not_move_do_not_split_it() {
    let half = |name: &str, node: &str, f: f64, refs: [C64; 2], se: f64| {
        let channels = vec![
            channel("ref", [1.0, 0.0, 0.0], Quantity::Displacement, true),
            channel("ref", [0.0, 1.0, 0.0], Quantity::Displacement, true),
            channel(node, [0.0, 0.0, 1.0], Quantity::Displacement, false),
        ];
        SetupModes {
            name: name.into(),
            channels,
            modes: vec![ReportedMode {
                frequency_hz: f,
                frequency_se_hz: Some(0.0004),
                damping_ratio: 0.02,
                damping_se: Some(0.002),
                shape: Some(vec![refs[0], refs[1], c(1.0, 0.0)]),
                shape_from_ssi: false,
                shape_se: Some(vec![se, se, 0.0]),
                ssi_mode: None,
            }],
        }
    };
    // Reference parts at right angles (MAC 0): noise at the nodes of the mode …
    let (a, b) = (
        [c(0.01, 0.004), c(0.004, 0.0)],
        [c(-0.004, 0.0), c(0.012, 0.0)],
    );
    let merged = merge(
        &[
            half("north", "1", 0.4563, a, 0.02),
            half("south", "2", 0.4568, b, 0.02),
        ],
        &MergeOptions::default(),
    )
    .unwrap();
    assert_eq!(merged.modes.len(), 1, "{:?}", merged.modes);
    assert_eq!(merged.modes[0].seen_in.len(), 2);
    // … or the references' true motion, told beyond their errors: two modes.
    let (a, b) = ([c(0.5, 0.0), c(0.3, 0.0)], [c(-0.3, 0.0), c(0.5, 0.0)]);
    let merged = merge(
        &[
            half("north", "1", 0.4563, a, 0.001),
            half("south", "2", 0.4568, b, 0.001),
        ],
        &MergeOptions::default(),
    )
    .unwrap();
    assert_eq!(merged.modes.len(), 2);
}
