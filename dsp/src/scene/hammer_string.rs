//! A piano hammer striking a modal stiff string (seed §5, docs/physics.md §6.4).
//!
//! The string runs from the agraffe at `x = 0`, near which the hammer strikes (`x_h` is measured
//! from there: 0.12 L for the C4 of Chaigne and Askenfelt), to the bridge at `x = L`, whose
//! transverse force is the default output (what drives a soundboard).
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
//! and no time-varying vectors: the per-sample loop is one pass over the modes (the string update,
//! which also projects the next step's `z̃` on `h`: [`ModalString::advance_projecting`]) and one
//! solve.
//!
//! Energy (docs/physics.md §6.3): `H^{n+1/2}` = string + `½ m_h ((w^{n+1} − w^n)/Δt)²` + the solver's
//! contact term; `H^{n+1/2} − H^{n−1/2} = −Δt (δ_t·ũ)ᵀ R̂ (δ_t·ũ)` exactly.
//!
//! # Retiring the hammer
//!
//! Once the hammer has rebounded it flies away at constant speed, and the string alone can never
//! reach it again: with the string's energy `H` (which only decreases once it is free),
//! Cauchy–Schwarz on `ũ^n = μ_t+ũ − ½δ_t+ũ` bounds the string at the striking point,
//!
//! ```text
//! |hᵀũ^n| ≤ √(2H)·(√(Σ h_i²/K̂_i) + ½Δt·√(Σ h_i²/m̃))  =: √(2H)·ρ_h
//! ```
//!
//! so when the hammer moves away with `w^n > √(2H)·ρ_h` the compression stays negative for ever
//! and every later force is zero. The real-time path ([`HammerCore::process_output`]) checks this
//! every [`RETIRE_CHECK`] steps (counted from the strike, so the same in any split into calls)
//! and then steps the string on its own ([`ModalString::free_steps`], the homogeneous recursion
//! `ũ^{n+1} = 2P ũ^n − Q ũ^{n−1}`): no contact projection, no solve. The harness path keeps
//! every step whole (`ũ^{n−1} − z̃` with a zero force, the same recursion rounded differently),
//! so its frames still carry the compression, and its output agrees with the real-time path's to
//! rounding.

use crate::contact::{ContactProblem, ContactSolver};
use crate::exciter::{Hammer, HammerParams};
use crate::scene::{Frame, Scene};
use crate::string::{ModalString, StringParams};

/// Steps between checks whether the hammer is out of the string's reach for good.
pub const RETIRE_CHECK: u32 = 64;

/// Which signal the scene outputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum OutputKind {
    /// String displacement at the pickup (m).
    Displacement,
    /// String velocity at the pickup (m/s), `(u^{n+1} − u^n)/Δt`.
    Velocity,
    /// Transverse force on the bridge (N) at `x = L`, `Σ (−1)^{i+1}(Tβ_i + EIβ_i³) ũ_i`: the far
    /// end from the nut or agraffe at `x = 0`, from which strike, slide, finger and pickup
    /// positions are measured.
    BridgeForce,
}

impl OutputKind {
    /// The output sample of step n from the pickup's projections `now` of `ũ^n` and `next` of
    /// `ũ^{n+1}`, with time step `dt` (s): the difference quotient for the velocity, else `now`.
    #[inline]
    pub fn sample(self, now: f64, next: f64, dt: f64) -> f64 {
        match self {
            OutputKind::Velocity => (next - now) / dt,
            OutputKind::Displacement | OutputKind::BridgeForce => now,
        }
    }
}

/// Where and what the scene listens to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pickup {
    /// The signal.
    pub kind: OutputKind,
    /// Pickup position as a fraction of the length, in (0, 1) (unused for the bridge force).
    pub position: f64,
    /// Length of string the pickup senses (m), centred on its position: 0 for a point, about
    /// 25 mm for a guitar's single-coil pickup (unused for the bridge force).
    pub aperture: f64,
}

impl Pickup {
    /// A point pickup of `kind` at `position` (fraction of the length).
    pub const fn point(kind: OutputKind, position: f64) -> Self {
        Self { kind, position, aperture: 0.0 }
    }

