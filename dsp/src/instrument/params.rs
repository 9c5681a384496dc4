//! The plugin's parameters, defined once: [`PARAMETERS`], one [`ParamSpec`] each (stable short id,
//! name, group, range, unit, default, display, and where the value lives in [`ParamValues`]), and
//! the one mapping of those values to [`Settings`].
//!
//! Everything that knows a parameter reads it from the table: the plugin builds its host-facing
//! parameters from it, the offline renderer's `--set ID=VALUE` and the factory presets parse
//! through [`ParamValues::set`], and the documentation table of `plugin/src/params.rs` is checked
//! against it. The ids, names, ranges and defaults are part of saved state and automation: they
//! never change once released.
//!
//! Values are held as the plugin holds them (plain `f32` values in the units it shows: ms, mm, g,
//! linear gain) and mapped to [`Settings`] by [`ParamValues::settings`], so the plugin and the
//! offline MIDI renderer give the same samples for the same values.

use crate::contact::Method;
use crate::instrument::MAX_VOICES;
use crate::instrument::notes::NoteParam;
use crate::instrument::settings::{
    GAIN_RANGE_DB, HARDNESS_RANGE, HandSource, MAX_BLOCK, MAX_SEGMENTS, Mode, Settings, SlideBody,
};

/// The editor section (host group: VST3 unit, CLAP module) that shows a parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Group {
    /// Mode, solver, control block, voices.
    Engine,
    /// The piano's settings.
    Piano,
    /// The slide guitar's settings.
    Slide,
    /// Gain and limiter.
    Output,
}

impl Group {
    /// The group's name as hosts show it.
    pub const fn name(self) -> &'static str {
        match self {
            Group::Engine => "Engine",
            Group::Piano => "Piano",
            Group::Slide => "Slide",
            Group::Output => "Output",
        }
    }
}

/// How a continuous parameter's normalized position (0..=1, what hosts automate) maps to its range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Scale {
    /// Evenly.
    Linear,
    /// Skewed towards the low end: nice-plug's `FloatRange::Skewed` with factor
    /// `FloatRange::skew_factor(exponent)` (negative exponents give the low end more travel).
    Skewed(f32),
    /// The range, default and text are in dB; the value is the linear gain `10^(dB/20)`, skewed as
    /// nice-plug skews gains (`FloatRange::gain_skew_factor`).
    Decibels,
}

/// How a continuous parameter's value is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ValueDisplay {
    /// The framework's default text.
    Plain,
    /// Rounded to this many decimals.
    Rounded(usize),
    /// Scientific notation with this many decimals (`1.00e9`).
    Scientific(usize),
}

/// What kind of value a parameter takes, with its range and default in the units it shows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ParamKind {
    /// A continuous value.
    Float {
        /// Lowest value (in `unit`).
        min: f32,
        /// Highest value (in `unit`).
        max: f32,
        /// Default (in `unit`).
        default: f32,
        /// Unit suffix as shown after the value (with its leading space, if any).
        unit: &'static str,
        /// How the normalized position maps to the range.
        scale: Scale,
        /// How the value is shown.
        display: ValueDisplay,
        /// Step the value snaps to, if any.
        step: Option<f32>,
        /// The per-note offset CLAP polyphonic modulation of this parameter drives, if it takes any.
        poly: Option<NoteParam>,
    },
    /// A whole number.
    Int {
        /// Lowest value.
        min: i32,
        /// Highest value.
        max: i32,
        /// Default.
        default: i32,
        /// Unit suffix as shown after the value.
        unit: &'static str,
    },
    /// On or off (`on`/`off`, `true`/`false`, `1`/`0` as text).
    Bool {
        /// Default.
        default: bool,
    },
    /// One of a list, held as its index.
    Choice {
        /// Every option as (stable id, also the text `--set` and presets take; display name).
        options: &'static [(&'static str, &'static str)],
        /// Index of the default option.
        default: usize,
    },
}

/// One parameter: everything the plugin, the renderer, the presets and the docs need to know.
#[derive(Debug, Clone, Copy)]
pub struct ParamSpec {
    /// Stable short id (saved state, automation, presets, `--set`).
    pub id: &'static str,
    /// Name hosts show.
    pub name: &'static str,
    /// Host group and editor section.
    pub group: Group,
    /// Value kind, range and default.
    pub kind: ParamKind,
    /// What the value sets in the engine (for the documentation table).
    pub maps_to: &'static str,
    /// The plain value (choices as their index, switches 0 or 1, gain linear) in `values`.
    pub get: fn(&ParamValues) -> f32,
    /// Store the plain value `plain` in `values`.
    pub put: fn(&mut ParamValues, f32),
}

/// The modes of `mode`, in option order.
const MODES: [Mode; 2] = [Mode::Piano, Mode::Slide];

/// The solvers of `solver`, in option order.
const SOLVERS: [Method; 3] = [Method::Qsa, Method::Exp, Method::Imp];

/// The hand-height sources of `handsrc`, in option order.
const HAND_SOURCES: [HandSource; 5] = [
    HandSource::Parameter,
    HandSource::ModWheel,
    HandSource::ChannelPressure,
    HandSource::PolyPressure,
    HandSource::Timbre,
];

/// The slide guitar's bodies of `sbody`, in option order.
const SLIDE_BODIES: [SlideBody; 2] = [SlideBody::Pickup, SlideBody::Acoustic];

/// The option of `options` at plain value (index) `plain`, clamped to the list.
fn pick<T: Copy, const N: usize>(options: [T; N], plain: f32) -> T {
    options[(plain.max(0.0) as usize).min(N - 1)]
}

/// The index of `value` in `options`, as a plain value.
fn index<T: PartialEq, const N: usize>(options: [T; N], value: T) -> f32 {
    options.iter().position(|o| *o == value).unwrap_or(0) as f32
}

/// A switch's plain value.
fn switch(on: bool) -> f32 {
    if on { 1.0 } else { 0.0 }
}

/// A relative ("×") parameter on a log-like scale around 1, shown with two decimals.
const fn ratio(min: f32, max: f32, scale: Scale) -> ParamKind {
    ParamKind::Float {
        min,
        max,
        default: 1.0,
        unit: "×",
        scale,
        display: ValueDisplay::Rounded(2),
        step: None,
        poly: None,
    }
}

/// A continuous parameter without step or polyphonic modulation.
const fn float(min: f32, max: f32, default: f32, unit: &'static str, scale: Scale, display: ValueDisplay) -> ParamKind {
    ParamKind::Float { min, max, default, unit, scale, display, step: None, poly: None }
}

