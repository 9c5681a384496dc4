//! Scene-file tables of the string scenes: `hammer-string` and `slide-string`.
//!
//! ```toml
//! [string]                     # a preset, explicit parameters, or a preset with overrides
//! preset = "c4"                # "c4" (Chaigne-Askenfelt) | "piano-note" (with note = 0..127)
//!                              # | "slide-guitar"
//! # note = 60                  # MIDI key, for preset = "piano-note"
//! # length = 0.62              # m
//! # tension = 670.0            # N
//! # linear_density = 6.34e-3   # kg/m
//! # bending_stiffness = 9.8e-3 # N m^2 (default 0 without a preset)
//! # eta0 = 0.5                 # 1/s  } damping, seed eq. 27: sigma_i = eta0 + eta2 beta_i^2
//! # eta2 = 6.6e-4              # m^2/s}
//! # b1 = 0.5                   # 1/s  } or the per-mode law sigma_i = b1 + b3 omega0_i^2
//! # b3 = 6.25e-9               # s    } (default: lossless without a preset)
//!
//! [output]
//! kind = "displacement"        # | "velocity" | "bridge-force"
//! position = 0.9               # pickup, fraction of the length (displacement, velocity)
//! normalize = true
//! gain = 1.0
//! ```
//!
//! `hammer-string` adds (the piano presets provide mass, position and `[contact]`):
//!
//! ```toml
//! [hammer]
//! mass = 2.97e-3               # kg
//! velocity = 3.5               # m/s towards the string
//! position = 0.12              # fraction of the length
//! gap = 2e-4                   # m, initial felt-string distance (default 0.2 mm)
//! ```
//!
//! `slide-string` adds (the slide-guitar preset provides `[slide]`, `[fingers]`, `[contact]`):
//!
//! ```toml
//! [slide]
//! mass = 0.03                  # kg
//! stiffness = 1e4              # N/m, hand stiffness k_H
//! damping = 5.0                # kg/s, hand damping r_H
//!
//! [fingers]
//! left_width = 0.015           # m
//! right_width = 0.01           # m
//! damping = 5.0                # s/m, r: finger damping is r*|force|
//!
//! [control]
//! block = 64                   # N_b, samples per control block (default 64)
//!
//! [controls]                   # constant values of the controls that are not automated
//! slide.position = 0.2         # m from the nut end x = 0; the speaking length is L - x
//! hand.height = 1e-3           # m; negative presses the slide into the string
//! finger.left.position = 0.18  # m (default 0.05 L)
//! finger.left.force = 0.3      # N (default 0)
//! finger.right.position = 0.6  # m (default 0.9 L)
//! finger.right.force = 0.0     # N (default 0)
//!
//! [[automation]]               # piecewise linear, held before the first and after the last point
//! target = "slide.position"    # any of the six names above
//! points = [[0.0, 0.2], [1.0, 0.3]]   # [time (s), value], times strictly increasing
//!
//! [body]                       # optional: the string's far end on an acoustic body, coupled both
//! kind = "guitar"              # ways; the output is then what it radiates (no output.kind/position)
//! ```
//!
//! `kind = "guitar"` is Christensen and Vistisen's measured two-mass guitar with its top's higher
//! modes ([`BodyParams::guitar`], docs/physics.md §13.5).

use serde::Deserialize;

use super::automation::{CONTROL_TARGETS, SlideAutomation};
use super::error::SceneError;
use super::tables::{
    Common, ContactTable, Head, OutputTable, SolverTable, common, finite, fraction, mass, non_negative, positive,
    required, unity, yes,
};
use crate::body::BodyParams;
use crate::control::Breakpoints;
use crate::exciter::{FingerParams, HammerParams, SlideParams};
use crate::preset::{chaigne_askenfelt_c4, piano_note, slide_guitar};
use crate::scene::{HammerStringParams, OutputKind, Pickup, SlideStringParams};
use crate::string::{Damping, StringParams};

/// The farthest a scene may hold the hand from the string, above or pressed in (m).
pub const MAX_HAND_HEIGHT: f64 = 1.0;

/// The largest force a scene may give a finger (N).
pub const MAX_FINGER_FORCE: f64 = 1000.0;

/// Most samples per control block a scene file may ask for (the plugin's own, smaller bound is
/// [`MAX_BLOCK`](crate::instrument::MAX_BLOCK)).
pub const MAX_SCENE_BLOCK: usize = 65_536;

/// A validated hammer–string scene.
#[derive(Debug, Clone, PartialEq)]
pub struct HammerStringDescription {
    /// Common settings.
    pub common: Common,
    /// String, hammer and output.
    pub params: HammerStringParams,
}

