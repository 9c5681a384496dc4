//! Offline render of a scene description: every sample's [`Frame`] and what the render measured.

use super::build::{Frames, OutputOnly, Sampling, build};
use super::error::SceneError;
use super::parse::SceneDescription;
use super::summary::Measurements;
use crate::scene::Frame;

/// A finished render.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// One frame per sample.
    pub frames: Vec<Frame>,
    /// What the render measured.
    pub measurements: Measurements,
}

/// Render `scene` with its own solver settings, advancing in calls of the sizes `chunks` yields
/// (sizes of 0 are skipped; when the iterator ends, or once it has given as many sizes of 0 as
/// there are frames, the rest is rendered in one call). The frames are bit-identical for any
/// chunking.
pub fn render(scene: &SceneDescription, chunks: impl Iterator<Item = usize>) -> Result<Rendered, SceneError> {
    let run = build(scene, &scene.common().solver, Sampling::NATIVE, Frames { chunks })?;
    let measurements = Measurements::measure(scene, &run);
    Ok(Rendered { frames: run.frames, measurements })
}

/// Render only the audio output of `scene` in calls of `chunk` samples, the way a plugin runs a
/// voice: no per-sample frames, no energy bookkeeping.
pub fn render_output(scene: &SceneDescription, chunk: usize) -> Result<Vec<f64>, SceneError> {
    build(scene, &scene.common().solver, Sampling::NATIVE, OutputOnly { chunk })
}
