//! The report's advice, in words, from the error rows: "What to choose" (per case and for the
//! plugin) and "Which method to pick" (the cheapest configurations per target, QSA against IMP,
//! the budget table, QSA against EXP).
//!
//! Every verdict goes through [`analysis`]: an error below the reference's own error
//! (`reference-check.csv`) is marked unresolved and never decides; a target below that error is
//! not judged; run times count as different only beyond the rows' timing noise
//! ([`analysis::faster`]); a target missed by less than the error's uncertainty does not decide a
//! duel ([`analysis::uncertainty`]).

use std::fmt::Write as _;

use qsa_dsp::contact::Method;

use super::analysis::{self, Match, Reach, Signal, Verdict};
use super::cases::Case;
use super::error::{ErrorRow, REFERENCE_OVERSAMPLING};
use super::results::{Results, e, label, t};

/// The error targets of the advice (log10): 10 %, 1 % and 0.1 %.
pub const ADVICE_TARGETS: [(f64, &str); 3] = [(-1.0, "10 %"), (-2.0, "1 %"), (-3.0, "0.1 %")];

/// Run-time budgets of the budget table (RTF).
pub const BUDGETS: [f64; 5] = [1e-3, 3e-3, 1e-2, 3e-2, 1e-1];

/// An error as printed, marked when the reference does not resolve it.
fn shown(v: f64, check: f64) -> String {
    if analysis::resolved(v, check) {
        e(v)
    } else {
        format!("{} (unresolved: below the reference's own {})", e(v), e(check))
    }
}

/// A configuration in plain words, e.g. `QSA with N = 6 at 44.1 kHz`.
fn plain(row: &ErrorRow) -> String {
    let rate = format!("{:.1} kHz", f64::from(row.sample_rate) / 1e3);
    match row.config.method {
        Method::Qsa => format!("QSA with N = {} at {rate}", row.config.segments),
        m => format!("{} at {rate}", m.name().to_uppercase()),
    }
}

/// The ties of a pick in a few words.
fn ties(pick: &analysis::Pick) -> String {
    match pick.ties.len() {
        0 => String::new(),
        n => {
            let shown: Vec<String> = pick.ties.iter().take(3).map(|r| label(r)).collect();
            let more = if n > 3 { format!(" and {} more", n - 3) } else { String::new() };
            format!("; tied within the timing noise with {}{more}", shown.join(", "))
        }
    }
}

fn find<'a>(rows: &'a [ErrorRow], case: &str, method: Method, segments: usize, k: usize) -> Option<&'a ErrorRow> {
    rows.iter().find(|r| {
        r.case == case && r.config.method == method && r.config.segments == segments && r.config.oversampling == k
    })
}

/// "What to choose": per case, the pick for each target on the output signal; then the plugin's
/// default against the data.
pub fn what_to_choose(w: &mut String, r: &Results) {
    let _ = writeln!(w, "## What to choose\n");
    let _ = writeln!(
        w,
        "By the output signal (what is heard), against the converged reference. Each cell is the cheapest \
         configuration that reaches the error; a configuration not slower than it beyond the timing noise ties \
         with it, and the plugin's default wins a tie. \"Unresolved\": the reference itself is not that accurate \
         for this case, so the data cannot say.\n"
    );
    let _ = writeln!(w, "| case | within 10 % | within 1 % | within 0.1 % |");
    let _ = writeln!(w, "|---|---|---|---|");
    for (case, check) in r.cases.iter().zip(&r.reference_checks) {
        let _ = write!(w, "| {} |", case.name);
        for (target, _) in ADVICE_TARGETS {
            match analysis::reach(&r.rows, case.name, Signal::Output, target, check.1, |_| true) {
                Reach::Unresolved => {
                    let _ = write!(w, " unresolved (the reference is good to {}) |", e(check.1));
                }
                Reach::Nothing => {
                    let _ = write!(w, " not reached |");
                }
                Reach::Found(pick) => {
                    let _ = write!(w, " {} (RTF {}{}) |", plain(pick.row), t(pick.row.rtf), ties(&pick));
                }
            }
        }
        let _ = writeln!(w);
    }
    let _ = writeln!(
        w,
        "\nFor a run-time budget instead of an error target, [By budget](#by-budget) lists the best error each \
         budget buys.\n"
    );
    plugin_default(w, r);
}