/// The parameters that say how this machine and the player's pedal play the instrument rather
/// than how it sounds: how many voices it may hold, whether it sheds voices when processing falls
/// behind, and where along the player's sustain pedal the dampers leave the strings. A preset
/// leaves them where the player set them unless its file names them (Pianoteq and Kontakt keep
/// their polyphony and pedal calibration outside the sound's presets too).
pub const PLAYER_SETTINGS: [&str; 4] = ["voices", "guard", "hpfrom", "hpto"];

/// Every parameter, in display order (the groups in the order Engine, Piano, Slide, Output).
pub const PARAMETERS: [ParamSpec; 35] = [
    ParamSpec {
        id: "mode",
        name: "Mode",
        group: Group::Engine,
        kind: ParamKind::Choice { options: &[("piano", "Piano"), ("slide", "Slide")], default: 0 },
        maps_to: "[`Settings::mode`]",
        get: |v| index(MODES, v.mode),
        put: |v, x| v.mode = pick(MODES, x),
    },
    ParamSpec {
        id: "solver",
        name: "Solver",
        group: Group::Engine,
        kind: ParamKind::Choice {
            options: &[(Method::Qsa.name(), "QSA"), (Method::Exp.name(), "EXP"), (Method::Imp.name(), "IMP")],
            default: 0,
        },
        maps_to: "[`Settings::method`]",
        get: |v| index(SOLVERS, v.method),
        put: |v, x| v.method = pick(SOLVERS, x),
    },
    ParamSpec {
        id: "segs",
        name: "QSA segments",
        group: Group::Engine,
        kind: ParamKind::Int { min: 1, max: MAX_SEGMENTS as i32, default: 6, unit: "" },
        maps_to: "[`Settings::segments`]",
        get: |v| v.segments as f32,
        put: |v, x| v.segments = x as i32,
    },
    ParamSpec {
        id: "nb",
        name: "Control block",
        group: Group::Engine,
        kind: ParamKind::Int { min: 1, max: MAX_BLOCK as i32, default: 64, unit: " smp" },
        maps_to: "[`Settings::block`]",
        get: |v| v.block as f32,
        put: |v, x| v.block = x as i32,
    },
    ParamSpec {
        id: "voices",
        name: "Voices",
        group: Group::Engine,
        kind: ParamKind::Int { min: 1, max: MAX_VOICES as i32, default: 32, unit: "" },
        maps_to: "voice pool size (at the next activation)",
        get: |v| v.voices as f32,
        put: |v, x| v.voices = x as i32,
    },
    ParamSpec {
        id: "guard",
        name: "Overload guard",
        group: Group::Engine,
        kind: ParamKind::Bool { default: true },
        maps_to: "the plugin's overload guard (real-time processing only; offline rendering never sheds)",
        get: |v| switch(v.overload_guard),
        put: |v, x| v.overload_guard = x != 0.0,
    },
    ParamSpec {
        id: "hard",
        name: "Hardness",
        group: Group::Piano,
        kind: ratio(HARDNESS_RANGE.0 as f32, HARDNESS_RANGE.1 as f32, Scale::Skewed(-1.5)),
        maps_to: "[`Settings::hardness`]",
        get: |v| v.hardness,
        put: |v, x| v.hardness = x,
    },
    ParamSpec {
        id: "hmass",
        name: "Hammer mass",
        group: Group::Piano,
        kind: ratio(0.25, 4.0, Scale::Skewed(-1.5)),
        maps_to: "[`Settings::hammer_mass`]",
        get: |v| v.hammer_mass,
        put: |v, x| v.hammer_mass = x,
    },
    ParamSpec {
        id: "strike",
        name: "Strike position",
        group: Group::Piano,
        kind: ratio(0.25, 2.5, Scale::Skewed(-1.5)),
        maps_to: "[`Settings::strike_position`]",
        get: |v| v.strike_position,
        put: |v, x| v.strike_position = x,
    },
    ParamSpec {
        id: "damp",
        name: "String damping",
        group: Group::Piano,
        kind: ratio(0.1, 20.0, Scale::Skewed(-1.5)),
        maps_to: "[`Settings::damping`]",
        get: |v| v.damping,
        put: |v, x| v.damping = x,
    },
    ParamSpec {
        id: "bright",
        name: "Brightness",
        group: Group::Piano,
        kind: ratio(0.0, 4.0, Scale::Linear),
        maps_to: "[`Settings::brightness`] (inharmonicity)",
        get: |v| v.brightness,
        put: |v, x| v.brightness = x,
    },
    ParamSpec {
        id: "damper",
        name: "Damper",
        group: Group::Piano,
        kind: float(1.0, 500.0, 60.0, " 1/s", Scale::Skewed(-2.0), ValueDisplay::Rounded(1)),
        maps_to: "[`Settings::damper_rate`]",
        get: |v| v.damper,
        put: |v, x| v.damper = x,
    },
    ParamSpec {
        id: "detune",
        name: "Unison detune",
        group: Group::Piano,
        kind: float(0.0, 20.0, 2.5, " ct", Scale::Skewed(-1.0), ValueDisplay::Rounded(2)),
        maps_to: "[`Settings::unison_detune`] (spread of each unison, cents)",
        get: |v| v.unison_detune,
        put: |v, x| v.unison_detune = x,
    },
    ParamSpec {
        id: "stretch",
        name: "Octave stretch",
        group: Group::Piano,
        kind: ratio(0.0, 2.0, Scale::Linear),
        maps_to: "[`Settings::stretch`] (octaves tuned on the partials)",
        get: |v| v.stretch,
        put: |v, x| v.stretch = x,
    },
    ParamSpec {
        id: "hpfrom",
        name: "Half pedal from",
        group: Group::Piano,
        kind: float(0.0, 100.0, 20.0, " %", Scale::Linear, ValueDisplay::Rounded(0)),
        maps_to: "[`Settings::half_pedal_from`] (×0.01 of the sustain pedal's travel: below, the dampers rest on the strings)",
        get: |v| v.half_pedal_from,
        put: |v, x| v.half_pedal_from = x,
    },
    ParamSpec {
        id: "hpto",
        name: "Half pedal to",
        group: Group::Piano,
        kind: float(0.0, 100.0, 80.0, " %", Scale::Linear, ValueDisplay::Rounded(0)),
        maps_to: "[`Settings::half_pedal_to`] (×0.01: above, the dampers are clear of the strings)",
        get: |v| v.half_pedal_to,
        put: |v, x| v.half_pedal_to = x,
    },
    ParamSpec {
        id: "slide",
        name: "Slide position",
        group: Group::Slide,
        kind: ParamKind::Float {
            min: 0.0,
            max: 24.0,
            default: 5.0,
            unit: " st",
            scale: Scale::Linear,
            display: ValueDisplay::Rounded(2),
            step: None,
            poly: Some(NoteParam::SlidePosition),
        },
        maps_to: "[`Settings::slide_position`]",
        get: |v| v.slide_position,
        put: |v, x| v.slide_position = x,
    },
    ParamSpec {
        id: "follow",
        name: "Slide follows key",
        group: Group::Slide,
        kind: ParamKind::Bool { default: true },
        maps_to: "[`Settings::follow_key`]",
        get: |v| switch(v.follow_key),
        put: |v, x| v.follow_key = x != 0.0,
    },
    ParamSpec {
        id: "glide",
        name: "Glide time",
        group: Group::Slide,
        kind: float(1.0, 2000.0, 50.0, " ms", Scale::Skewed(-2.0), ValueDisplay::Rounded(1)),
        maps_to: "[`Settings::glide_time`]",
        get: |v| v.glide_ms,
        put: |v, x| v.glide_ms = x,
    },
    ParamSpec {
        id: "bend",
        name: "Bend range",
        group: Group::Slide,
        kind: ParamKind::Float {
            min: 0.0,
            max: 24.0,
            default: 2.0,
            unit: " st",
            scale: Scale::Linear,
            display: ValueDisplay::Plain,
            step: Some(0.5),
            poly: None,
        },
        maps_to: "[`Settings::bend_range`]",
        get: |v| v.bend_range,
        put: |v, x| v.bend_range = x,
    },
    ParamSpec {
        id: "hand",
        name: "Hand height",
        group: Group::Slide,
        kind: ParamKind::Float {
            min: -3.0,
            max: 3.0,
            default: -1.5,
            unit: " mm",
            scale: Scale::Linear,
            display: ValueDisplay::Rounded(2),
            step: None,
            poly: Some(NoteParam::HandHeight),
        },
        maps_to: "[`Settings::hand_height`]",
        get: |v| v.hand_mm,
        put: |v, x| v.hand_mm = x,
    },
    ParamSpec {
        id: "handsrc",
        name: "Hand height from",
        group: Group::Slide,
        kind: ParamKind::Choice {
            options: &[
                ("param", "Parameter"),
                ("modwheel", "Mod wheel"),
                ("chanpress", "Channel pressure"),
                ("polypress", "Poly pressure"),
                ("cc74", "CC74 (timbre)"),
            ],
            default: 0,
        },
        maps_to: "[`Settings::hand_source`]",
        get: |v| index(HAND_SOURCES, v.hand_source),
        put: |v, x| v.hand_source = pick(HAND_SOURCES, x),
    },
    ParamSpec {
        id: "smass",
        name: "Slide mass",
        group: Group::Slide,
        kind: float(5.0, 200.0, 30.0, " g", Scale::Skewed(-1.5), ValueDisplay::Rounded(1)),
        maps_to: "[`Settings::slide_mass`]",
        get: |v| v.slide_mass_g,
        put: |v, x| v.slide_mass_g = x,
    },
    ParamSpec {
        id: "hstiff",
        name: "Hand stiffness",
        group: Group::Slide,
        kind: float(1e2, 1e6, 1e4, " N/m", Scale::Skewed(-2.5), ValueDisplay::Rounded(0)),
        maps_to: "[`Settings::hand_stiffness`]",
        get: |v| v.hand_stiffness,
        put: |v, x| v.hand_stiffness = x,
    },
    ParamSpec {
        id: "hdamp",
        name: "Hand damping",
        group: Group::Slide,
        kind: float(0.0, 100.0, 5.0, " kg/s", Scale::Linear, ValueDisplay::Rounded(1)),
        maps_to: "[`Settings::hand_damping`]",
        get: |v| v.hand_damping,
        put: |v, x| v.hand_damping = x,
    },
    ParamSpec {
        id: "fdamp",
        name: "Finger damping",
        group: Group::Slide,
        kind: float(0.0, 50.0, 5.0, " s/m", Scale::Linear, ValueDisplay::Rounded(1)),
        maps_to: "[`Settings::finger_damping`]",
        get: |v| v.finger_damping,
        put: |v, x| v.finger_damping = x,
    },
    ParamSpec {
        id: "kappa",
        name: "Slide stiffness",
        group: Group::Slide,
        kind: float(1e6, 1e13, 1e9, " N/m^a", Scale::Skewed(-3.0), ValueDisplay::Scientific(2)),
        maps_to: "[`Settings::slide_kappa`] (κ)",
        get: |v| v.kappa,
        put: |v, x| v.kappa = x,
    },
    ParamSpec {
        id: "alpha",
        name: "Slide exponent",
        group: Group::Slide,
        kind: float(1.0, 3.0, 1.5, "", Scale::Linear, ValueDisplay::Rounded(2)),
        maps_to: "[`Settings::slide_alpha`] (α)",
        get: |v| v.alpha,
        put: |v, x| v.alpha = x,
    },
    ParamSpec {
        id: "pluck",
        name: "Pluck position",
        group: Group::Slide,
        kind: float(0.5, 0.98, 0.9, "", Scale::Linear, ValueDisplay::Rounded(3)),
        maps_to: "[`Settings::pluck_position`] (fraction of the length)",
        get: |v| v.pluck_position,
        put: |v, x| v.pluck_position = x,
    },
    ParamSpec {
        id: "pickup",
        name: "Pickup position",
        group: Group::Slide,
        kind: float(0.5, 0.98, 0.9, "", Scale::Linear, ValueDisplay::Rounded(3)),
        maps_to: "[`Settings::pickup_position`] (fraction of the length)",
        get: |v| v.pickup_position,
        put: |v, x| v.pickup_position = x,
    },
    ParamSpec {
        id: "ptone",
        name: "Pickup resonance",
        group: Group::Slide,
        kind: float(1000.0, 10_000.0, 3500.0, " Hz", Scale::Skewed(-1.0), ValueDisplay::Rounded(0)),
        maps_to: "[`Settings::pickup_resonance`] (the loaded pickup's resonance)",
        get: |v| v.pickup_resonance,
        put: |v, x| v.pickup_resonance = x,
    },
    ParamSpec {
        id: "sbody",
        name: "Guitar",
        group: Group::Slide,
        kind: ParamKind::Choice { options: &[("electric", "Electric"), ("acoustic", "Acoustic")], default: 0 },
        maps_to: "[`Settings::slide_body`] (new notes)",
        get: |v| index(SLIDE_BODIES, v.slide_body),
        put: |v, x| v.slide_body = pick(SLIDE_BODIES, x),
    },
    ParamSpec {
        id: "gain",
        name: "Output gain",
        group: Group::Output,
        kind: float(
            GAIN_RANGE_DB.0 as f32,
            GAIN_RANGE_DB.1 as f32,
            0.0,
            " dB",
            Scale::Decibels,
            ValueDisplay::Rounded(1),
        ),
        maps_to: "[`Settings::gain`] (linear)",
        get: |v| v.gain,
        put: |v, x| v.gain = x,
    },
    ParamSpec {
        id: "limit",
        name: "Safety limiter",
        group: Group::Output,
        kind: ParamKind::Bool { default: true },
        maps_to: "[`Settings::limiter`]",
        get: |v| switch(v.limiter),
        put: |v, x| v.limiter = x != 0.0,
    },
    ParamSpec {
        id: "width",
        name: "Stereo width",
        group: Group::Output,
        kind: float(-100.0, 100.0, 60.0, " %", Scale::Linear, ValueDisplay::Rounded(0)),
        maps_to: "[`Settings::stereo_width`] (×0.01; the piano's keys panned along the bridge, the acoustic guitar body's higher modes left and right)",
        get: |v| v.stereo_width,
        put: |v, x| v.stereo_width = x,
    },
];

