//! Writing the report: CSV files, plots, `stability.md` and `README.md`.
//!
//! Every file goes to a temporary file in the report directory and is renamed into place when
//! complete. The texts state the measured numbers and the conclusions [`super::analysis`] draws
//! from them; nothing in them is typed in by hand except the explanations of the methods.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use qsa_dsp::contact::Method;
use qsa_dsp::string::ModalString;

use super::ReportError;
use super::analysis::{self, Order, Signal, Verdict};
use super::cases::Case;
use super::control_block::{self, BlockRow};
use super::error::{self, CHECK_OVERSAMPLING, ErrorRow, REFERENCE_OVERSAMPLING, SWEPT_SEGMENTS, TIMING_RUNS};
use super::fig4::{self, Fig4Study};
use super::files::make_readable;
use super::plot;
use super::sim::Setup;
use super::stability::{self, BUDGET_LIMIT, ENERGY_LIMIT, Summary, Tally};

/// The error table.
pub const ERROR_CSV: &str = "error-vs-runtime.csv";
/// The fitted orders.
pub const CONVERGENCE_CSV: &str = "convergence.csv";
/// The control-block table.
pub const CONTROL_BLOCK_CSV: &str = "control-block.csv";
/// The stability summary table.
pub const STABILITY_CSV: &str = "stability.csv";
/// The stability report.
pub const STABILITY_MD: &str = "stability.md";
/// The report.
pub const README: &str = "README.md";
/// The seed's Fig. 5 (right) plot.
pub const FIG5_PNG: &str = "fig5-right.png";
/// The Fig. 4 trajectories.
pub const FIG4_PNG: &str = "fig4-trajectories.png";

/// The Pareto plot of a case.
pub fn pareto_png(case: &str) -> String {
    format!("pareto-{case}.png")
}

/// Wall times of the report's parts (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timing {
    /// Error sweep (renders and timing).
    pub error_seconds: f64,
    /// Stability sweep.
    pub stability_seconds: f64,
    /// Everything, including the plots.
    pub total_seconds: f64,
}

/// Everything the report shows.
#[derive(Debug)]
pub struct Results<'a> {
    /// The cases.
    pub cases: &'a [Case],
    /// The error rows.
    pub rows: &'a [ErrorRow],
    /// Per case: force and output error of the 16× reference against 32×.
    pub reference_checks: &'a [(f64, f64)],
    /// The Fig. 4 study.
    pub fig4: &'a Fig4Study,
    /// The control-block study.
    pub blocks: &'a [BlockRow],
    /// The stability sweep.
    pub sweep: &'a stability::Sweep,
    /// Wall times.
    pub timing: Timing,
}

/// Write `content` to `dir/name` through a temporary file.
pub fn write_text(dir: &Path, name: &str, content: &str) -> Result<PathBuf, ReportError> {
    let path = dir.join(name);
    let io = |source| ReportError::Io { path: path.clone(), source };
    let mut temp = tempfile::Builder::new().prefix(".report-").tempfile_in(dir).map_err(io)?;
    temp.write_all(content.as_bytes()).map_err(io)?;
    make_readable(temp.as_file()).map_err(io)?;
    temp.persist(&path).map_err(|e| io(e.error))?;
    Ok(path)
}

/// Write the data files and the plots; the README last. Returns the paths written.
pub fn write_all(dir: &Path, r: &Results, started: std::time::Instant) -> Result<Vec<PathBuf>, ReportError> {
    let mut written = vec![write_text(dir, ERROR_CSV, &error::to_csv(r.rows))?];
    let names: Vec<&str> = r.cases.iter().map(|c| c.name).collect();
    let orders = analysis::orders(r.rows, &names);
    written.push(write_text(dir, CONVERGENCE_CSV, &convergence_csv(&orders))?);
    for case in r.cases {
        let rows: Vec<&ErrorRow> = r.rows.iter().filter(|row| row.case == case.name).collect();
        let path = dir.join(pareto_png(case.name));
        plot::pareto(&path, &format!("{}: error against run time", case.title), &rows)?;
        written.push(path);
    }
    let curves: Vec<(String, Vec<(f64, f64)>)> = r
        .cases
        .iter()
        .map(|c| {
            let points = SWEPT_SEGMENTS
                .iter()
                .filter_map(|&n| {
                    r.rows.iter().find(|row| {
                        row.case == c.name
                            && row.config.method == Method::Qsa
                            && row.config.segments == n
                            && row.config.oversampling == 1
                    })
                })
                .map(|row| (-(row.config.segments as f64).log10(), row.error_vs_imp))
                .collect();
            (c.name.to_owned(), points)
        })
        .collect();
    let fig5 = dir.join(FIG5_PNG);
    plot::fig5_right(&fig5, &curves)?;
    written.push(fig5);
    let fig4_path = dir.join(FIG4_PNG);
    plot::trajectories(&fig4_path, r.fig4)?;
    written.push(fig4_path);
    written.push(write_text(dir, CONTROL_BLOCK_CSV, &control_block::csv(r.blocks))?);
    let summary = Summary::from_sweep(r.sweep);
    written.push(write_text(dir, STABILITY_CSV, &stability_csv(&summary))?);
    written.push(write_text(dir, STABILITY_MD, &stability_md(&summary))?);
    let timing = Timing { total_seconds: started.elapsed().as_secs_f64(), ..r.timing };
    written.push(write_text(dir, README, &readme(r, &orders, timing))?);
    Ok(written)
}

fn e(v: f64) -> String {
    if v == f64::NEG_INFINITY { "exact".to_owned() } else { format!("{v:.2}") }
}

fn t(v: Option<f64>) -> String {
    v.map_or("–".to_owned(), |v| format!("{v:.2e}"))
}

