//! Sympathetic partners: the other keys' strings that ring with a struck key through the bridge
//! (docs/physics.md §14).
//!
//! With the sustain pedal down every damper is off its strings, and a struck key's partials set
//! ringing the strings of the keys whose partials they meet: striking C3 sounds C4, G4, C5 and E5
//! (its 2nd to 5th partials meet their 1st), and C2 and F1 below (its 1st meets their 2nd and
//! 3rd). With the pedal up, those of them without a damper (from E6 up) still ring. Each key
//! carries those strings on its own soundboard, coupled exactly as its unison is
//! (`crate::scene::UnisonCore`, "Sympathetic partners"): a partner is a key's unison moving in
//! phase, the motion a bridge drives, as one string of the unison's mass, tension and bending
//! stiffness together (so with the key's own partials), with its lowest [`PARTNER_MODES`] modes
//! up to the highest one a partial of the struck key meets.

use crate::instrument::{PianoVoice, Settings};
use crate::preset::piano_note;
use crate::scene::{MAX_PARTNERS, PARTNER_MODES};
use crate::string::ModalString;
use std::cell::Cell;

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

/// What [`PartnerTable::pick`] finds for a key: `(index into the table, modes)` of each partner,
/// and how many there are.
type Picks = ([(usize, usize); MAX_PARTNERS], usize);

/// Every key's partner string, prepared once and retuned when it is used after the settings that
/// shape strings changed.
#[derive(Debug, Clone)]
pub struct PartnerTable {
    strings: Vec<ModalString>,
    /// Each key's partners as [`PartnerTable::pick`] found them for the strings as tuned, once
    /// asked: a key struck again, on any voice, does not search again.
    picks: Vec<Cell<Option<Picks>>>,
    /// `(brightness, damping, stretch)` the strings are tuned for.
    tuned: (f64, f64, f64),
    /// The settings the table is used under next: [`ready`](Self::ready) tunes for them.
    wanted: Settings,
    sample_rate: f64,
}

impl PartnerTable {
    /// Every key's partner string at `sample_rate` (Hz) for `settings`. Allocates.
    pub fn new(sample_rate: f64, settings: &Settings) -> Self {
        let mut table = Self {
            strings: PARTNER_KEYS.map(|_| ModalString::with_capacity(PARTNER_MODES + 1)).collect(),
            picks: PARTNER_KEYS.map(|_| Cell::new(None)).collect(),
            tuned: (f64::NAN, f64::NAN, f64::NAN),
            wanted: *settings,
            sample_rate,
        };
        table.retune(settings);
        table
    }

    /// Use the table under `settings` from now on. The strings are retuned when it is next used
    /// ([`ready`](Self::ready)), not now: a setting that shapes strings, automated while keys
    /// ring, costs nothing until a key is struck or a partner joins.
    pub fn request(&mut self, settings: &Settings) {
        self.wanted = *settings;
    }

    /// The table for the settings last requested, retuned first if they shape the strings
    /// otherwise than before. Never allocates.
    pub fn ready(&mut self) -> &Self {
        let wanted = self.wanted;
        self.retune(&wanted);
        self
    }

