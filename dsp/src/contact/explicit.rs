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