fn convergence_csv(orders: &[Order]) -> String {
    let mut out = String::from("case,quantity,method,range,order,slope,intercept,r2,points\n");
    for o in orders {
        let f = &o.fit;
        writeln!(
            out,
            "{},{},{},{},{:.3},{:.4},{:.4},{:.4},{}",
            o.case,
            o.quantity.replace(',', ";"),
            o.method,
            o.range,
            o.order(),
            f.slope,
            f.intercept,
            f.r2,
            f.points
        )
        .expect("writing to a String");
    }
    out
}

fn modes(case: &Case) -> Option<usize> {
    let fs = f64::from(case.scene.sample_rate);
    match &case.scene.setup {
        Setup::MassBarrier(_) => None,
        Setup::Hammer(p) => ModalString::new(p.string, fs).ok().map(|s| s.modes()),
        Setup::Slide(p, _) => ModalString::new(p.string, fs).ok().map(|s| s.modes()),
    }
}

fn label(row: &ErrorRow) -> String {
    format!("`{}`", row.config.label())
}

fn readme(r: &Results, orders: &[Order], timing: Timing) -> String {
    let mut s = String::new();
    let w = &mut s;
    let rows = r.rows;
    let _ = writeln!(w, "# Error against run time, and stability\n");
    let _ = writeln!(
        w,
        "Generated by `cargo xtask report` (full run: {:.0} s on the project's 2-core machine; error sweep {:.0} s, \
         stability sweep {:.0} s). `cargo xtask report --quick` recomputes every error figure (not the timings) and \
         checks it against `{ERROR_CSV}` and `{CONTROL_BLOCK_CSV}`, leaving out the rows marked as sensitive to \
         rounding (CI runs it through \
         `cargo test`). Errors are deterministic. Run times are noisy (about ±20 % on a quiet machine, more while other jobs \
         run): compare configurations within a case, which are timed round-robin so that a slow spell hits them \
         alike, and read differences under a factor {} as ties.\n",
        timing.total_seconds,
        timing.error_seconds,
        timing.stability_seconds,
        analysis::NOISE_RATIO
    );
    let _ = writeln!(
        w,
        "Files: [`{ERROR_CSV}`]({ERROR_CSV}) (every configuration), [`{CONVERGENCE_CSV}`]({CONVERGENCE_CSV}) (fitted orders), [`{CONTROL_BLOCK_CSV}`]({CONTROL_BLOCK_CSV}) (the control block N_b), [`{STABILITY_MD}`]({STABILITY_MD}) and [`{STABILITY_CSV}`]({STABILITY_CSV}) (the stability sweep), and the plots below. The instrument's loudness per key, [`loudness.png`](loudness.png) and [`loudness.csv`](loudness.csv), comes from `cargo xtask loudness --write`.\n"
    );

    // ------------------------------------------------------------------ which method to pick
    let _ = writeln!(w, "## Which method to pick\n");
    let _ = writeln!(
        w,
        "\"Error\" is the contact-force error against the converged reference, log10 of the normalised L2 \
         difference (−2 = 1 %, −1 = 10 %). \"RTF\" is wall seconds per simulated second on the real-time path \
         (median of {TIMING_RUNS} runs). Labels: `qsa N=6 2x` is QSA with 6 segments at twice the base rate.\n"
    );
    for (case, check) in r.cases.iter().zip(r.reference_checks) {
        let _ = writeln!(w, "- **{}** ({}):", case.name, case.title);
        for (signal, check) in [(Signal::Force, check.0), (Signal::Output, check.1)] {
            let _ = write!(w, "  - by the {} signal: ", signal.name());
            pick_sentence(w, rows, case.name, signal);
            if check > -2.5 {
                let _ = write!(
                    w,
                    " *Caution:* the {REFERENCE_OVERSAMPLING}× reference is itself only {} from {CHECK_OVERSAMPLING}× \
                     here, so errors below about {} are not resolved.",
                    e(check),
                    e(check)
                );
            }
            let _ = writeln!(w);
        }
    }
    let _ = writeln!(w);
    qsa_against_imp(w, r);
    budget_guide(w, r);
    qsa_against_exp(w, r);

    // ------------------------------------------------------------------ cases
    let _ = writeln!(w, "## Cases\n");
    let _ = writeln!(
        w,
        "Every case is rendered at k = 1, 2, 4, 8 times its base rate. Strings keep the modes of the base rate \
         at every k (`ModalString::band_limited` at fs/2), so oversampling refines the time step only. The \
         converged reference is IMP at {REFERENCE_OVERSAMPLING}×; its own error against IMP at {CHECK_OVERSAMPLING}× \
         is listed to show how far it is converged.\n"
    );
    let _ = writeln!(
        w,
        "| case | what | base rate | length | modes | y_ref | reference vs {CHECK_OVERSAMPLING}×: force / output |"
    );
    let _ = writeln!(w, "|---|---|---|---|---|---|---|");
    for (case, check) in r.cases.iter().zip(r.reference_checks) {
        let _ = writeln!(
            w,
            "| `{}` | {} | {} Hz | {} samples ({:.0} ms) | {} | {:.3e} m | {} / {} |",
            case.name,
            case.title,
            case.scene.sample_rate,
            case.scene.samples,
            case.scene.seconds() * 1e3,
            modes(case).map_or("–".to_owned(), |m| m.to_string()),
            case.scene.y_ref(),
            e(check.0),
            e(check.1)
        );
    }
    let _ = writeln!(w, "\nDetails of each case are in the docs of `xtask/src/report/cases.rs`.\n");

    // ------------------------------------------------------------------ notes
    let unresolved: Vec<String> = r
        .cases
        .iter()
        .zip(r.reference_checks)
        .filter(|(_, check)| check.0 > -2.5)
        .map(|(case, check)| format!("`{}` (force {}, output {})", case.name, e(check.0), e(check.1)))
        .collect();
    if !unresolved.is_empty() {
        let _ = writeln!(w, "### Cases whose contact force is not resolved\n");
        let _ = writeln!(
            w,
            "In {}, IMP at {REFERENCE_OVERSAMPLING}× still differs from IMP at {CHECK_OVERSAMPLING}× by the amounts \
             given. A stiff contact pressed against the string's light high modes forms an oscillator above the base \
             rate's Nyquist frequency: in the renders, the stiff hammer's force oscillates at about 25 kHz (smooth at \
             16×), and the slide's force rattles at about 33 kHz at 8× (contact lost every ~10 samples) and oscillates \
             at about 40 kHz at 16×. Below that rate the implicit schemes cannot follow it and warp it to just \
             below the Nyquist frequency (at 1× the slide's force alternates from one sample to the next), so the \
             force error falls slowly or not at all with k, and the slide's force is chaotic (see `sensitivity`). \
             These oscillations are far above hearing: for these cases, choose by the output signal, which does \
             converge, and read force errors below the reference's own error as unresolved.\n",
            unresolved.join(" and ")
        );
    }

    // ------------------------------------------------------------------ measures
    let _ = writeln!(w, "## Error measures\n");
    let _ = writeln!(
        w,
        "For a signal a and a reference b on the same instants, e(a, b) = log10(‖a − b‖₂ / ‖b‖₂).\n\n\
         - `error_vs_imp`: contact force against IMP at the same rate (the seed's measure, its Fig. 5 right). It \
         isolates the contact solver.\n\
         - `error_vs_reference`: contact force against IMP at {REFERENCE_OVERSAMPLING}×, compared on the method's \
         grid (sample n at k·fs against reference sample n·{REFERENCE_OVERSAMPLING}/k). It adds the time-step error.\n\
         - `output_error_vs_imp`, `output_error_vs_reference`: the same on the output signal (force on the barrier, \
         bridge force, string displacement at 0.9 L).\n"
    );

    // ------------------------------------------------------------------ per case
    for case in r.cases {
        let _ = writeln!(w, "## {}\n", case.title);
        let _ = writeln!(w, "![error against run time]({})\n", pareto_png(case.name));
        let _ = writeln!(
            w,
            "Each cell: force error against the reference / against IMP at the same rate / output error against \
             the reference · RTF.\n"
        );
        let _ = writeln!(w, "| method | 1x | 2x | 4x | 8x |");
        let _ = writeln!(w, "|---|---|---|---|---|");
        let methods: Vec<(Method, usize)> =
            SWEPT_SEGMENTS.iter().map(|&n| (Method::Qsa, n)).chain([(Method::Exp, 0), (Method::Imp, 0)]).collect();
        for (method, n) in methods {
            let name = if method == Method::Qsa { format!("qsa N={n}") } else { method.name().to_owned() };
            let _ = write!(w, "| {name} |");
            for k in error::OVERSAMPLING {
                match rows.iter().find(|row| {
                    row.case == case.name
                        && row.config.method == method
                        && row.config.segments == n
                        && row.config.oversampling == k
                }) {
                    Some(row) => {
                        let _ = write!(
                            w,
                            " {} / {} / {} · {} |",
                            e(row.error_vs_reference),
                            e(row.error_vs_imp),
                            e(row.output_error_vs_reference),
                            t(row.rtf)
                        );
                    }
                    None => {
                        let _ = write!(w, " – |");
                    }
                }
            }
            let _ = writeln!(w);
        }
        let _ = writeln!(w);
        let imp: Vec<String> = error::OVERSAMPLING
            .iter()
            .filter_map(|&k| {
                rows.iter()
                    .find(|row| {
                        row.case == case.name && row.config.method == Method::Imp && row.config.oversampling == k
                    })
                    .map(|row| format!("{k}x: mean {:.2}, max {}", row.mean_work, row.max_work))
            })
            .collect();
        let _ = writeln!(w, "IMP Newton iterations per contact step: {}.\n", imp.join("; "));
        let front = analysis::pareto(rows, case.name, Signal::Force);
        let list: Vec<String> =
            front.iter().map(|row| format!("{} ({}, {})", label(row), e(row.error_vs_reference), t(row.rtf))).collect();
        let _ = writeln!(w, "Pareto front over all methods, force (error, RTF): {}.\n", list.join(" → "));
        let sensitive: Vec<String> = rows
            .iter()
            .filter(|row| row.case == case.name && row.sensitivity.is_some_and(|v| v > 0.01))
            .map(|row| format!("{} ({:.3})", label(row), row.sensitivity.unwrap_or(0.0)))
            .collect();
        if sensitive.is_empty() {
            let _ = writeln!(
                w,
                "Every error of this case moves by less than 0.01 under a perturbation of a few rounding errors (column `sensitivity`).\n"
            );
        } else {
            let _ = writeln!(
                w,
                "Rows whose errors move by more than 0.01 under a perturbation of a few rounding errors (column \
                 `sensitivity`; the contact rattles chaotically): {} of {}, up to {:.3}.\n",
                sensitive.len(),
                rows.iter().filter(|row| row.case == case.name).count(),
                rows.iter().filter(|row| row.case == case.name).filter_map(|row| row.sensitivity).fold(0.0, f64::max)
            );
        }
    }

    // ------------------------------------------------------------------ Fig. 5 right
    let _ = writeln!(w, "## QSA against IMP at the base rate (seed Fig. 5, right)\n");
    let _ = writeln!(w, "![error against segment spacing]({FIG5_PNG})\n");
    let _ = writeln!(
        w,
        "Δy/y_ref = 1/N. The seed's Fig. 5 values (docs/physics.md §9.4) were −1.18 at N = 3, −1.62 at N = 6 and \
         −4.01 at N = 50; measured here: {}.\n",
        [3, 6, 50]
            .iter()
            .filter_map(|&n| rows.iter().find(|row| row.case == "fig5-hammer"
                && row.config.method == Method::Qsa
                && row.config.segments == n
                && row.config.oversampling == 1))
            .map(|row| format!("{} at N = {}", e(row.error_vs_imp), row.config.segments))
            .collect::<Vec<_>>()
            .join(", ")
    );

    // ------------------------------------------------------------------ orders
    let _ = writeln!(w, "## Convergence orders\n");
    let _ = writeln!(
        w,
        "Least-squares lines (faer QR) through log10 error against log10 N or log10 k; the order p is minus the \
         slope (error ∝ N^−p or Δt^p). N-fits use N = {}–100 (below that the first segment decides the error); \
         k-fits use k = 1, 2, 4, 8. R² tells how straight the line is: a low R² means the order is not a useful \
         summary there.\n",
        analysis::ORDER_MIN_SEGMENTS
    );
    let _ = writeln!(w, "| case | quantity | method | range | order p | R² |");
    let _ = writeln!(w, "|---|---|---|---|---|---|");
    for o in orders {
        let _ = writeln!(
            w,
            "| {} | {} | {} | {} | {:.2} | {:.3} |",
            o.case,
            o.quantity,
            o.method,
            o.range,
            o.order(),
            o.fit.r2
        );
    }
    let _ = writeln!(w);

    let summary: Vec<String> = r
        .cases
        .iter()
        .filter_map(|case| {
            let find = |quantity: &str, method: &str| {
                orders.iter().find(|o| o.case == case.name && o.quantity == quantity && o.method == method)
            };
            let n = find("force error vs IMP, against N", "qsa 1x")?;
            let k = find("force error vs reference, against k", "imp")?;
            Some(format!(
                "`{}` (α {}): N-order {:.2} (R² {:.2}), time-step order of IMP {:.2} (R² {:.2})",
                case.name,
                case.scene.law.alpha(),
                n.order(),
                n.fit.r2,
                k.order(),
                k.fit.r2
            ))
        })
        .collect();
    let _ = writeln!(
        w,
        "In short, at the base rate: {}. The spline's force error should fall as N^−2 for α ≥ 2 and more slowly \
         for α < 2 (docs/physics.md §1.5), and the scheme should be second order in Δt; where R² is low (the \
         rattling slide, the unresolved stiff hammer) the numbers do not follow a power law.\n",
        summary.join("; ")
    );

    // ------------------------------------------------------------------ Fig. 4
    let _ = writeln!(w, "## Fig. 4: time-shifted entries\n");
    let _ = writeln!(w, "![trajectories]({FIG4_PNG})\n");
    let _ = writeln!(
        w,
        "The Fig. 4 mass enters the barrier at {} sub-sample phases ({} drawn). Effective contact time between the \
         free-flight lines (docs/physics.md §4.4; the seed's claim is that it does not depend on the phase for IMP \
         and QSA):\n",
        fig4::PHASES,
        fig4::PLOTTED_PHASES
    );
    let _ = writeln!(w, "| scheme | shortest (samples) | longest | spread |");
    let _ = writeln!(w, "|---|---|---|---|");
    for s in &r.fig4.schemes {
        let _ = writeln!(
            w,
            "| {} | {:.4} | {:.4} | {:.4} |",
            s.label,
            s.contact_samples.0,
            s.contact_samples.1,
            s.spread()
        );
    }
    let _ = writeln!(
        w,
        "\n(docs/physics.md §4.4 measured spreads of 0.001 (IMP), 0.008 (QSA N=5), 0.003 (QSA N=20) and 1.03 (EXP) \
         samples.)\n"
    );

    // ------------------------------------------------------------------ control block
    control_block_section(w, r.blocks);

    // ------------------------------------------------------------------ stability
    let _ = writeln!(w, "## Stability\n");
    stability_summary(w, &Summary::from_sweep(r.sweep));
    let _ =
        writeln!(w, "\nDetails, worst cases and the commands that rerun them: [`{STABILITY_MD}`]({STABILITY_MD}).\n");
    s
}

