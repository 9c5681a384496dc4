//! The modes a string keeps and the scheme's coefficients for each (docs/physics.md §6.1–6.2).
//!
//! Mode `i ≥ 1` has wavenumber `β_i = iπ/L`, `ω0_i² = (Tβ_i² + EIβ_i⁴)/ρA`, decay rate `σ_i` and
//! damped frequency `ω_i = √(ω0_i² − σ_i²)`; the string keeps the modes with `ω_i` strictly below
//! `π·min(fs, 2 f_max)`. From a mode's homogeneous recursion `ũ^{n+1} = 2P ũ^n − Q ũ^{n−1}`:
//!
//! ```text
//! A = 2P,   B = 1 + Q,   C = Δt²(1 + 2P + Q)/(4m̃)
//! K̂ = (4m̃/Δt²)(1 − 2P + Q)/(1 + 2P + Q) = (B − A)/C
//! R̂ = (4m̃/Δt)(1 − Q)/(1 + 2P + Q) = Δt(2 − B)/C
//! ```
//!
//! `K̂` and `R̂` are computed by the second forms, from `A`, `B` and `C` as stored
//! ([`Coefficients::new`]), so the energy balance closes on the recursion actually stepped.

use super::{MAX_MODES, StringParams};

/// One mode of a string.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Mode {
    /// Wavenumber β (1/m).
    pub(super) beta: f64,
    /// Undamped angular frequency ω0 (rad/s).
    pub(super) omega0: f64,
    /// Damped angular frequency ω (rad/s; 0 when overdamped).
    pub(super) omega: f64,
    /// Decay rate σ (1/s).
    pub(super) sigma: f64,
    underdamped: bool,
}

impl Mode {
    /// A single damped oscillator (not a string mode) with undamped angular frequency `omega0`
    /// (rad/s) and decay rate `sigma` (1/s): what another modal body (the bridge) steps with.
    pub(crate) fn oscillator(omega0: f64, sigma: f64) -> Self {
        let underdamped = sigma < omega0;
        let omega = if underdamped { (omega0 * omega0 - sigma * sigma).sqrt() } else { 0.0 };
        Self { beta: 0.0, omega0, omega, sigma, underdamped }
    }

    /// `(P, Q)` of the mode's homogeneous recursion `ũ^{n+1} = 2P ũ^n − Q ũ^{n−1}` at time step
    /// `dt` (s): `P = e^{−σΔt} cos(ωΔt)` (overdamped: `e^{−σΔt} cosh(γΔt)`, `γ = √(σ² − ω0²)`),
    /// `Q = e^{−2σΔt}`.
    pub(crate) fn recursion(&self, dt: f64) -> (f64, f64) {
        let decay = (-self.sigma * dt).exp();
        let p = if self.underdamped {
            decay * (self.omega * dt).cos()
        } else {
            // e^{−σΔt} cosh(γΔt) as the mean of two decaying exponentials (0 < γ < σ): the
            // product form gives 0·∞ = NaN once σΔt passes about 710. With `r = ω0/σ`,
            // `γ = σ√((1 − r)(1 + r))` and the slow rate `γ − σ = −ω0 r/(1 + γ/σ)`: σ is never
            // squared (σ² overflows past 1.3e154/s) and γ − σ is not a difference of near equals.
            // σ = 0 here only with ω0 = 0 (a mode at rest with no spring and no loss): r = 0.
            let r = if self.sigma > 0.0 { self.omega0 / self.sigma } else { 0.0 };
            let root = ((1.0 - r) * (1.0 + r)).sqrt();
            let (slow, fast) = (-self.omega0 * r / (1.0 + root), -self.sigma * (1.0 + root));
            0.5 * (slow * dt).exp() + 0.5 * (fast * dt).exp()
        };
        (p, decay * decay)
    }
}

/// The least `1 + 2P + Q` a kept mode may have: a mode this close to Nyquist (an undamped one
/// within `10⁻³` rad of `π` per step, 7 Hz at 44.1 kHz) is left out. `C` is proportional to it
/// and `K̂ = (B − A)/C`, so the few roundings of the sum (each `ε/2` absolute) are a relative
/// error of a few `ε/10⁻⁶ = 2.2e-10` at most in `C` and `K̂`, near the energy balance's 1e-9
/// only for a mode that holds the whole energy; at `ωΔt → π` the sum would round to 0 and make
/// `K̂` infinite.
pub(crate) const MIN_HEADROOM: f64 = 1e-6;

