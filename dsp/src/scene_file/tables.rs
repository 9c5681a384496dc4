//! The tables and checks every scene file shares: the top-level keys, `[solver]`, `[contact]`,
//! `[output]`, the bounds a file may ask for, and the value checks that name the offending key.

use serde::Deserialize;

use super::error::SceneError;
use crate::contact::{Method, PowerLaw, SolverSettings};

/// Longest render a scene file may ask for (s).
pub const MAX_SCENE_DURATION: f64 = 600.0;

/// Most samples a scene file may ask for: every sample keeps a frame of 72 bytes, so this bounds
/// a render's frames near 1 GB (600 s at 23 kHz, 317 s at 44.1 kHz).
pub const MAX_SCENE_SAMPLES: usize = 14_000_000;

/// Most QSA segments a scene file may ask for (the plugin's own, smaller bound is
/// [`MAX_SEGMENTS`](crate::instrument::MAX_SEGMENTS)).
pub const MAX_SCENE_SEGMENTS: usize = 100_000;

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

/// The least mass a scene may give a body (kg): a microgram. The lightest exciters weigh grams;
/// far lighter, the coupling `Δt²/m` leaves the floats (infinite below 3e-318 kg at 44.1 kHz,
/// where the explicit and Newton solvers return NaN).
pub const MIN_MASS: f64 = 1e-9;

/// Check that `value` is a mass (kg) of at least [`MIN_MASS`].
pub(super) fn mass(key: &str, value: f64) -> Result<f64, SceneError> {
    let value = positive(key, value)?;
    if value >= MIN_MASS {
        Ok(value)
    } else {
        Err(SceneError::invalid(key, format!("must be at least {MIN_MASS:e} kg (got {value:e})")))
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
    if duration > MAX_SCENE_DURATION {
        return Err(SceneError::invalid(
            "duration",
            format!("must be at most {MAX_SCENE_DURATION} s (got {duration})"),
        ));
    }
    let samples = (duration * fs).round() as usize;
    if samples == 0 || samples > MAX_SCENE_SAMPLES {
        return Err(SceneError::invalid(
            "duration",
            format!("gives {samples} samples at {fs} Hz; must be 1 to {MAX_SCENE_SAMPLES}"),
        ));
    }
    if solver.segments < 1 || solver.segments > MAX_SCENE_SEGMENTS as i64 {
        return Err(SceneError::invalid(
            "solver.segments",
            format!("must be 1 to {MAX_SCENE_SEGMENTS} (got {})", solver.segments),
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
