//! Shared helpers for the QSA Strings test suites.
//!
//! - Running a mass–barrier scene with any of the three contact solvers, either for a fixed
//!   number of steps or until the contact has ended ([`run_mass_barrier`], [`run_scheme`]).
//! - Measurements on a trajectory: energy drift, contact duration, rebound velocity, the
//!   normalised L2 force difference of docs/physics.md §9.4 ([`Trajectory`]; [`log10_rel_l2`] is
//!   the report's, re-exported so the tests and the report measure it one way).
//! - The analytic Hertz contact of a mass on a rigid barrier (docs/physics.md §9.1): the Gamma function
//!   ([`gamma`]), the integral `I_n` in closed form and by quadrature ([`hertz_integral`],
//!   [`hertz_integral_quadrature`]) and the closed-form peak compression and contact time
//!   ([`HertzContact`]).
//! - A seeded RNG ([`seeded_rng`]) so that random tests are reproducible.
//! - The DC component of an audio signal against its RMS ([`dc_db`]).
//!
//! Units are SI throughout (m, kg, N, s, Hz, J).

use qsa_dsp::contact::{
    ContactError, ContactSolver, ExplicitSolver, NewtonSolver, PowerLaw, QsaSolver, QuadSpline, SegmentSearch,
};
use qsa_dsp::scene::{Frame, MassBarrier, MassBarrierParams, Scene};
use qsa_dsp::scene_file::contact_intervals;
use rand::SeedableRng;
use rand_pcg::Pcg64;
pub use xtask::report::error::log10_rel_l2;

// ------------------------------------------------------------------------------------------------
// Running a mass–barrier
// ------------------------------------------------------------------------------------------------

/// When a mass–barrier run stops.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stop {
    /// Exactly this many steps.
    Steps(usize),
    /// After the first contact has ended (no force and no compression for `tail` consecutive
    /// samples after a sample with contact), or after `max_steps`, whichever comes first.
    AfterContact {
        /// Hard limit on the number of steps.
        max_steps: usize,
        /// Contact-free samples to keep after the contact.
        tail: usize,
    },
}

/// The frames of one mass–barrier run and what is needed to interpret them.
#[derive(Debug, Clone)]
pub struct Trajectory {
    /// Frame n holds `u^n`, `y^n`, `F^n` and `H^{n+1/2}`.
    pub frames: Vec<Frame>,
    /// `H^{−1/2}` (J).
    pub initial_energy: f64,
    /// Time step Δt (s).
    pub dt: f64,
}

/// A frame is "in contact" if it has a compression or a force (EXP can still push while its
/// auxiliary variable drains after separation).
fn touching(frame: &Frame) -> bool {
    frame.compression > 0.0 || frame.force != 0.0
}

/// Run `solver` on a mass–barrier at `sample_rate` (Hz) until `stop`.
pub fn run_mass_barrier<S: ContactSolver>(
    params: MassBarrierParams,
    sample_rate: f64,
    solver: S,
    stop: Stop,
) -> Trajectory {
    let mut scene = MassBarrier::new(params, sample_rate, solver);
    let initial_energy = scene.initial_energy();
    let frames = match stop {
        Stop::Steps(n) => {
            let mut frames = vec![Frame::default(); n];
            scene.process(&mut frames);
            frames
        }
        Stop::AfterContact { max_steps, tail } => {
            let mut frames = Vec::with_capacity(max_steps.min(1 << 16));
            let mut contact_seen = false;
            let mut free_since_contact = 0;
            let mut frame = [Frame::default()];
            while frames.len() < max_steps {
                scene.process(&mut frame);
                frames.push(frame[0]);
                if touching(&frame[0]) {
                    contact_seen = true;
                    free_since_contact = 0;
                } else if contact_seen {
                    free_since_contact += 1;
                    if free_since_contact >= tail {
                        break;
                    }
                }
            }
            frames
        }
    };
    Trajectory { frames, initial_energy, dt: 1.0 / sample_rate }
}

/// A contact scheme with its settings, for tests that loop over methods.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Scheme {
    /// QSA with N segments and the given segment search; V_ref = ½ m v0² (the scene default).
    Qsa {
        /// Segment count N.
        segments: usize,
        /// Segment search strategy.
        search: SegmentSearch,
    },
    /// Newton on the exact law.
    Imp,
    /// Explicit energy quadratisation with the branched gradient.
    Exp,
}

impl Scheme {
    /// QSA with N segments and the default (warm-started) search.
    pub fn qsa(segments: usize) -> Self {
        Scheme::Qsa { segments, search: SegmentSearch::WarmStart }
    }

