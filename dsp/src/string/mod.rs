//! Modal stiff string with damping (seed §5.1–5.2, physics §6).
//!
//! # Model (seed eq. 27, with the seed's `ρA ∂x²u` misprint read as `ρA ∂t²u`)
//!
//! ```text
//! ρA u_tt = T u_xx − EI u_xxxx + 2ρA(η2 ∂x² − η0) u_t + Σ forces
//! ```
//!
//! simply supported at `x = 0` and `x = L`. Modes `v_i(x) = sin(β_i x)`, `β_i = iπ/L`, modal
//! mass `m̃ = ρAL/2`, `ω0_i² = (Tβ_i² + EIβ_i⁴)/ρA`, decay rate `σ_i` (1/s) from a [`Damping`]
//! law, damped frequency `ω_i = √(ω0_i² − σ_i²)`. Lossless partials: `f_i = i f0 √(1 + B i²)`
//! with `f0 = √(T/ρA)/(2L)` and `B = π² EI/(T L²)`.
//!
//! # Exact-per-mode scheme (seed eq. 37–40, physics §6.2)
//!
//! `m̃ δ_tt ũ + R̂ δ_t· ũ + K̂ μ_t² ũ = Σ F h` with `K̂`, `R̂` chosen so the homogeneous recursion
//! of each mode is `ũ^{n+1} = 2P ũ^n − Q ũ^{n−1}`, `P = e^{−σΔt} cos(ωΔt)` (overdamped:
//! `cosh(γΔt)`, `γ = √(σ² − ω0²)`), `Q = e^{−2σΔt}`: every mode rings at exactly `ω_i` and
//! decays at exactly `σ_i`, at any sample rate. Per mode:
//!
//! ```text
//! K̂ = (4m̃/Δt²)(1 − 2P + Q)/(1 + 2P + Q),   R̂ = (4m̃/Δt)(1 − Q)/(1 + 2P + Q)
//! ũ^{n+1} = ũ^{n−1} − z̃ + C·h·F,   z̃ = B ũ^{n−1} − A ũ^n
//! A = 2P,   B = 1 + Q,   C = Δt²(1 + 2P + Q)/(4m̃)
//! ```
//!
//! `K̂` diverges for an undamped mode at Nyquist, so the string keeps exactly the modes with
//! `ω_i < π·fs` (strict); `ω_i` increases with `i`, so counting stops at the first failure
//! (an overdamped mode, which does not ring, is kept while `ω0_i < π·fs`).
//!
//! # Energy (physics §6.3)
//!
//! ```text
//! H^{n+1/2} = ½ m̃ ‖(ũ^{n+1} − ũ^n)/Δt‖² + ½ Σ K̂_i ((ũ_i^{n+1} + ũ_i^n)/2)²
//! H^{n+1/2} − H^{n−1/2} = −Δt (δ_t·ũ)ᵀ R̂ (δ_t·ũ) + (work of the forces)
//! ```
//!
//! # Layout
//!
//! Structure of arrays: every per-mode coefficient is a contiguous `Vec<f64>`, padded with inert
//! zero modes to a whole number of SIMD chunks ([`ModalString::padded_len`]; vectors handed to
//! the string come from [`ModalString::vector`]), and a step is two branch-free passes over the
//! modes (see `kernel`). [`ModalString::history`] projects `z̃` on the contact vectors;
//! [`ModalString::advance`] applies the forces, moves the state on, projects the new state on the
//! output vector and computes the next step's `z̃`, all in one pass. So the first pass of a step
//! that follows an `advance` only reads `z̃`; after anything else it computes `z̃` as well.

mod kernel;
mod simd;

use serde::Serialize;

pub use kernel::{FREE_STEP_FLOPS, GramVector, peak_probe};
pub use simd::{Isa, LANES};

/// Most modes a string may have (bounds memory and cost for extreme parameters).
pub const MAX_MODES: usize = 4096;

/// Modal amplitudes below this (m) are set to zero (physics §10.11): decaying modes would
/// otherwise become subnormal numbers, which are slower by orders of magnitude.
pub const FLUSH_BELOW: f64 = 1e-30;

/// Steps between flushes of tiny amplitudes (counted from the start, so independent of how a
/// render is split into calls).
pub const FLUSH_INTERVAL: u32 = 64;

/// How the modal decay rates `σ_i` (1/s) are set.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "law", rename_all = "kebab-case")]
pub enum Damping {
    /// Seed eq. 27: `σ_i = η0 + η2 β_i²`, with `η0` (1/s) and `η2` (m²/s).
    Viscous {
        /// Frequency-independent loss η0 (1/s).
        eta0: f64,
        /// Frequency-dependent loss η2 (m²/s).
        eta2: f64,
    },
    /// Chaigne–Askenfelt style per-mode law: `σ_i = b1 + b3 ω0_i²`, with `b1` (1/s) and `b3` (s).
    PerMode {
        /// Frequency-independent loss b1 (1/s).
        b1: f64,
        /// Loss growing with the square of the mode's frequency, b3 (s).
        b3: f64,
    },
}

