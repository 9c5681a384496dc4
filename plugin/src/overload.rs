//! The overload guard: when the audio thread cannot keep up, the plugin gives up its least
//! audible voices ([`Instrument::shed_voices`](qsa_dsp::instrument::Instrument::shed_voices))
//! rather than leave the host to drop whole buffers.
//!
//! Each `process` call's load is its time over its buffer's duration (1 = the whole real-time
//! budget; calls shorter than [`SHORTEST_SPAN`] are weighed with the next), counted up to
//! [`MAX_COUNTED_LOAD`] and smoothed over [`GUARD_TIME_CONSTANT`] of audio, or over
//! [`CALLS_SMOOTHED`] calls where the host's buffers are longer than that allows, so that one call
//! the operating system held up does not weigh like many at any buffer size (a 1024-sample call
//! would otherwise carry a third of the smoothed load, and one held up 30 ms would shed a third of
//! the voices). Once the smoothed load exceeds [`OVERLOAD`] (the host needs some of the budget for
//! itself and other plugins), the guard sheds the share of the sounding voices that brings it to
//! [`TARGET_LOAD`], taking every voice to cost alike, then waits [`SETTLE_TIME`] for the load to
//! show the effect before it sheds again. The plugin runs it in real-time processing only, while
//! its `Overload guard` switch is on: an offline render takes the time it needs and sounds the same
//! on every machine, and a user measuring how much of the CPU a performance takes can switch it
//! off.

/// Time constant of the guard's smoothed load (s of audio).
pub const GUARD_TIME_CONSTANT: f64 = 0.05;

/// The most one call's load counts for.
pub const MAX_COUNTED_LOAD: f64 = 2.0;

/// The shortest span of audio whose load is counted (s): shorter calls are weighed together with
/// those after them. The framework splits a host's buffer at each parameter change, and the
/// engine's work for a control block falls in whichever piece its start lands in: a piece of a
/// sample or two would count that work against its own tiny budget, up to [`MAX_COUNTED_LOAD`]
/// and no further, so the guard would read a buffer's overload as lower than it is.
pub const SHORTEST_SPAN: f64 = 1e-3;

/// The fewest calls the load is smoothed over: its time constant is at least this many calls'
/// duration, so that a call weighs at most `1 − e^(−1/8)`, 12 %, of the smoothed load.
pub const CALLS_SMOOTHED: f64 = 8.0;

/// Smoothed load above which voices are shed.
pub const OVERLOAD: f64 = 0.9;

/// Load that shedding aims for.
pub const TARGET_LOAD: f64 = 0.7;

/// Audio time after shedding before the guard may shed again (s): two time constants, in which
/// the smoothed load moves 86 % of the way to its new level. With long buffers the guard waits
/// two of their longer time constant ([`CALLS_SMOOTHED`]) instead.
pub const SETTLE_TIME: f64 = 2.0 * GUARD_TIME_CONSTANT;

/// The guard's state: the smoothed load, the time left to settle, whether it is switched off,
/// and the audio and time of the calls not yet counted (shorter together than [`SHORTEST_SPAN`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct OverloadGuard {
    load: f64,
    settle: f64,
    off: bool,
    short: (f64, f64),
}

impl OverloadGuard {
    /// Account for a call that rendered `duration` seconds of audio in `elapsed` seconds, with
    /// `sounding` voices that could be shed; returns how many to shed now.
    pub fn after_call(&mut self, duration: f64, elapsed: f64, sounding: usize) -> usize {
        if self.off || !(duration > 0.0) || !elapsed.is_finite() {
            return 0;
        }
        let (duration, elapsed) = (self.short.0 + duration, self.short.1 + elapsed);
        if duration < SHORTEST_SPAN {
            self.short = (duration, elapsed);
            return 0;
        }
        self.short = (0.0, 0.0);
        let raw = (elapsed / duration).clamp(0.0, MAX_COUNTED_LOAD);
        let time_constant = GUARD_TIME_CONSTANT.max(CALLS_SMOOTHED * duration);
        let a = 1.0 - (-duration / time_constant).exp();
        self.load += a * (raw - self.load);
        self.settle = (self.settle - duration).max(0.0);
        if self.settle > 0.0 || self.load <= OVERLOAD || sounding == 0 {
            return 0;
        }
        self.settle = SETTLE_TIME * time_constant / GUARD_TIME_CONSTANT;
        ((sounding as f64 * (1.0 - TARGET_LOAD / self.load)).ceil() as usize).clamp(1, sounding)
    }

    /// The smoothed load.
    pub fn load(&self) -> f64 {
        self.load
    }