/// The parameter ids, in display order.
pub const PARAM_IDS: [&str; PARAMETERS.len()] = {
    let mut ids = [""; PARAMETERS.len()];
    let mut i = 0;
    while i < ids.len() {
        ids[i] = PARAMETERS[i].id;
        i += 1;
    }
    ids
};

/// The index in [`PARAMETERS`] of parameter `id`. In a constant, an unknown id is a compile error.
pub const fn param_index(id: &str) -> usize {
    let mut i = 0;
    while i < PARAMETERS.len() {
        if same(PARAMETERS[i].id.as_bytes(), id.as_bytes()) {
            return i;
        }
        i += 1;
    }
    panic!("no parameter has this id")
}

/// Byte-wise equality, usable in constants.
const fn same(a: &[u8], b: &[u8]) -> bool {
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// The parameter with id `id`, if any.
pub fn param_spec(id: &str) -> Option<&'static ParamSpec> {
    PARAMETERS.iter().find(|p| p.id == id)
}

/// A finite number typed with or without `unit` after it ([`ParamSpec::parse_typed`]).
fn typed_number(text: &str, unit: &str) -> Option<f32> {
    let unit = unit.trim();
    let aliases: &[&str] = if unit == "×" { &["×", "x"] } else { &[unit] };
    let number = (aliases.iter())
        .filter(|unit| !unit.is_empty())
        .find_map(|unit| {
            let at = text.len().checked_sub(unit.len())?;
            (text.is_char_boundary(at) && text[at..].eq_ignore_ascii_case(unit)).then(|| text[..at].trim_end())
        })
        .unwrap_or(text);
    // A comma is a decimal comma unless it could group thousands (`10,000` or `0,125`: three
    // digits after it), which is read as nothing rather than guessed.
    let number = match number.split_once(',') {
        None => number.to_owned(),
        Some((_, after)) if after.len() == 3 && after.bytes().all(|b| b.is_ascii_digit()) => return None,
        Some(_) if number.contains('.') => return None,
        Some(_) => number.replacen(',', ".", 1),
    };
    number.parse::<f32>().ok().filter(|v| v.is_finite())
}

