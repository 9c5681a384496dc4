//! Error against run time: every method, segment count and oversampling on every case.
//!
//! # Error measures
//!
//! For two signals `a` (the method's) and `b` (a reference), both sampled on the same instants,
//!
//! ```text
//! e(a, b) = log10( ‖a − b‖₂ / ‖b‖₂ ) = ½·log10( Σ_n (a_n − b_n)² / Σ_n b_n² )
//! ```
//!
//! (docs/physics.md §9.4's dF; −2 means the difference is 1 % of the reference's norm). Each row has
//! - `error_vs_imp`: `e(F, F_IMP)` of the contact force against IMP at the same rate, over every
//!   sample: the seed's measure (its Fig. 5, right). It isolates the contact solver: IMP solves the
//!   same discrete scheme with the exact potential. It is `-inf` for IMP itself.
//! - `error_vs_reference`: `e(F, F_ref)` against the converged reference, IMP at 16× the base
//!   rate, compared on the method's own time grid: sample `n` of a render at `k·fs` is compared
//!   with sample `n·16/k` of the reference (the same instant `n/(k·fs)`). This adds the time
//!   discretisation error to the solver's.
//! - `output_error_vs_imp`, `output_error_vs_reference`: the same two measures on the scene's
//!   output signal (the contact force for the mass–barrier, the bridge force for the hammer, the
//!   string displacement at 0.9 L for the slide).
//!
//! # Sensitivity
//!
//! `sensitivity` is the largest change of the four errors when the exciter's initial speed (or the
//! slide's mass) is scaled by `1 ± 1e-14` ([`SENSITIVITY_PERTURBATION`]): a few rounding errors.
//! It is 0.000 wherever the dynamics are regular; a contact that rattled chaotically would amplify
//! such a perturbation, and its errors would then only be known to about this much (the report
//! names such cases; at the printed precision none of today's is). `--quick` compares, digit for
//! digit as printed, only rows whose sensitivity prints as 0.0000 (see `QUICK_MAX_SENSITIVITY`).
//!
//! # Run time
//!
//! `rtf` is the real-time factor, wall seconds per simulated second, of the real-time path
//! (output only, calls of 64 samples, no energy bookkeeping; see [`super::sim`]): the median of
//! [`TIMING_RUNS`] runs after one discarded warm-up run; `rtf_min` is the fastest run. The runs of a
//! case go round-robin over its configurations, so a slow spell of the machine hits all alike. Renders
//! shorter than [`MIN_TIMED_WALL`] are repeated within a run until the run lasts that long, and the
//! run's time is divided by the repetitions. The solver's work per step comes from the frame
//! render: `mean_work` is the mean over the steps with a non-zero force (QSA sign tests, IMP
//! Newton iterations, 0 for EXP) and `max_work` the largest over all steps.

use std::collections::BTreeSet;
use std::fmt::Write as _;

use qsa_dsp::contact::{Method, SolverSettings};
use qsa_dsp::scene::Frame;

use super::cases::Case;

/// QSA segment counts N of the sweep.
pub const SWEPT_SEGMENTS: [usize; 13] = [1, 2, 3, 4, 5, 6, 8, 10, 13, 20, 30, 50, 100];

/// Oversampling factors k of the sweep.
pub const OVERSAMPLING: [usize; 4] = [1, 2, 4, 8];

/// Oversampling of the converged reference (IMP).
pub const REFERENCE_OVERSAMPLING: usize = 16;

/// The seed paper's Fig. 5 (right) values, quoted in docs/physics.md §9.4: `(N, error_vs_imp)` of
/// QSA on the Fig. 5 hammer at the base rate, to compare with this sweep's.
pub const SEED_FIG5: [(usize, f64); 3] = [(3, -1.18), (6, -1.62), (50, -4.01)];

/// Timed runs per configuration; the median is reported.
pub const TIMING_RUNS: usize = 9;

/// Shortest timed run (s); shorter renders are repeated within a run.
pub const MIN_TIMED_WALL: f64 = 5e-3;

/// One method with its settings at one oversampling.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Config {
    /// The scheme.
    pub method: Method,
    /// QSA segment count N (0 for IMP and EXP).
    pub segments: usize,
    /// Oversampling factor k.
    pub oversampling: usize,
}

