//! The magnetic pickup's electrical response (docs/physics.md §13.4).
//!
//! A magnetic pickup's coil gives a voltage proportional to the rate of change of the flux the
//! steel string modulates, so to the string's velocity under it (the slide voice's output). Its
//! inductance `L` (1–10 H), its winding capacitance with the cable's (80–200 pF and 300–1,000 pF)
//! and the load form a resonant low-pass:
//!
//! ```text
//! H(s) = 1 / (1 + s/(Q ω_r) + s²/ω_r²),     ω_r = 1/√(LC)
//! ```
//!
//! Lemme measures the loaded resonance of most pickups with common cables between 2 and 5 kHz,
//! with a peak of 0 to 12 dB depending on the magnet, the load and a metal cover; slightly
//! underdamped pickups show a 3–5 dB bump. [`PICKUP_Q`] gives the middle of that: 4.0 dB.
//!
//! The low-pass is discretised by the bilinear transform prewarped at `ω_r`, so the resonance sits
//! at its frequency at every sample rate: at `z = e^{jωΔt}`, `s/ω_r` becomes `jΩ` with
//! `Ω = tan(ωΔt/2)/g` and `g = tan(ω_rΔt/2)`. It is run as a state-variable filter of trapezoidal
//! integrators (Zavalishin, *The Art of VA Filter Design*, ch. 4), whose two states are the
//! integrators' own: a resonance that moves changes `g` and leaves them where they are, so a
//! swept tone control changes the sound smoothly. A direct-form biquad's states mix the old
//! coefficients into the signal's past, and a step of its coefficients is a step of its output:
//! a click at every control block of a sweep. Per sample, with `k = 1/Q`:
//!
//! ```text
//! v1 = (s1 + g(x − s2)) / (1 + g(g + k)),   v2 = s2 + g·v1,   y = v2
//! s1 ← 2v1 − s1,   s2 ← 2v2 − s2
//! ```
//!
//! and `g` moves linearly, a sample at a time, to where [`tune`](PickupCircuit::tune) puts it
//! over the samples it is given (the instrument's control block), however the calls to
//! [`process`](PickupCircuit::process) cut them.

/// Quality factor of the loaded pickup: a resonance peak of 4.0 dB (`Q/√(1 − 1/(4Q²))`).
pub const PICKUP_Q: f64 = 1.5;

/// Below this the circuit's states are brought to rest (in the unit of its input: far below
/// anything heard, far above the subnormal numbers).
const FLUSH_BELOW: f64 = 1e-30;

/// A magnetic pickup's resonant low-pass (module docs), a state-variable filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PickupCircuit {
    /// `g = tan(ω_rΔt/2)` now.
    g: f64,
    /// `g` of the resonance asked for.
    target: f64,
    /// How much `g` moves a sample on its way to `target`.
    slope: f64,
    /// Samples left before `g` reaches `target`.
    left: usize,
    /// The integrators' states `s1`, `s2`.
    state: [f64; 2],
    /// The resonance asked for (Hz).
    resonance: f64,
}

impl PickupCircuit {
    /// A pickup resonating at `resonance` (Hz, kept below 0.45 of `sample_rate`) with [`PICKUP_Q`].
    pub fn new(resonance: f64, sample_rate: f64) -> Self {
        let mut circuit = Self { g: 0.0, target: 0.0, slope: 0.0, left: 0, state: [0.0; 2], resonance: 0.0 };
        circuit.set(resonance, sample_rate);
        circuit
    }

    /// Move the resonance to `resonance` (Hz) over the next `samples` samples filtered, keeping
    /// the filter's state.
    pub fn tune(&mut self, resonance: f64, sample_rate: f64, samples: usize) {
        let resonance = if resonance.is_finite() { resonance.clamp(10.0, 0.45 * sample_rate) } else { 3500.0 };
        if resonance == self.resonance {
            return;
        }
        self.resonance = resonance;
        self.target = (std::f64::consts::PI * resonance / sample_rate).tan();
        self.left = samples.max(1);
        self.slope = (self.target - self.g) / self.left as f64;
    }