/// The plugin's default (QSA, its default N, no oversampling) against the data of the musical
/// cases at the base rate.
fn plugin_default(w: &mut String, r: &Results) {
    let d = analysis::plugin_default();
    let musical: Vec<&Case> = r.cases.iter().filter(|c| c.musical).collect();
    let mut gaps = Vec::new(); // (case, QSA default − IMP output error at 1×)
    let (mut n_cost, mut imp_cost, mut k_cost, mut k_gain) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for case in &musical {
        let rows = &r.rows;
        let (Some(qsa), Some(many), Some(imp), Some(qsa2), Some(imp2)) = (
            find(rows, case.name, Method::Qsa, d.segments, 1),
            find(rows, case.name, Method::Qsa, *super::error::SWEPT_SEGMENTS.last().expect("segments"), 1),
            find(rows, case.name, Method::Imp, 0, 1),
            find(rows, case.name, Method::Qsa, d.segments, 2),
            find(rows, case.name, Method::Imp, 0, 2),
        ) else {
            continue;
        };
        let ratio = |a: &ErrorRow, b: &ErrorRow| a.rtf.zip(b.rtf).map_or(f64::NAN, |(a, b)| a / b);
        gaps.push((case.name, qsa.output_error_vs_reference - imp.output_error_vs_reference));
        n_cost.push((ratio(many, qsa), analysis::faster(qsa, many)));
        imp_cost.push((ratio(imp, qsa), analysis::faster(qsa, imp)));
        k_cost.push(ratio(qsa2, qsa));
        k_gain.push(imp.output_error_vs_reference - imp2.output_error_vs_reference);
    }
    if gaps.is_empty() {
        return;
    }
    let range = |v: &[f64], digits: usize| {
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        format!("{lo:.digits$}–{hi:.digits$}")
    };
    let worst_gap = gaps.iter().map(|g| g.1.abs()).fold(0.0, f64::max);
    let n_costs: Vec<f64> = n_cost.iter().map(|c| c.0).collect();
    let imp_costs: Vec<f64> = imp_cost.iter().map(|c| c.0).collect();
    let n_noise = n_cost.iter().filter(|c| !c.1).count();
    let imp_clear = imp_cost.iter().filter(|c| c.1).count();
    let many = super::error::SWEPT_SEGMENTS.last().expect("segments");
    let _ = writeln!(
        w,
        "**The plugin.** Its default is {} with N = {}, no oversampling: the host's sample rate is its only rate \
         knob. In the musical cases ({}), at the base rate:\n",
        d.method.name().to_uppercase(),
        d.segments,
        musical.iter().map(|c| c.name).collect::<Vec<_>>().join(", ")
    );
    let within_10 = musical
        .iter()
        .filter(|c| {
            find(&r.rows, c.name, d.method, d.segments, 1).is_some_and(|row| row.output_error_vs_reference <= -1.0)
        })
        .count();
    let _ = writeln!(
        w,
        "- QSA with N = {} reaches 10 % of the reference in {} of {} cases; its output error differs from IMP's at \
         the same rate by {}.",
        d.segments,
        within_10,
        musical.len(),
        gaps.iter().map(|(c, g)| format!("{g:+.2} ({c})")).collect::<Vec<_>>().join(", "),
    );
    // The fewest segments that match IMP's output error at the base rate, per case.
    let matching: Vec<(&str, usize)> = musical
        .iter()
        .filter_map(|c| {
            let imp = find(&r.rows, c.name, Method::Imp, 0, 1)?;
            let at_base = (r.rows.iter())
                .filter(|row| row.case == c.name && row.config.method == Method::Qsa && row.config.oversampling == 1);
            let qsa = analysis::fewest_segments_matching(
                at_base,
                |row| row.output_error_vs_reference,
                imp.output_error_vs_reference,
            )?;
            Some((c.name, qsa.config.segments))
        })
        .collect();
    if worst_gap > analysis::ERROR_TOLERANCE {
        let needed = matching.iter().map(|m| m.1).max().unwrap_or(d.segments);
        let costs: Vec<f64> = musical
            .iter()
            .filter_map(|c| {
                let a = find(&r.rows, c.name, Method::Qsa, needed, 1)?.rtf?;
                let b = find(&r.rows, c.name, Method::Qsa, d.segments, 1)?.rtf?;
                Some(a / b)
            })
            .collect();
        let _ = writeln!(
            w,
            "- So at N = {} the contact solver still adds a measurable part (over {}) to the time step's error where \
             the gap is positive. The fewest N that match IMP within {} are {}; N = {needed} costs {} times N = {}.",
            d.segments,
            analysis::ERROR_TOLERANCE,
            analysis::ERROR_TOLERANCE,
            matching.iter().map(|(c, n)| format!("{n} ({c})")).collect::<Vec<_>>().join(", "),
            range(&costs, 2),
            d.segments
        );
    } else {
        let _ = writeln!(
            w,
            "- So the contact solver adds nothing measurable (below {}) to the time step's error.",
            analysis::ERROR_TOLERANCE
        );
    }
    let _ = writeln!(
        w,
        "- N is nearly free: N = {many} costs {} times N = {} ({} of {} cases within the timing noise).",
        range(&n_costs, 2),
        d.segments,
        n_noise,
        n_cost.len()
    );
    let _ = writeln!(
        w,
        "- IMP costs {} times as much as QSA at N = {} (beyond the timing noise in {} of {} cases) in these scenes, \
         which are mostly contact (a strike's first 30 ms, the slide pressed on its string). Over a whole note the \
         free string, stepped alike by both, brings the ratio near 1; what stays is the call that holds a strike, \
         where real time is won or lost, and where IMP costs several times its mean call and QSA about twice \
         (`piano/restrike/*` in [bench.md](bench.md)).",
        range(&imp_costs, 1),
        d.segments,
        imp_clear,
        imp_cost.len()
    );
    let _ = writeln!(
        w,
        "- The time step sets the error: doubling the rate (the host at twice the rate) lowers IMP's output error \
         by {} decades, at {} times QSA's run time.\n",
        range(&k_gain, 2),
        range(&k_cost, 1)
    );
    let _ = writeln!(
        w,
        "{}\n",
        if worst_gap <= analysis::ERROR_TOLERANCE && imp_clear == imp_cost.len() {
            "So the default spends the run time where it buys accuracy: on the rate, which the host sets, not on N or \
             on IMP."
        } else if imp_clear == imp_cost.len() && within_10 == musical.len() {
            "So the default's choices of QSA over IMP and of the host's rate as the accuracy knob hold; its N is \
             within 10 % everywhere but not always as accurate as IMP, and a larger N would close that gap for \
             little run time."
        } else {
            "So the data do not support the default as it stands: see the items above."
        }
    );
}