impl Config {
    /// The solver settings (V_ref: the case's default).
    pub fn settings(&self) -> SolverSettings {
        SolverSettings { method: self.method, segments: self.segments.max(1), v_ref: None }
    }

    /// A short label, e.g. `qsa N=6 2x`.
    pub fn label(&self) -> String {
        match self.method {
            Method::Qsa => format!("qsa N={} {}x", self.segments, self.oversampling),
            m => format!("{} {}x", m.name(), self.oversampling),
        }
    }
}

/// Every configuration: QSA at each of `segments`, then EXP and IMP, at each of `oversampling`.
pub fn configs(segments: &[usize], oversampling: &[usize]) -> Vec<Config> {
    let mut out = Vec::new();
    for &k in oversampling {
        out.extend(segments.iter().map(|&n| Config { method: Method::Qsa, segments: n, oversampling: k }));
        out.push(Config { method: Method::Exp, segments: 0, oversampling: k });
        out.push(Config { method: Method::Imp, segments: 0, oversampling: k });
    }
    out
}

/// One row of `error-vs-runtime.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct ErrorRow {
    /// Case name.
    pub case: String,
    /// The configuration.
    pub config: Config,
    /// Sample rate k·fs (Hz).
    pub sample_rate: u32,
    /// Samples rendered.
    pub samples: usize,
    /// `e(F, F_IMP)` at the same rate (log10).
    pub error_vs_imp: f64,
    /// `e(F, F_ref)` against IMP at 16× (log10).
    pub error_vs_reference: f64,
    /// `e(out, out_IMP)` at the same rate (log10).
    pub output_error_vs_imp: f64,
    /// `e(out, out_ref)` against IMP at 16× (log10).
    pub output_error_vs_reference: f64,
    /// Largest change of the four errors under a perturbation of a few rounding errors (log10
    /// units), if measured.
    pub sensitivity: Option<f64>,
    /// Median real-time factor (wall s per simulated s), if timed.
    pub rtf: Option<f64>,
    /// Fastest run's real-time factor, if timed.
    pub rtf_min: Option<f64>,
    /// Steps with a non-zero contact force.
    pub contact_steps: usize,
    /// Mean solver work per contact step (QSA sign tests, IMP iterations).
    pub mean_work: f64,
    /// Largest solver work in one step.
    pub max_work: u32,
}

/// `log10(‖a − b‖₂/‖b‖₂)` over the pairs `(a_n, b_n)`, `b` the reference: the normalised L2
/// difference of two signals (docs/physics.md §9.4's dF), used by the report and the tests.
///
/// Edge cases: `-inf` if every pair agrees exactly (with a non-zero reference); NaN if the
/// reference is zero, where no relative error exists (every comparison with NaN is false, so a
/// bound on the result fails); only the pairs the iterator yields count (zipping signals of
/// different lengths compares the shorter span).
pub fn log10_rel_l2(pairs: impl Iterator<Item = (f64, f64)>) -> f64 {
    let (mut diff, mut norm) = (0.0, 0.0);
    for (a, b) in pairs {
        diff += (a - b) * (a - b);
        norm += b * b;
    }
    if norm == 0.0 { f64::NAN } else { 0.5 * (diff / norm).log10() }
}

/// `e` of one field of `frames` against `reference`, sampled every `stride` reference samples.
fn error_on_grid(frames: &[Frame], reference: &[Frame], stride: usize, field: fn(&Frame) -> f64) -> f64 {
    log10_rel_l2(frames.iter().enumerate().map(|(n, f)| (field(f), field(&reference[n * stride]))))
}

/// Median and fastest real-time factor of each of `configs` on `case` over `runs` timed runs.
///
/// The runs go round-robin over the configurations (one run of each, then the next round), so a
/// slow spell of the machine hits every configuration alike instead of a few, and comparisons
/// between methods stay fair. Each configuration first gets one discarded warm-up run, which also
/// fixes how many repetitions make one of its runs last [`MIN_TIMED_WALL`].
pub fn measure_rtf(case: &Case, configs: &[Config], runs: usize, tick: &dyn Fn()) -> Vec<(f64, f64)> {
    let scene = &case.scene;
    let repetitions: Vec<usize> = configs
        .iter()
        .map(|c| {
            let warm_up = scene.timed(c.settings(), c.oversampling);
            (MIN_TIMED_WALL / warm_up.max(1e-9)).ceil().clamp(1.0, 10_000.0) as usize
        })
        .collect();
    let mut rtfs = vec![Vec::with_capacity(runs); configs.len()];
    for _ in 0..runs.max(1) {
        for ((c, &reps), out) in configs.iter().zip(&repetitions).zip(&mut rtfs) {
            let wall: f64 = (0..reps).map(|_| scene.timed(c.settings(), c.oversampling)).sum();
            out.push(wall / (scene.seconds() * reps as f64));
        }
        tick();
    }
    rtfs.into_iter()
        .map(|mut v| {
            v.sort_by(f64::total_cmp);
            (v[v.len() / 2], v[0])
        })
        .collect()
}

