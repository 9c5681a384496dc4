//! A bank of independent modes stepped together: the modes of several strings and of other
//! modal bodies (a bridge) in one set of arrays, so that one pass over the modes advances them
//! all (docs/physics.md §6.2 and §12).
//!
//! Every mode has the exact per-mode scheme of the modal string,
//! `m_i δ_tt u_i + R̂_i δ_t· u_i + K̂_i μ_t² u_i = f_i`, that is
//! `u_i^{n+1} = u_i^{n−1} − z̃_i + C_i f_i` with `z̃ = B∘u^{n−1} − A∘u^n`, with its own modal mass
//! `m_i`. The bank does not know what its modes belong to: the owner keeps the ranges
//! ([`push_string`](ModalBank::push_string) returns one) and makes the contact, coupling and
//! output vectors over the whole bank.

use std::ops::Range;

use super::modes::{Coefficients, MIN_HEADROOM, Mode};
use super::step::Stepping;
use super::{Isa, LANES, ModalString, Tail, kernel};

/// Modes of several bodies, stepped together.
#[derive(Debug, Clone)]
pub struct ModalBank {
    /// `A_i = 2P_i`, `B_i = 1 + Q_i`, `C_i` (m/N) of the scheme, with any extra decay.
    coef_a: Vec<f64>,
    coef_b: Vec<f64>,
    coef_c: Vec<f64>,
    /// `K̂_i` (N/m) and `R̂_i` (kg/s), with any extra decay.
    stiffness: Vec<f64>,
    resistance: Vec<f64>,
    /// The modes' own `P_i`, `Q_i` and `K̂_i`, before any extra decay.
    own_p: Vec<f64>,
    own_q: Vec<f64>,
    own_stiffness: Vec<f64>,
    /// Modal masses `m_i` (kg).
    mass: Vec<f64>,
    /// `u^{n−1}`, `u^n` (m) and `z̃` of the current step.
    u_prev: Vec<f64>,
    u_now: Vec<f64>,
    history: Vec<f64>,
    history_ready: bool,
    modes: usize,
    since_flush: u32,
    sample_rate: f64,
    isa: Isa,
}

/// The next step's projections of a split bank's head and tail vectors
/// ([`ModalBank::advance_split`]).
pub type SplitProjections<const J: usize, const JT: usize> = ([f64; J], [f64; JT]);

impl ModalBank {
    /// An empty bank at `sample_rate` (Hz) with room for `modes` modes.
    pub fn with_capacity(modes: usize, sample_rate: f64) -> Self {
        let v = || Vec::with_capacity(modes.div_ceil(LANES) * LANES);
        Self {
            coef_a: v(),
            coef_b: v(),
            coef_c: v(),
            stiffness: v(),
            resistance: v(),
            own_p: v(),
            own_q: v(),
            own_stiffness: v(),
            mass: v(),
            u_prev: v(),
            u_now: v(),
            history: v(),
            history_ready: false,
            modes: 0,
            since_flush: 0,
            sample_rate,
            isa: Isa::detect(),
        }
    }

    /// Remove every mode. Never allocates.
    pub fn clear(&mut self) {
        for v in self.arrays_mut() {
            v.clear();
        }
        self.modes = 0;
        self.history_ready = false;
    }

    fn arrays_mut(&mut self) -> [&mut Vec<f64>; 12] {
        [
            &mut self.coef_a,
            &mut self.coef_b,
            &mut self.coef_c,
            &mut self.stiffness,
            &mut self.resistance,
            &mut self.own_p,
            &mut self.own_q,
            &mut self.own_stiffness,
            &mut self.mass,
            &mut self.u_prev,
            &mut self.u_now,
            &mut self.history,
        ]
    }

    /// Most modes the bank holds without allocating.
    pub fn capacity(&self) -> usize {
        self.coef_a.capacity()
    }

    /// Append one mode from its recursion `(P, Q)` and modal mass (kg), at rest; modes beyond
    /// the capacity are dropped (returns whether it was added).
    fn push(&mut self, p: f64, q: f64, mass: f64) -> bool {
        !self.append(&[p], &[q], mass).is_empty()
    }

