//! `cargo xtask report [--quick] [--out DIR] [--scenes DIR] [--sets N] [--rerun ID]`
//!
//! Runs the report's sweeps in one process and writes `docs/report/`:
//!
//! - **Error against run time** ([`error`], on the cases of [`cases`]): QSA with
//!   N ∈ {1, …, 100}, EXP and IMP at 1×, 2×, 4× and 8× the base rate. Each row has the
//!   contact-force error against IMP at the same rate and against a converged reference (IMP at
//!   16×), the output-signal errors, the real-time factor (median of 9 runs) and the solver's work
//!   per step. Files: `error-vs-runtime.csv`, `convergence.csv` (least-squares orders, [`fit`]),
//!   `pareto-<case>.png`, `fig5-right.png`, `fig4-trajectories.png` ([`fig4`], [`plot`]).
//! - **Control block** ([`control_block`]): the slide's glide and vibrato at N_b ∈ {1, 8, 64,
//!   256} with QSA and IMP, the errors against N_b = 1 and the run times. File:
//!   `control-block.csv`.
//! - **Stability** ([`stability`]): a seeded sweep of random parameter sets per scene and method
//!   plus hand-picked corners. Files: `stability.csv`, `stability.md`.
//! - `README.md` ([`readme`]): the tables, the plots, the fitted orders and, in plain words, which
//!   method to pick for which budget.
//!
//! A progress bar on stderr shows the long work; it is hidden when stderr is not a terminal.
//! Every file is written to a temporary file in the report directory and renamed into place when
//! complete; nothing outside the report directory is written.
//!
//! `--quick` (for CI, see [`quick_check`]) recomputes the error figures (not the timings) and a
//! small stability sweep, writes nothing, and fails if a fresh error, printed as the report prints
//! it, differs from the committed `error-vs-runtime.csv` or `control-block.csv` in any character
//! (see [`QUICK_MAX_SENSITIVITY`]) or if the stability sweep finds a failure. `--rerun ID` reruns
//! one stability case (the command printed next to each worst case in `stability.md`) and prints
//! its parameters and measurements as one JSON line.

pub mod analysis;
pub mod cases;
pub mod control_block;
pub mod error;
pub mod fig4;
pub mod files;
pub mod fit;
pub mod gestures;
pub mod pareto;
pub mod plot;
pub mod readme;
pub mod restrike;
pub mod sim;
pub mod stability;

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use error::ErrorRow;

/// Rows of `error-vs-runtime.csv` whose stored sensitivity (see [`error`]) exceeds this are
/// recomputed but not compared by `--quick`; every other error is compared exactly as the CSV
/// prints it (4 decimals), with no tolerance.
///
/// The errors are deterministic: the same binary on the same machine reproduces them bit for bit
/// (the string kernels have a fixed operation order on every instruction set, and no solver
/// depends on timing), so their printed digits are reproducible too. Only the run times depend on
/// timing, and `--quick` neither computes nor compares them. Across machines the system `libm`
/// (`powf`, `exp_m1`, `ln_1p` in the power law) can differ by an ulp; the `sensitivity` column
/// measures how far such a difference carries, as the largest change of a row's errors when the
/// exciter's initial state is perturbed by 1e-14 relative (about 50 ulps). A row whose
/// sensitivity prints above 0.0000 (5e-5 or more, half the last printed place) could print
/// differently after a change of rounding, so it is left out; every row of the committed report
/// prints 0.0000 and is compared.
pub const QUICK_MAX_SENSITIVITY: f64 = 0.0;

/// Random parameter sets per scene and method in the `--quick` stability sweep.
pub const QUICK_SETS: usize = 300;

