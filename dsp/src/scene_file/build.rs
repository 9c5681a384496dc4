//! The scene builder: a scene description and a solver choice become a runnable [`Scene`].
//!
//! [`build`] picks the contact solver once from [`SolverSettings`] (so the scene then runs fully
//! monomorphised, with no dynamic dispatch per sample), prepares the string, and hands the built
//! scene to a [`SceneJob`], which drives it. The renderer, the report, the bench and the tests all
//! build their scenes here; what they do with a scene (frames, output only, timing) is their job.
//!
//! A description can run at its own rate or oversampled ([`Sampling`]): at `k·fs` for `k` times as
//! many samples, so sample `n·k` of the oversampled run and sample `n` of the base run lie at the
//! same instant `t = n/fs`. Slide automation is in seconds and is re-sampled at `k·fs`, and the
//! control block `N_b` becomes `k·N_b`, so blocks start at the same instants. A slide scene whose
//! controls are all constant gets the scene type that never recomputes its vectors.

use super::automation::SlideAutomation;
use super::error::SceneError;
use super::mass_barrier::MassBarrierDescription;
use super::parse::SceneDescription;
use super::string_scenes::{HammerStringDescription, SlideStringDescription};
use crate::body::BodyParams;
use crate::contact::{ContactError, ContactSolver, Method, SolverSettings, WithSolver};
use crate::control::{ControlSource, Fixed};
use crate::scene::{Frame, HammerString, MassBarrier, Scene, SlideControls, SlideString, SlideStringParams};
use crate::string::{MAX_MODES, ModalString, StringParams};

/// What to do with a scene once it is built.
pub trait SceneJob {
    /// What the job returns.
    type Output;
    /// Drive `scene` for `samples` samples; `segments` is the QSA segment count N (0 for the
    /// other methods).
    fn run(self, scene: impl Scene, samples: usize, segments: usize) -> Self::Output;
}

/// The rate a description runs at, and which string modes it keeps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sampling {
    /// Oversampling factor `k ≥ 1`: the scene runs at `k·fs` for `k` times as many samples.
    pub oversampling: usize,
    /// Highest mode frequency a string keeps (Hz), besides the limit of the (oversampled)
    /// Nyquist frequency; `f64::INFINITY` keeps every mode below Nyquist.
    pub max_frequency: f64,
}

impl Sampling {
    /// The description's own rate, every string mode below its Nyquist frequency (the renderer).
    pub const NATIVE: Sampling = Sampling { oversampling: 1, max_frequency: f64::INFINITY };

    /// `k` times the base rate `fs` (Hz), the strings keeping exactly the modes below the base
    /// Nyquist `fs/2`: oversampling refines the time step only, not the modal system.
    pub fn oversampled(k: usize, fs: u32) -> Sampling {
        Sampling { oversampling: k, max_frequency: 0.5 * f64::from(fs) }
    }
}

/// Build `scene` around the solver `solver` names (its `v_ref`, when `None`, falls back to the
/// scene's default), sampled as `sampling` says, and hand it to `job`.
pub fn build<J: SceneJob>(
    scene: &SceneDescription,
    solver: &SolverSettings,
    sampling: Sampling,
    job: J,
) -> Result<J::Output, SceneError> {
    let common = scene.common();
    let (law, k) = (common.law, sampling.oversampling.max(1));
    let fs = f64::from(common.sample_rate) * k as f64;
    let run = Build { fs, samples: common.samples * k, k, max_frequency: sampling.max_frequency, job };
    // A string's parameters are checked with the scene; how many modes it has below the band
    // depends on the rate too.
    let string = match scene {
        SceneDescription::MassBarrier(_) => None,
        SceneDescription::HammerString(d) => Some(d.params.string),
        SceneDescription::SlideString(d) => Some(d.params.string),
    };
    if let Some(params) = string {
        let modes = ModalString::count_modes(params, fs, sampling.max_frequency)
            .map_err(|e| SceneError::invalid(&format!("string.{}", e.key), e.reason))?;
        // The string may be a preset's, and the rate counts as much as its length: the error
        // names the table and the rate, and says what moves the count either way.
        let limit = if sampling.max_frequency < 0.5 * fs {
            format!("{} Hz, the band limit", sampling.max_frequency)
        } else {
            format!("{} Hz, Nyquist at sample_rate = {}", 0.5 * fs, common.sample_rate)
        };
        if modes == 0 {
            return Err(SceneError::invalid(
                "string",
                format!(
                    "the string (fundamental {:.1} Hz) has no mode below {limit}: it would be silent; lengthen \
                     it, lower its tension or raise sample_rate",
                    params.fundamental()
                ),
            ));
        }
        if modes > MAX_MODES {
            return Err(SceneError::invalid(
                "string",
                format!(
                    "the string has more than {MAX_MODES} modes below {limit}; shorten it, raise its tension or \
                     lower sample_rate"
                ),
            ));
        }
    }
    let default_v_ref = scene.default_v_ref();
    // The default is the scene's own energy: when it leaves the floats, the fault is in the
    // values it comes from, not in a key the file does not have.
    if solver.method == Method::Qsa && solver.v_ref.is_none() && !(default_v_ref.is_finite() && default_v_ref > 0.0) {
        return Err(SceneError::invalid(
            "solver.v_ref",
            format!(
                "not given, and its default, the largest energy the scene can put into the contact, is \
                 {default_v_ref:e} J: the scene's masses, speeds or pushes leave the range a float holds"
            ),
        ));
    }
    let built = match scene {
        SceneDescription::MassBarrier(d) => solver.build(law, default_v_ref, Described { scene: d, run }),
        SceneDescription::HammerString(d) => solver.build(law, default_v_ref, Described { scene: d, run }),
        SceneDescription::SlideString(d) => solver.build(law, default_v_ref, Described { scene: d, run }),
    };
    built.map_err(|e| match e {
        // The default's energy is in the floats, but the compression it reaches under this law
        // is not: the fault is again in the values it comes from.
        ContactError::Invalid { key: "v_ref", value, .. } if solver.v_ref.is_none() => SceneError::invalid(
            "solver.v_ref",
            format!(
                "not given, and its default, the largest energy the scene can put into the contact \
                 ({default_v_ref:e} J), compresses this contact law beyond the range a float holds (got \
                 {value:e}): the scene's masses, speeds or contact.kappa are too far apart"
            ),
        ),
        e => SceneError::contact("contact", e),
    })
}

