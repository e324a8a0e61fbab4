//! The reports a browser opens (`hyst ssi --html`), opened in headless Chromium: no console
//! message, the poles and modes of the JSON report in the page's DOM, the mode shape's
//! animation advancing, and a screenshot kept under `target/html-report/`. Pages of a
//! measured-layout test (the steel frame's 15 setups on its geometry), of the OMA record made
//! outside the project, and of a 10-channel record (under 2 MB).
//!
//! Chromium is Debian's `chromium` (`.ci/run` installs it): missing, the test fails under CI
//! and is skipped with a message elsewhere.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

use hyst_testkit::chromium;

fn browser() -> Option<PathBuf> {
    match chromium::find() {
        Some(b) => Some(b),
        None if std::env::var_os("CI").is_some() => {
            panic!("chromium is missing, and CI needs it (apt-get install chromium)")
        }
        None => {
            eprintln!(
                "SKIPPED: chromium not found (apt-get install chromium, or set HYST_CHROMIUM)"
            );
            None
        }
    }
}

fn out_dir() -> PathBuf {
    let d = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("target")
        .join("html-report");
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn hyst(args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_hyst"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Open `page` in the browser and check what every report page must show: no console
/// message, `modes` rows in the modes' table, and the shape's animation advancing.
fn check_page(browser: &Path, page: &Path, modes: usize, height: u32) -> chromium::Opened {
    // One browser at a time: four at once on two cores drew 3 frames each in 2.5 s of
    // virtual time; alone, each draws more, so the animation's check does not hang on load.
    static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let png = page.with_extension("png");
    let opened = chromium::open(browser, page, 4000, Some((&png, 1100, height))).unwrap();
    assert!(
        opened.console.is_empty(),
        "{}: {:?}",
        page.display(),
        opened.console
    );
    assert_eq!(opened.count("class=\"mode\""), modes, "{}", page.display());
    let frames: usize = opened
        .attribute("shape", "data-frames")
        .unwrap()
        .parse()
        .unwrap();
    let phase: f64 = opened
        .attribute("shape", "data-phase")
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        frames >= 2 && phase > 0.0,
        "the animation stood still: {frames} frames, phase {phase}"
    );
    println!(
        "{}: {} bytes, {frames} frames drawn, screenshot {}",
        page.display(),
        std::fs::metadata(page).unwrap().len(),
        png.display()
    );
    opened
}

/// Poles and reported modes of a `hyst ssi --json` document.
fn counts(json: &Path) -> (usize, usize) {
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    let poles = doc["diagram"]["orders"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| o["poles"].as_array().unwrap().len())
        .sum();
    let analysis: covssi::ModalAnalysis = {
        let mut d = doc.clone();
        d.as_object_mut().unwrap().remove("record");
        serde_json::from_value(d).unwrap()
    };
    (poles, analysis.reported_modes().len())
}

/// `hyst ssi` with `args` writing the page `name`.html (and its JSON), opened and checked,
/// its poles in the DOM as in the JSON; the page's size in bytes.
fn check_record_page(browser: &Path, args: &[&str], name: &str) -> u64 {
    let dir = out_dir();
    let (page, json) = (
        dir.join(format!("{name}.html")),
        dir.join(format!("{name}.json")),
    );
    let mut all = vec!["ssi"];
    all.extend_from_slice(args);
    all.extend_from_slice(&[
        "--html",
        page.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    hyst(&all);
    let (poles, modes) = counts(&json);
    let opened = check_page(browser, &page, modes, 1900);
    assert_eq!(
        opened.attribute("diagram", "data-poles"),
        Some(poles.to_string())
    );
    std::fs::metadata(&page).unwrap().len()
}

#[test]
fn a_records_report_opens_with_its_poles_modes_and_moving_shape() {
    let Some(record) = common::data_file("oma/data_3dof.csv") else {
        return;
    };
    let Some(browser) = browser() else {
        return;
    };
    let r = record.to_str().unwrap();
    check_record_page(
        &browser,
        &["--input", r, "--fs", "20", "--columns", "y1,y2,y3"],
        "oma_3dof",
    );
}

#[test]
fn a_ten_channel_report_stays_under_two_megabytes() {
    use covssi::synth::ModalRecord;
    let Some(browser) = browser() else {
        return;
    };
    let modes: Vec<(f64, f64)> = (1..=6).map(|j| (1.1 * j as f64, 0.02)).collect();
    let gains: Vec<Vec<f64>> = (0..10)
        .map(|c| {
            (0..12)
                .map(|k| {
                    if k % 2 == 0 {
                        ((c + 1) as f64 * (k / 2 + 1) as f64 * 0.3).sin()
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect();
    let y = ModalRecord::new(20.0, &modes)
        .with_gains(gains)
        .with_noise(0.05)
        .generate(30000, 4_900_001);
    let dir = out_dir();
    let csv = dir.join("ten_channels.csv");
    let mut text = (0..10)
        .map(|c| format!("y{c}"))
        .collect::<Vec<_>>()
        .join(",")
        + "\n";
    for i in 0..y[0].len() {
        text += &(y
            .iter()
            .map(|c| c[i].to_string())
            .collect::<Vec<_>>()
            .join(",")
            + "\n");
    }
    std::fs::write(&csv, text).unwrap();
    let args = ["--input", csv.to_str().unwrap(), "--fs", "20"];
    let size = check_record_page(&browser, &args, "ten_channels");
    assert!(size < 2_000_000, "{size} bytes");
}

#[test]
fn merged_setups_open_on_the_steel_frames_geometry() {
    let Some(grid) = common::data_file("steelframe/grid.txt") else {
        return;
    };
    let Some(browser) = browser() else {
        return;
    };
    let Some((_, report, _)) = common::steel_frame() else {
        return;
    };
    // The page `hyst ssi --setups FOLDER --html` writes, from the merge the other steel
    // frame tests share (the command's page is the library's: pytest's
    // test_the_pages_are_the_commands compares them).
    let dir = out_dir();
    let page = dir.join("steelframe_setups.html");
    let folder = grid.parent().unwrap();
    let geometry = hyst::io::setups_geometry(folder, None, None).unwrap();
    let g = geometry.as_ref().map(|(g, p)| (g, p.as_path()));
    let title = format!("hyst ssi --setups {}", folder.display());
    let html = hyst::html::setups_page(&title, report, g).unwrap();
    std::fs::write(&page, html).unwrap();
    let opened = check_page(&browser, &page, 11, 1500);
    // Each setup's diagram to choose from, the first drawn with all its poles.
    let first = &report.setups[0].analysis.ssi.diagram;
    let poles: usize = first.orders.iter().map(|o| o.poles.len()).sum();
    assert_eq!(
        opened.attribute("diagram", "data-poles"),
        Some(poles.to_string())
    );
    assert_eq!(
        opened.count("<option value="),
        15 + 11,
        "15 setups, 11 modes"
    );
    // Every merged mode's MPC and MPD are in its row (none left as "—").
    let rows: Vec<&str> = opened.dom.split("class=\"mode\"").skip(1).collect();
    assert!(
        rows.iter()
            .all(|r| !r.split("</tr>").next().unwrap().contains('—'))
    );
    // The nodes no channel measures are said.
    assert!(
        opened
            .dom
            .contains("No channel measures node(s) 1, 2, 3, 4, 8, 12, 16, 20")
    );
}

#[test]
fn a_campaigns_report_opens_with_each_modes_series() {
    let Some(record) = common::data_file("oma/data_3dof.csv") else {
        return;
    };
    let Some(browser) = browser() else {
        return;
    };
    let dir = out_dir();
    let (page, out) = (dir.join("track.html"), dir.join("track"));
    let _ = std::fs::remove_dir_all(&out);
    let r = record.to_str().unwrap();
    hyst(&[
        "track",
        "--input",
        r,
        "--fs",
        "20",
        "--columns",
        "y1,y2,y3",
        "--window",
        "200",
        "--out",
        out.to_str().unwrap(),
        "--html",
        page.to_str().unwrap(),
    ]);
    let report: hyst_monitor::TrackReport =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let modes = report.reference.len();
    let opened = check_page(&browser, &page, modes, 2600);
    // A frequency and a damping chart per mode, every row's point, every alarm.
    assert_eq!(
        opened.attribute("track", "data-charts"),
        Some((2 * modes).to_string())
    );
    assert_eq!(
        opened.attribute("track", "data-points"),
        Some((2 * report.rows.len()).to_string())
    );
    assert_eq!(
        opened.attribute("track", "data-alarms"),
        Some(report.alarms.len().to_string())
    );
}
