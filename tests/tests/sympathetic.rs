//! Sympathetic resonance (docs/physics.md §14): with the sustain pedal down, a struck key's
//! partials set ringing, through the bridge, the strings of the keys whose partials they meet,
//! and not their neighbours; with it up, those of them that have no damper or whose keys are held
//! down.

use qsa_dsp::instrument::Event;
use qsa_dsp::preset::key_frequency as hz;
use xtask::realism::{
    FS, added_to, dry_piano, held_ring, held_with_pedal, level_near as level, perform, played, undamped_ring,
};

/// How far `x`'s level at key `key`'s pitch falls across a change at 1 s (dB): from `from`–1 s
/// to 1.3 s–the end (the change's damper lands within the 0.3 s left out).
fn fall(x: &[f64], from: f64, key: u8) -> f64 {
    let (before, after) = (&x[..FS as usize], &x[(1.3 * FS) as usize..]);
    20.0 * (level(before, (from * FS) as usize, hz(key)) / level(after, 0, hz(key))).log10()
}

/// C3 held with the pedal down against the same C3 with the pedal up: the difference is what the
/// other keys' free strings add (and what C3's own partials give up to them). Over 1–3 s it is at
/// least 15 dB stronger at the pitch of each of C4, G4, C5 and E5 (C3's 2nd to 5th partials) than
/// at the pitch of its upper neighbour, whose partials C3 does not meet (measured 32.4, 43.7, 44.1
/// and 17.7 dB); and each of those strings is heard: its part is at most 30 dB below everything
/// the piano sounds at that pitch (measured −1.7, 10.3, 4.1 and −9.6 dB: the partner and the
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
/// 33.8, 43.9 and 42.9 dB), and within 6 dB of what the pedal down from the strike gives them
/// (measured +0.6, −0.8 and +1.7 dB): the partials have lost little by then, and the partners'
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
/// at least 15 dB above the pitch of their upper neighbours (measured 43.2 and 37.2 dB), where
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
/// 91.7 dB, C7 32.1 dB).
#[test]
fn lifting_the_pedal_damps_only_the_partners_with_dampers() {
    let out = played(72, true, 0.1, 1.0, 2.3);
    let (c6, c7) = (fall(&out, 0.3, 84), fall(&out, 0.3, 96));
    println!("across the lift: C6 falls {c6:.1} dB, C7 {c7:.1} dB");
    assert!(c6 - c7 >= 30.0, "C6 {c6:.1} dB, C7 {c7:.1} dB");
}

/// A key held down has its damper off, so its strings ring with the partials of a key struck
/// with the pedal up: C3 struck and let go after 0.2 s, with C4 or G4 held down (pressed as
/// softly as MIDI can, before C3 or 0.1 s after it), still sounds 0.5–1.5 s later at the held
/// key's pitch (C3's 2nd and 3rd partials), at least 15 dB above the pitch a semitone higher, as
/// for the pedal (measured 32.0 and 33.8–34.0 dB, pressed before or after). With C♯4
/// held, whose strings no partial of C3 meets, what C3 adds there is at least 60 dB below what it
/// adds at C4's pitch with C4 held (measured: nothing; C3's voice ends as it would alone).
#[test]
fn a_held_key_rings_with_the_partials_of_a_staccato_note() {
    for press in [0.0, 0.1] {
        let rings = held_ring(press);
        let c4 = rings[0].1;
        for (key, on, beside) in rings {
            if key == 61 {
                let below = 20.0 * (c4 / on).log10();
                println!("pressed {press} s after C3, key {key} held: {below:.1} dB below C4's ring");
                assert!(below >= 60.0, "key {key}: {below:.1} dB");
            } else {
                let selective = 20.0 * (on / beside).log10();
                println!("pressed {press} s after C3, key {key} held: {selective:.1} dB above key {}'s pitch", key + 1);
                assert!(selective >= 15.0, "key {key}: {selective:.1} dB");
            }
        }
    }
}