/// Every frame of a run, and its initial energy.
#[derive(Debug, Clone)]
pub struct Run {
    /// One frame per sample.
    pub frames: Vec<Frame>,
    /// `H^{−1/2}` (J).
    pub initial_energy: f64,
    /// QSA segment count (0 for the other methods).
    pub segments: usize,
}

/// Advance `scene` over `frames` in calls of the sizes `chunks` yields (sizes of 0 are skipped;
/// when the iterator ends, the rest goes in one call, as it does once it has given as many sizes
/// of 0 as there are frames). The frames are the same for any chunking.
pub fn fill_frames(scene: &mut impl Scene, frames: &mut [Frame], mut chunks: impl Iterator<Item = usize>) {
    let samples = frames.len();
    let (mut done, mut zeros) = (0, 0);
    while done < samples {
        let n = match chunks.next() {
            Some(0) if zeros < samples => {
                zeros += 1;
                continue;
            }
            Some(n) if n > 0 => n.min(samples - done),
            _ => samples - done,
        };
        scene.process(&mut frames[done..done + n]);
        done += n;
    }
}

/// Job: every frame, in calls of the sizes an iterator gives (see [`fill_frames`]).
#[derive(Debug)]
pub struct Frames<I> {
    /// Call sizes.
    pub chunks: I,
}

impl<I: Iterator<Item = usize>> SceneJob for Frames<I> {
    type Output = Run;

    fn run(self, mut scene: impl Scene, samples: usize, segments: usize) -> Run {
        let initial_energy = scene.initial_energy();
        let mut frames = vec![Frame::default(); samples];
        fill_frames(&mut scene, &mut frames, self.chunks);
        Run { frames, initial_energy, segments }
    }
}

/// Job: the output signal only, the way a plugin runs a voice ([`Scene::process_output`] in
/// calls of `chunk` samples, no frames, no energy bookkeeping).
#[derive(Debug)]
pub struct OutputOnly {
    /// Samples per call (at least 1).
    pub chunk: usize,
}

impl SceneJob for OutputOnly {
    type Output = Vec<f64>;

    fn run(self, mut scene: impl Scene, samples: usize, _segments: usize) -> Vec<f64> {
        let mut out = vec![0.0; samples];
        for block in out.chunks_mut(self.chunk.max(1)) {
            scene.process_output(block);
        }
        out
    }
}

/// The rate, length and string band of a build, with the job to run.
struct Build<J> {
    fs: f64,
    samples: usize,
    k: usize,
    max_frequency: f64,
    job: J,
}

impl<J> Build<J> {
    /// A string prepared at the build's rate; its parameters were validated with the scene, and
    /// its modes counted at this rate by [`build`].
    fn string(&self, params: StringParams) -> ModalString {
        ModalString::band_limited(params, self.fs, self.max_frequency)
            .expect("string parameters are validated with the scene and at the build's rate")
    }
}

/// One kind of scene description with the build that turns it into a scene.
struct Described<'a, D, J> {
    scene: &'a D,
    run: Build<J>,
}

impl<J: SceneJob> WithSolver for Described<'_, MassBarrierDescription, J> {
    type Output = J::Output;

    fn run<S: ContactSolver>(self, solver: S) -> J::Output {
        let (run, segments) = (self.run, solver.segments());
        run.job.run(MassBarrier::new(self.scene.params, run.fs, solver), run.samples, segments)
    }
}

impl<J: SceneJob> WithSolver for Described<'_, HammerStringDescription, J> {
    type Output = J::Output;

    fn run<S: ContactSolver>(self, solver: S) -> J::Output {
        let (params, segments) = (&self.scene.params, solver.segments());
        let string = self.run.string(params.string);
        let run = self.run;
        run.job.run(HammerString::new(string, params, solver), run.samples, segments)
    }
}

impl<J: SceneJob> WithSolver for Described<'_, SlideStringDescription, J> {
    type Output = J::Output;

    fn run<S: ContactSolver>(self, solver: S) -> J::Output {
        let d = self.scene;
        let segments = solver.segments();
        let params = SlideStringParams { block: d.params.block * self.run.k, ..d.params };
        let string = self.run.string(params.string);
        let run = self.run;
        if d.controls.is_constant() {
            let fixed = Fixed(d.controls.at_time(0.0));
            run.job.run(on_body(SlideString::new(string, &params, solver, fixed), &d.body), run.samples, segments)
        } else {
            let controls = SlideAutomation::new(d.controls.lanes.clone(), run.fs);
            run.job.run(on_body(SlideString::new(string, &params, solver, controls), &d.body), run.samples, segments)
        }
    }
}

/// `scene` with its string's far end on `body`, if one is given.
fn on_body<S: ContactSolver, C: ControlSource<SlideControls>>(
    scene: SlideString<S, C>,
    body: &Option<BodyParams>,
) -> SlideString<S, C> {
    match body {
        Some(body) => scene.with_body(body),
        None => scene,
    }
}
