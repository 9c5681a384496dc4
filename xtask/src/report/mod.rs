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
//! - **The stiff hammer's resolution** ([`stiff`]): IMP and EXP against IMP at 16×, 32× and 64×,
//!   and the force waveform. File: `stiff-hammer.csv`.
//! - **The machine and the run** ([`machine`]): CPU, kernel level, commit, wall times. File:
//!   `run.csv`.
//! - `README.md` ([`readme`], advice in [`guide`]): the tables, the plots, the fitted orders and, in
//!   plain words, what to choose for which budget.
//!
//! The data files (`error-vs-runtime.csv`, `reference-check.csv`, `stiff-hammer.csv`,
//! `control-block.csv`, `stability.csv`, `run.csv`) determine every text and plot: `--from-data`
//! rewrites `README.md`, `stability.md`, `convergence.csv` and the plots from the committed data
//! files without running any sweep.
//!
//! A progress bar on stderr shows the long work; it is hidden when stderr is not a terminal.
//! Every file is written to a temporary file in the report directory and renamed into place when
//! complete; nothing outside the report directory is written.
//!
//! `--quick` (for CI, see [`quick_check`]) recomputes the error figures (not the timings) and a
//! small stability sweep, writes nothing, and fails if a fresh error, printed as the report prints
//! it, differs from the committed `error-vs-runtime.csv`, `reference-check.csv`,
//! `stiff-hammer.csv` or `control-block.csv` in any character (see [`QUICK_MAX_SENSITIVITY`]), if
//! the texts made from the committed data differ from the committed `README.md`, `stability.md` or
//! `convergence.csv` in any byte, or if the stability sweep finds a failure. `--rerun ID` reruns
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
pub mod guide;
pub mod machine;
pub mod pareto;
pub mod plot;
pub mod readme;
pub mod restrike;
pub mod results;
pub mod sim;
pub mod stability;
pub mod stiff;

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
    /// Rewrite README.md, stability.md, convergence.csv and the plots from the committed data
    /// files in the report directory, without running any sweep.
    #[arg(long, conflicts_with = "quick")]
    pub from_data: bool,
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
    /// Write into a report directory that holds files but not the report's README (replacing
    /// files of the same names).
    #[arg(long)]
    pub force: bool,
}

