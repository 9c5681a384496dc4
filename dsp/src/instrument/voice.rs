//! A piano voice: one string with its hammer, damper and solvers, reused note after note.

use crate::contact::{Method, PowerLaw};
use crate::exciter::HammerParams;
use crate::instrument::settings::{Settings, hammer_speed};
use crate::instrument::solvers::Solvers;
use crate::preset::piano_note;
use crate::scene::{HammerCore, HammerStringParams, OutputKind, Pickup};
use crate::string::{Damping, ModalString, StringParams};

/// Energy below which a voice that is not touching its hammer is released, relative to the
/// energy of its latest strike (−140 dB in energy, −70 dB in amplitude).
pub const RELEASE_ENERGY: f64 = 1e-14;

/// Decay rate that silences a stolen voice before its new note (1/s): −87 dB in 5 ms.
pub const STEAL_RATE: f64 = 2000.0;

/// How long a stolen voice fades before its new note starts (s).
pub const STEAL_TIME: f64 = 0.005;

/// A note to play: MIDI channel (0..16), key (0..128), velocity (0, 1].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Strike {
    /// MIDI channel, 0..=15.
    pub channel: u8,
    /// MIDI key, 0..=127.
    pub key: u8,
    /// Note velocity in (0, 1].
    pub velocity: f64,
}

/// One piano voice.
#[derive(Debug, Clone)]
pub struct PianoVoice {
    core: HammerCore,
    solvers: Solvers,
    /// The note it plays (valid while sounding).
    pub strike: Strike,
    /// Whether it produces sound.
    pub sounding: bool,
    /// Whether its key is held down.
    pub key_down: bool,
    /// Sample index of its latest note-on (for stealing the oldest).
    pub started: u64,
    /// Extra decay rate from the damper or a steal fade (1/s).
    damper: f64,
    /// Energy of the latest strike (J), the reference for releasing the voice.
    reference_energy: f64,
    /// Striking position of the latest strike (fraction of the length).
    position: f64,
    /// Samples of steal fade left before `pending` starts.
    fade_left: usize,
    /// A note waiting for the fade to finish.
    pending: Option<Strike>,
    /// Whether the pending note's key was released while it waited.
    pending_released: bool,
}

impl PianoVoice {
    /// A silent voice with room for `modes` modes, at `sample_rate` (Hz).
    pub fn new(modes: usize, sample_rate: f64) -> Self {
        let law = PowerLaw::new(1e9, 2.5).expect("a valid law");
        let mut string = ModalString::with_capacity(modes);
        let note = piano_note(60);
        string.retune(note.string, sample_rate, 20_000.0).expect("the C4 rule is a valid string");
        let params = HammerStringParams {
            string: note.string,
            hammer: HammerParams { mass: note.hammer_mass, velocity: 0.0, position: note.strike_position, gap: 1e-3 },
            pickup: Pickup { kind: OutputKind::BridgeForce, position: 0.5 },
        };
        Self {
            core: HammerCore::new(string, &params),
            solvers: Solvers::new(law),
            strike: Strike { channel: 0, key: 60, velocity: 0.0 },
            sounding: false,
            key_down: false,
            started: 0,
            damper: 0.0,
            reference_energy: 0.0,
            position: note.strike_position,
            fade_left: 0,
            pending: None,
            pending_released: false,
        }
    }

    /// The string a key gets under `settings`: the per-note rule with the relative settings.
    pub fn string_for(key: u8, settings: &Settings) -> StringParams {
        let mut string = piano_note(key).string;
        string.bending_stiffness *= settings.brightness;
        string.damping = match string.damping {
            Damping::PerMode { b1, b3 } => Damping::PerMode { b1: b1 * settings.damping, b3: b3 * settings.damping },
            Damping::Viscous { eta0, eta2 } => {
                Damping::Viscous { eta0: eta0 * settings.damping, eta2: eta2 * settings.damping }
            }
        };
        string
    }

