//! What the report concludes from the error rows: convergence orders, the cheapest configuration
//! that reaches an error target, and the QSA-against-EXP comparison.
//!
//! - **Orders** ([`orders`]): least-squares lines ([`super::fit`]) through QSA's force error
//!   against IMP versus `log10 N`, for N ≥ [`ORDER_MIN_SEGMENTS`] at each oversampling (below
//!   that the error is pre-asymptotic: the fit's first segment decides it), and through the force
//!   and output errors against the converged reference versus `log10 k`, k = 1…8, for IMP, EXP and
//!   QSA at N = 100 (whose spline error is far below the time-step error wherever the dynamics are
//!   regular, so it shows the scheme's time-step order). The order is `p = −slope`: the error falls
//!   as `N^−p` or `Δt^p`.
//! - **Cheapest within a target** ([`cheapest`]): the configuration with the lowest median RTF
//!   whose error against the reference (force or output signal, [`Signal`]) is at most the
//!   target, over all methods or one.
//! - **Pareto front** ([`super::pareto::front`]) over all methods, for the budget table.

use qsa_dsp::contact::Method;

use super::error::{Config, ErrorRow, OVERSAMPLING, REFERENCE_OVERSAMPLING, SWEPT_SEGMENTS};
use super::fit::{LineFit, fit_against_reference, fit_line};

/// Smallest N in the fits of the error against N.
pub const ORDER_MIN_SEGMENTS: usize = 4;

/// Error targets (log10) of the QSA-against-EXP comparison.
pub const TARGETS: [f64; 5] = [-1.0, -1.5, -2.0, -2.5, -3.0];

/// Two run times within this ratio of each other are always called equal, however small the
/// rows' own spreads (see [`faster`]).
pub const NOISE_RATIO: f64 = 1.2;

/// The smallest error difference the report reads as real (log10; 0.05 is 12 % of the error
/// itself): two errors closer than this count as equal, and a target missed by less counts as
/// neither reached nor missed. Where the reference's own error is close to a row's, the
/// uncertainty is larger ([`uncertainty`]).
pub const ERROR_TOLERANCE: f64 = 0.05;

/// Errors above this (log10; −1 = 10 %) are too large for two solutions' agreement to say
/// anything about their contact solvers: when both are this far off, each is dominated by the
/// time-step error, and "as accurate" is a coincidence of two wrong answers.
pub const USEFUL_ERROR: f64 = -1.0;

/// Which signal's error against the reference a selection uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Signal {
    /// The contact force (`error_vs_reference`).
    Force,
    /// The scene's output (`output_error_vs_reference`).
    Output,
}

impl Signal {
    /// The row's error against the reference for this signal.
    pub fn of(self, row: &ErrorRow) -> f64 {
        match self {
            Signal::Force => row.error_vs_reference,
            Signal::Output => row.output_error_vs_reference,
        }
    }

    /// This signal's error of the 16× reference against 32× from a `(force, output)` pair.
    pub fn check(self, check: (f64, f64)) -> f64 {
        match self {
            Signal::Force => check.0,
            Signal::Output => check.1,
        }
    }

    /// `force` or `output`.
    pub fn name(self) -> &'static str {
        match self {
            Signal::Force => "force",
            Signal::Output => "output",
        }
    }
}

/// One fitted order.
#[derive(Debug, Clone, PartialEq)]
pub struct Order {
    /// Case name.
    pub case: String,
    /// What was fitted against what.
    pub quantity: &'static str,
    /// Method and fixed setting, e.g. `qsa 2x` or `imp`.
    pub method: String,
    /// The fit range, in words.
    pub range: String,
    /// The line.
    pub fit: LineFit,
}

impl Order {
    /// `p = −slope`.
    pub fn order(&self) -> f64 {
        -self.fit.slope
    }
}

