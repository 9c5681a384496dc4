//! Sympathetic partners: the other keys' strings that ring with a struck key through the bridge
//! (docs/physics.md §14).
//!
//! With the sustain pedal down every damper is off its strings, and a struck key's partials set
//! ringing the strings of the keys whose partials they meet: striking C3 sounds C4, G4, C5 and E5
//! (its 2nd to 5th partials meet their 1st), and C2 and F1 below (its 1st meets their 2nd and
//! 3rd). With the pedal up, those of them without a damper (from E6 up) still ring. Each key
//! carries those strings on its own soundboard, coupled exactly as its unison is
//! (`crate::scene::UnisonCore`, "Sympathetic partners"): a partner is a key's unison moving in
//! phase, the motion a bridge drives, as one string of the unison's mass and tension, with its
//! lowest [`PARTNER_MODES`] modes up to the highest one a partial of the struck key meets.

use crate::instrument::{PianoVoice, Settings};
use crate::preset::piano_note;
use crate::scene::{MAX_PARTNERS, PARTNER_MODES};
use crate::string::ModalString;

/// The keyboard whose strings can be partners (MIDI): A0 to C8.
pub const PARTNER_KEYS: std::ops::Range<u8> = 21..109;

/// How close a partner's partial must be to one of the struck key's to ring with it: 15 cents,
/// wider than the unisons' spread and the partials' inharmonic stretch where they meet.
pub const PARTNER_TOLERANCE_CENTS: f64 = 15.0;

/// Highest partial frequency a partner keeps (Hz).
pub const PARTNER_BAND: f64 = 5000.0;

/// How many of the struck key's partials look for partners: the strong ones.
pub const STRIKING_PARTIALS: usize = 8;

/// Most partner modes a key carries in all.
pub const MAX_PARTNER_MODES: usize = 64;

/// Every key's partner string, prepared once and retuned when the settings that shape strings
/// change.
#[derive(Debug, Clone)]
pub struct PartnerTable {
    strings: Vec<ModalString>,
    /// `(brightness, damping)` the strings are tuned for.
    tuned: (f64, f64),
    sample_rate: f64,
}

impl PartnerTable {
    /// Every key's partner string at `sample_rate` (Hz) for `settings`. Allocates.
    pub fn new(sample_rate: f64, settings: &Settings) -> Self {
        let mut table = Self {
            strings: PARTNER_KEYS.map(|_| ModalString::with_capacity(PARTNER_MODES + 1)).collect(),
            tuned: (f64::NAN, f64::NAN),
            sample_rate,
        };
        table.retune(settings);
        table
    }

    /// Retune for `settings` if they shape the strings otherwise than before. Never allocates.
    pub fn retune(&mut self, settings: &Settings) {
        let tuned = (settings.brightness, settings.damping);
        if tuned == self.tuned {
            return;
        }
        self.tuned = tuned;
        for (string, key) in self.strings.iter_mut().zip(PARTNER_KEYS) {
            let mut p = PianoVoice::string_for(key, settings);
            let s = piano_note(key).strings.max(1) as f64;
            p.linear_density *= s;
            p.tension *= s;
            // Up to the PARTNER_MODES-th partial (stretched a little by inharmonicity).
            let f0 = p.fundamental();
            let band = (PARTNER_MODES as f64 + 0.3) * f0;
            let band = band.min(PARTNER_BAND.max(1.2 * f0)).min(0.45 * self.sample_rate);
            // The rule's strings and the clamped settings always give a valid string.
            let _ = string.retune(p, self.sample_rate, band);
        }
    }

    /// The partners of `key` (MIDI): the keys one of whose modes is within
    /// [`PARTNER_TOLERANCE_CENTS`] of one of `key`'s lowest [`STRIKING_PARTIALS`] partials, as
    /// `(index into the table, modes)` in `out`; returns how many: at most [`MAX_PARTNERS`], the
    /// strongest first (the lowest product of the two partial numbers that meet, where both strings
    /// move most), and no more than [`MAX_PARTNER_MODES`] modes in all.
    pub fn pick(&self, key: u8, out: &mut [(usize, usize); MAX_PARTNERS]) -> usize {
        let Some(own) = PARTNER_KEYS.clone().position(|k| k == key).map(|i| &self.strings[i]) else { return 0 };
        let tolerance = 2f64.powf(PARTNER_TOLERANCE_CENTS / 1200.0) - 1.0;
        // (table index, modes to keep, strength rank: the product of the partial numbers)
        let mut found = [(0usize, 0usize, usize::MAX); MAX_PARTNERS];
        let mut count = 0;
        for (index, string) in self.strings.iter().enumerate() {
            if std::ptr::eq(string, own) {
                continue;
            }
            let modes = string.modes().min(PARTNER_MODES);
            let (w, own_w) = (string.angular_frequencies(), own.angular_frequencies());
            let meeting =
                |i: usize| (0..own.modes().min(STRIKING_PARTIALS)).find(|&p| (w[i] / own_w[p] - 1.0).abs() < tolerance);
            let Some(rank) = (0..modes).filter_map(|i| meeting(i).map(|p| (i + 1) * (p + 1))).min() else { continue };
            let highest = (0..modes).rev().find(|&i| meeting(i).is_some()).unwrap_or(0);
            let candidate = (index, highest + 1, rank);
            if count < MAX_PARTNERS {
                found[count] = candidate;
                count += 1;
            } else if let Some(worst) = (0..MAX_PARTNERS).max_by_key(|&j| found[j].2)
                && found[worst].2 > rank
            {
                found[worst] = candidate;
            }
        }
        found[..count].sort_by_key(|f| f.2);
        let (mut kept, mut modes) = (0, 0);
        for f in &found[..count] {
            if modes + f.1 > MAX_PARTNER_MODES {
                continue;
            }
            out[kept] = (f.0, f.1);
            kept += 1;
            modes += f.1;
        }
        kept
    }

    /// Partner string `index` of the table.
    pub fn string(&self, index: usize) -> &ModalString {
        &self.strings[index]
    }

    /// The key of table index `index`.
    pub fn key(index: usize) -> u8 {
        PARTNER_KEYS.start + index as u8
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// C3's partners are the keys whose partials its own meet: C4, G4, C5 and E5 above (its 2nd to
    /// 5th partials), C2 and F1 below (its fundamental is their 2nd and 3rd), and no key a
    /// semitone from any of them; within [`MAX_PARTNER_MODES`] modes in all.
    #[test]
    fn c3_rings_with_the_keys_its_partials_meet() {
        let table = PartnerTable::new(48_000.0, &Settings::default());
        let mut out = [(0, 0); MAX_PARTNERS];
        let n = table.pick(48, &mut out);
        let keys: Vec<u8> = out[..n].iter().map(|&(i, _)| PartnerTable::key(i)).collect();
        let modes: usize = out[..n].iter().map(|&(_, m)| m).sum();
        println!("C3's partners: {keys:?}, {modes} modes");
        for key in [60, 67, 72, 76, 36, 29] {
            assert!(keys.contains(&key), "key {key} is a partner");
        }
        for key in [61, 59, 66, 68, 73, 71, 37, 35] {
            assert!(!keys.contains(&key), "key {key} is not");
        }
        assert!(modes <= MAX_PARTNER_MODES);
    }
}
