//! Bad input gives a clear error (or an empty result with the reason), never a panic.

use covssi::{BlockRows, SsiError, SsiOption, SsiOptions, identify};

fn sine(n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| (0.3 * k as f64).sin() + 0.1 * (1.7 * k as f64).cos())
        .collect()
}

#[test]
fn too_few_samples_for_the_lags() {
    let y = sine(30);
    let opts = SsiOptions {
        block_rows: BlockRows::Count(20),
        ..SsiOptions::default()
    };
    let e = identify(&[&y], 10.0, &opts).unwrap_err();
    assert!(
        matches!(
            e,
            SsiError::TooShort {
                samples: 30,
                block_rows: 20,
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("at least 41 samples"), "{e}");
}

#[test]
fn constant_channel() {
    let a = sine(500);
    let b = vec![2.5; 500];
    let e = identify(&[&a, &b], 10.0, &SsiOptions::default()).unwrap_err();
    assert_eq!(
        e,
        SsiError::ConstantChannel {
            channel: 1,
            value: 2.5
        }
    );
}

#[test]
fn nan_channel() {
    let mut a = sine(500);
    a[123] = f64::NAN;
    let e = identify(&[&a], 10.0, &SsiOptions::default()).unwrap_err();
    assert!(matches!(
        e,
        SsiError::NonFinite {
            channel: 0,
            index: 123,
            ..
        }
    ));
}

#[test]
fn unequal_lengths_and_no_channels_and_bad_rate() {
    let a = sine(500);
    let b = sine(400);
    assert!(matches!(
        identify(&[&a, &b], 10.0, &SsiOptions::default()),
        Err(SsiError::LengthMismatch {
            channel: 1,
            len: 400,
            expected: 500
        })
    ));
    assert_eq!(
        identify(&[], 10.0, &SsiOptions::default()),
        Err(SsiError::NoChannels)
    );
    assert!(matches!(
        identify(&[&a], 0.0, &SsiOptions::default()),
        Err(SsiError::NonPositiveRate { .. })
    ));
}

#[test]
fn order_above_the_rank() {
    // Exact correlations of one undamped sinusoid, R_k = cos(0.3 k): a rank-2 Toeplitz
    // matrix; asking for order 10 is an error naming the rank.
    let corr = covssi::Correlations {
        channels: 1,
        references: 1,
        r: (0..20).map(|k| vec![(0.3 * k as f64).cos()]).collect(),
    };
    let opts = SsiOptions {
        max_order: Some(10),
        ..SsiOptions::default()
    };
    let e = covssi::identify_from_correlations(&corr, 10.0, 10, &opts).unwrap_err();
    assert!(
        matches!(
            e,
            SsiError::OrderAboveRank {
                order: 10,
                rank: 2,
                ..
            }
        ),
        "{e}"
    );
    // More than the matrix has rows (5 block rows of one channel).
    let opts = SsiOptions {
        block_rows: BlockRows::Count(5),
        max_order: Some(8),
        ..SsiOptions::default()
    };
    let y = sine(2000);
    let e = identify(&[&y], 10.0, &opts);
    assert!(
        matches!(e, Err(SsiError::OrderAboveRank { order: 8, .. })),
        "{e:?}"
    );
}

#[test]
fn no_stable_pole_gives_an_empty_result_with_the_reason() {
    // Deterministic pseudo-random noise has no stable poles.
    let mut s = 7u64;
    let y: Vec<f64> = (0..3000)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        })
        .collect();
    let opts = SsiOptions {
        block_rows: BlockRows::Count(10),
        max_order: Some(10),
        criteria: covssi::StabilityCriteria {
            frequency: 0.001,
            damping: 0.001,
            mac: 0.001,
            real: 0.001,
        },
        ..SsiOptions::default()
    };
    let r = identify(&[&y], 10.0, &opts).unwrap();
    assert!(r.modes.is_empty());
    assert!(
        r.notes.iter().any(|n| n.contains("no mode found")),
        "{:?}",
        r.notes
    );
}

