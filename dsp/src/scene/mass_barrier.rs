//! A mass striking a rigid barrier (seed §4).
//!
//! The mass `m` (kg) at displacement `u` (m) meets a barrier at `u_b` (m); the compression is
//! `y = u − u_b` and the contact force `F(y) ≤ 0` acts on the mass:
//!
//! ```text
//! m δ_tt u = F   ⇒   s + z − q·F = 0,   s = y^{n+1} − y^{n−1},   z = 2(y^{n−1} − y^n),   q = Δt²/m
//! ```
//!
//! The state is kept as the compression relative to the barrier, `y^n`, and its increment
//! `δ^n = y^n − y^{n−1}`: `y` is never the difference of two large positions (docs/physics.md §10.6), and
//! `z = −2δ^n` and the velocity `δ^{n+1}/Δt = (s − δ^n)/Δt` keep full precision however far the
//! mass travels. The numerical energy (docs/physics.md §2)
//!
//! ```text
//! H^{n+1/2} = ½ m ((y^{n+1} − y^n)/Δt)² + (contact term of the solver)
//! ```
//!
//! is conserved to rounding by all three solvers.
//!
//! Time indexing: the initial displacement `u0` is `u^0` and the initial velocity `v0` gives
//! `u^{−1} = u0 − v0·Δt`, so the first step computes `F^0` and `u^1`.

use crate::contact::{ContactProblem, ContactSolver};
use crate::scene::{Frame, Scene};

/// Parameters of the mass and barrier.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MassBarrierParams {
    /// Mass `m` (kg), > 0.
    pub mass: f64,
    /// Initial displacement `u^0` (m).
    pub u0: f64,
    /// Initial velocity (m/s); positive moves towards a barrier above the mass.
    pub v0: f64,
    /// Barrier position `u_b` (m).
    pub barrier: f64,
}

impl MassBarrierParams {
    /// The largest energy the scene can put into the contact: all kinetic energy, `½ m v0²` (J).
    pub fn max_contact_energy(&self) -> f64 {
        0.5 * self.mass * self.v0 * self.v0
    }
}

/// The mass–barrier scene, generic over its contact solver.
#[derive(Debug, Clone)]
pub struct MassBarrier<S> {
    solver: S,
    params: MassBarrierParams,
    sample_rate: f64,
    dt: f64,
    /// `q = Δt²/m` (m/N).
    q: f64,
    /// `y^n` (m).
    y_now: f64,
    /// `δ^n = y^n − y^{n−1}` (m).
    step: f64,
    initial_energy: f64,
}

impl<S: ContactSolver> MassBarrier<S> {
    /// A scene at `sample_rate` (Hz). The parameters must already be validated
    /// (finite, `mass > 0`, `sample_rate > 0`).
    pub fn new(params: MassBarrierParams, sample_rate: f64, mut solver: S) -> Self {
        let dt = 1.0 / sample_rate;
        let y_now = params.u0 - params.barrier;
        let step = params.v0 * dt;
        let y_prev = y_now - step;
        solver.start(y_prev, y_now);
        let kinetic = 0.5 * params.mass * params.v0 * params.v0;
        let initial_energy = kinetic + solver.stored_energy(y_now, y_prev);
        Self { solver, params, sample_rate, dt, q: dt * dt / params.mass, y_now, step, initial_energy }
    }

    /// The contact solver.
    pub fn solver(&self) -> &S {
        &self.solver
    }

    #[inline]
    fn step(&mut self) -> Frame {
        let problem =
            ContactProblem { y_prev: self.y_now - self.step, y_now: self.y_now, z: -2.0 * self.step, q: self.q };
        let solution = self.solver.solve(&problem);
        let step = solution.s - self.step;
        let y_next = self.y_now + step;
        let velocity = step / self.dt;
        let energy = 0.5 * self.params.mass * velocity * velocity + self.solver.stored_energy(y_next, self.y_now);
        let frame = Frame {
            output: solution.force,
            displacement: self.y_now + self.params.barrier,
            velocity,
            compression: self.y_now,
            force: solution.force,
            energy,
            losses: 0.0,
            control_work: 0.0,
            work: self.solver.last_work(),
        };
        self.y_now = y_next;
        self.step = step;
        frame
    }
}

impl<S: ContactSolver> Scene for MassBarrier<S> {
    fn sample_rate(&self) -> f64 {
        self.sample_rate
    }

    fn initial_energy(&self) -> f64 {
        self.initial_energy
    }

    fn process(&mut self, frames: &mut [Frame]) {
        for frame in frames {
            *frame = self.step();
        }
    }

    fn process_output(&mut self, out: &mut [f64]) {
        for o in out {
            *o = self.step().output;
        }
    }
}