fn find<'a>(rows: &'a [ErrorRow], case: &str, method: Method, segments: usize, k: usize) -> Option<&'a ErrorRow> {
    rows.iter().find(|r| {
        r.case == case && r.config.method == method && r.config.segments == segments && r.config.oversampling == k
    })
}

/// Every fitted order, case by case.
pub fn orders(rows: &[ErrorRow], cases: &[&str]) -> Vec<Order> {
    let mut out = Vec::new();
    let fitted_segments: Vec<usize> = SWEPT_SEGMENTS.iter().copied().filter(|&n| n >= ORDER_MIN_SEGMENTS).collect();
    let (n_lo, n_hi) = (fitted_segments[0], fitted_segments[fitted_segments.len() - 1]);
    let (k_lo, k_hi) = (OVERSAMPLING[0], OVERSAMPLING[OVERSAMPLING.len() - 1]);
    for &case in cases {
        for &k in &OVERSAMPLING {
            let points: Vec<(f64, f64)> = fitted_segments
                .iter()
                .filter_map(|&n| find(rows, case, Method::Qsa, n, k).map(|r| ((n as f64).log10(), r.error_vs_imp)))
                .collect();
            if let Some(fit) = fit_line(&points) {
                out.push(Order {
                    case: case.to_owned(),
                    quantity: "force error vs IMP, against N",
                    method: format!("qsa {k}x"),
                    range: format!("N = {n_lo}–{n_hi}"),
                    fit,
                });
            }
        }
        let against_k = [
            (Signal::Force, "force error vs reference, against k"),
            (Signal::Output, "output error vs reference, against k"),
        ];
        for (signal, quantity) in against_k {
            for (method, segments, label) in
                [(Method::Imp, 0, "imp"), (Method::Exp, 0, "exp"), (Method::Qsa, 100, "qsa N=100")]
            {
                let points: Vec<(f64, f64)> = OVERSAMPLING
                    .iter()
                    .filter_map(|&k| find(rows, case, method, segments, k).map(|r| (k as f64, signal.of(r))))
                    .collect();
                // IMP is the reference's own scheme, so its error against it follows the model;
                // the others' differ from it by their own error and IMP's at 16×, and get the
                // straight line, as does IMP where the model does not apply.
                let model = (method == Method::Imp)
                    .then(|| fit_against_reference(&points, REFERENCE_OVERSAMPLING as f64))
                    .flatten();
                let logs: Vec<(f64, f64)> = points.iter().map(|&(k, y)| (k.log10(), y)).collect();
                let fitted = model.map(|f| (f, "")).or_else(|| fit_line(&logs).map(|f| (f, "; line")));
                if let Some((fit, how)) = fitted {
                    out.push(Order {
                        case: case.to_owned(),
                        quantity,
                        method: label.to_owned(),
                        range: format!("k = {k_lo}–{k_hi}{how}"),
                        fit,
                    });
                }
            }
        }
    }
    out
}

/// The order a straight line through `log10 k` reads, over the report's rates, from errors of
/// the exact order `order` measured against IMP at the reference's rate.
pub fn straight_line_order(order: f64) -> f64 {
    let r = REFERENCE_OVERSAMPLING as f64;
    let points: Vec<(f64, f64)> = (OVERSAMPLING.iter())
        .map(|&k| ((k as f64).log10(), ((k as f64).powf(-order) - r.powf(-order)).log10()))
        .collect();
    fit_line(&points).map_or(f64::NAN, |f| -f.slope)
}

/// The timed row of `case` with the lowest RTF among those whose `signal` error against the
/// reference is at most `target` and that `pick` accepts (no regard to noise; see [`reach`]).
pub fn cheapest<'a>(
    rows: &'a [ErrorRow],
    case: &str,
    signal: Signal,
    target: f64,
    pick: impl Fn(&Config) -> bool,
) -> Option<&'a ErrorRow> {
    rows.iter()
        .filter(|r| r.case == case && pick(&r.config) && signal.of(r) <= target && r.rtf.is_some())
        .min_by(|a, b| a.rtf.unwrap_or(f64::INFINITY).total_cmp(&b.rtf.unwrap_or(f64::INFINITY)))
}

