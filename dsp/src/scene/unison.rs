//! One piano key: a hammer striking a unison of one to three strings that end on a moving bridge
//! (docs/physics.md §11).
//!
//! # Strings on a moving bridge
//!
//! Each string `s` runs from the agraffe at `x = 0` to the bridge at `x = L`, where it moves with
//! the bridge, `u_s(L, t) = b(t)`. Split off the bridge's motion, `u_s = v_s + b·x/L`: the line
//! `x/L` is a static shape of the stiff string (no curvature, simply supported), so `v_s` is a
//! string fixed at both ends, modal as before (`v_s = Σ ṽ_i sin β_i x`). The kinetic and
//! potential energies of the string become
//!
//! ```text
//! T_s = ½m̃‖ṽ̇‖² + ḃ gᵀṽ̇ + ½m_L ḃ²,   V_s = ½Σ K_i ṽ_i² + ½k_L b²
//! g_i = ρA(−1)^{i+1}/β_i (kg),   m_L = ρAL/3 (kg),   k_L = T/L (N/m)
//! ```
//!
//! (`∫(x/L) sin β_i x dx = (−1)^{i+1}/β_i`; the cross term of the potential vanishes because
//! `v_s` is zero at both ends). The bridge couples to the string through the mass matrix
//! alone: mode `i` feels the force `−g_i b̈`, and the bridge feels `−Σ_s (g_sᵀṽ̈_s + m_L b̈ + k_L b)`.
//! With the bridge held still (`b = 0`) each string is exactly the modal string of the other
//! scenes. The string's own damping acts on `v_s` (the line moves with the bridge, whose own
//! losses are its modes').
//!
//! # The hammer on the unison
//!
//! The felt meets every string of the unison at the striking point `x_h = ℓL`. Its compression is
//! measured against the strings' mean displacement there, and the force is shared equally:
//!
//! ```text
//! y = (1/S) Σ_s u_s(x_h) − w = (1/S) Σ_s h_sᵀṽ_s + ℓ b − w,   string s takes F/S along h_s, the bridge ℓF
//! ```
//!
//! With identical strings and a still bridge this is one string struck by a hammer of `1/S` the
//! mass with a felt of `1/S` the stiffness: so the per-note rule's hammer (one string's share,
//! as Chaigne and Askenfelt's C4 is) gives the unison a hammer `S` times as heavy and as stiff.
//!
//! # One step in closed form
//!
//! Every body steps with its exact per-mode scheme, `ṽ^{n+1} = ṽ^{n−1} − z̃ + C∘(forces)`, the
//! bridge's coupling terms with `δ_tt b` and `μ_t² b = (b^{n+1} + 2b^n + b^{n−1})/4`. With the
//! bridge's acceleration `a = δ_tt b` and the hammer's force `F` as unknowns:
//!
//! ```text
//! ṽ_s^{n+1} = ṽ_s^{n−1} − z̃_s + (C∘h_s) F/S − (C∘g_s) a
//! f = (ℓ − Γ) F − G₀ + (Θ − E) a                       (the force on the bridge)
//! b^{n+1} = b_free + C_Σ f = Δt² a + 2b^n − b^{n−1}    (the bridge, see crate::bridge)
//! Γ = Σ_s θ_gh,s /(SΔt²),  Θ = Σ_s θ_gg,s /Δt²,  E = Σ_s (m_L,s + k_L,s Δt²/4)
//! G₀ = Σ_s (2g_sᵀṽ_s^{n−1} − g_sᵀz̃_s − 2g_sᵀṽ_s^n)/Δt² + Σ_s k_L,s b^n
//! ```
//!
//! with `θ_ab = aᵀ(C∘b)`. The bridge's equation gives `a = a₀ + a₁F` with
//! `Δ = Δt² + C_Σ(E − Θ)`, `a₀ = (b_free − 2b^n + b^{n−1} − C_Σ G₀)/Δ`, `a₁ = C_Σ(ℓ − Γ)/Δ`
//! (`E > Θ`: the string's mass beyond its modes, see below), and the compression's change
//! `s = y^{n+1} − y^{n−1}` is the common scalar problem `s + z − qF = 0` with
//!
//! ```text
//! z = (1/S)Σ_s h_sᵀz̃_s − z_h − Δt²(ℓ − Γ) a₀ − 2ℓ(b^n − b^{n−1})
//! q = Σ_s θ_hh,s/S² + ξ_h + Δt²(ℓ − Γ) a₁
//! ```
//!
//! one solve of the chosen contact solver, as for a single string: the bridge never makes the
//! contact iterative.
//!
//! # Energy
//!
//! ```text
//! H = Σ_s H_s + H_bridge + Σ_s g_sᵀ(δ_t+ṽ_s) δ_t+b + ½m_L(δ_t+b)² + ½k_L(μ_t+b)² + hammer + contact
//! ```
//!
//! changes only by the strings' and the bridge's damping (the cross terms are exact discrete
//! derivatives: `δ_t−(δ_t+x δ_t+y) = δ_tt x δ_t·y + δ_t·x δ_tt y`). The kinetic part is positive:
//! `m_L − Σ_i g_i²/m̃ = ρAL(1/3 − (2/π²)Σ_{i≤M} 1/i²) > 0` for any number of modes `M`.

