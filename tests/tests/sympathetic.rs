//! Sympathetic resonance (docs/physics.md §14): with the sustain pedal down, a struck key's
//! partials set ringing, through the bridge, the strings of the keys whose partials they meet,
//! and not their neighbours; with it up, those of them that have no damper.

use qsa_dsp::preset::key_frequency as hz;
use xtask::realism::{FS, held_with_pedal, level_near as level, played, undamped_ring};

/// C3 held with the pedal down against the same C3 with the pedal up: the difference is what the
/// other keys' free strings add (and what C3's own partials give up to them). Over 1–3 s it is at
/// least 15 dB stronger at the pitch of each of C4, G4, C5 and E5 (C3's 2nd to 5th partials) than
/// at the pitch of its upper neighbour, whose partials C3 does not meet (measured 33.7, 43.0, 43.5
/// and 17.2 dB); and each of those strings is heard: its part is at most 30 dB below everything
/// the piano sounds at that pitch (measured −0.7, 5.7, 2.2 and −8.8 dB: the partner and the
/// partial it shares beat).
#[test]
fn c3_sets_the_strings_of_its_partials_ringing() {
    let (down, up) = (held_with_pedal(48, Some(0.0), 3.0), held_with_pedal(48, None, 3.0));
    let added: Vec<f64> = down.iter().zip(&up).map(|(d, u)| d - u).collect();
    let from = (1.0 * FS) as usize;
    for key in [60u8, 67, 72, 76] {
        let (on, beside, all) =
            (level(&added, from, hz(key)), level(&added, from, hz(key + 1)), level(&down, from, hz(key)));
        let (selective, heard) = (20.0 * (on / beside).log10(), 20.0 * (on / all).log10());
        println!("key {key}: {selective:.1} dB above key {}'s pitch; {heard:.1} dB of the whole at its pitch", key + 1);
        assert!(selective >= 15.0, "key {key}: {selective:.1} dB");
        assert!(heard >= -30.0, "key {key}: {heard:.1} dB");
    }
}

/// The pedal pressed 0.25 s after C3 is struck (the usual legato pedalling) still sets the
/// strings of its partials ringing: against the pedal up, over 1–3 s, the difference is at least
/// 15 dB stronger at the pitch of each of C4, G4 and C5 than at its upper neighbour's (measured
/// 34.7, 43.1 and 42.4 dB), and within 6 dB of what the pedal down from the strike gives them
/// (measured +0.2, −1.1 and +0.9 dB): the partials have lost little by then, and the partners'
/// dampers lift within the damper's time constant (10 ms).
#[test]
fn the_pedal_pressed_after_the_strike_sets_the_partners_ringing() {
    let up = held_with_pedal(48, None, 3.0);
    let (late, early) = (held_with_pedal(48, Some(0.25), 3.0), held_with_pedal(48, Some(0.0), 3.0));
    let added = |down: &[f64]| -> Vec<f64> { down.iter().zip(&up).map(|(d, u)| d - u).collect() };
    let (late, early) = (added(&late), added(&early));
    let from = (1.0 * FS) as usize;
    for key in [60u8, 67, 72] {
        let (on, beside) = (level(&late, from, hz(key)), level(&late, from, hz(key + 1)));
        let (selective, against) = (20.0 * (on / beside).log10(), 20.0 * (on / level(&early, from, hz(key))).log10());
        println!(
            "key {key}: {selective:.1} dB above key {}'s pitch; {against:+.1} dB against the pedal from the strike",
            key + 1
        );
        assert!(selective >= 15.0, "key {key}: {selective:.1} dB");
        assert!(against.abs() <= 6.0, "key {key}: {against:.1} dB");
    }
}

/// The strings from E6 up have no dampers, so they ring with a key's partials even with the pedal
/// up: C5 struck and let go after 0.2 s, its own strings silenced by their damper, still sounds
/// 0.5–1.5 s later at the pitch of G6 and C7 (its 3rd and 4th partials meet their 1st): there,
/// at least 15 dB above the pitch of their upper neighbours (measured 43.3 and 22.1 dB), where
/// with dampers on every key nothing would sound.
#[test]
fn the_strings_without_dampers_ring_with_the_pedal_up() {
    for (key, selective) in undamped_ring() {
        println!("key {key}: {selective:.1} dB above key {}'s pitch", key + 1);
        assert!(selective >= 15.0, "key {key}: {selective:.1} dB");
    }
}

/// Lifting the pedal lets the dampers down on the partners that have one and not on the others:
/// C5 struck with the pedal down and let go after 0.1 s, the pedal lifted after 1 s. Between
/// 0.3–1 s and 1.3–2.3 s the level at the pitch of C6 (C5's 2nd partial, a string with a damper)
/// falls at least 30 dB more than at the pitch of C7 (its 4th, a string without one): at both,
/// C5's own partial falls silent, and the partner without a damper rings on (measured: C6 falls
/// 106.4 dB, C7 47.2 dB).
#[test]
fn lifting_the_pedal_damps_only_the_partners_with_dampers() {
    let out = played(72, true, 0.1, 1.0, 2.3);
    let (before, after) = (&out[..(1.0 * FS) as usize], &out[(1.3 * FS) as usize..]);
    let drop = |key: u8| 20.0 * (level(before, (0.3 * FS) as usize, hz(key)) / level(after, 0, hz(key))).log10();
    let (c6, c7) = (drop(84), drop(96));
    println!("across the lift: C6 falls {c6:.1} dB, C7 {c7:.1} dB");
    assert!(c6 - c7 >= 30.0, "C6 {c6:.1} dB, C7 {c7:.1} dB");
}
