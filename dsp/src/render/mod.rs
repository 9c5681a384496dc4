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
    Common, FORMAT_VERSION, MAX_DURATION, MAX_SAMPLES, MAX_SEGMENTS, MassBarrierDescription, OutputOptions, SCENE_KINDS,
    SceneDescription, parse_scene,
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
    let common = scene.common();
    fn build<W: WithSolver>(common: &Common, v_ref: f64, work: W) -> Result<W::Output, SceneError> {
        common.solver.build(common.law, v_ref, work).map_err(|e| SceneError::contact("contact", e))
    }
    let run = match scene {
        SceneDescription::MassBarrier(d) => build(common, d.default_v_ref(), Render { scene: d, chunks })?,
        SceneDescription::HammerString(d) => build(common, d.default_v_ref(), Render { scene: d, chunks })?,
        SceneDescription::SlideString(d) => build(common, d.default_v_ref(), Render { scene: d, chunks })?,
    };
    let summary = Summary::measure(scene, &run);
    Ok(Rendered { frames: run.frames, summary })
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

/// Drive `scene` for `samples` samples in calls of the sizes `chunks` yields.
pub fn drive(mut scene: impl Scene, samples: usize, mut chunks: impl Iterator<Item = usize>) -> (Vec<Frame>, f64) {
    let mut frames = vec![Frame::default(); samples];
    let start = Instant::now();
    let mut done = 0;
    while done < samples {
        let n = match chunks.next() {
            Some(0) => continue,
            Some(n) => n.min(samples - done),
            None => samples - done,
        };
        scene.process(&mut frames[done..done + n]);
        done += n;
    }
    (frames, start.elapsed().as_secs_f64())
}

/// Renders one kind of scene description with whichever solver it is handed.
struct Render<'a, D, I> {
    scene: &'a D,
    chunks: I,
}

impl<D, I: Iterator<Item = usize>> Render<'_, D, I> {
    fn drive(self, scene: impl Scene, samples: usize, segments: usize) -> Run {
        let initial_energy = scene.initial_energy();
        let (frames, wall_seconds) = drive(scene, samples, self.chunks);
        Run { frames, initial_energy, wall_seconds, segments }
    }
}

impl<I: Iterator<Item = usize>> WithSolver for Render<'_, MassBarrierDescription, I> {
    type Output = Run;

    fn run<S: ContactSolver>(self, solver: S) -> Run {
        let (common, segments) = (&self.scene.common, solver.segments());
        let scene = MassBarrier::new(self.scene.params, f64::from(common.sample_rate), solver);
        self.drive(scene, common.samples, segments)
    }
}

impl<I: Iterator<Item = usize>> WithSolver for Render<'_, HammerStringDescription, I> {
    type Output = Run;

    fn run<S: ContactSolver>(self, solver: S) -> Run {
        let (common, segments) = (&self.scene.common, solver.segments());
        let string = prepared_string(&self.scene.params.string, common.sample_rate);
        let scene = HammerString::new(string, &self.scene.params, solver);
        self.drive(scene, common.samples, segments)
    }
}

impl<I: Iterator<Item = usize>> WithSolver for Render<'_, SlideStringDescription, I> {
    type Output = Run;

    fn run<S: ContactSolver>(self, solver: S) -> Run {
        let d = self.scene;
        let (common, segments) = (&d.common, solver.segments());
        let string = prepared_string(&d.params.string, common.sample_rate);
        // Constant controls get the scene type that never recomputes its vectors.
        if d.controls.is_constant() {
            let fixed = Fixed(d.controls.at_time(0.0));
            self.drive(SlideString::new(string, &d.params, solver, fixed), common.samples, segments)
        } else {
            let scene = SlideString::new(string, &d.params, solver, d.controls.clone());
            self.drive(scene, common.samples, segments)
        }
    }
}

/// A string prepared at `sample_rate`; its parameters were validated with the scene.
fn prepared_string(params: &crate::string::StringParams, sample_rate: u32) -> ModalString {
    ModalString::new(*params, f64::from(sample_rate)).expect("string parameters are validated when the scene is parsed")
}