    /// Append the modes of recursions `(own_p[k], own_q[k])`, all of modal mass `mass` (kg), at
    /// rest, as many as the capacity holds. Returns their indices. Each array grows once, not
    /// once a mode.
    fn append(&mut self, own_p: &[f64], own_q: &[f64], mass: f64) -> Range<usize> {
        self.unpad();
        let m = self.modes;
        let count = own_p.len().min(own_q.len()).min(self.capacity() - m);
        for v in self.arrays_mut() {
            v.resize(m + count, 0.0);
        }
        self.set_modes(m, &own_p[..count], &own_q[..count], mass);
        self.modes += count;
        m..self.modes
    }

    /// Make entries `at..at + own_p.len()` of every array the modes of recursions
    /// `(own_p[k], own_q[k])` (as many as `own_q`) and modal mass `mass` (kg), at rest: one pass
    /// over equal slices.
    fn set_modes(&mut self, at: usize, own_p: &[f64], own_q: &[f64], mass: f64) {
        let dt = 1.0 / self.sample_rate;
        let end = at + own_p.len();
        let (a, b, c) = (&mut self.coef_a[at..end], &mut self.coef_b[at..end], &mut self.coef_c[at..end]);
        let (k_hat, r_hat) = (&mut self.stiffness[at..end], &mut self.resistance[at..end]);
        let (own_k, masses) = (&mut self.own_stiffness[at..end], &mut self.mass[at..end]);
        for (k, (&p, &q)) in own_p.iter().zip(&own_q[..own_p.len()]).enumerate() {
            let coefficients = Coefficients::new(p, q, dt, mass);
            (a[k], b[k], c[k]) = (coefficients.a, coefficients.b, coefficients.c);
            (k_hat[k], r_hat[k], own_k[k]) = (coefficients.stiffness, coefficients.resistance, coefficients.stiffness);
            masses[k] = mass;
        }
        self.own_p[at..end].copy_from_slice(own_p);
        self.own_q[at..end].copy_from_slice(&own_q[..own_p.len()]);
        for v in [&mut self.u_prev, &mut self.u_now, &mut self.history] {
            v[at..end].fill(0.0);
        }
    }

    /// Drop the padding so that modes can be appended.
    fn unpad(&mut self) {
        let m = self.modes;
        for v in self.arrays_mut() {
            v.truncate(m);
        }
    }

    /// Pad every array with inert zero modes to a whole number of chunks: call after the last
    /// push, before stepping. Never allocates within the capacity.
    pub fn finish(&mut self) {
        let padded = self.modes.div_ceil(LANES) * LANES;
        for v in self.arrays_mut() {
            v.resize(padded, 0.0);
        }
        self.history_ready = false;
        self.since_flush = 0;
    }

    /// Append the modes of `string` (prepared at the bank's sample rate), at rest. Returns their
    /// indices in the bank (fewer than the string's if the capacity runs out).
    pub fn push_string(&mut self, string: &ModalString) -> Range<usize> {
        self.push_modes(string, 0..string.modes())
    }

    /// Append the modes `modes` (indices into the string's, mode `i + 1` at `i`) of `string`, at
    /// rest. Returns their indices in the bank (fewer if the capacity runs out).
    pub fn push_modes(&mut self, string: &ModalString, modes: Range<usize>) -> Range<usize> {
        let end = modes.end.min(string.modes());
        let modes = modes.start.min(end)..end;
        self.append(&string.own_p[modes.clone()], &string.own_q[modes], string.modal_mass)
    }

    /// Insert the modes `modes` of `string` (as [`push_modes`](Self::push_modes)), at rest, before
    /// the bank's mode `at`: the modes from `at` on move up by as many, with their coefficients
    /// (any extra decay too) and their state. Returns the new modes' indices (fewer if the
    /// capacity runs out). Call [`finish`](Self::finish) before stepping. Never allocates.
    pub fn insert_modes(&mut self, at: usize, string: &ModalString, modes: Range<usize>) -> Range<usize> {
        self.unpad();
        let at = at.min(self.modes);
        let wanted = modes.end.min(string.modes()).saturating_sub(modes.start);
        let count = wanted.min(self.capacity() - self.modes);
        let m = self.modes;
        for v in self.arrays_mut() {
            v.resize(m + count, 0.0);
            v.copy_within(at..m, at + count);
        }
        let first = modes.start.min(string.modes());
        let new = first..first + count;
        self.set_modes(at, &string.own_p[new.clone()], &string.own_q[new], string.modal_mass);
        self.modes += count;
        self.history_ready = false;
        at..at + count
    }