    /// Forget the load measured so far (the engine was reset or made anew).
    pub fn reset(&mut self) {
        *self = Self { off: self.off, ..Self::default() };
    }

    /// Switch the guard on or off. Off, it sheds nothing and measures nothing; switched on again,
    /// it starts from rest, as after [`reset`](Self::reset), not from a load it saw before.
    pub fn switch(&mut self, on: bool) {
        if self.off == on {
            self.off = !on;
            self.reset();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 64-sample calls at 48 kHz.
    const CALL: f64 = 64.0 / 48_000.0;

    /// Run `calls` calls at load `load` with `sounding` voices; the sheds asked for, by call.
    fn run(guard: &mut OverloadGuard, calls: usize, load: f64, sounding: usize) -> Vec<(usize, usize)> {
        (0..calls)
            .filter_map(|i| Some((i, guard.after_call(CALL, load * CALL, sounding))).filter(|&(_, n)| n > 0))
            .collect()
    }

    /// A load held at 0.85, under the threshold, for ten seconds sheds nothing.
    #[test]
    fn a_load_under_the_threshold_sheds_nothing() {
        let mut guard = OverloadGuard::default();
        assert!(run(&mut guard, 7_500, 0.85, 88).is_empty());
        assert!((guard.load() - 0.85).abs() < 1e-9, "smoothed load {}", guard.load());
    }

    /// One call held up by the operating system for 30 ms (a load of 23 on a 64-sample call)
    /// amid calls at 0.6 counts as a load of 2 and sheds nothing; the same delay on every call
    /// sheds.
    #[test]
    fn one_late_call_does_not_shed_but_a_steady_overload_does() {
        let mut guard = OverloadGuard::default();
        run(&mut guard, 1_000, 0.6, 40);
        assert_eq!(guard.after_call(CALL, CALL + 0.03, 40), 0);
        assert!(run(&mut guard, 1_000, 0.6, 40).is_empty());
        assert!(!run(&mut guard, 100, 23.0, 40).is_empty());
    }

    /// One call held up by 30 ms amid calls at 0.6 with 40 voices sheds nothing at the buffer
    /// sizes and rates hosts use, from 64 samples at 48 kHz to 8192 at 48 kHz (a 1024-sample call
    /// weighed by its duration alone took the smoothed load to 1.09 and shed 15 voices), while a
    /// steady load of 1.2 sheds at every size once the smoothed load crosses 0.9, after
    /// `τ·ln(1.2/0.3)` with `τ` the longer of 50 ms and eight calls (within a call of it), and
    /// again only after settling for `2τ`.
    #[test]
    fn one_late_call_sheds_nothing_at_any_buffer_size_but_a_steady_overload_does() {
        for (block, rate) in [
            (64.0, 48e3),
            (256.0, 48e3),
            (512.0, 44.1e3),
            (1024.0, 48e3),
            (2048.0, 48e3),
            (4096.0, 96e3),
            (8192.0, 48e3),
        ] {
            let call: f64 = block / rate;
            let tau = GUARD_TIME_CONSTANT.max(CALLS_SMOOTHED * call);
            let calls = (10.0 * tau / call) as usize;
            let mut guard = OverloadGuard::default();
            let steady: Vec<usize> = (0..calls).map(|_| guard.after_call(call, 0.6 * call, 40)).collect();
            assert!(steady.iter().all(|&n| n == 0));
            let late = guard.after_call(call, call + 0.03, 40);
            let after: usize = (0..calls).map(|_| guard.after_call(call, 0.6 * call, 40)).sum();
            println!("{block} samples at {rate} Hz: the late call sheds {late}, load {:.3}", guard.load());
            assert_eq!((late, after), (0, 0), "{block} samples at {rate} Hz");
            let mut guard = OverloadGuard::default();
            // The end of each call that sheds (s).
            let sheds: Vec<f64> =
                (1..=calls).filter(|_| guard.after_call(call, 1.2 * call, 40) > 0).map(|i| i as f64 * call).collect();
            let crossing = tau * 4f64.ln();
            println!("steady overload: sheds at {sheds:.3?} s, the load crossing 0.9 at {crossing:.3} s");
            assert!(sheds.first().is_some_and(|&t| (t - crossing).abs() <= call), "{block} at {rate} Hz: {sheds:?}");
            assert!(sheds.windows(2).all(|w| w[1] - w[0] >= 2.0 * tau - 1e-9), "{block} at {rate} Hz: {sheds:?}");
        }
    }

    /// A steady overload of 1.2 with 88 voices: the first shed comes once the smoothed load
    /// crosses 0.9 (after `τ·ln(1.2/0.3)` from rest at 0: 69 ms, the 52nd call), and is the share
    /// `1 − 0.7/L` of the voices at that load; the next waits the settling time (75 calls).
    #[test]
    fn a_steady_overload_sheds_the_share_that_brings_the_load_to_its_target_then_settles() {
        let mut guard = OverloadGuard::default();
        let sheds = run(&mut guard, 200, 1.2, 88);
        let first = sheds[0].0;
        let crossing = (GUARD_TIME_CONSTANT * (1.2f64 / 0.3).ln() / CALL).ceil() as usize - 1;
        assert!(first.abs_diff(crossing) <= 1, "first shed at call {first}, expected {crossing}");
        // The smoothed load at that call.
        let at = 1.2 * (1.0 - (-((first + 1) as f64) * CALL / GUARD_TIME_CONSTANT).exp());
        let expected = (88.0 * (1.0 - TARGET_LOAD / at)).ceil() as usize;
        assert_eq!(sheds[0].1, expected, "load {at:.3}");
        assert!(sheds[0].1 >= 20 && sheds[0].1 <= 25, "{} voices", sheds[0].1);
        let settle = SETTLE_TIME / CALL;
        assert!(((sheds[1].0 - first) as f64 - settle).abs() <= 1.0, "{sheds:?}");
    }

    /// Switched off, two seconds of a steady overload of 1.5 shed nothing; switched on again, the
    /// guard starts from rest: the first shed comes at the same call as for a guard that never
    /// saw the overload (`τ·ln(1.5/0.6)`, the 35th call), not at once.
    #[test]
    fn switched_off_the_guard_sheds_nothing_and_switched_on_it_starts_from_rest() {
        let mut guard = OverloadGuard::default();
        run(&mut guard, 100, 1.5, 88);
        guard.switch(false);
        assert!(run(&mut guard, 1_500, 1.5, 88).is_empty());
        guard.switch(false);
        assert!(run(&mut guard, 10, 1.5, 88).is_empty(), "switching off twice keeps it off");
        guard.switch(true);
        let sheds = run(&mut guard, 200, 1.5, 88);
        let fresh = run(&mut OverloadGuard::default(), 200, 1.5, 88);
        let crossing = (GUARD_TIME_CONSTANT * (1.5f64 / 0.6).ln() / CALL).ceil() as usize - 1;
        assert!(sheds[0].0.abs_diff(crossing) <= 1, "first shed at call {}, expected {crossing}", sheds[0].0);
        assert_eq!(sheds, fresh);
        let load = guard.load();
        guard.switch(true);
        assert!(load > OVERLOAD && guard.load() == load, "switching on twice keeps the load measured");
    }

    /// A host's 64-sample buffers at 48 kHz, each split by a parameter change into a call of one
    /// sample that bears the control block's work (10.85 samples' worth of time) and one of 63
    /// at a load of 0.85: a whole buffer's load is (10.85 + 0.85·63)/64 = 1.006, past the
    /// threshold, and the guard sheds within a second, as it does for the same work in whole
    /// buffers. Counted call by call, the one-sample piece's load of 10.85 would be cut to 2 and
    /// the smoothed load would settle at 0.87, shedding nothing.
    #[test]
    fn a_buffer_split_at_a_parameter_change_counts_its_whole_load() {
        let sample = 1.0 / 48_000.0;
        let mut split = OverloadGuard::default();
        let mut whole = OverloadGuard::default();
        let (mut shed_split, mut shed_whole) = (0, 0);
        for _ in 0..750 {
            shed_split += split.after_call(sample, 10.85 * sample, 40);
            shed_split += split.after_call(63.0 * sample, 0.85 * 63.0 * sample, 40);
            shed_whole += whole.after_call(CALL, (10.85 + 0.85 * 63.0) * sample, 40);
        }
        let (a, b) = (split.load(), whole.load());
        println!("split buffers: load {a:.3}, shed {shed_split}; whole: load {b:.3}, shed {shed_whole}");
        assert!((split.load() - whole.load()).abs() < 1e-9, "{} vs {}", split.load(), whole.load());
        assert!(shed_split > 0 && shed_split == shed_whole, "{shed_split} vs {shed_whole}");
    }

    /// Nothing to shed, a zero-length call or a non-finite time asks for nothing.
    #[test]
    fn degenerate_calls_shed_nothing() {
        let mut guard = OverloadGuard::default();
        assert!(run(&mut guard, 500, 1.5, 0).is_empty());
        assert_eq!(guard.after_call(0.0, 1.0, 10), 0);
        assert_eq!(guard.after_call(CALL, f64::NAN, 10), 0);
        assert_eq!(guard.after_call(CALL, f64::INFINITY, 10), 0);
        guard.reset();
        assert_eq!(guard.load(), 0.0);
    }
}
