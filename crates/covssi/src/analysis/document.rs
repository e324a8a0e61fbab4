//! A [`ModalAnalysis`] as JSON: one list of modes, the answer, under `modes`; SSI's own
//! clusters under `ssi_modes`; the decision's source, verdict and what it set apart under
//! `decision` (without a second copy of the answer). Until this layout, SSI's fields sat
//! flattened at the top level, so `modes` held SSI's clusters, shadows included, while the
//! answer was `decision.modes`: a script reading `modes` got the wrong list (issue 76).
//! Documents in that layout are upgraded where they are read back (the `hyst` crate's
//! `report::reference_modes`).

use super::{DecimationReport, ModalAnalysis};
use crate::decision::{ModeDecision, ModeSource, RefinementVerdict, ReportedMode, SetApart};
use crate::jackknife::SsiErrors;
use crate::plausibility::NotReported;
use crate::{
    AutoLag, Mode, RealPoleCluster, RecordSurvey, Refinement, SsiResult, StabilizationDiagram,
};

/// The decision without its modes (they are the document's `modes`).
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct DecisionDocument {
    source: ModeSource,
    refinement: RefinementVerdict,
    set_apart: Vec<SetApart>,
    #[serde(default)]
    confirmed: Vec<SetApart>,
}

/// The layout written and read.
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ModalAnalysisDocument {
    channels: Vec<String>,
    fs_hz: f64,
    decimation: DecimationReport,
    /// The answer.
    modes: Vec<ReportedMode>,
    decision: DecisionDocument,
    block_rows: usize,
    singular_values: Vec<f64>,
    diagram: StabilizationDiagram,
    /// SSI's clusters, the answer's candidates.
    ssi_modes: Vec<Mode>,
    real_poles: Vec<RealPoleCluster>,
    notes: Vec<String>,
    auto_lag: Option<AutoLag>,
    survey: Option<RecordSurvey>,
    #[serde(default)]
    references: Vec<usize>,
    #[serde(default)]
    chosen_references: Option<crate::references::ChosenReferences>,
    mac: Vec<Vec<f64>>,
    refined: Option<Refinement>,
    not_refined: Option<String>,
    not_reported: Vec<NotReported>,
    ssi_errors: Option<SsiErrors>,
    #[serde(default)]
    no_errors: Option<String>,
}

impl From<ModalAnalysis> for ModalAnalysisDocument {
    fn from(a: ModalAnalysis) -> Self {
        let SsiResult {
            block_rows,
            singular_values,
            diagram,
            modes: ssi_modes,
            real_poles,
            notes,
            auto_lag,
            survey,
            references,
            chosen_references,
        } = a.ssi;
        let ModeDecision {
            source,
            modes,
            refinement,
            set_apart,
            confirmed,
        } = a.decision;
        ModalAnalysisDocument {
            channels: a.channels,
            fs_hz: a.fs_hz,
            decimation: a.decimation,
            modes,
            decision: DecisionDocument {
                source,
                refinement,
                set_apart,
                confirmed,
            },
            block_rows,
            singular_values,
            diagram,
            ssi_modes,
            real_poles,
            notes,
            auto_lag,
            survey,
            references,
            chosen_references,
            mac: a.mac,
            refined: a.refined,
            not_refined: a.not_refined,
            not_reported: a.not_reported,
            ssi_errors: a.ssi_errors,
            no_errors: a.no_errors,
        }
    }
}

impl From<ModalAnalysisDocument> for ModalAnalysis {
    fn from(d: ModalAnalysisDocument) -> Self {
        ModalAnalysis {
            channels: d.channels,
            fs_hz: d.fs_hz,
            decimation: d.decimation,
            ssi: SsiResult {
                block_rows: d.block_rows,
                singular_values: d.singular_values,
                diagram: d.diagram,
                modes: d.ssi_modes,
                real_poles: d.real_poles,
                notes: d.notes,
                auto_lag: d.auto_lag,
                survey: d.survey,
                references: d.references,
                chosen_references: d.chosen_references,
            },
            mac: d.mac,
            refined: d.refined,
            not_refined: d.not_refined,
            not_reported: d.not_reported,
            ssi_errors: d.ssi_errors,
            no_errors: d.no_errors,
            decision: ModeDecision {
                source: d.decision.source,
                modes: d.modes,
                refinement: d.decision.refinement,
                set_apart: d.decision.set_apart,
                confirmed: d.decision.confirmed,
            },
            fdd: None,
        }
    }
}
