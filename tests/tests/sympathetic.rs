//! Sympathetic resonance (docs/physics.md §14): with the sustain pedal down, a struck key's
//! partials set ringing, through the bridge, the strings of the keys whose partials they meet,
//! and not their neighbours.

use qsa_dsp::preset::key_frequency as hz;
use xtask::realism::{FS, held_with_pedal, level_near as level};

/// C3 held with the pedal down against the same C3 with the pedal up: the difference is what the
/// other keys' free strings add (and what C3's own partials give up to them). Over 1–3 s it is at
/// least 15 dB stronger at the pitch of each of C4, G4, C5 and E5 (C3's 2nd to 5th partials) than
/// at the pitch of its upper neighbour, whose partials C3 does not meet (measured 35.6, 41.7, 36.9
/// and 21.1 dB); and each of those strings is heard: its part is at most 30 dB below everything
/// the piano sounds at that pitch (measured 6.6, 10.1, 5.0 and −7.1 dB: the partner and the
/// partial it shares beat).
#[test]
fn c3_sets_the_strings_of_its_partials_ringing() {
    let (down, up) = (held_with_pedal(48, true, 3.0), held_with_pedal(48, false, 3.0));
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
