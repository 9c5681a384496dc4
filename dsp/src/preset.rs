//! Named parameter sets: the Chaigne–Askenfelt C4 piano string and hammer, and a rule that gives
//! a plausible string and hammer for every MIDI key.
//!
//! # Chaigne & Askenfelt (1994) C4 (docs/physics.md §8.2)
//!
//! L = 0.62 m, string mass 3.93 g, T = 670 N, ε = EI/(TL²) = 3.82e-5, b1 = 0.5 s⁻¹,
//! b3 = 6.25e-9 s; hammer 2.97 g, κ = 4.5e9 N/m^α, α = 2.5, struck at 0.12 L. Mapped to the
//! model of [`crate::string`] exactly as docs/physics.md §8.2 prescribes: `ρA = Ms/L`, `EI = ε T L²`,
//! `η0 = b1`, `η2 = b3·T/ρA`. Derived: ρA = 6.3387e-3 kg/m, EI = 9.838e-3 N·m², f0 = 262.19 Hz,
//! B = 3.770e-4, η2 = 6.606e-4 m²/s.
//!
//! # Per-note rule ([`piano_note`])
//!
//! For MIDI key `k` (0..=127), `f0 = 440·2^((k−69)/12)` Hz (equal temperament) and:
//! - length `L = 0.62·2^(−e(k−60)/12)` m with `e = 0.9` above C4 and `e = 0.45` below (bass
//!   strings are wound, so they grow more slowly), clamped to 1.9 m;
//! - inharmonicity `B` log-linear through C2 (key 36) 3.8e-5 and C4 (60) 3.3e-4, measured on a
//!   grand by Lehtonen et al. (JASA 122(3), 2007), and the Chaigne–Askenfelt C7 (96) 8.56e-3
//!   (extrapolated, clamped to [1e-5, 0.05]); `EI = B T L²/π²`;
//! - tension `T = 670 N` for every key, and `ρA = T/(2L f_flex)²` with `f_flex = f0/√(1 + B)`, so
//!   that the first partial `f_flex √(1 + B)` is exactly `f0`; the instrument then moves each key
//!   from equal temperament by the octave stretch a tuner gives it ([`stretch_cents`]);
//! - damping, per-mode law `σ_i = b1 + b3 ω0_i²`: the string's own losses, Chaigne and
//!   Askenfelt's Part I values, b1 = 0.5 s⁻¹ on every key and b3 log-linear through 6.25e-9,
//!   6.25e-9, 2.6e-10 s at C2, C4, C7. What a string loses into the soundboard is not in them:
//!   the instrument's strings end on a moving bridge that drains them (docs/physics.md §12), and
//!   with it the fundamentals of C2–C4 ring as long as a measured grand's (§12.7);
//! - the whole hammer's mass ([`hammer_mass`]) piecewise linear through a concert grand's strike
//!   weights, from 12.4 g at A0 to 5.8 g at C8, shared among the key's strings; felt stiffness κ (one string's
//!   share) log-linear through 4e8, 4.5e9, 1e12 N/m^α, clamped to [1e8, 1e13]; exponent α linear
//!   through 2.3, 2.5, 3.0, clamped to [2, 3.5]; striking position linear through 0.12, 0.12,
//!   0.0625 of L, clamped to [1/17, 0.2]: the top octave's hammers strike between 1/12 and 1/17
//!   of the length (Conklin, KTH lecture "Where should the hammer hit the string", C8 usually
//!   1/12–1/17; Fandrich, PTG list 1998, 1/12–1/16 at C88), which the line through C7 leaves
//!   from D♯7 up ([`SHORTEST_STRIKE`]).
//!
//! Each key has one to three strings ([`unison_strings`]), all the same string retensioned to a
//! small detuning ([`unison_detune`]); the hammer values above are one string's share.
//!
//! The C2 and C7 felt values are guesses in the source tables (docs/physics.md §8.2). How the
//! rule compares with measured grands is in docs/physics.md §8.4 (`tests/tests/piano_rule.rs`).

use crate::string::{Damping, StringParams};