    /// Retune for `settings` if they shape the strings otherwise than before. Never allocates.
    fn retune(&mut self, settings: &Settings) {
        let tuned = (settings.brightness, settings.damping, settings.stretch);
        if tuned == self.tuned {
            return;
        }
        self.tuned = tuned;
        self.picks.iter().for_each(|p| p.set(None));
        for (string, key) in self.strings.iter_mut().zip(PARTNER_KEYS) {
            let mut p = PianoVoice::string_for(key, settings);
            let s = piano_note(key).strings.max(1) as f64;
            p.linear_density *= s;
            p.tension *= s;
            p.bending_stiffness *= s;
            // Up to the PARTNER_MODES-th partial, stretched by inharmonicity, with a third of the
            // fundamental to spare.
            let f0 = p.fundamental();
            let band = p.partial(PARTNER_MODES) + 0.3 * f0;
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
        let Some(index) = PARTNER_KEYS.clone().position(|k| k == key) else { return 0 };
        let (picks, count) = match self.picks[index].get() {
            Some(found) => found,
            None => {
                let mut picks = [(0, 0); MAX_PARTNERS];
                let count = self.search(&self.strings[index], &mut picks);
                self.picks[index].set(Some((picks, count)));
                (picks, count)
            }
        };
        out[..count].copy_from_slice(&picks[..count]);
        count
    }

    /// How many keys' partners have been searched since the table was last retuned, of how many
    /// keys it holds.
    #[cfg(test)]
    pub fn searched(&self) -> (usize, usize) {
        (self.picks.iter().filter(|p| p.get().is_some()).count(), self.picks.len())
    }

    /// [`pick`](Self::pick)'s search among the table's strings for those meeting `own`'s partials.
    fn search(&self, own: &ModalString, out: &mut [(usize, usize); MAX_PARTNERS]) -> usize {
        let tolerance = 2f64.powf(PARTNER_TOLERANCE_CENTS / 1200.0) - 1.0;
        let own_w = &own.angular_frequencies()[..own.modes().min(STRIKING_PARTIALS)];
        // (table index, modes to keep, strength rank: the product of the partial numbers)
        let mut found = [(0usize, 0usize, usize::MAX); MAX_PARTNERS];
        let mut count = 0;
        for (index, string) in self.strings.iter().enumerate() {
            if std::ptr::eq(string, own) {
                continue;
            }
            let w = &string.angular_frequencies()[..string.modes().min(PARTNER_MODES)];
            let Some((modes, rank)) = meeting(own_w, w, tolerance) else { continue };
            let candidate = (index, modes, rank);
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

/// Where a string of mode frequencies `w` (rad/s, rising) meets the partials `own` (rad/s,
/// rising) of a struck key: each of its modes meets the first partial within `tolerance`
/// (relative) of it. Returns `(modes, rank)`: the modes up to the highest that meets one, and the
/// lowest product of the two partial numbers that meet; `None` if none meets.
fn meeting(own: &[f64], w: &[f64], tolerance: f64) -> Option<(usize, usize)> {
    let (&lowest, &highest) = (own.first()?, own.last()?);
    let (&first, &last) = (w.first()?, w.last()?);
    // Further than this from a partial, a frequency cannot meet it: a margin over the
    // tolerance, so that the exact test runs on every pair it might accept and on few others.
    let (below, above) = (1.0 - 2.0 * tolerance, 1.0 + 2.0 * tolerance);
    if first > highest * above || last < lowest * below {
        return None;
    }
    // Both rise with their numbers, so the scan of the partials stops past `w_i`.
    let meets = |wi: f64| {
        own.iter().take_while(|&&o| o * below <= wi).position(|&o| o * above >= wi && (wi / o - 1.0).abs() < tolerance)
    };
    let mut met = (0..w.len()).filter_map(|i| meets(w[i]).map(|p| (i, p)));
    let (i, p) = met.next()?;
    let (mut highest_met, mut rank) = (i, (i + 1) * (p + 1));
    for (i, p) in met {
        highest_met = i;
        rank = rank.min((i + 1) * (p + 1));
    }
    Some((highest_met + 1, rank))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A partner is its key's unison moving in phase: every mode it keeps rings at the frequency
    /// of that mode of the key's own string (as the voice tunes it, before the unison's spread),
    /// to rounding (1e-12), on every key, however bright the strings; a partner with the unison's
    /// mass and tension but one string's bending stiffness would have `1/S` of its inharmonicity,
    /// C7's fundamental 4.9 cents flat.
    #[test]
    fn a_partner_rings_at_its_keys_own_partials() {
        for brightness in [0.25, 1.0, 4.0] {
            let settings = Settings { brightness, ..Settings::default() };
            let table = PartnerTable::new(48_000.0, &settings);
            for (index, key) in PARTNER_KEYS.enumerate() {
                let partner = table.string(index);
                let mut own = ModalString::with_capacity(PARTNER_MODES + 1);
                own.retune(PianoVoice::string_for(key, &settings), 48_000.0, 21_600.0).unwrap();
                let kept = &partner.angular_frequencies()[..partner.modes()];
                for (i, (w, w_own)) in kept.iter().zip(own.angular_frequencies()).enumerate() {
                    assert!((w / w_own - 1.0).abs() < 1e-12, "key {key}, mode {}: {w} against {w_own}", i + 1);
                }
            }
        }
    }

    /// A partner keeps its lowest [`PARTNER_MODES`] modes wherever the band allows them, however
    /// inharmonic: at 48 kHz and brightness 1 and 4, every key whose partner's 16th partial lies
    /// below [`PARTNER_BAND`] keeps 16 modes (G3, B = 2.1e-4, has its 16th partial at 16.43 times
    /// its fundamental, beyond a band of 16.3 times it).
    #[test]
    fn a_partner_keeps_its_lowest_modes_however_inharmonic() {
        for brightness in [1.0, 4.0] {
            let table = PartnerTable::new(48_000.0, &Settings { brightness, ..Settings::default() });
            for (index, key) in PARTNER_KEYS.enumerate() {
                let partner = table.string(index);
                if partner.params().partial(PARTNER_MODES) < PARTNER_BAND {
                    assert_eq!(partner.modes(), PARTNER_MODES, "key {key} at brightness {brightness}");
                }
            }
        }
    }

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

    /// `meeting` tests only the pairs of frequencies that could meet: for every pair of keys, at
    /// the default settings and at the most inharmonic and most damped ones, it finds what testing
    /// every mode of the one against every striking partial of the other finds.
    #[test]
    fn meeting_finds_what_every_pair_of_partials_gives() {
        let tolerance = 2f64.powf(PARTNER_TOLERANCE_CENTS / 1200.0) - 1.0;
        let every_pair = |own: &[f64], w: &[f64]| {
            let met: Vec<(usize, usize)> = (0..w.len())
                .filter_map(|i| own.iter().position(|&o| (w[i] / o - 1.0).abs() < tolerance).map(|p| (i, p)))
                .collect();
            let rank = met.iter().map(|&(i, p)| (i + 1) * (p + 1)).min()?;
            Some((met.last()?.0 + 1, rank))
        };
        let stretched = Settings { brightness: 4.0, damping: 20.0, ..Settings::default() };
        let mut pairs_met = 0;
        for settings in [Settings::default(), stretched] {
            let table = PartnerTable::new(48_000.0, &settings);
            for own in &table.strings {
                let own_w = &own.angular_frequencies()[..own.modes().min(STRIKING_PARTIALS)];
                for string in &table.strings {
                    let w = &string.angular_frequencies()[..string.modes().min(PARTNER_MODES)];
                    let found = meeting(own_w, w, tolerance);
                    assert_eq!(found, every_pair(own_w, w));
                    pairs_met += usize::from(found.is_some());
                }
            }
        }
        println!("{pairs_met} pairs of keys meet");
        assert!(pairs_met > 1000);
    }

    /// Every key's partners, as `pick` gives them.
    fn every_pick(table: &PartnerTable) -> Vec<Vec<(usize, usize)>> {
        PARTNER_KEYS
            .map(|key| {
                let mut out = [(0, 0); MAX_PARTNERS];
                let n = table.pick(key, &mut out);
                out[..n].to_vec()
            })
            .collect()
    }

    /// The partners a table keeps from its searches are those of its strings as tuned now: after
    /// every key was picked at the default settings, stiffer, more damped strings requested give,
    /// once the table is next used, what a table made for those settings gives, for every key,
    /// though many keys' partners differ between the two; and so does a request that changes
    /// only the octave stretch. A request alone retunes nothing (a retune forgets the picks).
    #[test]
    fn a_retuned_table_picks_what_a_fresh_table_picks() {
        let stretched = Settings { brightness: 4.0, damping: 20.0, ..Settings::default() };
        let equal = Settings { stretch: 0.0, ..stretched };
        let mut table = PartnerTable::new(48_000.0, &Settings::default());
        let mut previous = every_pick(&table);
        assert_eq!(every_pick(&table), previous, "picked again from what was kept");
        for (settings, what) in [(stretched, "the settings"), (equal, "the stretch alone")] {
            table.request(&settings);
            assert_eq!(table.searched(), (88, 88), "requested {what}, not yet used");
            let picks = every_pick(table.ready());
            assert_eq!(picks, every_pick(&PartnerTable::new(48_000.0, &settings)), "retuned for {what}");
            let changed = previous.iter().zip(&picks).filter(|(a, b)| a != b).count();
            println!("{changed} of 88 keys' partners change with {what}");
            assert!(changed >= 10, "{what}");
            previous = picks;
        }
    }
}
