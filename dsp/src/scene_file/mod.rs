//! Scene files: the TOML format that describes one offline render, its parsing and validation,
//! the scene vocabulary (scene kinds, slide automation targets), the one builder that turns a
//! description and a solver choice into a runnable scene, and what a render measured.
//!
//! - `parse`: [`parse_scene`] turns a file into a validated [`SceneDescription`]; the tables of
//!   each kind are read in `mass_barrier` and `string_scenes`, the shared ones and the bounds a
//!   file may ask for in `tables`; `error` holds [`SceneError`], which names the key at fault.
//! - `automation`: the slide's control targets ([`CONTROL_TARGETS`]) and their breakpoint
//!   automation ([`SlideAutomation`]).
//! - `build`: [`build()`] runs a description with any solver, at its own rate or oversampled
//!   ([`Sampling`]), through a [`SceneJob`]; the renderer, the report, the bench and the tests all
//!   build their scenes with it.
//! - `render`: [`render()`] gives every sample's [`Frame`](crate::scene::Frame) with the
//!   [`Measurements`] of `summary`; [`render_output`] gives the output signal alone. Both are
//!   bit-identical for any chunking. Timing a render is the caller's business (the renderer's
//!   front end and the bench in `xtask`).

mod automation;
mod build;
mod error;
mod mass_barrier;
mod parse;
mod render;
mod string_scenes;
mod summary;
mod tables;

pub use automation::{CONTROL_TARGETS, SlideAutomation};
pub use build::{Frames, OutputOnly, Run, Sampling, SceneJob, build, fill_frames};
pub use error::SceneError;
pub use mass_barrier::MassBarrierDescription;
pub use parse::{FORMAT_VERSION, SCENE_KINDS, SceneDescription, parse_scene};
pub use render::{Rendered, render, render_output};
pub use string_scenes::{HammerStringDescription, MAX_SCENE_BLOCK, SlideStringDescription};
pub use summary::{Measurements, contact_intervals};
pub use tables::{Common, MAX_SCENE_DURATION, MAX_SCENE_SAMPLES, MAX_SCENE_SEGMENTS, OutputOptions};