impl HammerStringDescription {
    /// Default QSA reference energy: the hammer's kinetic energy `½ m v²` (J); for a hammer at
    /// rest, which never strikes, the potential at 1 mm of compression.
    pub fn default_v_ref(&self) -> f64 {
        let e = self.params.hammer.kinetic_energy();
        if e > 0.0 { e } else { self.common.law.potential(1e-3) }
    }
}

/// A validated slide–string scene.
#[derive(Debug, Clone, PartialEq)]
pub struct SlideStringDescription {
    /// Common settings.
    pub common: Common,
    /// String, slide, fingers, block length and output.
    pub params: SlideStringParams,
    /// Control inputs.
    pub controls: SlideAutomation,
    /// The body the string's far end rests on, if any (its output is then what the body radiates).
    pub body: Option<BodyParams>,
}

impl SlideStringDescription {
    /// Default QSA reference energy (J): the potential at the slide's reference compression
    /// ([`SlideParams::reference_compression`]) for the largest push the scene asks for: `d` the
    /// deepest hand press (`−min hand.height`, at least 0) and the finger forces `|F_le|`, `|F_re|`
    /// at their largest.
    pub fn default_v_ref(&self) -> f64 {
        let lanes = &self.controls.lanes;
        let depth = (-lanes[1].range().0).max(0.0);
        let peak = |i: usize| {
            let (lo, hi) = lanes[i].range();
            lo.abs().max(hi.abs())
        };
        let law = &self.common.law;
        law.potential(self.params.slide.reference_compression(law, depth, peak(3), peak(5)))
    }
}

/// `[string]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct StringTable {
    preset: Option<String>,
    note: Option<i64>,
    length: Option<f64>,
    tension: Option<f64>,
    linear_density: Option<f64>,
    bending_stiffness: Option<f64>,
    eta0: Option<f64>,
    eta2: Option<f64>,
    b1: Option<f64>,
    b3: Option<f64>,
}

/// What a preset provides besides the string. Its contact law `(κ, α)` is its own collider's, a
/// piano preset's felt for a hammer and the slide guitar's glass for a slide, and serves only a
/// scene with that collider: a slide is not a felt.
#[derive(Debug, Clone, Copy, Default)]
struct PresetExtras {
    hammer_law: Option<(f64, f64)>,
    slide_law: Option<(f64, f64)>,
    hammer_mass: Option<f64>,
    strike_position: Option<f64>,
    slide: Option<SlideParams>,
    fingers: Option<(FingerParams, FingerParams)>,
}

impl StringTable {
    fn resolve(&self) -> Result<(StringParams, PresetExtras), SceneError> {
        if self.preset.as_deref() != Some("piano-note") && self.note.is_some() {
            return Err(SceneError::invalid("string.note", "only used with preset = \"piano-note\""));
        }
        let (base, extras) = match self.preset.as_deref() {
            None => (None, PresetExtras::default()),
            Some(name) => {
                let piano = match name {
                    "c4" => chaigne_askenfelt_c4(),
                    "piano-note" => {
                        let note = self.note.ok_or_else(|| {
                            SceneError::invalid("string.note", "missing (preset \"piano-note\" needs a MIDI key)")
                        })?;
                        if !(0..=127).contains(&note) {
                            return Err(SceneError::invalid(
                                "string.note",
                                format!("must be a MIDI key 0 to 127 (got {note})"),
                            ));
                        }
                        piano_note(note as u8)
                    }
                    "slide-guitar" => {
                        let g = slide_guitar();
                        let extras = PresetExtras {
                            slide_law: Some((g.kappa, g.alpha)),
                            slide: Some(g.slide),
                            fingers: Some((g.left, g.right)),
                            ..Default::default()
                        };
                        return self.with_overrides(Some(g.string)).map(|s| (s, extras));
                    }
                    other => {
                        return Err(SceneError::invalid(
                            "string.preset",
                            format!("unknown preset \"{other}\" (one of: \"c4\", \"piano-note\", \"slide-guitar\")"),
                        ));
                    }
                };
                let extras = PresetExtras {
                    hammer_law: Some((piano.kappa, piano.alpha)),
                    hammer_mass: Some(piano.hammer_mass),
                    strike_position: Some(piano.strike_position),
                    ..Default::default()
                };
                (Some(piano.string), extras)
            }
        };
        self.with_overrides(base).map(|s| (s, extras))
    }