/// The cheapest configurations within 1 %, 10 % and 0.1 % of the reference on `signal`.
fn pick_sentence(w: &mut String, rows: &[ErrorRow], case: &str, signal: Signal, check: f64) {
    let within = |target| analysis::reach(rows, case, signal, target, check, |_| true);
    match within(-2.0) {
        Reach::Found(pick) => {
            let _ = write!(
                w,
                "within 1 % at the lowest run time: {} (error {}, RTF {}{}).",
                label(pick.row),
                shown(signal.of(pick.row), check),
                t(pick.row.rtf),
                ties(&pick)
            );
        }
        other => {
            let _ = write!(
                w,
                "{}",
                if matches!(other, Reach::Unresolved) {
                    format!("**1 % is below the reference's own error here ({}): unresolved**.", e(check))
                } else {
                    "**no configuration measured comes within 1 % of the reference**.".to_owned()
                }
            );
            if let Some(row) = analysis::most_accurate(rows, case, signal) {
                let _ = write!(
                    w,
                    " The most accurate is {} (error {}, RTF {}).",
                    label(row),
                    shown(signal.of(row), check),
                    t(row.rtf)
                );
            }
        }
    }
    for (target, name) in [(-1.0, "10 %"), (-3.0, "0.1 %")] {
        match within(target) {
            Reach::Found(pick) => {
                let _ = write!(w, " Within {name}: {} (RTF {}{}).", label(pick.row), t(pick.row.rtf), ties(&pick));
            }
            Reach::Unresolved if target > -2.0 => {
                let _ = write!(w, " Within {name}: unresolved.");
            }
            _ => {}
        }
    }
}