impl ParamSpec {
    /// The default as a plain value (what [`ParamSpec::get`] gives for it).
    pub fn default_plain(&self) -> f32 {
        match self.kind {
            ParamKind::Float { default, scale, .. } => scale.to_plain(default),
            ParamKind::Int { default, .. } => default as f32,
            ParamKind::Bool { default } => switch(default),
            ParamKind::Choice { default, .. } => default as f32,
        }
    }

    /// The number of steps a host sees (CLAP value range 0..=steps) for a stepped parameter;
    /// `None` for a continuous one.
    pub const fn step_count(&self) -> Option<u32> {
        match self.kind {
            ParamKind::Float { .. } => None,
            ParamKind::Int { min, max, .. } => Some(max.abs_diff(min)),
            ParamKind::Bool { .. } => Some(1),
            ParamKind::Choice { options, .. } => Some(options.len() as u32 - 1),
        }
    }

    /// The value `text` gives this parameter, in its shown unit (gain in dB, choices as their
    /// index, switches 0 or 1), or what was expected instead. Not range-checked: a finite number
    /// beyond an `f32`, or a whole number beyond an `i32`, is read as the nearest one there is, so
    /// that the range check refuses it as out of range rather than as no number.
    pub fn parse(&self, text: &str) -> Result<f32, String> {
        match self.kind {
            ParamKind::Float { .. } => text
                .trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .map(|v| v.clamp(-f64::from(f32::MAX), f64::from(f32::MAX)) as f32)
                .ok_or_else(|| "a finite number".into()),
            ParamKind::Int { .. } => text
                .trim()
                .parse::<i64>()
                .map(|v| v.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as f32)
                .map_err(|_| "a whole number".into()),
            ParamKind::Bool { .. } => match text.trim() {
                "on" | "true" | "1" => Ok(1.0),
                "off" | "false" | "0" => Ok(0.0),
                _ => Err("on or off".into()),
            },
            ParamKind::Choice { options, .. } => {
                options.iter().position(|(id, _)| *id == text).map(|i| i as f32).ok_or_else(|| {
                    let ids: Vec<&str> = options.iter().map(|(id, _)| *id).collect();
                    match ids.split_last() {
                        Some((last, [])) => (*last).to_owned(),
                        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
                        None => String::new(),
                    }
                })
            }
        }
    }

    /// The value of `text` typed by hand into a field that shows this parameter, in its shown
    /// unit, as a host's or the editor's text entry reads it: what [`parse`](Self::parse) reads,
    /// and also a number followed by the parameter's unit (with or without its space, in any
    /// letter case; `x` for `×`), a decimal comma (not one that could group thousands: `10,000`
    /// and `0,125` read as nothing), a whole number written with decimals (rounded) and a
    /// switch's `On`/`Off` in any case. `None` for anything else, NaN and infinities included,
    /// so that a slip of the keyboard changes nothing. Not range-checked (the framework clamps);
    /// choices are left to the framework, which reads their names.
    pub fn parse_typed(&self, text: &str) -> Option<f32> {
        let text = text.trim();
        match self.kind {
            ParamKind::Float { unit, .. } => typed_number(text, unit),
            ParamKind::Int { unit, .. } => typed_number(text, unit).map(f32::round),
            ParamKind::Bool { .. } => self.parse(&text.to_ascii_lowercase()).ok(),
            ParamKind::Choice { .. } => None,
        }
    }

    /// The plain value of `shown`, a value in the parameter's shown unit (gain: dB to linear).
    pub fn to_plain(&self, shown: f32) -> f32 {
        match self.kind {
            ParamKind::Float { scale, .. } => scale.to_plain(shown),
            _ => shown,
        }
    }

