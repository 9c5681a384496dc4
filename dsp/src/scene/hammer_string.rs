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
    core: HammerCore,
    solver: S,
    initial_energy: f64,
}

impl<S: ContactSolver> HammerString<S> {
    /// Prepare the scene: the string at rest, the hammer `gap` away and moving in.
    /// `string` must be prepared at the scene's sample rate.
    pub fn new(string: ModalString, params: &HammerStringParams, mut solver: S) -> Self {
        let core = HammerCore::new(string, params);
        let (y_prev, y_now) = core.compressions();
        solver.start(y_prev, y_now);
        let initial_energy = core.energy() + solver.stored_energy(y_now, y_prev);
        Self { core, solver, initial_energy }
    }

    /// The string.
    pub fn string(&self) -> &ModalString {
        &self.core.string
    }

    /// The contact solver.
    pub fn solver(&self) -> &S {
        &self.solver
    }

    /// The coupling `q = hᵀCh + ξ_h` (m/N).
    pub fn coupling(&self) -> f64 {
        self.core.q
    }
}

impl<S: ContactSolver> Scene for HammerString<S> {
    fn sample_rate(&self) -> f64 {
        self.core.string.sample_rate()
    }

    fn initial_energy(&self) -> f64 {
        self.initial_energy
    }

    fn process(&mut self, frames: &mut [Frame]) {
        for frame in frames {
            *frame = self.core.step::<S, true>(&mut self.solver);
        }
    }

    fn process_output(&mut self, out: &mut [f64]) {
        self.core.process_output(&mut self.solver, out);
    }
}

/// Everything of a hammer–string scene except the solver: string, hammer, contact and output
/// vectors. An instrument voice keeps one core and one solver of each kind, and picks the solver
/// once per block; [`retune`](Self::retune) and [`strike`](Self::strike) reuse the core for a new
/// note without allocating.
#[derive(Debug, Clone)]
pub struct HammerCore {
    string: ModalString,
    hammer: Hammer,
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
    /// Contact force of the latest step (N).
    last_force: f64,
    dt: f64,
}

impl HammerCore {
    /// A core around `string` (prepared at the scene's sample rate), the hammer `gap` away and
    /// moving in. The vectors get room for the string's capacity.
    pub fn new(string: ModalString, params: &HammerStringParams) -> Self {
        let fs = string.sample_rate();
        let hammer = Hammer::new(&params.hammer, fs);
        let mut core = Self {
            shape: string.vector(),
            gain: string.vector(),
            pickup: string.vector(),
            kind: params.pickup.kind,
            q: 0.0,
            y_prev: 0.0,
            y_now: 0.0,
            out_now: 0.0,
            losses: 0.0,
            last_force: 0.0,
            dt: 1.0 / fs,
            string,
            hammer,
        };
        core.place(params.hammer.position, params.pickup);
        core
    }

    /// Compute the contact and output vectors, `q` and the compressions for the current string.
    fn place(&mut self, hammer_position: f64, pickup: Pickup) {
        let s = &self.string;
        let length = s.params().length;
        for v in [&mut self.shape, &mut self.gain, &mut self.pickup] {
            s.fit_vector(v);
        }
        s.mode_shapes(hammer_position * length, &mut self.shape);
        for ((g, h), c) in self.gain.iter_mut().zip(&self.shape).zip(s.input_gains()) {
            *g = h * c;
        }
        match pickup.kind {
            OutputKind::Displacement | OutputKind::Velocity => {
                s.mode_shapes(pickup.position * length, &mut self.pickup)
            }
            OutputKind::BridgeForce => s.bridge_weights(false, &mut self.pickup),
        }
        self.kind = pickup.kind;
        self.q = dot(&self.shape, &self.gain) + self.hammer.coupling();
        self.measure();
    }

    /// Recompute the compressions and the output from the state.
    fn measure(&mut self) {
        self.y_prev = dot(self.string.previous_state(), &self.shape) - self.hammer.previous();
        self.y_now = dot(self.string.state(), &self.shape) - self.hammer.position();
        self.out_now = dot(self.string.state(), &self.pickup);
    }

    /// Re-prepare for another string (at rest) and striking point without allocating; see
    /// [`ModalString::retune`]. The hammer is left where it is: follow with [`strike`](Self::strike).
    pub fn retune(
        &mut self,
        string: StringParams,
        max_frequency: f64,
        hammer_position: f64,
        pickup: Pickup,
    ) -> Result<(), crate::string::StringError> {
        let fs = self.string.sample_rate();
        self.string.retune(string, fs, max_frequency)?;
        self.losses = 0.0;
        self.place(hammer_position, pickup);
        Ok(())
    }

    /// Throw the hammer again: `gap` away and moving in at `velocity`, with `mass`; the string
    /// keeps its motion. Restart the solver with [`compressions`](Self::compressions) afterwards.
    pub fn strike(&mut self, hammer: &HammerParams) {
        let old_coupling = self.hammer.coupling();
        self.hammer = Hammer::new(hammer, self.string.sample_rate());
        self.q += self.hammer.coupling() - old_coupling;
        self.measure();
    }

    /// `(y^{n−1}, y^n)` (m), to start a solver from.
    pub fn compressions(&self) -> (f64, f64) {
        (self.y_prev, self.y_now)
    }

    /// The string.
    pub fn string(&self) -> &ModalString {
        &self.string
    }

    /// The string, to damp it.
    pub fn string_mut(&mut self) -> &mut ModalString {
        &mut self.string
    }

    /// String and hammer energy of the current state (J), without the contact term.
    pub fn energy(&self) -> f64 {
        self.string.energy() + self.hammer.energy()
    }

    /// What a monitor shows: `(compression y^n (m), latest contact force (N))`.
    pub fn contact(&self) -> (f64, f64) {
        (self.y_now, self.last_force)
    }

    /// Whether the felt is touching or about to: compression above zero now or one step back.
    pub fn in_contact(&self) -> bool {
        self.y_now > 0.0 || self.y_prev > 0.0
    }

    /// One step with `solver`.
    #[inline]
    pub fn step<S: ContactSolver, const MONITOR: bool>(&mut self, solver: &mut S) -> Frame {
        let [hz] = self.string.history([&self.shape]);
        let z_h = self.hammer.history();
        let problem = ContactProblem { y_prev: self.y_prev, y_now: self.y_now, z: hz - z_h, q: self.q };
        let solution = solver.solve(&problem);
        let y_next = self.y_prev + solution.s;
        self.last_force = solution.force;
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
            work: solver.last_work(),
        };
        if MONITOR {
            self.losses += string_energy.dissipated;
            frame.energy = string_energy.stored + self.hammer.energy() + solver.stored_energy(y_next, self.y_now);
            frame.losses = self.losses;
        }
        self.out_now = out_next;
        self.y_prev = self.y_now;
        self.y_now = y_next;
        frame
    }

    /// Advance `out.len()` samples with `solver`, writing only the output.
    pub fn process_output<S: ContactSolver>(&mut self, solver: &mut S, out: &mut [f64]) {
        for o in out {
            *o = self.step::<S, false>(solver).output;
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