fn control_block_section(w: &mut String, rows: &[BlockRow]) {
    let _ = writeln!(w, "## The control block N_b: the slide in motion\n");
    let _ = writeln!(
        w,
        "The slide's controls are sampled every N_b samples and its contact vectors interpolated linearly in \
         between (docs/physics.md §7.5): like N and the sample rate, N_b trades accuracy for run time. A glide \
         (5 to 7 semitones in 0.1 s, about 0.5 m/s) and a vibrato (±3 mm at 5.5 Hz) on the slide-guitar preset \
         at 44.1 kHz, QSA N = {} and IMP, each against the same method at N_b = 1 over the samples where the \
         slide moves (log10 of the relative L2 difference; −2 = 1 %). RTF is the whole render's (median of the \
         timing runs). Data: [`{CONTROL_BLOCK_CSV}`]({CONTROL_BLOCK_CSV}).\n",
        control_block::STUDY_SEGMENTS
    );
    let _ = writeln!(w, "| gesture | method | N_b | output error | force error | RTF |");
    let _ = writeln!(w, "|---|---|---|---|---|---|");
    for r in rows {
        let err = |v: f64| if v.is_nan() { "(reference)".to_owned() } else { format!("{v:.2}") };
        let _ = writeln!(
            w,
            "| {} | {} | {} | {} | {} | {} |",
            r.gesture,
            r.method.name(),
            r.block,
            err(r.output_error),
            err(r.force_error),
            t(Some(r.rtf))
        );
    }
    let at = |gesture: &str, nb: usize, field: fn(&BlockRow) -> f64| {
        rows.iter().find(|r| r.gesture == gesture && r.method == Method::Qsa && r.block == nb).map_or(f64::NAN, field)
    };
    let order =
        |gesture: &str| (at(gesture, 64, |r| r.output_error) - at(gesture, 8, |r| r.output_error)) / 8f64.log10();
    let _ = writeln!(
        w,
        "\nWith QSA the output error falls at order {:.1} (glide) and {:.1} (vibrato) in N_b between 8 and 64, as \
         linear interpolation of the contact vectors should (second order). A per-sample render (N_b = 1) costs \
         {:.1} times the default N_b = 64 for the glide, which is within {:.2} % of it there: N_b = 64 is the \
         plugin's default, and N_b = 8 is the choice for a reference-quality render of fast gestures.\n",
        order("glide"),
        order("vibrato"),
        at("glide", 1, |r| r.rtf) / at("glide", 64, |r| r.rtf),
        100.0 * 10f64.powf(at("glide", 64, |r| r.output_error)),
    );
}

