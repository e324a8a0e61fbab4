//! The HTML reports' bundled libraries and the documentation's screenshots of them.
//!
//! - `cargo xtask vendor-js`: remake `src/html/vendor/` from the npm registry — uPlot's
//!   minified build and stylesheet as published, and three.js's scene, SVG renderer and orbit
//!   controls bundled and minified by esbuild (pinned versions below), with their licenses.
//! - `cargo xtask report-screenshots`: the report of the OMA record and of the steel frame's
//!   merged setups, opened in headless Chromium, saved as `docs/figures/report_*.png`.

use std::process::Command;

use hyst_testkit::run_ok as run;

/// The versions bundled.
const PACKAGES: [&str; 3] = ["three@0.187.0", "uplot@1.6.32", "esbuild@0.25.12"];

/// What of three.js the page uses.
const THREE_ENTRY: &str = "export { Scene, PerspectiveCamera, BufferGeometry, Float32BufferAttribute, LineBasicMaterial, LineSegments, Group, Color } from 'three';\n\
export { SVGRenderer } from 'three/addons/renderers/SVGRenderer.js';\n\
export { OrbitControls } from 'three/addons/controls/OrbitControls.js';\n";

pub fn vendor_js() -> Result<(), String> {
    let work = std::env::temp_dir().join(format!("hyst-vendor-js-{}", std::process::id()));
    std::fs::create_dir_all(&work).map_err(|e| format!("{}: {e}", work.display()))?;
    run(
        Command::new("npm").args(["init", "-y"]).current_dir(&work),
        "npm init",
    )?;
    run(
        Command::new("npm")
            .args(["install", "--silent"])
            .args(PACKAGES)
            .current_dir(&work),
        "npm install",
    )?;
    std::fs::write(work.join("entry.js"), THREE_ENTRY).map_err(|e| e.to_string())?;
    let vendor = hyst_testkit::workspace_root().join("src/html/vendor");
    run(
        Command::new("npx")
            .args([
                "esbuild",
                "entry.js",
                "--bundle",
                "--minify",
                "--format=iife",
                "--global-name=THREE",
            ])
            .arg(format!(
                "--outfile={}",
                vendor.join("three-svg.min.js").display()
            ))
            .current_dir(&work),
        "esbuild",
    )?;
    let modules = work.join("node_modules");
    for (from, to) in [
        ("uplot/dist/uPlot.iife.min.js", "uPlot.iife.min.js"),
        ("uplot/dist/uPlot.min.css", "uPlot.min.css"),
        ("uplot/LICENSE", "LICENSE-uPlot"),
        ("three/LICENSE", "LICENSE-three"),
    ] {
        std::fs::copy(modules.join(from), vendor.join(to)).map_err(|e| format!("{from}: {e}"))?;
    }
    let _ = std::fs::remove_dir_all(&work);
    println!("vendored into {}", vendor.display());
    Ok(())
}

pub fn screenshots() -> Result<(), String> {
    let browser = hyst_testkit::chromium::find()
        .ok_or("chromium is missing (apt-get install chromium, or set HYST_CHROMIUM)")?;
    let data = hyst_testkit::data_dir()
        .ok_or("no shared data folder: set HYST_DATA_DIR or provide ../shared/data")?;
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    run(
        Command::new(cargo)
            .args(["build", "--release", "--quiet", "--bin", "hyst"])
            .current_dir(hyst_testkit::workspace_root()),
        "cargo build --release --bin hyst",
    )?;
    let hyst = hyst_testkit::workspace_root().join("target/release/hyst");
    let pages = hyst_testkit::workspace_root().join("target/html-report");
    let figures = hyst_testkit::workspace_root().join("docs/figures");
    std::fs::create_dir_all(&pages).map_err(|e| e.to_string())?;
    let oma = data.join("oma/data_3dof.csv");
    let frame = data.join("steelframe");
    let cases: [(&str, Vec<String>, u32); 2] = [
        (
            "report_ssi",
            vec![
                "ssi".into(),
                "--input".into(),
                oma.display().to_string(),
                "--fs".into(),
                "20".into(),
                "--columns".into(),
                "y1,y2,y3".into(),
            ],
            1900,
        ),
        (
            "report_setups",
            vec!["ssi".into(), "--setups".into(), frame.display().to_string()],
            1500,
        ),
    ];
    for (name, args, height) in cases {
        let page = pages.join(format!("{name}.html"));
        run(
            Command::new(&hyst)
                .args(&args)
                .arg("--html")
                .arg(&page)
                .stdout(std::process::Stdio::null()),
            &format!("hyst {}", args.join(" ")),
        )?;
        let png = figures.join(format!("{name}.png"));
        let opened =
            hyst_testkit::chromium::open(&browser, &page, 2500, Some((&png, 1100, height)))?;
        if !opened.console.is_empty() {
            return Err(format!("{}: console: {:?}", page.display(), opened.console));
        }
        println!("{} ← {}", png.display(), page.display());
    }
    Ok(())
}