/// Run `configs` on `case`, timing each with `timing_runs` runs (0: no timing). `tick` is called
/// once per configuration, and once per timing round.
pub fn sweep_case(case: &Case, configs: &[Config], timing_runs: usize, tick: &dyn Fn()) -> Vec<ErrorRow> {
    let scene = &case.scene;
    let imp = |k| scene.frames(SolverSettings { method: Method::Imp, segments: 1, v_ref: None }, k);
    let reference = imp(REFERENCE_OVERSAMPLING);
    let rates: BTreeSet<usize> = configs.iter().map(|c| c.oversampling).collect();
    let mut rows = Vec::with_capacity(configs.len());
    for k in rates {
        let same_rate = imp(k);
        // Frame n of a run at k× lies on frame n·K/k of the reference at K×: K must be a multiple.
        assert_eq!(REFERENCE_OVERSAMPLING % k, 0, "{k}× does not divide the reference's rate");
        let stride = REFERENCE_OVERSAMPLING / k;
        for config in configs.iter().filter(|c| c.oversampling == k) {
            let owned;
            let frames = if config.method == Method::Imp {
                &same_rate
            } else {
                owned = scene.frames(config.settings(), k);
                &owned
            };
            let force = |f: &Frame| f.force;
            let output = |f: &Frame| f.output;
            let contact: Vec<&Frame> = frames.iter().filter(|f| f.force != 0.0).collect();
            rows.push(ErrorRow {
                case: case.name.to_owned(),
                config: *config,
                sample_rate: scene.sample_rate * k as u32,
                samples: frames.len(),
                error_vs_imp: error_on_grid(frames, &same_rate, 1, force),
                error_vs_reference: error_on_grid(frames, &reference, stride, force),
                output_error_vs_imp: error_on_grid(frames, &same_rate, 1, output),
                output_error_vs_reference: error_on_grid(frames, &reference, stride, output),
                sensitivity: None,
                rtf: None,
                rtf_min: None,
                contact_steps: contact.len(),
                mean_work: if contact.is_empty() {
                    0.0
                } else {
                    contact.iter().map(|f| f64::from(f.work)).sum::<f64>() / contact.len() as f64
                },
                max_work: frames.iter().map(|f| f.work).max().unwrap_or(0),
            });
            tick();
        }
    }
    if timing_runs > 0 {
        let ordered: Vec<Config> = rows.iter().map(|r| r.config).collect();
        for (row, (median, min)) in rows.iter_mut().zip(measure_rtf(case, &ordered, timing_runs, tick)) {
            row.rtf = Some(median);
            row.rtf_min = Some(min);
        }
    }
    rows
}

/// Relative perturbation of the sensitivity measure.
pub const SENSITIVITY_PERTURBATION: f64 = 1e-14;

impl ErrorRow {
    /// The four errors.
    pub fn errors(&self) -> [f64; 4] {
        [self.error_vs_imp, self.error_vs_reference, self.output_error_vs_imp, self.output_error_vs_reference]
    }
}

/// Fill in the `sensitivity` of `rows` (the rows of `case` for `configs`, in order): rerun them
/// with the exciter perturbed by `±`[`SENSITIVITY_PERTURBATION`] and keep the largest change.
pub fn measure_sensitivity(case: &Case, configs: &[Config], rows: &mut [ErrorRow], tick: &dyn Fn()) {
    for sign in [1.0, -1.0] {
        let perturbed = Case { scene: case.scene.perturbed(sign * SENSITIVITY_PERTURBATION), ..case.clone() };
        let again = sweep_case(&perturbed, configs, 0, tick);
        for (row, other) in rows.iter_mut().zip(&again) {
            let change = row
                .errors()
                .iter()
                .zip(other.errors())
                // An error that turns NaN (or back) under the perturbation is not known at all.
                .map(|(a, b)| if a == &b || (a.is_nan() && b.is_nan()) { 0.0 } else { (a - b).abs() })
                .fold(0.0, |most: f64, change| if change.is_nan() { f64::INFINITY } else { most.max(change) });
            row.sensitivity = Some(row.sensitivity.unwrap_or(0.0).max(change));
        }
    }
}