    /// Append a damped oscillator of undamped angular frequency `omega0` (rad/s), decay rate
    /// `sigma` (1/s) and modal mass `mass` (kg), at rest. Returns its index; none if the bank is
    /// full, or if the oscillator rings at or above Nyquist (it would alias) or so near it that
    /// `1 + 2P + Q` falls below 10⁻⁶ (its stiffness `K̂` would be infinite), as a string's modes
    /// there are left out.
    pub fn push_oscillator(&mut self, omega0: f64, sigma: f64, mass: f64) -> Option<usize> {
        let dt = 1.0 / self.sample_rate;
        let mode = Mode::oscillator(omega0, sigma);
        let (p, q) = mode.recursion(dt);
        if !(mode.omega * dt < std::f64::consts::PI && 1.0 + 2.0 * p + q >= MIN_HEADROOM) {
            return None;
        }
        self.push(p, q, mass).then_some(self.modes - 1)
    }

    /// Number of modes.
    pub fn modes(&self) -> usize {
        self.modes
    }

    /// Length of the per-mode arrays (a whole number of chunks).
    pub fn padded_len(&self) -> usize {
        self.u_now.len()
    }

    /// Sample rate (Hz).
    pub fn sample_rate(&self) -> f64 {
        self.sample_rate
    }

    /// Resize `v` to [`padded_len`](Self::padded_len), zeroed.
    pub fn fit_vector(&self, v: &mut Vec<f64>) {
        v.clear();
        v.resize(self.padded_len(), 0.0);
    }

    /// Per-mode `C_i` (m/N), padded.
    pub fn input_gains(&self) -> &[f64] {
        &self.coef_c
    }

    /// Per-mode `K̂_i` (N/m) with any extra decay, [`modes`](Self::modes) entries.
    pub fn stiffness(&self) -> &[f64] {
        &self.stiffness[..self.modes]
    }

    /// Per-mode modal masses `m_i` (kg), [`modes`](Self::modes) entries.
    pub fn masses(&self) -> &[f64] {
        &self.mass[..self.modes]
    }

    /// `xᵀy` over the padded arrays.
    pub fn project(&self, x: &[f64], y: &[f64]) -> f64 {
        kernel::dot(self.isa, x, y)
    }

    /// `(vᵀu^{n−1}, vᵀu^n)`.
    pub fn project_state(&self, v: &[f64]) -> (f64, f64) {
        (kernel::dot(self.isa, &self.u_prev, v), kernel::dot(self.isa, &self.u_now, v))
    }

    /// `v_kᵀu^n` for each of `vectors`, in one pass over the modes.
    pub fn project_now_each<const K: usize>(&self, vectors: [&[f64]; K]) -> [f64; K] {
        kernel::projections(self.isa, &self.u_now, vectors)
    }

    /// `u^{n−1}` and `u^n` (m) of the modes in `range`.
    pub fn state(&self, range: Range<usize>) -> (&[f64], &[f64]) {
        (&self.u_prev[range.clone()], &self.u_now[range])
    }

    /// Set the whole state (slices of [`modes`](Self::modes) entries), the padding beyond them
    /// zeroed (see [`ModalString::set_state`](super::ModalString::set_state)).
    pub fn set_state(&mut self, previous: &[f64], now: &[f64]) {
        let m = self.modes;
        self.u_prev[..m].copy_from_slice(previous);
        self.u_now[..m].copy_from_slice(now);
        self.u_prev[m..].fill(0.0);
        self.u_now[m..].fill(0.0);
        self.history_ready = false;
    }

    /// Every mode at `value` (m) at both steps (tests of what follows a corrupt state), the
    /// padding zeroed.
    pub fn fill(&mut self, value: f64) {
        let m = self.modes;
        self.u_prev[..m].fill(value);
        self.u_now[..m].fill(value);
        self.u_prev[m..].fill(0.0);
        self.u_now[m..].fill(0.0);
        self.history_ready = false;
    }

