//! The scene file format (TOML), version 1.
//!
//! A scene file describes one render. Unknown keys are errors, and every invalid value is an
//! error that names its key. The README documents every scene kind; this module mirrors it one
//! struct per table. Every scene has:
//!
//! ```toml
//! version = 1                 # optional; the only version so far
//! scene = "mass-barrier"      # | "hammer-string" | "slide-string"
//! sample_rate = 44100         # Hz, a whole number
//! duration = 0.005            # s
//!
//! [solver]
//! method = "qsa"              # "qsa" | "imp" | "exp"
//! segments = 5                # QSA N (default 5)
//! # v_ref = 0.02              # J; default: the largest energy the scene can put into the contact
//!
//! [contact]                   # the power law F = -kappa [y]+^alpha
//! kappa = 1e8                 # N/m^alpha
//! alpha = 1.3
//!
//! [output]                    # optional
//! normalize = true            # peak-normalise the WAV
//! gain = 1.0                  # linear gain applied after normalisation
//! ```
//!
//! and the tables of its kind (see [`super::strings`] for the string scenes):
//!
//! ```toml
//! [mass]                      # mass-barrier
//! mass = 0.01                 # kg
//! u0 = -1e-3                  # m, initial displacement
//! v0 = 2.0                    # m/s, initial velocity (towards the barrier when positive)
//!
//! [barrier]
//! position = 0.0              # m
//! ```

use serde::Deserialize;

use super::SceneError;
use super::strings::{HammerStringDescription, HammerStringFile, SlideStringDescription, SlideStringFile};
use crate::contact::{Method, PowerLaw, SolverSettings};
use crate::scene::MassBarrierParams;

/// The newest scene-file version this build reads.
pub const FORMAT_VERSION: i64 = 1;

/// Longest render a scene file may ask for (s).
pub const MAX_DURATION: f64 = 600.0;

/// Most samples a scene file may ask for (bounds memory: every sample keeps a frame).
pub const MAX_SAMPLES: usize = 50_000_000;

/// Most QSA segments a scene file may ask for.
pub const MAX_SEGMENTS: usize = 100_000;

/// The scene kinds, as written in files.
pub const SCENE_KINDS: [&str; 3] = ["mass-barrier", "hammer-string", "slide-string"];

/// A parsed and validated scene.
#[derive(Debug, Clone, PartialEq)]
// One description per render, moved rarely: boxing the slide variant would buy nothing.
#[allow(clippy::large_enum_variant)]
pub enum SceneDescription {
    /// A mass striking a rigid barrier (seed §4).
    MassBarrier(MassBarrierDescription),
    /// A hammer striking a modal string (seed §5).
    HammerString(HammerStringDescription),
    /// A slide on a plucked modal string (seed §6).
    SlideString(SlideStringDescription),
}

impl SceneDescription {
    /// The scene kind as written in files.
    pub fn kind(&self) -> &'static str {
        match self {
            SceneDescription::MassBarrier(_) => SCENE_KINDS[0],
            SceneDescription::HammerString(_) => SCENE_KINDS[1],
            SceneDescription::SlideString(_) => SCENE_KINDS[2],
        }
    }

    /// Common render settings.
    pub fn common(&self) -> &Common {
        match self {
            SceneDescription::MassBarrier(d) => &d.common,
            SceneDescription::HammerString(d) => &d.common,
            SceneDescription::SlideString(d) => &d.common,
        }
    }

    /// The same scene with other solver settings (for comparing methods on one scene).
    pub fn with_solver(&self, solver: SolverSettings) -> Self {
        let mut out = self.clone();
        match &mut out {
            SceneDescription::MassBarrier(d) => d.common.solver = solver,
            SceneDescription::HammerString(d) => d.common.solver = solver,
            SceneDescription::SlideString(d) => d.common.solver = solver,
        }
        out
    }
}

/// Settings every scene has.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Common {
    /// Sample rate (Hz), a whole number.
    pub sample_rate: u32,
    /// Number of samples to render.
    pub samples: usize,
    /// The contact solver.
    pub solver: SolverSettings,
    /// The contact law.
    pub law: PowerLaw,
    /// WAV output options.
    pub output: OutputOptions,
}

