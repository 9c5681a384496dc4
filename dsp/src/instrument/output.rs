//! The output stage: the user's gain, smoothed, and the safety limiter.
//!
//! # Gain
//!
//! The gain parameter is read at control-block boundaries and the applied gain follows it through
//! two one-pole stages in series, each with time constant τ = [`GAIN_SMOOTHING`]:
//! `a[n] = a[n−1] + (G − a[n−1]) k`, `g[n] = g[n−1] + (a[n] − g[n−1]) k`, `k = 1 − e^{−1/(τ fs)}`.
//! A jump of the parameter (−36 dB to +12 dB in one step) becomes a glide that starts with zero
//! slope and settles to 1e-3 of the step in about 11τ: no step and no kink in the envelope, so
//! neither a single jump nor a gain automated anew at every control block is heard as a click or
//! a buzz at the block rate.
//!
//! # Safety limiter
//!
//! A look-ahead peak limiter, linked across the two channels, that guarantees no sample leaves
//! the instrument above the ceiling `c` ([`CEILING`], −0.1 dBFS). With `W` samples of look-ahead
//! ([`LOOKAHEAD`] seconds) and the frame entering at time n:
//!
//! - the gain the frame needs is `g[n] = min(1, c / max(|l[n]|, |r[n]|))`;
//! - the held gain `m[n] = min(g[n−W+1] … g[n])` covers every frame still in the delay line;
//! - the released gain `h[n] = min(m[n], h[n−1] + (1 − h[n−1]) k)` recovers with time constant
//!   [`RELEASE`] (`k = 1 − e^{−1/(RELEASE·fs)}`) and never exceeds `m`;
//! - the applied gain `s[n] = (h[n−W+1] + … + h[n]) / W` is a box average, so it falls over W
//!   samples instead of stepping;
//! - the frame leaving is the one that entered at `d = n − (W − 1)`, scaled by `s[n]`.
//!
//! Every `h[k]` in the average has `d` inside its hold window (`k ∈ [d, d + W − 1]`), so
//! `h[k] ≤ g[d]` and `s[n] ≤ g[d]`: the frame leaves at or below `c`. The limiter delays the
//! output by `W − 1` samples whether or not it is on (the plugin reports that latency), so
//! switching it never shifts the sound. Switched off, every frame asks for gain 1 and the gain
//! it was applying recovers at the release rate instead of jumping.
//!
//! A frame that is not finite (NaN or infinite in either channel, or beyond the range of an `f32`
//! once the gain is applied) enters as silence.
//!
//! The physics never needs it in normal playing (the default gain keeps a fortissimo chord of
//! ten notes below 0 dBFS); it is there for 32 unison voices at full gain and for a gain raised
//! by +12 dB.

/// Time constant of each of the gain smoother's two one-pole stages (s).
pub const GAIN_SMOOTHING: f64 = 0.005;

/// Largest magnitude the limiter lets through: −0.1 dBFS.
pub const CEILING: f64 = 0.988_553_094_656_939_4;

/// Look-ahead of the limiter (s): the time its gain takes to fall.
pub const LOOKAHEAD: f64 = 1e-3;

/// Release time constant of the limiter (s).
pub const RELEASE: f64 = 0.1;

/// The look-ahead in samples at `sample_rate` (at least 1). The output is late by this minus 1.
pub fn lookahead_samples(sample_rate: f64) -> usize {
    ((LOOKAHEAD * sample_rate).round() as usize).max(1)
}

/// Gain smoother and safety limiter, sized once for a sample rate; allocation-free after that.
#[derive(Debug, Clone)]
pub struct OutputStage {
    /// The gain parameter G.
    target: f64,
    /// The smoother's two stages `(a, g)`: `g` is the gain applied to the newest frame.
    smooth: (f64, f64),
    /// The smoother's coefficient k.
    smoothing: f64,
    /// Frames in the delay line and the gains the limiter tracks, one ring of W entries each.
    delay: Vec<(f32, f32)>,
    needed: Vec<f64>,
    released: Vec<f64>,
    /// Entries of `needed` below 1: while there are none the hold is 1 without a scan.
    limiting: usize,
    /// Sum of `released` (recomputed once per turn of the ring, so rounding cannot drift).
    sum: f64,
    /// Released gain of the newest frame.
    held: f64,
    /// Ring position of the newest frame.
    at: usize,
    /// Release coefficient k.
    release: f64,
}

impl OutputStage {
    /// A stage at rest (silence in the delay line) with gain `gain`.
    pub fn new(sample_rate: f64, gain: f64) -> Self {
        let w = lookahead_samples(sample_rate);
        Self {
            target: gain,
            smooth: (gain, gain),
            smoothing: 1.0 - (-1.0 / (GAIN_SMOOTHING * sample_rate)).exp(),
            delay: vec![(0.0, 0.0); w],
            needed: vec![1.0; w],
            released: vec![1.0; w],
            limiting: 0,
            sum: w as f64,
            held: 1.0,
            at: 0,
            release: 1.0 - (-1.0 / (RELEASE * sample_rate)).exp(),
        }
    }