impl Damping {
    /// No loss at all.
    pub const LOSSLESS: Damping = Damping::Viscous { eta0: 0.0, eta2: 0.0 };

    /// Decay rate `σ` (1/s) of a mode with wavenumber `beta` (1/m) and angular frequency `omega0`
    /// (rad/s).
    pub fn sigma(&self, beta: f64, omega0: f64) -> f64 {
        match *self {
            Damping::Viscous { eta0, eta2 } => eta0 + eta2 * beta * beta,
            Damping::PerMode { b1, b3 } => b1 + b3 * omega0 * omega0,
        }
    }

    fn terms(&self) -> [(&'static str, f64); 2] {
        match *self {
            Damping::Viscous { eta0, eta2 } => [("eta0", eta0), ("eta2", eta2)],
            Damping::PerMode { b1, b3 } => [("b1", b1), ("b3", b3)],
        }
    }
}

/// Physical parameters of a stiff string.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StringParams {
    /// Length L (m).
    pub length: f64,
    /// Tension T (N).
    pub tension: f64,
    /// Linear density ρA (kg/m).
    pub linear_density: f64,
    /// Bending stiffness EI (N·m²).
    pub bending_stiffness: f64,
    /// Loss law.
    pub damping: Damping,
}

/// An invalid string parameter: names the key and the reason.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{key}: {reason}")]
pub struct StringError {
    /// Parameter name (as in scene files).
    pub key: &'static str,
    /// What is wrong.
    pub reason: String,
}

impl StringParams {
    /// Nominal fundamental of the flexible string, `f0 = √(T/ρA)/(2L)` (Hz).
    pub fn fundamental(&self) -> f64 {
        (self.tension / self.linear_density).sqrt() / (2.0 * self.length)
    }

    /// Inharmonicity coefficient `B = π² EI/(T L²)`.
    pub fn inharmonicity(&self) -> f64 {
        std::f64::consts::PI.powi(2) * self.bending_stiffness / (self.tension * self.length * self.length)
    }

    /// Lossless partial `f_i = i f0 √(1 + B i²)` (Hz), `i ≥ 1`.
    pub fn partial(&self, i: usize) -> f64 {
        let i = i as f64;
        i * self.fundamental() * (1.0 + self.inharmonicity() * i * i).sqrt()
    }

    /// Check every parameter, naming the first invalid one.
    pub fn validate(&self) -> Result<(), StringError> {
        let positive = |key, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(StringError { key, reason: format!("must be finite and > 0 (got {v})") })
            }
        };
        positive("length", self.length)?;
        positive("tension", self.tension)?;
        positive("linear_density", self.linear_density)?;
        if !(self.bending_stiffness.is_finite() && self.bending_stiffness >= 0.0) {
            return Err(StringError {
                key: "bending_stiffness",
                reason: format!("must be finite and >= 0 (got {})", self.bending_stiffness),
            });
        }
        for (key, v) in self.damping.terms() {
            if !(v.is_finite() && v >= 0.0) {
                return Err(StringError { key, reason: format!("must be finite and >= 0 (got {v})") });
            }
        }
        Ok(())
    }
}

fn check_rates(sample_rate: f64, max_frequency: f64) -> Result<(), StringError> {
    if !(sample_rate.is_finite() && sample_rate > 0.0) {
        return Err(StringError { key: "sample_rate", reason: format!("must be finite and > 0 (got {sample_rate})") });
    }
    if !(max_frequency > 0.0) {
        return Err(StringError { key: "max_frequency", reason: format!("must be > 0 (got {max_frequency})") });
    }
    Ok(())
}

/// One mode of a string: wavenumber (1/m), undamped and damped angular frequencies (rad/s),
/// decay rate (1/s).
#[derive(Debug, Clone, Copy)]
struct Mode {
    beta: f64,
    omega0: f64,
    omega: f64,
    sigma: f64,
    underdamped: bool,
}

/// The modes of a string that ring strictly below Nyquist and a frequency limit, in order.
/// `ω_i` increases with `i`, so the sequence stops at the first mode that fails (an overdamped
/// mode, which does not ring, is kept while `ω0_i` is below the limit).
struct ModeCounter<'a> {
    params: &'a StringParams,
    /// π·min(fs, 2 f_max) (rad/s).
    limit: f64,
    i: usize,
}

impl<'a> ModeCounter<'a> {
    fn new(params: &'a StringParams, sample_rate: f64, max_frequency: f64) -> Self {
        Self { params, limit: std::f64::consts::PI * sample_rate.min(2.0 * max_frequency), i: 0 }
    }

    /// Number of modes, counting at most `MAX_MODES + 1`.
    fn count(mut self) -> usize {
        let mut n = 0;
        while n <= MAX_MODES && self.next().is_some() {
            n += 1;
        }
        n
    }
}

