//! Fig. 4-style trajectories: the mass–barrier with its entry shifted by sub-sample phases.
//!
//! The seed's Fig. 4 point (docs/physics.md §4.4): a mass that reaches the barrier at a different phase
//! within a sample only time-shifts the IMP and QSA trajectories, because both solve an
//! autonomous energy-conserving implicit scheme; EXP's trajectory changes shape, because its
//! gradient `g^n` is evaluated at `y^n` and so depends on where the samples fall.
//!
//! For phase `φ ∈ [0, 1)` the initial displacement is `u0 + φ·v0·Δt`, so the approach line
//! `y(t) = y^0 + v0·t` crosses zero at `t_in = −y^0/v0`. Each run goes on until the contact has
//! ended and [`TAIL`] free samples have followed. Plotted: `y^n` against `(nΔt − t_in)/Δt`, for
//! [`PLOTTED_PHASES`] phases. Measured, over [`PHASES`] phases: the effective contact time between
//! the zero crossings of the free-flight lines, `t_out − t_in`, with `t_out = t_N − y^N/v^N` from
//! the last sample after the contact (the line through the last two samples), and its spread
//! (max − min) in samples: 0 for a scheme whose trajectories are pure time shifts.

use qsa_dsp::contact::{ContactSolver, ExplicitSolver, NewtonSolver, QsaSolver, QuadSpline};
use qsa_dsp::scene::{Frame, MassBarrier, MassBarrierParams, Scene};

use super::sim::{CaseScene, Setup};

/// The spreads of the effective contact time (samples) that docs/physics.md §4.4 quotes from the
/// prototype, per scheme, to compare with this study's.
pub const PHYSICS_DOC_SPREADS: [(&str, f64); 4] =
    [("IMP", 0.001), ("QSA N=5", 0.008), ("QSA N=20", 0.003), ("EXP", 1.03)];

/// Phases for the spread of the contact time.
pub const PHASES: usize = 40;

/// Phases drawn in the plot.
pub const PLOTTED_PHASES: usize = 8;

/// Free samples kept after the contact.
pub const TAIL: usize = 10;

/// Longest run (samples).
const MAX_STEPS: usize = 100_000;

/// One scheme's trajectories and contact-time spread.
#[derive(Debug, Clone)]
pub struct SchemeTrajectories {
    /// e.g. `QSA N=5`.
    pub label: String,
    /// For each plotted phase: `((nΔt − t_in)/Δt, y^n in µm)`.
    pub curves: Vec<Vec<(f64, f64)>>,
    /// Shortest and longest effective contact time over [`PHASES`] phases (samples).
    pub contact_samples: (f64, f64),
}

impl SchemeTrajectories {
    /// Spread of the effective contact time (samples).
    pub fn spread(&self) -> f64 {
        self.contact_samples.1 - self.contact_samples.0
    }
}

/// The study on the Fig. 4 scene.
#[derive(Debug, Clone)]
pub struct Fig4Study {
    /// IMP, QSA N = 5, QSA N = 20, EXP.
    pub schemes: Vec<SchemeTrajectories>,
    /// Sample rate (Hz).
    pub sample_rate: f64,
}

fn run<S: ContactSolver>(params: MassBarrierParams, fs: f64, solver: S) -> Vec<Frame> {
    let mut scene = MassBarrier::new(params, fs, solver);
    let mut frames = Vec::new();
    let mut frame = [Frame::default()];
    let (mut touched, mut free) = (false, 0);
    while frames.len() < MAX_STEPS && free < TAIL {
        scene.process(&mut frame);
        frames.push(frame[0]);
        if frame[0].compression > 0.0 || frame[0].force != 0.0 {
            touched = true;
            free = 0;
        } else if touched {
            free += 1;
        }
    }
    frames
}

fn scheme<S: ContactSolver>(label: &str, base: MassBarrierParams, fs: f64, make: impl Fn() -> S) -> SchemeTrajectories {
    let dt = 1.0 / fs;
    let mut curves = Vec::new();
    let (mut shortest, mut longest) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..PHASES {
        let phase = i as f64 / PHASES as f64;
        let params = MassBarrierParams { u0: base.u0 + phase * base.v0 * dt, ..base };
        let frames = run(params, fs, make());
        let t_in = -(params.u0 - params.barrier) / params.v0;
        let last = frames.len() - 1;
        let t_out = last as f64 * dt - frames[last].compression / frames[last].velocity;
        let samples = (t_out - t_in) / dt;
        shortest = shortest.min(samples);
        longest = longest.max(samples);
        if i % (PHASES / PLOTTED_PHASES) == 0 {
            curves.push(
                frames.iter().enumerate().map(|(n, f)| ((n as f64 * dt - t_in) / dt, f.compression * 1e6)).collect(),
            );
        }
    }
    SchemeTrajectories { label: label.to_owned(), curves, contact_samples: (shortest, longest) }
}

/// Run the study on `case` (a mass–barrier case).
pub fn study(case: &CaseScene) -> Fig4Study {
    let Setup::MassBarrier(params) = case.setup else {
        panic!("the Fig. 4 study needs a mass-barrier case");
    };
    let fs = f64::from(case.sample_rate);
    let law = case.law;
    let qsa = |n| move || QsaSolver::new(QuadSpline::from_reference_energy(law, case.v_ref, n).expect("a valid fit"));
    Fig4Study {
        schemes: vec![
            scheme("IMP", params, fs, || NewtonSolver::new(law)),
            scheme("QSA N=5", params, fs, qsa(5)),
            scheme("QSA N=20", params, fs, qsa(20)),
            scheme("EXP", params, fs, || ExplicitSolver::new(law)),
        ],
        sample_rate: fs,
    }
}
