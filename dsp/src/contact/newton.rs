//! IMP: the energy-conserving implicit scheme on the exact power law, solved by safeguarded
//! Newton (seed §4.1.2, docs/physics.md §5). This is the reference the QSA is measured against.
//!
//! Solve `G(s) = s + z + q·DG(yp, yp+s) = 0` with the exact discrete gradient
//! `DG(y0, y1) = (V(y1) − V(y0))/(y1 − y0)` computed without cancellation ([`PowerLaw`]).
//!
//! - **Bracket.** `G(−z) = q·DG(yp, yp−z) ≥ 0` and DG is non-decreasing, so
//!   `s* ∈ [−z − q·DG(yp, yp−z), −z]`. If `DG(yp, yp−z) = 0` the step is free flight: `s = −z`.
//! - **Newton** from `s = −z` with `G'(s) = 1 + q·(V'(yp+s) − DG)/s`, replaced by
//!   `1 + ½·q·V''(yp)` when `|s| ≤ 10⁻⁶·max(|yp|, |yp+s|)`. After each evaluation the bracket
//!   shrinks on the side given by the sign of G. Convergence (`|Δs| ≤ 10⁻¹⁵·max(|s|, |z|)`) is
//!   tested *before* the bracket fallback (the step is replaced by the bracket midpoint if it
//!   leaves the open bracket, or lands on an end already evaluated: the first bracket's lower end
//!   is a valid point to step onto); iteration also stops when the bracket is 10⁻¹⁵-narrow, or
//!   after 100 iterations.
//!
//! The iteration count is data dependent; [`ContactSolver::last_work`] reports it (mean 3.9, max 4
//! per contact step on the seed's Fig. 4 case).

use super::{ContactProblem, ContactSolution, ContactSolver, Method, PowerLaw, max_abs};

/// Newton iterations allowed per step before giving up on further refinement.
pub const MAX_ITERATIONS: u32 = 100;

/// Relative tolerance on the Newton step and on the bracket width.
const TOLERANCE: f64 = 1e-15;

/// The IMP solver (seed §4.1.2).
#[derive(Debug, Clone)]
pub struct NewtonSolver {
    law: PowerLaw,
    last_iterations: u32,
}

impl NewtonSolver {
    /// A Newton solver on the exact `law`.
    pub fn new(law: PowerLaw) -> Self {
        Self { law, last_iterations: 0 }
    }

    /// Replace the contact law (for a new note); restart the solver afterwards.
    pub fn set_law(&mut self, law: PowerLaw) {
        self.law = law;
    }

    /// The exact law.
    pub fn law(&self) -> &PowerLaw {
        &self.law
    }

    fn residual(&self, yp: f64, z: f64, q: f64, s: f64) -> f64 {
        s + z + q * self.law.discrete_gradient(yp, yp + s)
    }

    fn slope(&self, yp: f64, q: f64, s: f64) -> f64 {
        let y1 = yp + s;
        if s.abs() <= 1e-6 * max_abs(yp, y1) {
            return 1.0 + 0.5 * q * self.law.potential_curvature(yp);
        }
        1.0 + q * (self.law.potential_slope(y1) - self.law.discrete_gradient(yp, y1)) / s
    }
}

impl ContactSolver for NewtonSolver {
    const METHOD: Method = Method::Imp;

    fn start(&mut self, _y_prev: f64, _y_now: f64) {
        self.last_iterations = 0;
    }

