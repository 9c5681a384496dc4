//! A slide pressed onto, slid along and lifted off a plucked string (seed §6, physics §7).
//!
//! The string ([`ModalString`]) meets
//! - the slide at `x_o` through the power-law contact, `y = h_oᵀũ − w_o`, `h_o = v(x_o)`, with the
//!   slide held by the hand through the slide–hand oscillator ([`SlideHand`]);
//! - the left finger (trailing the slide, damping the dead part of the string) and the right
//!   finger (plucking), each a force `F_φe` spread over a half-cosine window with damping
//!   `F_φR = −r|F_φe| δ_t· u_φ` ([`finger`](crate::exciter::finger)).
//!
//! # One step (physics §7.3, seed eqs. 65, 72–74)
//!
//! With the contact vectors frozen for the step (`ĥ_ζ`, ζ ∈ {o, l, r}), their Gram matrix in the
//! C metric `θ_ζξ = Σ_i ĥ_ζ,i C_i ĥ_ξ,i`, `z_ζ = ĥ_ζᵀz̃`, `e_ζ = Σ_φ θ_ζφ F_φe`,
//! `d_φ = e_φ − z_φ` and `γ_φ = r|F_φe|/(2Δt)`, the finger damping forces are eliminated in
//! closed form:
//!
//! ```text
//! Δ    = (1 + γ_l θ_ll)(1 + γ_r θ_rr) − γ_l γ_r θ_lr²
//! s_l  = [(1+γ_rθ_rr)(d_l + θ_lo F) − γ_rθ_lr(d_r + θ_ro F)] / Δ  ≡ s_l0 + s_l1 F
//! s_r  = [(1+γ_lθ_ll)(d_r + θ_ro F) − γ_lθ_rl(d_l + θ_lo F)] / Δ  ≡ s_r0 + s_r1 F
//! z_str = z_o − e_o + γ_l θ_ol s_l0 + γ_r θ_or s_r0
//! q_str = θ_oo − γ_l θ_ol s_l1 − γ_r θ_or s_r1
//! s + (z_str − z_sho) − (q_str + q_sho) F = 0                                  (seed eq. 74)
//! ```
//!
//! and after the solve `F_φR = −γ_φ s_φ` and
//! `ũ^{n+1} = ũ^{n−1} − z̃ + C(ĥ_o F + Σ_φ ĥ_φ (F_φe + F_φR))` (seed eq. 65 with the excitation
//! counted once).
//!
//! # Controls (seed §6.7)
//!
//! Slide position `x_o`, hand height `w_H`, finger positions and finger forces come from a
//! [`ControlSource`] sampled at block boundaries every `N_b` samples. Within a block the hand
//! height and finger forces ramp linearly; the vectors, θ and the projections are recomputed once
//! per block from the positions at the block's start, and only when a position changed. With
//! [`Fixed`](crate::control::Fixed) controls none of this code runs. A finger whose force is zero
//! throughout a block is left out of that block's passes over the modes.
//!
//! # Energy (seed eqs. 75–80)
//!
//! `H^{n+1/2}` = string + SHO + contact. Per step the losses are `Δt(Q_str + Q_o + Σ Q_φ)` and the
//! sources `Δt(P_H + Σ P_φ)`, with `Δt Q_φ = γ_φ s_φ²/2` and `Δt P_φ = F_φe s_φ/2` for fixed
//! finger positions. Moving the slide or the fingers exchanges energy through the time-varying
//! vectors (seed eq. 77–78), which is not booked: the balance closes to rounding only while the
//! positions are fixed.

use crate::contact::{ContactProblem, ContactSolver};
use crate::control::{ControlSource, Ramp};
use crate::exciter::{FingerParams, HandMotion, SlideHand, SlideParams, finger};
use crate::scene::{Frame, OutputKind, Pickup, Scene};
use crate::string::{GramVector, ModalString, StringParams};

