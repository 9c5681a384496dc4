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

use super::error::{Config, ErrorRow, OVERSAMPLING, SWEPT_SEGMENTS};
use super::fit::{LineFit, fit_line};

/// Smallest N in the fits of the error against N.
pub const ORDER_MIN_SEGMENTS: usize = 4;

/// Error targets (log10) of the QSA-against-EXP comparison.
pub const TARGETS: [f64; 5] = [-1.0, -1.5, -2.0, -2.5, -3.0];

/// Two run times within this ratio of each other are called equal (the machine's noise).
pub const NOISE_RATIO: f64 = 1.2;

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
                    .filter_map(|&k| find(rows, case, method, segments, k).map(|r| ((k as f64).log10(), signal.of(r))))
                    .collect();
                if let Some(fit) = fit_line(&points) {
                    out.push(Order {
                        case: case.to_owned(),
                        quantity,
                        method: label.to_owned(),
                        range: format!("k = {k_lo}–{k_hi}"),
                        fit,
                    });
                }
            }
        }
    }
    out
}

/// The timed row of `case` with the lowest RTF among those whose `signal` error against the
/// reference is at most `target` and that `pick` accepts.
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

/// The row of `case` with the smallest `signal` error against the reference.
pub fn most_accurate<'a>(rows: &'a [ErrorRow], case: &str, signal: Signal) -> Option<&'a ErrorRow> {
    rows.iter()
        .filter(|r| r.case == case && signal.of(r).is_finite())
        .min_by(|a, b| signal.of(a).total_cmp(&signal.of(b)))
}

/// The Pareto front of `case` over all methods for `signal`, by increasing RTF.
pub fn pareto<'a>(rows: &'a [ErrorRow], case: &str, signal: Signal) -> Vec<&'a ErrorRow> {
    let points: Vec<(f64, f64, &ErrorRow)> =
        rows.iter().filter(|r| r.case == case).filter_map(|r| r.rtf.map(|t| (t, signal.of(r), r))).collect();
    super::pareto::front(&points).into_iter().map(|p| p.2).collect()
}

/// QSA against EXP at one target: the cheapest of each, if any reaches it.
#[derive(Debug, Clone, Copy)]
pub struct Duel<'a> {
    /// Error target (log10).
    pub target: f64,
    /// Cheapest QSA configuration within the target.
    pub qsa: Option<&'a ErrorRow>,
    /// Cheapest EXP configuration within the target.
    pub exp: Option<&'a ErrorRow>,
}

/// The outcome of a [`Duel`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// QSA is faster by more than the noise, or only QSA reaches the target.
    Qsa,
    /// EXP is faster by more than the noise, or only EXP reaches the target.
    Exp,
    /// Both reach it within the noise of each other.
    Tie,
    /// Neither reaches it.
    Neither,
}

impl Duel<'_> {
    /// Who wins.
    pub fn verdict(&self) -> Verdict {
        match (self.qsa.and_then(|r| r.rtf), self.exp.and_then(|r| r.rtf)) {
            (Some(q), Some(e)) if q * NOISE_RATIO < e => Verdict::Qsa,
            (Some(q), Some(e)) if e * NOISE_RATIO < q => Verdict::Exp,
            (Some(_), Some(_)) => Verdict::Tie,
            (Some(_), None) => Verdict::Qsa,
            (None, Some(_)) => Verdict::Exp,
            (None, None) => Verdict::Neither,
        }
    }

    /// The verdict in words.
    pub fn words(&self) -> &'static str {
        match (self.verdict(), self.qsa.is_some(), self.exp.is_some()) {
            (Verdict::Qsa, _, false) => "only QSA reaches it",
            (Verdict::Exp, false, _) => "only EXP reaches it",
            (Verdict::Qsa, ..) => "QSA faster",
            (Verdict::Exp, ..) => "EXP faster",
            (Verdict::Tie, ..) => "tie (within noise)",
            (Verdict::Neither, ..) => "neither reaches it",
        }
    }
}

/// QSA against EXP on `case` at every target of [`TARGETS`], on `signal`.
pub fn duels<'a>(rows: &'a [ErrorRow], case: &str, signal: Signal) -> Vec<Duel<'a>> {
    TARGETS
        .iter()
        .map(|&target| Duel {
            target,
            qsa: cheapest(rows, case, signal, target, |c| c.method == Method::Qsa),
            exp: cheapest(rows, case, signal, target, |c| c.method == Method::Exp),
        })
        .collect()
}

/// How close to IMP's error a QSA configuration must come to count as "as accurate as IMP" (log10).
pub const AS_ACCURATE: f64 = 0.05;

/// The QSA configuration with the fewest segments at oversampling `k` whose `signal` error against
/// the reference is within [`AS_ACCURATE`] of IMP's at the same `k`, with that IMP row.
pub fn as_accurate_as_imp<'a>(
    rows: &'a [ErrorRow],
    case: &str,
    k: usize,
    signal: Signal,
) -> Option<(&'a ErrorRow, &'a ErrorRow)> {
    let imp = rows.iter().find(|r| r.case == case && r.config.method == Method::Imp && r.config.oversampling == k)?;
    let qsa = rows
        .iter()
        .filter(|r| r.case == case && r.config.method == Method::Qsa && r.config.oversampling == k)
        .filter(|r| signal.of(r) <= signal.of(imp) + AS_ACCURATE)
        .min_by_key(|r| r.config.segments)?;
    Some((qsa, imp))
}