    /// A short label for messages.
    pub fn label(&self) -> String {
        match self {
            Scheme::Qsa { segments, search } => format!("QSA(N={segments},{search:?})"),
            Scheme::Imp => "IMP".to_owned(),
            Scheme::Exp => "EXP".to_owned(),
        }
    }
}

/// The QSA spline a mass–barrier scene would use: fitted up to the compression that stores the
/// whole kinetic energy `½ m v0²` (docs/physics.md §1.2).
pub fn scene_spline(law: PowerLaw, params: &MassBarrierParams, segments: usize) -> Result<QuadSpline, ContactError> {
    QuadSpline::from_reference_energy(law, params.max_contact_energy(), segments)
}

/// Run `method` on the law `(kappa, alpha)` for a mass–barrier with `params` at `sample_rate`.
pub fn run_scheme(
    scheme: Scheme,
    law: PowerLaw,
    params: MassBarrierParams,
    sample_rate: f64,
    stop: Stop,
) -> Trajectory {
    match scheme {
        Scheme::Qsa { segments, search } => {
            let spline = scene_spline(law, &params, segments).expect("spline fit");
            run_mass_barrier(params, sample_rate, QsaSolver::with_search(spline, search), stop)
        }
        Scheme::Imp => run_mass_barrier(params, sample_rate, NewtonSolver::new(law), stop),
        Scheme::Exp => run_mass_barrier(params, sample_rate, ExplicitSolver::new(law), stop),
    }
}

/// The seed's Fig. 4 case (docs/physics.md §8.1): 10 g at 2 m/s from u0 = −1 mm onto a barrier at 0.
pub fn fig4_params() -> MassBarrierParams {
    MassBarrierParams { mass: 0.01, u0: -1e-3, v0: 2.0, barrier: 0.0 }
}

/// The Fig. 4 law: κ = 1e8 N/m^1.3, α = 1.3.
pub fn fig4_law() -> PowerLaw {
    PowerLaw::new(1e8, 1.3).expect("valid law")
}

/// Fig. 4 sample rate (Hz).
pub const FIG4_SAMPLE_RATE: f64 = 44_100.0;

impl Trajectory {
    /// Largest `|H^{n+1/2} − H^{−1/2}| / H^{−1/2}` over the run.
    pub fn energy_drift(&self) -> f64 {
        let h0 = self.initial_energy;
        self.frames.iter().map(|f| (f.energy - h0).abs()).fold(0.0, f64::max) / h0
    }

    /// Every number in every frame is finite.
    pub fn all_finite(&self) -> bool {
        self.initial_energy.is_finite()
            && self.frames.iter().all(|f| {
                f.output.is_finite()
                    && f.displacement.is_finite()
                    && f.velocity.is_finite()
                    && f.compression.is_finite()
                    && f.force.is_finite()
                    && f.energy.is_finite()
            })
    }

    /// Contact intervals (s), entry and exit interpolated linearly (see `contact_intervals`).
    pub fn contact_intervals(&self) -> Vec<(f64, f64)> {
        contact_intervals(&self.frames, self.dt)
    }

    /// Duration of the single contact of the run (s). Panics unless there is exactly one
    /// contact interval and it closed before the end of the run.
    pub fn single_contact_duration(&self) -> f64 {
        let intervals = self.contact_intervals();
        assert_eq!(intervals.len(), 1, "expected exactly one contact, got {intervals:?}");
        let last = self.frames.last().expect("frames");
        assert!(last.compression <= 0.0, "the run ended in contact");
        intervals[0].1 - intervals[0].0
    }

    /// Largest sampled compression `max_n y^n` (m).
    pub fn max_compression(&self) -> f64 {
        self.frames.iter().map(|f| f.compression).fold(f64::NEG_INFINITY, f64::max)
    }

    /// Largest `|u^n|` (m).
    pub fn max_abs_displacement(&self) -> f64 {
        self.frames.iter().map(|f| f.displacement.abs()).fold(0.0, f64::max)
    }

    /// Largest `|F^n|` (N).
    pub fn max_abs_force(&self) -> f64 {
        self.frames.iter().map(|f| f.force.abs()).fold(0.0, f64::max)
    }

    /// The force signal `F^n` (N).
    pub fn forces(&self) -> Vec<f64> {
        self.frames.iter().map(|f| f.force).collect()
    }

    /// The velocity of the last frame, `(u^{n+1} − u^n)/Δt` (m/s).
    pub fn final_velocity(&self) -> f64 {
        self.frames.last().expect("frames").velocity
    }