/// Oversampling of the check on the reference.
pub const CHECK_OVERSAMPLING: usize = 32;

/// How converged the reference is: the force and output errors of IMP at 16× against IMP at 32×,
/// on the 16× grid.
pub fn reference_check(case: &Case) -> (f64, f64) {
    let imp = SolverSettings { method: Method::Imp, segments: 1, v_ref: None };
    let reference = case.scene.frames(imp, REFERENCE_OVERSAMPLING);
    let finer = case.scene.frames(imp, CHECK_OVERSAMPLING);
    let stride = CHECK_OVERSAMPLING / REFERENCE_OVERSAMPLING;
    (error_on_grid(&reference, &finer, stride, |f| f.force), error_on_grid(&reference, &finer, stride, |f| f.output))
}

/// The CSV header of `error-vs-runtime.csv`.
pub const CSV_HEADER: &str = "case,method,segments,oversampling,sample_rate,samples,error_vs_imp,error_vs_reference,\
output_error_vs_imp,output_error_vs_reference,sensitivity,rtf,rtf_min,contact_steps,mean_work,max_work";

/// `error-vs-runtime.csv`: one line per row; errors to 4 decimals, times to 4 significant digits.
pub fn to_csv(rows: &[ErrorRow]) -> String {
    let mut out = String::from(CSV_HEADER);
    out.push('\n');
    let time = |t: Option<f64>| t.map_or(String::new(), |t| format!("{t:.4e}"));
    for r in rows {
        let c = &r.config;
        writeln!(
            out,
            "{},{},{},{},{},{},{:.4},{:.4},{:.4},{:.4},{},{},{},{},{:.3},{}",
            r.case,
            c.method.name(),
            c.segments,
            c.oversampling,
            r.sample_rate,
            r.samples,
            r.error_vs_imp,
            r.error_vs_reference,
            r.output_error_vs_imp,
            r.output_error_vs_reference,
            r.sensitivity.map_or(String::new(), |v| format!("{v:.4}")),
            time(r.rtf),
            time(r.rtf_min),
            r.contact_steps,
            r.mean_work,
            r.max_work
        )
        .expect("writing to a String");
    }
    out
}

/// The error columns of one stored row, keyed by `(case, method, segments, oversampling)`.
#[derive(Debug, Clone, PartialEq)]
pub struct StoredErrors {
    /// `(case, method, segments, oversampling)`.
    pub key: (String, String, usize, usize),
    /// `error_vs_imp`, `error_vs_reference`, `output_error_vs_imp`, `output_error_vs_reference`.
    pub errors: [f64; 4],
    /// The stored sensitivity (NaN if not measured).
    pub sensitivity: f64,
}

/// The error columns of [`ERROR_COLUMNS`] in a CSV written by [`to_csv`].
pub const ERROR_COLUMNS: [&str; 4] =
    ["error_vs_imp", "error_vs_reference", "output_error_vs_imp", "output_error_vs_reference"];

/// Read the key and error columns of an `error-vs-runtime.csv`.
pub fn parse_csv(text: &str) -> Result<Vec<StoredErrors>, String> {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().ok_or("empty file")?.split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).ok_or(format!("no column {name}"));
    let keys = [column("case")?, column("method")?, column("segments")?, column("oversampling")?];
    let errors = ERROR_COLUMNS.map(column);
    let errors: Vec<usize> = errors.into_iter().collect::<Result<_, _>>()?;
    let sensitivity = column("sensitivity")?;
    let mut out = Vec::new();
    for (i, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let fields: Vec<&str> = line.split(',').collect();
        let field = |c: usize| fields.get(c).copied().ok_or(format!("line {}: too few fields", i + 2));
        let int = |c: usize| field(c)?.parse::<usize>().map_err(|e| format!("line {}: {e}", i + 2));
        let float = |c: usize| field(c)?.parse::<f64>().map_err(|e| format!("line {}: {e}", i + 2));
        out.push(StoredErrors {
            key: (field(keys[0])?.to_owned(), field(keys[1])?.to_owned(), int(keys[2])?, int(keys[3])?),
            errors: [float(errors[0])?, float(errors[1])?, float(errors[2])?, float(errors[3])?],
            sensitivity: field(sensitivity)?.parse::<f64>().unwrap_or(f64::NAN),
        });
    }
    Ok(out)
}

