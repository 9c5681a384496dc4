//! Raw MIDI messages to engine [`Event`]s, exactly as the plugin receives them: the host's
//! framework normalises the data bytes to `f32` (velocity and controllers `/127`, pitch bend
//! `/16383`), and the plugin maps those to events. The offline MIDI renderer uses this, so a MIDI
//! file gives the same samples offline and in a host.

use crate::instrument::Event;

/// The engine event for a channel message `status, data1, data2`, if the engine plays it
/// (notes, poly and channel pressure, pitch bend, CC1, the registered-parameter controllers CC6,
/// CC38, CC100 and CC101, CC64, CC66, CC67, CC120, CC121, CC123).
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
            let normalised = (u16::from(key) + (u16::from(value) << 7)) as f32 / ((1 << 14) - 1) as f32;
            Event::PitchBend { channel, value: 2.0 * normalised - 1.0 }
        }
        0xb0 => match key {
            1 => Event::ModWheel { channel, value: unit(value) },
            6 | 38 | 100 | 101 => Event::RegisteredParameter { channel, controller: key, value },
            64 => Event::Sustain { channel, depth: unit(value) },
            66 => Event::Sostenuto { channel, down: unit(value) >= 0.5 },
            67 => Event::SoftPedal { channel, down: unit(value) >= 0.5 },
            120 => Event::AllSoundOff,
            121 => Event::ResetControllers { channel },
            123 => Event::AllNotesOff,
            _ => return None,
        },
        _ => return None,
    })
}