/// The slide scene's control inputs at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlideControls {
    /// Slide contact position x_o (m from the nut end, x = 0), in (0, L).
    pub slide_position: f64,
    /// Hand height w_H (m): the slide's rest height relative to the string; negative presses.
    pub hand_height: f64,
    /// Left finger centre x_l (m), in (0, L).
    pub left_position: f64,
    /// Left finger force F_le (N).
    pub left_force: f64,
    /// Right finger centre x_r (m), in (0, L).
    pub right_position: f64,
    /// Right finger force F_re (N).
    pub right_force: f64,
}

impl SlideControls {
    fn positions(&self) -> [f64; 3] {
        [self.slide_position, self.left_position, self.right_position]
    }
}

/// Which fingers touch the string during a block. A finger whose force is zero at both ends of
/// a block (so throughout it) neither excites nor damps the string there (`F_φe = 0`, `γ_φ = 0`),
/// so its projection and its share of the update are skipped for the block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Fingers {
    None,
    Left,
    Right,
    Both,
}

impl Fingers {
    fn touching(start: &SlideControls, end: &SlideControls) -> Self {
        let left = start.left_force != 0.0 || end.left_force != 0.0;
        let right = start.right_force != 0.0 || end.right_force != 0.0;
        match (left, right) {
            (false, false) => Fingers::None,
            (true, false) => Fingers::Left,
            (false, true) => Fingers::Right,
            (true, true) => Fingers::Both,
        }
    }
}

/// Parameters of a slide–string scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlideStringParams {
    /// The string.
    pub string: StringParams,
    /// The slide and hand.
    pub slide: SlideParams,
    /// Left finger (trailing the slide).
    pub left: FingerParams,
    /// Right finger (plucking).
    pub right: FingerParams,
    /// Control block length N_b (samples), ≥ 1.
    pub block: usize,
    /// The output (the bridge is at x = L).
    pub pickup: Pickup,
}

/// The slide–string scene, generic over its contact solver and its control source.
#[derive(Debug, Clone)]
pub struct SlideString<S, C> {
    core: SlideCore,
    solver: S,
    controls: C,
    initial_energy: f64,
}

impl<S: ContactSolver, C: ControlSource<SlideControls>> SlideString<S, C> {
    /// Prepare the scene: the string at rest and the slide resting at the hand's height.
    /// `string` must be prepared at the scene's sample rate and `params.block ≥ 1`.
    pub fn new(string: ModalString, params: &SlideStringParams, mut solver: S, mut controls: C) -> Self {
        let block = params.block.max(1);
        let start = controls.at(0);
        let target = if C::VARYING { controls.at(block as u64) } else { start };
        let core = SlideCore::new(string, params, start, target);
        let (y_prev, y_now) = core.compressions();
        solver.start(y_prev, y_now);
        let initial_energy = core.energy() + solver.stored_energy(y_now, y_prev);
        Self { core, solver, controls, initial_energy }
    }

    /// The string.
    pub fn string(&self) -> &ModalString {
        &self.core.string
    }

    /// The contact solver.
    pub fn solver(&self) -> &S {
        &self.solver
    }

    /// The control source, to feed it.
    pub fn controls_mut(&mut self) -> &mut C {
        &mut self.controls
    }
}

impl<S: ContactSolver, C: ControlSource<SlideControls>> Scene for SlideString<S, C> {
    fn sample_rate(&self) -> f64 {
        self.core.string.sample_rate()
    }

    fn initial_energy(&self) -> f64 {
        self.initial_energy
    }

    fn process(&mut self, frames: &mut [Frame]) {
        self.core.run::<S, C, true>(&mut self.solver, &mut self.controls, frames.len(), |i, f| frames[i] = f);
    }

    fn process_output(&mut self, out: &mut [f64]) {
        self.core.process_output(&mut self.solver, &mut self.controls, out);
    }
}