/// A row's timing noise: how far its median run is above its fastest, relative to the median,
/// `(rtf − rtf_min) / rtf`. The runs of a case go round-robin over its configurations
/// ([`super::error::measure_rtf`]), so this spread is what the machine's interruptions did to
/// this configuration during the sweep. 0 for an untimed row.
pub fn noise(row: &ErrorRow) -> f64 {
    match (row.rtf, row.rtf_min) {
        (Some(t), Some(min)) if t > 0.0 => (t - min) / t,
        _ => 0.0,
    }
}

/// Whether `a` is faster than `b` beyond the timing noise: `b`'s median run time exceeds `a`'s by
/// more than the two rows' noises together ([`noise`]) and by more than [`NOISE_RATIO`].
pub fn faster(a: &ErrorRow, b: &ErrorRow) -> bool {
    match (a.rtf, b.rtf) {
        (Some(ta), Some(tb)) => tb / ta > NOISE_RATIO.max(1.0 + noise(a) + noise(b)),
        _ => false,
    }
}

/// How uncertain an error `e` measured against a reference whose own error is `check` is (log10):
/// the true error lies between `log10(10^e − 10^check)` and `log10(10^e + 10^check)`, so by
/// `log10(1 + 10^(check − e))` at most upward; never less than [`ERROR_TOLERANCE`].
pub fn uncertainty(e: f64, check: f64) -> f64 {
    ERROR_TOLERANCE.max((1.0 + 10f64.powf(check - e)).log10())
}

/// Whether an error `e` is resolved by a reference whose own error is `check`: an error below the
/// reference's own says only that the row agrees with the reference better than the reference
/// agrees with a finer render.
pub fn resolved(e: f64, check: f64) -> bool {
    e >= check
}

/// Whether a `target` can be told apart by a reference whose own error is `check`.
pub fn target_resolved(target: f64, check: f64) -> bool {
    target >= check + ERROR_TOLERANCE
}

/// The plugin's default: its method and segment count, at the host's rate.
pub fn plugin_default() -> Config {
    let settings = qsa_dsp::instrument::Settings::default();
    Config { method: settings.method, segments: settings.segments, oversampling: 1 }
}

/// The cheapest configuration within a target, with those that tie with it.
#[derive(Debug, Clone)]
pub struct Pick<'a> {
    /// The configuration to recommend: the plugin's default if it ties with the cheapest,
    /// otherwise the cheapest.
    pub row: &'a ErrorRow,
    /// Other configurations within the target that are not slower than the cheapest beyond the
    /// noise ([`faster`]), by increasing run time.
    pub ties: Vec<&'a ErrorRow>,
}

/// What can be said about the cheapest way to a target.
#[derive(Debug, Clone)]
pub enum Reach<'a> {
    /// The target is below the reference's resolution ([`target_resolved`]).
    Unresolved,
    /// No configuration reaches it.
    Nothing,
    /// The pick.
    Found(Pick<'a>),
}

/// The cheapest row of `case` reaching `target` on `signal` (over the rows `pick` accepts), the
/// rows that tie with it within the timing noise, and whether the reference resolves the target.
pub fn reach<'a>(
    rows: &'a [ErrorRow],
    case: &str,
    signal: Signal,
    target: f64,
    check: f64,
    pick: impl Fn(&Config) -> bool,
) -> Reach<'a> {
    if !target_resolved(target, check) {
        return Reach::Unresolved;
    }
    let mut within: Vec<&ErrorRow> = rows
        .iter()
        .filter(|r| r.case == case && pick(&r.config) && signal.of(r) <= target && r.rtf.is_some())
        .collect();
    within.sort_by(|a, b| a.rtf.unwrap_or(f64::INFINITY).total_cmp(&b.rtf.unwrap_or(f64::INFINITY)));
    let Some(&cheapest) = within.first() else {
        return Reach::Nothing;
    };
    let tied: Vec<&ErrorRow> = within.iter().copied().filter(|r| !faster(cheapest, r)).collect();
    let default = plugin_default();
    let row = tied.iter().copied().find(|r| r.config == default).unwrap_or(cheapest);
    let ties = tied.into_iter().filter(|r| !std::ptr::eq(*r, row)).collect();
    Reach::Found(Pick { row, ties })
}