    /// Hold every mode still under the static force `force(i)` (N) on it:
    /// `u_i^{n−1} = u_i^n = C_i force(i)/(B_i − A_i)`, which is `force(i)/K̂_i` (with any extra
    /// decay), the scheme's own equilibrium; 0 for a mode whose `K̂` is 0 (a free mass). Never
    /// allocates.
    pub fn rest_under(&mut self, force: impl Fn(usize) -> f64) {
        let coefficients = (&self.coef_a[..], &self.coef_b[..], &self.coef_c[..]);
        super::step::hold_still(coefficients, self.modes, (&mut self.u_prev, &mut self.u_now), force);
        self.history_ready = false;
    }

    /// Every mode at rest.
    pub fn reset(&mut self) {
        self.u_prev.fill(0.0);
        self.u_now.fill(0.0);
        self.history_ready = false;
        self.since_flush = 0;
    }

    /// Add the decay rates `extra` (1/s, one per mode of `range`; missing entries count as 0) to
    /// the own rates of the modes in `range`, as [`ModalString::set_extra_decay`] does: each
    /// mode decays faster and rings at its own frequency; the state is untouched. The part of
    /// `range` beyond the bank's modes is left out: the padding holds no mode (a massless entry
    /// given coefficients would carry an infinite force gain).
    pub fn set_extra_decay(&mut self, range: Range<usize>, extra: &[f64]) {
        let dt = 1.0 / self.sample_rate;
        for (k, i) in (range.start..range.end.min(self.modes)).enumerate() {
            let extra = extra.get(k).copied().unwrap_or(0.0);
            let c = Coefficients::with_extra_decay(self.own_p[i], self.own_q[i], extra, dt, self.mass[i]);
            self.coef_a[i] = c.a;
            self.coef_b[i] = c.b;
            self.coef_c[i] = c.c;
            self.stiffness[i] = c.stiffness;
            self.resistance[i] = c.resistance;
        }
        self.history_ready = false;
    }

    /// First pass of a step: `z̃` and its projections on `vectors` (see
    /// [`ModalString::history`]).
    #[inline]
    pub fn history<const K: usize>(&mut self, vectors: [&[f64]; K]) -> [f64; K] {
        if self.history_ready {
            return kernel::projections(self.isa, &self.history, vectors);
        }
        self.history_ready = true;
        kernel::history(self.isa, &self.coef_a, &self.coef_b, &self.u_prev, &self.u_now, &mut self.history, vectors)
    }

    /// Second pass: apply the forces and step on, returning `outputᵀu^{n+1}` and the next step's
    /// projections of `z̃` on `next` (`None` after a flush of tiny amplitudes); see
    /// [`ModalString::advance_projecting`].
    #[inline]
    pub fn advance_projecting<const K: usize, const J: usize>(
        &mut self,
        forces: [(&[f64], f64); K],
        output: &[f64],
        next: [&[f64]; J],
    ) -> (f64, Option<[f64; J]>) {
        let whole = Tail { start: self.u_prev.len(), forces: [], next: [] };
        let (projection, next) = self.advance_split(forces, output, next, whole);
        (projection, next.map(|(next, [])| next))
    }

    /// [`advance_projecting`](Self::advance_projecting) for a bank whose modes from `tail.start`
    /// on (a bridge after its strings) feel forces and are projected on vectors of their own, all
    /// zero before `tail.start`, while `forces`, `output` and `next` are zero from there on. The
    /// products of those zeros are skipped: the same bits, in less time. Returns the output, and
    /// the head's and the tail's projections (`None` after a flush, as there).
    #[inline]
    pub fn advance_split<const K: usize, const J: usize, const KT: usize, const JT: usize>(
        &mut self,
        forces: [(&[f64], f64); K],
        output: &[f64],
        next: [&[f64]; J],
        tail: Tail<'_, KT, JT>,
    ) -> (f64, Option<SplitProjections<J, JT>>) {
        debug_assert!(self.history_ready, "advance follows history");
        let (a, b) = (&self.coef_a, &self.coef_b);
        let (u_prev, u_now, history) = (&mut self.u_prev, &self.u_now, &mut self.history);
        let (projection, head, tail) =
            kernel::advance_split(self.isa, a, b, u_prev, u_now, history, forces, output, next, tail);
        self.finish_step();
        (projection, self.history_ready.then_some((head, tail)))
    }

