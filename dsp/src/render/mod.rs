//! Offline render of a scene description, shared by `cargo xtask render`, the test harness and
//! (later) the plugin's MIDI renderer.
//!
//! [`parse_scene`] turns a scene file into a validated [`SceneDescription`]; [`render`] runs it in
//! calls of the sizes a chunk iterator gives (the frames are bit-identical for any chunking) and
//! returns every sample's [`Frame`] with a [`Summary`].

mod file;
mod strings;
mod summary;

pub use file::{
    Common, FORMAT_VERSION, MAX_DURATION, MAX_SAMPLES, MAX_SEGMENTS, MassBarrierDescription, OutputOptions,
    SCENE_KINDS, SceneDescription, parse_scene,
};
pub use strings::{HammerStringDescription, MAX_BLOCK, SlideStringDescription};
pub use summary::{Summary, contact_intervals};

use std::time::Instant;

use crate::contact::{ContactError, ContactSolver, WithSolver};
use crate::control::Fixed;
use crate::scene::{Frame, HammerString, MassBarrier, Scene, SlideString};
use crate::string::ModalString;

/// A scene file that cannot be rendered.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// Not valid TOML, a key of the wrong type, or a key the format does not have.
    #[error("{0}")]
    Syntax(String),
    /// A value out of its domain.
    #[error("{key}: {reason}")]
    Invalid {
        /// Dotted key path, e.g. `mass.mass`.
        key: String,
        /// What is wrong.
        reason: String,
    },
}

impl SceneError {
    pub(crate) fn invalid(key: &str, reason: impl Into<String>) -> Self {
        Self::Invalid { key: key.to_owned(), reason: reason.into() }
    }

    /// Map a contact-parameter error to the scene key it came from (`table.key`).
    pub(crate) fn contact(table: &str, error: ContactError) -> Self {
        match error {
            ContactError::Invalid { key, reason, value } => {
                let key = match key {
                    "segments" | "v_ref" => format!("solver.{key}"),
                    _ => format!("{table}.{key}"),
                };
                Self::Invalid { key, reason: format!("{reason} (got {value})") }
            }
            e @ ContactError::NotConvex { .. } => Self::invalid("solver.segments", e.to_string()),
        }
    }
}

/// A finished render.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// One frame per sample.
    pub frames: Vec<Frame>,
    /// What the render measured.
    pub summary: Summary,
}

/// Render `scene`, advancing in calls of the sizes `chunks` yields (sizes of 0 are skipped;
/// when the iterator ends, the rest is rendered in one call).
pub fn render(scene: &SceneDescription, chunks: impl Iterator<Item = usize>) -> Result<Rendered, SceneError> {
    let run = dispatch(scene, FramesJob { chunks })?;
    let summary = Summary::measure(scene, &run);
    Ok(Rendered { frames: run.frames, summary })
}

/// Render only the audio output of `scene` in calls of `chunk` samples, the way a plugin runs a
/// voice: no per-sample frames, no energy bookkeeping. Returns the output and the wall-clock
/// time spent computing it (s).
pub fn render_output(scene: &SceneDescription, chunk: usize) -> Result<(Vec<f64>, f64), SceneError> {
    dispatch(scene, OutputJob { chunk: chunk.max(1) })
}

/// Build `scene` around the solver its settings name and hand it to `job`.
fn dispatch<J: Job>(scene: &SceneDescription, job: J) -> Result<J::Output, SceneError> {
    fn build<W: WithSolver>(common: &Common, v_ref: f64, work: W) -> Result<W::Output, SceneError> {
        common.solver.build(common.law, v_ref, work).map_err(|e| SceneError::contact("contact", e))
    }
    let common = scene.common();
    match scene {
        SceneDescription::MassBarrier(d) => build(common, d.default_v_ref(), Build { scene: d, job }),
        SceneDescription::HammerString(d) => build(common, d.default_v_ref(), Build { scene: d, job }),
        SceneDescription::SlideString(d) => build(common, d.default_v_ref(), Build { scene: d, job }),
    }
}

