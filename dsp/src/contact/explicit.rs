//! EXP: the explicit energy-quadratised scheme (seed §4.1.1, eqs. 19–21; physics §4).
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
//! # Branched gradient (physics §4.3, a reconstruction)
//!
//! The plain choice `g^n = dψ/dy(y^n)` lets ψ go negative (an adhesive force) or stay positive
//! after separation (energy locked in ψ: the Fig. 4 mass rebounds 3.6 % too slowly). Eliminating
//! `s`, `ψ^{n+1/2} ≥ 0` holds iff `0 ≤ g ≤ g_max` with
//!
//! ```text
//! g_max = 4ψ^{n−1/2} / (z + √(z² + 4q(ψ^{n−1/2})²))      (ψ^{n−1/2} > 0)
//! g_max = +∞ if z ≤ 0, 0 if z > 0                         (ψ^{n−1/2} = 0)
//! ```
//!
//! (the stable form of the positive root of `¼qψg² + ½zg − ψ = 0`). The branch is
//! - `y^n > 0`: `g = min(dψ/dy(y^n), g_max)`, so the force is never adhesive;
//! - `y^n ≤ 0`, `ψ > 0`: `g = g_max`, which drains ψ to zero and hands its energy back;
//! - `y^n ≤ 0`, `ψ = 0`: `g = 0` (free flight).
//!
//! Rounding can leave a tiny negative `ψ^{n+1/2}`; it is clamped to 0.

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
        let g_max = if psi > 0.0 {
            4.0 * psi / (z + (z * z + 4.0 * q * psi * psi).sqrt())
        } else if z <= 0.0 {
            f64::INFINITY
        } else {
            0.0
        };
        let g = if y_now > 0.0 {
            self.law.psi_gradient(y_now).min(g_max)
        } else if psi > 0.0 {
            g_max
        } else {
            0.0
        };
        if g == 0.0 {
            return ContactSolution { s: -z, force: 0.0 };
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