    /// `plain`, a plain value as saved state holds it, brought into the parameter's range (a
    /// choice to its index range); a value that is not finite gives the default.
    pub fn clamp_plain(&self, plain: f32) -> f32 {
        let (lo, hi) = match self.kind {
            ParamKind::Float { min, max, .. } => (self.to_plain(min), self.to_plain(max)),
            ParamKind::Int { min, max, .. } => (min as f32, max as f32),
            ParamKind::Bool { .. } => (0.0, 1.0),
            ParamKind::Choice { options, .. } => (0.0, options.len().saturating_sub(1) as f32),
        };
        if plain.is_finite() { plain.clamp(lo, hi) } else { self.default_plain() }
    }

    /// Whether `shown`, a value in the parameter's shown unit, is in its range.
    pub fn contains(&self, shown: f32) -> bool {
        match self.kind {
            ParamKind::Float { min, max, .. } => (min..=max).contains(&shown),
            ParamKind::Int { min, max, .. } => (min as f32..=max as f32).contains(&shown),
            ParamKind::Bool { .. } => shown == 0.0 || shown == 1.0,
            ParamKind::Choice { options, .. } => (0.0..options.len() as f32).contains(&shown),
        }
    }

    /// The range as the documentation writes it: `1..=64`, `-36..=12 dB`, `1e6..=1e13 N/m^a`,
    /// `on/off`, or the options' names.
    pub fn range_text(&self) -> String {
        match self.kind {
            ParamKind::Float { min, max, unit, .. } => format!("{}..={}{unit}", number_text(min), number_text(max)),
            ParamKind::Int { min, max, unit, .. } => format!("{min}..={max}{unit}"),
            ParamKind::Bool { .. } => "on/off".into(),
            ParamKind::Choice { options, .. } => options.iter().map(|(_, name)| *name).collect::<Vec<_>>().join(", "),
        }
    }

    /// The default as the documentation writes it (`60 1/s`, `1e9 N/m^a`, `Piano`, `on`).
    pub fn default_text(&self) -> String {
        match self.kind {
            ParamKind::Float { default, unit, .. } => format!("{}{unit}", number_text(default)),
            ParamKind::Int { default, unit, .. } => format!("{default}{unit}"),
            ParamKind::Bool { default } => (if default { "on" } else { "off" }).into(),
            ParamKind::Choice { options, default } => options[default].1.into(),
        }
    }
}

/// A number as the documentation writes it: `0.25`, `2000`, and from 1e5 up in powers of ten
/// (`1e6`).
fn number_text(value: f32) -> String {
    if value.abs() >= 1e5 { format!("{value:e}") } else { value.to_string() }
}

impl Scale {
    /// The plain value of `shown` (dB to linear gain for [`Scale::Decibels`]).
    pub fn to_plain(self, shown: f32) -> f32 {
        match self {
            // As the plugin framework converts (`util::db_to_gain`), so that a range's end in
            // dB is, to the bit, the end of the plugin's parameter.
            Scale::Decibels => 10f32.powf(shown * 0.05),
            Scale::Linear | Scale::Skewed(_) => shown,
        }
    }
}

/// Plain parameter values (the plugin's units: ms, mm, g, linear gain). [`PARAMETERS`] says which
/// field each id sets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamValues {
    /// `mode`.
    pub mode: Mode,
    /// `solver`.
    pub method: Method,
    /// `segs`.
    pub segments: i32,
    /// `nb` (samples).
    pub block: i32,
    /// `voices` (pool size at the next activation).
    pub voices: i32,
    /// `guard`.
    pub overload_guard: bool,
    /// `hard` (×).
    pub hardness: f32,
    /// `hmass` (×).
    pub hammer_mass: f32,
    /// `strike` (×).
    pub strike_position: f32,
    /// `damp` (×).
    pub damping: f32,
    /// `bright` (×).
    pub brightness: f32,
    /// `damper` (1/s).
    pub damper: f32,
    /// `detune` (cents).
    pub unison_detune: f32,
    /// `stretch` (×).
    pub stretch: f32,
    /// `hpfrom` (% of the sustain pedal's travel).
    pub half_pedal_from: f32,
    /// `hpto` (% of the sustain pedal's travel).
    pub half_pedal_to: f32,
    /// `slide` (semitones).
    pub slide_position: f32,
    /// `follow`.
    pub follow_key: bool,
    /// `glide` (ms).
    pub glide_ms: f32,
    /// `bend` (semitones).
    pub bend_range: f32,
    /// `hand` (mm).
    pub hand_mm: f32,
    /// `handsrc`.
    pub hand_source: HandSource,
    /// `smass` (g).
    pub slide_mass_g: f32,
    /// `hstiff` (N/m).
    pub hand_stiffness: f32,
    /// `hdamp` (kg/s).
    pub hand_damping: f32,
    /// `fdamp` (s/m).
    pub finger_damping: f32,
    /// `kappa` (N/m^α).
    pub kappa: f32,
    /// `alpha`.
    pub alpha: f32,
    /// `pluck` (fraction).
    pub pluck_position: f32,
    /// `pickup` (fraction).
    pub pickup_position: f32,
    /// `ptone` (Hz).
    pub pickup_resonance: f32,
    /// `sbody`.
    pub slide_body: SlideBody,
    /// `gain` (linear).
    pub gain: f32,
    /// `limit`.
    pub limiter: bool,
    /// `width` (%).
    pub stereo_width: f32,
}

impl Default for ParamValues {
    /// Every parameter at its default in [`PARAMETERS`].
    fn default() -> Self {
        let mut values = Self {
            mode: Mode::Piano,
            method: Method::Qsa,
            segments: 0,
            block: 0,
            voices: 0,
            overload_guard: false,
            hardness: 0.0,
            hammer_mass: 0.0,
            strike_position: 0.0,
            damping: 0.0,
            brightness: 0.0,
            damper: 0.0,
            unison_detune: 0.0,
            stretch: 0.0,
            half_pedal_from: 0.0,
            half_pedal_to: 0.0,
            slide_position: 0.0,
            follow_key: false,
            glide_ms: 0.0,
            bend_range: 0.0,
            hand_mm: 0.0,
            hand_source: HandSource::Parameter,
            slide_mass_g: 0.0,
            hand_stiffness: 0.0,
            hand_damping: 0.0,
            finger_damping: 0.0,
            kappa: 0.0,
            alpha: 0.0,
            pluck_position: 0.0,
            pickup_position: 0.0,
            pickup_resonance: 0.0,
            slide_body: SlideBody::Pickup,
            gain: 0.0,
            limiter: false,
            stereo_width: 0.0,
        };
        for spec in &PARAMETERS {
            (spec.put)(&mut values, spec.default_plain());
        }
        values
    }
}

