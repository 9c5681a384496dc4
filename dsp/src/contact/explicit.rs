//! EXP: the explicit energy-quadratised scheme (seed §4.1.1, eqs. 19–21; docs/physics.md §4).
//!
//! The potential is carried by the auxiliary variable `ψ ≈ √(2V)` at half steps, and the force is
//! `F^n = −μ_t ψ^n · g^n` with `μ_t ψ^n = (ψ^{n+1/2} + ψ^{n−1/2})/2` and the update
//! `ψ^{n+1/2} = ψ^{n−1/2} + ½ g^n s`. Substituting into `s + z − qF = 0` gives the explicit step
//!
//! ```text
//! s = −(z + q·ψ^{n−1/2}·g^n) / (1 + ¼·q·(g^n)²),   ψ^{n+1/2} = ψ^{n−1/2} + ½·g^n·s
//! ```
//!
//! and `H = kinetic + ½(ψ^{n+1/2})²` is conserved exactly for *any* choice of `g^n`.
//!
//! # Branched gradient (docs/physics.md §4.3, a reconstruction)
//!
//! The plain choice `g^n = dψ/dy(y^n)` lets ψ go negative (an adhesive force) or stay positive
//! after separation (energy locked in ψ: the Fig. 4 mass rebounds 3.6 % too slowly). Eliminating
//! `s`, `ψ^{n+1/2} ≥ 0` holds iff `0 ≤ g ≤ g_max` with
//!
//! ```text
//! g_max = 4ψ / (z + √(z² + 4qψ²))  if z > 0,   (√(z² + 4qψ²) − z) / (qψ)  if z ≤ 0   (ψ = ψ^{n−1/2} > 0)
//! g_max = +∞ if z ≤ 0, 0 if z > 0                                                 (ψ^{n−1/2} = 0)
//! ```
//!
//! (the positive root of `¼qψg² + ½zg − ψ = 0`, each sign of z in the form without cancellation:
//! for `z < 0` and `4qψ² < ε·z²` the first form divides by `z + |z| = 0`). The branch is
//! - `y^n > 0`: `g = min(dψ/dy(y^n), g_max)`, so the force is never adhesive;
//! - `y^n ≤ 0`, `ψ > 0`, bodies moving apart (`z > 0`): `g = g_max`, which drains ψ to zero and
//!   hands its energy back to the separation;
//! - `y^n ≤ 0` otherwise: `g = 0` (free flight). In particular ψ left over from rounding is not
//!   drained while the bodies approach: that would need a force of about `z/q` (it would stop
//!   them dead, a bounce off nothing); it is drained once they move apart.
//!
//! Whenever `g = g_max` the step ends with `ψ^{n+1/2} = 0` exactly, and then
//! `s = −2ψ^{n−1/2}/g_max`, evaluated as `−(z + √(z² + 4qψ²))/2` (z > 0) or
//! `−2qψ²/(√(z² + 4qψ²) − z)` (z ≤ 0): no huge `g_max` is formed (it overflows to +∞ when ψ is
//! tiny, and the general update would then give ∞/∞ = NaN), and no rounding residue is left in ψ.
//! (A residue of 1e-18 √J left by the general update, followed by a step out of contact with
//! `z < 0`, is how the slide excerpt of the report produced NaN: `stability_cases.rs`.) Otherwise
//! `ψ^{n+1/2} ≥ 0` holds in exact arithmetic; a negative value from rounding is clamped to 0.

use super::{ContactProblem, ContactSolution, ContactSolver, Method, PowerLaw};

/// The share of the critical stiffness `4/q_N` that the explicit part of a still contact
/// started by [`ExplicitSolver::start_still`] may reach ([`ExplicitSolver::still_force`]).
pub const STILL_SHARE: f64 = 0.5;

/// The EXP solver with the branched gradient.
#[derive(Debug, Clone)]
pub struct ExplicitSolver {
    law: PowerLaw,
    /// `ψ^{n−1/2}` before a step, `ψ^{n+1/2}` after it (√J).
    psi: f64,
}