    /// Write the output weights of this pickup on `string` into `out` (a vector fitted to the
    /// string): for displacement and velocity, the mode shapes `φ_i(x_p)` at the pickup
    /// `x_p = position·L` averaged over the aperture `w`, `sin(β_i x_p)·sinc(β_i w/2)`; the bridge
    /// weights `(−1)^{i+1}(Tβ_i + EIβ_i³)` at `x = L` for the bridge force.
    pub fn weights(&self, string: &ModalString, out: &mut [f64]) {
        match self.kind {
            OutputKind::Displacement | OutputKind::Velocity => {
                string.mode_shapes(self.position * string.params().length, out);
                if self.aperture > 0.0 {
                    for (w, &beta) in out.iter_mut().zip(string.wavenumbers()) {
                        let half = 0.5 * beta * self.aperture;
                        *w *= half.sin() / half;
                    }
                }
            }
            OutputKind::BridgeForce => string.bridge_weights(true, out),
        }
    }
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

    /// Whether the real-time path has retired the hammer (see the module docs).
    pub fn retired(&self) -> bool {
        self.core.retired()
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
    /// `ρ_h` (m/√J): the string's reach at the striking point per √(2H).
    reach: f64,
    /// Whether the hammer is out of the string's reach for good (see the module docs).
    retired: bool,
    /// Steps since the strike, modulo [`RETIRE_CHECK`].
    since_check: u32,
    /// `y^{n−1}`, `y^n` (m).
    y_prev: f64,
    y_now: f64,
    /// Output projection of `ũ^n`.
    out_now: f64,
    /// Energy dissipated so far (J).
    losses: f64,
    /// Contact force of the latest step (N).
    last_force: f64,
    /// `hᵀz̃` of the coming step when the last step's string pass already projected it.
    next_hz: Option<f64>,
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
            reach: f64::INFINITY,
            retired: false,
            since_check: 0,
            y_prev: 0.0,
            y_now: 0.0,
            out_now: 0.0,
            losses: 0.0,
            last_force: 0.0,
            next_hz: None,
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
        pickup.weights(s, &mut self.pickup);
        self.kind = pickup.kind;
        self.q = s.project(&self.shape, &self.gain) + self.hammer.coupling();
        self.reach = self.reach_of_string();
        self.measure();
    }

    /// Recompute the compressions and the output from the state; the hammer is back in play.
    fn measure(&mut self) {
        let (prev, now) = self.string.project_state(&self.shape);
        self.y_prev = prev - self.hammer.previous();
        self.y_now = now - self.hammer.position();
        self.out_now = self.string.project_state(&self.pickup).1;
        self.retired = false;
        self.since_check = 0;
        self.next_hz = None;
    }

    /// Whether the hammer moves away and is beyond the reach of the string's energy: then no
    /// force can ever act again (see the module docs).
    fn out_of_reach(&self) -> bool {
        self.hammer.velocity() > 0.0
            && self.y_now < 0.0
            && self.y_prev < 0.0
            && self.hammer.position() > self.reach * (2.0 * self.string.energy()).sqrt()
    }