use crate::bridge::{Bridge, BridgeEnergy, BridgeError, BridgeParams};
use crate::contact::{ContactProblem, ContactSolver};
use crate::exciter::{Hammer, HammerParams};
use crate::scene::Frame;
use crate::string::{ModalString, StringError, StringParams};

/// Most strings a unison has.
pub const MAX_UNISON: usize = 3;

/// A unison struck by one hammer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnisonParams {
    /// The nominal string: every string of the unison is this one, retensioned to its detuning.
    pub string: StringParams,
    /// How many strings, 1 to [`MAX_UNISON`].
    pub strings: usize,
    /// Each string's tuning relative to the nominal (cents; entries past `strings` unused).
    pub detune: [f64; MAX_UNISON],
}

impl UnisonParams {
    /// String `s` of the unison: the nominal string with its tension scaled by `2^{c/600}` for a
    /// detuning of `c` cents (the frequency goes with `√T`; the wire, and so `EI`, is the same).
    pub fn string(&self, s: usize) -> StringParams {
        let mut string = self.string;
        string.tension *= 2f64.powf(self.detune[s] / 600.0);
        string
    }
}

/// What went wrong preparing a unison.
#[derive(Debug, Clone, PartialEq)]
pub enum UnisonError {
    /// A string is invalid.
    String(StringError),
    /// The bridge is invalid.
    Bridge(BridgeError),
    /// The number of strings is outside 1 to [`MAX_UNISON`].
    Strings(usize),
}

/// One string of the unison with its vectors and the projections the step keeps.
#[derive(Debug, Clone)]
struct UnisonString {
    string: ModalString,
    /// `h_i = sin(β_i x_h)`.
    shape: Vec<f64>,
    /// `g_i = ρA(−1)^{i+1}/β_i` (kg).
    lift: Vec<f64>,
    /// `C∘h` (m/N).
    shape_gain: Vec<f64>,
    /// `C∘g` (m·s²/m = kg·m/N).
    lift_gain: Vec<f64>,
    /// The bridge force weights over `S` (N/m).
    pickup: Vec<f64>,
    /// `θ_hh`, `θ_gh`, `θ_gg`.
    theta: [f64; 3],
    /// `m_L = ρAL/3` (kg) and `k_L = T/L` (N/m).
    lift_mass: f64,
    lift_stiffness: f64,
    /// `(hᵀṽ^{n−1}, hᵀṽ^n)` (m) and `(gᵀṽ^{n−1}, gᵀṽ^n)` (kg·m).
    hv: (f64, f64),
    gv: (f64, f64),
    /// `(hᵀz̃, gᵀz̃)` of the coming step when the last pass already projected it.
    next: Option<[f64; 2]>,
}

