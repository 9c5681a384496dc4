//! The control block N_b as a cost and accuracy knob of the slide in motion.
//!
//! The slide's controls are sampled every N_b samples and its contact vectors interpolated
//! linearly in between (docs/physics.md §7.5), so N_b trades accuracy for run time as N and the
//! sample rate do. For the glide and the vibrato of [`gestures`](super::gestures), rendered with
//! QSA (N = 5) and IMP at N_b ∈ [`BLOCKS`], each row has the error of the output and of the
//! contact force against the same method at N_b = 1, over the samples where the slide moves
//! (log10 of the relative L2 difference), and the real-time factor of the whole render through
//! the real-time path (median of the timing runs, the configurations of a gesture timed round
//! robin so that a slow spell hits them alike).

use std::fmt::Write as _;

use qsa_dsp::contact::{Method, SolverSettings};
use qsa_dsp::scene::Frame;

use super::error::log10_rel_l2;
use super::gestures::Gesture;

/// The control blocks compared (samples); the first is the reference.
pub const BLOCKS: [usize; 4] = [1, 8, 64, 256];

/// QSA's segment count in the study (the slide phrase's).
pub const STUDY_SEGMENTS: usize = 5;

/// The methods compared.
pub const STUDY_METHODS: [Method; 2] = [Method::Qsa, Method::Imp];

/// One configuration's figures.
#[derive(Debug, Clone, PartialEq)]
pub struct BlockRow {
    /// `glide` or `vibrato`.
    pub gesture: String,
    /// The method.
    pub method: Method,
    /// N_b (samples).
    pub block: usize,
    /// log10 relative L2 error of the output against N_b = 1 (NaN for N_b = 1).
    pub output_error: f64,
    /// log10 relative L2 error of the contact force against N_b = 1.
    pub force_error: f64,
    /// Median real-time factor (NaN without timing runs).
    pub rtf: f64,
}

fn settings(method: Method) -> SolverSettings {
    SolverSettings { method, segments: STUDY_SEGMENTS, v_ref: None }
}

/// Every row for both gestures and methods; `timing_runs` renders per configuration are timed
/// (0: no timing, `rtf` is NaN).
pub fn study(timing_runs: usize, tick: &dyn Fn()) -> Vec<BlockRow> {
    let mut rows = Vec::new();
    for gesture in [Gesture::glide(), Gesture::vibrato()] {
        let window = gesture.window();
        for method in STUDY_METHODS {
            let frames: Vec<Vec<Frame>> =
                BLOCKS.iter().map(|&nb| gesture.scene(nb).frames(settings(method), 1)).collect();
            let error = |f: &[Frame], field: fn(&Frame) -> f64| {
                log10_rel_l2(
                    f[window.clone()].iter().zip(&frames[0][window.clone()]).map(|(a, b)| (field(a), field(b))),
                )
            };
            let mut times = vec![Vec::new(); BLOCKS.len()];
            for _ in 0..timing_runs {
                for (i, &nb) in BLOCKS.iter().enumerate() {
                    times[i].push(gesture.scene(nb).timed(settings(method), 1));
                }
            }
            for (i, &nb) in BLOCKS.iter().enumerate() {
                let (output_error, force_error) = if i == 0 {
                    (f64::NAN, f64::NAN)
                } else {
                    (error(&frames[i], |f| f.output), error(&frames[i], |f| f.force))
                };
                rows.push(BlockRow {
                    gesture: gesture.name.to_owned(),
                    method,
                    block: nb,
                    output_error,
                    force_error,
                    rtf: median(&mut times[i]) / gesture.seconds,
                });
                tick();
            }
        }
    }
    rows
}

fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// The CSV of the rows (`control-block.csv`).
pub fn csv(rows: &[BlockRow]) -> String {
    let mut out = String::from("gesture,method,segments,block,output_error_vs_nb1,force_error_vs_nb1,rtf\n");
    for r in rows {
        let _ = writeln!(
            out,
            "{},{},{STUDY_SEGMENTS},{},{:.4},{:.4},{:.4e}",
            r.gesture,
            r.method.name(),
            r.block,
            r.output_error,
            r.force_error,
            r.rtf
        );
    }
    out
}

/// Read what [`csv`] wrote (errors to 4 decimals, run times to 5 significant digits, as printed).
pub fn parse(text: &str) -> Result<Vec<BlockRow>, String> {
    text.lines()
        .skip(1)
        .filter(|l| !l.is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let float = |i: usize| f[i].parse::<f64>().map_err(|e| format!("{l}: {e}"));
            if f.len() != 7 {
                return Err(format!("{l}: expected 7 fields"));
            }
            Ok(BlockRow {
                gesture: f[0].to_owned(),
                method: Method::from_name(f[1]).ok_or_else(|| format!("{l}: method {:?}", f[1]))?,
                block: f[3].parse().map_err(|e| format!("{l}: {e}"))?,
                output_error: float(4)?,
                force_error: float(5)?,
                rtf: float(6)?,
            })
        })
        .collect()
}

/// Compare fresh rows (errors only) with the committed CSV `text`: every error, printed as [`csv`]
/// prints it, must be the committed text exactly (the errors are deterministic; only `rtf`, not
/// compared, depends on timing). Returns the mismatches, one line each.
pub fn compare(fresh: &[BlockRow], text: &str) -> Vec<String> {
    let stored: Vec<Vec<&str>> =
        text.lines().skip(1).filter(|l| !l.is_empty()).map(|l| l.split(',').collect()).collect();
    let mut problems = Vec::new();
    if stored.len() != fresh.len() {
        problems.push(format!("{} rows committed, {} computed", stored.len(), fresh.len()));
        return problems;
    }
    for (r, s) in fresh.iter().zip(&stored) {
        let key = format!("{}/{}/N_b {}", r.gesture, r.method.name(), r.block);
        if s.len() < 7 || s[0] != r.gesture || s[1] != r.method.name() || s[3] != r.block.to_string() {
            problems.push(format!("{key}: the committed row is {s:?}"));
            continue;
        }
        for (what, value, stored) in [("output", r.output_error, s[4]), ("force", r.force_error, s[5])] {
            let printed = format!("{value:.4}");
            if printed != stored {
                problems.push(format!("{key}: {what} error {printed}, committed {stored}"));
            }
        }
    }
    problems
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(block: usize, output_error: f64) -> BlockRow {
        BlockRow { gesture: "glide".into(), method: Method::Qsa, block, output_error, force_error: -1.0, rtf: 1e-3 }
    }

    #[test]
    fn compare_accepts_its_own_csv_and_catches_a_moved_error() {
        let rows = vec![row(1, f64::NAN), row(8, -4.2)];
        let text = csv(&rows);
        assert!(compare(&rows, &text).is_empty());
        assert_eq!(csv(&parse(&text).unwrap()), text, "the CSV reads back as printed");
        let moved = vec![row(1, f64::NAN), row(8, -4.2001)];
        assert_eq!(compare(&moved, &text).len(), 1, "a move by one unit of the last printed place");
        let unprinted = vec![row(1, f64::NAN), row(8, -4.200_04)];
        assert!(compare(&unprinted, &text).is_empty(), "a move below the printed precision");
        assert_eq!(compare(&rows[..1], &text).len(), 1);
    }
}