    /// `outputs.len()` steps with no force, by the homogeneous recursion (see
    /// [`ModalString::free_steps`]), writing each step's `outputᵀu^{n+1}`.
    pub fn free_steps(&mut self, output: &[f64], outputs: &mut [f64]) {
        let mut stepping =
            Stepping { u_prev: &mut self.u_prev, u_now: &mut self.u_now, since_flush: &mut self.since_flush };
        stepping.free_steps(self.isa, &self.coef_a, &self.coef_b, output, outputs);
        self.history_ready = false;
    }

    /// [`advance_projecting`](Self::advance_projecting) without the projections, returning the
    /// step's energy terms too: `(outputᵀu^{n+1}, stored H^{n+1/2} (J), dissipated (J))`.
    pub fn advance_monitored<const K: usize>(&mut self, forces: [(&[f64], f64); K], output: &[f64]) -> (f64, f64, f64) {
        debug_assert!(self.history_ready, "advance follows history");
        let fs = self.sample_rate;
        let (mut stored, mut dissipated) = (0.0, 0.0);
        for i in 0..self.modes {
            let mut next = self.u_prev[i] - self.history[i];
            for (g, f) in &forces {
                next += g[i] * f;
            }
            let (v, mean, centred) =
                ((next - self.u_now[i]) * fs, 0.5 * (next + self.u_now[i]), 0.5 * (next - self.u_prev[i]) * fs);
            stored += 0.5 * self.mass[i] * v * v + 0.5 * self.stiffness[i] * mean * mean;
            dissipated += self.resistance[i] * centred * centred / fs;
            self.u_prev[i] = next;
        }
        let out = kernel::dot(self.isa, output, &self.u_prev);
        self.finish_step();
        self.history_ready = false;
        (out, stored, dissipated)
    }

    /// The energy `H^{n−1/2}` of the modes in `range` weighed with their own stiffnesses (J):
    /// as [`ModalString::own_energy`].
    pub fn own_energy(&self, range: Range<usize>) -> f64 {
        let fs = self.sample_rate;
        range
            .map(|i| {
                let (v, mean) = ((self.u_now[i] - self.u_prev[i]) * fs, 0.5 * (self.u_now[i] + self.u_prev[i]));
                0.5 * self.mass[i] * v * v + 0.5 * self.own_stiffness[i] * mean * mean
            })
            .sum()
    }

    /// The squared amplitude (m²) of the motion at the fraction `x` of a string's length of the
    /// string modes in `range`, the string's modes `first, first + 1, …` (shapes `sin(kπx)`):
    /// `Σ sin²(kπx)·a_k²`, with `a_k² = ū_k² + (m_k/K̂_k)·v_k²` the squared amplitude of mode
    /// `k`'s swing (its own stiffness; `ū`, `v` the state's mean and velocity between `n − 1` and
    /// `n`). The square root is the amplitude of the sinusoid with the motion's mean square.
    pub fn swing_at(&self, range: Range<usize>, first: usize, x: f64) -> f64 {
        let fs = self.sample_rate;
        let theta = std::f64::consts::PI * x;
        // sin(kθ) by the recurrence sin((k+1)θ) = 2cos θ·sin(kθ) − sin((k−1)θ).
        let (two_cos, mut before, mut shape) =
            (2.0 * theta.cos(), ((first as f64 - 1.0) * theta).sin(), (first as f64 * theta).sin());
        let mut sum = 0.0;
        for i in range {
            let (v, mean) = ((self.u_now[i] - self.u_prev[i]) * fs, 0.5 * (self.u_now[i] + self.u_prev[i]));
            let stiffness = self.own_stiffness[i];
            let swing = if stiffness > 0.0 { mean * mean + self.mass[i] / stiffness * v * v } else { mean * mean };
            sum += shape * shape * swing;
            (before, shape) = (shape, two_cos * shape - before);
        }
        sum
    }