#[test]
fn options_out_of_range_name_the_option() {
    // A zero count or a threshold that is zero, negative or NaN would otherwise reject every
    // pole and read as "no mode found"; each is named instead.
    let y = sine(2000);
    let cases: [(SsiOptions, SsiOption, f64); 6] = [
        (
            SsiOptions {
                max_order: Some(0),
                ..SsiOptions::default()
            },
            SsiOption::MaxOrder,
            0.0,
        ),
        (
            SsiOptions {
                order_step: 0,
                ..SsiOptions::default()
            },
            SsiOption::OrderStep,
            0.0,
        ),
        (
            SsiOptions {
                min_cluster_size: Some(0),
                ..SsiOptions::default()
            },
            SsiOption::MinClusterSize,
            0.0,
        ),
        (
            SsiOptions {
                criteria: covssi::StabilityCriteria {
                    frequency: -1.0,
                    ..Default::default()
                },
                ..SsiOptions::default()
            },
            SsiOption::CriteriaFrequency,
            -1.0,
        ),
        (
            SsiOptions {
                max_damping: 0.0,
                ..SsiOptions::default()
            },
            SsiOption::MaxDamping,
            0.0,
        ),
        (
            SsiOptions {
                cluster_tolerance: f64::INFINITY,
                ..SsiOptions::default()
            },
            SsiOption::ClusterTolerance,
            f64::INFINITY,
        ),
    ];
    for (opts, name, value) in cases {
        let e = identify(&[&y], 10.0, &opts).unwrap_err();
        assert_eq!(
            e,
            SsiError::InvalidOption {
                option: name,
                value
            },
            "{e}"
        );
        assert!(e.to_string().contains(name.name()), "{e}");
    }
    let nan = SsiOptions {
        criteria: covssi::StabilityCriteria {
            damping: f64::NAN,
            ..Default::default()
        },
        ..SsiOptions::default()
    };
    let e = identify(&[&y], 10.0, &nan).unwrap_err();
    assert!(
        matches!(e, SsiError::InvalidOption { option: SsiOption::CriteriaDamping, value } if value.is_nan()),
        "{e}"
    );
}

#[test]
fn any_units_give_the_same_poles_or_say_they_are_out_of_range() {
    // SSI scales the Toeplitz matrix by a power of two, so a record in any units whose
    // correlations are normal doubles gives the poles it gives in its own units, bit for bit
    // when the units differ by a power of two (before, 1e100-sized values made the SVD fail
    // and 1e-100-sized ones moved the poles); beyond that range it is an error, not a
    // "constant channel" or "rank 0".
    let base = sine(3000);
    let opts = SsiOptions {
        max_order: Some(8),
        ..SsiOptions::default()
    };
    let poles = |r: &covssi::SsiResult| -> Vec<covssi::Complex64> {
        r.diagram
            .orders
            .iter()
            .flat_map(|o| o.poles.iter().map(|p| p.lambda))
            .collect()
    };
    let reference = poles(&identify(&[&base], 10.0, &opts).unwrap());
    for k in [-450, -300, -100, 100, 300, 490] {
        let s = 2f64.powi(k);
        let y: Vec<f64> = base.iter().map(|v| v * s).collect();
        let r = identify(&[&y], 10.0, &opts).unwrap();
        assert_eq!(poles(&r), reference, "scale 2^{k}");
    }
    for s in [1e-160, 1e160, 1e300] {
        let y: Vec<f64> = base.iter().map(|v| v * s).collect();
        let e = identify(&[&y], 10.0, &opts).unwrap_err();
        assert!(matches!(e, SsiError::OutOfRange { .. }), "scale {s:e}: {e}");
        assert!(e.to_string().contains("rescale the record"), "{e}");
    }
}

#[test]
fn lags_as_a_time_or_as_periods_are_checked() {
    let y = sine(2000);
    let fs = 10.0;
    // A count, a time or a number of periods too large for any record is "too short", not an
    // overflow of 2·block_rows: 1e18 s at 10 Hz asks for 5e18 block rows, and a count of 2^63
    // has 2·i = 2^64, one past usize::MAX.
    for block_rows in [
        BlockRows::Count(1 << 63),
        BlockRows::Count(usize::MAX),
        BlockRows::Seconds(1e18),
        BlockRows::Seconds(1e300),
        BlockRows::Periods {
            count: 1e20,
            frequency_hz: 1.0,
        },
    ] {
        let opts = SsiOptions {
            block_rows,
            ..SsiOptions::default()
        };
        let e = identify(&[&y], fs, &opts).unwrap_err();
        assert!(
            matches!(e, SsiError::TooShort { samples: 2000, .. }),
            "{block_rows:?}: {e}"
        );
    }
    // A bad time, count of periods or frequency is named with the value that is wrong, not
    // a ratio of the two.
    let cases = [
        (BlockRows::Seconds(-1.0), SsiOption::BlockRowsSeconds, -1.0),
        (
            BlockRows::Periods {
                count: 0.0,
                frequency_hz: 1.5,
            },
            SsiOption::BlockRowsPeriodsCount,
            0.0,
        ),
        (
            BlockRows::Periods {
                count: 10.0,
                frequency_hz: 0.0,
            },
            SsiOption::BlockRowsPeriodsFrequency,
            0.0,
        ),
        (
            BlockRows::Periods {
                count: 10.0,
                frequency_hz: -2.0,
            },
            SsiOption::BlockRowsPeriodsFrequency,
            -2.0,
        ),
    ];
    for (block_rows, name, value) in cases {
        let opts = SsiOptions {
            block_rows,
            ..SsiOptions::default()
        };
        let e = identify(&[&y], fs, &opts).unwrap_err();
        assert_eq!(
            e,
            SsiError::InvalidOption {
                option: name,
                value
            },
            "{e}"
        );
    }
    // Ten periods of 0.5 Hz at 10 Hz: the largest lag 2i − 1 must cover 200 samples, so
    // i = 101 (ceil of 100.5); 10 s likewise.
    for block_rows in [
        BlockRows::Seconds(20.0),
        BlockRows::Periods {
            count: 10.0,
            frequency_hz: 0.5,
        },
    ] {
        assert_eq!(block_rows.resolve(fs), Ok(Some(101)), "{block_rows:?}");
    }
}