/// "Which method to pick": the pick sentences, QSA against IMP, the budget table and QSA against
/// EXP.
pub fn which_method(w: &mut String, r: &Results) {
    let _ = writeln!(w, "## Which method to pick\n");
    let _ = writeln!(
        w,
        "\"Error\" is the error against the converged reference, log10 of the normalised L2 difference (−2 = 1 %, \
         −1 = 10 %). \"RTF\" is wall seconds per simulated second on the real-time path (median of the timing \
         runs). Labels: `qsa N=6 2x` is QSA with 6 segments at twice the base rate (N = segments, k× = \
         oversampling). An error below the reference's own error (its distance from IMP at the next rate, listed \
         under Cases) is marked unresolved and decides nothing.\n"
    );
    for (case, check) in r.cases.iter().zip(&r.reference_checks) {
        let _ = writeln!(w, "- **{}** ({}):", case.name, case.title);
        for (signal, check) in [(Signal::Force, check.0), (Signal::Output, check.1)] {
            let _ = write!(w, "  - by the {} signal: ", signal.name());
            pick_sentence(w, &r.rows, case.name, signal, check);
            let _ = writeln!(w);
        }
    }
    let _ = writeln!(w);
    qsa_against_imp(w, r);
    budget_guide(w, r);
    qsa_against_exp(w, r);
}

/// At the lowest rate where it means something: the fewest QSA segments that match IMP's accuracy.
fn qsa_against_imp(w: &mut String, r: &Results) {
    let _ = writeln!(w, "### QSA against IMP\n");
    let _ = writeln!(
        w,
        "At the lowest rate where IMP's error is resolved by the reference and below {} ({:.0} %; where both \
         solvers are further off, their agreement is a coincidence of two time-step errors), the fewest QSA \
         segments whose error is within {} of IMP's, and the run times. \"QSA / IMP\" is the ratio of the \
         medians; \"beyond noise\" tells whether it exceeds the two rows' timing noise.\n",
        analysis::USEFUL_ERROR,
        100.0 * 10f64.powf(analysis::USEFUL_ERROR),
        analysis::ERROR_TOLERANCE
    );
    let _ = writeln!(
        w,
        "| case | signal | rate | QSA as accurate as IMP | its error | IMP's error | QSA RTF | IMP RTF | QSA / IMP |"
    );
    let _ = writeln!(w, "|---|---|---|---|---|---|---|---|---|");
    for (case, check) in r.cases.iter().zip(&r.reference_checks) {
        for (signal, check) in [(Signal::Force, check.0), (Signal::Output, check.1)] {
            match analysis::as_accurate_as_imp(&r.rows, case.name, signal, check) {
                Match::Found { qsa, imp } => {
                    let ratio = match (qsa.rtf, imp.rtf) {
                        (Some(q), Some(i)) => format!(
                            "{:.2} ({})",
                            q / i,
                            if analysis::faster(qsa, imp) || analysis::faster(imp, qsa) {
                                "beyond noise"
                            } else {
                                "within noise"
                            }
                        ),
                        _ => "–".to_owned(),
                    };
                    let _ = writeln!(
                        w,
                        "| {} | {} | {}× | N = {} | {} | {} | {} | {} | {ratio} |",
                        case.name,
                        signal.name(),
                        imp.config.oversampling,
                        qsa.config.segments,
                        e(signal.of(qsa)),
                        e(signal.of(imp)),
                        t(qsa.rtf),
                        t(imp.rtf)
                    );
                }
                Match::Unresolved { best_imp } => {
                    let best = best_imp.map_or("–".to_owned(), |b| {
                        format!("IMP's best is {} at {}×", shown(signal.of(b), check), b.config.oversampling)
                    });
                    let _ = writeln!(
                        w,
                        "| {} | {} | – | unresolved: {best}; reference good to {} | – | – | – | – | – |",
                        case.name,
                        signal.name(),
                        e(check)
                    );
                }
            }
        }
    }
    let _ = writeln!(w);
}