    /// Put the resonance at `resonance` (Hz) at once, keeping the filter's state.
    pub fn set(&mut self, resonance: f64, sample_rate: f64) {
        self.tune(resonance, sample_rate, 1);
        (self.g, self.left) = (self.target, 0);
    }

    /// Bring the circuit to rest.
    pub fn reset(&mut self) {
        self.state = [0.0; 2];
    }

    /// Filter `io` in place, `g` moving on towards the resonance asked for. A circuit at rest
    /// given silence stays at rest.
    pub fn process(&mut self, io: &mut [f64]) {
        let k = 1.0 / PICKUP_Q;
        let [mut s1, mut s2] = self.state;
        let mut step = |x: f64, g: f64, a: f64| {
            let v1 = a * (s1 + g * (x - s2));
            let v2 = s2 + g * v1;
            s1 = 2.0 * v1 - s1;
            s2 = 2.0 * v2 - s2;
            // A circuit left ringing down in silence reaches the subnormal numbers and would
            // cycle among them for ever, each step costing up to a hundred normal ones; brought
            // to rest here, sample by sample, it rests where it would however its input is cut
            // into calls.
            if s1.abs() < FLUSH_BELOW && s2.abs() < FLUSH_BELOW {
                (s1, s2) = (0.0, 0.0);
            }
            v2
        };
        let (moving, still) = io.split_at_mut(self.left.min(io.len()));
        for x in moving {
            self.left -= 1;
            self.g = if self.left == 0 { self.target } else { self.g + self.slope };
            *x = step(*x, self.g, 1.0 / (1.0 + self.g * (self.g + k)));
        }
        let (g, a) = (self.g, 1.0 / (1.0 + self.g * (self.g + k)));
        still.iter_mut().for_each(|x| *x = step(*x, g, a));
        self.state = if s1.is_finite() && s2.is_finite() { [s1, s2] } else { [0.0; 2] };
    }

