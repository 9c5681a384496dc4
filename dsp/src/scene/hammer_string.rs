//! A piano hammer striking a modal stiff string (seed §5, physics §6.4).
//!
//! With the mode shapes at the striking point `h_i = sin(β_i x_h)`, the compression is
//! `y = hᵀũ − w` and one step reduces to the common scalar problem (seed eq. 42):
//!
//! ```text
//! s + (hᵀz̃ − z_h) − (hᵀC h + ξ_h)·F^n = 0
//! ```
//!
//! `q = hᵀCh + ξ_h` (m/N) is constant while the striking point is fixed, so it is computed once.
//! After the solve the string takes `C∘h·F` and the hammer `−F`. A strike has no fingers, no slide
//! and no time-varying vectors: the per-sample loop is two passes over the modes and one solve.
//!
//! Energy (physics §6.3): `H^{n+1/2}` = string + `½ m_h ((w^{n+1} − w^n)/Δt)²` + the solver's
//! contact term; `H^{n+1/2} − H^{n−1/2} = −Δt (δ_t·ũ)ᵀ R̂ (δ_t·ũ)` exactly.

use crate::contact::{ContactProblem, ContactSolver};
use crate::exciter::{Hammer, HammerParams};
use crate::scene::{Frame, Scene};
use crate::string::{ModalString, StringParams};

/// Which signal the scene outputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum OutputKind {
    /// String displacement at the pickup (m).
    Displacement,
    /// String velocity at the pickup (m/s), `(u^{n+1} − u^n)/Δt`.
    Velocity,
    /// Transverse force on the bridge (N): at `x = 0` for the hammer–string scene,
    /// `Σ (Tβ_i + EIβ_i³) ũ_i`; at `x = L` for the slide–string scene.
    BridgeForce,
}

/// Where and what the scene listens to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pickup {
    /// The signal.
    pub kind: OutputKind,
    /// Pickup position as a fraction of the length, in (0, 1) (unused for the bridge force).
    pub position: f64,
}

/// Parameters of a hammer–string scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HammerStringParams {
    /// The string.
    pub string: StringParams,
    /// The hammer.
    pub hammer: HammerParams,
    /// The output.
    pub pickup: Pickup,
}

/// The hammer–string scene, generic over its contact solver.
#[derive(Debug, Clone)]
pub struct HammerString<S> {
    string: ModalString,
    hammer: Hammer,
    solver: S,
    /// `h_i = sin(β_i x_h)` (dimensionless).
    shape: Vec<f64>,
    /// `C_i h_i` (m/N).
    gain: Vec<f64>,
    /// Output weights on `ũ`.
    pickup: Vec<f64>,
    kind: OutputKind,
    /// `q = hᵀCh + ξ_h` (m/N).
    q: f64,
    /// `y^{n−1}`, `y^n` (m).
    y_prev: f64,
    y_now: f64,
    /// Output projection of `ũ^n`.
    out_now: f64,
    /// Energy dissipated so far (J).
    losses: f64,
    initial_energy: f64,
    dt: f64,
}

impl<S: ContactSolver> HammerString<S> {
    /// Prepare the scene: the string at rest, the hammer `gap` away and moving in.
    /// `string` must be prepared at the scene's sample rate.
    pub fn new(string: ModalString, params: &HammerStringParams, mut solver: S) -> Self {
        let fs = string.sample_rate();
        let length = string.params().length;
        let mut shape = string.vector();
        string.mode_shapes(params.hammer.position * length, &mut shape);
        let gain: Vec<f64> = shape.iter().zip(string.input_gains()).map(|(h, c)| h * c).collect();
        let mut pickup = string.vector();
        match params.pickup.kind {
            OutputKind::Displacement | OutputKind::Velocity => {
                string.mode_shapes(params.pickup.position * length, &mut pickup)
            }
            OutputKind::BridgeForce => string.bridge_weights(false, &mut pickup),
        }
        let hammer = Hammer::new(&params.hammer, fs);
        let q = shape.iter().zip(&gain).map(|(h, g)| h * g).sum::<f64>() + hammer.coupling();
        let project = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(a, b)| a * b).sum::<f64>();
        let y_prev = project(string.previous_state(), &shape) - hammer.previous();
        let y_now = project(string.state(), &shape) - hammer.position();
        solver.start(y_prev, y_now);
        let out_now = project(string.state(), &pickup);
        let initial_energy = string.energy() + hammer.energy() + solver.stored_energy(y_now, y_prev);
        Self {
            string,
            hammer,
            solver,
            shape,
            gain,
            pickup,
            kind: params.pickup.kind,
            q,
            y_prev,
            y_now,
            out_now,
            losses: 0.0,
            initial_energy,
            dt: 1.0 / fs,
        }
    }

    /// The string.
    pub fn string(&self) -> &ModalString {
        &self.string
    }

    /// The contact solver.
    pub fn solver(&self) -> &S {
        &self.solver
    }

    /// The coupling `q = hᵀCh + ξ_h` (m/N).
    pub fn coupling(&self) -> f64 {
        self.q
    }

    #[inline]
    fn step<const MONITOR: bool>(&mut self) -> Frame {
        let [hz] = self.string.history([&self.shape]);
        let z_h = self.hammer.history();
        let problem = ContactProblem { y_prev: self.y_prev, y_now: self.y_now, z: hz - z_h, q: self.q };
        let solution = self.solver.solve(&problem);
        let y_next = self.y_prev + solution.s;
        let forces = [(&self.gain[..], solution.force)];
        let (out_next, string_energy) = if MONITOR {
            self.string.advance_monitored(forces, &self.pickup)
        } else {
            (self.string.advance(forces, &self.pickup), Default::default())
        };
        let w_now = self.hammer.position();
        self.hammer.advance(solution.force);
        let output = match self.kind {
            OutputKind::Velocity => (out_next - self.out_now) / self.dt,
            OutputKind::Displacement | OutputKind::BridgeForce => self.out_now,
        };
        let mut frame = Frame {
            output,
            displacement: w_now,
            velocity: self.hammer.velocity(),
            compression: self.y_now,
            force: solution.force,
            energy: 0.0,
            losses: 0.0,
            work: self.solver.last_work(),
        };
        if MONITOR {
            self.losses += string_energy.dissipated;
            frame.energy = string_energy.stored + self.hammer.energy() + self.solver.stored_energy(y_next, self.y_now);
            frame.losses = self.losses;
        }
        self.out_now = out_next;
        self.y_prev = self.y_now;
        self.y_now = y_next;
        frame
    }
}

impl<S: ContactSolver> Scene for HammerString<S> {
    fn sample_rate(&self) -> f64 {
        self.string.sample_rate()
    }

    fn initial_energy(&self) -> f64 {
        self.initial_energy
    }

    fn process(&mut self, frames: &mut [Frame]) {
        for frame in frames {
            *frame = self.step::<true>();
        }
    }

    fn process_output(&mut self, out: &mut [f64]) {
        for o in out {
            *o = self.step::<false>().output;
        }
    }
}