/// The raw result of driving a scene.
#[derive(Debug, Clone)]
pub struct Run {
    /// One frame per sample.
    pub frames: Vec<Frame>,
    /// `H^{−1/2}` (J).
    pub initial_energy: f64,
    /// Wall-clock time spent in [`Scene::process`] (s).
    pub wall_seconds: f64,
    /// QSA segment count (0 for the other methods).
    pub segments: usize,
}

/// What to do with a scene once it is built.
trait Job {
    type Output;
    fn run(self, scene: impl Scene, samples: usize, segments: usize) -> Self::Output;
}

/// Every frame, in calls of the sizes an iterator gives.
struct FramesJob<I> {
    chunks: I,
}

impl<I: Iterator<Item = usize>> Job for FramesJob<I> {
    type Output = Run;

    fn run(mut self, mut scene: impl Scene, samples: usize, segments: usize) -> Run {
        let initial_energy = scene.initial_energy();
        let mut frames = vec![Frame::default(); samples];
        let start = Instant::now();
        let mut done = 0;
        while done < samples {
            let n = match self.chunks.next() {
                Some(0) => continue,
                Some(n) => n.min(samples - done),
                None => samples - done,
            };
            scene.process(&mut frames[done..done + n]);
            done += n;
        }
        Run { frames, initial_energy, wall_seconds: start.elapsed().as_secs_f64(), segments }
    }
}

/// The output signal only, in calls of a fixed size.
struct OutputJob {
    chunk: usize,
}

impl Job for OutputJob {
    type Output = (Vec<f64>, f64);

    fn run(self, mut scene: impl Scene, samples: usize, _segments: usize) -> (Vec<f64>, f64) {
        let mut out = vec![0.0; samples];
        // Write every page before the clock starts (a fresh zeroed allocation is mapped lazily):
        // a host's buffers are mapped already, so first-touch page faults are not the scene's cost.
        out.fill(std::hint::black_box(0.0));
        let start = Instant::now();
        for block in out.chunks_mut(self.chunk) {
            scene.process_output(block);
        }
        (out, start.elapsed().as_secs_f64())
    }
}

/// Builds one kind of scene description around whichever solver it is handed, then runs a job.
struct Build<'a, D, J> {
    scene: &'a D,
    job: J,
}

impl<J: Job> WithSolver for Build<'_, MassBarrierDescription, J> {
    type Output = J::Output;

    fn run<S: ContactSolver>(self, solver: S) -> J::Output {
        let (common, segments) = (&self.scene.common, solver.segments());
        let scene = MassBarrier::new(self.scene.params, f64::from(common.sample_rate), solver);
        self.job.run(scene, common.samples, segments)
    }
}

impl<J: Job> WithSolver for Build<'_, HammerStringDescription, J> {
    type Output = J::Output;

    fn run<S: ContactSolver>(self, solver: S) -> J::Output {
        let (common, segments) = (&self.scene.common, solver.segments());
        let string = prepared_string(&self.scene.params.string, common.sample_rate);
        let scene = HammerString::new(string, &self.scene.params, solver);
        self.job.run(scene, common.samples, segments)
    }
}

impl<J: Job> WithSolver for Build<'_, SlideStringDescription, J> {
    type Output = J::Output;

    fn run<S: ContactSolver>(self, solver: S) -> J::Output {
        let d = self.scene;
        let (common, segments) = (&d.common, solver.segments());
        let string = prepared_string(&d.params.string, common.sample_rate);
        // Constant controls get the scene type that never recomputes its vectors.
        if d.controls.is_constant() {
            let fixed = Fixed(d.controls.at_time(0.0));
            self.job.run(SlideString::new(string, &d.params, solver, fixed), common.samples, segments)
        } else {
            let scene = SlideString::new(string, &d.params, solver, d.controls.clone());
            self.job.run(scene, common.samples, segments)
        }
    }
}

/// A string prepared at `sample_rate`; its parameters were validated with the scene.
fn prepared_string(params: &crate::string::StringParams, sample_rate: u32) -> ModalString {
    ModalString::new(*params, f64::from(sample_rate)).expect("string parameters are validated when the scene is parsed")
}