/// A string and the hammer that strikes it.
///
/// The hammer is one string's share: a key with `strings` strings has a hammer `strings` times
/// as heavy, whose felt is `strings` times as stiff (it presses every string of the unison
/// alike; see [`crate::scene::UnisonCore`]), as Chaigne and Askenfelt's C4 hammer is one
/// string's share of a trichord's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PianoNote {
    /// The string.
    pub string: StringParams,
    /// Strings in the key's unison, 1 to 3.
    pub strings: usize,
    /// Each string's share of the unison's detuning (multiples of the spread between the lowest
    /// and highest string; entries past `strings` are zero).
    pub detune: [f64; 3],
    /// Hammer mass per string (kg).
    pub hammer_mass: f64,
    /// Felt stiffness κ per string (N/m^α).
    pub kappa: f64,
    /// Felt exponent α.
    pub alpha: f64,
    /// Striking position as a fraction of the length.
    pub strike_position: f64,
}

/// The Chaigne–Askenfelt C4 string and hammer, mapped as docs/physics.md §8.2 prescribes.
pub fn chaigne_askenfelt_c4() -> PianoNote {
    let (length, mass, tension, epsilon, b1, b3) = (0.62, 3.93e-3, 670.0, 3.82e-5, 0.5, 6.25e-9);
    let linear_density = mass / length;
    PianoNote {
        string: StringParams {
            length,
            tension,
            linear_density,
            bending_stiffness: epsilon * tension * length * length,
            damping: Damping::Viscous { eta0: b1, eta2: b3 * tension / linear_density },
        },
        strings: 1,
        detune: [0.0; 3],
        hammer_mass: 2.97e-3,
        kappa: 4.5e9,
        alpha: 2.5,
        strike_position: 0.12,
    }
}

/// Equal-tempered frequency of MIDI key `key` (Hz), A4 = 440 Hz.
pub fn key_frequency(key: u8) -> f64 {
    440.0 * 2f64.powf((f64::from(key) - 69.0) / 12.0)
}

/// The unison of key `k`: a single string from A0 to E1 (keys below 29), two from F1 to A♯2
/// (below 47), three above, as on a modern concert grand (the exact breaks vary between makers).
pub fn unison_strings(key: u8) -> usize {
    match key {
        0..29 => 1,
        29..47 => 2,
        _ => 3,
    }
}

/// How the strings of key `key`'s unison share a detuning spread of 1 (module docs): two strings
/// at ∓½, three at −½, +0.1, +0.4, scaled per key by a fixed factor in [0.7, 1.3) (a tuner does
/// not leave every unison alike).
pub fn unison_detune(key: u8) -> [f64; 3] {
    let scale = 0.7 + 0.6 * (f64::from(key) * 0.618_033_988_749_895).fract();
    match unison_strings(key) {
        1 => [0.0; 3],
        2 => [-0.5 * scale, 0.5 * scale, 0.0],
        _ => [-0.5 * scale, 0.1 * scale, 0.4 * scale],
    }
}

/// A concert grand's hammers (kg) at MIDI keys 21, 42, 64, 86 and 108: the strike weights of a
/// technician's guideline for a full tone (Stanwood, PTG list 1995: 12.4, 11.5, 10.2, 8.3 and
/// 5.8 g at keys 1, 22, 44, 66 and 88 of the keyboard, the boundary between its "full" and
/// "medium" zones). A strike weight is the mass the hammer presents at the striking point, head
/// and shank together (the head alone is about 1.9 g lighter; Conklin gives about 11 g for the
/// largest bass heads and 3.5 g for the smallest treble ones): the mass of the lumped hammer.
const HAMMER_MASSES: [(f64, f64); 5] =
    [(21.0, 12.4e-3), (42.0, 11.5e-3), (64.0, 10.2e-3), (86.0, 8.3e-3), (108.0, 5.8e-3)];

/// The strike weights scaled so that C4's hammer is Chaigne and Askenfelt's, 2.97 g for each of
/// its three strings: their C4 string and hammer reproduce measured strikes (docs/physics.md
/// §8.2), and the guideline's shape carries them across the keyboard.
const HAMMER_SCALE: f64 = 3.0 * 2.97e-3 / (11.5e-3 + (10.2e-3 - 11.5e-3) * (60.0 - 42.0) / (64.0 - 42.0));

/// The whole hammer's mass of MIDI key `key` (kg): `HAMMER_MASSES` joined by straight lines,
/// constant beyond A0 and C8, scaled by `HAMMER_SCALE`.
pub fn hammer_mass(key: u8) -> f64 {
    HAMMER_SCALE * strike_weight(key)
}

fn strike_weight(key: u8) -> f64 {
    let k = f64::from(key);
    let (first, last) = (HAMMER_MASSES[0], HAMMER_MASSES[HAMMER_MASSES.len() - 1]);
    if k <= first.0 {
        return first.1;
    }
    HAMMER_MASSES
        .windows(2)
        .find(|w| k <= w[1].0)
        .map_or(last.1, |w| w[0].1 + (w[1].1 - w[0].1) * (k - w[0].0) / (w[1].0 - w[0].0))
}