/// Read every column of an `error-vs-runtime.csv` written by [`to_csv`] back into rows (errors
/// to 4 decimals, times to 4 significant digits, as printed). Empty `sensitivity`, `rtf` and
/// `rtf_min` fields read as `None`.
pub fn parse_rows(text: &str) -> Result<Vec<ErrorRow>, String> {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().ok_or("empty file")?.split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).ok_or(format!("no column {name}"));
    let names = [
        "case",
        "method",
        "segments",
        "oversampling",
        "sample_rate",
        "samples",
        "error_vs_imp",
        "error_vs_reference",
        "output_error_vs_imp",
        "output_error_vs_reference",
        "sensitivity",
        "rtf",
        "rtf_min",
        "contact_steps",
        "mean_work",
        "max_work",
    ];
    let at: Vec<usize> = names.iter().map(|n| column(n)).collect::<Result<_, _>>()?;
    let mut out = Vec::new();
    for (i, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let fields: Vec<&str> = line.split(',').collect();
        let err = |m: String| format!("line {}: {m}", i + 2);
        let field = |c: usize| fields.get(at[c]).copied().ok_or_else(|| err("too few fields".into()));
        let float = |c: usize| field(c)?.parse::<f64>().map_err(|e| err(format!("{}: {e}", names[c])));
        let int = |c: usize| field(c)?.parse::<usize>().map_err(|e| err(format!("{}: {e}", names[c])));
        let optional = |c: usize| -> Result<Option<f64>, String> {
            match field(c)? {
                "" => Ok(None),
                v => v.parse::<f64>().map(Some).map_err(|e| err(format!("{}: {e}", names[c]))),
            }
        };
        let method = Method::from_name(field(1)?).ok_or_else(|| err(format!("method {:?}", field(1).unwrap_or(""))))?;
        out.push(ErrorRow {
            case: field(0)?.to_owned(),
            config: Config { method, segments: int(2)?, oversampling: int(3)? },
            sample_rate: field(4)?.parse().map_err(|e| err(format!("sample_rate: {e}")))?,
            samples: int(5)?,
            error_vs_imp: float(6)?,
            error_vs_reference: float(7)?,
            output_error_vs_imp: float(8)?,
            output_error_vs_reference: float(9)?,
            sensitivity: optional(10)?,
            rtf: optional(11)?,
            rtf_min: optional(12)?,
            contact_steps: int(13)?,
            mean_work: float(14)?,
            max_work: field(15)?.parse().map_err(|e| err(format!("max_work: {e}")))?,
        });
    }
    Ok(out)
}

/// Per case, the force and output errors of the 16× reference against 32× ([`reference_check`]).
pub type ReferenceChecks = Vec<(String, (f64, f64))>;

/// The header of `reference-check.csv`.
pub const REFERENCE_CSV_HEADER: &str = "case,force_error,output_error";

/// `reference-check.csv`: per case, the force and output errors of the 16× reference against
/// 32× ([`reference_check`]), to 4 decimals.
pub fn reference_csv(checks: &[(String, (f64, f64))]) -> String {
    let mut out = format!("{REFERENCE_CSV_HEADER}\n");
    for (case, (force, output)) in checks {
        let _ = writeln!(out, "{case},{force:.4},{output:.4}");
    }
    out
}

/// Read what [`reference_csv`] wrote.
pub fn parse_reference_csv(text: &str) -> Result<ReferenceChecks, String> {
    let mut lines = text.lines();
    if lines.next() != Some(REFERENCE_CSV_HEADER) {
        return Err(format!("the first line must be {REFERENCE_CSV_HEADER}"));
    }
    lines
        .filter(|l| !l.is_empty())
        .map(|l| match l.split(',').collect::<Vec<_>>()[..] {
            [case, force, output] => Ok((
                case.to_owned(),
                (force.parse().map_err(|e| format!("{l}: {e}"))?, output.parse().map_err(|e| format!("{l}: {e}"))?),
            )),
            _ => Err(format!("{l}: expected 3 fields")),
        })
        .collect()
}