impl Iterator for ModeCounter<'_> {
    type Item = Mode;

    fn next(&mut self) -> Option<Mode> {
        let p = self.params;
        self.i += 1;
        let beta = self.i as f64 * std::f64::consts::PI / p.length;
        let b2 = beta * beta;
        let omega0 = ((p.tension * b2 + p.bending_stiffness * b2 * b2) / p.linear_density).sqrt();
        let sigma = p.damping.sigma(beta, omega0);
        let underdamped = sigma < omega0;
        let omega = if underdamped { (omega0 * omega0 - sigma * sigma).sqrt() } else { 0.0 };
        if !(omega < self.limit) || !omega0.is_finite() || (!underdamped && omega0 >= self.limit) {
            return None;
        }
        Some(Mode { beta, omega0, omega, sigma, underdamped })
    }
}

/// The scheme's per-mode coefficients for a mode whose homogeneous recursion is
/// `ũ^{n+1} = 2P ũ^n − Q ũ^{n−1}` (module docs), with time step `dt` (s) and modal mass `m̃` (kg).
struct Coefficients {
    a: f64,
    b: f64,
    c: f64,
    stiffness: f64,
    resistance: f64,
}

impl Coefficients {
    #[inline]
    fn new(p: f64, q: f64, dt: f64, modal_mass: f64) -> Self {
        let den = 1.0 + 2.0 * p + q;
        Self {
            a: 2.0 * p,
            b: 1.0 + q,
            c: dt * dt * den / (4.0 * modal_mass),
            stiffness: 4.0 * modal_mass / (dt * dt) * (1.0 - 2.0 * p + q) / den,
            resistance: 4.0 * modal_mass / dt * (1.0 - q) / den,
        }
    }
}

/// A modal string prepared for one sample rate: coefficients and state.
#[derive(Debug, Clone)]
pub struct ModalString {
    params: StringParams,
    sample_rate: f64,
    /// Modal mass m̃ = ρAL/2 (kg).
    modal_mass: f64,
    /// Wavenumbers β_i = iπ/L (1/m).
    beta: Vec<f64>,
    /// Undamped angular frequencies ω0_i (rad/s).
    omega0: Vec<f64>,
    /// Decay rates σ_i (1/s).
    sigma: Vec<f64>,
    /// The string's own `P_i = e^{−σ_iΔt} cos(ω_iΔt)` and `Q_i = e^{−2σ_iΔt}`, before any extra
    /// decay ([`ModalString::set_extra_decay`]).
    own_p: Vec<f64>,
    own_q: Vec<f64>,
    /// `A_i = 2P_i`.
    coef_a: Vec<f64>,
    /// `B_i = 1 + Q_i`.
    coef_b: Vec<f64>,
    /// `C_i = Δt²(1 + 2P + Q)/(4m̃)` (m/N).
    coef_c: Vec<f64>,
    /// `K̂_i` (N/m).
    stiffness: Vec<f64>,
    /// The string's own `K̂_i` (N/m), before any extra decay.
    own_stiffness: Vec<f64>,
    /// `R̂_i` (kg/s).
    resistance: Vec<f64>,
    /// `ũ^{n−1}` (m).
    u_prev: Vec<f64>,
    /// `ũ^n` (m).
    u_now: Vec<f64>,
    /// `z̃` of the current step (m), from [`ModalString::history`] or left by
    /// [`ModalString::advance`].
    history: Vec<f64>,
    /// Whether `history` holds `z̃ = B ũ^{n−1} − A ũ^n` for the current state. Everything that
    /// changes the state otherwise clears it.
    history_ready: bool,
    /// Steps since the last flush of tiny amplitudes.
    since_flush: u32,
    /// The vector unit the kernels run on.
    isa: Isa,
}

/// Set the amplitudes below [`FLUSH_BELOW`] (m) to zero. Written as a select, not a branch, so
/// it compiles to a few vector instructions per chunk instead of a mispredicted branch per mode.
#[inline]
fn flush_tiny(u: &mut [f64]) {
    for u in u {
        *u = if u.abs() < FLUSH_BELOW { 0.0 } else { *u };
    }
}

/// Energy terms of one string step (J), returned by [`ModalString::advance_monitored`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StringEnergy {
    /// `½ m̃ ‖(ũ^{n+1} − ũ^n)/Δt‖² + ½ Σ K̂ ((ũ^{n+1} + ũ^n)/2)²` (J).
    pub stored: f64,
    /// Energy dissipated in the step, `Δt (δ_t·ũ)ᵀ R̂ (δ_t·ũ)` (J).
    pub dissipated: f64,
}

impl ModalString {
    /// Prepare the string at `sample_rate` (Hz): every mode strictly below Nyquist, at rest.
    pub fn new(params: StringParams, sample_rate: f64) -> Result<Self, StringError> {
        Self::band_limited(params, sample_rate, f64::INFINITY)
    }