    /// Number of frames in contact (compression > 0 or force ≠ 0).
    pub fn contact_samples(&self) -> usize {
        self.frames.iter().filter(|f| touching(f)).count()
    }
}

/// `x`'s DC component (Hann-weighted mean) over `range`, relative to its RMS there, in dB.
pub fn dc_db(x: &[f64], range: std::ops::Range<usize>) -> f64 {
    let s = &x[range];
    let n = s.len() as f64;
    let hann = |i: usize| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / n).cos();
    let dc = s.iter().enumerate().map(|(i, v)| hann(i) * v).sum::<f64>()
        / s.iter().enumerate().map(|(i, _)| hann(i)).sum::<f64>();
    let rms = (s.iter().map(|v| v * v).sum::<f64>() / n).sqrt();
    20.0 * (dc.abs() / rms).log10()
}

// ------------------------------------------------------------------------------------------------
// Analytic Hertz contact (docs/physics.md §9.1)
// ------------------------------------------------------------------------------------------------

/// Lanczos coefficients (g = 7, 9 terms); relative accuracy about 1e-15 for real arguments.
const LANCZOS_G: f64 = 7.0;
#[allow(clippy::excessive_precision)] // published coefficients, kept as printed
const LANCZOS: [f64; 9] = [
    0.999_999_999_999_809_93,
    676.520_368_121_885_1,
    -1_259.139_216_722_402_8,
    771.323_428_777_653_13,
    -176.615_029_162_140_59,
    12.507_343_278_686_905,
    -0.138_571_095_265_720_12,
    9.984_369_578_019_571_6e-6,
    1.505_632_735_149_311_6e-7,
];

/// The Gamma function Γ(x) for real x (Lanczos approximation with reflection for x < ½).
pub fn gamma(x: f64) -> f64 {
    use std::f64::consts::PI;
    if x < 0.5 {
        return PI / ((PI * x).sin() * gamma(1.0 - x));
    }
    let x = x - 1.0;
    let t = x + LANCZOS_G + 0.5;
    let series = LANCZOS[1..].iter().enumerate().fold(LANCZOS[0], |acc, (i, c)| acc + c / (x + i as f64 + 1.0));
    (2.0 * PI).sqrt() * t.powf(x + 0.5) * (-t).exp() * series
}

/// `I_n = ∫_0^1 (1 − x^n)^(−1/2) dx = √π Γ(1 + 1/n) / Γ(1/n + 1/2)` (docs/physics.md §9.1), n = α + 1.
pub fn hertz_integral(n: f64) -> f64 {
    std::f64::consts::PI.sqrt() * gamma(1.0 + 1.0 / n) / gamma(1.0 / n + 0.5)
}

/// `I_n` by quadrature, independent of [`gamma`]. The substitution `x = 1 − t²` removes the
/// inverse-square-root singularity at x = 1: `I_n = ∫_0^1 2t / √(1 − (1 − t²)^n) dt`, whose
/// integrand tends to `2/√n` at t = 0. `1 − (1 − t²)^n` is evaluated as
/// `−expm1(n·ln1p(−t²))` so that it keeps its digits for small t. Composite 5-point
/// Gauss–Legendre on 400 panels.
pub fn hertz_integral_quadrature(n: f64) -> f64 {
    const NODES: [f64; 5] =
        [0.0, 0.538_469_310_105_683_1, -0.538_469_310_105_683_1, 0.906_179_845_938_664, -0.906_179_845_938_664];
    const WEIGHTS: [f64; 5] = [
        0.568_888_888_888_888_9,
        0.478_628_670_499_366_47,
        0.478_628_670_499_366_47,
        0.236_926_885_056_189_08,
        0.236_926_885_056_189_08,
    ];
    let integrand = |t: f64| {
        if t == 0.0 {
            return 2.0 / n.sqrt();
        }
        let one_minus = -(n * (-t * t).ln_1p()).exp_m1();
        2.0 * t / one_minus.sqrt()
    };
    let panels = 400;
    let h = 1.0 / panels as f64;
    let mut sum = 0.0;
    for k in 0..panels {
        let mid = (k as f64 + 0.5) * h;
        for (x, w) in NODES.iter().zip(WEIGHTS) {
            sum += w * integrand(mid + 0.5 * h * x);
        }
    }
    0.5 * h * sum
}

/// Closed-form contact of a mass `m` (kg) hitting a rigid barrier at `v0` (m/s) with the law
/// `F = −κ[y]+^α` (docs/physics.md §9.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HertzContact {
    /// Peak compression `y_max = (n m v0²/(2κ))^(1/n)`, n = α + 1 (m).
    pub y_max: f64,
    /// Contact time `T_c = 2 (y_max/v0) I_n` (s).
    pub contact_time: f64,
    /// Peak force `κ y_max^α` (N).
    pub f_max: f64,
}

