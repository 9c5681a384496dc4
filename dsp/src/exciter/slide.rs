//! The slide–hand oscillator (SHO, seed eqs. 49, 64–71; docs/physics.md §7.2).
//!
//! A slide of mass `m_o` (kg) at height `w_o` (m) is held by the hand at height `w_H` (a control
//! input) through a spring `k_H` (N/m) and a damper `r_H` (kg/s):
//! `m_o ẅ_o + r_H (ẇ_o − ẇ_H) + k_H (w_o − w_H) = −F`. The contact compression is
//! `y = h_oᵀũ − w_o`: lowering the hand presses the slide into the string. Discretised with
//! `m_o δ_tt w_o + r_H δ_t·(w_o − w_H) + k_H μ_t²(w_o − w_H) = −F^n` (seed eq. 64):
//!
//! ```text
//! w_o^{n+1} = w_o^{n−1} − z_sho − q_sho F^n
//! z_sho = [2(K_H+1) w_o^{n−1} + 2(K_H−1) w_o^n − ξ_o T_H^n] / (1 + K_H + R_H)
//! q_sho = ξ_o / (1 + K_H + R_H)
//! K_H = k_HΔt²/(4m_o),  R_H = r_HΔt/(2m_o),  ξ_o = Δt²/m_o
//! T_H^n = k_H (w_H^{n+1} + 2w_H^n + w_H^{n−1})/4 + r_H (w_H^{n+1} − w_H^{n−1})/(2Δt)
//! ```
//!
//! The seed's eq. 69 prints `(K_H − 1) w_o^n` without the factor 2; with `k_H = r_H = 0` only
//! the version with the 2 reduces to the free mass `z = 2(w^{n−1} − w^n)`.
//!
//! Energy (seed eqs. 76–79): `½ m_o (δ_t+ w_o)² + ½ k_H (μ_t+(w_o − w_H))²`, losing
//! `Q_o = r_H (δ_t· w_o)²` and gaining the hand power
//! `P_H = {r_H δ_t· w_o − k_H μ_t²(w_o − w_H)} δ_t· w_H`.

use crate::contact::PowerLaw;

/// Slide and hand parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlideParams {
    /// Slide mass m_o (kg), > 0.
    pub mass: f64,
    /// Hand stiffness k_H (N/m), ≥ 0.
    pub stiffness: f64,
    /// Hand damping r_H (kg/s), ≥ 0.
    pub damping: f64,
}

impl SlideParams {
    /// The reference compression `y_ref` (m) that sizes the QSA fit of the slide contact: where
    /// the force `κ y^α` of `law` reaches twice the largest static push the hand and the fingers
    /// make, `F_ref = 2(k_H (d + 1 mm) + F_1 + F_2)`, with `d` (m, ≥ 0) the deepest hand press
    /// and `F_1`, `F_2` (N) the largest finger forces: `y_ref = (max(F_ref, 1 mN)/κ)^{1/α}`.
    /// Compressions beyond it are still stable (the fit is extended), only softer. Scene files
    /// and the plugin's slide voice both size their fits with it.
    pub fn reference_compression(&self, law: &PowerLaw, depth: f64, finger_1: f64, finger_2: f64) -> f64 {
        let force = 2.0 * (self.stiffness * (depth + 1e-3) + finger_1 + finger_2);
        (force.max(1e-3) / law.kappa()).powf(1.0 / law.alpha())
    }
}

/// The SHO state and its per-sample-rate constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlideHand {
    params: SlideParams,
    dt: f64,
    /// `K_H = k_H Δt²/(4 m_o)`.
    k: f64,
    /// `ξ_o/(1 + K_H + R_H)` (m/N).
    q: f64,
    /// `1/(1 + K_H + R_H)`.
    norm: f64,
    /// `ξ_o = Δt²/m_o` (m/N).
    xi: f64,
    /// `w_o^{n−1}`, `w_o^n` (m).
    w_prev: f64,
    w_now: f64,
}

/// Energy exchanged between the hand and the slide in one step (J).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct HandExchange {
    /// Work the moving hand did on the slide, `Δt·P_H` (J; either sign).
    pub supplied: f64,
    /// Energy the hand's damping took, `Δt·Q_o` (J, ≥ 0).
    pub dissipated: f64,
}

/// One step's hand input `w_H^{n−1}, w_H^n, w_H^{n+1}` (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandMotion {
    /// `w_H^{n−1}` (m).
    pub prev: f64,
    /// `w_H^n` (m).
    pub now: f64,
    /// `w_H^{n+1}` (m).
    pub next: f64,
}