/// Everything of a slide–string scene except the solver and the control source: string, slide
/// and hand, fingers, contact vectors and the block ramps. An instrument voice keeps one core and
/// one solver of each kind and feeds the controls itself.
#[derive(Debug, Clone)]
pub struct SlideCore {
    string: ModalString,
    sho: SlideHand,
    left_window: Vec<f64>,
    right_window: Vec<f64>,
    /// Contact vectors `ĥ_o, ĥ_l, ĥ_r`.
    shapes: [Vec<f64>; 3],
    /// `C∘ĥ_ζ` (m/N).
    gains: [Vec<f64>; 3],
    /// `θ_ζξ` (m/N).
    theta: [[f64; 3]; 3],
    /// Positions the vectors were computed for (m).
    positions: [f64; 3],
    pickup: Vec<f64>,
    kind: OutputKind,
    /// Finger damping parameters r (s/m).
    r: [f64; 2],
    block: usize,
    /// Block length to use from the next block boundary.
    next_block: usize,
    /// Sample index of the next step.
    n: u64,
    /// Index of the next step within its block.
    k: usize,
    /// Controls at the start of the current block and at the start of the next.
    start: SlideControls,
    target: SlideControls,
    hand: Ramp,
    left_force: Ramp,
    right_force: Ramp,
    /// Which fingers touch the string anywhere in the current block.
    fingers: Fingers,
    /// `w_H^{n−1}` (m).
    hand_prev: f64,
    y_prev: f64,
    y_now: f64,
    out_now: f64,
    losses: f64,
    /// Contact force of the latest step (N).
    last_force: f64,
    dt: f64,
}

impl SlideCore {
    /// A core around `string` (prepared at the scene's sample rate): the string at rest and the
    /// slide resting at the hand's height, with controls `start` now and `target` one block on.
    pub fn new(string: ModalString, params: &SlideStringParams, start: SlideControls, target: SlideControls) -> Self {
        let fs = string.sample_rate();
        let block = params.block.max(1);
        let mut pickup = string.vector();
        match params.pickup.kind {
            OutputKind::Displacement | OutputKind::Velocity => {
                string.mode_shapes(params.pickup.position * string.params().length, &mut pickup)
            }
            OutputKind::BridgeForce => string.bridge_weights(true, &mut pickup),
        }
        let sho = SlideHand::new(params.slide, fs, start.hand_height);
        let mut core = Self {
            left_window: finger::window_factors(&string, params.left.width),
            right_window: finger::window_factors(&string, params.right.width),
            shapes: [string.vector(), string.vector(), string.vector()],
            gains: [string.vector(), string.vector(), string.vector()],
            theta: [[0.0; 3]; 3],
            positions: [f64::NAN; 3],
            pickup,
            kind: params.pickup.kind,
            r: [params.left.damping, params.right.damping],
            block,
            next_block: block,
            n: 0,
            k: 0,
            start,
            target,
            hand: Ramp::new(start.hand_height, target.hand_height, block),
            left_force: Ramp::new(start.left_force, target.left_force, block),
            right_force: Ramp::new(start.right_force, target.right_force, block),
            fingers: Fingers::touching(&start, &target),
            hand_prev: start.hand_height,
            y_prev: 0.0,
            y_now: 0.0,
            out_now: 0.0,
            losses: 0.0,
            last_force: 0.0,
            dt: 1.0 / fs,
            string,
            sho,
        };
        core.place(start.positions());
        core.out_now = core.string.project_state(&core.pickup).1;
        core
    }

    /// `(y^{n−1}, y^n)` (m), to start a solver from.
    pub fn compressions(&self) -> (f64, f64) {
        (self.y_prev, self.y_now)
    }

    /// New slide-and-hand and finger-damping parameters and control block length N_b (samples),
    /// taking effect at once (the block length at the next block boundary). Keeps the motion.
    pub fn set_params(&mut self, slide: SlideParams, finger_damping: [f64; 2], block: usize) {
        self.sho.set_params(slide);
        self.r = finger_damping;
        self.next_block = block.max(1);
    }

    /// Move the pickup to `pickup` (the string's output weights). Never allocates.
    pub fn set_pickup(&mut self, pickup: Pickup) {
        let s = &self.string;
        s.fit_vector(&mut self.pickup);
        match pickup.kind {
            OutputKind::Displacement | OutputKind::Velocity => {
                s.mode_shapes(pickup.position * s.params().length, &mut self.pickup)
            }
            OutputKind::BridgeForce => s.bridge_weights(true, &mut self.pickup),
        }
        self.kind = pickup.kind;
        self.out_now = s.project_state(&self.pickup).1;
    }

