//! The collision law and its three solvers.
//!
//! # One scalar problem (seed eq. 18)
//!
//! Every scene reduces its time step to one scalar equation in the compression increment
//! `s = y^{n+1} − y^{n−1}` (m):
//!
//! ```text
//! s + z − q·F^n = 0,      q > 0 (m/N),  z (m) = known history term
//! ```
//!
//! (mass–barrier: `z = 2(u^{n−1} − u^n)`, `q = Δt²/m`). A scene hands a [`ContactProblem`]
//! `(y^{n−1}, y^n, z, q)` to a [`ContactSolver`] and gets back `s` and the force `F^n` (N).
//! Solvers know nothing about strings; strings know nothing about solvers.
//!
//! - [`QsaSolver`]: the paper's non-iterative branched solve on the quadratic spline
//!   potential (seed §4.2). Bounded cost per step.
//! - [`NewtonSolver`] ("IMP"): safeguarded Newton on the exact power law with the energy-conserving
//!   discrete gradient (seed §4.1.2). The reference; its iteration count is data dependent.
//! - [`ExplicitSolver`] ("EXP"): energy quadratisation with a branched gradient that keeps
//!   ψ ≥ 0 (seed §4.1.1, docs/physics.md §4.3).
//!
//! Scenes are generic over the solver, so the sample loop has no dynamic dispatch.

mod explicit;
mod law;
mod newton;
mod qsa;
mod spline;

pub use explicit::{ExplicitSolver, STILL_SHARE};
pub use law::PowerLaw;
pub use newton::{MAX_ITERATIONS, NewtonSolver};
pub use qsa::{QsaSolver, SegmentSearch};
pub use spline::QuadSpline;

use serde::{Deserialize, Serialize};

/// An invalid contact or solver parameter.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ContactError {
    /// A parameter is out of its domain.
    #[error("{key}: {reason} (got {value})")]
    Invalid {
        /// The parameter's name as used in scene files.
        key: &'static str,
        /// What the parameter must satisfy.
        reason: &'static str,
        /// The offending value.
        value: f64,
    },
    /// The spline fit is not convex, so the branched solve would be invalid.
    #[error("spline fit is not convex: segment {segment} has curvature {curvature}")]
    NotConvex {
        /// Segment index j.
        segment: usize,
        /// Its curvature coefficient A_j (N/m).
        curvature: f64,
    },
}

impl ContactError {
    pub(crate) fn invalid(key: &'static str, reason: &'static str, value: f64) -> Self {
        Self::Invalid { key, reason, value }
    }
}

/// The data of one step's scalar problem `s + z − q F = 0` (seed eq. 18).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactProblem {
    /// Compression two samples back, `y^{n−1}` (m).
    pub y_prev: f64,
    /// Compression now, `y^n` (m). Only EXP uses it (its gradient is evaluated at `y^n`).
    pub y_now: f64,
    /// History term `z` (m).
    pub z: f64,
    /// Coupling `q > 0` (m/N): the compression change per newton of contact force.
    pub q: f64,
}

/// The result of one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSolution {
    /// `s = y^{n+1} − y^{n−1}` (m).
    pub s: f64,
    /// Contact force `F^n = (s + z)/q` (N); ≤ 0 to rounding (an ulp of `z` over `q` at a grazing
    /// exit), it pushes the compression back down.
    pub force: f64,
}

impl ContactSolution {
    /// Complete a solution from `s`: `F = (s + z)/q`.
    #[inline]
    pub fn from_increment(s: f64, problem: &ContactProblem) -> Self {
        Self { s, force: (s + problem.z) / problem.q }
    }
}

/// The three collision schemes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Quadratic spline approximation, non-iterative (seed §4.2).
    Qsa,
    /// Implicit discrete gradient on the exact law, solved by Newton (seed §4.1.2).
    Imp,
    /// Explicit energy-quadratised scheme (seed §4.1.1).
    Exp,
}

impl Method {
    /// Every method, in declaration order.
    pub const ALL: [Method; 3] = [Method::Qsa, Method::Imp, Method::Exp];

    /// The name used in scene files, reports, presets and the plugin's `solver` parameter (the
    /// one spelling everywhere; serde's lowercase names are these, a test checks it).
    pub const fn name(self) -> &'static str {
        match self {
            Method::Qsa => "qsa",
            Method::Imp => "imp",
            Method::Exp => "exp",
        }
    }

    /// The method called `name` ([`Method::name`]'s spelling), if any.
    pub fn from_name(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// A solver of the scalar contact problem. Implementations hold their own per-contact state
/// (QSA: the previous segment; EXP: the auxiliary variable ψ).
pub trait ContactSolver {
    /// Which scheme this is.
    const METHOD: Method;

    /// Reset internal state for a trajectory starting at `y^{−1} = y_prev`, `y^0 = y_now` (m).
    fn start(&mut self, y_prev: f64, y_now: f64);

    /// Solve one step.
    fn solve(&mut self, problem: &ContactProblem) -> ContactSolution;

    /// The contact's share of the numerical energy `H^{n+1/2}` (J) after the last
    /// [`solve`](Self::solve), given `y^{n+1}` and `y^n` (m).
    fn stored_energy(&self, y_next: f64, y_now: f64) -> f64;

    /// Work done in the last step: sign tests (QSA), Newton iterations (IMP), 0 (EXP).
    fn last_work(&self) -> u32;

    /// Segment count for reporting (QSA's N, 0 for the others).
    fn segments(&self) -> usize {
        0
    }
}

/// Which solver to build, and its settings. Scenes build their concrete solver from this once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverSettings {
    /// The scheme.
    pub method: Method,
    /// QSA segment count N ≥ 1 (ignored by the others).
    pub segments: usize,
    /// QSA reference energy V_ref (J) that sizes the fit, or `None` for the scene's default
    /// (the largest energy it can put into the contact).
    pub v_ref: Option<f64>,
}

/// The largest of two positive magnitudes, used for relative tolerances.
#[inline]
pub(crate) fn max_abs(a: f64, b: f64) -> f64 {
    a.abs().max(b.abs())
}

/// Something to do with a concrete solver type: lets code pick the solver once from
/// [`SolverSettings`] and then run fully monomorphised (no dynamic dispatch per sample).
pub trait WithSolver {
    /// What the work returns.
    type Output;
    /// Do the work with `solver`.
    fn run<S: ContactSolver>(self, solver: S) -> Self::Output;
}

impl SolverSettings {
    /// Build the solver these settings name on `law`, and hand it to `work`. `default_v_ref` (J)
    /// sizes the QSA fit when the settings give no V_ref.
    pub fn build<W: WithSolver>(&self, law: PowerLaw, default_v_ref: f64, work: W) -> Result<W::Output, ContactError> {
        Ok(match self.method {
            Method::Qsa => {
                let v_ref = self.v_ref.unwrap_or(default_v_ref);
                let spline = QuadSpline::from_reference_energy(law, v_ref, self.segments)?;
                work.run(QsaSolver::new(spline))
            }
            Method::Imp => work.run(NewtonSolver::new(law)),
            Method::Exp => work.run(ExplicitSolver::new(law)),
        })
    }
}