/// Arguments of `report`.
#[derive(Debug, Clone, Args)]
pub struct ReportArgs {
    /// Check mode for CI: recompute the error figures (no timing, no plots) and a small
    /// stability sweep, compare with the committed CSV, write nothing.
    #[arg(long)]
    pub quick: bool,
    /// Report directory.
    #[arg(long, default_value = "docs/report")]
    pub out: PathBuf,
    /// Directory holding the shipped scene files.
    #[arg(long, default_value = "scenes")]
    pub scenes: PathBuf,
    /// Random parameter sets per scene and method in the stability sweep.
    #[arg(long, default_value_t = stability::SETS)]
    pub sets: usize,
    /// Rerun one stability case and print it as JSON, e.g. `hammer-string/qsa/1234` or
    /// `mass-barrier/imp/corner-2`.
    #[arg(long, value_name = "SCENE/METHOD/SET")]
    pub rerun: Option<String>,
}

/// Why the report could not be made, or why `--quick` failed.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A scene file could not be parsed, or a case could not be built.
    #[error("{0}")]
    Scene(String),
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A plot could not be drawn.
    #[error("plot {path}: {message}")]
    Plot {
        /// The PNG.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// `--quick`: fresh errors differ from the committed ones.
    #[error("the committed error figures no longer match fresh runs ({0} mismatches):\n{1}")]
    Mismatch(usize, String),
    /// The stability sweep found failures (`--quick`), or a rerun id is unknown.
    #[error("stability: {0}")]
    Stability(String),
}

/// A progress bar on stderr, hidden unless stderr is a terminal.
pub fn progress(len: usize, message: &'static str) -> ProgressBar {
    let bar = if std::io::stderr().is_terminal() { ProgressBar::new(len as u64) } else { ProgressBar::hidden() };
    let style = ProgressStyle::with_template("{msg:22} [{bar:40}] {pos}/{len} {elapsed_precise} (eta {eta})")
        .expect("a valid template")
        .progress_chars("=> ");
    bar.set_style(style);
    bar.set_message(message);
    bar
}

/// Run the task.
pub fn run(args: &ReportArgs, stdout: &mut dyn Write) -> Result<(), ReportError> {
    if let Some(id) = &args.rerun {
        let cases = cases::cases(&args.scenes)?;
        let line = stability::rerun(id, excerpt(&cases))?;
        writeln!(stdout, "{line}").ok();
        return Ok(());
    }
    if args.quick {
        let outcome = quick_check(&args.scenes, &args.out)?;
        writeln!(
            stdout,
            "report --quick: {} error rows match {} to every printed digit ({} rows too sensitive to rounding to \
             compare); {} stability runs without failure ({:.1} s)",
            outcome.rows,
            args.out.join(readme::ERROR_CSV).display(),
            outcome.sensitive,
            outcome.stability_runs,
            outcome.seconds
        )
        .ok();
        return Ok(());
    }
    let written = full(args)?;
    for path in written {
        writeln!(stdout, "wrote {}", path.display()).ok();
    }
    Ok(())
}

/// What `--quick` checked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuickOutcome {
    /// Error rows recomputed and compared.
    pub rows: usize,
    /// Rows recomputed but not compared: their stored sensitivity exceeds [`QUICK_MAX_SENSITIVITY`].
    pub sensitive: usize,
    /// Stability runs made.
    pub stability_runs: usize,
    /// Wall time (s).
    pub seconds: f64,
}