impl UnisonString {
    fn new(modes: usize) -> Self {
        let string = ModalString::with_capacity(modes);
        let v = || Vec::with_capacity(string.capacity());
        Self {
            shape: v(),
            lift: v(),
            shape_gain: v(),
            lift_gain: v(),
            pickup: v(),
            string,
            theta: [0.0; 3],
            lift_mass: 0.0,
            lift_stiffness: 0.0,
            hv: (0.0, 0.0),
            gv: (0.0, 0.0),
            next: None,
        }
    }

    /// Make the vectors for striking point `position` (fraction of the length) in a unison of
    /// `count` strings.
    fn place(&mut self, position: f64, count: usize) {
        let s = &self.string;
        for v in [&mut self.shape, &mut self.lift, &mut self.shape_gain, &mut self.lift_gain, &mut self.pickup] {
            s.fit_vector(v);
        }
        let p = *s.params();
        s.mode_shapes(position * p.length, &mut self.shape);
        for (i, (g, &beta)) in self.lift.iter_mut().zip(s.wavenumbers()).enumerate() {
            let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
            *g = sign * p.linear_density / beta;
        }
        s.bridge_weights(true, &mut self.pickup);
        self.pickup.iter_mut().for_each(|w| *w /= count as f64);
        self.lift_mass = p.linear_density * p.length / 3.0;
        self.lift_stiffness = p.tension / p.length;
        self.refresh();
    }

    /// The gains and `θ` from the string's current coefficients.
    fn refresh(&mut self) {
        let s = &self.string;
        for (((hg, gg), (h, g)), c) in self
            .shape_gain
            .iter_mut()
            .zip(self.lift_gain.iter_mut())
            .zip(self.shape.iter().zip(&self.lift))
            .zip(s.input_gains())
        {
            *hg = h * c;
            *gg = g * c;
        }
        self.theta = [
            s.project(&self.shape, &self.shape_gain),
            s.project(&self.lift, &self.shape_gain),
            s.project(&self.lift, &self.lift_gain),
        ];
        self.next = None;
    }

    /// Recompute the projections of the state.
    fn measure(&mut self) {
        self.hv = self.string.project_state(&self.shape);
        self.gv = self.string.project_state(&self.lift);
        self.next = None;
    }
}

/// The sums over the unison's strings that a step needs (module docs).
#[derive(Debug, Clone, Copy, Default)]
struct Sums {
    /// `Σ θ_hh/S²` (m/N).
    hh: f64,
    /// `Σ θ_gh/S`.
    gh: f64,
    /// `Σ θ_gg`.
    gg: f64,
    /// `Σ m_L` (kg).
    mass: f64,
    /// `Σ k_L` (N/m).
    stiffness: f64,
}

/// A hammer, a unison of strings and their bridge: everything of a piano key except the solver.
/// Prepared once with room for the most modes a string may need, then retuned and struck note
/// after note without allocating.
#[derive(Debug, Clone)]
pub struct UnisonCore {
    strings: Vec<UnisonString>,
    count: usize,
    bridge: Bridge,
    hammer: Hammer,
    /// `ℓ = x_h/L`.
    ell: f64,
    sums: Sums,
    /// `y^{n−1}`, `y^n` (m).
    y_prev: f64,
    y_now: f64,
    /// Output (mean bridge force per string, N) at `n`.
    out_now: f64,
    /// Contact force of the latest step (N).
    last_force: f64,
    /// Energy dissipated so far (J), when monitored.
    losses: f64,
    dt: f64,
}