    fn with_overrides(&self, base: Option<StringParams>) -> Result<StringParams, SceneError> {
        let eta = self.eta0.is_some() || self.eta2.is_some();
        let per_mode = self.b1.is_some() || self.b3.is_some();
        if eta && per_mode {
            let key = if self.b1.is_some() { "string.b1" } else { "string.b3" };
            return Err(SceneError::invalid(key, "give damping either as eta0/eta2 or as b1/b3, not both"));
        }
        // A coefficient not given is the base's in the same form; a form other than the base's
        // replaces its damping whole, so it needs both of its coefficients.
        let base_damping = base.map(|b| b.damping);
        let other_form = |given: [(&str, Option<f64>); 2], form: &str| match given.iter().find(|(_, v)| v.is_none()) {
            Some((key, _)) if base_damping.is_some() => Err(SceneError::invalid(
                key,
                format!("missing: the preset gives its damping in the other form; give {form} both to replace it"),
            )),
            _ => Ok((0.0, 0.0)),
        };
        let damping = if eta {
            let (e0, e2) = match base_damping {
                Some(Damping::Viscous { eta0, eta2 }) => (eta0, eta2),
                _ => other_form([("string.eta0", self.eta0), ("string.eta2", self.eta2)], "eta0 and eta2")?,
            };
            Damping::Viscous {
                eta0: non_negative("string.eta0", self.eta0.unwrap_or(e0))?,
                eta2: non_negative("string.eta2", self.eta2.unwrap_or(e2))?,
            }
        } else if per_mode {
            let (b1, b3) = match base_damping {
                Some(Damping::PerMode { b1, b3 }) => (b1, b3),
                _ => other_form([("string.b1", self.b1), ("string.b3", self.b3)], "b1 and b3")?,
            };
            Damping::PerMode {
                b1: non_negative("string.b1", self.b1.unwrap_or(b1))?,
                b3: non_negative("string.b3", self.b3.unwrap_or(b3))?,
            }
        } else {
            base_damping.unwrap_or(Damping::LOSSLESS)
        };
        let params = StringParams {
            length: positive("string.length", required("string.length", self.length, base.map(|b| b.length))?)?,
            tension: positive("string.tension", required("string.tension", self.tension, base.map(|b| b.tension))?)?,
            linear_density: positive(
                "string.linear_density",
                required("string.linear_density", self.linear_density, base.map(|b| b.linear_density))?,
            )?,
            bending_stiffness: non_negative(
                "string.bending_stiffness",
                self.bending_stiffness.or(base.map(|b| b.bending_stiffness)).unwrap_or(0.0),
            )?,
            damping,
        };
        params.validate().map_err(|e| SceneError::invalid(&format!("string.{}", e.key), e.reason))?;
        Ok(params)
    }
}

/// `[output]` of the string scenes.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct StringOutputTable {
    kind: Option<OutputKind>,
    position: Option<f64>,
    #[serde(default = "yes")]
    normalize: bool,
    #[serde(default = "unity")]
    gain: f64,
}

impl Default for StringOutputTable {
    fn default() -> Self {
        Self { kind: None, position: None, normalize: true, gain: 1.0 }
    }
}

impl StringOutputTable {
    fn pickup(&self, default_kind: OutputKind) -> Result<Pickup, SceneError> {
        let kind = self.kind.unwrap_or(default_kind);
        // The bridge force is taken at the bridge: a pickup position would be ignored.
        if kind == OutputKind::BridgeForce && self.position.is_some() {
            return Err(SceneError::invalid(
                "output.position",
                "the bridge force is taken at the bridge; a position applies to the displacement or velocity",
            ));
        }
        let position = fraction("output.position", self.position.unwrap_or(0.9))?;
        Ok(Pickup::point(kind, position))
    }

    fn options(&self) -> OutputTable {
        OutputTable { normalize: self.normalize, gain: self.gain }
    }
}

/// A `hammer-string` scene file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct HammerStringFile {
    /// Checked before the typed parse.
    #[allow(dead_code)]
    version: Option<i64>,
    /// Checked before the typed parse.
    #[allow(dead_code)]
    scene: String,
    sample_rate: f64,
    duration: f64,
    solver: SolverTable,
    #[serde(default)]
    contact: ContactTable,
    string: StringTable,
    hammer: HammerTable,
    #[serde(default)]
    output: StringOutputTable,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HammerTable {
    mass: Option<f64>,
    velocity: f64,
    position: Option<f64>,
    gap: Option<f64>,
}