    /// Whether the hammer has been retired (see the module docs).
    pub fn retired(&self) -> bool {
        self.retired
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

    /// Throw the hammer again, moving in at `velocity` with `mass`, `gap` beyond where the string
    /// is under it (zero for a string at rest): the string keeps its motion, and the felt meets it
    /// wherever it swings, at the relative speed of the two. The felt is clear of the string at
    /// both of the steps a solver starts from: `w^n − gap` is the higher of `hᵀũ^n` and
    /// `hᵀũ^{n−1} − vΔt`, so that `w^{n−1} = w^n + vΔt` is above `hᵀũ^{n−1}` too. Restart the
    /// solver with [`compressions`](Self::compressions) afterwards.
    pub fn strike(&mut self, hammer: &HammerParams) {
        let old_coupling = self.hammer.coupling();
        let (before, now) = self.string.project_state(&self.shape);
        let under = now.max(before - hammer.velocity * self.dt);
        self.hammer = Hammer::above(under, hammer, self.string.sample_rate());
        self.q += self.hammer.coupling() - old_coupling;
        self.measure();
    }

    /// After the string's coefficients changed ([`ModalString::set_extra_decay`]): the contact
    /// gains `C∘h`, the coupling `q` and the hammer's reach follow them; the state and the
    /// compressions stay, and a retired hammer is judged again with the new reach.
    pub fn refresh_coupling(&mut self) {
        let s = &self.string;
        for ((g, h), c) in self.gain.iter_mut().zip(&self.shape).zip(s.input_gains()) {
            *g = h * c;
        }
        self.q = s.project(&self.shape, &self.gain) + self.hammer.coupling();
        self.reach = self.reach_of_string();
        self.next_hz = None;
        if self.retired {
            self.measure();
            self.retired = self.out_of_reach();
        }
    }

    /// How far the string's motion under the hammer can reach per `√(2H)` (m/√J), with the
    /// string's current coefficients (see the module docs).
    fn reach_of_string(&self) -> f64 {
        let s = &self.string;
        let (mut by_stiffness, mut squares) = (0.0, 0.0);
        for (h, k) in self.shape.iter().zip(s.stiffness()) {
            by_stiffness += h * h / k;
            squares += h * h;
        }
        let reach = by_stiffness.sqrt() + 0.5 / s.sample_rate() * (squares / s.modal_mass()).sqrt();
        if reach.is_finite() { reach } else { f64::INFINITY }
    }

    /// The string's displacement under the hammer `hᵀũ^n` (m) and its velocity there
    /// `hᵀ(ũ^n − ũ^{n−1})/Δt` (m/s).
    pub fn string_under_hammer(&self) -> (f64, f64) {
        let (prev, now) = self.string.project_state(&self.shape);
        (now, (now - prev) / self.dt)
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
        self.next_hz = None;
        &mut self.string
    }

    /// String and hammer energy of the current state (J), without the contact term.
    pub fn energy(&self) -> f64 {
        self.string.energy() + self.hammer.energy()
    }

    /// What a monitor shows: `(compression y^n (m), latest contact force (N))`.
    pub fn contact(&self) -> (f64, f64) {
        if self.retired {
            (self.string.project_state(&self.shape).1 - self.hammer.position(), 0.0)
        } else {
            (self.y_now, self.last_force)
        }
    }

    /// Whether the felt is touching or about to: compression above zero now or one step back.
    pub fn in_contact(&self) -> bool {
        !self.retired && (self.y_now > 0.0 || self.y_prev > 0.0)
    }

    /// One step with `solver`. A hammer retired by [`process_output`](Self::process_output) is
    /// back in play: its compressions are measured again from the state, which the free steps
    /// moved on without them.
    #[inline]
    pub fn step<S: ContactSolver, const MONITOR: bool>(&mut self, solver: &mut S) -> Frame {
        if self.retired {
            self.measure();
        }
        let hz = match self.next_hz.take() {
            Some(hz) => hz,
            None => self.string.history([&self.shape])[0],
        };
        let z_h = self.hammer.history();
        let problem = ContactProblem { y_prev: self.y_prev, y_now: self.y_now, z: hz - z_h, q: self.q };
        let solution = solver.solve(&problem);
        let y_next = self.y_prev + solution.s;
        self.last_force = solution.force;
        let forces = [(&self.gain[..], solution.force)];
        let (out_next, string_energy) = if MONITOR {
            self.string.advance_monitored(forces, &self.pickup)
        } else {
            let (out_next, next) = self.string.advance_projecting(forces, &self.pickup, [&self.shape]);
            self.next_hz = next.map(|[hz]| hz);
            (out_next, Default::default())
        };
        let w_now = self.hammer.position();
        self.hammer.advance(solution.force);
        let output = self.kind.sample(self.out_now, out_next, self.dt);
        let mut frame = Frame {
            output,
            displacement: w_now,
            velocity: self.hammer.velocity(),
            compression: self.y_now,
            force: solution.force,
            energy: 0.0,
            losses: 0.0,
            control_work: 0.0,
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

    /// Advance `out.len()` samples with `solver`, writing only the output; once the hammer is
    /// out of reach for good, without it (see the module docs).
    pub fn process_output<S: ContactSolver>(&mut self, solver: &mut S, out: &mut [f64]) {
        let mut done = 0;
        while done < out.len() && !self.retired {
            out[done] = self.step::<S, false>(solver).output;
            done += 1;
            self.since_check += 1;
            if self.since_check == RETIRE_CHECK {
                self.since_check = 0;
                self.retired = self.out_of_reach();
            }
        }
        let free = &mut out[done..];
        if free.is_empty() {
            return;
        }
        self.last_force = 0.0;
        self.string.free_steps(&self.pickup, free);
        for _ in 0..free.len() {
            self.hammer.advance(0.0);
        }
        // `free` holds the projections of ũ^{n+1}, ũ^{n+2}, …; turn them into the outputs.
        let mut before = self.out_now;
        for o in free {
            let next = *o;
            *o = self.kind.sample(before, next, self.dt);
            before = next;
        }
        self.out_now = before;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::{PowerLaw, QsaSolver, QuadSpline};
    use crate::preset::chaigne_askenfelt_c4;

    /// The paper's C4 struck at 3.5 m/s at 48 kHz, with its bridge force as the output, solved by
    /// QSA.
    fn c4_scene() -> HammerString<QsaSolver> {
        let c4 = chaigne_askenfelt_c4();
        let hammer = HammerParams { mass: c4.hammer_mass, velocity: 3.5, position: c4.strike_position, gap: 2e-4 };
        let params =
            HammerStringParams { string: c4.string, hammer, pickup: Pickup::point(OutputKind::BridgeForce, 0.5) };
        let law = PowerLaw::new(c4.kappa, c4.alpha).unwrap();
        let y_ref = law.compression_at_energy(hammer.kinetic_energy());
        let solver = QsaSolver::new(QuadSpline::new(law, y_ref, 6).unwrap());
        HammerString::new(ModalString::new(c4.string, 48_000.0).unwrap(), &params, solver)
    }

    /// Frames stepped after the real-time path retired the hammer go on from where that path
    /// left the string: ten frames, 0.5 s of the real-time path (the hammer retired, between
    /// two of the string's flushes), then 0.1 s of frames gives what 0.1 s more of the real-time
    /// path gives, to 1e-9 of the peak.
    #[test]
    fn frames_after_the_hammer_retired_go_on_from_the_real_time_path() {
        let mut scene = c4_scene();
        scene.process(&mut [Frame::default(); 10]);
        let mut head = vec![0.0; 24_000];
        scene.process_output(&mut head);
        assert!(scene.core.retired() && scene.core.next_hz.is_some());
        let peak = head.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let worst = crate::scene::frames_against_the_real_time_path(&scene, 4_800);
        println!("peak {peak:.3} N, worst difference {worst:.2e} N");
        assert!(worst < 1e-9 * peak, "{worst:e} of {peak}");
    }

    /// After the string's coefficients change (a damper of 2,000 1/s on every mode), the
    /// hammer's reach and coupling are what placing the hammer afresh on the damped string gives,
    /// bit for bit.
    #[test]
    fn a_refreshed_coupling_is_the_coupling_placed_afresh() {
        let mut core = c4_scene().core;
        let extra = vec![2_000.0; core.string().modes()];
        core.string_mut().set_extra_decay(&extra);
        core.refresh_coupling();
        let mut fresh = core.clone();
        let c4 = chaigne_askenfelt_c4();
        fresh.place(c4.strike_position, Pickup::point(OutputKind::BridgeForce, 0.5));
        assert_eq!((core.reach.to_bits(), core.q.to_bits()), (fresh.reach.to_bits(), fresh.q.to_bits()));
    }

    /// A pickup of aperture `w` hears each mode as the mean of what point pickups across the
    /// aperture hear (to 1e-6 of the largest weight, against a 4,001-point trapezoidal mean); a
    /// mode one wavelength long over the aperture (`β_i w = 2π`) is not heard at all (to 1e-12);
    /// and the bridge force ignores the aperture.
    #[test]
    fn a_wide_pickup_averages_out_the_modes_it_spans() {
        let params = crate::preset::slide_guitar().string;
        let string = ModalString::band_limited(params, 48_000.0, 20_000.0).unwrap();
        let n = string.padded_len();
        // The aperture of exactly one wavelength of mode 40 (β = 40π/L).
        let aperture = 2.0 * params.length / 40.0;
        let (mut point, mut wide) = (vec![0.0; n], vec![0.0; n]);
        Pickup::point(OutputKind::Velocity, 0.83).weights(&string, &mut point);
        Pickup { kind: OutputKind::Velocity, position: 0.83, aperture }.weights(&string, &mut wide);
        let largest = point.iter().fold(0.0f64, |m, w| m.max(w.abs()));
        let k = 4000;
        let mut mean = vec![0.0; n];
        let mut at = vec![0.0; n];
        for j in 0..=k {
            let x = 0.83 + aperture / params.length * (j as f64 / k as f64 - 0.5);
            Pickup::point(OutputKind::Velocity, x).weights(&string, &mut at);
            let weight = if j == 0 || j == k { 0.5 } else { 1.0 } / k as f64;
            mean.iter_mut().zip(&at).for_each(|(m, a)| *m += weight * a);
        }
        let worst = wide.iter().zip(&mean).map(|(w, m)| (w - m).abs()).fold(0.0, f64::max);
        println!("worst against the mean of point pickups {worst:.1e}; mode 40 {:.1e}", wide[39]);
        assert!(worst < 1e-6 * largest, "{worst:e}");
        assert!(wide[39].abs() < 1e-12 * largest);
        let (mut bridge, mut bridge_wide) = (vec![0.0; n], vec![0.0; n]);
        Pickup::point(OutputKind::BridgeForce, 0.83).weights(&string, &mut bridge);
        Pickup { kind: OutputKind::BridgeForce, position: 0.83, aperture }.weights(&string, &mut bridge_wide);
        assert_eq!(bridge, bridge_wide);
    }
}
