//! A snapshot of the instrument for displays: the loudest voice's string shape, contact and
//! energy. Taking one costs `SHAPE_POINTS × M` multiply-adds and never allocates, so the audio
//! thread can take one every few blocks and hand it to a GUI through a lock-free queue.

use crate::instrument::{Instrument, Mode};

/// Points along the string in [`Monitor::shape`].
pub const SHAPE_POINTS: usize = 64;

/// What a display shows of the instrument.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Monitor {
    /// Voices sounding.
    pub sounding: usize,
    /// Voices the guard has silenced since the engine started ([`Instrument::guard_trips`]).
    pub guard_trips: u32,
    /// Voices shed to lighten the load since the engine started ([`Instrument::shed_count`]).
    pub shed: u64,
    /// Mode of the loudest voice.
    pub mode: Mode,
    /// Its MIDI key.
    pub key: u8,
    /// Its energy (J): the strings' and the exciter's (hammer, or slide and hand); a slide's
    /// includes its contact's stored energy, a hammer's leaves it and the bridge's cross terms
    /// out.
    pub energy: f64,
    /// The vibration it holds: its strings' energy (with the bridge's for a piano key), without
    /// the exciter (J).
    pub vibration: f64,
    /// Its contact compression (m); positive means touching.
    pub compression: f64,
    /// Its latest contact force (N), ≤ 0.
    pub force: f64,
    /// Where its hammer or slide touches, as a fraction of the length.
    pub contact_position: f64,
    /// Its string length (m).
    pub length: f64,
    /// Its string's displacement (m) at `SHAPE_POINTS` points from x = 0 to x = L.
    pub shape: [f32; SHAPE_POINTS],
}

impl Default for Monitor {
    fn default() -> Self {
        Self {
            sounding: 0,
            guard_trips: 0,
            shed: 0,
            mode: Mode::Piano,
            key: 60,
            energy: 0.0,
            vibration: 0.0,
            compression: 0.0,
            force: 0.0,
            contact_position: 0.0,
            length: 1.0,
            shape: [0.0; SHAPE_POINTS],
        }
    }
}

impl Instrument {
    /// A snapshot of the loudest voice (the one whose string moves most); when none sounds, the
    /// [`Monitor::default`] with the counts of guard trips and sheds.
    pub fn monitor(&self) -> Monitor {
        let piano = self.voices.iter().filter(|v| v.sounding).map(|v| {
            let energies = (v.energy(), v.vibration());
            (v.string().kinetic_energy(), v.string(), None, energies, v.contact(), v.strike.key, Mode::Piano)
        });
        let slide = self.slides.iter().filter(|v| v.sounding).map(|v| {
            let (weights, energies) = (v.coupling_weights(), (v.energy(), v.string().energy()));
            (v.string().kinetic_energy(), v.string(), weights, energies, v.contact(), v.strike.key, Mode::Slide)
        });
        let Some((_, string, weights, (energy, vibration), (compression, force, position), key, mode)) =
            piano.chain(slide).max_by(|a, b| a.0.total_cmp(&b.0))
        else {
            return Monitor { guard_trips: self.guard_trips(), shed: self.shed_count(), ..Monitor::default() };
        };
        let length = string.params().length;
        let mut shape = [0.0f32; SHAPE_POINTS];
        for (k, s) in shape.iter_mut().enumerate() {
            let x = length * k as f64 / (SHAPE_POINTS - 1) as f64;
            *s = string.displacement_at(x, weights) as f32;
        }
        Monitor {
            sounding: self.sounding(),
            guard_trips: self.guard_trips(),
            shed: self.shed_count(),
            mode,
            key,
            energy,
            vibration,
            compression,
            force,
            contact_position: position,
            length,
            shape,
        }
    }
}
