//! Why EXP looks more accurate than IMP on the stiff hammer: `stiff-hammer.csv`.
//!
//! On the stiff hammer (κ 1e12) the 16× reference is itself far from converged, and EXP at 8×
//! comes out much closer to it than IMP at 8×. Two readings are possible: EXP is more accurate
//! there, or EXP happens to land near the under-resolved reference. The study tells them apart by
//! measuring IMP and EXP at [`OVERSAMPLING`] against IMP at each of [`REFERENCES`] (the finest,
//! 64×, is the best estimate of the true solution), on the report's grids (sample `n` at `k·fs`
//! against sample `n·K/k` at `K·fs`), and by looking at the force waveform: the height (N) and time
//! (µs) of its first peak, and the ripple on it, whose frequency is `1 / mean spacing` of the first
//! [`RIPPLE_PEAKS`] local maxima of `|F|`.

use std::fmt::Write as _;

use qsa_dsp::contact::{Method, SolverSettings};
use qsa_dsp::scene::Frame;

use super::cases::Case;
use super::error::log10_rel_l2;

/// Oversampling factors of the methods studied.
pub const OVERSAMPLING: [usize; 4] = [4, 8, 16, 32];

/// Oversampling factors of the IMP references; the last is the finest.
pub const REFERENCES: [usize; 3] = [16, 32, 64];

/// Local maxima of `|F|` whose mean spacing gives the ripple's frequency.
pub const RIPPLE_PEAKS: usize = 5;

/// One method at one rate against one reference.
#[derive(Debug, Clone, PartialEq)]
pub struct StiffRow {
    /// IMP or EXP.
    pub method: Method,
    /// Its oversampling k.
    pub oversampling: usize,
    /// The IMP reference's oversampling K.
    pub reference: usize,
    /// `e(F, F_ref)` (log10).
    pub force_error: f64,
    /// `e(out, out_ref)` (log10).
    pub output_error: f64,
    /// Height of the first local maximum of `|F|` (N).
    pub first_peak_force: f64,
    /// Its time (µs).
    pub first_peak_us: f64,
    /// Frequency of the ripple on the force (Hz).
    pub ripple_hz: f64,
}

/// Times (s) and heights of the local maxima of `|F|` of a render at `rate` (Hz).
fn maxima(frames: &[Frame], rate: f64) -> Vec<(f64, f64)> {
    let f: Vec<f64> = frames.iter().map(|x| x.force.abs()).collect();
    (1..f.len().saturating_sub(1))
        .filter(|&i| f[i] > 0.0 && f[i] > f[i - 1] && f[i] >= f[i + 1])
        .map(|i| (i as f64 / rate, f[i]))
        .collect()
}

/// First peak (N, µs) and ripple frequency (Hz) of a render at `rate`.
fn waveform(frames: &[Frame], rate: f64) -> (f64, f64, f64) {
    let peaks = maxima(frames, rate);
    let first = peaks.first().copied().unwrap_or((f64::NAN, f64::NAN));
    let ripple = match peaks.get(RIPPLE_PEAKS - 1) {
        Some(last) => (RIPPLE_PEAKS - 1) as f64 / (last.0 - first.0),
        None => f64::NAN,
    };
    (first.1, first.0 * 1e6, ripple)
}

