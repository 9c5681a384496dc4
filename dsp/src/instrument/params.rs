//! Parameter values as the plugin stores them (plain values, `f32`, in the units the plugin shows),
//! keyed by the plugin's stable ids, and their one mapping to [`Settings`].
//!
//! The plugin and the offline MIDI renderer both build their [`Settings`] through
//! [`ParamValues::settings`], so the same parameter values give the same samples in both.

use crate::contact::Method;
use crate::instrument::settings::{HandSource, Mode, Settings};

/// The plugin's parameter ids, in display order.
pub const PARAM_IDS: [&str; 27] = [
    "mode", "solver", "segs", "nb", "voices", "hard", "hmass", "strike", "damp", "bright", "damper", "slide", "follow",
    "glide", "bend", "hand", "handsrc", "smass", "hstiff", "hdamp", "fdamp", "kappa", "alpha", "pluck", "pickup",
    "gain", "limit",
];

/// Plain parameter values (the plugin's units: ms, mm, g, linear gain).
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
    /// `gain` (linear).
    pub gain: f32,
    /// `limit`.
    pub limiter: bool,
}

impl Default for ParamValues {
    fn default() -> Self {
        let d = Settings::default();
        Self {
            mode: d.mode,
            method: d.method,
            segments: d.segments as i32,
            block: d.block as i32,
            voices: 32,
            hardness: 1.0,
            hammer_mass: 1.0,
            strike_position: 1.0,
            damping: 1.0,
            brightness: 1.0,
            damper: d.damper_rate as f32,
            slide_position: d.slide_position as f32,
            follow_key: d.follow_key,
            glide_ms: (d.glide_time * 1000.0) as f32,
            bend_range: d.bend_range as f32,
            hand_mm: (d.hand_height * 1000.0) as f32,
            hand_source: d.hand_source,
            slide_mass_g: (d.slide_mass * 1000.0) as f32,
            hand_stiffness: d.hand_stiffness as f32,
            hand_damping: d.hand_damping as f32,
            finger_damping: d.finger_damping as f32,
            kappa: d.slide_kappa as f32,
            alpha: d.slide_alpha as f32,
            pluck_position: d.pluck_position as f32,
            pickup_position: d.pickup_position as f32,
            gain: d.gain as f32,
            limiter: d.limiter,
        }
    }
}