/// The best error each run-time budget buys, per case and signal.
fn budget_guide(w: &mut String, r: &Results) {
    let _ = writeln!(w, "### By budget\n");
    let _ = writeln!(
        w,
        "The best error each run-time budget buys (Pareto front over all methods; the plots below show every \
         configuration). Errors below the reference's own error count as that error (the cheapest such \
         configuration stands for them) and are marked \"(unresolved)\".\n"
    );
    let _ = write!(w, "| case | signal |");
    for (i, b) in BUDGETS.iter().enumerate() {
        let _ = write!(w, " {}{b:.0e} |", if i == 0 { "RTF ≤ " } else { "≤ " });
    }
    let _ = writeln!(w, "\n|---|---|{}", "---|".repeat(BUDGETS.len()));
    for (case, check) in r.cases.iter().zip(&r.reference_checks) {
        for (signal, check) in [(Signal::Force, check.0), (Signal::Output, check.1)] {
            let front = analysis::pareto(&r.rows, case.name, signal, check);
            let _ = write!(w, "| {} | {} |", case.name, signal.name());
            for budget in BUDGETS {
                match front.iter().rev().find(|row| row.rtf.is_some_and(|t| t <= budget)) {
                    Some(row) => {
                        let v = signal.of(row);
                        let mark = if analysis::resolved(v, check) { "" } else { " (unresolved)" };
                        let _ = write!(w, " {} {}{mark} |", label(row), e(v));
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
        "For each error target, the cheapest QSA and the cheapest EXP configuration that reach it (any N and k). \
         A method is faster only if its run time beats the other's by more than the two rows' timing noise (and \
         by at least a factor {}), and only if the other method does not come within the error's uncertainty \
         (at least {}, more where the reference's own error is near) of the target at a lower cost: a target \
         missed by less than that decides nothing. Targets below the reference's own error are not judged.\n",
        analysis::NOISE_RATIO,
        analysis::ERROR_TOLERANCE
    );
    let musical: Vec<&str> = r.cases.iter().filter(|c| c.musical).map(|c| c.name).collect();
    for signal in [Signal::Force, Signal::Output] {
        let _ = writeln!(w, "| case | {} target | QSA | EXP | verdict |", signal.name());
        let _ = writeln!(w, "|---|---|---|---|---|");
        let mut tally = [0usize; 5];
        for (case, check) in r.cases.iter().zip(&r.reference_checks) {
            for d in analysis::duels(&r.rows, case.name, signal, signal.check(*check)) {
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
                        Verdict::Unresolved => 4,
                    }] += 1;
                }
            }
        }
        let _ = writeln!(
            w,
            "\n**{}**: across the musically relevant cases ({}), over {} (case, target) pairs, QSA is the faster way to \
             the target (or the only one to reach it) in {}, EXP in {}, the two tie in {}, neither reaches the \
             target in {}, and the reference does not resolve the target in {}. {}\n",
            signal.name(),
            musical.join(", "),
            tally.iter().sum::<usize>(),
            tally[0],
            tally[1],
            tally[2],
            tally[3],
            tally[4],
            duel_conclusion(tally)
        );
    }
    let _ =
        writeln!(w, "The reference is IMP at {REFERENCE_OVERSAMPLING}×; its own error is in the Cases table below.\n");
}

/// The conclusion of one QSA-against-EXP table, from its tally (QSA, EXP, tie, neither,
/// unresolved).
fn duel_conclusion(tally: [usize; 5]) -> &'static str {
    let [qsa, exp, tie, ..] = tally;
    if qsa == 0 && exp == 0 {
        "On these numbers neither method is faster to a given error: where both reach it, they cost the same within \
         the noise."
    } else if exp == 0 && tie >= qsa {
        "QSA is never slower than EXP to a given error here, but the two tie at least as often as QSA is clearly \
         faster: in the string cases the modal update dominates the cost of a step, so QSA and EXP cost about the \
         same per sample, and both need the same rate for a given error unless EXP's own error forces it to a \
         higher rate. The claim that QSA reaches a given error at lower run time than EXP holds here only in that \
         weak sense."
    } else if exp == 0 {
        "On these numbers QSA reaches a given error at lower run time than EXP wherever the two differ beyond the \
         noise."
    } else if qsa > exp {
        "QSA wins more often than EXP, but not everywhere: see the rows where EXP is faster."
    } else if qsa == exp {
        "On these numbers neither method is generally faster to a given error."
    } else {
        "On these numbers EXP, not QSA, is more often the faster way to a given error."
    }
}