/// The row of `case` with the smallest `signal` error against the reference.
pub fn most_accurate<'a>(rows: &'a [ErrorRow], case: &str, signal: Signal) -> Option<&'a ErrorRow> {
    rows.iter()
        .filter(|r| r.case == case && signal.of(r).is_finite())
        .min_by(|a, b| signal.of(a).total_cmp(&signal.of(b)))
}

/// The Pareto front of `case` over all methods for `signal`, by increasing RTF, with errors below
/// the reference's resolution `check` counted as `check` (no row is credited with an accuracy the
/// reference cannot confirm, so the cheapest of such rows stands for them), each row better by
/// more than [`ERROR_TOLERANCE`] than the cheaper row before it on the front (a difference the
/// report calls equal buys no place at a higher cost). A row whose error is not a number is left
/// out.
pub fn pareto<'a>(rows: &'a [ErrorRow], case: &str, signal: Signal, check: f64) -> Vec<&'a ErrorRow> {
    let points: Vec<(f64, f64, &ErrorRow)> = (rows.iter())
        .filter(|r| r.case == case && !signal.of(r).is_nan())
        .filter_map(|r| r.rtf.map(|t| (t, signal.of(r).max(check), r)))
        .collect();
    super::pareto::front(&points, ERROR_TOLERANCE).into_iter().map(|p| p.2).collect()
}

/// QSA against EXP at one target.
#[derive(Debug, Clone)]
pub struct Duel<'a> {
    /// Error target (log10).
    pub target: f64,
    /// The cheapest QSA configuration within the target.
    pub qsa: Option<&'a ErrorRow>,
    /// The cheapest EXP configuration within the target.
    pub exp: Option<&'a ErrorRow>,
    /// The cheapest QSA configuration within the target widened by its error's uncertainty.
    pub qsa_near: Option<&'a ErrorRow>,
    /// The same for EXP.
    pub exp_near: Option<&'a ErrorRow>,
    /// Whether the reference resolves the target.
    pub resolved: bool,
}

/// The outcome of a [`Duel`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// QSA reaches the target faster than EXP comes near it, beyond the noise.
    Qsa,
    /// EXP reaches the target faster than QSA comes near it, beyond the noise.
    Exp,
    /// Both reach it (or one reaches it and the other misses it by less than the error's
    /// uncertainty) with run times within the noise, or the faster one only nearly reaches it.
    Tie,
    /// Neither reaches it.
    Neither,
    /// The reference does not resolve the target.
    Unresolved,
}

/// The cheapest row of `case` with `signal` error at most `bound(row)`, among `method`'s.
fn cheapest_by<'a>(
    rows: &'a [ErrorRow],
    case: &str,
    signal: Signal,
    method: Method,
    bound: impl Fn(&ErrorRow) -> f64,
) -> Option<&'a ErrorRow> {
    rows.iter()
        .filter(|r| r.case == case && r.config.method == method && r.rtf.is_some() && signal.of(r) <= bound(r))
        .min_by(|a, b| a.rtf.unwrap_or(f64::INFINITY).total_cmp(&b.rtf.unwrap_or(f64::INFINITY)))
}