impl HammerStringFile {
    pub(super) fn validate(self) -> Result<HammerStringDescription, SceneError> {
        let (string, extras) = self.string.resolve()?;
        let head = Head { sample_rate: self.sample_rate, duration: self.duration };
        let common = common(&head, &self.solver, &self.contact, extras.hammer_law, &self.output.options())?;
        let h = &self.hammer;
        let hammer = HammerParams {
            mass: mass("hammer.mass", required("hammer.mass", h.mass, extras.hammer_mass)?)?,
            velocity: non_negative("hammer.velocity", h.velocity)?,
            position: fraction("hammer.position", required("hammer.position", h.position, extras.strike_position)?)?,
            gap: positive("hammer.gap", h.gap.unwrap_or(HammerParams::DEFAULT_GAP))?,
        };
        let pickup = self.output.pickup(OutputKind::BridgeForce)?;
        Ok(HammerStringDescription { common, params: HammerStringParams { string, hammer, pickup } })
    }
}

/// A `slide-string` scene file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SlideStringFile {
    /// Checked before the typed parse.
    #[allow(dead_code)]
    version: Option<i64>,
    /// Checked before the typed parse.
    #[allow(dead_code)]
    scene: String,
    sample_rate: f64,
    duration: f64,
    solver: SolverTable,
    #[serde(default)]
    contact: ContactTable,
    string: StringTable,
    #[serde(default)]
    slide: SlideTable,
    #[serde(default)]
    fingers: FingersTable,
    #[serde(default)]
    control: ControlTable,
    #[serde(default)]
    controls: ControlsTable,
    #[serde(default)]
    automation: Vec<AutomationEntry>,
    #[serde(default)]
    output: StringOutputTable,
    body: Option<BodyTable>,
}

/// `[body]` of a slide-string scene.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct BodyTable {
    kind: String,
}

