//! The report's simulations: one physical set-up rendered at any oversampling with any solver.
//!
//! A [`Setup`] is a scene's physical description at its base rate `fs` (Hz). Oversampling by `k`
//! renders the same set-up at `k·fs` for `k` times as many samples, so sample `n·k` of the
//! oversampled render and sample `n` of the base render lie at the same instant `t = n/fs`
//! (every scene starts its time axis at `u^0`, `t = 0`).
//!
//! - **Strings keep the modes of the base rate.** A string is prepared with
//!   [`ModalString::band_limited`] at `f_max = fs/2`, so at every `k` it has exactly the modes the
//!   base render has. Oversampling then refines only the time step (and the contact solve), and the
//!   converged reference is the same modal system at a fine step. (The plain renderer keeps every
//!   mode below the oversampled Nyquist instead; the extra modes ring above 20 kHz, and the bridge
//!   force weights them by `Tβ_i + EIβ_i³`, so they would dominate an output-signal comparison.)
//! - **Slide controls keep their timing.** Automation is in seconds and is re-sampled at `k·fs`,
//!   and the control block `N_b` is multiplied by `k`, so blocks start at the same instants.
//!
//! Two jobs run on a built scene: `Frames` (every per-sample [`Frame`], with energy
//! bookkeeping) and `Timed` (the real-time path, [`Scene::process_output`] in calls of 64
//! samples with no bookkeeping, timed with the wall clock). At `k = 1` a string has exactly the
//! modes the renderer gives it (every mode below Nyquist), so the stability sweep builds its
//! scenes here too.

use std::time::Instant;

use qsa_dsp::contact::{ContactSolver, PowerLaw, SolverSettings, WithSolver};
use qsa_dsp::scene::{Frame, HammerString, HammerStringParams, MassBarrier, MassBarrierParams, Scene, SlideString};
use qsa_dsp::scene::{SlideAutomation, SlideStringParams};
use qsa_dsp::string::ModalString;

/// Samples per call of the real-time path, as a plugin would run a voice.
pub const CHUNK: usize = 64;

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
        self.build(settings, k, Frames).0
    }

    /// Every frame and the initial numerical energy `H^{−1/2}` (J) of a render with `settings` at
    /// `k` times the base rate.
    pub fn frames_and_energy(&self, settings: SolverSettings, k: usize) -> (Vec<Frame>, f64) {
        self.build(settings, k, Frames)
    }

    /// Wall-clock seconds of one render through the real-time path.
    pub fn timed(&self, settings: SolverSettings, k: usize) -> f64 {
        self.build(settings, k, Timed)
    }

    fn build<J: Job>(&self, settings: SolverSettings, k: usize, job: J) -> J::Output {
        settings
            .build(self.law, self.v_ref, Build { case: self, k, job })
            .expect("the report's cases have valid contact parameters")
    }
}

/// What to do with a built scene.
trait Job {
    type Output;
    fn run(self, scene: impl Scene, samples: usize) -> Self::Output;
}

/// Every frame, and the initial energy.
struct Frames;

impl Job for Frames {
    type Output = (Vec<Frame>, f64);

    fn run(self, mut scene: impl Scene, samples: usize) -> (Vec<Frame>, f64) {
        let initial = scene.initial_energy();
        let mut frames = vec![Frame::default(); samples];
        scene.process(&mut frames);
        (frames, initial)
    }
}

/// The output only, in calls of [`CHUNK`] samples; returns the wall seconds spent processing.
struct Timed;

impl Job for Timed {
    type Output = f64;

    fn run(self, mut scene: impl Scene, samples: usize) -> f64 {
        let mut out = vec![0.0; samples];
        let start = Instant::now();
        for block in out.chunks_mut(CHUNK) {
            scene.process_output(block);
        }
        let wall = start.elapsed().as_secs_f64();
        std::hint::black_box(&out);
        wall
    }
}

struct Build<'a, J> {
    case: &'a CaseScene,
    k: usize,
    job: J,
}

impl<J: Job> WithSolver for Build<'_, J> {
    type Output = J::Output;

    fn run<S: ContactSolver>(self, solver: S) -> J::Output {
        let case = self.case;
        let base = f64::from(case.sample_rate);
        let fs = base * self.k as f64;
        let samples = case.samples * self.k;
        let string = |params| {
            ModalString::band_limited(params, fs, 0.5 * base).expect("the report's strings have valid parameters")
        };
        match &case.setup {
            Setup::MassBarrier(params) => self.job.run(MassBarrier::new(*params, fs, solver), samples),
            Setup::Hammer(params) => self.job.run(HammerString::new(string(params.string), params, solver), samples),
            Setup::Slide(params, controls) => {
                let params = SlideStringParams { block: params.block * self.k, ..*params };
                let controls = SlideAutomation::new(controls.lanes.clone(), fs);
                self.job.run(SlideString::new(string(params.string), &params, solver, controls), samples)
            }
        }
    }
}