    /// What a monitor shows: `(compression y^n (m), latest contact force (N), slide position x_o (m))`.
    pub fn contact(&self) -> (f64, f64, f64) {
        (self.y_now, self.last_force, self.positions[0])
    }

    /// Whether the slide touches the string (now or one step back).
    pub fn in_contact(&self) -> bool {
        self.y_now > 0.0 || self.y_prev > 0.0
    }

    /// String and slide energy of the current state (J), without the contact term.
    pub fn energy(&self) -> f64 {
        self.string.energy() + self.sho.energy(self.hand_prev, self.hand.at(self.k))
    }

    /// The string.
    pub fn string(&self) -> &ModalString {
        &self.string
    }

    /// Recompute the contact vectors that moved (the slide's always, a finger's only while it
    /// touches the string), the Gram matrix of the touching ones, and the compressions, in one
    /// [`ModalString::gram`]: a pass a vector makes it by rotations, windows it and sums its θ
    /// entry; one more sums the cross terms and the slide's projections.
    /// A finger left out keeps its old vector and θ entries, which only ever meet its zero force.
    fn place(&mut self, positions: [f64; 3]) {
        let s = &self.string;
        let left = matches!(self.fingers, Fingers::Left | Fingers::Both);
        let right = matches!(self.fingers, Fingers::Right | Fingers::Both);
        let needed = [true, left, right];
        let mut fresh = [None; 3];
        for z in 0..3 {
            if needed[z] && positions[z] != self.positions[z] {
                fresh[z] = Some(s.shape_angle(positions[z]));
                self.positions[z] = positions[z];
            }
        }
        if fresh == [None; 3] {
            return;
        }
        let [sh_o, sh_l, sh_r] = &mut self.shapes;
        let [g_o, g_l, g_r] = &mut self.gains;
        let o = GramVector { shape: sh_o, gain: g_o, window: None, fresh: fresh[0] };
        let l = GramVector { shape: sh_l, gain: g_l, window: Some(&self.left_window), fresh: fresh[1] };
        let r = GramVector { shape: sh_r, gain: g_r, window: Some(&self.right_window), fresh: fresh[2] };
        let state = match self.fingers {
            Fingers::None => {
                let (t, state) = s.gram([o]);
                set_gram(&mut self.theta, &t, [0]);
                state
            }
            Fingers::Left => {
                let (t, state) = s.gram([o, l]);
                set_gram(&mut self.theta, &t, [0, 1]);
                state
            }
            Fingers::Right => {
                let (t, state) = s.gram([o, r]);
                set_gram(&mut self.theta, &t, [0, 2]);
                state
            }
            Fingers::Both => {
                let (t, state) = s.gram([o, l, r]);
                set_gram(&mut self.theta, &t, [0, 1, 2]);
                state
            }
        };
        if fresh[0].is_some() {
            self.y_prev = state.0 - self.sho.previous();
            self.y_now = state.1 - self.sho.position();
        }
    }

    /// Start a new block: move the targets on and, if a position changed, the vectors.
    fn begin_block<C: ControlSource<SlideControls>>(&mut self, controls: &mut C) {
        self.start = self.target;
        self.target = controls.at(self.n + self.block as u64);
        let (s, t, len) = (&self.start, &self.target, self.block);
        self.hand = Ramp::new(s.hand_height, t.hand_height, len);
        self.left_force = Ramp::new(s.left_force, t.left_force, len);
        self.right_force = Ramp::new(s.right_force, t.right_force, len);
        self.fingers = Fingers::touching(s, t);
        self.place(self.start.positions());
    }