    /// The magnitude (at `frequency`, Hz, at `sample_rate`, Hz) of the response asked for:
    /// `|1/(1 − Ω² + jΩ/Q)|`.
    pub fn magnitude(&self, frequency: f64, sample_rate: f64) -> f64 {
        let omega = (std::f64::consts::PI * frequency / sample_rate).tan() / self.target;
        1.0 / (1.0 - omega * omega).hypot(omega / PICKUP_Q)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A circuit ringing down in silence comes to rest rather than cycling among subnormal
    /// numbers: a pluck-sized impulse, then 2 s of silence sample by sample, at 48 and 44.1 kHz
    /// with resonances from 1 to 10 kHz; its states are never subnormal and end at 0 (without the
    /// flush they stay subnormal for 98 % of the samples from 0.1 s on).
    #[test]
    fn a_circuit_ringing_down_comes_to_rest() {
        for fs in [44_100.0, 48_000.0] {
            for resonance in [1_000.0, 3_500.0, 10_000.0] {
                let mut circuit = PickupCircuit::new(resonance, fs);
                let mut io = [0.01];
                for _ in 0..(2.0 * fs) as usize {
                    circuit.process(&mut io);
                    let subnormal = circuit.state.iter().any(|s| *s != 0.0 && !s.is_normal());
                    assert!(!subnormal, "{fs} Hz, {resonance} Hz: {:?}", circuit.state);
                    io.fill(0.0);
                }
                assert_eq!(circuit.state, [0.0; 2], "{fs} Hz, {resonance} Hz");
            }
        }
    }

    /// The pickup passes low frequencies unchanged (−0.1 dB at 200 Hz), peaks by 4.0 dB ± 0.3 at
    /// its resonance at every common rate (the prewarping), and cuts an octave and a half above
    /// it by more than 12 dB: a 2nd-order low-pass, as Lemme's loaded pickups.
    #[test]
    fn the_pickup_peaks_at_its_resonance_and_rolls_off_above() {
        for fs in [44_100.0, 48_000.0, 96_000.0] {
            let p = PickupCircuit::new(3500.0, fs);
            let db = |f: f64| 20.0 * p.magnitude(f, fs).log10();
            let peak = (1000..9000).map(|f| db(f as f64)).fold(f64::MIN, f64::max);
            println!(
                "{fs} Hz: 200 Hz {:.3} dB, 3.5 kHz {:.2} dB, peak {peak:.2} dB, 9.9 kHz {:.1} dB",
                db(200.0),
                db(3500.0),
                db(9900.0)
            );
            assert!(db(200.0).abs() < 0.1);
            assert!((peak - 4.0).abs() < 0.3, "{peak}");
            assert!((db(3500.0) - 20.0 * PICKUP_Q.log10()).abs() < 1e-9);
            assert!(db(9900.0) < -12.0);
        }
    }

    /// A resonance moved over a control block gives the same output however the block is cut
    /// into calls (zero-length ones included), to the bit, and reaches the resonance asked for
    /// at the block's end; [`PickupCircuit::set`] reaches it at once.
    #[test]
    fn a_moving_resonance_does_not_depend_on_how_the_calls_cut_the_block() {
        let fs = 48_000.0;
        let input: Vec<f64> = (0..256).map(|k| (0.37 * k as f64).sin() + 0.2 * (1.9 * k as f64).cos()).collect();
        let run = |cuts: &[usize]| {
            let mut p = PickupCircuit::new(1_000.0, fs);
            let mut io = input.clone();
            let mut at = 0;
            for block in io.chunks_mut(64) {
                p.tune(1_000.0 * 2f64.powf(1.0 + at as f64 / 64.0), fs, 64);
                let mut rest = block;
                for &cut in cuts.iter().cycle().take(64) {
                    let (now, later) = rest.split_at_mut(cut.min(rest.len()));
                    p.process(now);
                    rest = later;
                    if rest.is_empty() {
                        break;
                    }
                }
                p.process(rest);
                at += 64;
            }
            (io, p)
        };
        let (whole, p) = run(&[64]);
        for cuts in [vec![1], vec![0, 7, 0, 20], vec![63, 1], vec![5, 0, 0, 59]] {
            let (cut, q) = run(&cuts);
            assert!(whole.iter().zip(&cut).all(|(a, b)| a.to_bits() == b.to_bits()), "cuts {cuts:?}");
            assert_eq!((p.g, p.left), (q.g, q.left));
        }
        assert_eq!((p.g, p.left), (p.target, 0));
        let mut set = PickupCircuit::new(1_000.0, fs);
        set.set(8_000.0, fs);
        assert_eq!((set.g, set.left), ((std::f64::consts::PI * 8_000.0 / fs).tan(), 0));
    }

    /// Filtering a sine gives the magnitude the response says (the filter is the response).
    #[test]
    fn the_pickup_filters_as_its_response_says() {
        let fs = 48_000.0;
        let mut p = PickupCircuit::new(3500.0, fs);
        let f = 3000.0;
        let mut io: Vec<f64> = (0..48_000).map(|k| (std::f64::consts::TAU * f * k as f64 / fs).sin()).collect();
        p.process(&mut io);
        // The amplitude by projection on sine and cosine over the last half second (whole periods).
        let w = std::f64::consts::TAU * f / fs;
        let (s, c) = io[24_000..].iter().enumerate().fold((0.0, 0.0), |(s, c), (k, y)| {
            let t = (k + 24_000) as f64 * w;
            (s + y * t.sin(), c + y * t.cos())
        });
        let amplitude = 2.0 * s.hypot(c) / 24_000.0;
        assert!((amplitude / p.magnitude(f, fs) - 1.0).abs() < 1e-6, "{amplitude}");
    }
}