/// The CI check: recompute every error figure (no timing, no plots) and compare it with
/// `report_dir/error-vs-runtime.csv` and `control-block.csv` as printed, digit for digit (rows
/// whose stored sensitivity exceeds [`QUICK_MAX_SENSITIVITY`] are recomputed but not compared),
/// then run [`QUICK_SETS`]
/// stability sets per scene kind and method, which must show no failure. Writes nothing.
pub fn quick_check(scenes: &Path, report_dir: &Path) -> Result<QuickOutcome, ReportError> {
    let start = Instant::now();
    let csv_path = report_dir.join(readme::ERROR_CSV);
    let text =
        std::fs::read_to_string(&csv_path).map_err(|source| ReportError::Io { path: csv_path.clone(), source })?;
    let stored = error::parse_csv(&text).map_err(|e| ReportError::Scene(format!("{}: {e}", csv_path.display())))?;
    let cases = cases::cases(scenes)?;
    let configs = error::configs(&error::SWEPT_SEGMENTS, &error::OVERSAMPLING);
    let bar = progress(cases.len() * configs.len(), "errors (quick)");
    let mut fresh = Vec::new();
    for case in &cases {
        fresh.extend(error::sweep_case(case, &configs, 0, &|| bar.inc(1)));
    }
    bar.finish_and_clear();
    let mut comparison = error::compare(&fresh, &stored, QUICK_MAX_SENSITIVITY);
    let blocks_path = report_dir.join(readme::CONTROL_BLOCK_CSV);
    let blocks_text = std::fs::read_to_string(&blocks_path)
        .map_err(|source| ReportError::Io { path: blocks_path.clone(), source })?;
    let blocks = control_block::study(0, &|| {});
    comparison.problems.extend(control_block::compare(&blocks, &blocks_text));
    comparison.compared += blocks.len();
    if !comparison.problems.is_empty() {
        return Err(ReportError::Mismatch(comparison.problems.len(), comparison.problems.join("\n")));
    }
    let bar = progress(stability::sets_per_kind(QUICK_SETS, true).iter().sum(), "stability (quick)");
    let sweep = stability::sweep(QUICK_SETS, excerpt(&cases), &|| bar.inc(1));
    bar.finish_and_clear();
    let failures = sweep.failures();
    if !failures.is_empty() {
        return Err(ReportError::Stability(failures.join("\n")));
    }
    Ok(QuickOutcome {
        rows: comparison.compared,
        sensitive: comparison.sensitive,
        stability_runs: sweep.runs(),
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// The report's slide excerpt, which the stability sweep also runs as a corner.
fn excerpt(cases: &[cases::Case]) -> Option<&sim::CaseScene> {
    cases.iter().find(|c| matches!(c.scene.setup, sim::Setup::Slide(..))).map(|c| &c.scene)
}

/// The full report: every sweep, every file. Returns the files written.
fn full(args: &ReportArgs) -> Result<Vec<PathBuf>, ReportError> {
    let start = Instant::now();
    std::fs::create_dir_all(&args.out).map_err(|source| ReportError::Io { path: args.out.clone(), source })?;
    let cases = cases::cases(&args.scenes)?;
    let configs = error::configs(&error::SWEPT_SEGMENTS, &error::OVERSAMPLING);
    let bar = progress(cases.len() * (3 * configs.len() + error::TIMING_RUNS + 1), "error vs run time");
    let mut rows: Vec<ErrorRow> = Vec::new();
    let mut reference_checks = Vec::new();
    for case in &cases {
        let mut case_rows = error::sweep_case(case, &configs, error::TIMING_RUNS, &|| bar.inc(1));
        error::measure_sensitivity(case, &configs, &mut case_rows, &|| bar.inc(1));
        rows.extend(case_rows);
        reference_checks.push(error::reference_check(case));
        bar.inc(1);
    }
    bar.finish_and_clear();
    let error_seconds = start.elapsed().as_secs_f64();
    let fig4 = fig4::study(&cases[0].scene);
    let bar = progress(2 * control_block::STUDY_METHODS.len() * control_block::BLOCKS.len(), "control block");
    let blocks = control_block::study(error::TIMING_RUNS, &|| bar.inc(1));
    bar.finish_and_clear();
    let stability_start = Instant::now();
    let bar = progress(stability::sets_per_kind(args.sets, true).iter().sum(), "stability sweep");
    let sweep = stability::sweep(args.sets, excerpt(&cases), &|| bar.inc(1));
    bar.finish_and_clear();
    let stability_seconds = stability_start.elapsed().as_secs_f64();
    let results = readme::Results {
        cases: &cases,
        rows: &rows,
        reference_checks: &reference_checks,
        fig4: &fig4,
        blocks: &blocks,
        sweep: &sweep,
        timing: readme::Timing { error_seconds, stability_seconds, total_seconds: 0.0 },
    };
    readme::write_all(&args.out, &results, start)
}