    fn solve(&mut self, problem: &ContactProblem) -> ContactSolution {
        let ContactProblem { y_prev: yp, z, q, .. } = *problem;
        let push = q * self.law.discrete_gradient(yp, yp - z);
        self.last_iterations = 0;
        if push == 0.0 {
            return ContactSolution { s: -z, force: 0.0 };
        }
        let (mut lo, mut hi) = (-z - push, -z);
        // Whether `lo` is a point already evaluated (the start `hi` always is).
        let mut lo_evaluated = false;
        let mut s = hi;
        for iteration in 1..=MAX_ITERATIONS {
            self.last_iterations = iteration;
            let g = self.residual(yp, z, q, s);
            if g > 0.0 {
                hi = s;
            } else if g < 0.0 {
                (lo, lo_evaluated) = (s, true);
            } else {
                break;
            }
            let step = -g / self.slope(yp, q, s);
            let next = s + step;
            if step.abs() <= TOLERANCE * max_abs(s, z) {
                s = next;
                break;
            }
            // The first bracket's lower end is a valid point not yet evaluated (`G ≤ 0` there):
            // a step onto it, as the first step when `G′` rounds to 1, is a Newton step like any
            // other. A step onto an end already evaluated would cycle between the ends.
            let inside = (next > lo && next < hi) || (next == lo && !lo_evaluated);
            s = if inside { next } else { 0.5 * (lo + hi) };
            if hi - lo <= TOLERANCE * max_abs(lo, hi) {
                break;
            }
        }
        ContactSolution::from_increment(s, problem)
    }

    fn stored_energy(&self, y_next: f64, y_now: f64) -> f64 {
        0.5 * (self.law.potential(y_next) + self.law.potential(y_now))
    }

    fn last_work(&self) -> u32 {
        self.last_iterations
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `problem` solved by IMP on `law`: the evaluations it took and the residual `G(s)` at the
    /// increment it returned.
    fn solved(law: PowerLaw, problem: &ContactProblem) -> (u32, f64) {
        let mut imp = NewtonSolver::new(law);
        imp.start(problem.y_prev, problem.y_now);
        let solution = imp.solve(problem);
        let residual = imp.residual(problem.y_prev, problem.z, problem.q, solution.s);
        println!("{} evaluations, residual {residual:e}", imp.last_work());
        (imp.last_work(), residual)
    }

    /// Where `G'` is within rounding of 1 (a soft felt, `qV''` tiny), the first Newton step from
    /// `s = −z` lands exactly on the bracket's lower end `−z − q·DG`, which is a valid point
    /// (`G ≤ 0` there). Taken, it converges as Newton does, in at most 4 evaluations; refused for
    /// not lying strictly inside, the bracket would be halved instead, about 11 times here. The
    /// root either way satisfies `G(s) = 0` to the tolerance.
    #[test]
    fn a_newton_step_onto_the_brackets_end_is_taken() {
        let problem = ContactProblem { y_prev: 2e-5, y_now: 2e-5, z: -5e-6, q: 2.712673611111111e-9 };
        let (evaluations, residual) = solved(PowerLaw::new(1e5, 3.0).unwrap(), &problem);
        assert!(residual.abs() <= 4.0 * f64::EPSILON * problem.z.abs(), "G(s) = {residual:e}");
        assert!(evaluations <= 4, "{evaluations} evaluations");
    }

    /// From this state (met in the stability sweep, a hammer on a string) the Newton step from
    /// one end of the bracket lands on the other, already evaluated, and from there back: taken
    /// each time, the iteration would cycle between the two ends to the cap of 100. Replaced by
    /// the midpoint, it converges as from any other bracket, within the sweep's largest count
    /// for IMP (8), to a residual within the rounding of evaluating `G`'s three terms, each of
    /// about `|z|` here (a few ulps of `z` each).
    #[test]
    fn a_newton_step_onto_an_evaluated_end_is_replaced_rather_than_cycling() {
        let problem = ContactProblem {
            y_prev: 0.007158911489581048,
            y_now: 0.007119217480823404,
            z: -6.251578300960471e-5,
            q: 1.1425180048612067e-6,
        };
        let (evaluations, residual) = solved(PowerLaw::new(39639.715022169294, 1.1646319038117756).unwrap(), &problem);
        assert!(residual.abs() <= 8.0 * f64::EPSILON * problem.z.abs(), "G(s) = {residual:e}");
        assert!(evaluations <= 8, "{evaluations} evaluations");
    }
}