/// The cheapest configurations within 1 %, 10 % and 0.1 % of the reference on `signal`.
fn pick_sentence(w: &mut String, rows: &[ErrorRow], case: &str, signal: Signal) {
    let within = |target| analysis::cheapest(rows, case, signal, target, |_| true);
    match within(-2.0) {
        Some(row) => {
            let _ = write!(
                w,
                "within 1 % at the lowest run time: {} (error {}, RTF {}).",
                label(row),
                e(signal.of(row)),
                t(row.rtf)
            );
        }
        None => {
            let _ = write!(w, "**no configuration measured comes within 1 % of the reference**.");
            if let Some(row) = analysis::most_accurate(rows, case, signal) {
                let _ = write!(
                    w,
                    " The most accurate is {} (error {}, RTF {}).",
                    label(row),
                    e(signal.of(row)),
                    t(row.rtf)
                );
            }
        }
    }
    if let Some(row) = within(-1.0) {
        let _ = write!(w, " Within 10 %: {} (RTF {}).", label(row), t(row.rtf));
    }
    if let Some(row) = within(-3.0) {
        let _ = write!(w, " Within 0.1 %: {} (RTF {}).", label(row), t(row.rtf));
    }
}

/// At the base rate: the fewest QSA segments that match IMP's accuracy, and what that saves.
fn qsa_against_imp(w: &mut String, r: &Results) {
    let _ = writeln!(w, "### QSA against IMP\n");
    let _ = writeln!(
        w,
        "At each case's base rate, the fewest QSA segments whose force error against the reference is within \
         {} of IMP's (so the contact solver adds nothing visible to the time-step error), and the run times:\n",
        analysis::AS_ACCURATE
    );
    let _ = writeln!(w, "| case | QSA as accurate as IMP | its error | IMP's error | QSA RTF | IMP RTF | QSA / IMP |");
    let _ = writeln!(w, "|---|---|---|---|---|---|---|");
    for case in r.cases {
        if let Some((qsa, imp)) = analysis::as_accurate_as_imp(r.rows, case.name, 1, Signal::Force) {
            let ratio = match (qsa.rtf, imp.rtf) {
                (Some(q), Some(i)) => format!("{:.2}", q / i),
                _ => "–".to_owned(),
            };
            let _ = writeln!(
                w,
                "| {} | N = {} | {} | {} | {} | {} | {ratio} |",
                case.name,
                qsa.config.segments,
                e(qsa.error_vs_reference),
                e(imp.error_vs_reference),
                t(qsa.rtf),
                t(imp.rtf)
            );
        }
    }
    let _ = writeln!(w);
}