/// Run the study on `case`.
pub fn study(case: &Case) -> Vec<StiffRow> {
    let scene = &case.scene;
    let render = |method, k| scene.frames(SolverSettings { method, segments: 1, v_ref: None }, k);
    let references: Vec<(usize, Vec<Frame>)> = REFERENCES.iter().map(|&k| (k, render(Method::Imp, k))).collect();
    let base = f64::from(scene.sample_rate);
    let mut rows = Vec::new();
    for method in [Method::Imp, Method::Exp] {
        for &k in &OVERSAMPLING {
            let frames = render(method, k);
            let (first_peak_force, first_peak_us, ripple_hz) = waveform(&frames, base * k as f64);
            for (reference, ref_frames) in references.iter().filter(|(r, _)| *r > k) {
                assert_eq!(reference % k, 0, "{k}× does not divide the reference's rate");
                let stride = reference / k;
                let error = |field: fn(&Frame) -> f64| {
                    log10_rel_l2(frames.iter().enumerate().map(|(n, f)| (field(f), field(&ref_frames[n * stride]))))
                };
                rows.push(StiffRow {
                    method,
                    oversampling: k,
                    reference: *reference,
                    force_error: error(|f| f.force),
                    output_error: error(|f| f.output),
                    first_peak_force,
                    first_peak_us,
                    ripple_hz,
                });
            }
        }
    }
    let (finest, frames) = references.last().expect("a reference");
    let (first_peak_force, first_peak_us, ripple_hz) = waveform(frames, base * *finest as f64);
    rows.push(StiffRow {
        method: Method::Imp,
        oversampling: *finest,
        reference: *finest,
        force_error: f64::NEG_INFINITY,
        output_error: f64::NEG_INFINITY,
        first_peak_force,
        first_peak_us,
        ripple_hz,
    });
    rows
}

/// The CSV header of `stiff-hammer.csv`.
pub const CSV_HEADER: &str =
    "method,oversampling,reference_oversampling,force_error,output_error,first_peak_force,first_peak_us,ripple_hz";

/// `stiff-hammer.csv`: errors to 4 decimals, the waveform to 4 significant digits.
pub fn csv(rows: &[StiffRow]) -> String {
    let mut out = String::from(CSV_HEADER);
    out.push('\n');
    for r in rows {
        let _ = writeln!(
            out,
            "{},{},{},{:.4},{:.4},{:.4e},{:.4e},{:.4e}",
            r.method.name(),
            r.oversampling,
            r.reference,
            r.force_error,
            r.output_error,
            r.first_peak_force,
            r.first_peak_us,
            r.ripple_hz
        );
    }
    out
}

/// Read what [`csv`] wrote.
pub fn parse(text: &str) -> Result<Vec<StiffRow>, String> {
    let mut lines = text.lines();
    if lines.next() != Some(CSV_HEADER) {
        return Err(format!("the first line must be {CSV_HEADER}"));
    }
    lines
        .enumerate()
        .filter(|(_, l)| !l.is_empty())
        .map(|(i, line)| {
            let at = |m: String| format!("line {}: {m}", i + 2);
            let f: Vec<&str> = line.split(',').collect();
            if f.len() != 8 {
                return Err(at(format!("expected 8 fields, found {}", f.len())));
            }
            let int = |s: &str| s.parse::<usize>().map_err(|e| at(e.to_string()));
            let float = |s: &str| s.parse::<f64>().map_err(|e| at(e.to_string()));
            Ok(StiffRow {
                method: Method::from_name(f[0]).ok_or_else(|| at(format!("method {:?}", f[0])))?,
                oversampling: int(f[1])?,
                reference: int(f[2])?,
                force_error: float(f[3])?,
                output_error: float(f[4])?,
                first_peak_force: float(f[5])?,
                first_peak_us: float(f[6])?,
                ripple_hz: float(f[7])?,
            })
        })
        .collect()
}

/// The error (log10) of the finest render, estimated from IMP's errors against it at half and
/// a quarter of its rate (log10), for a scheme converging as `C h^p`: `half − log10(r − 2)`,
/// `r = 10^(quarter − half)` (see [`explanation`]); `None` unless `r > 2` (no convergence seen).
fn own_error(half: Option<f64>, quarter: Option<f64>) -> Option<f64> {
    let (half, quarter) = (half?, quarter?);
    let r = 10f64.powf(quarter - half);
    (r > 2.0).then(|| half - (r - 2.0).log10())
}