/// Why `--set ID=VALUE` was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// No parameter has that id.
    #[error("unknown parameter id \"{0}\" (one of: {ids})", ids = PARAM_IDS.join(", "))]
    UnknownId(String),
    /// The value does not parse for that parameter.
    #[error("{id}: cannot use \"{value}\" ({expected})")]
    BadValue {
        /// The parameter id.
        id: String,
        /// The text given.
        value: String,
        /// What was expected.
        expected: &'static str,
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
            gain: f(self.gain),
            limiter: self.limiter,
            ..Settings::default()
        }
    }

    /// Set parameter `id` from text: numbers in the parameter's unit (`gain` in dB, like the
    /// plugin shows it), `on`/`off` for `follow` and `limit`, names for the choices (`piano`/`slide`,
    /// `qsa`/`exp`/`imp`, `param`/`modwheel`/`chanpress`/`polypress`).
    pub fn set(&mut self, id: &str, value: &str) -> Result<(), ParamError> {
        let bad = |expected| ParamError::BadValue { id: id.to_owned(), value: value.to_owned(), expected };
        let number =
            || value.trim().parse::<f32>().ok().filter(|v| v.is_finite()).ok_or_else(|| bad("a finite number"));
        let whole = || value.trim().parse::<i32>().map_err(|_| bad("a whole number"));
        let switch = || match value.trim() {
            "on" | "true" | "1" => Some(true),
            "off" | "false" | "0" => Some(false),
            _ => None,
        };
        match id {
            "mode" => {
                self.mode = match value {
                    "piano" => Mode::Piano,
                    "slide" => Mode::Slide,
                    _ => return Err(bad("piano or slide")),
                }
            }
            "solver" => {
                self.method = match value {
                    "qsa" => Method::Qsa,
                    "exp" => Method::Exp,
                    "imp" => Method::Imp,
                    _ => return Err(bad("qsa, exp or imp")),
                }
            }
            "handsrc" => {
                self.hand_source = match value {
                    "param" => HandSource::Parameter,
                    "modwheel" => HandSource::ModWheel,
                    "chanpress" => HandSource::ChannelPressure,
                    "polypress" => HandSource::PolyPressure,
                    _ => return Err(bad("param, modwheel, chanpress or polypress")),
                }
            }
            "follow" => self.follow_key = switch().ok_or_else(|| bad("on or off"))?,
            "limit" => self.limiter = switch().ok_or_else(|| bad("on or off"))?,
            "segs" => self.segments = whole()?,
            "nb" => self.block = whole()?,
            "voices" => self.voices = whole()?,
            "hard" => self.hardness = number()?,
            "hmass" => self.hammer_mass = number()?,
            "strike" => self.strike_position = number()?,
            "damp" => self.damping = number()?,
            "bright" => self.brightness = number()?,
            "damper" => self.damper = number()?,
            "slide" => self.slide_position = number()?,
            "glide" => self.glide_ms = number()?,
            "bend" => self.bend_range = number()?,
            "hand" => self.hand_mm = number()?,
            "smass" => self.slide_mass_g = number()?,
            "hstiff" => self.hand_stiffness = number()?,
            "hdamp" => self.hand_damping = number()?,
            "fdamp" => self.finger_damping = number()?,
            "kappa" => self.kappa = number()?,
            "alpha" => self.alpha = number()?,
            "pluck" => self.pluck_position = number()?,
            "pickup" => self.pickup_position = number()?,
            "gain" => self.gain = 10f32.powf(number()? / 20.0),
            _ => return Err(ParamError::UnknownId(id.to_owned())),
        }
        Ok(())
    }

    /// The plugin's plain value of parameter `id` as an `f32`, as a host-facing parameter holds it:
    /// numbers in the parameter's unit (`gain` linear, not dB), whole numbers as themselves,
    /// `follow` and `limit` as 0 or 1, and choices as their index in the plugin's order (`mode`:
    /// piano, slide; `solver`: qsa, exp, imp; `handsrc`: param, modwheel, chanpress, polypress).
    /// `None` for an unknown id. This is how a preset is applied to the plugin's parameters.
    pub fn plain(&self, id: &str) -> Option<f32> {
        let switch = |on: bool| if on { 1.0 } else { 0.0 };
        Some(match id {
            "mode" => match self.mode {
                Mode::Piano => 0.0,
                Mode::Slide => 1.0,
            },
            "solver" => match self.method {
                Method::Qsa => 0.0,
                Method::Exp => 1.0,
                Method::Imp => 2.0,
            },
            "handsrc" => match self.hand_source {
                HandSource::Parameter => 0.0,
                HandSource::ModWheel => 1.0,
                HandSource::ChannelPressure => 2.0,
                HandSource::PolyPressure => 3.0,
            },
            "follow" => switch(self.follow_key),
            "limit" => switch(self.limiter),
            "segs" => self.segments as f32,
            "nb" => self.block as f32,
            "voices" => self.voices as f32,
            "hard" => self.hardness,
            "hmass" => self.hammer_mass,
            "strike" => self.strike_position,
            "damp" => self.damping,
            "bright" => self.brightness,
            "damper" => self.damper,
            "slide" => self.slide_position,
            "glide" => self.glide_ms,
            "bend" => self.bend_range,
            "hand" => self.hand_mm,
            "smass" => self.slide_mass_g,
            "hstiff" => self.hand_stiffness,
            "hdamp" => self.hand_damping,
            "fdamp" => self.finger_damping,
            "kappa" => self.kappa,
            "alpha" => self.alpha,
            "pluck" => self.pluck_position,
            "pickup" => self.pickup_position,
            "gain" => self.gain,
            _ => return None,
        })
    }

    /// The first parameter (in [`PARAM_IDS`] order) whose plain value differs from `other`'s by
    /// more than a host's `f32` normalisation can account for (relative 1e-4, or 1e-5 absolute
    /// near zero), or `None` when they match. Used to mark a preset as modified.
    pub fn first_difference(&self, other: &Self) -> Option<&'static str> {
        PARAM_IDS.into_iter().find(|id| {
            let (a, b) = (self.plain(id).unwrap_or(0.0), other.plain(id).unwrap_or(0.0));
            (a - b).abs() > 1e-5f32.max(1e-4 * a.abs().max(b.abs()))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_give_the_default_settings() {
        let s = ParamValues::default().settings();
        let d = Settings::default();
        assert_eq!((s.mode, s.method, s.segments, s.block), (d.mode, d.method, d.segments, d.block));
        assert!((s.glide_time - d.glide_time).abs() < 1e-9 && (s.hand_height - d.hand_height).abs() < 1e-9);
    }

    #[test]
    fn every_id_can_be_set_and_unknown_ones_are_refused() {
        let mut p = ParamValues::default();
        for id in PARAM_IDS {
            let value = match id {
                "mode" => "slide",
                "solver" => "imp",
                "handsrc" => "modwheel",
                "follow" | "limit" => "off",
                _ => "2",
            };
            p.set(id, value).unwrap_or_else(|e| panic!("{id}: {e}"));
        }
        assert_eq!(p.mode, Mode::Slide);
        assert!((p.gain - 10f32.powf(0.1)).abs() < 1e-6, "gain is given in dB");
        assert!(matches!(p.set("kapa", "1"), Err(ParamError::UnknownId(_))));
        assert!(p.set("hard", "nan").is_err());
        assert!(p.set("mode", "banjo").is_err());
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
        assert_eq!(defaults.first_difference(&defaults), None);
        let mut q = defaults;
        q.kappa *= 1.000_01;
        assert_eq!(defaults.first_difference(&q), None, "f32 normalisation noise is no change");
        q.alpha = 2.0;
        assert_eq!(defaults.first_difference(&q), Some("alpha"));
    }
}