/// A plain-words budget guide: for each case, what the front offers at each order of magnitude of RTF.
fn budget_guide(w: &mut String, r: &Results) {
    let _ = writeln!(w, "### By budget\n");
    let _ = writeln!(
        w,
        "The best error each run-time budget buys (Pareto front over all methods; the plots below show every \
         configuration):\n"
    );
    let budgets = [1e-3, 3e-3, 1e-2, 3e-2, 1e-1];
    let _ = writeln!(w, "| case | signal | RTF ≤ 1e-3 | ≤ 3e-3 | ≤ 1e-2 | ≤ 3e-2 | ≤ 1e-1 |");
    let _ = writeln!(w, "|---|---|---|---|---|---|---|");
    for case in r.cases {
        for signal in [Signal::Force, Signal::Output] {
            let front = analysis::pareto(r.rows, case.name, signal);
            let _ = write!(w, "| {} | {} |", case.name, signal.name());
            for budget in budgets {
                match front.iter().rev().find(|row| row.rtf.is_some_and(|t| t <= budget)) {
                    Some(row) => {
                        let _ = write!(w, " {} {} |", label(row), e(signal.of(row)));
                    }
                    None => {
                        let _ = write!(w, " – |");
                    }
                }
            }
            let _ = writeln!(w);
        }
    }
    let _ = writeln!(w);
}

fn qsa_against_exp(w: &mut String, r: &Results) {
    let _ = writeln!(w, "### QSA against EXP\n");
    let _ = writeln!(
        w,
        "For each error target, the cheapest QSA and the cheapest EXP configuration that reach it (any N and k), \
         on the contact force and on the output signal. Run times within a factor {} of each other count as a tie \
         (the machine's noise).\n",
        analysis::NOISE_RATIO
    );
    let musical: Vec<&str> = r.cases.iter().filter(|c| c.musical).map(|c| c.name).collect();
    for signal in [Signal::Force, Signal::Output] {
        let _ = writeln!(w, "| case | {} target | QSA | EXP | verdict |", signal.name());
        let _ = writeln!(w, "|---|---|---|---|---|");
        let mut tally = [0usize; 4];
        for case in r.cases {
            for d in analysis::duels(r.rows, case.name, signal) {
                let cell = |row: Option<&ErrorRow>| {
                    row.map_or("–".to_owned(), |row| format!("{} RTF {}", label(row), t(row.rtf)))
                };
                let _ = writeln!(
                    w,
                    "| {} | {:.1} | {} | {} | {} |",
                    case.name,
                    d.target,
                    cell(d.qsa),
                    cell(d.exp),
                    d.words()
                );
                if case.musical {
                    tally[match d.verdict() {
                        Verdict::Qsa => 0,
                        Verdict::Exp => 1,
                        Verdict::Tie => 2,
                        Verdict::Neither => 3,
                    }] += 1;
                }
            }
        }
        let _ = writeln!(
            w,
            "\n**{}**: across the musically relevant cases ({}), over {} (case, target) pairs, QSA is the faster way to \
             the target (or the only one to reach it) in {}, EXP in {}, the two tie within the noise in {}, and \
             neither reaches the target in {}. {}\n",
            signal.name(),
            musical.join(", "),
            tally.iter().sum::<usize>(),
            tally[0],
            tally[1],
            tally[2],
            tally[3],
            duel_conclusion(tally)
        );
    }
}