    #[inline]
    fn step<S: ContactSolver, const MONITOR: bool>(&mut self, solver: &mut S) -> Frame {
        let k = self.k;
        let hand = HandMotion { prev: self.hand_prev, now: self.hand.at(k), next: self.hand.at(k + 1) };
        let (f_le, f_re) = (self.left_force.at(k), self.right_force.at(k));
        let th = &self.theta;
        let [sh_o, sh_l, sh_r] = &self.shapes;
        let (z_o, z_l, z_r) = match self.fingers {
            Fingers::None => {
                let [z_o] = self.string.history([sh_o]);
                (z_o, 0.0, 0.0)
            }
            Fingers::Left => {
                let [z_o, z_l] = self.string.history([sh_o, sh_l]);
                (z_o, z_l, 0.0)
            }
            Fingers::Right => {
                let [z_o, z_r] = self.string.history([sh_o, sh_r]);
                (z_o, 0.0, z_r)
            }
            Fingers::Both => {
                let [z_o, z_l, z_r] = self.string.history([sh_o, sh_l, sh_r]);
                (z_o, z_l, z_r)
            }
        };
        let e = [0, 1, 2].map(|a| th[a][1] * f_le + th[a][2] * f_re);
        let (d_l, d_r) = (e[1] - z_l, e[2] - z_r);
        let (g_l, g_r) = (self.r[0] * f_le.abs() / (2.0 * self.dt), self.r[1] * f_re.abs() / (2.0 * self.dt));
        let (a_l, a_r) = (1.0 + g_l * th[1][1], 1.0 + g_r * th[2][2]);
        let det = a_l * a_r - g_l * g_r * th[1][2] * th[1][2];
        let s_l0 = (a_r * d_l - g_r * th[1][2] * d_r) / det;
        let s_l1 = (a_r * th[1][0] - g_r * th[1][2] * th[2][0]) / det;
        let s_r0 = (a_l * d_r - g_l * th[2][1] * d_l) / det;
        let s_r1 = (a_l * th[2][0] - g_l * th[2][1] * th[1][0]) / det;
        let z_str = z_o - e[0] + g_l * th[0][1] * s_l0 + g_r * th[0][2] * s_r0;
        let q_str = th[0][0] - g_l * th[0][1] * s_l1 - g_r * th[0][2] * s_r1;
        let z_sho = self.sho.history(&hand);
        let problem =
            ContactProblem { y_prev: self.y_prev, y_now: self.y_now, z: z_str - z_sho, q: q_str + self.sho.coupling() };
        let solution = solver.solve(&problem);
        let force = solution.force;
        self.last_force = force;
        let y_next = self.y_prev + solution.s;
        let (s_l, s_r) = (s_l0 + s_l1 * force, s_r0 + s_r1 * force);
        let [g_o, g_lf, g_rf] = &self.gains;
        let (o, l, r) = ((&g_o[..], force), (&g_lf[..], f_le - g_l * s_l), (&g_rf[..], f_re - g_r * s_r));
        let (out_next, string_energy) = match (MONITOR, self.fingers) {
            (true, _) => self.string.advance_monitored([o, l, r], &self.pickup),
            (false, Fingers::None) => (self.string.advance([o], &self.pickup), Default::default()),
            (false, Fingers::Left) => (self.string.advance([o, l], &self.pickup), Default::default()),
            (false, Fingers::Right) => (self.string.advance([o, r], &self.pickup), Default::default()),
            (false, Fingers::Both) => (self.string.advance([o, l, r], &self.pickup), Default::default()),
        };
        let w_now = self.sho.position();
        let exchanged = self.sho.advance(z_sho, force, &hand);
        let output = self.kind.sample(self.out_now, out_next, self.dt);
        let mut frame = Frame {
            output,
            displacement: w_now,
            velocity: self.sho.velocity(),
            compression: self.y_now,
            force,
            energy: 0.0,
            losses: 0.0,
            work: solver.last_work(),
        };
        if MONITOR {
            let fingers = 0.5 * (g_l * s_l * s_l + g_r * s_r * s_r - f_le * s_l - f_re * s_r);
            self.losses += string_energy.dissipated + fingers - exchanged;
            frame.energy =
                string_energy.stored + self.sho.energy(hand.now, hand.next) + solver.stored_energy(y_next, self.y_now);
            frame.losses = self.losses;
        }
        self.out_now = out_next;
        self.y_prev = self.y_now;
        self.y_now = y_next;
        self.hand_prev = hand.now;
        self.n += 1;
        self.k += 1;
        frame
    }