impl HertzContact {
    /// The analytic contact for `law`, mass (kg) and approach speed (m/s).
    pub fn new(law: PowerLaw, mass: f64, v0: f64) -> Self {
        let n = law.alpha() + 1.0;
        let y_max = (n * mass * v0 * v0 / (2.0 * law.kappa())).powf(1.0 / n);
        Self {
            y_max,
            contact_time: 2.0 * y_max / v0.abs() * hertz_integral(n),
            f_max: law.kappa() * y_max.powf(law.alpha()),
        }
    }
}

// ------------------------------------------------------------------------------------------------
// Randomness
// ------------------------------------------------------------------------------------------------

/// A reproducible RNG for randomised tests.
pub fn seeded_rng(seed: u64) -> Pcg64 {
    Pcg64::seed_from_u64(seed)
}

/// A log-uniform sample in `[lo, hi]` (both > 0) from a uniform `u ∈ [0, 1)`.
pub fn log_uniform(u: f64, lo: f64, hi: f64) -> f64 {
    (lo.ln() + u * (hi.ln() - lo.ln())).exp()
}

/// Fundamental frequency (Hz) of `signal` by autocorrelation: the shortest lag in
/// `[fs/f_max, fs/f_min]` whose correlation is within 10 % of the largest, refined by a parabola.
pub fn fundamental(signal: &[f64], fs: f64, f_min: f64, f_max: f64) -> f64 {
    let mean = signal.iter().sum::<f64>() / signal.len() as f64;
    let x: Vec<f64> = signal.iter().map(|v| v - mean).collect();
    let (lo, hi) = ((fs / f_max).floor() as usize, (fs / f_min).ceil() as usize + 1);
    let n = x.len() - hi - 1;
    let r: Vec<f64> = (0..=hi + 1).map(|lag| (0..n).map(|i| x[i] * x[i + lag]).sum()).collect();
    let peak = (lo..=hi).map(|l| r[l]).fold(f64::NEG_INFINITY, f64::max);
    let lag = (lo..=hi).find(|&l| r[l] >= 0.9 * peak && r[l] >= r[l - 1] && r[l] >= r[l + 1]).expect("a peak");
    let (a, b, c) = (r[lag - 1], r[lag], r[lag + 1]);
    fs / (lag as f64 + 0.5 * (a - c) / (a - 2.0 * b + c))
}

/// The string's displacement at a magnetic pickup (in the output's units times samples) from the
/// slide's output, which is the string's velocity there: its running sum. Its first partial
/// leads, as the string's does, where the velocity lifts the upper partials by their number.
pub fn displacement(velocity: &[f32]) -> Vec<f64> {
    velocity
        .iter()
        .scan(0.0, |sum, &v| {
            *sum += f64::from(v);
            Some(*sum)
        })
        .collect()
}

/// Frequency (Hz) of the largest spectral peak of `signal` between `f_lo` and `f_hi`: the
/// Hann-windowed DFT evaluated on a grid of 1/8 bin, refined by a parabola through the log
/// magnitudes around the maximum. Accurate to a small fraction of a bin for an isolated partial.
pub fn spectral_peak(signal: &[f64], fs: f64, f_lo: f64, f_hi: f64) -> f64 {
    let n = signal.len();
    let window: Vec<f64> =
        (0..n).map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / n as f64).cos()).collect();
    let magnitude = |f: f64| {
        let w = 2.0 * std::f64::consts::PI * f / fs;
        let (mut re, mut im) = (0.0, 0.0);
        for (i, (&x, &h)) in signal.iter().zip(&window).enumerate() {
            let (s, c) = (w * i as f64).sin_cos();
            re += x * h * c;
            im -= x * h * s;
        }
        (re * re + im * im).sqrt().max(f64::MIN_POSITIVE).ln()
    };
    let step = fs / n as f64 / 8.0;
    let grid: Vec<f64> = (0..).map(|k| f_lo + k as f64 * step).take_while(|&f| f <= f_hi).collect();
    let mags: Vec<f64> = grid.iter().map(|&f| magnitude(f)).collect();
    let best = (1..mags.len() - 1).max_by(|&a, &b| mags[a].total_cmp(&mags[b])).expect("a grid of 3 or more points");
    let (a, b, c) = (mags[best - 1], mags[best], mags[best + 1]);
    grid[best] + 0.5 * step * (a - c) / (a - 2.0 * b + c)
}