    /// The energy `H^{n−1/2}` weighed with the modes' own stiffnesses (J), as
    /// [`own_energy`](Self::own_energy), of the modes before `at` and of those from `at` on: one
    /// vector pass over the whole chunks of each, the modes of the chunk they share one by one.
    /// (The sums run in another order than `own_energy`'s, so the two agree to rounding.)
    pub fn own_energy_split(&self, at: usize) -> (f64, f64) {
        let fs = self.sample_rate;
        let at = at.min(self.modes);
        let (whole_head, whole_tail) = (at / LANES, at.div_ceil(LANES));
        let (up, un, m, k) = (&self.u_prev, &self.u_now, &self.mass, &self.own_stiffness);
        let weigh = |(steps, sums): (f64, f64)| 0.5 * fs * fs * steps + 0.125 * sums;
        let chunks = up.len() / LANES;
        let head = weigh(kernel::weighted_energy_sums(self.isa, up, un, m, k, 0..whole_head));
        let tail = weigh(kernel::weighted_energy_sums(self.isa, up, un, m, k, whole_tail..chunks));
        let shared = whole_head * LANES..(whole_tail * LANES).min(self.modes);
        (head + self.own_energy(shared.start..at), tail + self.own_energy(at..shared.end))
    }

    /// The numerical energy `H^{n−1/2}` of every mode, with the current stiffnesses (J).
    pub fn energy(&self) -> f64 {
        let fs = self.sample_rate;
        (0..self.modes)
            .map(|i| {
                let (v, mean) = ((self.u_now[i] - self.u_prev[i]) * fs, 0.5 * (self.u_now[i] + self.u_prev[i]));
                0.5 * self.mass[i] * v * v + 0.5 * self.stiffness[i] * mean * mean
            })
            .sum()
    }

