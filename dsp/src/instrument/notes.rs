//! Per-note addressing: which host note each voice plays, which voices a per-note event reaches,
//! and the notes whose voices have ended.
//!
//! A host that modulates per note (CLAP note expressions and polyphonic modulation, VST3 note
//! expressions) names a note by the voice (note) id it gave at note-on, by channel and key, or
//! both. A voice matches an event when every field the event gives equals the voice's note's
//! (CLAP's rule: an absent field is a wildcard); a note-on without an id matches only events
//! without one or addressed by channel and key.
//!
//! A voice's note ends when the voice stops sounding or another note takes the voice over (a
//! steal, a piano re-strike of the same string, a legato glide to a new key). Ended notes are
//! queued with the sample they ended at, for the host (a CLAP host frees its per-voice
//! modulators on the plugin's note-end events). The queue is sized once and never grows: while
//! it is full (a caller that never collects it, like the offline renderer), ending notes are not
//! queued.

use std::ops::Range;

/// A note as the host started it: its voice (note) id, if the host gave one, channel and key.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Note {
    /// The host's voice (note) id, if it gave one.
    pub voice: Option<i32>,
    /// MIDI channel, 0..=15.
    pub channel: u8,
    /// MIDI key, 0..=127.
    pub key: u8,
}

/// The notes a per-note event addresses: a voice matches when each given field equals its
/// note's; `None` matches anything.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NoteTarget {
    /// The host's voice (note) id.
    pub voice: Option<i32>,
    /// MIDI channel.
    pub channel: Option<u8>,
    /// MIDI key.
    pub key: Option<u8>,
}

impl NoteTarget {
    /// The note the host started with voice id `voice`.
    pub fn voice(voice: i32) -> Self {
        Self { voice: Some(voice), channel: None, key: None }
    }

    /// Every note on `channel` and `key`.
    pub fn key(channel: u8, key: u8) -> Self {
        Self { voice: None, channel: Some(channel & 15), key: Some(key & 127) }
    }

    /// Whether `note` is one of the addressed notes.
    pub fn matches(&self, note: &Note) -> bool {
        self.voice.is_none_or(|v| note.voice == Some(v))
            && self.channel.is_none_or(|c| c & 15 == note.channel)
            && self.key.is_none_or(|k| k & 127 == note.key)
    }
}

/// A slide setting that polyphonic modulation offsets per note.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NoteParam {
    /// `slide_position` (offset in semitones).
    SlidePosition,
    /// `hand_height` (offset in metres).
    HandHeight,
}

impl NoteParam {
    /// The largest offset that can matter (the setting's span), in the setting's unit: anything
    /// beyond is clamped to it, NaN is 0.
    fn span(self) -> f64 {
        match self {
            Self::SlidePosition => 24.0,
            Self::HandHeight => 6e-3,
        }
    }

    /// `offset` from a host made safe: NaN gives 0, the rest is clamped to ± the span.
    pub fn sanitize(self, offset: f32) -> f64 {
        if offset.is_nan() { 0.0 } else { f64::from(offset).clamp(-self.span(), self.span()) }
    }
}

/// Largest tuning a host may send (semitones): CLAP's and VST3's tuning expression range.
pub const MAX_TUNING: f64 = 120.0;

/// A tuning from a host (semitones) made safe: NaN gives 0, the rest is clamped to
/// ±[`MAX_TUNING`].
pub fn sanitize_tuning(semitones: f32) -> f64 {
    if semitones.is_nan() { 0.0 } else { f64::from(semitones).clamp(-MAX_TUNING, MAX_TUNING) }
}

/// A note whose voice ended, and when.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EndedNote {
    /// The note.
    pub note: Note,
    /// Sample index (since the instrument was made) at which it ended.
    pub at: u64,
}

/// The host note on each voice of a pool (indexed by a caller's flat voice index), and the ended
/// notes not yet collected.
#[derive(Debug, Clone)]
pub(crate) struct NoteBook {
    live: Vec<Option<Note>>,
    /// One bit per voice, set while `live` holds its note: the live voices without a pass over
    /// them all.
    live_bits: Vec<u64>,
    ended: Vec<EndedNote>,
}