impl UnisonCore {
    /// A silent key with room for `modes` modes per string and `bridge` at `sample_rate` (Hz).
    pub fn new(modes: usize, bridge: &BridgeParams, sample_rate: f64) -> Result<Self, UnisonError> {
        let bridge = Bridge::new(bridge, sample_rate).map_err(UnisonError::Bridge)?;
        let hammer = Hammer::new(&HammerParams { mass: 1e-2, velocity: 0.0, position: 0.1, gap: 1e-3 }, sample_rate);
        Ok(Self {
            strings: (0..MAX_UNISON).map(|_| UnisonString::new(modes)).collect(),
            count: 0,
            bridge,
            hammer,
            ell: 0.1,
            sums: Sums::default(),
            y_prev: 0.0,
            y_now: 0.0,
            out_now: 0.0,
            last_force: 0.0,
            losses: 0.0,
            dt: 1.0 / sample_rate,
        })
    }

    /// Re-prepare for `params` (every string and the bridge at rest), with the modes below
    /// `max_frequency` (Hz), struck at `position` (fraction of the length). Never allocates.
    pub fn retune(&mut self, params: &UnisonParams, max_frequency: f64, position: f64) -> Result<(), UnisonError> {
        if !(1..=MAX_UNISON).contains(&params.strings) {
            return Err(UnisonError::Strings(params.strings));
        }
        let fs = 1.0 / self.dt;
        for s in 0..params.strings {
            self.strings[s].string.retune(params.string(s), fs, max_frequency).map_err(UnisonError::String)?;
        }
        self.count = params.strings;
        self.ell = position;
        for s in &mut self.strings[..self.count] {
            s.place(position, params.strings);
        }
        self.bridge.reset();
        self.sum_up();
        self.losses = 0.0;
        self.measure();
        Ok(())
    }

    fn sum_up(&mut self) {
        let n = self.count as f64;
        let mut sums = Sums::default();
        for s in &self.strings[..self.count] {
            sums.hh += s.theta[0] / (n * n);
            sums.gh += s.theta[1] / n;
            sums.gg += s.theta[2];
            sums.mass += s.lift_mass;
            sums.stiffness += s.lift_stiffness;
        }
        self.sums = sums;
    }

    /// The strings' mean displacement at the striking point plus the bridge's share,
    /// `(u_h^{n−1}, u_h^n)` (m).
    fn under_hammer(&self) -> (f64, f64) {
        let n = self.count as f64;
        let (b_prev, b_now) = self.bridge.displacement();
        let (mut prev, mut now) = (self.ell * b_prev, self.ell * b_now);
        for s in &self.strings[..self.count] {
            prev += s.hv.0 / n;
            now += s.hv.1 / n;
        }
        (prev, now)
    }

    /// Recompute every projection, the compressions and the output from the state.
    fn measure(&mut self) {
        let mut out = 0.0;
        for s in &mut self.strings[..self.count] {
            s.measure();
            out += s.string.project_state(&s.pickup).1;
        }
        let (prev, now) = self.under_hammer();
        self.y_prev = prev - self.hammer.previous();
        self.y_now = now - self.hammer.position();
        self.out_now = out;
    }

    /// Throw the hammer (its whole mass) again, `gap` beyond the string under it: see
    /// [`HammerCore::strike`](super::HammerCore::strike). Restart the solver with
    /// [`compressions`](Self::compressions) afterwards.
    pub fn strike(&mut self, hammer: &HammerParams) {
        let (before, now) = self.under_hammer();
        let under = now.max(before - hammer.velocity * self.dt);
        self.hammer = Hammer::above(under, hammer, 1.0 / self.dt);
        self.measure();
    }

    /// After the strings' coefficients changed (a damper): the gains and sums follow.
    pub fn refresh_coupling(&mut self) {
        for s in &mut self.strings[..self.count] {
            s.refresh();
        }
        self.sum_up();
    }

    /// Add the decay rates `extra` (1/s per mode) to every string (see
    /// [`ModalString::set_extra_decay`]) and refresh the coupling.
    pub fn set_extra_decay(&mut self, extra: &[f64]) {
        for s in &mut self.strings[..self.count] {
            s.string.set_extra_decay(extra);
        }
        self.refresh_coupling();
    }

    /// Bring strings and bridge to rest.
    pub fn reset(&mut self) {
        for s in &mut self.strings[..self.count] {
            s.string.reset();
        }
        self.bridge.reset();
        self.measure();
    }

