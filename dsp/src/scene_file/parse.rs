//! The scene file format (TOML), version 1.
//!
//! A scene file describes one render. Unknown keys are errors, and every invalid value is an
//! error that names its key. docs/scene-files.md documents every scene kind; this module mirrors
//! it one struct per table. Every scene has:
//!
//! ```toml
//! version = 1                 # optional; the only version so far
//! scene = "mass-barrier"      # | "hammer-string" | "slide-string"
//! sample_rate = 44100         # Hz, a whole number
//! duration = 0.005            # s
//!
//! [solver]
//! method = "qsa"              # "qsa" | "imp" | "exp"
//! segments = 5                # QSA N (default 5); IMP and EXP do not read it
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
//! and the tables of its kind: [`super::mass_barrier`] for `mass-barrier`, [`super::string_scenes`]
//! for `hammer-string` and `slide-string`. The tables every kind shares are read and checked in
//! [`super::tables`].

use super::error::SceneError;
use super::mass_barrier::{MassBarrierDescription, MassBarrierFile};
use super::string_scenes::{HammerStringDescription, HammerStringFile, SlideStringDescription, SlideStringFile};
use super::tables::Common;
use crate::contact::SolverSettings;

/// The newest scene-file version this build reads.
pub const FORMAT_VERSION: i64 = 1;

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

    /// The QSA reference energy V_ref a scene file that gives none takes (J): the largest energy
    /// the scene can put into the contact.
    pub fn default_v_ref(&self) -> f64 {
        match self {
            SceneDescription::MassBarrier(d) => d.default_v_ref(),
            SceneDescription::HammerString(d) => d.default_v_ref(),
            SceneDescription::SlideString(d) => d.default_v_ref(),
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