impl NoteBook {
    /// Room for `voices` voices; the ended queue holds four times as many notes.
    pub(crate) fn new(voices: usize) -> Self {
        Self {
            live: vec![None; voices],
            live_bits: vec![0; voices.div_ceil(64)],
            ended: Vec::with_capacity(4 * voices.max(1)),
        }
    }

    /// The note voice `index` plays, if it has not ended.
    pub(crate) fn get(&self, index: usize) -> Option<Note> {
        self.live.get(index).copied().flatten()
    }

    /// Voice `index` starts `note` at sample `at`; the note it played before ends.
    pub(crate) fn start(&mut self, index: usize, note: Note, at: u64) {
        let Some(slot) = self.live.get_mut(index) else { return };
        self.live_bits[index / 64] |= 1 << (index % 64);
        if let Some(old) = slot.replace(note) {
            self.push(old, at);
        }
    }

    /// Voice `index` is silent (`sounding` false) at sample `at`: its note ends.
    pub(crate) fn check(&mut self, index: usize, sounding: bool, at: u64) {
        if !sounding && let Some(old) = self.live.get_mut(index).and_then(Option::take) {
            self.live_bits[index / 64] &= !(1 << (index % 64));
            self.push(old, at);
        }
    }

    /// `note`, which no voice plays, ends at sample `at` (a note-on the engine takes for a
    /// note-off: the host still hears of its end).
    pub(crate) fn end_unplayed(&mut self, note: Note, at: u64) {
        self.push(note, at);
    }

    /// Every live note ends at sample `at`, in the order of its voice's index.
    pub(crate) fn end_all(&mut self, at: u64) {
        self.check_live(at, |_| false);
        // Notes queued already ended by `at` at the latest: after a reset, whose clock starts
        // again from 0, none is reported later than the reset's notes.
        self.ended.iter_mut().for_each(|e| e.at = e.at.min(at));
    }

    /// [`check`](Self::check) every voice with a live note, in the order of their indices, with
    /// `sounding(index)` its state at sample `at`.
    pub(crate) fn check_live(&mut self, at: u64, sounding: impl Fn(usize) -> bool) {
        for word in 0..self.live_bits.len() {
            let mut bits = self.live_bits[word];
            while bits != 0 {
                let index = word * 64 + bits.trailing_zeros() as usize;
                bits &= bits - 1;
                self.check(index, sounding(index), at);
            }
        }
    }

