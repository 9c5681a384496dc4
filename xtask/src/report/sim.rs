//! The report's simulations: one physical set-up rendered at any oversampling with any solver.
//!
//! A [`Setup`] is a scene's physical description at its base rate `fs` (Hz). Oversampling by `k`
//! renders the same set-up at `k·fs` for `k` times as many samples, so sample `n·k` of the
//! oversampled render and sample `n` of the base render lie at the same instant `t = n/fs`
//! (every scene starts its time axis at `u^0`, `t = 0`).
//!
//! - **Strings keep the modes of the base rate.** A string is prepared with
//!   [`ModalString::band_limited`](qsa_dsp::string::ModalString::band_limited) at `f_max = fs/2`,
//!   so at every `k` it has exactly the modes the base render has. Oversampling then refines only
//!   the time step (and the contact solve), and the converged reference is the same modal system
//!   at a fine step. (The plain renderer keeps every mode below the oversampled Nyquist instead;
//!   the extra modes ring above 20 kHz, and the bridge force weights them by `Tβ_i + EIβ_i³`, so
//!   they would dominate an output-signal comparison.)
//! - **Slide controls keep their timing.** Automation is in seconds and is re-sampled at `k·fs`,
//!   and the control block `N_b` is multiplied by `k`, so blocks start at the same instants.
//!
//! The scenes are built by the scene builder ([`qsa_dsp::scene_file::build()`], with
//! [`Sampling::oversampled`]) from the [`SceneDescription`] of the set-up, and run either for
//! every per-sample [`Frame`] (with energy bookkeeping) or through the real-time path, timed
//! ([`TimedOutput`], in calls of [`CALL_SAMPLES`] samples). At `k = 1` a string has exactly the modes
//! the renderer gives it (every mode below Nyquist), so the stability sweep builds its scenes here
//! too.

use qsa_dsp::contact::{Method, PowerLaw, SolverSettings};
use qsa_dsp::scene::{Frame, HammerStringParams, MassBarrierParams, SlideStringParams};
use qsa_dsp::scene_file::{
    Common, Frames, HammerStringDescription, MassBarrierDescription, OutputOptions, Sampling, SceneDescription,
    SceneJob, SlideAutomation, SlideStringDescription, build,
};

use crate::bench::TimedOutput;

/// Samples per call of the real-time path, as a plugin would run a voice.
pub const CALL_SAMPLES: usize = 64;

/// A physical set-up: the scene kind and its parameters.
#[derive(Debug, Clone)]
// A handful per report: boxing the slide variant would buy nothing.
#[allow(clippy::large_enum_variant)]
pub enum Setup {
    /// Mass on a rigid barrier.
    MassBarrier(MassBarrierParams),
    /// Hammer on a modal string.
    Hammer(HammerStringParams),
    /// Slide on a modal string, with its control automation (times in s).
    Slide(SlideStringParams, SlideAutomation),
}

/// A set-up with its contact law, base rate, length and QSA reference energy.
#[derive(Debug, Clone)]
pub struct CaseScene {
    /// The bodies.
    pub setup: Setup,
    /// The contact law.
    pub law: PowerLaw,
    /// Base sample rate fs (Hz).
    pub sample_rate: u32,
    /// Samples at the base rate.
    pub samples: usize,
    /// QSA reference energy V_ref (J): the scene file's default for this set-up.
    pub v_ref: f64,
}

impl CaseScene {
    /// Simulated duration (s).
    pub fn seconds(&self) -> f64 {
        self.samples as f64 / f64::from(self.sample_rate)
    }

    /// Reference compression `y_ref` (m) that V_ref gives (seed eq. 5).
    pub fn y_ref(&self) -> f64 {
        self.law.compression_at_energy(self.v_ref)
    }

    /// The same set-up with the exciter's initial speed (mass–barrier, hammer) or mass (slide)
    /// scaled by `1 + rel`: a perturbation of the size of a few rounding errors, to measure how
    /// sensitive a result is to rounding.
    pub fn perturbed(&self, rel: f64) -> CaseScene {
        let mut out = self.clone();
        match &mut out.setup {
            Setup::MassBarrier(p) => p.v0 *= 1.0 + rel,
            Setup::Hammer(p) => p.hammer.velocity *= 1.0 + rel,
            Setup::Slide(p, _) => p.slide.mass *= 1.0 + rel,
        }
        out
    }

    /// Every frame of a render with `settings` at `k` times the base rate.
    pub fn frames(&self, settings: SolverSettings, k: usize) -> Vec<Frame> {
        self.frames_and_energy(settings, k).0
    }

    /// Every frame and the initial numerical energy `H^{−1/2}` (J) of a render with `settings` at
    /// `k` times the base rate.
    pub fn frames_and_energy(&self, settings: SolverSettings, k: usize) -> (Vec<Frame>, f64) {
        let run = self.build(settings, k, Frames { chunks: std::iter::empty() });
        (run.frames, run.initial_energy)
    }

    /// Wall-clock seconds of one render through the real-time path.
    pub fn timed(&self, settings: SolverSettings, k: usize) -> f64 {
        self.build(settings, k, TimedOutput { chunk: CALL_SAMPLES })
    }

    /// The set-up as a scene description at the base rate; its solver is QSA at the case's
    /// V_ref, and `Self::build` names the solver of each run.
    pub fn description(&self) -> SceneDescription {
        let common = Common {
            sample_rate: self.sample_rate,
            samples: self.samples,
            solver: SolverSettings { method: Method::Qsa, segments: 5, v_ref: Some(self.v_ref) },
            law: self.law,
            output: OutputOptions { normalize: true, gain: 1.0 },
        };
        match &self.setup {
            Setup::MassBarrier(params) => {
                SceneDescription::MassBarrier(MassBarrierDescription { common, params: *params })
            }
            Setup::Hammer(params) => {
                SceneDescription::HammerString(HammerStringDescription { common, params: *params })
            }
            Setup::Slide(params, controls) => SceneDescription::SlideString(SlideStringDescription {
                common,
                params: *params,
                controls: controls.clone(),
                body: None,
            }),
        }
    }

    /// Build the set-up with `settings` (V_ref falling back to the case's) at `k` times the base
    /// rate, the strings keeping the modes of the base rate, and run `job` on it.
    fn build<J: SceneJob>(&self, settings: SolverSettings, k: usize, job: J) -> J::Output {
        let solver = SolverSettings { v_ref: settings.v_ref.or(Some(self.v_ref)), ..settings };
        build(&self.description(), &solver, Sampling::oversampled(k, self.sample_rate), job)
            .expect("the report's cases have valid contact parameters")
    }
}