/// How the WAV is written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputOptions {
    /// Peak-normalise the signal before the gain.
    pub normalize: bool,
    /// Linear gain.
    pub gain: f64,
}

/// A validated mass–barrier scene.
#[derive(Debug, Clone, PartialEq)]
pub struct MassBarrierDescription {
    /// Common settings.
    pub common: Common,
    /// The mass and barrier.
    pub params: MassBarrierParams,
}

impl MassBarrierDescription {
    /// The default QSA reference energy: everything the scene can put into the contact, the
    /// initial kinetic energy plus any initial compression energy (J). A scene that starts at
    /// rest out of contact never touches; its fit then spans 1 mm.
    pub fn default_v_ref(&self) -> f64 {
        let law = &self.common.law;
        let y0 = self.params.u0 - self.params.barrier;
        let energy = self.params.max_contact_energy() + law.potential(y0);
        if energy > 0.0 { energy } else { law.potential(1e-3) }
    }
}

/// Parse and validate a scene file.
pub fn parse_scene(text: &str) -> Result<SceneDescription, SceneError> {
    let table: toml::Table = text.parse().map_err(|e: toml::de::Error| SceneError::Syntax(e.to_string()))?;
    if let Some(version) = table.get("version") {
        match version.as_integer() {
            Some(FORMAT_VERSION) => {}
            _ => {
                return Err(SceneError::invalid(
                    "version",
                    format!("this build reads scene format version {FORMAT_VERSION}, got {version}"),
                ));
            }
        }
    }
    let kinds = SCENE_KINDS.map(|k| format!("\"{k}\"")).join(", ");
    let kind = match table.get("scene") {
        None => return Err(SceneError::invalid("scene", format!("missing (one of: {kinds})"))),
        Some(v) => v.as_str().ok_or_else(|| SceneError::invalid("scene", "must be a string"))?,
    };
    fn typed<T: serde::de::DeserializeOwned>(text: &str) -> Result<T, SceneError> {
        toml::from_str(text).map_err(|e| SceneError::Syntax(e.to_string()))
    }
    match kind {
        "mass-barrier" => typed::<MassBarrierFile>(text)?.validate().map(SceneDescription::MassBarrier),
        "hammer-string" => typed::<HammerStringFile>(text)?.validate().map(SceneDescription::HammerString),
        "slide-string" => typed::<SlideStringFile>(text)?.validate().map(SceneDescription::SlideString),
        other => Err(SceneError::invalid("scene", format!("unknown scene kind \"{other}\" (one of: {kinds})"))),
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MassBarrierFile {
    /// Checked before the typed parse.
    #[allow(dead_code)]
    version: Option<i64>,
    /// Checked before the typed parse.
    #[allow(dead_code)]
    scene: String,
    sample_rate: f64,
    duration: f64,
    solver: SolverTable,
    contact: ContactTable,
    mass: MassTable,
    barrier: BarrierTable,
    #[serde(default)]
    output: OutputTable,
}

/// The top-level keys every scene file has. (Each file struct lists them itself: serde cannot
/// combine `flatten` with `deny_unknown_fields`; `version` and `scene` were already checked.)
#[derive(Debug, Clone, Copy)]
pub(super) struct Head {
    pub(super) sample_rate: f64,
    pub(super) duration: f64,
}

/// `[solver]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SolverTable {
    method: Method,
    #[serde(default = "default_segments")]
    segments: i64,
    v_ref: Option<f64>,
}

fn default_segments() -> i64 {
    5
}

/// `[contact]`; each key may fall back to a preset.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ContactTable {
    pub(super) kappa: Option<f64>,
    pub(super) alpha: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MassTable {
    mass: f64,
    u0: f64,
    v0: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct BarrierTable {
    position: f64,
}

/// `[output]` of the mass–barrier scene.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct OutputTable {
    #[serde(default = "yes")]
    pub(super) normalize: bool,
    #[serde(default = "unity")]
    pub(super) gain: f64,
}

impl Default for OutputTable {
    fn default() -> Self {
        Self { normalize: true, gain: 1.0 }
    }
}

pub(super) fn yes() -> bool {
    true
}

pub(super) fn unity() -> f64 {
    1.0
}

/// Check that `value` is finite, naming `key` otherwise.
pub(super) fn finite(key: &str, value: f64) -> Result<f64, SceneError> {
    if value.is_finite() { Ok(value) } else { Err(SceneError::invalid(key, format!("must be finite (got {value})"))) }
}

/// Check that `value` is finite and > 0.
pub(super) fn positive(key: &str, value: f64) -> Result<f64, SceneError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(SceneError::invalid(key, format!("must be finite and > 0 (got {value})")))
    }
}