    /// The voices among the flat indices `voices` with a live note, in the order of their indices,
    /// counted from `voices.start`: a pass over one pool's sounding voices that does not look at
    /// the others (every voice that sounds or fades has a live note until it is checked silent).
    pub(crate) fn live_in(&self, voices: Range<usize>) -> impl Iterator<Item = usize> + Clone + '_ {
        let start = voices.start;
        (start / 64..voices.end.div_ceil(64))
            .flat_map(move |word| {
                let mut bits = self.live_bits.get(word).copied().unwrap_or(0);
                std::iter::from_fn(move || {
                    let index = word * 64 + bits.trailing_zeros() as usize;
                    (bits != 0).then(|| {
                        bits &= bits - 1;
                        index
                    })
                })
            })
            .filter(move |index| voices.contains(index))
            .map(move |index| index - start)
    }

    /// The voices (flat indices, in order) whose live notes `target` addresses, with their notes.
    pub(crate) fn addressed(&self, target: NoteTarget) -> impl Iterator<Item = (usize, Note)> + '_ {
        self.live_in(0..self.live.len()).filter_map(move |i| self.get(i).filter(|n| target.matches(n)).map(|n| (i, n)))
    }

    /// End every live note of `old` and queue its ended notes here at sample `at`, oldest first
    /// (as many as the queue holds).
    pub(crate) fn take_ends_from(&mut self, old: &mut NoteBook, at: u64) {
        old.end_all(0);
        for ended in old.drain_ended() {
            self.push(ended.note, at);
        }
    }

    /// Queue an ended note, unless the queue is full. Never allocates.
    fn push(&mut self, note: Note, at: u64) {
        if self.ended.len() < self.ended.capacity() {
            self.ended.push(EndedNote { note, at });
        }
    }

    /// Take the ended notes, oldest first. Never allocates.
    pub(crate) fn drain_ended(&mut self) -> std::vec::Drain<'_, EndedNote> {
        self.ended.drain(..)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn targets_match_by_every_given_field() {
        let with_id = Note { voice: Some(7), channel: 2, key: 60 };
        let without = Note { voice: None, channel: 2, key: 60 };
        assert!(NoteTarget::voice(7).matches(&with_id));
        assert!(!NoteTarget::voice(8).matches(&with_id));
        assert!(!NoteTarget::voice(7).matches(&without), "an id addresses only the note that has it");
        assert!(NoteTarget::key(2, 60).matches(&with_id) && NoteTarget::key(2, 60).matches(&without));
        assert!(!NoteTarget::key(3, 60).matches(&without));
        assert!(NoteTarget::default().matches(&without), "all wildcards match every note");
        let both = NoteTarget { voice: Some(7), channel: Some(2), key: Some(61) };
        assert!(!both.matches(&with_id), "every given field must match");
    }

    #[test]
    fn host_values_are_sanitized() {
        assert_eq!(sanitize_tuning(f32::NAN), 0.0);
        assert_eq!(sanitize_tuning(f32::INFINITY), MAX_TUNING);
        assert_eq!(sanitize_tuning(-1e9), -MAX_TUNING);
        assert_eq!(NoteParam::SlidePosition.sanitize(f32::NEG_INFINITY), -24.0);
        assert_eq!(NoteParam::HandHeight.sanitize(1.0), 6e-3);
        assert_eq!(NoteParam::HandHeight.sanitize(f32::NAN), 0.0);
    }

    #[test]
    fn ended_notes_are_queued_once_and_never_beyond_capacity() {
        let mut book = NoteBook::new(1);
        let note = |key| Note { voice: Some(i32::from(key)), channel: 0, key };
        book.start(0, note(1), 10);
        book.start(0, note(2), 20);
        book.check(0, true, 25);
        book.check(0, false, 30);
        book.check(0, false, 40);
        let ended: Vec<_> = book.drain_ended().collect();
        assert_eq!(ended, [EndedNote { note: note(1), at: 20 }, EndedNote { note: note(2), at: 30 }]);
        let capacity = book.ended.capacity();
        for k in 0..=(2 * capacity as u8) {
            book.start(0, note(k), u64::from(k));
        }
        assert_eq!(book.ended.len(), capacity, "full, not grown");
        assert_eq!(book.ended.capacity(), capacity);
    }

    /// Over 200 voices (four words of bits), `check_live` asks only the voices with live notes,
    /// in the order of their indices, and ends exactly those that fell silent.
    #[test]
    fn check_live_asks_only_the_live_voices_and_ends_the_silent_ones() {
        let mut book = NoteBook::new(200);
        let note = |key| Note { voice: None, channel: 0, key };
        for index in [3, 63, 64, 130, 199] {
            book.start(index, note(index as u8), 0);
        }
        let asked = std::cell::RefCell::new(Vec::new());
        book.check_live(50, |index| {
            asked.borrow_mut().push(index);
            index % 2 == 0
        });
        assert_eq!(asked.take(), [3, 63, 64, 130, 199]);
        let ended: Vec<_> = book.drain_ended().map(|e| (e.note.key, e.at)).collect();
        assert_eq!(ended, [(3, 50), (63, 50), (199, 50)]);
        book.check_live(60, |index| {
            asked.borrow_mut().push(index);
            true
        });
        assert_eq!(asked.take(), [64, 130], "the ended notes are not asked again");
    }

    /// `live_in` gives the live voices of a range of flat indices, counted from its start, in
    /// order, across words of bits and at a range's ends: one pool's voices without the other's.
    #[test]
    fn live_in_gives_one_pools_live_voices_from_its_start() {
        let mut book = NoteBook::new(200);
        let note = |key| Note { voice: None, channel: 0, key };
        for index in [0, 3, 63, 64, 99, 100, 130, 199] {
            book.start(index, note(index as u8), 0);
        }
        let live = |book: &NoteBook, range| book.live_in(range).collect::<Vec<_>>();
        assert_eq!(live(&book, 0..100), [0, 3, 63, 64, 99]);
        assert_eq!(live(&book, 100..200), [0, 30, 99]);
        assert_eq!(live(&book, 64..65), [0]);
        assert_eq!(live(&book, 4..63), [] as [usize; 0]);
        book.check(64, false, 10);
        assert_eq!(live(&book, 0..100), [0, 3, 63, 99], "an ended note is not live");
    }
}