impl Duel<'_> {
    /// Who wins. A method wins only if its cheapest row within the target is faster, beyond the
    /// noise, than the other method's cheapest row within the target widened by that row's
    /// uncertainty: a target missed by less than the error's own uncertainty does not decide.
    pub fn verdict(&self) -> Verdict {
        if !self.resolved {
            return Verdict::Unresolved;
        }
        let beats = |winner: Option<&ErrorRow>, other_near: Option<&ErrorRow>| match (winner, other_near) {
            (Some(_), None) => true,
            (Some(w), Some(o)) => faster(w, o),
            (None, _) => false,
        };
        if beats(self.qsa, self.exp_near) {
            Verdict::Qsa
        } else if beats(self.exp, self.qsa_near) {
            Verdict::Exp
        } else if self.qsa.is_none() && self.exp.is_none() {
            Verdict::Neither
        } else {
            Verdict::Tie
        }
    }

    /// The verdict in words.
    pub fn words(&self) -> String {
        match self.verdict() {
            Verdict::Unresolved => "unresolved (target below the reference's resolution)".to_owned(),
            Verdict::Qsa if self.exp_near.is_none() => "only QSA reaches it".to_owned(),
            Verdict::Exp if self.qsa_near.is_none() => "only EXP reaches it".to_owned(),
            Verdict::Qsa => "QSA faster".to_owned(),
            Verdict::Exp => "EXP faster".to_owned(),
            Verdict::Neither => "neither reaches it".to_owned(),
            Verdict::Tie => {
                fn missed<'r>(within: Option<&'r ErrorRow>, near: Option<&'r ErrorRow>) -> Option<&'r ErrorRow> {
                    near.filter(|n| within.is_none_or(|w| !std::ptr::eq(*n, w)))
                }
                match (missed(self.qsa, self.qsa_near), missed(self.exp, self.exp_near)) {
                    (Some(n), _) => {
                        format!("tie (QSA's `{}` misses it within the error's uncertainty)", n.config.label())
                    }
                    (_, Some(n)) => {
                        format!("tie (EXP's `{}` misses it within the error's uncertainty)", n.config.label())
                    }
                    _ => "tie (within the timing noise)".to_owned(),
                }
            }
        }
    }
}

/// QSA against EXP on `case` at every target of [`TARGETS`], on `signal`; `check` is the
/// reference's own error on that signal.
pub fn duels<'a>(rows: &'a [ErrorRow], case: &str, signal: Signal, check: f64) -> Vec<Duel<'a>> {
    TARGETS
        .iter()
        .map(|&target| {
            let within = |m| cheapest_by(rows, case, signal, m, |_| target);
            let near = |m| cheapest_by(rows, case, signal, m, |r| target + uncertainty(signal.of(r), check));
            Duel {
                target,
                qsa: within(Method::Qsa),
                exp: within(Method::Exp),
                qsa_near: near(Method::Qsa),
                exp_near: near(Method::Exp),
                resolved: target_resolved(target, check),
            }
        })
        .collect()
}

/// QSA matched against IMP at the lowest rate where the comparison means something.
#[derive(Debug, Clone, Copy)]
pub enum Match<'a> {
    /// At `imp`'s rate, `qsa` has the fewest segments whose error is within [`ERROR_TOLERANCE`]
    /// of IMP's.
    Found {
        /// The QSA row.
        qsa: &'a ErrorRow,
        /// IMP at the same rate.
        imp: &'a ErrorRow,
    },
    /// At no swept rate is IMP's error both resolved by the reference and below [`USEFUL_ERROR`].
    Unresolved {
        /// IMP's most accurate row.
        best_imp: Option<&'a ErrorRow>,
    },
}

/// Of `rows`, the QSA rows of one case at one rate, the one with the fewest segments from which
/// every row with more segments also has an `error` within [`ERROR_TOLERANCE`] of `target`: a
/// match that holds as N grows, not one N whose spline error happens to cancel the time step's
/// while the next N's does not.
pub fn fewest_segments_matching<'a>(
    rows: impl Iterator<Item = &'a ErrorRow>,
    error: impl Fn(&ErrorRow) -> f64,
    target: f64,
) -> Option<&'a ErrorRow> {
    let mut rows: Vec<&ErrorRow> = rows.collect();
    rows.sort_by_key(|r| r.config.segments);
    let from = rows.iter().rposition(|r| !(error(r) <= target + ERROR_TOLERANCE)).map_or(0, |i| i + 1);
    rows.get(from).copied()
}