/// Letting a held key go lets its damper down on its strings as a partner too: C3 struck and let
/// go after 0.2 s with C4 held down (pressed as softly as MIDI can), C4 let go after 1 s or held
/// on. Between 0.5–1 s and 1.3–2.3 s, what C3 adds at C4's pitch falls at least 30 dB more when
/// C4 is let go than when it is held (measured: 173.8 dB, C3's voice ending, against 13.7 dB).
#[test]
fn letting_a_held_key_go_damps_its_strings_as_a_partner() {
    let c3 =
        [(0.0, Event::NoteOn { channel: 0, key: 48, velocity: 0.7 }), (0.2, Event::NoteOff { channel: 0, key: 48 })];
    let fall = |c4: &[(f64, Event)]| fall(&added_to(c4, &c3, 2.3), 0.5, 60);
    let press = (0.0, Event::NoteOn { channel: 0, key: 60, velocity: 1.0 / 127.0 });
    let (let_go, held) = (fall(&[press, (1.0, Event::NoteOff { channel: 0, key: 60 })]), fall(&[press]));
    println!("across C4's release: {let_go:.1} dB let go, {held:.1} dB held");
    assert!(let_go - held >= 30.0, "let go {let_go:.1} dB, held {held:.1} dB");
}

/// A held key keeps its strings free when the pedal lifts: C3 struck with the pedal down and C4
/// held down (pressed as softly as MIDI can), C3 let go after 0.1 s, the pedal lifted after 1 s.
/// Between 0.3–1 s and 1.3–2.3 s what C3 adds at the pitch of G4 (a partner whose damper falls
/// with the pedal, and none of whose modes C4's strings share) falls at least 30 dB more than at
/// C4's (one whose key holds its damper off) (measured: G4 falls 55.5 dB, to where C4's ring leaks
/// into its pitch; C4 8.1 dB).
#[test]
fn lifting_the_pedal_leaves_the_held_keys_strings_ringing() {
    let pedal = [(0.0, Event::Sustain { channel: 0, depth: 1.0 }), (1.0, Event::Sustain { channel: 0, depth: 0.0 })];
    let c4 = [(0.0, Event::NoteOn { channel: 0, key: 60, velocity: 1.0 / 127.0 })];
    let c3 =
        [(0.0, Event::NoteOn { channel: 0, key: 48, velocity: 0.7 }), (0.1, Event::NoteOff { channel: 0, key: 48 })];
    let added = added_to(&[&pedal[..], &c4].concat(), &c3, 2.3);
    let (c4, g4) = (fall(&added, 0.3, 60), fall(&added, 0.3, 67));
    println!("across the lift: G4 falls {g4:.1} dB, C4 {c4:.1} dB");
    assert!(g4 - c4 >= 30.0, "G4 {g4:.1} dB, C4 {c4:.1} dB");
}

/// A key stays held down when its voice is taken for another note: on a piano of two voices, C4
/// pressed as softly as MIDI can and C3 struck, both held, then E5 struck at 0.1 s (taking C4's
/// voice, the quieter) and C3 let go at 0.2 s. With C4 still held, C3 sounds 0.5–1.5 s later at
/// C4's pitch at least 30 dB louder than with C4 let go at 0.15 s: its strings stay free on C3's
/// bridge (measured 49.7 dB; 0.0 when a key counted as held only while a voice played it).
#[test]
fn a_key_stays_held_when_its_voice_is_taken() {
    let at_c4 = |release: bool| {
        let mut piano = dry_piano(2);
        let mut events = vec![
            (0.0, Event::NoteOn { channel: 0, key: 60, velocity: 1.0 / 127.0 }),
            (0.0, Event::NoteOn { channel: 0, key: 48, velocity: 0.7 }),
            (0.1, Event::NoteOn { channel: 0, key: 76, velocity: 0.7 }),
            (0.2, Event::NoteOff { channel: 0, key: 48 }),
        ];
        if release {
            events.push((0.15, Event::NoteOff { channel: 0, key: 60 }));
        }
        let out = perform(&mut piano, 64, &events, 1.5);
        assert_eq!(piano.steals(), 1, "E5 takes a voice");
        level(&out, (0.5 * FS) as usize, hz(60))
    };
    let louder = 20.0 * (at_c4(false) / at_c4(true)).log10();
    println!("C4 held on against let go: {louder:.1} dB at its pitch");
    assert!(louder >= 30.0, "{louder:.1} dB");
}