impl BodyTable {
    fn params(&self) -> Result<BodyParams, SceneError> {
        match self.kind.as_str() {
            "guitar" => Ok(BodyParams::guitar()),
            other => Err(SceneError::invalid("body.kind", format!("unknown body \"{other}\" (one of: guitar)"))),
        }
    }
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct SlideTable {
    mass: Option<f64>,
    stiffness: Option<f64>,
    damping: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct FingersTable {
    left_width: Option<f64>,
    right_width: Option<f64>,
    damping: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct ControlTable {
    block: Option<i64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct ControlsTable {
    slide: Option<PositionControl>,
    hand: Option<HandControl>,
    finger: Option<FingerControls>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PositionControl {
    position: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HandControl {
    height: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FingerControls {
    left: Option<FingerControl>,
    right: Option<FingerControl>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FingerControl {
    position: Option<f64>,
    force: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct AutomationEntry {
    target: String,
    /// `[time (s), value]` pairs; read as lists so that a point of other than two numbers is
    /// refused (a tuple would take the first two and drop the rest).
    points: Vec<Vec<f64>>,
}

impl ControlsTable {
    /// Constant values in [`CONTROL_TARGETS`] order, `None` where not given.
    fn values(&self) -> [Option<f64>; 6] {
        let left = self.finger.as_ref().and_then(|f| f.left.as_ref());
        let right = self.finger.as_ref().and_then(|f| f.right.as_ref());
        [
            self.slide.as_ref().and_then(|s| s.position),
            self.hand.as_ref().and_then(|h| h.height),
            left.and_then(|f| f.position),
            left.and_then(|f| f.force),
            right.and_then(|f| f.position),
            right.and_then(|f| f.force),
        ]
    }
}

impl SlideStringFile {
    pub(super) fn validate(self) -> Result<SlideStringDescription, SceneError> {
        let (string, extras) = self.string.resolve()?;
        let head = Head { sample_rate: self.sample_rate, duration: self.duration };
        let common = common(&head, &self.solver, &self.contact, extras.slide_law, &self.output.options())?;
        let preset_slide = extras.slide;
        let s = &self.slide;
        let slide = SlideParams {
            mass: mass("slide.mass", required("slide.mass", s.mass, preset_slide.map(|p| p.mass))?)?,
            stiffness: non_negative(
                "slide.stiffness",
                required("slide.stiffness", s.stiffness, preset_slide.map(|p| p.stiffness))?,
            )?,
            damping: non_negative(
                "slide.damping",
                required("slide.damping", s.damping, preset_slide.map(|p| p.damping))?,
            )?,
        };
        let (pl, pr) = (extras.fingers.map(|f| f.0), extras.fingers.map(|f| f.1));
        let f = &self.fingers;
        let r = non_negative("fingers.damping", required("fingers.damping", f.damping, pl.map(|p| p.damping))?)?;
        let left = FingerParams {
            width: positive("fingers.left_width", required("fingers.left_width", f.left_width, pl.map(|p| p.width))?)?,
            damping: r,
        };
        let right = FingerParams {
            width: positive(
                "fingers.right_width",
                required("fingers.right_width", f.right_width, pr.map(|p| p.width))?,
            )?,
            damping: r,
        };
        let block = self.control.block.unwrap_or(64);
        if !(1..=MAX_SCENE_BLOCK as i64).contains(&block) {
            return Err(SceneError::invalid(
                "control.block",
                format!("must be 1 to {MAX_SCENE_BLOCK} samples (got {block})"),
            ));
        }
        let controls = self.controls(string.length, common.sample_rate)?;
        let pickup = self.output.pickup(OutputKind::Displacement)?;
        let body = self.body.as_ref().map(BodyTable::params).transpose()?;
        if body.is_some() && (self.output.kind.is_some() || self.output.position.is_some()) {
            return Err(SceneError::invalid(
                "output",
                String::from("a string on a body is heard through the body: leave out output.kind and output.position"),
            ));
        }
        let params = SlideStringParams { string, slide, left, right, block: block as usize, pickup };
        Ok(SlideStringDescription { common, params, controls, body })
    }

    fn controls(&self, length: f64, sample_rate: u32) -> Result<SlideAutomation, SceneError> {
        let constants = self.controls.values();
        let defaults = [None, None, Some(0.05 * length), Some(0.0), Some(0.9 * length), Some(0.0)];
        // Each lane with the key its values came from.
        let mut lanes: [Option<(Breakpoints, String)>; 6] = Default::default();
        for (i, entry) in self.automation.iter().enumerate() {
            let key = format!("automation[{i}].target");
            let Some(index) = CONTROL_TARGETS.iter().position(|t| *t == entry.target) else {
                return Err(SceneError::invalid(
                    &key,
                    format!("unknown target \"{}\" (one of: {})", entry.target, CONTROL_TARGETS.join(", ")),
                ));
            };
            if lanes[index].is_some() {
                return Err(SceneError::invalid(&key, format!("\"{}\" is automated twice", entry.target)));
            }
            if constants[index].is_some() {
                return Err(SceneError::invalid(
                    &key,
                    format!("\"{}\" is automated and also given in [controls]; give one of them", entry.target),
                ));
            }
            let points_key = format!("automation[{i}].points");
            let mut points = Vec::with_capacity(entry.points.len());
            for (j, point) in entry.points.iter().enumerate() {
                let &[t, v] = point.as_slice() else {
                    return Err(SceneError::invalid(
                        &points_key,
                        format!("point {j} has {} numbers; a point is [time s, value]", point.len()),
                    ));
                };
                points.push((t, v));
            }
            let lane = Breakpoints::new(points)
                .map_err(|e| SceneError::invalid(&points_key, format!("{} (time s, value): {e}", entry.target)))?;
            lanes[index] = Some((lane, points_key));
        }
        let mut out = Vec::with_capacity(6);
        for (index, lane) in lanes.into_iter().enumerate() {
            let target = CONTROL_TARGETS[index];
            let (lane, key) = match lane {
                Some(lane) => lane,
                None => {
                    let key = format!("controls.{target}");
                    let value = constants[index].or(defaults[index]).ok_or_else(|| {
                        SceneError::invalid(&key, "missing: give a constant here or an [[automation]] for it")
                    })?;
                    (Breakpoints::constant(finite(&key, value)?), key)
                }
            };
            if target.ends_with("position") {
                for &(t, x) in lane.points() {
                    if !(x > 0.0 && x < length) {
                        return Err(SceneError::invalid(
                            &key,
                            format!("position {x} m at t = {t} s is outside the string (0, {length}) m"),
                        ));
                    }
                }
            }
            // Far beyond any gesture, and a lane between its bounds interpolates in the floats.
            let (bound, unit) =
                if target.ends_with("force") { (MAX_FINGER_FORCE, "N") } else { (MAX_HAND_HEIGHT, "m") };
            if !target.ends_with("position") {
                for &(t, v) in lane.points() {
                    if v.abs() > bound {
                        return Err(SceneError::invalid(
                            &key,
                            format!("{v:e} {unit} at t = {t} s is beyond ±{bound} {unit}"),
                        ));
                    }
                }
            }
            out.push(lane);
        }
        let lanes: [Breakpoints; 6] = out.try_into().expect("six lanes");
        Ok(SlideAutomation::new(lanes, f64::from(sample_rate)))
    }
}
