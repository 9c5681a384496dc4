//! What the report's texts are made from (the data files' contents, [`Results`]) and how they
//! print an error, a run time and a configuration.

use super::cases::Case;
use super::control_block::BlockRow;
use super::error::ErrorRow;
use super::fig4::Fig4Study;
use super::machine::RunInfo;
use super::stability::Summary;
use super::stiff::StiffRow;

/// Everything the report shows: what the data files hold, and the cases they were made on.
#[derive(Debug)]
pub struct Results {
    /// The cases (from the scene files).
    pub cases: Vec<Case>,
    /// The error rows (`error-vs-runtime.csv`).
    pub rows: Vec<ErrorRow>,
    /// Per case, in the order of `cases`: force and output error of the 16× reference against
    /// 32× (`reference-check.csv`).
    pub reference_checks: Vec<(f64, f64)>,
    /// The Fig. 4 study (recomputed: it takes milliseconds and is deterministic).
    pub fig4: Fig4Study,
    /// The control-block study (`control-block.csv`).
    pub blocks: Vec<BlockRow>,
    /// The stability summary (`stability.csv`).
    pub summary: Summary,
    /// The stiff hammer's resolution study (`stiff-hammer.csv`).
    pub stiff: Vec<StiffRow>,
    /// The machine and the run (`run.csv`).
    pub run: RunInfo,
}

/// An error as the report prints it (`exact` for −∞).
pub fn e(v: f64) -> String {
    if v == f64::NEG_INFINITY { "exact".to_owned() } else { format!("{v:.2}") }
}

/// A run time as the report prints it.
pub fn t(v: Option<f64>) -> String {
    v.map_or("–".to_owned(), |v| format!("{v:.2e}"))
}

/// A configuration's label in code style.
pub fn label(row: &ErrorRow) -> String {
    format!("`{}`", row.config.label())
}