/// The lowest oversampling at which IMP's `signal` error is resolved (`check`) and below
/// [`USEFUL_ERROR`], and there the QSA row with the fewest segments from which every larger N
/// is within [`ERROR_TOLERANCE`] of IMP's error ([`fewest_segments_matching`]).
pub fn as_accurate_as_imp<'a>(rows: &'a [ErrorRow], case: &str, signal: Signal, check: f64) -> Match<'a> {
    let imp_at =
        |k: usize| rows.iter().find(|r| r.case == case && r.config.method == Method::Imp && r.config.oversampling == k);
    for &k in &OVERSAMPLING {
        let Some(imp) = imp_at(k) else { continue };
        let e = signal.of(imp);
        if e > USEFUL_ERROR || !resolved(e, check) {
            continue;
        }
        let at_k =
            rows.iter().filter(|r| r.case == case && r.config.method == Method::Qsa && r.config.oversampling == k);
        if let Some(qsa) = fewest_segments_matching(at_k, |r| signal.of(r), e) {
            return Match::Found { qsa, imp };
        }
    }
    let best_imp = OVERSAMPLING.iter().filter_map(|&k| imp_at(k)).min_by(|a, b| signal.of(a).total_cmp(&signal.of(b)));
    Match::Unresolved { best_imp }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(method: Method, segments: usize, k: usize, error: f64, rtf: f64, rtf_min: f64) -> ErrorRow {
        ErrorRow {
            case: "c".into(),
            config: Config { method, segments, oversampling: k },
            sample_rate: 44_100 * k as u32,
            samples: 10,
            error_vs_imp: error,
            error_vs_reference: error,
            output_error_vs_imp: error,
            output_error_vs_reference: error,
            sensitivity: Some(0.0),
            rtf: Some(rtf),
            rtf_min: Some(rtf_min),
            contact_steps: 1,
            mean_work: 1.0,
            max_work: 1,
        }
    }

    #[test]
    fn run_times_closer_than_the_rows_noise_are_a_tie() {
        // Noise 0.2 each: 1.35 times faster is inside 1 + 0.2 + 0.2, 1.45 times is beyond it.
        let a = row(Method::Qsa, 6, 1, -1.5, 1.0, 0.8);
        assert!(!faster(&a, &row(Method::Exp, 0, 1, -1.5, 1.35, 1.08)));
        assert!(faster(&a, &row(Method::Exp, 0, 1, -1.5, 1.45, 1.16)));
        // Without noise, the floor NOISE_RATIO still applies.
        let quiet = row(Method::Qsa, 6, 1, -1.5, 1.0, 1.0);
        assert!(!faster(&quiet, &row(Method::Exp, 0, 1, -1.5, 1.19, 1.19)));
        assert!(faster(&quiet, &row(Method::Exp, 0, 1, -1.5, 1.21, 1.21)));
    }

    #[test]
    fn a_target_missed_by_less_than_the_uncertainty_does_not_decide() {
        // QSA reaches −1.5 at run time 1; EXP misses it by 0.02 at run time 0.5 and reaches it at 3.
        let rows = vec![
            row(Method::Qsa, 6, 1, -1.52, 1.0, 1.0),
            row(Method::Exp, 0, 1, -1.48, 0.5, 0.5),
            row(Method::Exp, 0, 2, -2.0, 3.0, 3.0),
        ];
        let duel = &duels(&rows, "c", Signal::Force, -4.0)[1];
        assert_eq!(duel.target, -1.5);
        assert_eq!(duel.verdict(), Verdict::Tie, "{}", duel.words());
        // Missed by 0.1, twice the tolerance: QSA is the faster way to the target.
        let rows = vec![rows[0].clone(), row(Method::Exp, 0, 1, -1.4, 0.5, 0.5), rows[2].clone()];
        assert_eq!(duels(&rows, "c", Signal::Force, -4.0)[1].verdict(), Verdict::Qsa);
    }

    #[test]
    fn a_target_below_the_references_own_error_is_unresolved() {
        let rows = vec![row(Method::Exp, 0, 8, -1.76, 1.0, 1.0)];
        // The reference is only −1.40 from a finer one: −1.5 and −2 cannot be judged, −1 can.
        let duels = duels(&rows, "c", Signal::Force, -1.40);
        assert_eq!(duels[0].verdict(), Verdict::Exp);
        assert_eq!(duels[1].verdict(), Verdict::Unresolved);
        assert_eq!(duels[2].verdict(), Verdict::Unresolved);
        assert!(!resolved(-1.76, -1.40));
        // The uncertainty of an error equal to the reference's own is log10(2).
        assert!((uncertainty(-1.4, -1.4) - 2f64.log10()).abs() < 1e-12);
    }

    #[test]
    fn both_solvers_far_off_is_no_match() {
        // At 1× both are 34 % off (−0.47): no verdict there; at 2× IMP is within 10 %.
        let rows = vec![
            row(Method::Imp, 0, 1, -0.47, 3.0, 3.0),
            row(Method::Qsa, 2, 1, -0.47, 1.0, 1.0),
            row(Method::Imp, 0, 2, -1.3, 6.0, 6.0),
            row(Method::Qsa, 2, 2, -1.1, 2.0, 2.0),
            row(Method::Qsa, 8, 2, -1.28, 2.0, 2.0),
        ];
        match as_accurate_as_imp(&rows, "c", Signal::Force, -4.0) {
            Match::Found { qsa, imp } => assert_eq!((qsa.config.segments, imp.config.oversampling), (8, 2)),
            other => panic!("{other:?}"),
        }
        assert!(matches!(as_accurate_as_imp(&rows[..2], "c", Signal::Force, -4.0), Match::Unresolved { .. }));
    }

    /// A QSA row that matches IMP while the next N does not (its spline error cancelling the
    /// time step's) is no match: the fewest segments is the one from which every larger N
    /// matches.
    #[test]
    fn a_match_must_hold_for_every_larger_n() {
        let rows = vec![
            row(Method::Imp, 0, 1, -1.33, 3.0, 3.0),
            row(Method::Qsa, 2, 1, -1.43, 1.0, 1.0),
            row(Method::Qsa, 3, 1, -1.23, 1.0, 1.0),
            row(Method::Qsa, 4, 1, -1.30, 1.0, 1.0),
            row(Method::Qsa, 6, 1, -1.32, 1.0, 1.0),
        ];
        match as_accurate_as_imp(&rows, "c", Signal::Force, -4.0) {
            Match::Found { qsa, .. } => assert_eq!(qsa.config.segments, 4),
            other => panic!("{other:?}"),
        }
        let none_past = fewest_segments_matching(rows[1..3].iter(), |r| Signal::Force.of(r), -1.33);
        assert!(none_past.is_none(), "the largest N does not match: {none_past:?}");
    }

    #[test]
    fn the_plugin_default_wins_a_tie() {
        let d = plugin_default();
        let rows = vec![
            row(Method::Qsa, 5, 1, -1.2, 0.99, 0.9),
            row(d.method, d.segments, 1, -1.2, 1.0, 0.9),
            row(Method::Exp, 0, 1, -1.2, 3.0, 3.0),
        ];
        match reach(&rows, "c", Signal::Output, -1.0, -4.0, |_| true) {
            Reach::Found(pick) => {
                assert_eq!(pick.row.config, d);
                assert_eq!(pick.ties.len(), 1, "N = 5 ties; EXP, three times slower, does not");
            }
            other => panic!("{other:?}"),
        }
    }
}