    /// `(y^{n−1}, y^n)` (m), to start a solver from.
    pub fn compressions(&self) -> (f64, f64) {
        (self.y_prev, self.y_now)
    }

    /// The strings of the unison.
    pub fn strings(&self) -> impl Iterator<Item = &ModalString> {
        self.strings[..self.count].iter().map(|s| &s.string)
    }

    /// The first string (what a monitor draws).
    pub fn string(&self) -> &ModalString {
        &self.strings[0].string
    }

    /// The first string, to set its state directly (tests of what follows a corrupt state). The
    /// projections the step keeps are stale until the next [`retune`](Self::retune) or strike.
    pub fn string_mut(&mut self) -> &mut ModalString {
        self.strings[0].next = None;
        &mut self.strings[0].string
    }

    /// The most modes any string of the unison has.
    pub fn modes(&self) -> usize {
        self.strings().map(ModalString::modes).max().unwrap_or(0)
    }

    /// The bridge.
    pub fn bridge(&self) -> &Bridge {
        &self.bridge
    }

    /// The strings' energy weighed with their own stiffnesses plus the bridge's own energy (J):
    /// what a voice's guard and release read (the coupling's cross terms left out; see
    /// [`ModalString::own_energy`]).
    pub fn own_energy(&self) -> f64 {
        self.strings().map(ModalString::own_energy).sum::<f64>() + self.bridge.energy()
    }

    /// The strings' energy weighed with their own stiffnesses (J), without the bridge: what
    /// decides that a voice is silent (the strings are what sounds; the bridge's slowest modes
    /// ring on at its own rate).
    pub fn strings_energy(&self) -> f64 {
        self.strings().map(ModalString::own_energy).sum()
    }

    /// The strings' and bridge's energy and the hammer's (J), without the coupling's cross terms
    /// and the contact term.
    pub fn energy(&self) -> f64 {
        self.strings().map(ModalString::energy).sum::<f64>() + self.bridge.energy() + self.hammer.energy()
    }

    /// The hammer's energy (J).
    pub fn hammer_energy(&self) -> f64 {
        self.hammer.energy()
    }

    /// `(compression y^n (m), latest contact force (N))`.
    pub fn contact(&self) -> (f64, f64) {
        (self.y_now, self.last_force)
    }

    /// Whether the felt is touching or about to.
    pub fn in_contact(&self) -> bool {
        self.y_now > 0.0 || self.y_prev > 0.0
    }

    /// Whether the hammer flies away from the strings, clear of them: what a voice needs before
    /// it releases a string that has fallen silent (a silent string cannot reach a hammer
    /// moving away; the contact is still solved at every step).
    pub fn hammer_leaving(&self) -> bool {
        self.hammer.velocity() > 0.0 && self.y_now < 0.0 && self.y_prev < 0.0
    }

