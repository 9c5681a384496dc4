//! A slide-guitar voice: one string, its slide and hand, and the two fingers.
//!
//! The string is the slide-guitar preset (open A2, [`crate::preset::slide_guitar`]); the pitch
//! comes from where the slide stops it. Per control block the voice sets the scene's controls:
//! - slide position `x_o = L(1 − 2^(−p/12))` for `p` semitones above the open string: the played
//!   key's distance from the open string when following keys, else the `slide_position` setting;
//!   plus pitch bend × bend range; glided towards its target with time constant `glide_time`;
//!   kept between 5 mm and 0.8 L;
//! - hand height from the setting or a controller (0 lifts the slide by 2 mm, full presses it
//!   2 mm in: [`HAND_RANGE`]);
//! - the left finger trails the slide by 2 cm with 0.3 N while the voice sounds, damping the
//!   dead part of the string;
//! - note-on plucks with the right finger at the plucking position: the force ramps up over
//!   [`PLUCK_TIME`] to `0.3 + 2.7·velocity` N and is then released; note-off lays the finger on
//!   with 0.3 N, muting the string.

use crate::contact::{Method, PowerLaw};
use crate::control::Live;
use crate::exciter::SlideParams;
use crate::instrument::settings::{HAND_RANGE, HandSource, Settings};
use crate::instrument::solvers::Solvers;
use crate::instrument::voice::{RELEASE_ENERGY, Strike};
use crate::preset::slide_guitar;
use crate::scene::{OutputKind, Pickup, SlideControls, SlideCore, SlideStringParams};
use crate::string::ModalString;

/// MIDI key of the open string (A2).
pub const OPEN_KEY: u8 = 45;

/// How long a pluck pushes before the finger lets go (s).
pub const PLUCK_TIME: f64 = 0.008;

/// Force of a finger resting on the string: trailing the slide, or muting after note-off (N).
pub const REST_FORCE: f64 = 0.3;

/// How far the left finger trails the slide (m).
pub const TRAIL: f64 = 0.02;

/// What the voice reads from its MIDI channel.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ChannelState {
    /// Pitch bend, −1..=1.
    pub bend: f64,
    /// Channel pressure, 0..=1.
    pub pressure: f64,
    /// Mod wheel, 0..=1.
    pub mod_wheel: f64,
}

/// One slide voice.
#[derive(Debug, Clone)]
pub struct SlideVoice {
    core: SlideCore,
    solvers: Solvers,
    live: Live<SlideControls>,
    length: f64,
    /// The note it plays.
    pub strike: Strike,
    /// Whether it produces sound.
    pub sounding: bool,
    /// Whether its key is held down.
    pub key_down: bool,
    /// Sample index of its latest note-on.
    pub started: u64,
    /// Poly pressure of its key, 0..=1.
    pub poly_pressure: f64,
    /// Slide position (semitones above the open string), after the glide.
    position: f64,
    /// Time into the pluck (s), while plucking.
    pluck: Option<f64>,
    /// Energy a pluck puts into the string (J): the release reference.
    reference_energy: f64,
    /// Recent peak of the string's kinetic energy (J), decaying with a 50 ms time constant.
    motion: f64,
}

impl SlideVoice {
    /// A silent voice at `sample_rate` (Hz).
    pub fn new(sample_rate: f64, settings: &Settings) -> Self {
        let g = slide_guitar();
        let string = ModalString::band_limited(g.string, sample_rate, settings.max_frequency.min(0.5 * sample_rate))
            .expect("the slide-guitar preset is a valid string");
        let length = g.string.length;
        let rest = SlideControls {
            slide_position: 0.25 * length,
            hand_height: HAND_RANGE.0,
            left_position: 0.25 * length - TRAIL,
            left_force: 0.0,
            right_position: settings.pluck_position * length,
            right_force: 0.0,
        };
        let params = SlideStringParams {
            string: g.string,
            slide: SlideParams {
                mass: settings.slide_mass,
                stiffness: settings.hand_stiffness,
                damping: settings.hand_damping,
            },
            left: g.left,
            right: g.right,
            block: settings.block,
            pickup: Pickup { kind: OutputKind::Displacement, position: settings.pickup_position },
        };
        let law = PowerLaw::new(settings.slide_kappa, settings.slide_alpha).expect("clamped settings give a valid law");
        Self {
            core: SlideCore::new(string, &params, rest, rest),
            solvers: Solvers::new(law),
            live: Live(rest),
            length,
            strike: Strike { channel: 0, key: OPEN_KEY, velocity: 0.0 },
            sounding: false,
            key_down: false,
            started: 0,
            poly_pressure: 0.0,
            position: settings.slide_position,
            pluck: None,
            reference_energy: f64::MIN_POSITIVE,
            motion: 0.0,
        }
    }