/// Why the report could not be made, or why `--quick` failed.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A scene file could not be parsed, or a case could not be built.
    #[error("{0}")]
    Scene(String),
    /// The report directory holds someone else's files.
    #[error("{0}")]
    Folder(String),
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
    if !args.quick {
        crate::folder::claim(&args.out, "report", readme::TITLE, args.force).map_err(ReportError::Folder)?;
    }
    if args.from_data {
        let results = load(&args.scenes, &args.out)?;
        for path in readme::write_derived(&args.out, &results)? {
            writeln!(stdout, "wrote {}", path.display()).ok();
        }
        return Ok(());
    }
    if args.quick {
        let outcome = quick_check(&args.scenes, &args.out)?;
        writeln!(
            stdout,
            "report --quick: {} error rows match {} to every printed digit ({} rows too sensitive to rounding to \
             compare); {} texts match what the committed data give; {} stability runs without failure ({:.1} s)",
            outcome.rows,
            args.out.join(readme::ERROR_CSV).display(),
            outcome.sensitive,
            outcome.texts,
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
    /// Texts regenerated from the committed data and found identical to the committed files.
    pub texts: usize,
    /// Stability runs made.
    pub stability_runs: usize,
    /// Wall time (s).
    pub seconds: f64,
}

/// Read `dir/name`.
fn read(dir: &Path, name: &str) -> Result<String, ReportError> {
    let path = dir.join(name);
    std::fs::read_to_string(&path).map_err(|source| ReportError::Io { path, source })
}

/// Everything the report shows, from the committed data files in `report_dir` and the scene files
/// in `scenes` (the Fig. 4 study, deterministic and quick, is recomputed).
pub fn load(scenes: &Path, report_dir: &Path) -> Result<results::Results, ReportError> {
    let bad = |name: &str, e: String| ReportError::Scene(format!("{}: {e}", report_dir.join(name).display()));
    let cases = cases::cases(scenes)?;
    let rows = error::parse_rows(&read(report_dir, readme::ERROR_CSV)?).map_err(|e| bad(readme::ERROR_CSV, e))?;
    let checks = error::parse_reference_csv(&read(report_dir, readme::REFERENCE_CSV)?)
        .map_err(|e| bad(readme::REFERENCE_CSV, e))?;
    let reference_checks = cases
        .iter()
        .map(|c| {
            checks
                .iter()
                .find(|(name, _)| name == c.name)
                .map(|(_, check)| *check)
                .ok_or_else(|| bad(readme::REFERENCE_CSV, format!("no line for {}", c.name)))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let stiff = stiff::parse(&read(report_dir, readme::STIFF_CSV)?).map_err(|e| bad(readme::STIFF_CSV, e))?;
    let blocks = control_block::parse(&read(report_dir, readme::CONTROL_BLOCK_CSV)?)
        .map_err(|e| bad(readme::CONTROL_BLOCK_CSV, e))?;
    let summary = stability::Summary::parse_csv(&read(report_dir, readme::STABILITY_CSV)?)
        .map_err(|e| bad(readme::STABILITY_CSV, e))?;
    let run = machine::RunInfo::parse_csv(&read(report_dir, readme::RUN_CSV)?).map_err(|e| bad(readme::RUN_CSV, e))?;
    let fig4 = fig4::study(&cases[0].scene);
    Ok(results::Results { cases, rows, reference_checks, fig4, blocks, summary, stiff, run })
}

/// The first line where `fresh` and `committed` differ, for a mismatch message.
fn first_difference(name: &str, fresh: &str, committed: &str) -> String {
    let (mut a, mut b) = (fresh.lines(), committed.lines());
    for line in 1.. {
        match (a.next(), b.next()) {
            (Some(x), Some(y)) if x == y => continue,
            (None, None) => break,
            (x, y) => {
                return format!(
                    "{name}: line {line} differs from what the committed data give:\n  now:       {}\n  committed: {}",
                    x.unwrap_or("(end of file)"),
                    y.unwrap_or("(end of file)")
                );
            }
        }
    }
    format!("{name}: differs only in line endings")
}

/// The CI check: recompute every error figure (no timing, no plots) and compare it with
/// `report_dir/error-vs-runtime.csv`, `reference-check.csv`, `stiff-hammer.csv` and
/// `control-block.csv` as printed, digit for digit (rows of the error table whose stored
/// sensitivity exceeds [`QUICK_MAX_SENSITIVITY`] are recomputed but not compared); regenerate
/// `README.md`, `stability.md` and `convergence.csv` from the committed data files and compare them
/// byte for byte with the committed ones; then run [`QUICK_SETS`] stability sets per scene kind and
/// method, which must show no failure. Writes nothing.
pub fn quick_check(scenes: &Path, report_dir: &Path) -> Result<QuickOutcome, ReportError> {
    let start = Instant::now();
    let stored = error::parse_csv(&read(report_dir, readme::ERROR_CSV)?)
        .map_err(|e| ReportError::Scene(format!("{}: {e}", report_dir.join(readme::ERROR_CSV).display())))?;
    let cases = cases::cases(scenes)?;
    let configs = error::configs(&error::SWEPT_SEGMENTS, &error::OVERSAMPLING);
    let bar = progress(cases.len() * (configs.len() + 1) + 1, "errors (quick)");
    let mut fresh = Vec::new();
    let mut checks = Vec::new();
    for case in &cases {
        fresh.extend(error::sweep_case(case, &configs, 0, &|| bar.inc(1)));
        checks.push((case.name.to_owned(), error::reference_check(case)));
        bar.inc(1);
    }
    let stiff_rows = cases.iter().find(|c| c.name == cases::STIFF_HAMMER).map(stiff::study);
    bar.finish_and_clear();
    let mut comparison = error::compare(&fresh, &stored, QUICK_MAX_SENSITIVITY);
    let blocks_text = read(report_dir, readme::CONTROL_BLOCK_CSV)?;
    let blocks = control_block::study(0, &|| {});
    comparison.problems.extend(control_block::compare(&blocks, &blocks_text));
    comparison.compared += blocks.len();
    let mut recomputed = vec![(readme::REFERENCE_CSV, error::reference_csv(&checks))];
    if let Some(rows) = &stiff_rows {
        recomputed.push((readme::STIFF_CSV, stiff::csv(rows)));
    }
    for (name, text) in recomputed {
        let committed = read(report_dir, name)?;
        if text != committed {
            comparison.problems.push(first_difference(name, &text, &committed));
        }
        comparison.compared += text.lines().count().saturating_sub(1);
    }
    let mut texts = 0;
    match load(scenes, report_dir) {
        Ok(results) => {
            for (name, text) in readme::derived_texts(&results) {
                let committed = read(report_dir, name)?;
                if text == committed {
                    texts += 1;
                } else {
                    comparison.problems.push(first_difference(name, &text, &committed));
                }
            }
        }
        Err(e) => comparison.problems.push(format!("the committed data files cannot be read: {e}")),
    }
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
        texts,
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
    let stiff = cases.iter().find(|c| c.name == cases::STIFF_HAMMER).map(stiff::study).unwrap_or_default();
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
    let run =
        machine::RunInfo::this_machine(&args.out, error_seconds, stability_seconds, start.elapsed().as_secs_f64());
    let results = results::Results {
        cases,
        rows,
        reference_checks,
        fig4,
        blocks,
        summary: stability::Summary::from_sweep(&sweep),
        stiff,
        run,
    };
    // The texts and plots are made from the data files as written (errors to 4 decimals, times to
    // 4 significant digits), exactly as `--from-data` and `--quick` make them.
    let mut written = readme::write_data(&args.out, &results)?;
    let from_files = load(&args.scenes, &args.out)?;
    written.extend(readme::write_derived(&args.out, &from_files)?);
    Ok(written)
}