/// The study's findings in words, from its rows; `base_rate` is the case's (Hz). Empty if the
/// rows lack the comparison at 8× (a study run with other settings).
pub fn explanation(rows: &[StiffRow], base_rate: f64) -> String {
    let k = 8;
    let (coarse, finest) = (REFERENCES[0], REFERENCES[REFERENCES.len() - 1]);
    let find =
        |m: Method, k: usize, r: usize| rows.iter().find(|x| x.method == m && x.oversampling == k && x.reference == r);
    let (Some(imp_c), Some(exp_c), Some(imp_f), Some(exp_f), Some(truth), Some(ref_vs_finest)) = (
        find(Method::Imp, k, coarse),
        find(Method::Exp, k, coarse),
        find(Method::Imp, k, finest),
        find(Method::Exp, k, finest),
        find(Method::Imp, finest, finest),
        find(Method::Imp, coarse, finest),
    ) else {
        return String::new();
    };
    let lead_coarse = imp_c.force_error - exp_c.force_error;
    let lead_finest = imp_f.force_error - exp_f.force_error;
    let mut s = String::new();
    let _ = write!(
        s,
        "Against IMP at {coarse}×, EXP at {k}× is {lead_coarse:.2} decades closer than IMP at {k}× on the force \
         (EXP {:.2}, IMP {:.2}). Against IMP at {finest}×, the finest render, the lead is {lead_finest:.2} decades \
         (EXP {:.2}, IMP {:.2}). ",
        exp_c.force_error, imp_c.force_error, exp_f.force_error, imp_f.force_error
    );
    if lead_finest < lead_coarse {
        let _ = write!(
            s,
            "So {:.0} % of the lead seen against the {coarse}× reference is an artefact of that reference, which is \
             itself {:.2} from {finest}×{} ",
            100.0 * (lead_coarse - lead_finest) / lead_coarse,
            ref_vs_finest.force_error,
            if exp_c.force_error < ref_vs_finest.force_error {
                format!(
                    ": EXP at {k}× is closer to the {coarse}× reference ({:.2}) than that reference is to {finest}×.",
                    exp_c.force_error
                )
            } else {
                ".".to_owned()
            }
        );
    }
    // The finest render's own error, estimated from IMP's convergence: with `x_h = x + C h^p`,
    // IMP at half and a quarter of the finest rate differ from the finest render by `C h^p`
    // times `2^p − 1` and `4^p − 1`, whose ratio `r` is `2^p + 1`; the finest render's own
    // error, `C h^p`, is then IMP's at half its rate over `r − 2`. A lead whose EXP error is
    // below that is not resolved by the finest render.
    let own_error = own_error(
        find(Method::Imp, finest / 2, finest).map(|r| r.force_error),
        find(Method::Imp, finest / 4, finest).map(|r| r.force_error),
    );
    let leads: Vec<String> = OVERSAMPLING
        .iter()
        .filter_map(|&k| Some((k, find(Method::Imp, k, finest)?, find(Method::Exp, k, finest)?)))
        .map(|(k, imp, exp)| {
            let unresolved = own_error.is_some_and(|own| exp.force_error < own);
            let mark = if unresolved { " (unresolved: EXP below the finest render's own error)" } else { "" };
            format!("{k}×: {:+.2}{mark}", imp.force_error - exp.force_error)
        })
        .collect();
    let always = OVERSAMPLING
        .iter()
        .filter_map(|&k| Some((find(Method::Imp, k, finest)?, find(Method::Exp, k, finest)?)))
        .filter(|(_, exp)| !own_error.is_some_and(|own| exp.force_error < own))
        .all(|(imp, exp)| imp.force_error - exp.force_error > 0.0);
    let _ = write!(
        s,
        "The rest is {}: against IMP at {finest}×, EXP's force error is below IMP's at the same rate by {} decades. ",
        if always { "real" } else { "not consistent" },
        leads.join(", ")
    );
    let nyquist = base_rate / 2.0;
    let _ = write!(
        s,
        "The force rides on a ripple at {:.1} kHz (IMP at {finest}×: mean spacing of its first {RIPPLE_PEAKS} peaks), \
         above the base rate's Nyquist frequency ({:.2} kHz), which the base rate cannot resolve. Its first peak is \
         {:.2} N at {:.1} µs; IMP at {k}× moves it by {:+.1} µs and {:+.1} % in height, EXP at {k}× by {:+.1} µs \
         and {:+.1} %",
        truth.ripple_hz / 1e3,
        nyquist / 1e3,
        truth.first_peak_force,
        truth.first_peak_us,
        imp_f.first_peak_us - truth.first_peak_us,
        100.0 * (imp_f.first_peak_force / truth.first_peak_force - 1.0),
        exp_f.first_peak_us - truth.first_peak_us,
        100.0 * (exp_f.first_peak_force / truth.first_peak_force - 1.0),
    );
    let miss = |row: &StiffRow| {
        ((row.first_peak_us - truth.first_peak_us).abs(), (row.first_peak_force / truth.first_peak_force - 1.0).abs())
    };
    let (imp_miss, exp_miss) = (miss(imp_f), miss(exp_f));
    // The peaks are the largest samples: at k× their times are known to a sample, and a crest
    // between two samples reads low by where they fall.
    let sample_us = 1e6 / (base_rate * k as f64);
    // A crest read up to half a sample off its top reads low by up to `1 − cos(π f Δt)`.
    let crest = 1.0 - (std::f64::consts::PI * truth.ripple_hz * sample_us * 1e-6).cos();
    let closer = |imp: f64, exp: f64, resolution: f64, what: &str| {
        if (imp - exp).abs() <= resolution {
            format!("in {what} the two differ by less than the samples resolve")
        } else {
            format!("in {what} {} is closer", if exp < imp { "EXP" } else { "IMP" })
        }
    };
    let _ = write!(
        s,
        ". The peaks are read at samples, {sample_us:.2} µs apart at {k}×, so a time is known to a sample and \
         a height to {:.1} % (a crest at the ripple's frequency read half a sample off its top): {}, and {}.",
        100.0 * crest,
        closer(imp_miss.0, exp_miss.0, sample_us, "time"),
        closer(imp_miss.1, exp_miss.1, crest, "height"),
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Renders `x_h = x + C h^p` at steps `h_f`, `2h_f` and `4h_f`: the finest render's own error
    /// `C h_f^p` is recovered from the other two's errors against it, for orders 1, 2 and 1.94.
    #[test]
    fn the_finest_renders_own_error_is_recovered_at_any_order() {
        for p in [1.0f64, 2.0, 1.94] {
            let c_h = 1e-3;
            let against_finest = |steps: f64| (c_h * (steps.powf(p) - 1.0)).log10();
            let own = own_error(Some(against_finest(2.0)), Some(against_finest(4.0))).expect("converging");
            assert!((own - c_h.log10()).abs() < 1e-12, "order {p}: {own} against {}", c_h.log10());
        }
        assert_eq!(own_error(Some(-1.0), Some(-1.2)), None, "errors growing with the rate: no estimate");
    }

    #[test]
    fn csv_reads_back_what_it_wrote() {
        let row = StiffRow {
            method: Method::Exp,
            oversampling: 8,
            reference: 64,
            force_error: -1.177_04,
            output_error: -1.5,
            first_peak_force: 26.32,
            first_peak_us: 79.4,
            ripple_hz: 24_000.0,
        };
        let back = parse(&csv(std::slice::from_ref(&row))).unwrap();
        assert_eq!(back[0].method, Method::Exp);
        assert!((back[0].force_error - (-1.177)).abs() < 1e-12, "4 decimals kept");
        assert_eq!(csv(&back), csv(&[row]));
    }

    #[test]
    fn a_pure_sine_ripple_has_its_own_frequency() {
        // |F| of a 24 kHz sine sampled at 2.8224 MHz: maxima every half period, so 48 kHz.
        let rate = 2_822_400.0;
        let frames: Vec<Frame> = (0..2000)
            .map(|n| Frame {
                force: (2.0 * std::f64::consts::PI * 24_000.0 * n as f64 / rate).sin(),
                ..Frame::default()
            })
            .collect();
        let (_, _, ripple) = waveform(&frames, rate);
        assert!((ripple / 48_000.0 - 1.0).abs() < 0.01, "{ripple}");
    }
}