    /// Prepare the string keeping only the modes that ring strictly below both Nyquist and
    /// `max_frequency` (Hz). With the same `max_frequency` at every sample rate (below the
    /// lowest Nyquist in use), the string has the same modes, and so the same sound, at all of them.
    pub fn band_limited(params: StringParams, sample_rate: f64, max_frequency: f64) -> Result<Self, StringError> {
        check_rates(sample_rate, max_frequency)?;
        params.validate()?;
        let count = ModeCounter::new(&params, sample_rate, max_frequency).count();
        if count > MAX_MODES {
            return Err(StringError {
                key: "length",
                reason: format!(
                    "the string has more than {MAX_MODES} modes below Nyquist; shorten it or raise the tension"
                ),
            });
        }
        let mut s = Self::with_capacity(count);
        s.retune(params, sample_rate, max_frequency)?;
        Ok(s)
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
            let decay = (-mode.sigma * dt).exp();
            let p = if mode.underdamped {
                decay * (mode.omega * dt).cos()
            } else {
                // e^{−σΔt} cosh(γΔt) as the mean of two decaying exponentials (0 < γ < σ): the
                // product form gives 0·∞ = NaN once σΔt passes about 710.
                let gamma = (mode.sigma * mode.sigma - mode.omega0 * mode.omega0).sqrt();
                0.5 * ((gamma - mode.sigma) * dt).exp() + 0.5 * ((-gamma - mode.sigma) * dt).exp()
            };
            let q = decay * decay;
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

    /// Modal displacements `ũ^n` (m), M entries.
    pub fn state(&self) -> &[f64] {
        &self.u_now[..self.modes()]
    }

    /// Modal displacements `ũ^{n−1}` (m), M entries.
    pub fn previous_state(&self) -> &[f64] {
        &self.u_prev[..self.modes()]
    }

    /// Set the modal state `ũ^{n−1}`, `ũ^n` (m). Slices must have [`modes`](Self::modes) entries.
    pub fn set_state(&mut self, previous: &[f64], now: &[f64]) {
        let m = self.modes();
        self.u_prev[..m].copy_from_slice(previous);
        self.u_now[..m].copy_from_slice(now);
        self.history_ready = false;
    }

    /// Multiply the modal state by `factor` (0..=1): an extra decay of the free vibration by that
    /// factor, applied at once (a damper applies `e^{−σ_d N_b Δt}` once per control block).
    pub fn scale_state(&mut self, factor: f64) {
        for u in self.u_prev.iter_mut().chain(self.u_now.iter_mut()) {
            *u *= factor;
        }
        self.history_ready = false;
    }

    /// Add the decay rates `extra` (1/s, ≥ 0, one per mode; missing entries count as 0) to the
    /// string's own: each mode then decays at `σ_i + extra_i` and still rings at `ω_i`, since
    /// `P = e^{−(σ+σ_e)Δt} cos(ωΔt)` and `Q = e^{−2(σ+σ_e)Δt}` are the string's own scaled by
    /// `e^{−σ_eΔt}` and its square. The state is untouched, so the signal stays continuous: a
    /// damper or a fade changes how fast the modes decay from here on, never where they are. All
    /// zeros restore the string's own coefficients exactly. Changes `C` (and with it every contact
    /// gain `C∘h` and coupling `q` built on it) and the stored-energy weights `K̂`. Never
    /// allocates.
    pub fn set_extra_decay(&mut self, extra: &[f64]) {
        let (dt, m) = (1.0 / self.sample_rate, self.modal_mass);
        for i in 0..self.modes() {
            let d = (-extra.get(i).copied().unwrap_or(0.0) * dt).exp();
            let c = Coefficients::new(self.own_p[i] * d, self.own_q[i] * (d * d), dt, m);
            self.coef_a[i] = c.a;
            self.coef_b[i] = c.b;
            self.coef_c[i] = c.c;
            self.stiffness[i] = c.stiffness;
            self.resistance[i] = c.resistance;
        }
        self.history_ready = false;
    }

    /// Bring the string to rest.
    pub fn reset(&mut self) {
        self.u_prev.fill(0.0);
        self.u_now.fill(0.0);
        self.since_flush = 0;
        self.history_ready = false;
    }

    /// Write the mode shapes at `x` (m), `sin(β_i x)`, into `out` (dimensionless; entries past M
    /// are zeroed). One sine and one cosine for all modes: the rest by rotations (see
    /// `kernel::sines`), eight modes at a time when `out` holds whole chunks.
    pub fn mode_shapes(&self, x: f64, out: &mut [f64]) {
        let (s1, c1) = self.shape_angle(x);
        let m = self.modes().min(out.len());
        let whole = m.div_ceil(LANES) * LANES;
        if whole <= out.len() {
            kernel::sines(self.isa, s1, c1, &mut out[..whole]);
        } else {
            let (mut sn, mut cs) = (s1, c1);
            for o in &mut out[..m] {
                *o = sn;
                (sn, cs) = (sn * c1 + cs * s1, cs * c1 - sn * s1);
            }
        }
        out[m..].fill(0.0);
    }

    /// `(sin θ, cos θ)` for `θ = πx/L` (`x` in m), the angle the mode shapes at `x` are made from
    /// (`β_i x = iθ`): what a fresh [`GramVector`] takes.
    #[inline]
    pub fn shape_angle(&self, x: f64) -> (f64, f64) {
        (std::f64::consts::PI * x / self.params.length).sin_cos()
    }

    /// The weights that turn the modal state into the transverse force on the support (N/m):
    /// `T β_i + EI β_i³` at `x = 0`, and `(−1)^(i+1)(T β_i + EI β_i³)` at `x = L` (the mirror
    /// image, since `sin(β_i (L − x)) = (−1)^(i+1) sin(β_i x)`).
    pub fn bridge_weights(&self, at_far_end: bool, out: &mut [f64]) {
        out.fill(0.0);
        let (t, ei) = (self.params.tension, self.params.bending_stiffness);
        for (i, (o, &b)) in out.iter_mut().zip(&self.beta).enumerate() {
            let sign = if at_far_end && i % 2 == 1 { -1.0 } else { 1.0 };
            *o = sign * (t * b + ei * b * b * b);
        }
    }

    /// First pass of a step: compute `z̃ = B ũ^{n−1} − A ũ^n` and return its projections on
    /// each of the `K` vectors (m). Vectors have [`padded_len`](Self::padded_len) entries.
    /// When the previous step was an [`advance`](Self::advance), `z̃` is already there and this
    /// pass only projects it.
    #[inline]
    pub fn history<const K: usize>(&mut self, vectors: [&[f64]; K]) -> [f64; K] {
        if self.history_ready {
            return kernel::projections(self.isa, &self.history, vectors);
        }
        self.history_ready = true;
        kernel::history(self.isa, &self.coef_a, &self.coef_b, &self.u_prev, &self.u_now, &mut self.history, vectors)
    }

    /// Second pass: `ũ^{n+1} = ũ^{n−1} − z̃ + Σ_k gains_k · F_k`, where `gains_k = C∘h_k` (m/N,
    /// see [`input_gains`](Self::input_gains)) and `F_k` (N) are the modal forces along each contact
    /// vector; then step the state on. Returns `outputᵀ ũ^{n+1}`. The same pass computes the next
    /// step's `z̃`, so that the next [`history`](Self::history) only projects it.
    #[inline]
    pub fn advance<const K: usize>(&mut self, forces: [(&[f64], f64); K], output: &[f64]) -> f64 {
        self.advance_projecting(forces, output, []).0
    }

    /// [`advance`](Self::advance), also projecting the next step's `z̃` on the `J` vectors `next`
    /// in the same pass: the second value is what [`history(next)`](Self::history) would return
    /// next, bit for bit, so a caller whose vectors stay put can skip that pass. It is `None`
    /// when this step flushed tiny amplitudes (the new `z̃` is then recomputed from the flushed
    /// state by the next `history`).
    #[inline]
    pub fn advance_projecting<const K: usize, const J: usize>(
        &mut self,
        forces: [(&[f64], f64); K],
        output: &[f64],
        next: [&[f64]; J],
    ) -> (f64, Option<[f64; J]>) {
        debug_assert!(self.history_ready, "advance follows history");
        let (a, b) = (&self.coef_a, &self.coef_b);
        let (projection, next) =
            kernel::advance(self.isa, a, b, &mut self.u_prev, &self.u_now, &mut self.history, forces, output, next);
        self.finish_step();
        (projection, self.history_ready.then_some(next))
    }

    /// A whole step with no force on the string in one pass, by the homogeneous recursion
    /// `ũ^{n+1} = 2P ũ^n − Q ũ^{n−1}` with the coefficients of [`history`](Self::history) and
    /// [`advance`](Self::advance) (which compute `ũ^{n−1} − z̃`, the same recursion rounded
    /// differently: a few ulps per step). Returns `outputᵀ ũ^{n+1}`.
    #[inline]
    pub fn free_step(&mut self, output: &[f64]) -> f64 {
        let projection = kernel::free(self.isa, &self.coef_a, &self.coef_b, &mut self.u_prev, &self.u_now, output);
        self.finish_step();
        self.history_ready = false;
        projection
    }

    /// [`free_step`](Self::free_step) `outputs.len()` times, writing each step's
    /// `outputᵀ ũ^{n+1}` into `outputs`, bit-identically but faster (the state stays in registers
    /// between steps; see `kernel::free_run`).
    pub fn free_steps(&mut self, output: &[f64], outputs: &mut [f64]) {
        let mut done = 0;
        while done < outputs.len() {
            let until_flush = (FLUSH_INTERVAL - self.since_flush) as usize;
            let n = (outputs.len() - done).min(until_flush).min(kernel::RUN);
            let (a, b) = (&self.coef_a, &self.coef_b);
            kernel::free_run(self.isa, a, b, &mut self.u_prev, &mut self.u_now, output, &mut outputs[done..done + n]);
            // `free_run` leaves the last state in `u_now`; `finish_step` swaps, so undo that.
            std::mem::swap(&mut self.u_prev, &mut self.u_now);
            self.since_flush += n as u32 - 1;
            self.finish_step();
            done += n;
        }
        self.history_ready = false;
    }

    /// `xᵀy` for two per-mode vectors of [`padded_len`](Self::padded_len) entries, with the
    /// kernels' fixed summation order.
    #[inline]
    pub fn project(&self, x: &[f64], y: &[f64]) -> f64 {
        kernel::dot(self.isa, x, y)
    }

    /// Make the contact vectors marked fresh (the mode shapes at their angle, see
    /// [`shape_angle`](Self::shape_angle), times their window, and their gains; see
    /// [`GramVector`]) and return their Gram matrix in the C metric `θ_ab = h_aᵀ(C∘h_b)` for
    /// `a ≤ b` (m/N; zero below the diagonal) and the projections `(h_0ᵀũ^{n−1}, h_0ᵀũ^n)` (m)
    /// of the state on the first. A fresh shape is the [`mode_shapes`](Self::mode_shapes) at
    /// the same angle times the window, and every sum equals the [`project`](Self::project) or
    /// [`project_state`](Self::project_state) of the finished vectors, bit for bit.
    #[inline]
    pub fn gram<const K: usize>(&self, vectors: [GramVector<'_>; K]) -> ([[f64; K]; K], (f64, f64)) {
        let (c, modes) = (&self.coef_c, self.modes());
        let (gram, [prev, now]) = kernel::gram(self.isa, c, &self.u_prev, &self.u_now, modes, vectors);
        (gram, (prev, now))
    }

    /// `(vᵀũ^{n−1}, vᵀũ^n)` for a per-mode vector `v` of [`padded_len`](Self::padded_len) entries.
    #[inline]
    pub fn project_state(&self, v: &[f64]) -> (f64, f64) {
        (kernel::dot(self.isa, &self.u_prev, v), kernel::dot(self.isa, &self.u_now, v))
    }

    /// [`advance`](Self::advance), also returning the string's energy terms for this step.
    pub fn advance_monitored<const K: usize>(
        &mut self,
        forces: [(&[f64], f64); K],
        output: &[f64],
    ) -> (f64, StringEnergy) {
        let (projection, [step2, k_sum2, r_diff2]) = kernel::advance_monitored(
            &mut self.u_prev,
            &self.u_now,
            &self.history,
            forces,
            output,
            &self.stiffness,
            &self.resistance,
        );
        self.finish_step();
        self.history_ready = false;
        // Δt·ΣR̂(δ_t·ũ)² from the unscaled sum.
        let dissipated = 0.25 * r_diff2 * self.sample_rate;
        (projection, StringEnergy { stored: self.stored_energy(step2, k_sum2), dissipated })
    }

    /// `½ m̃ ‖δ/Δt‖² + ½ Σ K̂ (σ/2)²` (J) between two states, from the unscaled sums `Σ δ²` and
    /// `Σ K̂ σ²` of their difference δ and their sum σ.
    #[inline]
    fn stored_energy(&self, step2: f64, k_sum2: f64) -> f64 {
        self.kinetic_from(step2) + 0.125 * k_sum2
    }

    /// `½ m̃ ‖δ/Δt‖²` (J) from `Σ δ²`.
    #[inline]
    fn kinetic_from(&self, step2: f64) -> f64 {
        let fs = self.sample_rate;
        0.5 * self.modal_mass * step2 * fs * fs
    }

    /// Step the state on, flushing tiny amplitudes every [`FLUSH_INTERVAL`] steps (a flush makes
    /// the next `z̃` stale).
    #[inline]
    fn finish_step(&mut self) {
        std::mem::swap(&mut self.u_prev, &mut self.u_now);
        self.since_flush += 1;
        if self.since_flush == FLUSH_INTERVAL {
            self.since_flush = 0;
            self.history_ready = false;
            flush_tiny(&mut self.u_prev);
            flush_tiny(&mut self.u_now);
        }
    }

    /// String displacement `u(x) = Σ sin(β_i x) ũ_i^n` (m) at `x` (m): one pass over the modes.
    pub fn displacement_at(&self, x: f64) -> f64 {
        let theta = std::f64::consts::PI * x / self.params.length;
        let (s1, c1) = theta.sin_cos();
        let two_c = 2.0 * c1;
        let (mut prev, mut now, mut sum) = (0.0, s1, 0.0);
        for &u in &self.u_now[..self.modes()] {
            sum += now * u;
            let next = two_c * now - prev;
            prev = now;
            now = next;
        }
        sum
    }

    /// Kinetic energy of the latest step, `½ m̃ ‖(ũ^n − ũ^{n−1})/Δt‖²` (J): zero for a string held
    /// still however far it is deflected.
    pub fn kinetic_energy(&self) -> f64 {
        let (step2, _) = kernel::energy_sums(self.isa, &self.u_prev, &self.u_now, &self.stiffness);
        self.kinetic_from(step2)
    }

    /// [`kinetic_energy`](Self::kinetic_energy) and [`energy`](Self::energy) (J) from one pass
    /// over the modes.
    pub fn energies(&self) -> (f64, f64) {
        let (step2, k_sum2) = kernel::energy_sums(self.isa, &self.u_prev, &self.u_now, &self.stiffness);
        (self.kinetic_from(step2), self.stored_energy(step2, k_sum2))
    }

    /// The string's energy of the current state weighed with its own modal stiffnesses (J): as
    /// [`energy`](Self::energy), but with the `K̂_i` the string has without any extra decay
    /// ([`set_extra_decay`](Self::set_extra_decay)). A damper or a fade changes `K̂` (it depends
    /// on the decay rate), so the numerical energy of an unchanged state jumps when they land, by
    /// up to hundreds of times for a low mode damped far beyond its frequency; this measure does
    /// not, and it decays as the damped motion does (docs/physics.md §6.5). What a piano voice's
    /// guard and release test read.
    pub fn own_energy(&self) -> f64 {
        let (step2, k_sum2) = kernel::energy_sums(self.isa, &self.u_prev, &self.u_now, &self.own_stiffness);
        self.stored_energy(step2, k_sum2)
    }

    /// The string's energy `H^{n−1/2}` of the current state (J): the stored term between
    /// `ũ^{n−1}` and `ũ^n`, `½ m̃ ‖(ũ^n − ũ^{n−1})/Δt‖² + ½ Σ K̂ ((ũ^n + ũ^{n−1})/2)²`, from the
    /// unscaled sums in one pass (as [`advance_monitored`](Self::advance_monitored) does).
    pub fn energy(&self) -> f64 {
        let (step2, k_sum2) = kernel::energy_sums(self.isa, &self.u_prev, &self.u_now, &self.stiffness);
        self.stored_energy(step2, k_sum2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c4() -> StringParams {
        StringParams {
            length: 0.62,
            tension: 670.0,
            linear_density: 3.93e-3 / 0.62,
            bending_stiffness: 3.82e-5 * 670.0 * 0.62 * 0.62,
            damping: Damping::Viscous { eta0: 0.5, eta2: 6.25e-9 * 670.0 / (3.93e-3 / 0.62) },
        }
    }

    #[test]
    fn mode_count_is_every_mode_below_nyquist() {
        // physics §8.2: M = 34 / 56 / 59 / 90 / 132 for the C4 string.
        for (fs, m) in [(22050.0, 34), (44100.0, 56), (48000.0, 59), (96000.0, 90), (192000.0, 132)] {
            assert_eq!(ModalString::new(c4(), fs).unwrap().modes(), m, "fs = {fs}");
        }
    }

    #[test]
    fn mode_shape_recurrence_matches_sine() {
        let s = ModalString::new(c4(), 44100.0).unwrap();
        let mut shapes = vec![0.0; s.modes()];
        let x = 0.12 * 0.62;
        s.mode_shapes(x, &mut shapes);
        for (i, (&got, &beta)) in shapes.iter().zip(s.wavenumbers()).enumerate() {
            assert!((got - (beta * x).sin()).abs() < 1e-12, "mode {}", i + 1);
        }
    }

    /// A decaying string never holds a subnormal amplitude: every [`FLUSH_INTERVAL`] steps the
    /// amplitudes below [`FLUSH_BELOW`] become exact zeros and the others are left alone, so the
    /// string comes to rest. With η0 = 2000/s, 1e-3 m falls below 1e-30 m in about 0.03 s (1,400
    /// steps at 44.1 kHz; without the flush it would still be about 1e-129 m after the 6,400 steps
    /// here), and no amplitude is anywhere near the threshold in the first 500 steps.
    #[test]
    fn tiny_amplitudes_are_flushed_to_zero() {
        let mut p = c4();
        p.damping = Damping::Viscous { eta0: 2000.0, eta2: 0.0 };
        let mut s = ModalString::new(p, 44100.0).unwrap();
        let start: Vec<f64> = (0..s.modes()).map(|i| 1e-3 / (i + 1) as f64).collect();
        s.set_state(&start, &start);
        let pickup = s.vector();
        let mut out = [0.0; 37];
        for call in 0..173 {
            s.free_steps(&pickup, &mut out);
            let steps = (call + 1) * out.len();
            for &u in s.state().iter().chain(s.previous_state()) {
                assert!(!u.is_subnormal(), "step {steps}: subnormal {u:e}");
                assert!(steps > 500 || u != 0.0, "step {steps}: an audible amplitude was flushed");
            }
        }
        assert!(s.state().iter().chain(s.previous_state()).all(|u| *u == 0.0), "the string comes to rest");
    }

    /// The one-pass energy is the per-mode definition (physics §6.3) to rounding.
    #[test]
    fn energy_is_the_stored_term_of_every_mode() {
        let mut s = ModalString::new(c4(), 44100.0).unwrap();
        let m = s.modes();
        let prev: Vec<f64> = (0..m).map(|i| 1e-4 * ((i * 7 % 11) as f64 - 5.0) / (i + 1) as f64).collect();
        let now: Vec<f64> = (0..m).map(|i| 1e-4 * ((i * 5 % 13) as f64 - 6.0) / (i + 1) as f64).collect();
        s.set_state(&prev, &now);
        let (fs, mass) = (s.sample_rate(), s.modal_mass());
        let (mut kinetic, mut potential) = (0.0, 0.0);
        for i in 0..m {
            let v = (now[i] - prev[i]) * fs;
            let mean = 0.5 * (now[i] + prev[i]);
            kinetic += 0.5 * mass * v * v;
            potential += 0.5 * s.stiffness()[i] * mean * mean;
        }
        assert!((s.kinetic_energy() / kinetic - 1.0).abs() < 1e-13, "{} vs {kinetic}", s.kinetic_energy());
        assert!((s.energy() / (kinetic + potential) - 1.0).abs() < 1e-13, "{} vs {}", s.energy(), kinetic + potential);
    }

    /// An overdamped mode with a decay rate far beyond the sample rate (σΔt ≈ 2000, where
    /// `e^{−σΔt}` underflows to 0 and `cosh(γΔt)` overflows) gets finite coefficients, and its
    /// recursion `ũ^{n+1} = 2P ũ^n − Q ũ^{n−1}` has `P` within rounding of the exact
    /// `½(e^{(γ−σ)Δt} + e^{(−γ−σ)Δt})`, computed here with the slowest part alone.
    #[test]
    fn overdamped_modes_with_huge_damping_stay_finite() {
        let mut p = c4();
        p.damping = Damping::Viscous { eta0: 1e8, eta2: 0.0 };
        let mut s = ModalString::new(p, 44100.0).unwrap();
        assert!(s.modes() > 0);
        for i in 0..s.modes() {
            let (a, b, c) = (s.coef_a[i], s.coef_b[i], s.coef_c[i]);
            assert!(a.is_finite() && b.is_finite() && c.is_finite(), "mode {i}: A {a} B {b} C {c}");
            let (sigma, omega0) = (s.decay_rates()[i], s.angular_frequencies()[i]);
            let gamma = (sigma * sigma - omega0 * omega0).sqrt();
            let slow = 0.5 * ((gamma - sigma) / 44100.0).exp();
            assert!((0.5 * a - slow).abs() <= 1e-12 * slow.max(f64::MIN_POSITIVE), "mode {i}: P {} vs {slow}", 0.5 * a);
        }
        let ones = vec![1e-3; s.modes()];
        s.set_state(&ones, &ones);
        let pickup = s.vector();
        let mut out = [0.0; 128];
        s.free_steps(&pickup, &mut out);
        assert!(s.state().iter().all(|u| u.is_finite() && u.abs() <= 1e-3), "the state decays and stays finite");
    }

    /// With an extra decay rate the free vibration of a mode is `e^{−(σ+σ_e)t} cos(ωt)` with the
    /// string's own damped `ω` (the exact recursion, to 1e-10 over 4,410 steps as for the plain
    /// string), and a zero extra rate gives back the string's own coefficients bit for bit.
    #[test]
    fn extra_decay_adds_to_each_modes_rate_and_keeps_its_frequency() {
        let mut s = ModalString::new(c4(), 44100.0).unwrap();
        let m = s.modes();
        let own = (s.coef_a.clone(), s.coef_b.clone(), s.coef_c.clone(), s.stiffness.clone());
        let extra: Vec<f64> = (0..m).map(|i| 30.0 + 5.0 * i as f64).collect();
        s.set_extra_decay(&extra);
        let dt = 1.0 / 44100.0;
        for mode in [0, 7, m - 1] {
            let (sigma, omega0) = (s.decay_rates()[mode] + extra[mode], s.angular_frequencies()[mode]);
            let omega = (omega0 * omega0 - s.decay_rates()[mode].powi(2)).sqrt();
            let exact = |n: f64| (-sigma * n * dt).exp() * (omega * n * dt).cos();
            let (mut prev, mut now) = (vec![0.0; m], vec![0.0; m]);
            prev[mode] = exact(-1.0);
            now[mode] = exact(0.0);
            let mut t = s.clone();
            t.set_state(&prev, &now);
            let mut out = vec![0.0; 4410];
            let mut probe = t.vector();
            probe[mode] = 1.0;
            t.free_steps(&probe, &mut out);
            for (n, &y) in out.iter().enumerate() {
                assert!(
                    (y - exact(n as f64 + 1.0)).abs() < 1e-10,
                    "mode {mode}, step {n}: {y} vs {}",
                    exact(n as f64 + 1.0)
                );
            }
        }
        s.set_extra_decay(&[]);
        assert_eq!((s.coef_a.clone(), s.coef_b.clone(), s.coef_c.clone(), s.stiffness.clone()), own);
    }

    #[test]
    fn invalid_parameters_name_their_key() {
        let mut p = c4();
        p.tension = -1.0;
        assert_eq!(ModalString::new(p, 44100.0).unwrap_err().key, "tension");
        let mut p = c4();
        p.damping = Damping::Viscous { eta0: f64::NAN, eta2: 0.0 };
        assert_eq!(ModalString::new(p, 44100.0).unwrap_err().key, "eta0");
    }
}
