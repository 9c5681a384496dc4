//! The scene file format (TOML), version 1.
//!
//! A scene file describes one render. Unknown keys are errors, and every invalid value is an
//! error that names its key. The format of each scene kind is documented in the README; this
//! module mirrors it one struct per table.
//!
//! ```toml
//! version = 1                 # optional; the only version so far
//! scene = "mass-barrier"
//! sample_rate = 44100         # Hz, a whole number
//! duration = 0.005            # s
//!
//! [solver]
//! method = "qsa"              # "qsa" | "imp" | "exp"
//! segments = 5                # QSA N
//! # v_ref = 0.02              # J; default: the largest energy the scene can put into the contact
//!
//! [contact]
//! kappa = 1e8                 # N/m^alpha
//! alpha = 1.3
//!
//! [mass]
//! mass = 0.01                 # kg
//! u0 = -1e-3                  # m, initial displacement
//! v0 = 2.0                    # m/s, initial velocity (towards the barrier when positive)
//!
//! [barrier]
//! position = 0.0              # m
//!
//! [output]                    # optional
//! normalize = true            # peak-normalise the WAV
//! gain = 1.0                  # linear gain applied after normalisation
//! ```

use serde::Deserialize;

use super::SceneError;
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

/// A parsed and validated scene.
#[derive(Debug, Clone, PartialEq)]
pub enum SceneDescription {
    /// A mass striking a rigid barrier (seed §4).
    MassBarrier(MassBarrierDescription),
}

impl SceneDescription {
    /// The scene kind as written in files.
    pub fn kind(&self) -> &'static str {
        match self {
            SceneDescription::MassBarrier(_) => "mass-barrier",
        }
    }

    /// Common render settings.
    pub fn common(&self) -> &Common {
        match self {
            SceneDescription::MassBarrier(d) => &d.common,
        }
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
    let kind = match table.get("scene") {
        None => return Err(SceneError::invalid("scene", "missing (one of: \"mass-barrier\")")),
        Some(v) => v.as_str().ok_or_else(|| SceneError::invalid("scene", "must be a string"))?,
    };
    match kind {
        "mass-barrier" => {
            let raw: MassBarrierFile = toml::from_str(text).map_err(|e| SceneError::Syntax(e.to_string()))?;
            raw.validate().map(SceneDescription::MassBarrier)
        }
        other => Err(SceneError::invalid("scene", format!("unknown scene kind \"{other}\" (one of: \"mass-barrier\")"))),
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MassBarrierFile {
    #[allow(dead_code)]
    version: Option<i64>,
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

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SolverTable {
    method: Method,
    #[serde(default = "default_segments")]
    segments: i64,
    v_ref: Option<f64>,
}

fn default_segments() -> i64 {
    5
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ContactTable {
    kappa: f64,
    alpha: f64,
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

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct OutputTable {
    #[serde(default = "yes")]
    normalize: bool,
    #[serde(default = "unity")]
    gain: f64,
}

impl Default for OutputTable {
    fn default() -> Self {
        Self { normalize: true, gain: 1.0 }
    }
}

fn yes() -> bool {
    true
}

fn unity() -> f64 {
    1.0
}

/// Check that `value` is finite, naming `key` otherwise.
fn finite(key: &str, value: f64) -> Result<f64, SceneError> {
    if value.is_finite() { Ok(value) } else { Err(SceneError::invalid(key, format!("must be finite (got {value})"))) }
}

/// Check that `value` is finite and > 0.
fn positive(key: &str, value: f64) -> Result<f64, SceneError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(SceneError::invalid(key, format!("must be finite and > 0 (got {value})")))
    }
}

fn common(
    sample_rate: f64,
    duration: f64,
    solver: &SolverTable,
    contact: &ContactTable,
    output: &OutputTable,
) -> Result<Common, SceneError> {
    let fs = positive("sample_rate", sample_rate)?;
    if fs.fract() != 0.0 || fs > 10_000_000.0 {
        return Err(SceneError::invalid("sample_rate", format!("must be a whole number of Hz up to 1e7 (got {fs})")));
    }
    let duration = positive("duration", duration)?;
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
    let law = PowerLaw::new(contact.kappa, contact.alpha).map_err(|e| SceneError::contact("contact", e))?;
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
        let common = common(self.sample_rate, self.duration, &self.solver, &self.contact, &self.output)?;
        let params = MassBarrierParams {
            mass: positive("mass.mass", self.mass.mass)?,
            u0: finite("mass.u0", self.mass.u0)?,
            v0: finite("mass.v0", self.mass.v0)?,
            barrier: finite("barrier.position", self.barrier.position)?,
        };
        Ok(MassBarrierDescription { common, params })
    }
}