/// Check that `value` is finite and ≥ 0.
pub(super) fn non_negative(key: &str, value: f64) -> Result<f64, SceneError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(SceneError::invalid(key, format!("must be finite and >= 0 (got {value})")))
    }
}

/// Check that `value` lies strictly inside (0, 1).
pub(super) fn fraction(key: &str, value: f64) -> Result<f64, SceneError> {
    if value.is_finite() && value > 0.0 && value < 1.0 {
        Ok(value)
    } else {
        Err(SceneError::invalid(
            key,
            format!("must be a fraction of the length strictly between 0 and 1 (got {value})"),
        ))
    }
}

/// A required key: its value, or the preset's, or an error naming it.
pub(super) fn required(key: &str, value: Option<f64>, preset: Option<f64>) -> Result<f64, SceneError> {
    value.or(preset).ok_or_else(|| SceneError::invalid(key, "missing (and no preset provides it)"))
}

/// Validate the settings every scene has. `law_preset` gives fallbacks for `[contact]`.
pub(super) fn common(
    head: &Head,
    solver: &SolverTable,
    contact: &ContactTable,
    law_preset: Option<(f64, f64)>,
    output: &OutputTable,
) -> Result<Common, SceneError> {
    let fs = positive("sample_rate", head.sample_rate)?;
    if fs.fract() != 0.0 || fs > 10_000_000.0 {
        return Err(SceneError::invalid("sample_rate", format!("must be a whole number of Hz up to 1e7 (got {fs})")));
    }
    let duration = positive("duration", head.duration)?;
    if duration > MAX_DURATION {
        return Err(SceneError::invalid("duration", format!("must be at most {MAX_DURATION} s (got {duration})")));
    }
    let samples = (duration * fs).round() as usize;
    if samples == 0 || samples > MAX_SAMPLES {
        return Err(SceneError::invalid(
            "duration",
            format!("gives {samples} samples at {fs} Hz; must be 1 to {MAX_SAMPLES}"),
        ));
    }
    if solver.segments < 1 || solver.segments > MAX_SEGMENTS as i64 {
        return Err(SceneError::invalid(
            "solver.segments",
            format!("must be 1 to {MAX_SEGMENTS} (got {})", solver.segments),
        ));
    }
    if let Some(v_ref) = solver.v_ref {
        positive("solver.v_ref", v_ref)?;
    }
    let kappa = required("contact.kappa", contact.kappa, law_preset.map(|p| p.0))?;
    let alpha = required("contact.alpha", contact.alpha, law_preset.map(|p| p.1))?;
    let law = PowerLaw::new(kappa, alpha).map_err(|e| SceneError::contact("contact", e))?;
    let gain = finite("output.gain", output.gain)?;
    Ok(Common {
        sample_rate: fs as u32,
        samples,
        solver: SolverSettings { method: solver.method, segments: solver.segments as usize, v_ref: solver.v_ref },
        law,
        output: OutputOptions { normalize: output.normalize, gain },
    })
}

impl MassBarrierFile {
    fn validate(self) -> Result<MassBarrierDescription, SceneError> {
        let head = Head { sample_rate: self.sample_rate, duration: self.duration };
        let common = common(&head, &self.solver, &self.contact, None, &self.output)?;
        let params = MassBarrierParams {
            mass: positive("mass.mass", self.mass.mass)?,
            u0: finite("mass.u0", self.mass.u0)?,
            v0: finite("mass.v0", self.mass.v0)?,
            barrier: finite("barrier.position", self.barrier.position)?,
        };
        Ok(MassBarrierDescription { common, params })
    }
}
