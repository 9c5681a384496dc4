//! One contact solver of each kind, kept by every voice so that switching schemes between notes
//! never allocates; the voice picks the chosen one once per block.

use crate::contact::{ContactSolver, ExplicitSolver, Method, NewtonSolver, PowerLaw, QsaSolver, QuadSpline};
use crate::instrument::settings::MAX_SEGMENTS;

/// The three solvers and which one plays.
#[derive(Debug, Clone)]
pub struct Solvers {
    /// QSA, with room for [`MAX_SEGMENTS`] segments.
    pub qsa: QsaSolver,
    /// IMP.
    pub imp: NewtonSolver,
    /// EXP.
    pub exp: ExplicitSolver,
    /// The one in use.
    pub method: Method,
}

impl Solvers {
    /// Solvers for `law`, QSA chosen.
    pub fn new(law: PowerLaw) -> Self {
        Self {
            qsa: QsaSolver::new(QuadSpline::with_capacity(law, MAX_SEGMENTS)),
            imp: NewtonSolver::new(law),
            exp: ExplicitSolver::new(law),
            method: Method::Qsa,
        }
    }

    /// Choose `method` for a new contact with `law` (QSA fitted with `segments` segments over
    /// `[0, y_ref]`, m) and start it from the compressions `(y^{n−1}, y^n)` (m). Never allocates.
    /// Returns `false`, leaving the previous choice, if the fit is impossible.
    pub fn restart(
        &mut self,
        method: Method,
        law: PowerLaw,
        y_ref: f64,
        segments: usize,
        (y_prev, y_now): (f64, f64),
    ) -> bool {
        match method {
            Method::Qsa => {
                if self.qsa.spline_mut().refit(law, y_ref, segments).is_err() {
                    return false;
                }
                self.qsa.start(y_prev, y_now);
            }
            Method::Imp => {
                self.imp.set_law(law);
                self.imp.start(y_prev, y_now);
            }
            Method::Exp => {
                self.exp.set_law(law);
                self.exp.start(y_prev, y_now);
            }
        }
        self.method = method;
        true
    }

    /// Start the solver in use afresh, at rest at the compression `y` (m) holding the force
    /// magnitude `held` (N) that [`static_slope`](Self::static_slope) gave there, its law and fit
    /// kept: QSA and IMP from the compressions alone, EXP with ψ to match
    /// ([`ExplicitSolver::start_still`]).
    pub fn start_still(&mut self, y: f64, held: f64) {
        match self.method {
            Method::Qsa => self.qsa.start(y, y),
            Method::Imp => self.imp.start(y, y),
            Method::Exp => self.exp.start_still(y, held),
        }
    }

    /// The magnitude `V̂'(y)` (N) of the force the solver in use holds at a still compression
    /// `y` (m) where the contact meets the compliance `q_N` (m/N) at the Nyquist rate
    /// ([`SlideCore::nyquist_compliance`](crate::scene::SlideCore::nyquist_compliance)): the
    /// spline's slope for QSA, the law's `κ[y]₊^α` for IMP, and for EXP the law's where its
    /// explicit gradient holds that still, else the most it holds stably
    /// ([`ExplicitSolver::still_force`]).
    pub fn static_slope(&self, y: f64, nyquist: f64) -> f64 {
        match self.method {
            Method::Qsa => self.qsa.spline().slope(y),
            Method::Imp => self.imp.law().potential_slope(y),
            Method::Exp => self.exp.still_force(y, nyquist),
        }
    }

    /// The contact's share of the energy (J) of the solver in use, given `y^{n+1}` and `y^n` (m).
    pub fn stored_energy(&self, y_next: f64, y_now: f64) -> f64 {
        match self.method {
            Method::Qsa => self.qsa.stored_energy(y_next, y_now),
            Method::Imp => self.imp.stored_energy(y_next, y_now),
            Method::Exp => self.exp.stored_energy(y_next, y_now),
        }
    }
}