/// The outcome of [`compare`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Comparison {
    /// Rows compared.
    pub compared: usize,
    /// Rows left out because their stored sensitivity exceeds the given limit.
    pub sensitive: usize,
    /// The mismatches, one message each (empty: all agree).
    pub problems: Vec<String>,
}

/// Compare fresh rows with stored ones as [`to_csv`] prints them: each error to 4 decimals must
/// be the committed text exactly (`-inf` and `NaN` included), with no tolerance, since the errors
/// are deterministic. Rows whose stored sensitivity exceeds `max_sensitivity` are left out.
/// Every fresh row must be stored.
pub fn compare(fresh: &[ErrorRow], stored: &[StoredErrors], max_sensitivity: f64) -> Comparison {
    let mut out = Comparison::default();
    for row in fresh {
        let c = &row.config;
        let key = (row.case.clone(), c.method.name().to_owned(), c.segments, c.oversampling);
        let Some(s) = stored.iter().find(|s| s.key == key) else {
            out.problems.push(format!("{} {}: no such row in the committed CSV", row.case, c.label()));
            continue;
        };
        if !(s.sensitivity <= max_sensitivity) {
            out.sensitive += 1;
            continue;
        }
        out.compared += 1;
        for ((name, a), b) in ERROR_COLUMNS.iter().zip(row.errors()).zip(s.errors) {
            // A stored value is a 4-decimal text parsed to the nearest f64, which prints back to
            // the same text: comparing the two printings compares the fresh text with the file's.
            let (fresh_text, committed_text) = (format!("{a:.4}"), format!("{b:.4}"));
            if fresh_text != committed_text {
                out.problems.push(format!(
                    "{} {}: {name} is {fresh_text} now, {committed_text} committed",
                    row.case,
                    c.label()
                ));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_error_is_log10_of_the_norm_ratio() {
        let e = log10_rel_l2([(1.01, 1.0), (2.02, 2.0)].into_iter());
        assert!((e - (-2.0)).abs() < 1e-12, "{e}");
        assert_eq!(log10_rel_l2([(1.0, 1.0)].into_iter()), f64::NEG_INFINITY);
        assert!(log10_rel_l2([(1.0, 0.0)].into_iter()).is_nan());
    }

    #[test]
    fn csv_round_trips_the_errors() {
        let row = ErrorRow {
            case: "c".into(),
            config: Config { method: Method::Imp, segments: 0, oversampling: 2 },
            sample_rate: 88200,
            samples: 10,
            error_vs_imp: f64::NEG_INFINITY,
            error_vs_reference: -2.345_67,
            output_error_vs_imp: f64::NEG_INFINITY,
            output_error_vs_reference: f64::NAN,
            sensitivity: Some(0.0),
            rtf: Some(1.234_56e-3),
            rtf_min: None,
            contact_steps: 3,
            mean_work: 4.5,
            max_work: 5,
        };
        let back = parse_rows(&to_csv(std::slice::from_ref(&row))).unwrap();
        assert_eq!(to_csv(&back), to_csv(std::slice::from_ref(&row)), "every column reads back as printed");
        assert_eq!((back[0].rtf_min, back[0].max_work), (None, 5));
        let stored = parse_csv(&to_csv(std::slice::from_ref(&row))).unwrap();
        assert_eq!(stored[0].key, ("c".into(), "imp".into(), 0, 2));
        let same = compare(std::slice::from_ref(&row), &stored, 0.0);
        assert_eq!((same.compared, same.problems.len()), (1, 0));
        let mut unprinted = row.clone();
        unprinted.error_vs_reference += 1e-5;
        assert_eq!(compare(&[unprinted], &stored, 0.0).problems.len(), 0, "a change below the printed precision");
        let mut off = row;
        off.error_vs_reference += 1e-4;
        assert_eq!(compare(std::slice::from_ref(&off), &stored, 0.0).problems.len(), 1, "one unit of the last place");
        let mut sensitive = stored;
        sensitive[0].sensitivity = 1e-4;
        let skipped = compare(&[off], &sensitive, 0.0);
        assert_eq!((skipped.compared, skipped.sensitive, skipped.problems.len()), (0, 1, 0));
    }
}