    /// Pluck `strike` now. With `legato` (following keys, another key still held) the slide
    /// glides to the new key without a new pluck.
    pub fn play(&mut self, strike: Strike, settings: &Settings, legato: bool, now: u64) {
        self.strike = strike;
        self.key_down = true;
        self.poly_pressure = 0.0;
        if legato && self.sounding {
            return;
        }
        if !self.sounding {
            self.position = self.target(settings, &ChannelState::default());
        }
        let Ok(law) = PowerLaw::new(settings.slide_kappa, settings.slide_alpha) else { return };
        // The QSA fit spans twice the largest static push the hand and fingers can make
        // (the scene-file rule of `SlideStringDescription::default_v_ref`).
        let push = 2.0 * (settings.hand_stiffness * (-HAND_RANGE.1 + 1e-3) + 3.0 + REST_FORCE);
        let y_ref = (push / law.kappa()).powf(1.0 / law.alpha());
        if !self.solvers.restart(settings.method, law, y_ref, settings.segments, self.core.compressions()) {
            return;
        }
        // Static energy of the pluck: ½F² x(L − x)/(T L) for a point force F at x.
        let force = 0.3 + 2.7 * strike.velocity;
        let (x, t) = (settings.pluck_position * self.length, self.core.string().params().tension);
        self.reference_energy =
            (0.5 * force * force * x * (self.length - x) / (t * self.length)).max(f64::MIN_POSITIVE);
        self.motion = self.reference_energy;
        self.pluck = Some(0.0);
        self.sounding = true;
        self.started = now;
    }

    /// Release the key.
    pub fn key_up(&mut self) {
        self.key_down = false;
    }

    /// Stop at once.
    pub fn silence(&mut self) {
        self.sounding = false;
        self.key_down = false;
        self.pluck = None;
    }

    /// Energy of the string and slide (J).
    pub fn energy(&self) -> f64 {
        self.core.energy()
    }

    /// Slide position (semitones above the open string) the controls ask for.
    fn target(&self, settings: &Settings, channel: &ChannelState) -> f64 {
        let base = if settings.follow_key {
            f64::from(self.strike.key) - f64::from(OPEN_KEY)
        } else {
            settings.slide_position
        };
        base + channel.bend * settings.bend_range
    }

    /// Work at a control-block boundary: move the controls on for the coming `len` samples and
    /// release the voice once silent.
    pub fn begin_block(&mut self, settings: &Settings, channel: &ChannelState, len: usize) {
        if !self.sounding {
            return;
        }
        let fs = self.core.string().sample_rate();
        let span = len as f64 / fs;
        let target = self.target(settings, channel);
        self.position += (target - self.position) * (1.0 - (-span / settings.glide_time).exp());
        // Arrive: an exponential glide never quite does, and a moving slide costs a recomputation
        // of the contact vectors every block.
        if (target - self.position).abs() < 1e-4 {
            self.position = target;
        }
        let x_o = (self.length * (1.0 - 2f64.powf(-self.position / 12.0))).clamp(0.005, 0.8 * self.length);
        let pressed = |v: f64| HAND_RANGE.0 + (HAND_RANGE.1 - HAND_RANGE.0) * v.clamp(0.0, 1.0);
        let hand_height = match settings.hand_source {
            HandSource::Parameter => settings.hand_height,
            HandSource::ModWheel => pressed(channel.mod_wheel),
            HandSource::ChannelPressure => pressed(channel.pressure),
            HandSource::PolyPressure => pressed(self.poly_pressure),
        };
        let right_force = match self.pluck {
            Some(t) if t < PLUCK_TIME => {
                self.pluck = Some(t + span);
                (0.3 + 2.7 * self.strike.velocity) * ((t + span) / PLUCK_TIME).min(1.0)
            }
            Some(_) => {
                self.pluck = None;
                0.0
            }
            None if self.key_down => 0.0,
            None => REST_FORCE,
        };
        self.live.0 = SlideControls {
            slide_position: x_o,
            hand_height,
            left_position: (x_o - TRAIL).max(0.002),
            left_force: REST_FORCE,
            right_position: settings.pluck_position * self.length,
            right_force,
        };
        let slide = SlideParams {
            mass: settings.slide_mass,
            stiffness: settings.hand_stiffness,
            damping: settings.hand_damping,
        };
        self.core.set_params(slide, [settings.finger_damping; 2], settings.block);
        // A pressed slide holds static energy in the string and the hand for ever, so silence is
        // judged on the string's motion.
        self.motion = self.core.string().kinetic_energy().max(self.motion * (-span / 0.05).exp());
        if !self.key_down && self.pluck.is_none() && self.motion < RELEASE_ENERGY * self.reference_energy {
            self.sounding = false;
        }
    }

    /// The string, for monitoring.
    pub fn string(&self) -> &ModalString {
        self.core.string()
    }

    /// `(compression (m), latest contact force (N), slide position (fraction of the length))`.
    pub fn contact(&self) -> (f64, f64, f64) {
        let (y, f, x) = self.core.contact();
        (y, f, x / self.length)
    }

    /// Whether the slide touches the string (now or one step back).
    pub fn in_contact(&self) -> bool {
        self.core.in_contact()
    }

    /// Move the pickup (fraction of the length).
    pub fn set_pickup(&mut self, position: f64) {
        self.core.set_pickup(Pickup { kind: OutputKind::Displacement, position });
    }

    /// Render `out.len()` samples of string displacement at the pickup (m).
    pub fn render(&mut self, out: &mut [f64]) {
        let s = &mut self.solvers;
        match s.method {
            Method::Qsa => self.core.process_output(&mut s.qsa, &mut self.live, out),
            Method::Imp => self.core.process_output(&mut s.imp, &mut self.live, out),
            Method::Exp => self.core.process_output(&mut s.exp, &mut self.live, out),
        }
    }
}