/// Angle per step (rad) above which a mode's headroom `1 + 2P + Q` is checked: below it the
/// headroom is at least `sin² 3 = 0.0199` for any damping (`1 + 2d cos θ + d²`, `d = e^{−σΔt}`,
/// is least at `d = −cos θ`, where it is `sin² θ`).
const NEAR_NYQUIST: f64 = 3.0;

/// The modes of a string that ring strictly below Nyquist and a frequency limit, in order, with
/// at least [`MIN_HEADROOM`] in `1 + 2P + Q`. The sequence stops at the first mode that fails
/// (an overdamped mode, which does not ring, is kept while `ω0_i` is below the limit). `ω_i`
/// increases with `i` up to the limit unless the damping grows like `β²` (`η2`, `b3`): then
/// `ω_i` falls again towards overdamping, and modes far above the limit, decaying faster than
/// `π·fs` per second, may ring below it again; they are left out.
pub(super) struct ModeCounter<'a> {
    params: &'a StringParams,
    /// π·min(fs, 2 f_max) (rad/s).
    limit: f64,
    /// Time step (s).
    dt: f64,
    i: usize,
}

impl<'a> ModeCounter<'a> {
    pub(super) fn new(params: &'a StringParams, sample_rate: f64, max_frequency: f64) -> Self {
        let limit = std::f64::consts::PI * sample_rate.min(2.0 * max_frequency);
        Self { params, limit, dt: 1.0 / sample_rate, i: 0 }
    }

    /// Number of modes, counting at most `MAX_MODES + 1`.
    pub(super) fn count(mut self) -> usize {
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
        let mode = Mode { beta, omega0, omega, sigma, underdamped };
        if underdamped && omega * self.dt > NEAR_NYQUIST {
            let (p, q) = mode.recursion(self.dt);
            if !(1.0 + 2.0 * p + q >= MIN_HEADROOM) {
                return None;
            }
        }
        Some(mode)
    }
}

/// The scheme's per-mode coefficients for a mode whose homogeneous recursion is
/// `ũ^{n+1} = 2P ũ^n − Q ũ^{n−1}` (module docs), with time step `dt` (s) and modal mass `m̃` (kg).
pub(crate) struct Coefficients {
    /// `A = 2P`.
    pub(crate) a: f64,
    /// `B = 1 + Q`.
    pub(crate) b: f64,
    /// `C = Δt²(1 + 2P + Q)/(4m̃)` (m/N).
    pub(crate) c: f64,
    /// `K̂` (N/m).
    pub(crate) stiffness: f64,
    /// `R̂` (kg/s).
    pub(crate) resistance: f64,
}

impl Coefficients {
    /// The coefficients of a mode with recursion `(P, Q)` decaying `extra` (1/s) faster: `P` scaled
    /// by `e^{−σ_eΔt}` and `Q` by its square, so the mode still rings at its own frequency.
    #[inline]
    pub(crate) fn with_extra_decay(p: f64, q: f64, extra: f64, dt: f64, modal_mass: f64) -> Self {
        let d = (-extra * dt).exp();
        Self::new(p * d, q * (d * d), dt, modal_mass)
    }

    /// `K̂` and `R̂` are those of the recursion as stored, `ũ^{n+1} = Aũ^n − (B − 1)ũ^{n−1} + CF`
    /// with `A`, `B` and `C` rounded: matching it to the scheme gives `K̂ = (B − A)/C` and
    /// `R̂ = Δt(2 − B)/C`, whose differences are exact where they cancel (`2 − B` always, `B − A`
    /// for a mode well below Nyquist). From the unrounded `P` and `Q` instead,
    /// `1 − 2P + Q` would differ from the stepped `B − A` by up to `ε`, a relative `ε/(ωΔt)²` in
    /// `K̂` (1e-9 for a 10 Hz mode at 192 kHz), and the books would not close on the steps taken.
    #[inline]
    pub(crate) fn new(p: f64, q: f64, dt: f64, modal_mass: f64) -> Self {
        let (a, b) = (2.0 * p, 1.0 + q);
        let c = dt * dt * (1.0 + 2.0 * p + q) / (4.0 * modal_mass);
        Self { a, b, c, stiffness: (b - a) / c, resistance: dt * (2.0 - b) / c }
    }
}