/// The conclusion of one QSA-against-EXP table, from its tally (QSA, EXP, tie, neither).
fn duel_conclusion(tally: [usize; 4]) -> &'static str {
    let [qsa, exp, tie, _] = tally;
    if qsa == 0 && exp == 0 {
        "On these numbers neither method is faster to a given error: where both reach it, they cost the same within \
         the noise."
    } else if exp == 0 && tie > qsa {
        "QSA is never slower than EXP to a given error here, but it is clearly faster in fewer comparisons than \
         the two tie: in the string cases the modal update dominates the cost of a step, so QSA and EXP cost about \
         the same per sample, and both need the same rate for a given error unless EXP's own error forces it to a \
         higher rate. The claim that QSA reaches a given error at lower run time than EXP holds here only in that \
         weak sense."
    } else if exp == 0 {
        "On these numbers QSA reaches a given error at lower run time than EXP wherever the two differ."
    } else if qsa > exp {
        "QSA wins more often than EXP, but not everywhere: see the rows where EXP is faster."
    } else if qsa == exp {
        "On these numbers neither method is generally faster to a given error."
    } else {
        "On these numbers EXP, not QSA, is more often the faster way to a given error."
    }
}

/// A ratio as the stability texts print it: three decimals up to 100, else two significant digits.
fn ratio_text(v: f64) -> String {
    if v < 100.0 { format!("{v:.3}") } else { format!("{v:.1e}") }
}

fn stability_summary(w: &mut String, summary: &Summary) {
    let failures = summary.failures();
    let non_finite: usize = summary.tallies.iter().map(|t| t.non_finite.len() + t.panics.len()).sum();
    let long: Vec<String> = summary
        .tallies
        .iter()
        .filter(|t| t.kind.long() && t.method == Method::Qsa)
        .map(|t| format!("{} for `{}`", t.random, t.kind.name()))
        .collect();
    let _ = writeln!(
        w,
        "{} random parameter sets per scene kind ({}, whose runs last 2–3 s) plus hand-picked corners, each run \
         with QSA, IMP and EXP: {} runs, {} with a NaN, infinity or panic, {} failures in all (energy error over \
         {ENERGY_LIMIT:.0e}, stored energy above the initial energy and the supplied work by over \
         {BUDGET_LIMIT:.0e} in the moving kinds, the exciter's speed beyond its energy bound, QSA's or IMP's \
         compression beyond its energy bound, QSA over its sign-test bound, or non-finite).\n",
        summary.sets,
        long.join(", "),
        summary.runs(),
        non_finite,
        failures.len()
    );
    let _ = writeln!(
        w,
        "| scene | method | runs | non-finite | worst drift (balance closes) | worst increase (lossy) | worst excess over supplied work | max y/y_ref | max y/y_max (energy bound) | max \\|v\\|/v_max (energy bound) | max work/step |"
    );
    let _ = writeln!(w, "|---|---|---|---|---|---|---|---|---|---|---|");
    for tally in &summary.tallies {
        let first =
            |list: &Vec<stability::Worst>| list.first().map_or("–".to_owned(), |x| format!("{:.1e}", x.value));
        let ratio = |list: &Vec<stability::Worst>| list.first().map_or("–".to_owned(), |x| ratio_text(x.value));
        let _ = writeln!(
            w,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            tally.kind.name(),
            tally.method.name(),
            tally.runs(),
            tally.non_finite.len() + tally.panics.len(),
            first(&tally.drift),
            first(&tally.increase),
            first(&tally.excess),
            ratio(&tally.compression),
            ratio(&tally.compression_bound),
            ratio(&tally.velocity_bound),
            tally.work.first().map_or("–".to_owned(), |x| format!("{:.0}", x.value)),
        );
    }
}

fn stability_csv(summary: &Summary) -> String {
    summary.to_csv()
}

fn worst_list(w: &mut String, tally: &Tally, title: &str, list: &[stability::Worst], format: fn(f64) -> String) {
    if list.is_empty() {
        return;
    }
    let _ = writeln!(w, "{title}:\n");
    for x in list {
        let _ = writeln!(w, "- {} — `{}` — {}", format(x.value), tally.command(&x.id), x.about);
    }
    let _ = writeln!(w);
}

/// The largest first entry of a list over the tallies that `pick` selects (0 when none).
fn largest(summary: &Summary, pick: impl Fn(&Tally) -> Option<&Vec<stability::Worst>>) -> f64 {
    summary.tallies.iter().filter_map(&pick).filter_map(|l| l.first()).map(|x| x.value).fold(0.0, f64::max)
}