#[test]
fn reference_channels_are_checked() {
    let (a, b) = (
        sine(500),
        sine(500).iter().map(|v| v * v).collect::<Vec<_>>(),
    );
    let with = |r: Vec<usize>| SsiOptions {
        references: Some(r),
        ..SsiOptions::default()
    };
    for (refs, name, value) in [
        (vec![], SsiOption::ReferencesEmpty, 0.0),
        (vec![0, 2], SsiOption::ReferenceOutOfRange, 2.0),
        // The same channel twice repeats a block column of the Toeplitz matrix: a slip of the
        // user's, named, not passed over.
        (vec![1, 0, 1], SsiOption::ReferenceRepeated, 1.0),
    ] {
        let e = identify(&[&a, &b], 10.0, &with(refs.clone())).unwrap_err();
        assert_eq!(
            e,
            SsiError::InvalidOption {
                option: name,
                value
            },
            "{refs:?}: {e}"
        );
    }
}

#[test]
fn refinement_options_are_checked() {
    let y = sine(4000);
    let res = identify(&[&y], 10.0, &SsiOptions::default()).unwrap();
    assert!(!res.modes.is_empty());
    for (opts, name, value) in [
        (
            covssi::RefineOptions {
                max_iterations: 0,
                ..Default::default()
            },
            SsiOption::MaxIterations,
            0.0,
        ),
        (
            covssi::RefineOptions {
                tolerance: -1e-6,
                ..Default::default()
            },
            SsiOption::Tolerance,
            -1e-6,
        ),
    ] {
        let e = covssi::refine(&[&y], 10.0, &res.modes, &opts).unwrap_err();
        assert_eq!(
            e,
            SsiError::InvalidOption {
                option: name,
                value
            },
            "{e}"
        );
    }
    let nan = covssi::RefineOptions {
        tolerance: f64::NAN,
        ..Default::default()
    };
    assert!(matches!(
        covssi::refine(&[&y], 10.0, &res.modes, &nan),
        Err(SsiError::InvalidOption { option: SsiOption::Tolerance, value }) if value.is_nan()
    ));
}

#[test]
fn correlations_of_the_wrong_shape_are_named() {
    // Correlations built by hand (from another tool, say) must have l·r entries per lag.
    let good = covssi::corr::direct(&[&sine(500), &sine(500)], &[0, 1], 40);
    let mut short = good.clone();
    short.r[7].pop();
    let e =
        covssi::identify_from_correlations(&short, 10.0, 20, &SsiOptions::default()).unwrap_err();
    assert_eq!(
        e,
        SsiError::CorrelationShape {
            lag: 7,
            len: 3,
            channels: 2,
            references: 2
        }
    );
    assert!(e.to_string().contains("lag 7 has 3 entries"), "{e}");
    let none = covssi::Correlations {
        channels: 0,
        references: 0,
        r: vec![vec![]; 40],
    };
    assert_eq!(
        covssi::identify_from_correlations(&none, 10.0, 20, &SsiOptions::default()),
        Err(SsiError::NoChannels)
    );
}

/// A lag the user gives that is shorter than a period of a mode found is said: a 0.53 Hz
/// mode seen through 0.39 s of lags came out at 7 % damping on a building's record.
#[test]
fn a_lag_shorter_than_a_mode_s_period_is_said() {
    let fs = 100.0;
    let y: Vec<f64> = (0..20000)
        .map(|k| {
            let t = k as f64 / fs;
            (-0.02 * t).exp() * (2.0 * std::f64::consts::PI * 0.8 * t).sin()
                + 0.01 * ((k * 7919 % 101) as f64 / 101.0 - 0.5)
        })
        .collect();
    let short = SsiOptions {
        block_rows: BlockRows::Count(20),
        max_order: Some(10),
        ..SsiOptions::default()
    };
    let r = identify(&[&y], fs, &short).unwrap();
    assert!(!r.modes.is_empty(), "{:?}", r.notes);
    assert!(
        r.notes
            .iter()
            .any(|n| n.contains("largest lag (0.390 s) is shorter than one period of the mode")),
        "{:?}",
        r.notes
    );
    // Ten periods: no such note.
    let long = SsiOptions {
        block_rows: BlockRows::Seconds(12.5),
        max_order: Some(10),
        ..SsiOptions::default()
    };
    let r = identify(&[&y], fs, &long).unwrap();
    assert!(!r.modes.is_empty(), "{:?}", r.notes);
    assert!(
        !r.notes
            .iter()
            .any(|n| n.contains("shorter than one period")),
        "{:?}",
        r.notes
    );
}