impl SlideHand {
    /// A slide at rest at height `w0` (m).
    pub fn new(params: SlideParams, sample_rate: f64, w0: f64) -> Self {
        let dt = 1.0 / sample_rate;
        let xi = dt * dt / params.mass;
        let k = params.stiffness * dt * dt / (4.0 * params.mass);
        let r = params.damping * dt / (2.0 * params.mass);
        let norm = 1.0 / (1.0 + k + r);
        Self { params, dt, k, q: xi * norm, norm, xi, w_prev: w0, w_now: w0 }
    }

    /// New slide and hand parameters, keeping the slide's motion (the same ones change nothing).
    pub fn set_params(&mut self, params: SlideParams) {
        if params == self.params {
            return;
        }
        let (w_prev, w_now) = (self.w_prev, self.w_now);
        *self = Self::new(params, 1.0 / self.dt, w_now);
        self.w_prev = w_prev;
    }

    /// The slide at rest at height `w0` (m).
    pub fn rest(&mut self, w0: f64) {
        self.w_prev = w0;
        self.w_now = w0;
    }

    /// The slide and hand parameters.
    pub fn params(&self) -> SlideParams {
        self.params
    }

    /// `w_o^{n−1}` (m).
    #[inline]
    pub fn previous(&self) -> f64 {
        self.w_prev
    }

    /// `w_o^n` (m).
    #[inline]
    pub fn position(&self) -> f64 {
        self.w_now
    }

    /// `q_sho` (m/N).
    #[inline]
    pub fn coupling(&self) -> f64 {
        self.q
    }

    /// `z_sho` (m) for the hand motion around step n.
    #[inline]
    pub fn history(&self, hand: &HandMotion) -> f64 {
        let p = &self.params;
        let t_h = 0.25 * p.stiffness * (hand.next + 2.0 * hand.now + hand.prev)
            + p.damping * (hand.next - hand.prev) / (2.0 * self.dt);
        (2.0 * (self.k + 1.0) * self.w_prev + 2.0 * (self.k - 1.0) * self.w_now - self.xi * t_h) * self.norm
    }

    /// Apply the contact force (N; the slide feels `−F`) and step on. Returns the energy the
    /// hand's motion supplied during the step, `Δt·P_H` (J), and the energy its damping took,
    /// `Δt·Q_o` (J, ≥ 0).
    #[inline]
    pub fn advance(&mut self, z_sho: f64, force: f64, hand: &HandMotion) -> HandExchange {
        let next = self.w_prev - z_sho - self.q * force;
        let p = &self.params;
        let centred = (next - self.w_prev) / (2.0 * self.dt);
        let hand_centred = (hand.next - hand.prev) / (2.0 * self.dt);
        let spring = 0.25 * ((next - hand.next) + 2.0 * (self.w_now - hand.now) + (self.w_prev - hand.prev));
        let exchange = HandExchange {
            supplied: self.dt * (p.damping * centred - p.stiffness * spring) * hand_centred,
            dissipated: self.dt * p.damping * centred * centred,
        };
        self.w_prev = self.w_now;
        self.w_now = next;
        exchange
    }

    /// Stored energy `½ m_o (δ_t+ w_o)² + ½ k_H (μ_t+(w_o − w_H))²` (J) of the latest step,
    /// given the hand at the two latest samples.
    #[inline]
    pub fn energy(&self, hand_prev: f64, hand_now: f64) -> f64 {
        let v = (self.w_now - self.w_prev) / self.dt;
        let stretch = 0.5 * ((self.w_now - hand_now) + (self.w_prev - hand_prev));
        0.5 * self.params.mass * v * v + 0.5 * self.params.stiffness * stretch * stretch
    }

    /// Velocity of the latest step (m/s).
    #[inline]
    pub fn velocity(&self) -> f64 {
        (self.w_now - self.w_prev) / self.dt
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// With k_H = r_H = 0 the SHO is a free mass: z_sho = 2(w^{n−1} − w^n) (the check that
    /// exposes the seed's eq. 69 misprint).
    #[test]
    fn reduces_to_a_free_mass() {
        let mut sho = SlideHand::new(SlideParams { mass: 0.03, stiffness: 0.0, damping: 0.0 }, 44100.0, 1e-3);
        let still = HandMotion { prev: 0.0, now: 0.0, next: 0.0 };
        let z = sho.history(&still);
        sho.advance(z, 0.0, &still);
        sho.w_now = 2e-3;
        assert_eq!(sho.history(&still), 2.0 * (1e-3 - 2e-3));
    }
}
