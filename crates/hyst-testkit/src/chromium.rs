//! Headless Chromium (Debian's package) opening a report page: its DOM after the page's
//! scripts ran for a while, what the page wrote to the console, and a screenshot. For the
//! tests that check what a browser shows, and for the screenshots in the documentation.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The browser: `HYST_CHROMIUM`, else `chromium` on the PATH; `None` when neither runs.
pub fn find() -> Option<PathBuf> {
    let candidate = std::env::var_os("HYST_CHROMIUM")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("chromium"));
    let ok = Command::new(&candidate)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    ok.then_some(candidate)
}

/// The flags every run takes: headless, no sandbox (as root), no GPU, and none of the
/// background connections a closed network refuses; a fresh profile in `profile`.
fn command(browser: &Path, profile: &Path) -> Command {
    let mut c = Command::new(browser);
    c.args([
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--hide-scrollbars",
        "--enable-logging=stderr",
        "--v=0",
    ])
    .arg(format!("--user-data-dir={}", profile.display()));
    c
}

/// What the browser made of a page.
#[derive(Debug, Clone)]
pub struct Opened {
    /// The DOM after the page ran for the time budget, serialized.
    pub dom: String,
    /// The page's console messages (errors and uncaught exceptions among them).
    pub console: Vec<String>,
}

/// Open `page` for `budget_ms` of virtual time: its DOM and console; and, when `screenshot`
/// is given, a second run that saves a `width` × `height` screenshot there.
pub fn open(
    browser: &Path,
    page: &Path,
    budget_ms: u32,
    screenshot: Option<(&Path, u32, u32)>,
) -> Result<Opened, String> {
    let url = format!(
        "file://{}",
        std::fs::canonicalize(page)
            .map_err(|e| format!("{}: {e}", page.display()))?
            .display()
    );
    // A fresh profile per page: two browsers on one profile refuse each other.
    static OPENED: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = OPENED.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let profile = std::env::temp_dir().join(format!("hyst-chromium-{}-{n}", std::process::id()));
    let out = command(browser, &profile)
        .arg(format!("--virtual-time-budget={budget_ms}"))
        .arg("--dump-dom")
        .arg(&url)
        .output()
        .map_err(|e| format!("{}: {e}", browser.display()))?;
    let console = String::from_utf8_lossy(&out.stderr)
        .lines()
        .filter(|l| l.contains(":CONSOLE"))
        .map(str::to_string)
        .collect();
    if let Some((png, w, h)) = screenshot {
        let status = command(browser, &profile)
            .arg(format!("--virtual-time-budget={budget_ms}"))
            .arg(format!("--window-size={w},{h}"))
            .arg(format!("--screenshot={}", png.display()))
            .arg(&url)
            .output()
            .map_err(|e| format!("{}: {e}", browser.display()))?;
        if !png.is_file() {
            return Err(format!(
                "no screenshot at {}: {}",
                png.display(),
                String::from_utf8_lossy(&status.stderr)
            ));
        }
    }
    let _ = std::fs::remove_dir_all(&profile);
    Ok(Opened {
        dom: String::from_utf8_lossy(&out.stdout).into_owned(),
        console,
    })
}

impl Opened {
    /// The value of attribute `name` of the element whose id is `id`, as the DOM holds it.
    pub fn attribute(&self, id: &str, name: &str) -> Option<String> {
        let at = self.dom.find(&format!("id=\"{id}\""))?;
        let start = self.dom[..at].rfind('<')?;
        let end = at + self.dom[at..].find('>')?;
        let tag = &self.dom[start..end];
        let key = format!("{name}=\"");
        let v = tag.find(&key)? + key.len();
        Some(tag[v..v + tag[v..].find('"')?].to_string())
    }

    /// How many times `needle` occurs in the DOM.
    pub fn count(&self, needle: &str) -> usize {
        self.dom.matches(needle).count()
    }
}