/// Why `--set ID=VALUE` was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// No parameter has that id.
    #[error("unknown parameter id \"{0}\" (one of: {ids})", ids = PARAM_IDS.join(", "))]
    UnknownId(String),
    /// A value outside the parameter's range (the plugin would clamp it, so it would not sound as
    /// written).
    #[error("{id} = {value} is outside the parameter's range {range}")]
    OutOfRange {
        /// The parameter id.
        id: String,
        /// The text given.
        value: String,
        /// The range ([`ParamSpec::range_text`]).
        range: String,
    },
    /// The value does not parse for that parameter.
    #[error("{id}: cannot use \"{value}\" ({expected})")]
    BadValue {
        /// The parameter id.
        id: String,
        /// The text given.
        value: String,
        /// What was expected.
        expected: String,
    },
}

impl ParamValues {
    /// The engine settings for these values. Allocation-free.
    pub fn settings(&self) -> Settings {
        let f = f64::from;
        Settings {
            mode: self.mode,
            method: self.method,
            segments: self.segments.max(1) as usize,
            block: self.block.max(1) as usize,
            hardness: f(self.hardness),
            hammer_mass: f(self.hammer_mass),
            strike_position: f(self.strike_position),
            damping: f(self.damping),
            brightness: f(self.brightness),
            damper_rate: f(self.damper),
            unison_detune: f(self.unison_detune),
            stretch: f(self.stretch),
            half_pedal_from: f(self.half_pedal_from) * 0.01,
            half_pedal_to: f(self.half_pedal_to) * 0.01,
            slide_position: f(self.slide_position),
            follow_key: self.follow_key,
            glide_time: f(self.glide_ms) * 1e-3,
            bend_range: f(self.bend_range),
            hand_height: f(self.hand_mm) * 1e-3,
            hand_source: self.hand_source,
            slide_mass: f(self.slide_mass_g) * 1e-3,
            hand_stiffness: f(self.hand_stiffness),
            hand_damping: f(self.hand_damping),
            finger_damping: f(self.finger_damping),
            slide_kappa: f(self.kappa),
            slide_alpha: f(self.alpha),
            pluck_position: f(self.pluck_position),
            pickup_position: f(self.pickup_position),
            pickup_resonance: f(self.pickup_resonance),
            slide_body: self.slide_body,
            gain: f(self.gain),
            limiter: self.limiter,
            stereo_width: f(self.stereo_width) * 0.01,
            ..Settings::default()
        }
    }

    /// Set parameter `id` from text ([`ParamSpec::parse`]): numbers in the parameter's unit
    /// (`gain` in dB, like the plugin shows it), `on`/`off` for switches, option ids for the
    /// choices (`piano`/`slide`, `qsa`/`exp`/`imp`, `param`/`modwheel`/`chanpress`/`polypress`/
    /// `cc74`, `electric`/`acoustic`); a number outside the parameter's range is refused, naming
    /// it, and a stepped one takes its nearest step.
    pub fn set(&mut self, id: &str, value: &str) -> Result<(), ParamError> {
        let spec = param_spec(id).ok_or_else(|| ParamError::UnknownId(id.to_owned()))?;
        let shown = spec.parse(value).map_err(|expected| ParamError::BadValue {
            id: id.to_owned(),
            value: value.to_owned(),
            expected,
        })?;
        if !spec.contains(shown) {
            return Err(ParamError::OutOfRange {
                id: id.to_owned(),
                value: value.to_owned(),
                range: spec.range_text(),
            });
        }
        // A stepped parameter takes the step nearest the value, as the plugin's own rounds what a
        // host sends (`(v/step).round()·step`), so that a render plays what the plugin would.
        let shown = match spec.kind {
            ParamKind::Float { step: Some(step), .. } => (shown / step).round() * step,
            _ => shown,
        };
        (spec.put)(self, spec.to_plain(shown));
        Ok(())
    }

    /// The plugin's plain value of parameter `id` as an `f32`, as a host-facing parameter holds it:
    /// numbers in the parameter's unit (`gain` linear, not dB), whole numbers as themselves,
    /// switches as 0 or 1, and choices as their option index. `None` for an unknown id. This is how
    /// a preset is applied to the plugin's parameters.
    pub fn plain(&self, id: &str) -> Option<f32> {
        param_spec(id).map(|spec| (spec.get)(self))
    }

    /// The first parameter (in [`PARAMETERS`] order) whose plain value differs from `other`'s by
    /// more than a host's `f32` normalisation can account for (relative 1e-4, or 1e-5 absolute
    /// near zero), or `None` when they match. Used to mark a preset as modified.
    pub fn first_difference(&self, other: &Self) -> Option<&'static str> {
        self.first_difference_among(other, |_| true)
    }

    /// [`first_difference`](Self::first_difference) among the parameters whose id `compared`
    /// accepts.
    pub fn first_difference_among(&self, other: &Self, compared: impl Fn(&str) -> bool) -> Option<&'static str> {
        PARAMETERS
            .iter()
            .filter(|spec| compared(spec.id))
            .map(|spec| (spec.id, (spec.get)(self), (spec.get)(other)))
            .find_map(|(id, a, b)| plain_values_differ(a, b).then_some(id))
    }
}