/// How much a short window of `x` stands out from its neighbourhood in its sample-to-sample
/// curvature: the click detector of the tests.
///
/// A click is a discontinuity the physics does not make: a step in the signal (a block-wise gain,
/// a voice cut off) or in its slope. Such a step puts a spike into the third difference
/// `r_n = x_n − 3x_{n−1} + 3x_{n−2} − x_{n−3}`, a high-pass (+18 dB/octave) that a band-limited
/// sound keeps small and smooth. The detector takes the energy of `r` in windows of 0.5 ms, and for each
/// window its ratio (dB) to the median of the windows within 10 ms on either side (leaving out
/// the window's immediate neighbours); it returns the largest ratio and the sample where that
/// window starts, skipping windows that overlap `exclude` (note attacks: a hammer's impact is the
/// sound, not a click). A floor 160 dB below full scale keeps silence from counting. It panics
/// when `exclude` leaves no window to judge: a test that judged nothing would pass whatever.
///
/// The threshold the tests use, [`CLICK_DB`], is set between what clean renders of this engine
/// give and what a small known step gives (see `tests/tests/instrument.rs`,
/// `the_click_detector_finds_a_small_step_and_passes_a_clean_render`).
pub fn click_strength(x: &[f64], fs: f64, exclude: &[std::ops::Range<usize>]) -> (f64, usize) {
    let w = ((0.0005 * fs).round() as usize).max(2);
    let reach = ((0.010 * fs) as usize / w).max(2);
    let residual: Vec<f64> = x.windows(4).map(|v| v[3] - 3.0 * v[2] + 3.0 * v[1] - v[0]).collect();
    let energy: Vec<f64> = residual.chunks(w).map(|c| c.iter().map(|r| r * r).sum::<f64>() / c.len() as f64).collect();
    let floor = 1e-16;
    let mut worst = (f64::NEG_INFINITY, 0);
    let mut around = Vec::with_capacity(2 * reach);
    for k in 0..energy.len() {
        let start = k * w;
        // The window's residuals read `x[start..start + w + 3]`.
        if exclude.iter().any(|e| e.start < start + w + 3 && start < e.end) {
            continue;
        }
        around.clear();
        let (lo, hi) = (k.saturating_sub(reach), (k + reach + 1).min(energy.len()));
        around.extend((lo..hi).filter(|&j| j + 1 < k || j > k + 1).map(|j| energy[j]));
        if around.is_empty() {
            continue;
        }
        around.sort_by(f64::total_cmp);
        let median = around[around.len() / 2];
        let db = 10.0 * ((energy[k] + floor) / (median + floor)).log10();
        if db > worst.0 {
            worst = (db, start);
        }
    }
    assert!(worst.0 > f64::NEG_INFINITY, "the exclusions leave no window of {} samples to judge", x.len());
    worst
}

/// The click threshold (dB of [`click_strength`]): clean renders of notes with their note-offs and
/// damper landings stay below it (at most 14.2 dB, bass to treble, pp to ff: A0 at fortissimo
/// 0.15 s after its damper lands, where the curvature's energy is 133 dB below full scale and
/// the neighbourhood's quieter still), and a step of 2 % of the note's peak added after its damper
/// lands is found above it (24.5 dB at least: D♯6, whose undamped partners D♯7 and A♯7, in tune
/// with its partials, ring on 41 dB below its peak), so it sits 5.8 dB above the one and 4.5 dB
/// below the other.
pub const CLICK_DB: f64 = 20.0;

#[cfg(test)]
mod tests {
    use super::*;

    /// A step left out of the search is left out of every window whose residuals read it: at
    /// 48 kHz (windows of 24 samples), silence and then a step at sample 50 that the search
    /// excludes from there on leaves nothing to find, though the window starting at sample 24
    /// reads sample 50 in its last residual.
    #[test]
    fn an_excluded_step_is_left_out_of_every_window_that_reads_it() {
        let x: Vec<f64> = (0..2_000).map(|i| if i < 50 { 0.0 } else { 1.0 }).collect();
        let step = 50..400;
        let (db, at) = click_strength(&x, 48_000.0, std::slice::from_ref(&step));
        assert!(db < CLICK_DB, "{db} dB at {at}");
        let (db, at) = click_strength(&x, 48_000.0, &[]);
        assert!(db > CLICK_DB, "not excluded, the step is found: {db} dB at {at}");
    }

    #[test]
    fn gamma_matches_known_values() {
        assert!((gamma(1.0) - 1.0).abs() < 1e-14);
        assert!((gamma(5.0) - 24.0).abs() < 1e-12);
        assert!((gamma(0.5) - std::f64::consts::PI.sqrt()).abs() < 1e-14);
    }
}