    /// One step with `solver`; with `MONITOR` the frame also carries the energy terms.
    #[inline]
    pub fn step<S: ContactSolver, const MONITOR: bool>(&mut self, solver: &mut S) -> Frame {
        let (dt, n, ell) = (self.dt, self.count as f64, self.ell);
        let dt2 = dt * dt;
        let sums = self.sums;
        // Projections of z̃ and the known part of the bridge force.
        let (mut hz, mut g0) = (0.0, 0.0);
        let mut zs = [[0.0; 2]; MAX_UNISON];
        for (s, z) in self.strings[..self.count].iter_mut().zip(&mut zs) {
            *z = match s.next.take() {
                Some(z) => z,
                None => s.string.history([&s.shape, &s.lift]),
            };
            hz += z[0] / n;
            g0 += 2.0 * s.gv.0 - z[1] - 2.0 * s.gv.1;
        }
        let (b_prev, b_now) = self.bridge.displacement();
        g0 = g0 / dt2 + sums.stiffness * b_now;
        let (b_free, compliance) = self.bridge.predict();
        let gamma = sums.gh / dt2;
        let theta = sums.gg / dt2;
        let inertia = sums.mass + 0.25 * sums.stiffness * dt2;
        let den = dt2 + compliance * (inertia - theta);
        let a0 = (b_free - 2.0 * b_now + b_prev - compliance * g0) / den;
        let a1 = compliance * (ell - gamma) / den;
        let lever = dt2 * (ell - gamma);
        let z_h = self.hammer.history();
        let problem = ContactProblem {
            y_prev: self.y_prev,
            y_now: self.y_now,
            z: hz - z_h - lever * a0 - 2.0 * ell * (b_now - b_prev),
            q: sums.hh + self.hammer.coupling() + lever * a1,
        };
        let solution = solver.solve(&problem);
        let force = solution.force;
        let a = a0 + a1 * force;
        let f = (ell - gamma) * force - g0 + (theta - inertia) * a;
        let mut energy = 0.0;
        let b_next = if MONITOR {
            let (b_next, BridgeEnergy { stored, dissipated }) = self.bridge.advance_monitored(f);
            energy += stored;
            self.losses += dissipated;
            b_next
        } else {
            self.bridge.advance(f)
        };
        let mut out_next = 0.0;
        let mut cross = 0.0;
        for (s, z) in self.strings[..self.count].iter_mut().zip(&zs) {
            let forces = [(&s.shape_gain[..], force / n), (&s.lift_gain[..], -a)];
            let [th_hh, th_gh, th_gg] = s.theta;
            let hv_next = s.hv.0 - z[0] + th_hh * force / n - th_gh * a;
            let gv_next = s.gv.0 - z[1] + th_gh * force / n - th_gg * a;
            if MONITOR {
                let (out, e) = s.string.advance_monitored(forces, &s.pickup);
                out_next += out;
                energy += e.stored;
                self.losses += e.dissipated;
                cross += (gv_next - s.gv.1) / dt;
                s.hv = (s.hv.1, hv_next);
                s.gv = (s.gv.1, gv_next);
                s.next = None;
            } else {
                let (out, next) = s.string.advance_projecting(forces, &s.pickup, [&s.shape, &s.lift]);
                out_next += out;
                s.next = next;
                if next.is_some() {
                    s.hv = (s.hv.1, hv_next);
                    s.gv = (s.gv.1, gv_next);
                } else {
                    // The string flushed tiny amplitudes: project the state afresh.
                    s.measure();
                }
            }
        }
        let w_now = self.hammer.position();
        self.hammer.advance(force);
        let y_next = self.y_prev + solution.s;
        let output = self.out_now;
        let mut frame = Frame {
            output,
            displacement: w_now,
            velocity: self.hammer.velocity(),
            compression: self.y_now,
            force,
            energy: 0.0,
            losses: 0.0,
            control_work: 0.0,
            work: solver.last_work(),
        };
        if MONITOR {
            let db = (b_next - b_now) / dt;
            let mean = 0.5 * (b_next + b_now);
            energy += cross * db + 0.5 * sums.mass * db * db + 0.5 * sums.stiffness * mean * mean;
            frame.energy = energy + self.hammer.energy() + solver.stored_energy(y_next, self.y_now);
            frame.losses = self.losses;
        }
        self.last_force = force;
        self.out_now = out_next;
        self.y_prev = self.y_now;
        self.y_now = y_next;
        frame
    }

    /// Advance `out.len()` samples with `solver`, writing the output (the mean bridge force per
    /// string, N).
    pub fn process_output<S: ContactSolver>(&mut self, solver: &mut S, out: &mut [f64]) {
        for o in out {
            *o = self.step::<S, false>(solver).output;
        }
    }
}

/// A hammer striking a unison on a bridge, as a scene (for renders and tests).
#[derive(Debug, Clone)]
pub struct HammerUnison<S> {
    core: UnisonCore,
    solver: S,
    initial_energy: f64,
}