/// Whether two plain values of a parameter differ by more than a host's `f32` normalisation can
/// account for: relative 1e-4, or 1e-5 absolute near zero
/// ([`ParamValues::first_difference`]'s tolerance).
pub fn plain_values_differ(a: f32, b: f32) -> bool {
    (a - b).abs() > 1e-5f32.max(1e-4 * a.abs().max(b.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stepped parameter set between its steps takes the nearest, as the plugin's parameter
    /// does: `bend = 1.3` (steps of 0.5) plays a range of 1.5 semitones, and 1.2 one of 1.0.
    #[test]
    fn a_stepped_parameter_set_between_steps_takes_the_nearest() {
        let mut values = ParamValues::default();
        for (given, taken) in [("1.3", 1.5), ("1.2", 1.0), ("24", 24.0), ("0.1", 0.0)] {
            values.set("bend", given).unwrap();
            assert_eq!(values.plain("bend"), Some(taken), "bend = {given}");
        }
    }

    /// Text typed by hand reads as a number with or without its unit, a decimal comma, a whole
    /// number rounded, a switch in any case; NaN, infinities, other words and a bare unit read as
    /// nothing.
    #[test]
    fn typed_text_reads_as_a_finite_value_or_nothing() {
        let spec = |id| param_spec(id).unwrap();
        let cases: [(&str, &str, Option<f32>); 27] = [
            ("glide", "50", Some(50.0)),
            ("glide", " 50 ms ", Some(50.0)),
            ("glide", "50ms", Some(50.0)),
            ("glide", "50 MS", Some(50.0)),
            ("glide", "12,5", Some(12.5)),
            ("ptone", "10,000", None),
            ("pluck", "0,125", None),
            ("glide", "1,000.5", None),
            ("glide", "1e2", Some(100.0)),
            ("glide", "nan", None),
            ("glide", "NaN ms", None),
            ("glide", "inf", None),
            ("glide", "-infinity", None),
            ("glide", "ms", None),
            ("glide", "fast", None),
            ("gain", "-6 dB", Some(-6.0)),
            ("gain", "-6db", Some(-6.0)),
            ("gain", "-inf dB", None),
            ("kappa", "1.5e9 N/m^a", Some(1.5e9)),
            ("hard", "1.5×", Some(1.5)),
            ("hard", "1.5X", Some(1.5)),
            ("nb", "6.5 smp", Some(7.0)),
            ("nb", "64", Some(64.0)),
            ("limit", "On", Some(1.0)),
            ("limit", "0", Some(0.0)),
            ("limit", "yes", None),
            ("mode", "slide", None),
        ];
        for (id, text, expected) in cases {
            assert_eq!(spec(id).parse_typed(text), expected, "{id}: {text:?}");
        }
    }

    /// A value outside a parameter's range is refused with the range, and the value kept, beyond
    /// an `f32` or an `i32` too (not as no number); the ends of the range are accepted.
    #[test]
    fn setting_a_value_outside_its_range_is_refused_with_the_range() {
        let mut values = ParamValues::default();
        for (id, value, range) in [
            ("gain", "100", "gain = 100 is outside the parameter's range -36..=12 dB"),
            ("segs", "0", "1..=64"),
            ("voices", "1000", "1..=128"),
            ("hard", "1e39", "hard = 1e39 is outside the parameter's range"),
            ("segs", "3000000000", "segs = 3000000000 is outside the parameter's range"),
        ] {
            let before = values.plain(id);
            let err = values.set(id, value).expect_err(id).to_string();
            assert!(err.contains(range), "{id}={value}: {err}");
            assert_eq!(values.plain(id), before, "{id} unchanged");
        }
        values.set("gain", "-36").unwrap();
        values.set("gain", "12").unwrap();
        values.set("voices", "128").unwrap();
    }

    /// Whether two `Debug` texts are the same but for numbers that differ by no more than an
    /// `f32`'s rounding (the table's ends are `f32`, the engine's `f64`).
    fn same_to_f32(a: &str, b: &str) -> bool {
        let words = |s: &str| {
            s.split([' ', ',', ':', '{', '}']).filter(|w| !w.is_empty()).map(str::to_owned).collect::<Vec<_>>()
        };
        let (a, b) = (words(a), words(b));
        a.len() == b.len()
            && a.iter().zip(&b).all(|(x, y)| match (x.parse::<f64>(), y.parse::<f64>()) {
                (Ok(x), Ok(y)) => (x - y).abs() <= 1e-7 * x.abs().max(y.abs()),
                _ => x == y,
            })
    }

    /// The engine plays no value a parameter cannot take: for every number, a plain value far
    /// beyond either end of its range (as a corrupt saved state may hold) gives the engine the
    /// same settings as that end, and `clamp_plain` brings it to that end (a NaN to the default).
    #[test]
    fn the_engine_clamps_every_number_to_its_parameters_range() {
        for spec in &PARAMETERS {
            let (lo, hi) = match spec.kind {
                ParamKind::Float { min, max, .. } => (spec.to_plain(min), spec.to_plain(max)),
                ParamKind::Int { min, max, .. } => (min as f32, max as f32),
                _ => continue,
            };
            let span = (hi - lo).max(1.0);
            for (end, beyond) in [(lo, (lo - 100.0 * span).min(0.0)), (hi, hi + 100.0 * span)] {
                let with = |plain: f32| {
                    let mut values = ParamValues::default();
                    (spec.put)(&mut values, plain);
                    values.settings().sanitized()
                };
                let (a, b) = (format!("{:?}", with(beyond)), format!("{:?}", with(end)));
                assert!(same_to_f32(&a, &b), "{}: {beyond} plays as {end}:\n{a}\n{b}", spec.id);
                assert_eq!(spec.clamp_plain(beyond), end, "{}: {beyond} clamped", spec.id);
            }
            assert_eq!(spec.clamp_plain(f32::NAN), spec.default_plain(), "{}: NaN", spec.id);
        }
    }

    /// Ids are unique, every default is in its range, and `param_index` finds each.
    #[test]
    fn the_table_is_consistent() {
        for (i, spec) in PARAMETERS.iter().enumerate() {
            assert_eq!(param_index(spec.id), i);
            assert_eq!(PARAMETERS.iter().filter(|p| p.id == spec.id).count(), 1, "{} is unique", spec.id);
            let shown = match spec.kind {
                ParamKind::Float { default, .. } => default,
                _ => spec.default_plain(),
            };
            assert!(spec.contains(shown), "{}: default in range", spec.id);
        }
    }

    /// Released ids never change: saved state, automation, presets and hosts refer to them.
    #[test]
    fn ids_are_the_released_ones() {
        let released = [
            "mode", "solver", "segs", "nb", "voices", "guard", "hard", "hmass", "strike", "damp", "bright", "damper",
            "detune", "stretch", "hpfrom", "hpto", "slide", "follow", "glide", "bend", "hand", "handsrc", "smass",
            "hstiff", "hdamp", "fdamp", "kappa", "alpha", "pluck", "pickup", "ptone", "sbody", "gain", "limit",
            "width",
        ];
        assert_eq!(PARAM_IDS, released);
    }

    /// The table's defaults are the engine's defaults.
    #[test]
    fn defaults_give_the_default_settings() {
        let s = ParamValues::default().settings();
        let d = Settings::default();
        assert_eq!((s.mode, s.method, s.segments, s.block), (d.mode, d.method, d.segments, d.block));
        assert_eq!((s.follow_key, s.hand_source, s.limiter), (d.follow_key, d.hand_source, d.limiter));
        assert_eq!(s.slide_body, d.slide_body);
        let pairs = [
            (s.hardness, d.hardness),
            (s.hammer_mass, d.hammer_mass),
            (s.strike_position, d.strike_position),
            (s.damping, d.damping),
            (s.brightness, d.brightness),
            (s.damper_rate, d.damper_rate),
            (s.unison_detune, d.unison_detune),
            (s.stretch, d.stretch),
            (s.half_pedal_from, d.half_pedal_from),
            (s.half_pedal_to, d.half_pedal_to),
            (s.slide_position, d.slide_position),
            (s.glide_time, d.glide_time),
            (s.bend_range, d.bend_range),
            (s.hand_height, d.hand_height),
            (s.slide_mass, d.slide_mass),
            (s.hand_stiffness, d.hand_stiffness),
            (s.hand_damping, d.hand_damping),
            (s.finger_damping, d.finger_damping),
            (s.slide_kappa, d.slide_kappa),
            (s.slide_alpha, d.slide_alpha),
            (s.pluck_position, d.pluck_position),
            (s.pickup_position, d.pickup_position),
            (s.pickup_resonance, d.pickup_resonance),
            (s.gain, d.gain),
            (s.stereo_width, d.stereo_width),
        ];
        for (i, (got, want)) in pairs.into_iter().enumerate() {
            assert!((got - want).abs() <= 1e-7 * want.abs().max(1e-3), "pair {i}: {got} vs {want}");
        }
    }

    /// The engine's clamping ([`Settings::sanitized`]) keeps every continuous parameter's whole
    /// range and no more: the table's ranges are the engine's (gain aside, whose engine range is
    /// wider).
    #[test]
    fn ranges_are_the_engines() {
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 * a.abs().max(b.abs()).max(1e-9);
        let fields = |s: &Settings| {
            [s.hardness, s.hammer_mass, s.strike_position, s.damping, s.brightness, s.damper_rate, s.slide_position]
                .into_iter()
                .chain([s.unison_detune, s.stretch, s.half_pedal_from, s.half_pedal_to])
                .chain([s.glide_time, s.bend_range, s.hand_height, s.slide_mass, s.hand_stiffness, s.hand_damping])
                .chain([s.finger_damping, s.slide_kappa, s.slide_alpha, s.pluck_position, s.pickup_position])
                .chain([s.pickup_resonance, s.stereo_width])
                .collect::<Vec<f64>>()
        };
        for spec in PARAMETERS.iter().filter(|p| p.id != "gain") {
            let ParamKind::Float { min, max, .. } = spec.kind else { continue };
            let span = max - min;
            for (shown, inside) in [(min, true), (max, true), (min - 0.01 * span, false), (max + 0.01 * span, false)] {
                let mut values = ParamValues::default();
                (spec.put)(&mut values, shown);
                let settings = values.settings();
                let unchanged =
                    fields(&settings).into_iter().zip(fields(&settings.sanitized())).all(|(a, b)| close(a, b));
                assert_eq!(unchanged, inside, "{} = {shown}", spec.id);
            }
        }
        for (id, max) in [("segs", MAX_SEGMENTS), ("nb", MAX_BLOCK), ("voices", MAX_VOICES)] {
            let Some(ParamSpec { kind: ParamKind::Int { min, max: top, .. }, .. }) = param_spec(id) else {
                panic!("{id} is a whole number")
            };
            assert_eq!((*min, *top), (1, max as i32), "{id}");
        }
    }

    /// The solver's option ids are the methods' names, which are serde's (scene files).
    #[test]
    fn solver_names_are_the_methods_names() {
        for method in Method::ALL {
            assert_eq!(Method::from_name(method.name()), Some(method));
            assert_eq!(toml::Value::try_from(method).unwrap(), toml::Value::String(method.name().into()));
            let mut values = ParamValues::default();
            values.set("solver", method.name()).unwrap();
            assert_eq!(values.method, method);
        }
        assert_eq!(Method::from_name("QSA"), None);
    }

    #[test]
    fn every_id_can_be_set_and_unknown_ones_are_refused() {
        let mut p = ParamValues::default();
        for id in PARAM_IDS {
            // A number within each range: its upper end, or 2 where the range holds it.
            let number =
                |max: f32| if param_spec(id).unwrap().contains(2.0) { "2".to_owned() } else { max.to_string() };
            let value = match (id, param_spec(id).unwrap().kind) {
                ("mode", _) => "slide".to_owned(),
                ("solver", _) => "imp".to_owned(),
                ("handsrc", _) => "modwheel".to_owned(),
                ("sbody", _) => "acoustic".to_owned(),
                ("follow" | "limit" | "guard", _) => "off".to_owned(),
                (_, ParamKind::Float { max, .. }) => number(max),
                (_, ParamKind::Int { max, .. }) => number(max as f32),
                _ => unreachable!("{id}: every switch and choice is named above"),
            };
            p.set(id, &value).unwrap_or_else(|e| panic!("{id}: {e}"));
        }
        assert_eq!((p.mode, p.slide_body), (Mode::Slide, SlideBody::Acoustic));
        assert!((p.gain - 10f32.powf(0.1)).abs() < 1e-6, "gain is given in dB");
        assert!(matches!(p.set("kapa", "1"), Err(ParamError::UnknownId(_))));
        assert!(p.set("hard", "nan").is_err());
        assert_eq!(p.set("mode", "banjo").unwrap_err().to_string(), "mode: cannot use \"banjo\" (piano or slide)");
        let expected = p.set("handsrc", "foot").unwrap_err().to_string();
        assert_eq!(expected, "handsrc: cannot use \"foot\" (param, modwheel, chanpress, polypress or cc74)");
    }

    /// `plain` knows every id, reads back what `set` stored (gain linear, choices as indices) and
    /// `first_difference` names the one parameter that changed.
    #[test]
    fn plain_values_read_back_what_set_stored() {
        let defaults = ParamValues::default();
        assert!(PARAM_IDS.iter().all(|id| defaults.plain(id).is_some()));
        assert_eq!(defaults.plain("kapa"), None);
        let mut p = defaults;
        for (id, text, plain) in [
            ("mode", "slide", 1.0),
            ("solver", "imp", 2.0),
            ("handsrc", "polypress", 3.0),
            ("follow", "off", 0.0),
            ("segs", "13", 13.0),
            ("hard", "0.25", 0.25),
            ("gain", "-6", 0.501_187_2),
        ] {
            p.set(id, text).unwrap();
            let got = p.plain(id).unwrap();
            assert!((got - plain).abs() < 1e-6, "{id}: {got}, expected {plain}");
        }
        for spec in &PARAMETERS {
            let mut values = defaults;
            (spec.put)(&mut values, spec.default_plain());
            assert_eq!(values, defaults, "{}: put and get agree on the default", spec.id);
            assert_eq!((spec.get)(&defaults), spec.default_plain(), "{}", spec.id);
        }
        assert_eq!(defaults.first_difference(&defaults), None);
        let mut q = defaults;
        q.kappa *= 1.000_01;
        assert_eq!(defaults.first_difference(&q), None, "f32 normalisation noise is no change");
        q.alpha = 2.0;
        assert_eq!(defaults.first_difference(&q), Some("alpha"));
    }
}