impl ExplicitSolver {
    /// An explicit solver on the exact `law`.
    pub fn new(law: PowerLaw) -> Self {
        Self { law, psi: 0.0 }
    }

    /// Replace the contact law (for a new note); restart the solver afterwards.
    pub fn set_law(&mut self, law: PowerLaw) {
        self.law = law;
    }

    /// The auxiliary variable ψ at the latest half step (√J).
    pub fn psi(&self) -> f64 {
        self.psi
    }

    /// The magnitude (N) of the force EXP holds still at the compression `y` (m), started there
    /// by [`start_still`](Self::start_still), where the contact meets the compliance `q_N` (m/N)
    /// at the Nyquist rate: the law's `V'(y)` where that is stable with room to spare, else less,
    /// ψ short of `√(2V(y))`.
    ///
    /// Linearised about a still contact holding `F = ψψ'(y)` (any ψ: the update keeps
    /// `ψ^{n+1/2} − ψ'(y)·μ_t+y` constant, so a still state with ψ short of `√(2V(y))` is as much
    /// an equilibrium of the scheme as the consistent one), the force's answer to a deviation δy
    /// is `−ψ'²·(δy^{n+1} + 2δy^n + δy^{n−1})/4 − ψψ''·δy^n`: a stiffness `ψ'²` averaged as an
    /// implicit scheme does, and an explicit one, `k_e = ψψ'' = F(α − 1)/(2y)`, at `y^n` alone.
    /// A deviation alternating from step to step escapes the average and sees the masses behind
    /// the contact as `q_N/4` ([`SlideCore::nyquist_compliance`](crate::scene::SlideCore::nyquist_compliance)),
    /// so it grows unless `k_e·q_N/4 < 1` (below that the scheme's energy, whose ½ψ² holds
    /// `½k_e δy^n δy^{n+1}`, bounds it). On the consistent ψ, `k_e = κ(α − 1)y^{α−1}/2` grows with the
    /// press: a slide pressed with about a newton on the defaults (α = 1.5) is at
    /// `k_e·q_N/4 ≈ 4.75` and starts chattering at Nyquist from rounding, its compression's
    /// deviation doubling every step. For the same force a deeper compression has a smaller
    /// `k_e`, so EXP's still contact holds at most `y·8s/((α − 1)q_N)` with the share
    /// `s =` [`STILL_SHARE`]: `min(V'(y), 8s·y/((α − 1)q_N))`, increasing in y. (A slide set down
    /// onto the string gets there by itself: its landing chatters until ψ has been drained that
    /// far, and with the defaults a landed slide rests at `k_e·q_N/4 ≈ 0.58`, ψ about 4 % of
    /// `√(2V(y))`.) With α = 1, ψ'' = 0 and the force is the law's.
    pub fn still_force(&self, y: f64, nyquist: f64) -> f64 {
        let consistent = self.law.potential_slope(y);
        let alpha = self.law.alpha();
        if alpha > 1.0 && nyquist > 0.0 {
            // Off contact (y ≤ 0) both are 0: the bound's sign follows y's.
            consistent.min(8.0 * STILL_SHARE * y.max(0.0) / ((alpha - 1.0) * nyquist))
        } else {
            consistent
        }
    }

    /// Start at rest at the compression `y` (m) holding the force magnitude `held` (N), from
    /// [`still_force`](Self::still_force): `ψ = held/ψ'(y)`, which is `√(2V(y))` when `held` is
    /// the law's `V'(y)` (and 0 off contact).
    pub fn start_still(&mut self, y: f64, held: f64) {
        self.psi = if y > 0.0 && held < self.law.potential_slope(y) {
            held.max(0.0) / self.law.psi_gradient(y)
        } else {
            self.law.psi(y)
        };
    }
}

impl ContactSolver for ExplicitSolver {
    const METHOD: Method = Method::Exp;

    fn start(&mut self, y_prev: f64, y_now: f64) {
        self.psi = self.law.psi(0.5 * (y_prev + y_now));
    }

