//! Preparing a string for a sample rate: construction, retuning in place, and what it is made of
//! (its parameters, modes and per-mode coefficients; docs/physics.md §6.1–6.2).

use super::modes::{Coefficients, ModeCounter};
use super::params::check_rates;
use super::{Damping, Isa, LANES, MAX_MODES, ModalString, StringError, StringParams};

impl ModalString {
    /// Prepare the string at `sample_rate` (Hz): every mode strictly below Nyquist, at rest.
    pub fn new(params: StringParams, sample_rate: f64) -> Result<Self, StringError> {
        Self::band_limited(params, sample_rate, f64::INFINITY)
    }

    /// Prepare the string keeping only the modes that ring strictly below both Nyquist and
    /// `max_frequency` (Hz). With the same `max_frequency` at every sample rate (below the
    /// lowest Nyquist in use), the string has the same modes, and so the same sound, at all of them.
    pub fn band_limited(params: StringParams, sample_rate: f64, max_frequency: f64) -> Result<Self, StringError> {
        let count = Self::modes_below(params, sample_rate, max_frequency)?;
        let mut s = Self::with_capacity(count);
        s.retune(params, sample_rate, max_frequency)?;
        Ok(s)
    }

    /// How many modes [`band_limited`](Self::band_limited) would keep, or why it would fail:
    /// invalid parameters or rates, or more than [`MAX_MODES`] modes.
    pub fn modes_below(params: StringParams, sample_rate: f64, max_frequency: f64) -> Result<usize, StringError> {
        let count = Self::count_modes(params, sample_rate, max_frequency)?;
        if count > MAX_MODES {
            return Err(StringError {
                key: "length",
                reason: format!(
                    "the string has more than {MAX_MODES} modes below Nyquist; shorten it or raise the tension"
                ),
            });
        }
        Ok(count)
    }

    /// How many modes the string keeps below Nyquist and `max_frequency` (Hz), counted up to
    /// [`MAX_MODES`]` + 1` (more than a string holds), or why its parameters or rates are invalid.
    pub fn count_modes(params: StringParams, sample_rate: f64, max_frequency: f64) -> Result<usize, StringError> {
        check_rates(sample_rate, max_frequency)?;
        params.validate()?;
        Ok(ModeCounter::new(&params, sample_rate, max_frequency).count())
    }

    /// An empty string (no modes) with room for `modes` modes, so that later
    /// [`retune`](Self::retune)s never allocate.
    pub fn with_capacity(modes: usize) -> Self {
        let padded = modes.div_ceil(LANES) * LANES;
        let v = || Vec::with_capacity(padded);
        Self {
            params: StringParams {
                length: 1.0,
                tension: 1.0,
                linear_density: 1.0,
                bending_stiffness: 0.0,
                damping: Damping::LOSSLESS,
            },
            sample_rate: 1.0,
            modal_mass: 0.5,
            beta: v(),
            omega0: v(),
            sigma: v(),
            own_p: v(),
            own_q: v(),
            coef_a: v(),
            coef_b: v(),
            coef_c: v(),
            stiffness: v(),
            own_stiffness: v(),
            resistance: v(),
            u_prev: v(),
            u_now: v(),
            history: v(),
            history_ready: false,
            since_flush: 0,
            isa: Isa::detect(),
        }
    }

    /// Most modes this string can hold without allocating.
    pub fn capacity(&self) -> usize {
        self.coef_a.capacity() / LANES * LANES
    }

    /// Re-prepare the string in place for new parameters: every mode below Nyquist and
    /// `max_frequency` (Hz), up to [`capacity`](Self::capacity) (higher modes are dropped), at rest.
    /// Never allocates.
    pub fn retune(&mut self, params: StringParams, sample_rate: f64, max_frequency: f64) -> Result<(), StringError> {
        check_rates(sample_rate, max_frequency)?;
        params.validate()?;
        let dt = 1.0 / sample_rate;
        let modal_mass = 0.5 * params.linear_density * params.length;
        let limit = self.capacity();
        let all = [&mut self.beta, &mut self.omega0, &mut self.sigma, &mut self.coef_a, &mut self.coef_b];
        all.into_iter().for_each(Vec::clear);
        self.own_p.clear();
        self.own_q.clear();
        for v in [&mut self.coef_c, &mut self.stiffness, &mut self.own_stiffness, &mut self.resistance] {
            v.clear();
        }
        let mut counter = ModeCounter::new(&params, sample_rate, max_frequency);
        while self.beta.len() < limit {
            let Some(mode) = counter.next() else { break };
            let (p, q) = mode.recursion(dt);
            let c = Coefficients::new(p, q, dt, modal_mass);
            self.beta.push(mode.beta);
            self.omega0.push(mode.omega0);
            self.sigma.push(mode.sigma);
            self.own_p.push(p);
            self.own_q.push(q);
            self.coef_a.push(c.a);
            self.coef_b.push(c.b);
            self.coef_c.push(c.c);
            self.stiffness.push(c.stiffness);
            self.own_stiffness.push(c.stiffness);
            self.resistance.push(c.resistance);
        }
        let padded = self.beta.len().div_ceil(LANES) * LANES;
        let coefficients = [&mut self.coef_a, &mut self.coef_b, &mut self.coef_c, &mut self.stiffness];
        for v in coefficients.into_iter().chain([&mut self.own_stiffness, &mut self.resistance]) {
            v.resize(padded, 0.0);
        }
        for v in [&mut self.u_prev, &mut self.u_now, &mut self.history] {
            v.clear();
            v.resize(padded, 0.0);
        }
        self.params = params;
        self.sample_rate = sample_rate;
        self.modal_mass = modal_mass;
        self.since_flush = 0;
        self.history_ready = false;
        Ok(())
    }