    #[inline]
    fn finish_step(&mut self) {
        let mut stepping =
            Stepping { u_prev: &mut self.u_prev, u_now: &mut self.u_now, since_flush: &mut self.since_flush };
        if stepping.finish() {
            self.history_ready = false;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::string::{Damping, StringParams};

    /// Every array of `bank` over its first `n` modes, by name.
    fn arrays(bank: &mut ModalBank, n: usize) -> Vec<Vec<f64>> {
        bank.arrays_mut().map(|v| v[..n].to_vec()).to_vec()
    }

    /// A string's modes added to a bank, all at once, one at a time, or some inserted between
    /// others, carry the string's own coefficients (made by the string's setup) bit for bit, its
    /// modal mass, and rest; ranges past the string's end or reversed add nothing, and a bank
    /// keeps what its capacity holds.
    #[test]
    fn modes_added_to_a_bank_are_the_strings_modes() {
        let fs = 48_000.0;
        // A C3-like wire: 0.95 m at 670 N, 130.8 Hz.
        let (length, tension) = (0.95, 670.0);
        let linear_density = tension / (2.0 * length * 130.8f64).powi(2);
        let params = StringParams {
            length,
            tension,
            linear_density,
            bending_stiffness: 1e-4 * tension * length * length,
            damping: Damping::PerMode { b1: 0.5, b3: 1e-9 },
        };
        let string = ModalString::band_limited(params, fs, 20_000.0).unwrap();
        let n = string.modes();
        let reference: Vec<Vec<f64>> = {
            let s = &string;
            let mass = vec![s.modal_mass; n];
            let zeros = vec![0.0; n];
            [&s.coef_a, &s.coef_b, &s.coef_c, &s.stiffness, &s.resistance, &s.own_p, &s.own_q, &s.own_stiffness]
                .map(|v| v[..n].to_vec())
                .into_iter()
                .chain([mass, zeros.clone(), zeros.clone(), zeros])
                .collect()
        };
        let mut whole = ModalBank::with_capacity(n, fs);
        assert_eq!(whole.push_modes(&string, 0..n), 0..n);
        let mut one_by_one = ModalBank::with_capacity(n, fs);
        for i in 0..n {
            assert_eq!(one_by_one.push_modes(&string, i..i + 1), i..i + 1);
        }
        let mut inserted = ModalBank::with_capacity(n, fs);
        inserted.push_modes(&string, 0..10);
        inserted.push_modes(&string, 20..n);
        assert_eq!(inserted.insert_modes(10, &string, 10..20), 10..20);
        for (name, bank) in [("whole", &mut whole), ("one by one", &mut one_by_one), ("inserted", &mut inserted)] {
            let reversed = Range { start: 5, end: 3 };
            assert_eq!(bank.push_modes(&string, reversed), n..n, "{name}: reversed");
            assert_eq!(bank.push_modes(&string, n + 5..n + 9), n..n, "{name}: past the end");
            assert_eq!(bank.insert_modes(3, &string, n + 5..n + 9), 3..3, "{name}: past the end");
            bank.finish();
            assert_eq!(bank.modes(), n);
            let got = arrays(bank, n);
            for (k, (g, r)) in got.iter().zip(&reference).enumerate() {
                let same = g.iter().zip(r).all(|(a, b)| a.to_bits() == b.to_bits());
                assert!(same, "{name}: array {k}");
            }
        }
        let mut small = ModalBank::with_capacity(n / 2, fs);
        let kept = small.capacity();
        assert!(kept < n);
        assert_eq!(small.push_modes(&string, 0..n), 0..kept);
        assert_eq!(small.push_modes(&string, 0..n), kept..kept);
        small.finish();
        let got = arrays(&mut small, kept);
        assert!(got.iter().zip(&reference).all(|(g, r)| g[..] == r[..kept]));
    }

    /// Extra decay asked for over a range running past the bank's modes into its padding
    /// changes the modes it covers and nothing beyond them: the bank's state and energy stay
    /// finite through a thousand steps, and its arrays past the modes stay zero.
    #[test]
    fn extra_decay_past_the_modes_leaves_the_padding_alone() {
        let fs = 48_000.0;
        let mut bank = ModalBank::with_capacity(3, fs);
        for f in [100.0, 200.0, 300.0] {
            bank.push_oscillator(std::f64::consts::TAU * f, 1.0, 1.0).expect("room");
        }
        bank.finish();
        let (n, padded) = (bank.modes(), bank.coef_a.len());
        assert!(padded > n, "the bank is padded to its lanes: {padded} for {n} modes");
        let before = arrays(&mut bank, n);
        bank.set_extra_decay(0..padded, &vec![5.0; padded]);
        let after = arrays(&mut bank, n);
        assert!(before.iter().zip(&after).any(|(b, a)| b != a), "the modes decay faster");
        assert!(bank.arrays_mut().iter().all(|v| v[n..].iter().all(|&x| x == 0.0)), "the padding holds no mode");
        bank.set_state(&[1e-3; 3], &[1e-3; 3]);
        let mut out = [0.0; 1_000];
        bank.free_steps(&vec![1.0; padded], &mut out);
        assert!(out.iter().all(|x| x.is_finite()), "the output stays finite");
        assert!(bank.energy().is_finite() && bank.energy() > 0.0, "energy {}", bank.energy());
    }

    /// An oscillator at Nyquist or above, or with no headroom left below it, is refused, and the
    /// bank's energy stays finite; one just below, a free mass and a critically damped one are
    /// taken.
    #[test]
    fn an_oscillator_at_nyquist_is_refused() {
        let fs = 48_000.0;
        let nyquist = std::f64::consts::PI * fs;
        let mut bank = ModalBank::with_capacity(8, fs);
        assert_eq!(bank.push_oscillator(nyquist, 0.0, 1.0), None, "at Nyquist");
        assert_eq!(bank.push_oscillator(1.5 * nyquist, 0.0, 1.0), None, "above it");
        assert_eq!(bank.push_oscillator(nyquist * (1.0 - 1e-5), 0.0, 1.0), None, "without headroom");
        assert_eq!(bank.push_oscillator(f64::NAN, 0.0, 1.0), None, "not a number");
        assert_eq!(bank.push_oscillator(0.9 * nyquist, 0.0, 1.0), Some(0), "just below");
        assert_eq!(bank.push_oscillator(0.0, 0.0, 1.0), Some(1), "a free mass");
        assert_eq!(bank.push_oscillator(1e3, 1e3, 1.0), Some(2), "critically damped");
        bank.finish();
        assert!(bank.energy().is_finite() && bank.energy() == 0.0, "energy {}", bank.energy());
    }

    /// The books close on the recursion as stored: a 10 Hz mode at 192 kHz (`ωΔt` = 3.3e-4, where
    /// `1 − 2P + Q` is a difference of near equals) started on its exact free motion keeps its
    /// stored energy plus what it dissipated equal to its start over 20,000 steps (a period) to
    /// the walk of its state's rounding: each step's rounding of `ũ` moves the velocity, and so
    /// the energy, by about `2ε/(ωΔt)` = 1.3e-12, which over `N` steps walks to `√N` times that;
    /// the bound is twice that walk, 3.8e-10 (measured 0.9e-10). With `K̂` and `R̂` formed from
    /// the exact `P` and `Q` instead of the rounded `A` and `B`, the stored energy swings by about
    /// `ε/(ωΔt)²` = 2e-9 over the period (measured 9.2e-10).
    #[test]
    fn a_slow_mode_at_a_high_rate_keeps_its_books_to_rounding() {
        let fs = 192_000.0;
        let (omega0, sigma) = (2.0 * std::f64::consts::PI * 10.0, 1.0);
        let mut bank = ModalBank::with_capacity(1, fs);
        bank.push_oscillator(omega0, sigma, 1.0).expect("room for one");
        bank.finish();
        let omega = (omega0 * omega0 - sigma * sigma).sqrt();
        let exact = |n: f64| 1e-3 * (-sigma * n / fs).exp() * (omega * n / fs + 0.3).cos();
        bank.set_state(&[exact(0.0)], &[exact(1.0)]);
        let start = bank.energy();
        let output = vec![0.0; bank.padded_len()];
        let (mut dissipated, mut worst) = (0.0, 0.0f64);
        let steps = 20_000;
        let walk = (steps as f64).sqrt() * 2.0 * f64::EPSILON / (omega / fs);
        for _ in 0..steps {
            bank.history::<0>([]);
            let (_, stored, lost) = bank.advance_monitored::<0>([], &output);
            dissipated += lost;
            worst = worst.max(((stored + dissipated) / start - 1.0).abs());
        }
        println!("largest relative imbalance {worst:.2e}");
        assert!(dissipated > 0.01 * start, "the mode decays");
        assert!(worst <= 2.0 * walk, "the books open by {worst:.2e} of the start, against {walk:.2e}");
    }

    /// An oscillator with neither spring nor loss (`ω0 = σ = 0`, a free mass) gets finite
    /// coefficients: `P = 1`, `Q = 1`, so `K̂ = 0` and `R̂ = 0`, and it drifts at its speed.
    #[test]
    fn a_free_mass_has_finite_coefficients() {
        let mut bank = ModalBank::with_capacity(1, 48_000.0);
        bank.push_oscillator(0.0, 0.0, 1.0).expect("room for one");
        bank.finish();
        assert_eq!((bank.coef_a[0], bank.coef_b[0], bank.stiffness[0], bank.resistance[0]), (2.0, 2.0, 0.0, 0.0));
        bank.set_state(&[0.0], &[1e-6]);
        bank.history::<0>([]);
        let output = vec![0.0; bank.padded_len()];
        bank.advance_monitored::<0>([], &output);
        assert_eq!(bank.state(0..1).1[0], 2e-6, "it moves on at its speed");
    }

    /// The split weighing is the mode-by-mode weighing of each part, to rounding (1e-13 of the
    /// whole; the sums run in another order), wherever the split falls: at either end, on a
    /// chunk's edge or inside one; and it gives the same bits on every instruction set.
    #[test]
    fn the_split_weighing_is_the_weighing_of_each_part() {
        let fs = 48_000.0;
        let modes = 37;
        let mut bank = ModalBank::with_capacity(modes, fs);
        for i in 0..modes {
            let omega0 = 2.0 * std::f64::consts::PI * 55.0 * (i + 1) as f64;
            bank.push_oscillator(omega0, 1.0 + i as f64, 1e-3 * (1.0 + (i % 5) as f64));
        }
        bank.finish();
        let wave = |phase: f64| -> Vec<f64> { (0..modes).map(|i| 1e-4 * (phase + 0.7 * i as f64).sin()).collect() };
        bank.set_state(&wave(0.0), &wave(0.1));
        let whole = bank.own_energy(0..modes);
        assert!(whole > 0.0);
        for at in [0, 5, 8, 16, 21, modes] {
            let (head, tail) = bank.own_energy_split(at);
            let (want_head, want_tail) = (bank.own_energy(0..at), bank.own_energy(at..modes));
            assert!((head - want_head).abs() <= 1e-13 * whole, "split at {at}: head {head} against {want_head}");
            assert!((tail - want_tail).abs() <= 1e-13 * whole, "split at {at}: tail {tail} against {want_tail}");
            for isa in Isa::available() {
                let mut other = bank.clone();
                other.isa = isa;
                let (h, t) = other.own_energy_split(at);
                assert_eq!((h.to_bits(), t.to_bits()), (head.to_bits(), tail.to_bits()), "{isa:?}, split at {at}");
            }
        }
    }
}