    /// Play `strike` now: on the same string if this voice already sounds that key (a re-strike),
    /// else on a freshly tuned string at rest. Never allocates.
    pub fn play(&mut self, strike: Strike, settings: &Settings, now: u64) {
        let note = piano_note(strike.key);
        let position = (note.strike_position * settings.strike_position).clamp(0.02, 0.5);
        let restrike = self.sounding && self.strike.key == strike.key && self.pending.is_none();
        if !restrike {
            let fs = self.core.string().sample_rate();
            let string = Self::string_for(strike.key, settings);
            let max_frequency = settings.max_frequency.min(0.5 * fs);
            let pickup = Pickup { kind: OutputKind::BridgeForce, position: 0.5 };
            // The per-note rule and the clamped settings always give a valid string.
            if self.core.retune(string, max_frequency, position, pickup).is_err() {
                return;
            }
        }
        let fs = self.core.string().sample_rate();
        let velocity = hammer_speed(strike.velocity);
        let mass = note.hammer_mass * settings.hammer_mass;
        // The felt starts two samples of travel away, so the hammer lands almost at once.
        let hammer = HammerParams { mass, velocity, position, gap: 2.0 * velocity / fs };
        self.core.strike(&hammer);
        self.position = position;
        let Ok(law) = PowerLaw::new(note.kappa * settings.hardness, note.alpha) else { return };
        self.reference_energy = hammer.kinetic_energy().max(f64::MIN_POSITIVE);
        let y_ref = law.compression_at_energy(self.reference_energy);
        if !self.solvers.restart(settings.method, law, y_ref, settings.segments, self.core.compressions()) {
            return;
        }
        self.strike = strike;
        self.sounding = true;
        self.key_down = true;
        self.started = now;
        self.damper = 0.0;
    }

    /// Fade out over [`STEAL_TIME`], then play `strike` (a stolen voice).
    pub fn steal(&mut self, strike: Strike, sample_rate: f64, now: u64) {
        self.fade_left = (STEAL_TIME * sample_rate).ceil() as usize;
        self.pending = Some(strike);
        self.pending_released = false;
        self.key_down = false;
        self.started = now;
    }

    /// The key this voice will sound once any steal fade is over.
    pub fn upcoming_key(&self) -> Option<u8> {
        match self.pending {
            Some(p) => Some(p.key),
            None => self.sounding.then_some(self.strike.key),
        }
    }

    /// Release `key` on `channel` if this voice plays it (or will, after a steal fade).
    pub fn key_up(&mut self, channel: u8, key: u8) {
        match self.pending {
            Some(p) if p.channel == channel && p.key == key => self.pending_released = true,
            _ if self.sounding && self.strike.channel == channel && self.strike.key == key => self.key_down = false,
            _ => {}
        }
    }

    /// Release whatever key this voice plays.
    pub fn release(&mut self) {
        self.key_down = false;
        self.pending_released = true;
    }

    /// Stop at once: the string at rest, no pending note.
    pub fn silence(&mut self) {
        self.core.string_mut().reset();
        self.sounding = false;
        self.key_down = false;
        self.pending = None;
        self.fade_left = 0;
        self.damper = 0.0;
    }

    /// Whether the hammer touches the string (or is about to) in a sounding voice.
    pub fn in_contact(&self) -> bool {
        self.sounding && self.core.in_contact()
    }

    /// Whether this voice is being faded out to make room for another note.
    pub fn fading(&self) -> bool {
        self.pending.is_some()
    }

    /// Energy of the string and hammer (J).
    pub fn energy(&self) -> f64 {
        self.core.energy()
    }

    /// Work at a control-block boundary: start a pending note, move the damper towards its
    /// target and apply it for the coming `len` samples, release the voice once silent.
    pub fn begin_block(&mut self, settings: &Settings, sustained: bool, len: usize, now: u64) {
        if !self.sounding && self.pending.is_none() {
            return;
        }
        let fs = self.core.string().sample_rate();
        if let Some(strike) = self.pending
            && self.fade_left == 0
        {
            self.pending = None;
            self.sounding = false;
            self.play(strike, settings, now);
            self.key_down = !self.pending_released;
        }
        let span = len as f64 / fs;
        if self.pending.is_some() {
            self.damper = STEAL_RATE;
            self.fade_left = self.fade_left.saturating_sub(len);
        } else {
            let target = if self.key_down || sustained { 0.0 } else { settings.damper_rate };
            self.damper += (target - self.damper) * (1.0 - (-span / settings.damper_time).exp());
        }
        if self.damper > 0.0 {
            self.core.string_mut().scale_state((-self.damper * span).exp());
        }
        if self.pending.is_none() && !self.core.in_contact() && self.energy() < RELEASE_ENERGY * self.reference_energy {
            self.sounding = false;
        }
    }

    /// The string, for monitoring.
    pub fn string(&self) -> &ModalString {
        self.core.string()
    }

    /// `(compression (m), latest contact force (N), strike position (fraction of the length))`.
    pub fn contact(&self) -> (f64, f64, f64) {
        let (y, f) = self.core.contact();
        (y, f, self.position)
    }

    /// Render `out.len()` samples of bridge force (N).
    pub fn render(&mut self, out: &mut [f64]) {
        let s = &mut self.solvers;
        match s.method {
            Method::Qsa => self.core.process_output(&mut s.qsa, out),
            Method::Imp => self.core.process_output(&mut s.imp, out),
            Method::Exp => self.core.process_output(&mut s.exp, out),
        }
    }
}