impl<S: ContactSolver> HammerUnison<S> {
    /// `core` retuned and struck; the solver is started from its compressions.
    pub fn new(core: UnisonCore, mut solver: S) -> Self {
        let (y_prev, y_now) = core.compressions();
        solver.start(y_prev, y_now);
        let initial_energy = core.energy() + solver.stored_energy(y_now, y_prev);
        Self { core, solver, initial_energy }
    }

    /// The key.
    pub fn core(&self) -> &UnisonCore {
        &self.core
    }
}

impl<S: ContactSolver> super::Scene for HammerUnison<S> {
    fn sample_rate(&self) -> f64 {
        1.0 / self.core.dt
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bridge::{BridgeMode, SOUNDBOARD_CONDUCTANCE};
    use crate::contact::{ExplicitSolver, NewtonSolver, PowerLaw, QsaSolver, QuadSpline};
    use crate::preset::chaigne_askenfelt_c4;
    use crate::scene::{HammerString, HammerStringParams, OutputKind, Pickup, Scene};

    const FS: f64 = 48_000.0;

    fn c4_unison(strings: usize, detune: [f64; 3], bridge: &BridgeParams) -> UnisonCore {
        let c4 = chaigne_askenfelt_c4();
        let params = UnisonParams { string: c4.string, strings, detune };
        let mut core = UnisonCore::new(200, bridge, FS).unwrap();
        core.retune(&params, f64::INFINITY, c4.strike_position).unwrap();
        let mass = c4.hammer_mass * strings as f64;
        core.strike(&HammerParams { mass, velocity: 3.5, position: c4.strike_position, gap: 2e-4 });
        core
    }

    fn law(strings: usize) -> PowerLaw {
        let c4 = chaigne_askenfelt_c4();
        PowerLaw::new(c4.kappa * strings as f64, c4.alpha).unwrap()
    }

    /// Over a strike and 0.5 s of ringing on the soundboard, a detuned trichord's energy
    /// `H + losses` stays at its initial value to 1e-9 relative, for each of the three solvers:
    /// the bridge's elimination is exact, and every cross term of the coupling is counted.
    #[test]
    fn a_trichord_on_the_soundboard_keeps_its_energy_balance() {
        let board = BridgeParams::soundboard(SOUNDBOARD_CONDUCTANCE);
        let detune = [-1.0, 0.2, 0.8];
        let y_ref = law(3).compression_at_energy(0.5 * 3.0 * 2.97e-3 * 3.5 * 3.5);
        let frames = |mut scene: Box<dyn Scene>| {
            let mut frames = vec![Frame::default(); 24_000];
            scene.process(&mut frames);
            let start = scene.initial_energy();
            let peak = frames.iter().map(|f| f.energy).fold(start, f64::max);
            let drift = frames.iter().map(|f| (f.balance() - start).abs()).fold(0.0, f64::max) / peak;
            let losses = frames.last().unwrap().losses / start;
            (drift, losses)
        };
        let qsa = QsaSolver::new(QuadSpline::new(law(3), y_ref, 6).unwrap());
        let results = [
            ("qsa", frames(Box::new(HammerUnison::new(c4_unison(3, detune, &board), qsa)))),
            ("imp", frames(Box::new(HammerUnison::new(c4_unison(3, detune, &board), NewtonSolver::new(law(3)))))),
            ("exp", frames(Box::new(HammerUnison::new(c4_unison(3, detune, &board), ExplicitSolver::new(law(3)))))),
        ];
        for (name, (drift, losses)) in results {
            println!("{name}: drift {drift:.2e}, losses {losses:.3} of the initial energy");
            assert!(drift < 1e-9, "{name}: {drift:e}");
            assert!(losses > 0.05, "{name}: the strings and bridge dissipate ({losses})");
        }
    }

    /// With a bridge that does not move (one mode of 10¹² kg) and three identical strings, the
    /// unison is the single string of the other scenes struck by a third of the hammer: the
    /// output (mean bridge force per string) equals the single string's bridge force to 1e-9 of
    /// its peak over a strike and 2,000 steps after it.
    #[test]
    fn a_unison_of_identical_strings_on_a_still_bridge_is_one_string() {
        let rigid = BridgeParams { modes: vec![BridgeMode { frequency: 50.0, mass: 1e12, loss_factor: 0.0 }] };
        let c4 = chaigne_askenfelt_c4();
        let y_ref = law(1).compression_at_energy(0.5 * 2.97e-3 * 3.5 * 3.5);
        let mut unison = HammerUnison::new(
            c4_unison(3, [0.0; 3], &rigid),
            QsaSolver::new(QuadSpline::new(law(3), y_ref, 6).unwrap()),
        );
        let params = HammerStringParams {
            string: c4.string,
            hammer: HammerParams { mass: c4.hammer_mass, velocity: 3.5, position: c4.strike_position, gap: 2e-4 },
            pickup: Pickup { kind: OutputKind::BridgeForce, position: 0.5 },
        };
        let string = ModalString::new(c4.string, FS).unwrap();
        let mut single = HammerString::new(string, &params, QsaSolver::new(QuadSpline::new(law(1), y_ref, 6).unwrap()));
        let (mut a, mut b) = (vec![0.0; 2400], vec![0.0; 2400]);
        unison.process_output(&mut a);
        single.process_output(&mut b);
        let peak = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let worst = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
        println!("peak {peak:.3} N, worst difference {worst:.2e} N");
        assert!(peak > 1.0 && worst < 1e-9 * peak, "{worst:e} of {peak}");
    }
}

#[cfg(test)]
mod decay_probe {
    use super::*;
    use crate::bridge::SOUNDBOARD_CONDUCTANCE;
    use crate::contact::{PowerLaw, QsaSolver, QuadSpline};
    use crate::preset::piano_note;
    use crate::scene::Scene;