    /// Samples by which the output is late: W − 1.
    pub fn latency(&self) -> usize {
        self.delay.len() - 1
    }

    /// Set the gain parameter G that the applied gain glides to.
    pub fn set_gain(&mut self, gain: f64) {
        self.target = gain;
    }

    /// Silence the delay line and release the limiter (all sound off).
    pub fn clear(&mut self) {
        self.delay.fill((0.0, 0.0));
        self.needed.fill(1.0);
        self.released.fill(1.0);
        self.limiting = 0;
        self.sum = self.delay.len() as f64;
        self.held = 1.0;
    }

    /// As made: silence in the delay line from its first entry, the limiter released and the
    /// gain at its target.
    pub fn reset(&mut self) {
        self.clear();
        self.at = 0;
        self.smooth = (self.target, self.target);
    }

    /// Apply the smoothed gain, then the limiter if `limit`, to the frames in `left` and `right`
    /// (in place, the same length).
    pub fn process(&mut self, left: &mut [f32], right: &mut [f32], limit: bool) {
        let w = self.delay.len();
        for (l, r) in left.iter_mut().zip(right.iter_mut()) {
            let (a, g) = &mut self.smooth;
            *a += (self.target - *a) * self.smoothing;
            *g += (*a - *g) * self.smoothing;
            let mut frame = (f64::from(*l) * *g, f64::from(*r) * *g);
            // A frame not finite in either channel, or beyond an `f32` once the gain is applied,
            // leaves as silence, limiter or not: no voice makes one, but a sum can overflow, and
            // the host must never receive one.
            if !((frame.0 as f32).is_finite() && (frame.1 as f32).is_finite()) {
                frame = (0.0, 0.0);
            }
            let peak = frame.0.abs().max(frame.1.abs());
            let need = if limit && peak > CEILING { CEILING / peak } else { 1.0 };
            self.at = if self.at + 1 == w { 0 } else { self.at + 1 };
            self.limiting -= usize::from(self.needed[self.at] < 1.0);
            self.limiting += usize::from(need < 1.0);
            self.needed[self.at] = need;
            let hold = if self.limiting == 0 { 1.0 } else { self.needed.iter().copied().fold(1.0, f64::min) };
            self.held = hold.min(self.held + (1.0 - self.held) * self.release);
            self.sum += self.held - self.released[self.at];
            self.released[self.at] = self.held;
            if self.at == 0 {
                self.sum = self.released.iter().sum();
            }
            let applied = (self.sum / w as f64).min(1.0);

            // The newest frame takes the slot of the one that left; the oldest is next in the ring.
            self.delay[self.at] = (frame.0 as f32, frame.1 as f32);
            let (dl, dr) = self.delay[if self.at + 1 == w { 0 } else { self.at + 1 }];
            let (mut yl, mut yr) = (f64::from(dl) * applied, f64::from(dr) * applied);
            if limit {
                yl = yl.clamp(-CEILING, CEILING);
                yr = yr.clamp(-CEILING, CEILING);
            }
            (*l, *r) = (yl as f32, yr as f32);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame that is not finite in either channel, or that the gain (here 2) carries beyond
    /// an `f32`, leaves as silence in both, with the limiter on or off, and the frames around it
    /// leave as they would without it: the gain and the limiter take no harm.
    #[test]
    fn a_frame_that_is_not_finite_leaves_as_silence() {
        let bad = [(100, f32::NAN), (101, f32::INFINITY), (250, f32::NEG_INFINITY), (300, 3e38)];
        for limit in [true, false] {
            for channel in 0..3 {
                let input: Vec<f32> = (0..400).map(|i| (0.45 * (0.3 * i as f64).sin()) as f32).collect();
                let run = |faults: &[(usize, f32)]| {
                    let mut stage = OutputStage::new(48_000.0, 2.0);
                    let (mut l, mut r) = (input.clone(), input.clone());
                    for &(i, x) in faults {
                        if channel != 1 {
                            l[i] = x;
                        }
                        if channel != 0 {
                            r[i] = x;
                        }
                    }
                    stage.process(&mut l, &mut r, limit);
                    (l, r, stage.latency())
                };
                let (clean, _, lat) = run(&[]);
                let (l, r, _) = run(&bad);
                for (i, (y, c)) in l.iter().zip(&clean).enumerate() {
                    let faulty = i >= lat && bad.iter().any(|&(at, _)| at == i - lat);
                    let expected = if faulty { 0.0 } else { *c };
                    assert_eq!(*y, expected, "limit {limit}, channels {channel}, sample {i}");
                    assert_eq!(r[i], expected, "limit {limit}, channels {channel}, sample {i}");
                }
            }
        }
    }

    /// The frames leave unchanged but `W − 1` samples late when nothing reaches the ceiling.
    #[test]
    fn below_the_ceiling_the_stage_is_a_pure_delay() {
        let mut stage = OutputStage::new(48_000.0, 1.0);
        let input: Vec<f32> = (0..200).map(|i| (0.9 * (0.3 * i as f64).sin()) as f32).collect();
        let (mut l, mut r) = (input.clone(), input.clone());
        stage.process(&mut l, &mut r, true);
        let lat = stage.latency();
        assert_eq!(lat, 47);
        for i in lat..200 {
            assert_eq!(l[i], input[i - lat]);
            assert_eq!(r[i], input[i - lat]);
        }
    }

    /// A burst at +20 dBFS (10×) leaves at or below the ceiling, and the gain falls over the
    /// look-ahead: no sample-to-sample gain step larger than 1/W of the reduction.
    #[test]
    fn a_burst_twenty_db_over_leaves_at_the_ceiling_with_a_smooth_gain() {
        let mut stage = OutputStage::new(48_000.0, 1.0);
        let n = 4_800;
        let input: Vec<f32> = (0..n).map(|i| if (1_000..2_000).contains(&i) { 10.0 } else { 0.5 } as f32).collect();
        let (mut l, mut r) = (input.clone(), input.clone());
        stage.process(&mut l, &mut r, true);
        let peak = l.iter().fold(0.0f32, |m, x| m.max(x.abs()));
        assert!(peak <= CEILING as f32, "peak {peak}");
        assert!(f64::from(peak) > 0.98 * CEILING, "the burst is limited to the ceiling, not below: {peak}");
        let lat = stage.latency();
        let gains: Vec<f64> = (lat..n).map(|i| f64::from(l[i]) / f64::from(input[i - lat])).collect();
        let largest_step = gains.windows(2).map(|g| (g[1] - g[0]).abs()).fold(0.0, f64::max);
        let w = (lat + 1) as f64;
        assert!(largest_step <= (1.0 - CEILING / 10.0) / w + 1e-6, "gain step {largest_step}");
    }

    /// Switched off, the stage passes +20 dBFS through (only delayed).
    #[test]
    fn switched_off_the_limiter_passes_everything() {
        let mut stage = OutputStage::new(44_100.0, 1.0);
        let (mut l, mut r) = (vec![10.0f32; 300], vec![-10.0f32; 300]);
        stage.process(&mut l, &mut r, false);
        assert_eq!((l[299], r[299]), (10.0, -10.0));
    }

    /// A gain jump (−36 dB to +12 dB) glides: the applied gain never steps by more than the
    /// smoother allows in one sample (k² of the jump in the first sample, k/e at most), its slope
    /// changes by less than k² of the jump per sample (no kink), and it is within 1e-3 of the jump
    /// of its target 11τ later.
    #[test]
    fn a_gain_jump_glides_without_a_step_or_a_kink() {
        let fs = 48_000.0;
        let (lo, hi) = (10f64.powf(-36.0 / 20.0), 10f64.powf(12.0 / 20.0));
        let mut stage = OutputStage::new(fs, lo);
        let n = 3200;
        let (mut l, mut r) = (vec![0.01f32; n], vec![0.01f32; n]);
        stage.process(&mut l[..200], &mut r[..200], false);
        stage.set_gain(hi);
        stage.process(&mut l[200..], &mut r[200..], false);
        let lat = stage.latency();
        let gain: Vec<f64> = l[lat..].iter().map(|&x| f64::from(x) / 0.01).collect();
        let k = 1.0 - (-1.0 / (GAIN_SMOOTHING * fs)).exp();
        let jump = hi - lo;
        let steps: Vec<f64> = gain.windows(2).map(|g| g[1] - g[0]).collect();
        let largest_step = steps.iter().copied().fold(0.0, f64::max);
        assert!(largest_step <= jump * k / std::f64::consts::E * 1.01, "step {largest_step}");
        let largest_kink = steps.windows(2).map(|s| (s[1] - s[0]).abs()).fold(0.0, f64::max);
        assert!(largest_kink <= jump * k * k * 1.01, "kink {largest_kink}");
        let settled = 200 + (11.0 * GAIN_SMOOTHING * fs) as usize;
        assert!((gain[settled] - hi).abs() < 1e-3 * jump, "gain {} after 11 τ", gain[settled]);
        assert!((gain[199] - lo).abs() < 1e-6 * lo, "the gain held before the jump");
    }
}
