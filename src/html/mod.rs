//! Reports a browser opens: one self-contained HTML page (no network needed) per analysis —
//! the stabilization diagram over the FDD singular values with each pole's numbers and the
//! reason it was rejected on hover (uPlot), the modes with their errors and EFDD's second
//! opinion, each mode shape drawn on the structure and animated (three.js, drawn as SVG so no
//! GPU is needed), and the MAC matrix. The page's data is serialized from [`PageData`]; the
//! libraries are bundled from `vendor/` (`cargo xtask vendor-js` remakes them from npm).

mod data;
mod track;

pub use data::{
    Diagram, ModeRow, PageData, PolePoint, SetupDiagram, Shapes, diagram_of, setups_page_data,
    ssi_page_data,
};
pub use data::{ModeSeries, TrackSeries};
pub use track::track_page_data;

/// uPlot (MIT), its stylesheet, and three.js's scene, SVG renderer and orbit controls (MIT)
/// bundled by esbuild.
const UPLOT_JS: &str = include_str!("vendor/uPlot.iife.min.js");
const UPLOT_CSS: &str = include_str!("vendor/uPlot.min.css");
const THREE_JS: &str = include_str!("vendor/three-svg.min.js");
const PAGE_JS: &str = include_str!("page.js");
const PAGE_CSS: &str = include_str!("page.css");

/// The page of one record's analysis, with the record's FDD behind the diagram and EFDD's
/// opinion beside each mode when the analysis computed it ([`covssi::AnalysisOptions::fdd`]).
pub fn ssi_page(title: &str, analysis: &covssi::ModalAnalysis) -> String {
    page(&ssi_page_data(title, analysis))
}

/// The page of merged setups, drawn on `geometry` (read from `grid`) when given: a channel's
/// node the geometry lacks is an error; the geometry's nodes no channel measures are said,
/// and drawn at rest.
pub fn setups_page(
    title: &str,
    report: &crate::setups::SetupsReport,
    geometry: Option<(&crate::io::Geometry, &std::path::Path)>,
) -> Result<String, crate::io::IoError> {
    let merged = &report.merged;
    let mut data = setups_page_data(title, report, geometry.map(|g| g.0));
    if let Some((g, grid)) = geometry {
        let still = g.unmeasured(grid, merged.dofs.iter().map(|d| d.node.as_str()))?;
        if !still.is_empty() {
            data.summary.push(format!(
                "No channel measures node(s) {} of the geometry: drawn at rest.",
                still.join(", ")
            ));
        }
    }
    Ok(page(&data))
}

/// The title of a campaign's page, from the command and from Python alike.
pub const TRACK_TITLE: &str = "hyst track: modes against time";

/// The page of a campaign's report (`hyst track --html`, `report.html()` of `hyst.track`).
pub fn track_page(report: &hyst_monitor::TrackReport) -> String {
    page(&track_page_data(TRACK_TITLE, report))
}

/// The page of `data`.
pub fn page(data: &PageData) -> String {
    // serde_json never fails on these types (string keys, finite or null numbers).
    let json = serde_json::to_string(data).unwrap_or_else(|_| "{}".into());
    // Inside a <script> element, "</" would end it and "<!--<script>" would make the
    // parser swallow the rest of the page (it went blank): no "<", ">" or "&" is left in
    // the text, each written as its JSON escape (they occur only inside JSON strings).
    let json = json
        .replace('<', "\\u003c")
        .replace('>', "\\u003e")
        .replace('&', "\\u0026");
    let title = escape(&data.title);
    format!(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
         <title>{title}</title><style>{UPLOT_CSS}\n{PAGE_CSS}</style></head>\n<body>\
         <h1>{title}</h1><p id=\"summary\"></p>\
         <section id=\"diagram-section\"><h2>Stabilization diagram</h2>\
         <p class=\"help\">Poles of every model order over the singular values of the output \
         spectral matrix (FDD); hover over a pole for its numbers and why it was kept or \
         rejected; drag to zoom, double-click to zoom out.</p>\
         <label id=\"diagram-pick-label\" hidden>Setup <select id=\"diagram-pick\"></select></label>\
         <div id=\"diagram\"></div>\
         <div id=\"tip\" class=\"tip\"></div></section>\
         <section id=\"track-section\"><h2>Each mode against time</h2>\
         <p class=\"help\">Frequency and damping ratio of every record ± one standard error; \
         the training's end dashed, alarms in red; drag to zoom, double-click to zoom out.</p>\
         <div id=\"track\"></div></section>\
         <section><h2>Modes</h2><table id=\"modes\"></table></section>\
         <section><h2>Mode shapes</h2><p class=\"help\">Drag to turn, scroll to zoom.</p>\
         <label>Mode <select id=\"mode-pick\"></select></label><div id=\"shape\"></div></section>\
         <section><h2>MAC between the modes</h2><table id=\"mac\"></table></section>\
         <script type=\"application/json\" id=\"report-data\">{json}</script>\n\
         <script>{UPLOT_JS}</script>\n<script>{THREE_JS}</script>\n<script>{PAGE_JS}</script>\
         </body></html>\n"
    )
}

/// `text` safe inside HTML.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_data_cannot_close_its_script_element() {
        let data = PageData {
            title: "a </script><script>alert(1)</script> & b".into(),
            ..PageData::default()
        };
        let html = page(&data);
        assert_eq!(
            html.matches("</script>").count(),
            4,
            "the four scripts' own ends only"
        );
        assert!(html.contains("<title>a &lt;/script&gt;"));
    }

    /// A name holding `<!--<script>` left the page blank: the embedded JSON holds no `<`,
    /// `>` or `&`, and reads back to the names given.
    #[test]
    fn the_data_holds_no_markup_and_reads_back() {
        let title = "test <!--<script> & </script> 1 > 0";
        let data = PageData {
            title: title.into(),
            ..PageData::default()
        };
        let html = page(&data);
        let start = "<script type=\"application/json\" id=\"report-data\">";
        let from = html.find(start).unwrap() + start.len();
        let json = &html[from..from + html[from..].find("</script>").unwrap()];
        assert!(!json.contains(['<', '>', '&']), "{json}");
        let back: serde_json::Value = serde_json::from_str(json).unwrap();
        assert_eq!(back["title"], title);
    }
}
