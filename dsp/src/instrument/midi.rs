//! Raw MIDI messages to engine [`Event`]s, exactly as the plugin receives them: the host's
//! framework normalises the data bytes to `f32` (velocity and controllers `/127`, pitch bend
//! `/16383`), and the plugin maps those to events. The offline MIDI renderer uses this, so a MIDI
//! file gives the same samples offline and in a host.

use crate::instrument::Event;

/// The pitch wheel's largest 14-bit value.
const BEND_MAX: f32 = 16383.0;
/// The pitch wheel at rest: 0x2000.
const BEND_CENTRE: f32 = 8192.0;

/// The engine's bend (−1..=1) for a pitch-wheel value as the framework hands it on, `raw / 16383`.
///
/// The wheel at rest (8192) is exactly no bend, and either end is the whole bend range: the lower
/// half is scaled by 8192 steps, the upper by the 8191 it has (the min–centre–max scaling by which
/// MIDI 2.0 widens a MIDI 1.0 value). A straight line through 0..=16383 would put the wheel at
/// rest 6.1e-5 of the range sharp: 0.3 cents on an MPE member's ±48 semitones. Not a number passes
/// on as it is, for the engine to treat as any other bad value.
pub fn bend_from_normalised(normalised: f32) -> f32 {
    let steps = (normalised * BEND_MAX).round() - BEND_CENTRE;
    steps / if steps < 0.0 { BEND_CENTRE } else { BEND_MAX - BEND_CENTRE }
}

/// The engine event for a channel message `status, data1, data2`, if the engine plays it
/// (notes, poly and channel pressure, pitch bend, CC1, the parameter-number controllers CC6,
/// CC38 and CC98–101, CC64, CC66, CC67, CC74, CC120, CC121, CC123).
pub fn event_from_midi(status: u8, data1: u8, data2: u8) -> Option<Event> {
    let channel = status & 0x0f;
    let (key, value) = (data1 & 0x7f, data2 & 0x7f);
    let unit = |v: u8| f32::from(v) / 127.0;
    Some(match status & 0xf0 {
        0x90 if value == 0 => Event::NoteOff { channel, key },
        0x90 => Event::NoteOn { channel, key, velocity: unit(value) },
        0x80 => Event::NoteOff { channel, key },
        0xa0 => Event::PolyPressure { channel, key, value: unit(value) },
        0xd0 => Event::ChannelPressure { channel, value: unit(key) },
        0xe0 => {
            let normalised = (u16::from(key) + (u16::from(value) << 7)) as f32 / BEND_MAX;
            Event::PitchBend { channel, value: bend_from_normalised(normalised) }
        }
        0xb0 => match key {
            1 => Event::ModWheel { channel, value: unit(value) },
            6 | 38 | 98..=101 => Event::RegisteredParameter { channel, controller: key, value },
            64 => Event::Sustain { channel, depth: unit(value) },
            66 => Event::Sostenuto { channel, down: unit(value) >= 0.5 },
            67 => Event::SoftPedal { channel, down: unit(value) >= 0.5 },
            74 => Event::Timbre { channel, value: unit(value) },
            120 => Event::AllSoundOff,
            121 => Event::ResetControllers { channel },
            123 => Event::AllNotesOff,
            _ => return None,
        },
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bend(raw: u16) -> f32 {
        match event_from_midi(0xe0, (raw & 0x7f) as u8, (raw >> 7) as u8) {
            Some(Event::PitchBend { value, .. }) => value,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn the_pitch_wheel_at_rest_bends_nothing_and_its_ends_bend_the_whole_range() {
        assert_eq!(bend(8192), 0.0);
        assert_eq!(bend(0), -1.0);
        assert_eq!(bend(16383), 1.0);
        assert_eq!(bend(4096), -0.5);
        // One step either side of rest is one step of its half.
        assert_eq!(bend(8193), 1.0 / 8191.0);
        assert_eq!(bend(8191), -1.0 / 8192.0);
    }

    #[test]
    fn the_pitch_wheel_bends_further_at_every_step() {
        let mut last = bend(0);
        for raw in 1..=16383 {
            let now = bend(raw);
            assert!(now > last, "{raw}: {now} after {last}");
            last = now;
        }
        assert!(bend_from_normalised(f32::NAN).is_nan());
    }
}