/// Anchor keys of the per-note rule: C2, C4, C7.
const ANCHOR_KEYS: [f64; 3] = [36.0, 60.0, 96.0];

/// Piecewise-linear interpolation through the anchors, extrapolated with the end slopes.
fn through(key: f64, values: [f64; 3]) -> f64 {
    let [k0, k1, k2] = ANCHOR_KEYS;
    if key <= k1 {
        values[0] + (values[1] - values[0]) * (key - k0) / (k1 - k0)
    } else {
        values[1] + (values[2] - values[1]) * (key - k1) / (k2 - k1)
    }
}

/// Log-linear interpolation through positive anchors.
fn log_through(key: f64, values: [f64; 3]) -> f64 {
    through(key, values.map(f64::ln)).exp()
}

/// The inharmonicity coefficient B of the rule's string for MIDI key `key` (module docs).
pub fn inharmonicity(key: u8) -> f64 {
    log_through(f64::from(key.min(127)), [3.8e-5, 3.3e-4, 8.56e-3]).clamp(1e-5, 0.05)
}

/// The keys tuned in equal temperament, A♯3 to A4 (A4 at 440 Hz): the temperament octave from
/// which [`stretch_cents`] tunes every other key by octaves.
pub const TEMPERAMENT_OCTAVE: std::ops::RangeInclusive<u8> = 58..=69;

/// How far key `key` (MIDI) sits from equal temperament (cents) when the keys outside the
/// temperament octave are tuned from it by octaves, each beatless on the lower key's second
/// partial, as a tuner tunes octaves by ear, on strings whose B is the rule's times `brightness`.
///
/// The second partial of a stiff string lies above twice its first,
/// `f_2/f_1 = 2√((1 + 4B)/(1 + B))`, so each octave comes out wider than 2:1 by
/// `1200 log₂ √((1 + 4B)/(1 + B)) ≈ 2600 B` cents of its lower key, and the octaves add up away
/// from the middle: the treble sharp and the bass flat of equal temperament, Railsback's stretch
/// of tuned pianos (JASA 9, 274, 1938), the more so where B is large. Keys beyond A0–C8, which no
/// tuner sets, keep the stretch of the nearest key of the keyboard.
pub fn stretch_cents(key: u8, brightness: f64) -> f64 {
    let octave = |lower: u8| {
        let b = brightness * inharmonicity(lower);
        600.0 * ((1.0 + 4.0 * b) / (1.0 + b)).log2()
    };
    let (mut key, mut cents) = (key.clamp(21, 108), 0.0);
    while key > *TEMPERAMENT_OCTAVE.end() {
        key -= 12;
        cents += octave(key);
    }
    while key < *TEMPERAMENT_OCTAVE.start() {
        cents -= octave(key);
        key += 12;
    }
    cents
}

/// Where the rule's hammer strikes MIDI key `key`'s strings (fraction of the length): the
/// [`PianoNote::strike_position`] of [`piano_note`], without the rest of the rule.
pub fn strike_position(key: u8) -> f64 {
    through(f64::from(key.min(127)), [0.12, 0.12, 0.0625]).clamp(SHORTEST_STRIKE, 0.2)
}

/// The shortest striking distance the rule gives (fraction of the length): 1/17, the short end
/// of what grands' top octaves are voiced to (module docs).
pub const SHORTEST_STRIKE: f64 = 1.0 / 17.0;