    /// Run `count` steps with `solver`, starting blocks where they fall and asking `controls`
    /// for their targets, handing each frame to `sink`.
    #[inline]
    pub fn run<S: ContactSolver, C: ControlSource<SlideControls>, const MONITOR: bool>(
        &mut self,
        solver: &mut S,
        controls: &mut C,
        count: usize,
        mut sink: impl FnMut(usize, Frame),
    ) {
        let mut done = 0;
        while done < count {
            if self.k == self.block {
                self.k = 0;
                self.block = self.next_block;
                if C::VARYING {
                    self.begin_block(controls);
                }
            }
            let run = (self.block - self.k).min(count - done);
            for i in done..done + run {
                sink(i, self.step::<S, MONITOR>(solver));
            }
            done += run;
        }
    }

    /// Advance `out.len()` samples writing only the output signal.
    pub fn process_output<S: ContactSolver, C: ControlSource<SlideControls>>(
        &mut self,
        solver: &mut S,
        controls: &mut C,
        out: &mut [f64],
    ) {
        self.run::<S, C, false>(solver, controls, out.len(), |i, f| out[i] = f.output);
    }
}

/// Write the Gram matrix `t` of the vectors `index` (upper triangle) into θ, symmetrically.
fn set_gram<const K: usize>(theta: &mut [[f64; 3]; 3], t: &[[f64; K]; K], index: [usize; K]) {
    for a in 0..K {
        for b in a..K {
            let (i, j) = (index[a], index[b]);
            theta[i][j] = t[a][b];
            theta[j][i] = t[a][b];
        }
    }
}

/// The control target names used by scene files and automation.
pub const CONTROL_TARGETS: [&str; 6] = [
    "slide.position",
    "hand.height",
    "finger.left.position",
    "finger.left.force",
    "finger.right.position",
    "finger.right.force",
];

/// Slide controls from breakpoint automation, one lane per target (in [`CONTROL_TARGETS`]
/// order), evaluated at `t = n/fs`.
#[derive(Debug, Clone, PartialEq)]
pub struct SlideAutomation {
    /// Lanes in [`CONTROL_TARGETS`] order.
    pub lanes: [crate::control::Breakpoints; 6],
    /// Sample rate (Hz).
    pub sample_rate: f64,
    /// Each lane's segment at the latest sample asked for (see `Breakpoints::at_cursor`).
    cursors: [usize; 6],
}

impl SlideAutomation {
    /// Automation from its lanes (in [`CONTROL_TARGETS`] order) at `sample_rate` (Hz).
    pub fn new(lanes: [crate::control::Breakpoints; 6], sample_rate: f64) -> Self {
        Self { lanes, sample_rate, cursors: [0; 6] }
    }

    /// The values at time `t` (s).
    pub fn at_time(&self, t: f64) -> SlideControls {
        let [a, b, c, d, e, f] = &self.lanes;
        SlideControls {
            slide_position: a.at(t),
            hand_height: b.at(t),
            left_position: c.at(t),
            left_force: d.at(t),
            right_position: e.at(t),
            right_force: f.at(t),
        }
    }

    /// Whether every lane is a single constant.
    pub fn is_constant(&self) -> bool {
        self.lanes.iter().all(|l| l.points().len() == 1)
    }
}

impl ControlSource<SlideControls> for SlideAutomation {
    const VARYING: bool = true;

    fn at(&mut self, n: u64) -> SlideControls {
        let t = n as f64 / self.sample_rate;
        let mut v = [0.0; 6];
        for ((v, lane), cursor) in v.iter_mut().zip(&self.lanes).zip(&mut self.cursors) {
            *v = lane.at_cursor(t, cursor);
        }
        let [slide_position, hand_height, left_position, left_force, right_position, right_force] = v;
        SlideControls { slide_position, hand_height, left_position, left_force, right_position, right_force }
    }
}