fn stability_md(summary: &Summary) -> String {
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(w, "# Stability on stiff and extreme cases\n");
    let _ = writeln!(
        w,
        "Generated by `cargo xtask report`. The parameter ranges, the corners and the measures are defined in the \
         docs of `xtask/src/report/stability.rs`; in short: κ 1e2–1e16 N/m^α, α 1–4, speeds 1e-3–50 m/s, masses \
         0.1 g–1 kg, fs 8–384 kHz, QSA N 1–100,000 (the most a scene file takes), control blocks N_b 1–256, \
         log-uniform, seeded (set i of a scene is reproducible alone). Half of the hammer-string, slide-string and \
         hammer-ringing sets use a random string (L 0.05–2 m, T 50–2000 N, ρA 0.2 g/m–0.2 kg/m, EI 1e-7–0.2 N·m², \
         fundamental 20–5000 Hz, decay b1 0.05–20 1/s, b3 1e-11–1e-7 s), the others a preset's. Four kinds move: \
         `slide-gesture` (the slide gliding at up to 5 m/s with vibrato, the hand pressing and lifting, the fingers \
         switching, at 22.05–192 kHz), `hammer-restrike` (a piano string struck again while it swings, from one \
         sample to 30 ms apart, with dampers landing during contacts), and two that run for 2–3 s of simulated \
         time: `hammer-ringing` (a string struck one to four times and left ringing, a damper landing in a third \
         of them) and `slide-rattling` (a slide trajectory pressing, lifting and dropping the slide on the ringing \
         string). Each strike refits QSA over the hammer's energy plus the string's (as the piano voice does) or, \
         in half of the re-striking sets, over the hammer's energy alone, so that a strike on a swinging string \
         compresses the felt beyond the fit and QSA works on its last quadratic extended beyond the last knot. \
         Each set runs with QSA, IMP and EXP. E = H + booked losses − work of the controls must stay constant: its \
         largest deviation relative to the largest energy is the *drift* of a set whose balance closes and, \
         counting only gains, the *increase* of a lossy one. In the moving kinds the stored energy must also stay \
         below the initial energy plus the work supplied (the *excess*, relative to the largest energy, is what \
         it exceeds that by). y/y_ref compares the largest compression with the QSA fit's range. \
         *Energy bounds*: every term of QSA's and IMP's numerical energy is non-negative, among them the \
         exciter's ½M v² and the contact's ½(V(y^(n+1)) + V(y^n)) (V the fit in force for QSA, the law for IMP), \
         and the energy never exceeds E = H(0) + the work supplied; so y ≤ y_max = V⁻¹(2E) and \
         \\|v\\| ≤ v_max = √(2E/M), with E allowed the energy tolerance {ENERGY_LIMIT:.0e} of the largest \
         energy on top. A run beyond either bound fails (for EXP only the speed counts, see below). \
         Work is QSA sign tests (bound 2⌈log2(N+1)⌉ + 1) or IMP Newton iterations (cap 100) per step.\n"
    );
    stability_summary(w, summary);
    let _ = writeln!(w);
    let failures = summary.failures();
    let _ = writeln!(w, "## Failures\n");
    if failures.is_empty() {
        let _ = writeln!(w, "None in this sweep.\n");
    } else {
        for f in &failures {
            let _ = writeln!(w, "- {f}");
        }
        let _ = writeln!(w);
    }
    let _ = writeln!(w, "## Reading the numbers\n");
    let of = |kind: stability::Kind, method: Method, list: fn(&Tally) -> &Vec<stability::Worst>| {
        summary.tally(kind, method).and_then(|t| list(t).first()).map_or(f64::NAN, |x| x.value)
    };
    let max_ratio = |kind, method| of(kind, method, |t| &t.compression);
    let worst_energy = largest(summary, |t| Some(&t.drift)).max(largest(summary, |t| Some(&t.increase)));
    let worst_excess = |method: Method| largest(summary, |t| (t.method == method).then_some(&t.excess));
    let bound = |method: Method, list: fn(&Tally) -> &Vec<stability::Worst>| {
        largest(summary, |t| (t.method == method).then_some(list(t)))
    };
    let long_drift = |method: Method| {
        largest(summary, |t| (t.method == method && t.kind.long()).then_some(&t.drift))
            .max(largest(summary, |t| (t.method == method && t.kind.long()).then_some(&t.excess)))
    };
    let _ = writeln!(
        w,
        "- **Moving controls.** Over every slide gesture, rattle, re-strike and ringing string the stored energy \
         stayed within the initial energy plus the work supplied (by the hand, the fingers, the slide's travel, \
         the hammers thrown and the dampers' rate changes) to {:.1e} (QSA), {:.1e} (IMP) and {:.1e} (EXP) of the \
         largest energy, against a bound of {BUDGET_LIMIT:.0e}: the moving schemes create no energy \
         (docs/physics.md §7.5).",
        worst_excess(Method::Qsa),
        worst_excess(Method::Imp),
        worst_excess(Method::Exp),
    );
    let _ = writeln!(
        w,
        "- **Seconds of ringing and rattling.** Over the 2–3 s runs the balance held to {:.1e} (QSA), {:.1e} (IMP) \
         and {:.1e} (EXP) of the largest energy (drift or excess, whichever is larger): rounding does not \
         accumulate into a trend over 10⁵ steps.",
        long_drift(Method::Qsa),
        long_drift(Method::Imp),
        long_drift(Method::Exp),
    );
    let _ = writeln!(
        w,
        "- **Energy bounds.** The largest compression reached {} of its energy bound with QSA and {} with IMP; the \
         exciter's speed reached {} (QSA), {} (IMP) and {} (EXP) of its bound. A ratio near 1 is a contact \
         holding nearly all the energy in one sample's potential (the factor 2 in V⁻¹(2E)). EXP's compression, \
         measured against the law's bound, reached {}: its energy holds ½ψ² in place of the potential and nothing \
         ties ψ to y, so its compression is not bounded by its energy and is not counted as a failure; its energy \
         and its speed are bounded.",
        ratio_text(bound(Method::Qsa, |t| &t.compression_bound)),
        ratio_text(bound(Method::Imp, |t| &t.compression_bound)),
        ratio_text(bound(Method::Qsa, |t| &t.velocity_bound)),
        ratio_text(bound(Method::Imp, |t| &t.velocity_bound)),
        ratio_text(bound(Method::Exp, |t| &t.velocity_bound)),
        ratio_text(bound(Method::Exp, |t| &t.compression_bound)),
    );
    let _ = writeln!(
        w,
        "- **Energy.** The worst energy error of any run is {worst_energy:.1e} of the largest energy: rounding, \
         largest for contacts much stiffer than one sample can resolve (docs/physics.md §3.5 expected up to \
         ~1e-8).\n\
         - **Compression beyond y_ref.** With the discrete energy ½(V(y^(n+1)) + V(y^n)), one sample can hold up to \
         twice the contact energy when its neighbour is out of contact, so IMP and QSA reach up to \
         2^(1/(α+1)) ≤ √2 times y_ref on the mass–barrier (measured {:.3}) and a little less on the string \
         ({:.3}). A re-strike whose fit spans the hammer's energy alone meets a string that may swing with more: \
         QSA's compression reached {} times the first fit's y_ref there (`hammer-restrike`), on the extended last \
         quadratic, and {} of its energy bound. On the slide, V_ref is the scene files' default, sized from the \
         static push of the hand; a slide thrown onto the string by a hand at up to 50 m/s carries far more \
         energy, and the compression goes far beyond y_ref (QSA {:.1e}): QSA then works on its extended last \
         segment (docs/physics.md §10.4), softer than the law but stable. EXP's compression is not bound to its \
         energy (ψ carries the potential): at stiff contacts sampled coarsely the bodies pass deep into each other \
         before the force builds up (up to {:.1e} y_ref on the mass–barrier and {:.1e} on the slide). EXP stays \
         finite and keeps its energy, but its trajectory is then meaningless; IMP and QSA do not do this.\n\
         - **Work.** {}; IMP's iteration count is data dependent (the largest is listed per scene below, against \
         a cap of 100; {} runs hit the cap).\n",
        max_ratio(stability::Kind::MassBarrier, Method::Qsa),
        max_ratio(stability::Kind::HammerString, Method::Qsa),
        ratio_text(max_ratio(stability::Kind::HammerRestrike, Method::Qsa)),
        ratio_text(of(stability::Kind::HammerRestrike, Method::Qsa, |t| &t.compression_bound)),
        max_ratio(stability::Kind::SlideString, Method::Qsa),
        max_ratio(stability::Kind::MassBarrier, Method::Exp),
        max_ratio(stability::Kind::SlideString, Method::Exp),
        match summary.tallies.iter().map(|t| t.over_bound.len()).sum::<usize>() {
            0 => "QSA never exceeded its sign-test bound".to_owned(),
            n => format!("QSA exceeded its sign-test bound in {n} runs (see Failures)"),
        },
        summary.tallies.iter().map(|t| t.newton_cap).sum::<usize>(),
    );
    let _ = writeln!(w, "## Engine fixes found by this report\n");
    let _ = writeln!(
        w,
        "- **EXP returned NaN** on the report's slide excerpt (a slide rattling on a plucked string). After a step \
         that drained ψ with g = g_max, rounding left ψ ≈ 1e-18 √J; the next step was out of contact with the \
         bodies approaching (z < 0), so g = g_max again, and the form 4ψ/(z + √(z² + 4qψ²)) divided by \
         z + |z| = 0: g = ∞ and s = ∞/∞. Fixed in `dsp/src/contact/explicit.rs`: g_max uses the cancellation-free \
         form for each sign of z, and a step with g = g_max sets ψ to exactly 0 and takes s = −2ψ/g_max in a form \
         that never forms g_max. Regression tests: `tests/tests/stability_cases.rs`.\n"
    );
    let _ = writeln!(w, "## Worst cases\n");
    let _ = writeln!(w, "Each line: value — command that reruns the set and prints it as JSON — parameters.\n");
    for tally in &summary.tallies {
        let _ = writeln!(w, "### {} / {}\n", tally.kind.name(), tally.method.name());
        let _ = writeln!(
            w,
            "{} random sets and {} corners; {} runs whose balance closes, {} lossy runs; {} IMP runs at the Newton cap.\n",
            tally.random, tally.corners, tally.conservative, tally.lossy, tally.newton_cap
        );
        worst_list(w, tally, "Largest energy drift (sets whose balance closes)", &tally.drift, |v| format!("{v:.2e}"));
        worst_list(w, tally, "Largest energy increase (lossy sets)", &tally.increase, |v| format!("{v:.2e}"));
        worst_list(w, tally, "Largest excess over the supplied work", &tally.excess, |v| format!("{v:.2e}"));
        worst_list(w, tally, "Largest compression / y_ref", &tally.compression, |v| {
            if v < 100.0 { format!("{v:.4}") } else { format!("{v:.2e}") }
        });
        let counted = if tally.method == Method::Exp { ", reported, not counted" } else { "" };
        worst_list(
            w,
            tally,
            &format!("Largest compression / its energy bound y_max{counted}"),
            &tally.compression_bound,
            |v| if v < 100.0 { format!("{v:.4}") } else { format!("{v:.2e}") },
        );
        worst_list(w, tally, "Largest exciter speed / its energy bound v_max", &tally.velocity_bound, |v| {
            format!("{v:.4}")
        });
        let bound = if tally.method == Method::Qsa { " (QSA bound 2⌈log2(N+1)⌉ + 1)" } else { "" };
        worst_list(w, tally, &format!("Most work in one step{bound}"), &tally.work, |v| format!("{v:.0}"));
    }
    s
}