    #[test]
    fn probe() {
        let fs = 48_000.0;
        for (key, strings, detune) in [
            (60u8, 3, [-1.5, 0.3, 1.2]),
            (60, 3, [-3.0, 0.5, 2.5]),
            (60, 2, [-1.0, 1.0, 0.0]),
            (55, 3, [-1.5, 0.3, 1.2]),
            (67, 3, [-1.5, 0.3, 1.2]),
        ] {
            let note = piano_note(key);
            let board = BridgeParams::soundboard(SOUNDBOARD_CONDUCTANCE);
            let mut core = UnisonCore::new(400, &board, fs).unwrap();
            core.retune(&UnisonParams { string: note.string, strings, detune }, 20_000.0, note.strike_position)
                .unwrap();
            let s = strings as f64;
            core.strike(&HammerParams {
                mass: note.hammer_mass * s,
                velocity: 2.0,
                position: note.strike_position,
                gap: 1e-4,
            });
            let law = PowerLaw::new(note.kappa * s, note.alpha).unwrap();
            let y_ref = law.compression_at_energy(0.5 * note.hammer_mass * s * 4.0);
            let mut scene = HammerUnison::new(core, QsaSolver::new(QuadSpline::new(law, y_ref, 6).unwrap()));
            let n = (6.0 * fs) as usize;
            let mut out = vec![0.0; n];
            scene.process_output(&mut out);
            let f1 = note.string.partial(1);
            for partial in [1usize, 2] {
                let f = note.string.partial(partial);
                let w = (0.05 * fs) as usize;
                let levels: Vec<f64> = (0..n / w)
                    .map(|k| {
                        let (mut re, mut im) = (0.0, 0.0);
                        for i in k * w..(k + 1) * w {
                            let ph = std::f64::consts::TAU * f * i as f64 / fs;
                            re += out[i] * ph.cos();
                            im += out[i] * ph.sin();
                        }
                        10.0 * ((re * re + im * im) / (w * w) as f64).log10()
                    })
                    .collect();
                let row: Vec<String> = levels.iter().step_by(4).map(|l| format!("{l:.0}")).collect();
                println!("key {key} S {strings} {detune:?} f1 {f1:.1} partial {partial}: {}", row.join(" "));
            }
        }
    }
}
