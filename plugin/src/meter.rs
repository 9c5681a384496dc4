//! The data path from the audio thread to the editor, lock-free and allocation-free on the audio
//! side.
//!
//! - **DSP load**: each `process` call is timed with [`Instant`](std::time::Instant); the load is
//!   the time taken over the buffer's duration (1.0 = the whole real-time budget). The audio
//!   thread keeps a smoothed value (time constant [`LOAD_TIME_CONSTANT`]) and a peak; both go to
//!   the editor through [`AtomicF32`]s. The editor takes the peak with a swap, so it sees the
//!   worst call since its last frame. The peak weighs calls of at least [`PEAK_SPAN`] samples
//!   together: the framework splits a host's buffer at each parameter change, and a piece of a
//!   few samples, paying a call's fixed cost against its own tiny budget, would read as an
//!   overload the buffer never had.
//! - **Monitor**: every [`SNAPSHOT_PERIOD`] seconds of audio (counted in samples, so it does not
//!   depend on the host's buffer size: a call spanning several periods pushes one snapshot for
//!   each, the traces' time kept) the audio thread takes the engine's
//!   [`Monitor`] and `force_push`es it into a fixed-capacity
//!   [`ArrayQueue`]: when the editor falls behind, the oldest snapshot is dropped, never the audio
//!   thread blocked. Then it asks the editor to repaint ([`RepaintNotifier`] is one atomic store).
//!
//! Everything shared is allocated once, in the plugin's `Default`. The editor keeps the histories
//! (energy and force traces) on its own side.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use atomic_float::AtomicF32;
use crossbeam_queue::ArrayQueue;
use nice_plug_egui::RepaintNotifier;
use qsa_dsp::instrument::{Instrument, Monitor};

/// Seconds of audio between two monitor snapshots (about a display frame).
pub const SNAPSHOT_PERIOD: f64 = 1.0 / 30.0;

/// Snapshots the queue holds before the oldest is dropped.
pub const QUEUE_CAPACITY: usize = 8;

/// Time constant of the smoothed load (s of audio).
pub const LOAD_TIME_CONSTANT: f64 = 0.3;

/// The fewest samples the peak load is taken over: calls shorter than this are weighed together
/// with those after them (1.3 ms at 48 kHz: with a host's buffers of 32 samples, two are weighed
/// together, and an overrun in one shows at about half).
pub const PEAK_SPAN: usize = 64;

/// What the audio thread shares with the editor.
#[derive(Debug)]
pub struct Shared {
    /// Smoothed DSP load: process time over buffer duration (1.0 = the real-time budget).
    pub load: AtomicF32,
    /// Largest unsmoothed load since the editor last took it (with `swap(0.0)`).
    pub peak: AtomicF32,
    /// Monitor snapshots, oldest first.
    pub monitors: ArrayQueue<Monitor>,
    /// Set when a snapshot arrives; the editor polls it and repaints.
    pub repaint: RepaintNotifier,
    /// The voice count the engine was last activated with (0 before the first activation).
    pub voices: AtomicUsize,
}

impl Default for Shared {
    fn default() -> Self {
        Self {
            load: AtomicF32::new(0.0),
            peak: AtomicF32::new(0.0),
            monitors: ArrayQueue::new(QUEUE_CAPACITY),
            repaint: RepaintNotifier::new(),
            voices: AtomicUsize::new(0),
        }
    }
}

/// The audio thread's side of the data path: the sample counter and the load smoother.
#[derive(Debug)]
pub struct Tap {
    shared: Arc<Shared>,
    sample_rate: f64,
    /// Samples between snapshots.
    period: usize,
    /// Samples until the next snapshot.
    countdown: usize,
    /// Smoothed load (the audio thread's copy).
    load: f64,
    /// Samples and time of the calls not yet weighed into the peak (fewer than [`PEAK_SPAN`]).
    short: (usize, Duration),
}

impl Tap {
    /// A tap writing into `shared`, at 48 kHz until [`Tap::set_sample_rate`] is called.
    pub fn new(shared: Arc<Shared>) -> Self {
        let mut tap =
            Self { shared, sample_rate: 48_000.0, period: 1, countdown: 0, load: 0.0, short: (0, Duration::ZERO) };
        tap.set_sample_rate(48_000.0);
        tap
    }

    /// The shared state this tap writes.
    pub fn shared(&self) -> &Arc<Shared> {
        &self.shared
    }

    /// Set the sample rate (Hz), from `activate`. Restarts the snapshot count.
    pub fn set_sample_rate(&mut self, sample_rate: f64) {
        self.sample_rate = if sample_rate.is_finite() && sample_rate > 0.0 { sample_rate } else { 48_000.0 };
        self.period = ((self.sample_rate * SNAPSHOT_PERIOD).round() as usize).max(1);
        self.countdown = 0;
    }