    fn solve(&mut self, problem: &ContactProblem) -> ContactSolution {
        let ContactProblem { y_now, z, q, .. } = *problem;
        let psi = self.psi;
        let root = (z * z + 4.0 * q * psi * psi).sqrt();
        let g_max = if psi > 0.0 {
            if z > 0.0 { 4.0 * psi / (z + root) } else { (root - z) / (q * psi) }
        } else if z <= 0.0 {
            f64::INFINITY
        } else {
            0.0
        };
        let g = if y_now > 0.0 {
            self.law.psi_gradient(y_now).min(g_max)
        } else if psi > 0.0 && z > 0.0 {
            g_max
        } else {
            0.0
        };
        if g == 0.0 {
            return ContactSolution { s: -z, force: 0.0 };
        }
        if psi > 0.0 && g == g_max {
            // ψ^{n+1/2} = 0 exactly; s = −2ψ/g_max without forming g_max (see the module docs).
            let s = if z > 0.0 { -0.5 * (z + root) } else { -2.0 * q * psi * psi / (root - z) };
            self.psi = 0.0;
            return ContactSolution::from_increment(s, problem);
        }
        let s = -(z + q * psi * g) / (1.0 + 0.25 * q * g * g);
        self.psi = (psi + 0.5 * g * s).max(0.0);
        ContactSolution::from_increment(s, problem)
    }

    fn stored_energy(&self, _y_next: f64, _y_now: f64) -> f64 {
        0.5 * self.psi * self.psi
    }

    fn last_work(&self) -> u32 {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A contact started still by `start_still` with the force `still_force` gives it holds that
    /// force and stays still: the law's `V'(y)` (ψ = √(2V(y))) while its explicit stiffness
    /// `k_e = F(α − 1)/(2y)` is within the share of `4/q_N`, and at the share beyond (ψ short of
    /// √(2V(y))); the law's at any press with α = 1.
    /// Off contact no force holds: `still_force` is 0 at and below a compression of 0, with
    /// α above 1 and at 1.
    #[test]
    fn no_still_force_holds_off_contact() {
        for alpha in [1.0, 1.5, 3.0] {
            let exp = ExplicitSolver::new(PowerLaw::new(1e9, alpha).unwrap());
            for y in [0.0, -1e-9, -1e-6, -1e-3] {
                assert_eq!(exp.still_force(y, 7.1e-5), 0.0, "α {alpha}, y {y}");
            }
        }
    }

    #[test]
    fn a_still_start_holds_its_force() {
        let (nyquist, q) = (7.1e-5, 2.2e-5);
        let law = PowerLaw::new(1e9, 1.5).unwrap();
        let mut exp = ExplicitSolver::new(law);
        for y in [1e-9, 1e-7, 1e-6, 1e-5, 1e-4] {
            let held = exp.still_force(y, nyquist);
            let share = held * (law.alpha() - 1.0) / (2.0 * y) * nyquist / 4.0;
            if held < law.potential_slope(y) {
                assert!((share / STILL_SHARE - 1.0).abs() < 1e-12, "{y:e}: {share}");
            } else {
                assert!(share <= STILL_SHARE, "{y:e}: {share}");
            }
            exp.start_still(y, held);
            let psi = exp.psi();
            if held == law.potential_slope(y) {
                assert_eq!(psi, law.psi(y));
            }
            let solution = exp.solve(&ContactProblem { y_prev: y, y_now: y, z: -q * held, q });
            assert!(solution.s.abs() < 1e-14 * q * held, "{y:e}: s = {:e}", solution.s);
            assert!((solution.force / -held - 1.0).abs() < 1e-14, "{y:e}: {} N", solution.force);
            assert!((exp.psi() / psi - 1.0).abs() < 1e-14);
        }
        let linear = ExplicitSolver::new(PowerLaw::new(1e9, 1.0).unwrap());
        assert_eq!(linear.still_force(1e-4, nyquist), 1e5);
    }
}