/// A plausible piano string and hammer for MIDI key `key` (0..=127): the rule in the module docs.
pub fn piano_note(key: u8) -> PianoNote {
    let k = f64::from(key.min(127));
    let f0 = key_frequency(key.min(127));
    let exponent = if k >= 60.0 { 0.9 } else { 0.45 };
    let length = (0.62 * 2f64.powf(-exponent * (k - 60.0) / 12.0)).min(1.9);
    let tension = 670.0;
    let b = inharmonicity(key);
    let flexible = f0 / (1.0 + b).sqrt();
    let linear_density = tension / (2.0 * length * flexible).powi(2);
    PianoNote {
        strings: unison_strings(key.min(127)),
        detune: unison_detune(key.min(127)),
        string: StringParams {
            length,
            tension,
            linear_density,
            bending_stiffness: b * tension * length * length / std::f64::consts::PI.powi(2),
            damping: Damping::PerMode { b1: 0.5, b3: log_through(k, [6.25e-9, 6.25e-9, 2.6e-10]) },
        },
        hammer_mass: hammer_mass(key.min(127)) / unison_strings(key.min(127)) as f64,
        kappa: log_through(k, [4e8, 4.5e9, 1e12]).clamp(1e8, 1e13),
        alpha: through(k, [2.3, 2.5, 3.0]).clamp(2.0, 3.5),
        strike_position: strike_position(key),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The top octave's hammers strike within what grands are voiced to, 1/12 to 1/17 of the
    /// length (Conklin; Fandrich 1/12–1/16 at C8): the line through C7's 1/16 would reach 1/23
    /// at C8; below C7 the rule is its line.
    #[test]
    fn the_top_octave_strikes_within_the_published_range() {
        for key in 96..=108u8 {
            let x = strike_position(key);
            assert!((1.0 / 17.0 - 1e-12..=1.0 / 12.0).contains(&x), "key {key}: 1/{:.1}", 1.0 / x);
        }
        assert_eq!(strike_position(96), 0.0625);
        assert_eq!(strike_position(60), 0.12);
    }

    #[test]
    fn c4_matches_the_derived_values_of_physics_8_2() {
        let c4 = chaigne_askenfelt_c4().string;
        assert!((c4.linear_density - 6.3387e-3).abs() < 1e-7);
        assert!((c4.bending_stiffness - 9.838e-3).abs() < 1e-6);
        assert!((c4.fundamental() - 262.19).abs() < 0.01);
        assert!((c4.inharmonicity() - 3.770e-4).abs() < 1e-7);
        let Damping::Viscous { eta0, eta2 } = c4.damping else { panic!("C4 uses the eta law") };
        assert_eq!(eta0, 0.5);
        assert!((eta2 - 6.606e-4).abs() < 1e-7);
    }

    #[test]
    fn every_key_gives_a_valid_string_at_its_pitch() {
        for key in 0..=127u8 {
            let note = piano_note(key);
            note.string.validate().unwrap_or_else(|e| panic!("key {key}: {e}"));
            let f1 = note.string.partial(1);
            assert!((f1 / key_frequency(key) - 1.0).abs() < 1e-12, "key {key}: first partial {f1}");
            assert!(note.hammer_mass > 0.0 && note.kappa > 0.0 && note.alpha >= 1.0);
            assert!(note.strike_position > 0.0 && note.strike_position < 0.5);
        }
    }
}

/// A slide-guitar string with its slide, hand and fingers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlideGuitar {
    /// The string.
    pub string: StringParams,
    /// Slide and hand.
    pub slide: crate::exciter::SlideParams,
    /// Left finger (trailing the slide).
    pub left: crate::exciter::FingerParams,
    /// Right finger (plucking).
    pub right: crate::exciter::FingerParams,
    /// Slide contact stiffness κ (N/m^α).
    pub kappa: f64,
    /// Slide contact exponent α (Hertzian cylinder on string: 1.5, seed §6).
    pub alpha: f64,
}

/// The slide-guitar set-up used for development (docs/physics.md §8.3: the DAFx-20 parameters were not
/// available, so these are documented placeholders): an A2 string, L = 0.65 m, T = 100 N,
/// f0 = 110 Hz (ρA = T/(2Lf0)²), B = 1e-5, η0 = 1 s⁻¹, η2 = 1e-4 m²/s; a 30 g slide held with
/// k_H = 1e4 N/m and r_H = 5 kg/s; contact κ = 1e9 N/m^1.5, α = 1.5; finger windows 15 mm (left)
/// and 10 mm (right) with r = 5 s/m.
pub fn slide_guitar() -> SlideGuitar {
    let (length, tension, f0, b) = (0.65_f64, 100.0_f64, 110.0_f64, 1e-5);
    SlideGuitar {
        string: StringParams {
            length,
            tension,
            linear_density: tension / (2.0 * length * f0).powi(2),
            bending_stiffness: b * tension * length * length / std::f64::consts::PI.powi(2),
            damping: Damping::Viscous { eta0: 1.0, eta2: 1e-4 },
        },
        slide: crate::exciter::SlideParams { mass: 0.03, stiffness: 1e4, damping: 5.0 },
        left: crate::exciter::FingerParams { width: 0.015, damping: 5.0 },
        right: crate::exciter::FingerParams { width: 0.01, damping: 5.0 },
        kappa: 1e9,
        alpha: 1.5,
    }
}