    /// The physical parameters.
    pub fn params(&self) -> &StringParams {
        &self.params
    }

    /// Sample rate (Hz).
    pub fn sample_rate(&self) -> f64 {
        self.sample_rate
    }

    /// Number of modes M.
    pub fn modes(&self) -> usize {
        self.beta.len()
    }

    /// Length of every per-mode vector the string works with: M rounded up to whole SIMD chunks.
    pub fn padded_len(&self) -> usize {
        self.u_now.len()
    }

    /// A zero vector of [`padded_len`](Self::padded_len) entries, for mode shapes, gains and
    /// output weights, with room for [`capacity`](Self::capacity) modes so that it can follow
    /// later [`retune`](Self::retune)s without allocating (see [`fit_vector`](Self::fit_vector)).
    pub fn vector(&self) -> Vec<f64> {
        let mut v = Vec::with_capacity(self.capacity().max(self.padded_len()));
        v.resize(self.padded_len(), 0.0);
        v
    }

    /// Resize `v` (made by [`vector`](Self::vector)) to the current [`padded_len`](Self::padded_len),
    /// zeroed. Does not allocate within the string's capacity.
    pub fn fit_vector(&self, v: &mut Vec<f64>) {
        v.clear();
        v.resize(self.padded_len(), 0.0);
    }

    /// Per-mode stiffness `K̂_i` of the scheme (N/m), M entries.
    pub fn stiffness(&self) -> &[f64] {
        &self.stiffness[..self.modes()]
    }

    /// Per-mode coupling weights `w_i = √(K̂_i/(m̃ω0_i²))` ([`padded_len`](Self::padded_len) entries,
    /// zero past M), from the string's own `K̂_i`: a contact or a pickup that reaches mode `i`
    /// along `w_i h_i` in place of `h_i` meets the continuous mode's static stiffness `m̃ω0_i²`
    /// whatever the time step, where along `h_i` it meets `K̂_i`, which exceeds it by about
    /// `tan²(ωΔt/2)/(ωΔt/2)²` (23× for a 20 kHz mode at 44.1 kHz). A scheme whose vectors all
    /// carry them is the same scheme for a string whose mode `i` has mass `m̃/w_i²` (in
    /// `q_i = w_i ũ_i`): its free recursion and energy balance are as they were, and its top modes
    /// answer fast force changes more strongly (docs/physics.md §7.7). Allocates.
    pub fn coupling_weights(&self) -> Vec<f64> {
        let mut w = self.vector();
        for (i, w) in w.iter_mut().enumerate().take(self.modes()) {
            let omega0 = self.omega0[i];
            *w = (self.own_stiffness[i] / (self.modal_mass * omega0 * omega0)).sqrt();
        }
        w
    }

    /// Modal mass m̃ = ρAL/2 (kg).
    pub fn modal_mass(&self) -> f64 {
        self.modal_mass
    }

    /// Wavenumbers β_i (1/m), mode `i + 1` at index `i`.
    pub fn wavenumbers(&self) -> &[f64] {
        &self.beta
    }

    /// Decay rates σ_i (1/s).
    pub fn decay_rates(&self) -> &[f64] {
        &self.sigma
    }

    /// Undamped angular frequencies ω0_i (rad/s).
    pub fn angular_frequencies(&self) -> &[f64] {
        &self.omega0
    }

    /// Per-mode `C_i` (m/N): the modal displacement change per newton of modal force
    /// ([`padded_len`](Self::padded_len) entries, zero past M).
    pub fn input_gains(&self) -> &[f64] {
        &self.coef_c
    }
}