    /// Come to rest as the plugin stops processing (deactivated): the load and its peak at 0 and
    /// a snapshot of no voice sounding, which keeps `engine`'s counts of sheds and guard trips
    /// (they go on across activations), so that the editor does not show the last call's figures
    /// while nothing runs, and the load measured after the next activation starts afresh.
    pub fn rest(&mut self, engine: Option<&Instrument>) {
        self.load = 0.0;
        self.short = (0, Duration::ZERO);
        self.shared.load.store(0.0, Ordering::Relaxed);
        self.shared.peak.store(0.0, Ordering::Relaxed);
        let counts = engine.map_or((0, 0), |e| (e.shed_count(), e.guard_trips()));
        let idle = Monitor { shed: counts.0, guard_trips: counts.1, ..Monitor::default() };
        let _ = self.shared.monitors.force_push(idle);
        self.shared.repaint.request_repaint();
        self.countdown = 0;
    }

    /// Samples between two snapshots.
    pub fn period(&self) -> usize {
        self.period
    }

    /// Account for one process call of `samples` samples that took `elapsed`: update the load and,
    /// for each snapshot due and if `engine` is given, push its monitor and request a repaint.
    /// Returns how many snapshots were pushed. Allocation-free, lock-free.
    pub fn after_process(&mut self, samples: usize, elapsed: Duration, engine: Option<&Instrument>) -> usize {
        if samples == 0 {
            return 0;
        }
        let duration = samples as f64 / self.sample_rate;
        let raw = elapsed.as_secs_f64() / duration;
        let a = 1.0 - (-duration / LOAD_TIME_CONSTANT).exp();
        self.load += a * (raw - self.load);
        self.shared.load.store(self.load as f32, Ordering::Relaxed);
        self.short = (self.short.0 + samples, self.short.1 + elapsed);
        if self.short.0 >= PEAK_SPAN {
            let weighed = self.short.1.as_secs_f64() * self.sample_rate / self.short.0 as f64;
            self.shared.peak.fetch_max(weighed as f32, Ordering::Relaxed);
            self.short = (0, Duration::ZERO);
        }

        if samples < self.countdown {
            self.countdown -= samples;
            return 0;
        }
        // Overshoot carries over, so snapshots keep the audio-time rate for any buffer size.
        let due = 1 + (samples - self.countdown) / self.period;
        let overshoot = (samples - self.countdown) % self.period;
        self.countdown = self.period - overshoot;
        let Some(engine) = engine else {
            return 0;
        };
        // The engine's state at the call's end stands for each period the call spanned (at most
        // a queue's worth). A displaced (oldest) snapshot is plain data: dropping it frees nothing.
        let pushed = due.min(QUEUE_CAPACITY);
        let monitor = engine.monitor();
        for _ in 0..pushed {
            let _ = self.shared.monitors.force_push(monitor);
        }
        self.shared.repaint.request_repaint();
        pushed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use qsa_dsp::instrument::{Event, Settings};

    /// Processing through the engine path pushes one snapshot per period of audio, whatever the
    /// buffer size, each showing the struck string; and the load follows process time over buffer
    /// duration.
    #[test]
    fn process_path_pushes_snapshots_and_sets_load() {
        let fs = 48_000.0;
        let mut engine = Instrument::new(fs, 4, Settings::default());
        let shared = Arc::new(Shared::default());
        let mut tap = Tap::new(shared.clone());
        tap.set_sample_rate(fs);
        assert_eq!(tap.period(), 1600);

        engine.handle(Event::NoteOn { channel: 0, key: 60, velocity: 0.8 });
        let (mut left, mut right) = (vec![0.0f32; 1024], vec![0.0f32; 1024]);
        let mut pushed = 0;
        let mut rendered = 0;
        // Uneven buffer sizes, 0.25 s in all.
        for size in [1usize, 64, 1000, 37, 512, 1024].iter().cycle() {
            if rendered >= 12_000 {
                break;
            }
            let n = (*size).min(12_000 - rendered);
            engine.process(&mut left[..n], &mut right[..n]);
            // Pretend each call took a quarter of its budget.
            let elapsed = Duration::from_secs_f64(0.25 * n as f64 / fs);
            pushed += tap.after_process(n, elapsed, Some(&engine));
            rendered += n;
        }
        // A snapshot at the first call, then one every 1600 samples: 0, 1600, ..., 11200.
        assert_eq!(pushed, 8);
        assert_eq!(shared.monitors.len(), 8);
        let mut last = None;
        while let Some(m) = shared.monitors.pop() {
            last = Some(m);
        }
        let m = last.expect("a snapshot");
        assert_eq!(m.sounding, 1);
        assert_eq!(m.key, 60);
        assert!(m.energy > 0.0, "energy {}", m.energy);
        assert!(m.shape.iter().any(|&y| y != 0.0));

        // 0.25 s at a constant 0.25 load, smoothed with 0.3 s: within the smoother's rise.
        let load = shared.load.load(Ordering::Relaxed);
        let expected = 0.25 * (1.0 - (-0.25f64 / LOAD_TIME_CONSTANT).exp());
        assert!((f64::from(load) - expected).abs() < 0.01, "load {load}, expected {expected}");
        assert!((shared.peak.swap(0.0, Ordering::Relaxed) - 0.25).abs() < 1e-4);

        // A full queue drops the oldest, and no engine means no snapshot but still a load.
        for _ in 0..2 * QUEUE_CAPACITY {
            tap.after_process(tap.period(), Duration::ZERO, Some(&engine));
        }
        assert_eq!(shared.monitors.len(), QUEUE_CAPACITY);
        assert_eq!(tap.after_process(4 * tap.period(), Duration::from_millis(1), None), 0);
        assert!(shared.peak.load(Ordering::Relaxed) > 0.0);
    }

    /// Snapshots come thirty times a second of audio whatever the host's buffer size: at
    /// 48 kHz, 1.024 s in calls of 2048, 4096 or 8192 samples (1.3, 2.6 and 5.1 periods each)
    /// give 31 snapshots, one at each multiple of 1600 samples, as calls of 64 do.
    #[test]
    fn a_tap_gives_thirty_snapshots_a_second_whatever_the_buffer_size() {
        let engine = Instrument::new(48_000.0, 4, Settings::default());
        for size in [64, 2048, 4096, 8192] {
            let shared = Arc::new(Shared::default());
            let mut tap = Tap::new(shared.clone());
            let (mut pushed, mut popped) = (0, 0);
            for _ in 0..49_152 / size {
                pushed += tap.after_process(size, Duration::ZERO, Some(&engine));
                while shared.monitors.pop().is_some() {
                    popped += 1;
                }
            }
            assert_eq!((pushed, popped), (31, 31), "calls of {size} samples");
        }
    }

    /// A host's buffer that the framework splits at a parameter change into 4 and 1020 samples
    /// (taking 50 µs and 5 ms, a fixed cost of the short piece against its own 83 µs budget)
    /// shows the buffer's peak load, 0.24, not the piece's 0.6; calls of 64 samples and more are
    /// each their own peak.
    #[test]
    fn a_buffer_split_at_a_parameter_change_shows_the_peak_of_the_whole_buffer() {
        let shared = Arc::new(Shared::default());
        let mut tap = Tap::new(shared.clone());
        tap.after_process(4, Duration::from_micros(50), None);
        assert_eq!(shared.peak.load(Ordering::Relaxed), 0.0, "a short piece waits for the next");
        tap.after_process(1020, Duration::from_millis(5), None);
        let peak = shared.peak.swap(0.0, Ordering::Relaxed);
        assert!((peak - 5.05 / (1024.0 / 48.0)).abs() < 1e-4, "peak {peak}");
        tap.after_process(64, Duration::from_secs_f64(0.9 * 64.0 / 48_000.0), None);
        assert!((shared.peak.load(Ordering::Relaxed) - 0.9).abs() < 1e-4);
    }

    /// A tap brought to rest (the plugin deactivated while a note sounds and the load is 45 %)
    /// leaves the editor a load and peak of 0 and, newest in the queue, a snapshot of no voice
    /// sounding with the engine's counts of sheds (here 1) kept; the next call's load is measured
    /// from 0, not from the old load.
    #[test]
    fn a_tap_at_rest_shows_nothing_running() {
        let fs = 48_000.0;
        let mut engine = Instrument::new(fs, 4, Settings::default());
        engine.handle(Event::NoteOn { channel: 0, key: 60, velocity: 0.8 });
        engine.handle(Event::NoteOn { channel: 0, key: 64, velocity: 0.8 });
        let shared = Arc::new(Shared::default());
        let mut tap = Tap::new(shared.clone());
        let (mut left, mut right) = (vec![0.0f32; 480], vec![0.0f32; 480]);
        engine.process(&mut left, &mut right);
        engine.shed_voices(1);
        for _ in 0..100 {
            engine.process(&mut left, &mut right);
            tap.after_process(480, Duration::from_secs_f64(0.45 * 0.01), Some(&engine));
        }
        assert!(shared.load.load(Ordering::Relaxed) > 0.4);
        assert_eq!(engine.shed_count(), 1);
        tap.rest(Some(&engine));
        assert_eq!((shared.load.load(Ordering::Relaxed), shared.peak.load(Ordering::Relaxed)), (0.0, 0.0));
        let mut newest = None;
        while let Some(m) = shared.monitors.pop() {
            newest = Some(m);
        }
        assert_eq!(newest.map(|m| (m.sounding, m.shed)), Some((0, 1)));
        tap.after_process(480, Duration::ZERO, None);
        assert_eq!(shared.load.load(Ordering::Relaxed), 0.0);
    }
}
