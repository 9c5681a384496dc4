//! A slide pressed onto, slid along and lifted off a plucked string (seed §6, docs/physics.md §7).
//!
//! The string ([`ModalString`]) meets
//! - the slide at `x_o` through the power-law contact, `y = h_oᵀũ − w_o`, `h_o = v(x_o)`, with the
//!   slide held by the hand through the slide–hand oscillator ([`SlideHand`]);
//! - the left finger (trailing the slide, damping the dead part of the string) and the right
//!   finger (plucking), each a force `F_φe` spread over a half-cosine window with damping
//!   `F_φR = −r|F_φe| δ_t· u_φ` ([`finger`]).
//!
//! # One step (seed eqs. 65, 72–74; docs/physics.md §7.3)
//!
//! With the contact vectors `ĥ_ζ` (ζ ∈ {o, l, r}) of the step, their Gram matrix in the C metric
//! `θ_ζξ = Σ_i ĥ_ζ,i C_i ĥ_ξ,i`, `z_ζ = ĥ_ζᵀz̃`, `e_ζ = Σ_φ θ_ζφ F_φe`, `d_φ = e_φ − z_φ` and
//! `γ_φ = r|F_φe|/(2Δt)`, the finger damping forces are eliminated in closed form:
//!
//! ```text
//! Δ    = (1 + γ_l θ_ll)(1 + γ_r θ_rr) − γ_l γ_r θ_lr²
//! s_l  = [(1+γ_rθ_rr)(d_l + θ_lo F) − γ_rθ_lr(d_r + θ_ro F)] / Δ  ≡ s_l0 + s_l1 F
//! s_r  = [(1+γ_lθ_ll)(d_r + θ_ro F) − γ_lθ_rl(d_l + θ_lo F)] / Δ  ≡ s_r0 + s_r1 F
//! z_str = z_o − e_o + γ_l θ_ol s_l0 + γ_r θ_or s_r0
//! q_str = θ_oo − γ_l θ_ol s_l1 − γ_r θ_or s_r1
//! s + (z_str − z_sho − J) − (q_str + q_sho) F = 0                         (seed eq. 74, with J)
//! ```
//!
//! and after the solve `F_φR = −γ_φ s_φ` and
//! `ũ^{n+1} = ũ^{n−1} − z̃ + C(ĥ_o F + Σ_φ ĥ_φ (F_φe + F_φR))` (seed eq. 65 with the excitation
//! counted once).
//!
//! # Controls within a block (seed §6.7; docs/physics.md §7.5)
//!
//! Slide position `x_o`, hand height `w_H`, finger positions and finger forces come from a
//! [`ControlSource`] sampled at block boundaries every `N_b` samples and moved linearly inside
//! the block: the hand height and finger forces by ramps (the hand's bent into a parabola where
//! the instrument asks, [`SlideCore::bow_hand`]), and every contact vector by
//! interpolating between the exact vectors at the block's two ends,
//! `ĥ_ζ = (1 − a) h_ζ(x_ζ^start) + a h_ζ(x_ζ^end)` at fraction `a = k/N_b` of the block. A step
//! then projects `z̃` on both end vectors and spreads each force along both, and
//! `θ(a) = (1−a)² θ_ss + a(1−a)(θ_se + θ_es) + a² θ_ee` comes from one Gram matrix of the block's
//! vectors. The vectors are made at block boundaries only (or at the ends of a block's pieces,
//! below; an end vector becomes the next block's start vector), and only for contacts that touch
//! the string: the slide always, a finger while its force is non-zero at either end of the block.
//! With [`Fixed`](crate::control::Fixed) controls none of this runs.
//!
//! A straight line between two end vectors cuts the corner of each mode's shape as the shape
//! turns: mode `i` falls short of `h_i(x(t))` by about `(β_i Δx)²/8` mid-block for a travel `Δx`,
//! and the pressing force times that shortfall, back in every block and swelling with the speed,
//! is heard at multiples of `fs/N_b` (a vibrato's buzz). So the instrument's voices
//! ([`SlideCore::cut_blocks`]) cut a block whose touching contacts travel further than
//! [`PIECE_TURN`] allows the highest mode into equal pieces (at most [`MAX_PIECES`]), each planned
//! as a block of its own from the controls at its ends (which lie on the block's ramps, the
//! hand's on its parabola): the vectors are then made at the pieces' ends, and the scheme, and
//! its energy balance, is the same as a shorter block's. The scenes keep the seed's blocks whole (§6.7), as the report's
//! control-block study measures them.
//!
//! A force meets mode `i` through the scheme's static stiffness `K̂_i`, which exceeds the
//! continuous mode's `m̃ω_i²` by `(tan x/x)²`, `x = ω_iΔt/2` (23 times at 20 kHz at 44.1 kHz): a
//! pressed slide, a point support, then lets more of the string's motion through to the dead side
//! at lower rates, and a stopped note decays faster there. The instrument's voices
//! ([`SlideCore::couple_statically`]) reach mode `i` along `w_i h_i`, `w_i = √(K̂_i/(m̃ω_i²))`, in
//! every vector (slide, fingers, the body's lift, the pickup): in `q_i = w_i ũ_i` the seed's
//! scheme for a string whose mode `i` has mass `m̃/w_i²`, so the energy balance holds as it was
//! and each mode has its continuous static compliance; the lighter top modes answer fast force
//! changes more strongly (docs/physics.md §7.7). The scenes keep the seed's vectors.
//!
//! # The compression carried across a moving vector
//!
//! The contact potential is evaluated on carried compressions: `y^{n+1} = ĥ_oᵀũ^{n+1} − w_o^{n+1}`
//! is measured with the step's vector, and the step's `y^{n−1}` is the one the step before last
//! measured, with its own vector. Where the slide's vector changed in between, the string under
//! the slide now differs from the carried value by
//!
//! ```text
//! J = ĥ_o^nᵀũ^{n−1} − w_o^{n−1} − y^{n−1}
//! ```
//!
//! which enters the scalar problem above. The potential is then continuous in time, and the slide's
//! travel does the work `−½F^n J` on the system in the step (`F ≤ 0`): a force times a
//! displacement, the discrete form of `−F ∂_x u ẋ_o` (seed eq. 57). Re-measuring both
//! compressions with the new vector instead makes the potential jump by `V(y + J) − V(y)`, which
//! for a stiff contact (κ = 1e13 with α = 1, `J` of micrometres) is joules pumped into the
//! string in one step: the scheme blew up. The projections `ĥᵀũ^{n−1}` that `J` needs are kept
//! for the slide's two vectors by the update's own recursion
//! `hᵀũ^{n+1} = hᵀũ^{n−1} − hᵀz̃ + Σ_ζ hᵀ(C∘ĥ_ζ) F_ζ`, which needs only sums the step already has.
//!
//! # Energy (seed eqs. 75–80; docs/physics.md §7.4–7.5)
//!
//! `H^{n+1/2}` = string + SHO + contact. Per step the losses are `Δt(Q_str + Q_o + Σ Q_φ)` with
//! `Δt Q_φ = γ_φ s_φ²/2`, and the controls supply `Δt(P_H + Σ P_φ) − ½F J` with
//! `Δt P_φ = F_φe s_φ/2`: `H^{n+1/2} + losses − control work` is constant to rounding whatever
//! the controls do, since every vector used to distribute a force is the one used to project the
//! motion it works on.
//!
//! # A body at the bridge (docs/physics.md §13.5)
//!
//! With a body attached ([`SlideCore::attach_body`]) the string's far end moves with it,
//! `u = v + b·x/L`, as the piano's strings end on their bridge (`crate::scene::UnisonCore`): the
//! lift `g` on the modes (in its own vector slot), a lever `ℓ_ζ = x_ζ/L` on each contact, and the
//! string's static share of the bridge's mass and stiffness. Eliminating the bridge's
//! acceleration `a = a₀ + Σ_ζ (C_Σκ_ζ/Δ)F_ζ`, `κ_ζ = ℓ_ζ − θ_gζ/Δt²`, leaves the step above with
//!
//! ```text
//! θ'_ζξ = θ_ζξ + (Δt²C_Σ/Δ) κ_ζ κ_ξ,   z'_ζ = z_ζ − 2ℓ_ζ(b^n − b^{n−1}) − Δt² κ_ζ a₀
//! ```
//!
//! in place of `θ` and `z`; after the solve the string takes `−a` along `C∘g` and the body the
//! force `Σ_ζ κ_ζ F_ζ − G₀ + (Θ − E)a`. `H` gains the body's energy and the coupling's terms, and
//! the output is what the body radiates.

use crate::body::{BodyParams, RadiatingMode, Side};
use crate::contact::{ContactProblem, ContactSolution, ContactSolver};
use crate::control::{Bow, Bowed, ControlSource, Ramp};
use crate::exciter::{FingerParams, HandMotion, SlideHand, SlideParams, finger};
use crate::scene::{Frame, OutputKind, Pickup, Scene};
use crate::string::{GramVector, ModalBank, ModalString, StringEnergy, StringParams};

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

    /// The controls a fraction `t` of the way from `self` to `to`, every one linearly.
    pub fn lerp(&self, to: &Self, t: f64) -> Self {
        let at = |a: f64, b: f64| a + (b - a) * t;
        Self {
            slide_position: at(self.slide_position, to.slide_position),
            hand_height: at(self.hand_height, to.hand_height),
            left_position: at(self.left_position, to.left_position),
            left_force: at(self.left_force, to.left_force),
            right_position: at(self.right_position, to.right_position),
            right_force: at(self.right_force, to.right_force),
        }
    }
}

/// The most a contact's vector may turn across one piece of a control block: the angle
/// `β_max |Δx|` (rad) of the highest mode over the piece's travel `Δx`. A block whose contacts
/// travel further is cut into equal pieces with vectors made at their ends (module docs), where a
/// core cuts blocks at all ([`SlideCore::cut_blocks`]).
pub const PIECE_TURN: f64 = 0.05;

/// The most pieces a control block is cut into: a slide travelling fast enough to need more (a
/// glide or a jump at metres per second) sweeps its partials through the block-rate bands, which
/// hides what is left, and a block costs at most this many makings of the vectors.
pub const MAX_PIECES: usize = 16;

/// The slide's contact, then the left and the right finger.
const SLIDE: usize = 0;
const LEFT: usize = 1;
const RIGHT: usize = 2;

/// Slots of the contact vectors: contact `c` keeps the vector at its position at the block's
/// start in slot `2c` and the one at the block's end in slot `2c + 1`; the last slot holds the
/// lift `g` of a string whose end moves with a body ([`BRIDGE_SLOT`]).
const SLOTS: usize = 7;

/// The slot of the lift `g` (docs/physics.md §13.5), which belongs to "contact" [`BRIDGE`]: the
/// bridge's acceleration acts on the string's modes along it.
const BRIDGE_SLOT: usize = 6;
const BRIDGE: usize = 3;

/// The slot of contact `c`'s start (`end = false`) or end vector.
#[inline(always)]
const fn slot(c: usize, end: bool) -> usize {
    2 * c + end as usize
}

/// The contact a slot belongs to.
#[inline(always)]
const fn contact(slot: usize) -> usize {
    slot / 2
}

/// Which contact vectors a block's passes over the modes use.
///
/// A contact touches the string during a block if it is the slide (always) or a finger whose
/// force is non-zero at the block's start or end (a finger with zero force throughout neither
/// excites nor damps the string: `F_φe = 0`, `γ_φ = 0`). A touching contact whose position
/// changes across the block (with `N_b ≥ 2`) is interpolated between its start and end vectors,
/// so the passes use both; any other touching contact uses its start vector alone.
///
/// There are 128 plans, one for each combination, made once ([`PLANS`]): a block looks its plan
/// up, and two blocks have the same plan when they have the same key.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Plan {
    touching: [bool; 3],
    moving: [bool; 3],
    /// Whether the string's end moves with a body: the lift's slot is in use.
    bridge: bool,
    /// The slots in use, in order: `slots[..count]`.
    slots: [usize; SLOTS],
    count: usize,
    /// The plan's index in [`PLANS`]: its flags, one bit each.
    key: u8,
}

/// Every plan, by key (its flags, one bit each: see [`Plan::touching_bit`]).
static PLANS: [Plan; 128] = {
    let mut plans = [Plan::NONE; 128];
    let mut key = 0;
    while key < 128 {
        plans[key] = Plan::make(key as u8);
        key += 1;
    }
    plans
};

impl Plan {
    /// No contact at all (key 0).
    const NONE: Plan =
        Plan { touching: [false; 3], moving: [false; 3], bridge: false, slots: [0; SLOTS], count: 0, key: 0 };

    /// Bit of the key: contact `c` touches the string.
    const fn touching_bit(c: usize) -> u8 {
        1 << c
    }

    /// Bit of the key: contact `c` moves across the block.
    const fn moving_bit(c: usize) -> u8 {
        1 << (3 + c)
    }

    /// Bit of the key: the bridge's lift is in use.
    const BRIDGE_BIT: u8 = 1 << 6;

    /// The plan of `key`.
    fn of(key: u8) -> &'static Plan {
        &PLANS[usize::from(key & 127)]
    }

    /// The plan of the flags in `key`: the slots of the touching contacts in order (a moving
    /// one's start and end), then the lift's.
    const fn make(key: u8) -> Self {
        let mut plan = Plan {
            touching: [false; 3],
            moving: [false; 3],
            bridge: key & Plan::BRIDGE_BIT != 0,
            slots: [0; SLOTS],
            count: 0,
            key,
        };
        let mut c = 0;
        while c < 3 {
            plan.touching[c] = key & Plan::touching_bit(c) != 0;
            plan.moving[c] = plan.touching[c] && key & Plan::moving_bit(c) != 0;
            if plan.touching[c] {
                plan.slots[plan.count] = slot(c, false);
                plan.count += 1;
                if plan.moving[c] {
                    plan.slots[plan.count] = slot(c, true);
                    plan.count += 1;
                }
            }
            c += 1;
        }
        if plan.bridge {
            plan.slots[plan.count] = BRIDGE_SLOT;
            plan.count += 1;
        }
        plan
    }

    /// The first `V` slots (`V = count`).
    #[inline(always)]
    fn slots<const V: usize>(&self) -> [usize; V] {
        std::array::from_fn(|j| self.slots[j])
    }

    /// The weight of `slot`'s vector at fraction `a` of the block: `1 − a` and `a` for the start
    /// and end vectors of a moving contact, 1 for a contact held still.
    #[inline(always)]
    fn weight(&self, slot: usize, a: f64) -> f64 {
        if slot == BRIDGE_SLOT {
            return 1.0;
        }
        match (slot % 2 == 1, self.moving[contact(slot)]) {
            (true, _) => a,
            (false, true) => 1.0 - a,
            (false, false) => 1.0,
        }
    }
}

/// Run `$body` with the const `$v` equal to the runtime count `$count` (1 to [`SLOTS`]), so the
/// per-sample code is compiled once for each number of vectors.
macro_rules! with_count {
    ($count:expr, |$v:ident| $body:expr) => {
        match $count {
            1 => {
                const $v: usize = 1;
                $body
            }
            2 => {
                const $v: usize = 2;
                $body
            }
            3 => {
                const $v: usize = 3;
                $body
            }
            4 => {
                const $v: usize = 4;
                $body
            }
            5 => {
                const $v: usize = 5;
                $body
            }
            6 => {
                const $v: usize = 6;
                $body
            }
            _ => {
                const $v: usize = 7;
                $body
            }
        }
    };
}

/// The contact vectors of every slot, their gains and their Gram matrix.
#[derive(Debug, Clone)]
struct ContactVectors {
    /// `h` of each slot (dimensionless).
    shapes: [Vec<f64>; SLOTS],
    /// `C∘h` of each slot (m/N).
    gains: [Vec<f64>; SLOTS],
    /// Where each slot's vector was made (m); NaN before the first.
    made_at: [f64; SLOTS],
    /// `θ_jk = h_jᵀ(C∘h_k)` between the slots of the current plan (m/N), both triangles.
    gram: [[f64; SLOTS]; SLOTS],
    /// Per-mode factors of each contact's vectors: the fingers' windows, times the string's
    /// coupling weights where the core reaches the modes through their static stiffness
    /// ([`SlideCore::couple_statically`]), which the slide's are then (the lift, made whole in
    /// [`SlideCore::attach_body`], has none here).
    windows: [Option<Vec<f64>>; 4],
}

impl ContactVectors {
    fn new(string: &ModalString, left: &FingerParams, right: &FingerParams) -> Self {
        Self {
            shapes: std::array::from_fn(|_| string.vector()),
            gains: std::array::from_fn(|_| string.vector()),
            made_at: [f64::NAN; SLOTS],
            gram: [[0.0; SLOTS]; SLOTS],
            windows: [
                None,
                Some(finger::window_factors(string, left.width)),
                Some(finger::window_factors(string, right.width)),
                None,
            ],
        }
    }

    /// Exchange contact `c`'s start and end vectors (with their rows and columns of θ).
    fn swap_ends(&mut self, c: usize) {
        let (s, e) = (slot(c, false), slot(c, true));
        self.shapes.swap(s, e);
        self.gains.swap(s, e);
        self.made_at.swap(s, e);
        self.gram.swap(s, e);
        for row in &mut self.gram {
            row.swap(s, e);
        }
    }

    /// Make the slots marked in `fresh` at their positions (m) and the Gram matrix of `order`
    /// (a plan's slots, any order) in one [`ModalString::gram`]; returns the projections
    /// `(hᵀũ^{n−1}, hᵀũ^n)` (m) of the state on the first slot of `order`.
    fn update<const V: usize>(
        &mut self,
        string: &ModalString,
        order: [usize; V],
        fresh: [Option<f64>; SLOTS],
    ) -> (f64, f64) {
        let mut shapes = self.shapes.each_mut().map(Some);
        let mut gains = self.gains.each_mut().map(Some);
        let vectors: [GramVector<'_>; V] = std::array::from_fn(|j| {
            let k = order[j];
            GramVector {
                shape: shapes[k].take().expect("a plan names each slot once"),
                gain: gains[k].take().expect("a plan names each slot once"),
                window: self.windows[contact(k)].as_deref(),
                fresh: fresh[k].map(|x| string.shape_angle(x)),
            }
        });
        let (theta, state) = string.gram(vectors);
        for a in 0..V {
            for b in a..V {
                let (j, k) = (order[a], order[b]);
                self.gram[j][k] = theta[a][b];
                self.gram[k][j] = theta[a][b];
            }
        }
        for (made, at) in self.made_at.iter_mut().zip(fresh) {
            if let Some(x) = at {
                *made = x;
            }
        }
        state
    }
}

/// The coefficients `[c0, c1, c2]` of `θ_ζξ(a) = c0 + a·c1 + a²·c2` (m/N) between the contacts'
/// vectors interpolated over a block, `ĥ_ζ = w_s h_ζs + w_e h_ζe`, from the Gram matrix `g` of the
/// plan's slots: with `θ^{ss}`, `θ^{se} + θ^{es}` and `θ^{ee}` of a pair, `θ(a) = (1−a)²θ^{ss} +
/// a(1−a)(θ^{se} + θ^{es}) + a²θ^{ee}`, so `c0 = θ^{ss}`, `c1 = (θ^{se} + θ^{es}) − 2θ^{ss}` and
/// `c2 = θ^{ss} − (θ^{se} + θ^{es}) + θ^{ee}`. A contact held still has its start vector at both
/// ends.
fn block_theta(plan: &Plan, g: &[[f64; SLOTS]; SLOTS]) -> [[[f64; 3]; 3]; 3] {
    let mut theta = [[[0.0; 3]; 3]; 3];
    let ends = |c: usize| (slot(c, false), if plan.moving[c] { slot(c, true) } else { slot(c, false) });
    for i in (0..3).filter(|&i| plan.touching[i]) {
        for k in (0..3).filter(|&k| plan.touching[k]) {
            let ((is, ie), (ks, ke)) = (ends(i), ends(k));
            let (ss, mixed, ee) = (g[is][ks], g[is][ke] + g[ie][ks], g[ie][ke]);
            if plan.moving[i] || plan.moving[k] {
                theta[0][i][k] = ss;
                theta[1][i][k] = mixed - 2.0 * ss;
                theta[2][i][k] = ss - mixed + ee;
            } else {
                theta[0][i][k] = ss;
            }
        }
    }
    theta
}

/// What the controls give one step with `V` vectors (see [`SlideCore::step_controls`]).
#[derive(Debug, Clone, Copy)]
struct StepControls<const V: usize> {
    /// Fraction `a = k/N_b` of the block.
    a: f64,
    /// Weight of each slot's vector in its contact's interpolated vector.
    weights: [f64; V],
    /// Hand heights `w_H^{n−1}`, `w_H^n`, `w_H^{n+1}` (m).
    hand: HandMotion,
    /// Finger forces `F_φe` (N), left and right.
    finger_forces: [f64; 2],
    /// Finger damping coefficients `γ_φ = r_φ|F_φe|/(2Δt)` (N/m), left and right.
    gamma: [f64; 2],
}

/// The finger damping forces eliminated in closed form (module docs): the fingers' velocity
/// projections `s_φ = s_φ0 + s_φ1 F` and the slide's `z_str`, `q_str`.
#[derive(Debug, Clone, Copy)]
struct Elimination {
    s0: [f64; 2],
    s1: [f64; 2],
    z_str: f64,
    q_str: f64,
}

impl Elimination {
    /// From the Gram matrix `th` of the step's vectors (m/N), the projections `z` of `z̃` on
    /// them (m), the finger forces `f` (N) and damping coefficients `γ` (N/m).
    #[inline(always)]
    fn new(th: &[[f64; 3]; 3], z: [f64; 3], f: [f64; 2], g: [f64; 2]) -> Self {
        let e = [0, 1, 2].map(|a| th[a][1] * f[0] + th[a][2] * f[1]);
        let (d_l, d_r) = (e[1] - z[LEFT], e[2] - z[RIGHT]);
        let (g_l, g_r) = (g[0], g[1]);
        let (a_l, a_r) = (1.0 + g_l * th[1][1], 1.0 + g_r * th[2][2]);
        let det = a_l * a_r - g_l * g_r * th[1][2] * th[1][2];
        let s_l0 = (a_r * d_l - g_r * th[1][2] * d_r) / det;
        let s_l1 = (a_r * th[1][0] - g_r * th[1][2] * th[2][0]) / det;
        let s_r0 = (a_l * d_r - g_l * th[2][1] * d_l) / det;
        let s_r1 = (a_l * th[2][0] - g_l * th[2][1] * th[1][0]) / det;
        Self {
            s0: [s_l0, s_r0],
            s1: [s_l1, s_r1],
            z_str: z[SLIDE] - e[0] + g_l * th[0][1] * s_l0 + g_r * th[0][2] * s_r0,
            q_str: th[0][0] - g_l * th[0][1] * s_l1 - g_r * th[0][2] * s_r1,
        }
    }
}

/// The most a body mode's radiation weight is raised to make up for the scheme's droop at its
/// peak (`θ/sin θ`, 12 dB): reached at `θ = 0.79π`, 8.7 kHz at 22.05 kHz, above the guitar's
/// highest mode at every rate from 22.05 kHz up.
const MAX_DROOP_CORRECTION: f64 = 4.0;

/// A body at the string's far end (`x = L`, the bridge), coupled both ways (docs/physics.md
/// §13.5): the string's end moves with the bridge, `u = v + b·x/L`, the body's modes move under
/// the string's force on the bridge, and the bridge's acceleration is eliminated in closed form in
/// each step, which only adds a rank-one term to the contacts' Gram matrix.
///
/// The body is heard by `Σ r_j ẍ_j`, the acceleration taken as the centred second difference of the
/// modes' displacements. Through the scheme's step (its poles exact, its response a bilinear image
/// of the mode's) that peaks at each mode's own frequency `sin θ_j/θ_j` below the mode's true
/// acceleration, `θ_j = ω_jΔt` its damped frequency per step: −2.0 dB at 4 kHz at 22.05 kHz, −0.4
/// dB at 48 kHz. Each weight carries `θ_j/sin θ_j`, which makes up for it where the mode is heard
/// most, at most [`MAX_DROOP_CORRECTION`] (a mode near Nyquist would otherwise have its whole
/// response raised for its peak's sake). Only the output changes (the string and the energy see `e`
/// alone): the guitar's transmittance then holds within 3.4 % from 150 Hz to 10 kHz at 22.05 kHz
/// and 0.5 % at 44.1 kHz (10 % and 3.0 % without).
#[derive(Debug, Clone)]
struct BodyCoupling {
    /// The body's modes (at the bridge), `e` (1 on each: `b = eᵀx`), `C∘e`, and each mode's
    /// radiation weight `r_j θ_j/sin θ_j` (what `Σ r_j ẍ_j` is heard as).
    bank: ModalBank,
    sole: Vec<f64>,
    sole_gain: Vec<f64>,
    radiation: Vec<f64>,
    /// The radiation weights of the modes heard on the left and on the right ([`Side`]), zero
    /// on the others.
    sides: [Vec<f64>; 2],
    /// `C_Σ = eᵀ(C∘e)` (m/N).
    compliance: f64,
    /// The string's static share of the bridge's mass `ρAL/3` (kg) and stiffness `T/L` (N/m).
    lift_mass: f64,
    lift_stiffness: f64,
    /// `(b^{n−1}, b^n)` (m), `(gᵀũ^{n−1}, gᵀũ^n)` (kg·m), `(rᵀx^{n−1}, rᵀx^n)` and the same of
    /// each side's weights.
    b: (f64, f64),
    lifted: (f64, f64),
    heard: (f64, f64),
    heard_sides: [(f64, f64); 2],
    /// What the modes on each side radiated at the last step.
    sides_now: [f64; 2],
    /// Whether the string's end moves with the body; else the end is held and the body rests.
    on: bool,
}

impl BodyCoupling {
    /// `body` at `string`'s sample rate, at rest and off. Allocates.
    fn new(body: &BodyParams, string: &ModalString) -> Self {
        let fs = string.sample_rate();
        let kept: Vec<&RadiatingMode> = body.modes.iter().filter(|m| m.mode.frequency < 0.49 * fs).collect();
        let mut bank = ModalBank::with_capacity(kept.len(), fs);
        for m in &kept {
            let omega0 = std::f64::consts::TAU * m.mode.frequency;
            bank.push_oscillator(omega0, 0.5 * m.mode.loss_factor * omega0, m.mode.mass);
        }
        bank.finish();
        let (mut sole, mut sole_gain, mut radiation) = (Vec::new(), Vec::new(), Vec::new());
        let mut sides = [Vec::new(), Vec::new()];
        let [left, right] = &mut sides;
        for v in [&mut sole, &mut sole_gain, &mut radiation, left, right] {
            bank.fit_vector(v);
        }
        for (j, m) in kept.iter().enumerate() {
            sole[j] = 1.0;
            sole_gain[j] = bank.input_gains()[j];
            // The scheme's droop at the mode's own peak, made up for (see the struct's docs).
            let omega0 = std::f64::consts::TAU * m.mode.frequency;
            let sigma = 0.5 * m.mode.loss_factor * omega0;
            let theta = (omega0 * omega0 - sigma * sigma).max(0.0).sqrt() / fs;
            let made_up = if theta > 0.0 { (theta / theta.sin()).min(MAX_DROOP_CORRECTION) } else { 1.0 };
            let weight = m.radiation * made_up;
            radiation[j] = weight;
            match m.side {
                Side::Left => sides[0][j] = weight,
                Side::Right => sides[1][j] = weight,
                Side::Centre => {}
            }
        }
        let compliance = bank.project(&sole, &sole_gain);
        let p = string.params();
        Self {
            bank,
            sole,
            sole_gain,
            radiation,
            sides,
            compliance,
            lift_mass: p.linear_density * p.length / 3.0,
            lift_stiffness: p.tension / p.length,
            b: (0.0, 0.0),
            lifted: (0.0, 0.0),
            heard: (0.0, 0.0),
            heard_sides: [(0.0, 0.0); 2],
            sides_now: [0.0; 2],
            on: false,
        }
    }

    /// Bring the body to rest, with the string (whose projection on the lift is then 0).
    fn rest(&mut self) {
        self.bank.reset();
        self.b = (0.0, 0.0);
        self.lifted = (0.0, 0.0);
        self.heard = (0.0, 0.0);
        self.heard_sides = [(0.0, 0.0); 2];
        self.sides_now = [0.0; 2];
    }

    /// Step the body under the force `force` (N) on the bridge, `dt` (s) on from the last step
    /// (its history taken), returning the radiated `Σ r_j ẍ_j` at this step (keeping each side's
    /// share of it for [`SlideCore::heard_sides`]) and, with `MONITOR`, the energy of the body and
    /// of the coupling at `n + 1/2` and what the body dissipated.
    #[inline(always)]
    fn advance<const MONITOR: bool>(&mut self, force: f64, dt: f64) -> (f64, StringEnergy) {
        let forces = [(&self.sole_gain[..], force)];
        let (b_next, mut energy) = if MONITOR {
            let (b, stored, dissipated) = self.bank.advance_monitored(forces, &self.sole);
            (b, StringEnergy { stored, dissipated })
        } else {
            (self.bank.advance_projecting(forces, &self.sole, []).0, StringEnergy::default())
        };
        let [heard_next, sides_next @ ..] =
            self.bank.project_now_each([&self.radiation, &self.sides[0], &self.sides[1]]);
        let heard = (heard_next - 2.0 * self.heard.1 + self.heard.0) / (dt * dt);
        for ((now, sum), next) in self.sides_now.iter_mut().zip(&mut self.heard_sides).zip(sides_next) {
            *now = (next - 2.0 * sum.1 + sum.0) / (dt * dt);
            *sum = (sum.1, next);
        }
        if MONITOR {
            // The lift has moved on already: `lifted` holds `(gᵀũ^n, gᵀũ^{n+1})`.
            let (db, mean) = ((b_next - self.b.1) / dt, 0.5 * (b_next + self.b.1));
            let cross = (self.lifted.1 - self.lifted.0) / dt * db;
            energy.stored += cross + 0.5 * self.lift_mass * db * db + 0.5 * self.lift_stiffness * mean * mean;
        }
        self.b = (self.b.1, b_next);
        self.heard = (self.heard.1, heard_next);
        (heard, energy)
    }

    /// The energy of the body and of the string's motion with its end (J), the numerical
    /// `H^{n−1/2}` of docs/physics.md §12.
    fn energy(&self, dt: f64) -> f64 {
        let (db, mean) = ((self.b.1 - self.b.0) / dt, 0.5 * (self.b.1 + self.b.0));
        let cross = (self.lifted.1 - self.lifted.0) / dt * db;
        self.bank.energy() + cross + 0.5 * self.lift_mass * db * db + 0.5 * self.lift_stiffness * mean * mean
    }
}

/// One step's bridge, eliminated (docs/physics.md §13.5): the contacts' Gram matrix and
/// projections with the bridge folded in, and how the bridge's acceleration and the force on it
/// follow from the contact forces.
#[derive(Debug, Clone, Copy)]
struct BridgeStep {
    theta: [[f64; 3]; 3],
    z: [f64; 3],
    /// `a = a₀ + Σ_ζ a_ζ F_ζ` (m/s²).
    a0: f64,
    a1: [f64; 3],
    /// `f = Σ_ζ κ_ζ F_ζ − G₀ + (Θ − E) a` (N).
    kappa: [f64; 3],
    g0: f64,
    theta_e: f64,
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

    /// The same scene with `body` at the string's far end, coupled both ways (docs/physics.md
    /// §13.5); its output is then what the body radiates.
    pub fn with_body(mut self, body: &BodyParams) -> Self {
        self.core.attach_body(body, true);
        self
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
        self.core.run::<S, C, true>(&mut self.solver, &mut self.controls, frames.len(), |i, f, _| frames[i] = f);
    }

    fn process_output(&mut self, out: &mut [f64]) {
        self.core.process_output(&mut self.solver, &mut self.controls, out, None);
    }
}

/// Everything of a slide–string scene except the solver and the control source: string, slide
/// and hand, fingers, contact vectors and the block ramps. An instrument voice keeps one core and
/// one solver of each kind and feeds the controls itself.
#[derive(Debug, Clone)]
pub struct SlideCore {
    string: ModalString,
    sho: SlideHand,
    vectors: ContactVectors,
    /// The current block's vectors.
    plan: &'static Plan,
    /// `θ_ζξ(a) = c0 + a·c1 + a²·c2` between the contacts' interpolated vectors over the block
    /// (m/N): `[c0, c1, c2]`, zero for contacts that do not touch.
    theta: [[[f64; 3]; 3]; 3],
    pickup: Vec<f64>,
    kind: OutputKind,
    /// While the pickup glides to new weights ([`set_pickup`](Self::set_pickup)): the weights it
    /// left, their projection `pᵀũ^n` on the state, and the glide's steps done and in all.
    pickup_from: Vec<f64>,
    out_from: f64,
    glide: (usize, usize),
    /// Finger damping parameters r (s/m).
    r: [f64; 2],
    block: usize,
    /// `1/N_b` of the current block.
    inv_block: f64,
    /// Block length to use from the next block boundary.
    next_block: usize,
    /// Sample index of the next step.
    n: u64,
    /// Index of the next step within its block.
    k: usize,
    /// Controls at the start of the current block and at the start of the next.
    start: SlideControls,
    target: SlideControls,
    hand: Bowed,
    /// The hand's height at the current whole block's start (m) and the sag of its path across
    /// the block that [`bow_hand`](Self::bow_hand) asked for (m): with the height at its end,
    /// `whole_end`'s, the path ([`whole_hand`](Self::whole_hand)).
    hand_from: f64,
    hand_sag: f64,
    /// The sag (m) of the hand's path across the next block ([`bow_hand`](Self::bow_hand)).
    next_hand_sag: f64,
    left_force: Ramp,
    right_force: Ramp,
    /// `w_H^{n−1}` (m).
    hand_prev: f64,
    /// The carried compressions `y^{n−1}`, `y^n` (m): each measured with the slide vector of the
    /// step that made it.
    y_prev: f64,
    y_now: f64,
    /// `(hᵀũ^{n−1}, hᵀũ^n)` (m) for the slide's start and end vectors, kept by the string
    /// update's own recursion (used when the slide vector changes).
    slide_state: [[f64; 2]; 2],
    /// Whether the slide's vector in the block's first step differs from the one before it.
    slide_jumped: bool,
    /// Steps since the slide's vector last changed (saturating).
    slide_still: u32,
    /// A control block cut into pieces (module docs): its controls at its end, its length, the
    /// number of pieces and the index of the piece under way; one piece when the block is whole.
    whole_end: SlideControls,
    whole_len: usize,
    pieces: usize,
    piece: usize,
    /// `β_max`, the highest mode's wavenumber (1/m).
    beta_max: f64,
    /// The most a contact's vector may turn across a piece of a block (rad): infinite, blocks
    /// whole, unless [`cut_blocks`](Self::cut_blocks) says otherwise.
    piece_turn: f64,
    out_now: f64,
    losses: f64,
    control_work: f64,
    /// Contact force of the latest step (N).
    last_force: f64,
    /// A body at the string's far end, if one is attached (docs/physics.md §13.5).
    body: Option<BodyCoupling>,
    dt: f64,
}

impl SlideCore {
    /// A core around `string` (prepared at the scene's sample rate): the string at rest and the
    /// slide resting at the hand's height, with controls `start` now and `target` one block on.
    pub fn new(string: ModalString, params: &SlideStringParams, start: SlideControls, target: SlideControls) -> Self {
        let fs = string.sample_rate();
        let block = params.block.max(1);
        let mut pickup = string.vector();
        params.pickup.weights(&string, &mut pickup);
        let mut pickup_from = string.vector();
        pickup_from.clone_from(&pickup);
        let sho = SlideHand::new(params.slide, fs, start.hand_height);
        let mut core = Self {
            vectors: ContactVectors::new(&string, &params.left, &params.right),
            // No contact at all until the first block is planned.
            plan: Plan::of(0),
            theta: [[[0.0; 3]; 3]; 3],
            pickup,
            kind: params.pickup.kind,
            pickup_from,
            out_from: 0.0,
            glide: (0, 0),
            r: [params.left.damping, params.right.damping],
            block,
            inv_block: 1.0 / block as f64,
            next_block: block,
            n: 0,
            k: 0,
            start,
            target,
            hand: Bowed::new(start.hand_height, target.hand_height, block, 0.0),
            hand_from: start.hand_height,
            hand_sag: 0.0,
            next_hand_sag: 0.0,
            left_force: Ramp::new(start.left_force, target.left_force, block),
            right_force: Ramp::new(start.right_force, target.right_force, block),
            hand_prev: start.hand_height,
            y_prev: 0.0,
            y_now: 0.0,
            slide_state: [[0.0; 2]; 2],
            slide_jumped: false,
            slide_still: u32::MAX,
            whole_end: target,
            whole_len: block,
            pieces: 1,
            piece: 0,
            beta_max: string.wavenumbers().iter().fold(0.0, |m: f64, &b| m.max(b)),
            piece_turn: f64::INFINITY,
            out_now: 0.0,
            losses: 0.0,
            control_work: 0.0,
            last_force: 0.0,
            body: None,
            dt: 1.0 / fs,
            string,
            sho,
        };
        core.plan_block();
        // The compressions start out measured with the first slide vector.
        let [p, n] = core.slide_state[0];
        core.y_prev = p - core.sho.previous();
        core.y_now = n - core.sho.position();
        core.slide_jumped = false;
        core.out_now = core.string.project_state(&core.pickup).1;
        core
    }

    /// Bring the string to rest and the slide to rest at the hand height of `controls`, held
    /// from now on until the controls move again (`N_b`, parameters and the pickup are kept).
    /// Never allocates.
    pub fn rest(&mut self, controls: SlideControls) {
        self.string.reset();
        if let Some(body) = &mut self.body {
            body.rest();
        }
        self.sho.rest(controls.hand_height);
        self.start = controls;
        self.target = controls;
        self.hand = Bowed::new(controls.hand_height, controls.hand_height, self.block, 0.0);
        (self.hand_from, self.hand_sag, self.next_hand_sag) = (controls.hand_height, 0.0, 0.0);
        self.whole_end = controls;
        self.left_force = Ramp::new(controls.left_force, controls.left_force, self.block);
        self.right_force = Ramp::new(controls.right_force, controls.right_force, self.block);
        self.hand_prev = controls.hand_height;
        if self.pieces > 1 {
            // A block cut short by its pieces is whole again.
            self.block = self.whole_len;
            self.inv_block = 1.0 / self.block as f64;
        }
        self.plan_block();
        self.slide_state = [[0.0; 2]; 2];
        self.slide_jumped = false;
        self.slide_still = u32::MAX;
        (self.pieces, self.piece) = (1, 0);
        self.y_prev = -self.sho.previous();
        self.y_now = -self.sho.position();
        self.out_now = 0.0;
        self.out_from = 0.0;
        self.glide = (0, 0);
        self.last_force = 0.0;
    }

    /// Bring string, slide, hand and body (if the string's end moves with one) to the static
    /// equilibrium of the scheme under the still `controls`: each finger pressing with its force,
    /// the hand at its height and the slide pressed onto the string as far as the hand's spring
    /// and the contact balance, held from now on until the controls move again. `slope(y, q_N)`
    /// is the magnitude `V̂'(y)` (N) of the contact force the solver will hold at a still
    /// compression `y` (m), given the compliance `q_N` (m/N) the contact meets at the Nyquist rate
    /// there ([`nyquist_compliance`](Self::nyquist_compliance)): the spline's slope for QSA, the
    /// law's `κy^α` for IMP, at most a share of the stiffness EXP can hold for EXP
    /// ([`ExplicitSolver::still_force`](crate::contact::ExplicitSolver::still_force)). Returns
    /// whether the slide touches the string there (else the state holds the fingers' deflection
    /// alone, the slide still at the hand's height, which is the equilibrium too); `None`, with
    /// the core at rest as [`rest`](Self::rest) leaves it, if the hand has no spring to hold the
    /// slide still. Never allocates; O(modes).
    ///
    /// With `K̂_i` the scheme's static stiffness (the string's update leaves `ũ_i = f_i/K̂_i` where
    /// it is under a static modal force `f_i`), the string's end on the body at `b = C'Σ_ζ ℓ_ζF_ζ`
    /// (`C' = C_b/(1 + C_b T/L)`, `C_b = Σ_j 1/K̂_j` of the body's modes, the string's `T/L`
    /// pulling its end back) and the slide at `w_o = w_H − F/k_H`, the compression is linear in
    /// the slide's force `F ≤ 0`: `y = d + A F` with `A = h_oᵀK̂⁻¹h_o + C'ℓ_o² + 1/k_H` and
    /// `d = Σ_φ (h_oᵀK̂⁻¹h_φ + C'ℓ_oℓ_φ) F_φe − w_H`; the contact closes it, `F = −V̂'(y)`, a
    /// monotone scalar equation `y + A V̂'(y) = d`, solved by bisection for `y ∈ (0, d]`.
    pub fn rest_pressed(&mut self, controls: SlideControls, slope: impl Fn(f64, f64) -> f64) -> Option<bool> {
        self.rest(controls);
        let k_h = self.sho.params().stiffness;
        if !(k_h > 0.0) {
            return None;
        }
        let length = self.string.params().length;
        let plan = self.plan;
        let fingers = [LEFT, RIGHT].map(|c| {
            let force = [controls.left_force, controls.right_force][c - 1];
            if plan.touching[c] { force } else { 0.0 }
        });
        let positions = controls.positions();
        let levers = positions.map(|x| x / length);
        // The body's static compliance at the bridge, with the string's own pull on its end.
        let compliance = match &self.body {
            Some(body) if body.on => {
                let c_b: f64 = body.bank.stiffness().iter().map(|k| 1.0 / k).sum();
                c_b / (1.0 + c_b * body.lift_stiffness)
            }
            _ => 0.0,
        };
        let (modes, stiffness) = (self.string.modes(), self.string.stiffness());
        let shapes = &self.vectors.shapes;
        let slide = &shapes[slot(SLIDE, false)][..modes];
        let mut a = 1.0 / k_h + compliance * levers[SLIDE] * levers[SLIDE];
        let mut d = -controls.hand_height;
        for (i, (&h, &k)) in slide.iter().zip(stiffness).enumerate() {
            a += h * h / k;
            for c in [LEFT, RIGHT] {
                if fingers[c - 1] != 0.0 {
                    d += h * shapes[slot(c, false)][i] / k * fingers[c - 1];
                }
            }
        }
        for c in [LEFT, RIGHT] {
            d += compliance * levers[SLIDE] * levers[c] * fingers[c - 1];
        }
        let nyquist = self.nyquist_compliance();
        let slope = |y| slope(y, nyquist);
        // `y + A V̂'(y) = d`: increasing in `y`, negative at 0 and non-negative at `d`.
        let pressed = (d > 0.0).then(|| {
            let (mut lo, mut hi) = (0.0, d);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if mid <= lo || mid >= hi {
                    break;
                }
                if mid + a * slope(mid) > d { hi = mid } else { lo = mid }
            }
            let residual = |y: f64| (y + a * slope(y) - d).abs();
            if residual(lo) < residual(hi) { lo } else { hi }
        });
        let force = pressed.map_or(0.0, |y| -slope(y));
        let along = [force, fingers[0], fingers[1]];
        let vectors = [0, 1, 2].map(|c| (c == SLIDE || along[c] != 0.0).then(|| &shapes[slot(c, false)][..]));
        self.string.rest_under(|i| {
            let mut f = 0.0;
            for c in 0..3 {
                if let Some(h) = vectors[c] {
                    f += h[i] * along[c];
                }
            }
            f
        });
        let mut under = self.string.project_state(&shapes[slot(SLIDE, false)]).1;
        self.slide_state = [[under; 2], [self.string.project_state(&shapes[slot(SLIDE, true)]).1; 2]];
        if let Some(body) = self.body.as_mut().filter(|b| b.on) {
            let on_bridge: f64 = (0..3).map(|c| levers[c] * along[c]).sum();
            let b = compliance * on_bridge;
            let pull = on_bridge - body.lift_stiffness * b;
            body.bank.rest_under(|_| pull);
            let b = body.bank.project_state(&body.sole).1;
            let lifted = self.string.project_state(&shapes[BRIDGE_SLOT]).1;
            let heard = body.bank.project_state(&body.radiation).1;
            let sides = [0, 1].map(|j| body.bank.project_state(&body.sides[j]).1);
            body.b = (b, b);
            body.lifted = (lifted, lifted);
            body.heard = (heard, heard);
            body.heard_sides = sides.map(|x| (x, x));
            body.sides_now = [0.0; 2];
            under += levers[SLIDE] * b;
        }
        self.sho.rest(controls.hand_height - force / k_h);
        // The carried compressions are the ones the force belongs to (the state measures them
        // within rounding: `under − w_o`).
        let y = pressed.unwrap_or(under - self.sho.position());
        self.y_prev = y;
        self.y_now = y;
        self.out_now = self.string.project_state(&self.pickup).1;
        self.out_from = self.string.project_state(&self.pickup_from).1;
        self.last_force = force;
        Some(pressed.is_some())
    }

    /// The compliance `q_N` (m/N) the slide's contact meets at the Nyquist rate, where the slide
    /// is now: the compression's answer `y^n = −(q_N/4)F^n` to a force alternating from step to
    /// step. There `μ_t²` and `δ_t·` vanish, so stiffness and damping drop out and each mode, the
    /// slide on its hand and each of the body's modes answers as its mass alone, `Δt²/(4m)`:
    /// `q_N = Δt²(Σ_i h_i²/m̃ + 1/m_o + ℓ_o²Σ_j 1/m_j)` (the body's modes reached through the
    /// lever `ℓ_o = x_o/L`; the string's share of the bridge's mass left out: over 200 random
    /// pressed notes on both guitars, EXP started still at shares 0.98 of `k_e q_N/4 = 1` all
    /// held and at 1.02 some grew, and [`STILL_SHARE`](crate::contact::STILL_SHARE) stays a factor
    /// of two below). It exceeds the step's coupling `q` (each mode's `C_i` is `Δt²/(4m̃)` times
    /// `1 + 2P_i + Q_i ≤ 4`), about 3.3 times with the defaults, from the modes near Nyquist.
    /// Never allocates; O(modes).
    pub fn nyquist_compliance(&self) -> f64 {
        let dt2 = self.dt * self.dt;
        let h = &self.vectors.shapes[slot(SLIDE, false)][..self.string.modes()];
        let modes: f64 = h.iter().map(|h| h * h).sum::<f64>() / self.string.modal_mass();
        let body = match &self.body {
            Some(body) if body.on => {
                let lever = self.start.slide_position / self.string.params().length;
                lever * lever * body.bank.masses().iter().map(|m| 1.0 / m).sum::<f64>()
            }
            _ => 0.0,
        };
        dt2 * (modes + 1.0 / self.sho.params().mass + body)
    }

    /// As made, for a core brought to rest ([`rest`](Self::rest)): the control blocks counted
    /// from this step and the energy's books at zero.
    pub fn restart(&mut self) {
        (self.n, self.k) = (0, 0);
        self.open_books();
    }

    /// Start the energy books afresh: no losses and no control work so far. A state gone
    /// non-finite leaves NaN in them, which every later difference of the work would carry.
    pub fn open_books(&mut self) {
        (self.losses, self.control_work) = (0.0, 0.0);
    }

    /// Attach `body` at the string's far end (the bridge, `x = L`), at rest, the string's end
    /// moving with it if `on` (see [`set_body`](Self::set_body)). Call it on a core at rest,
    /// before its first step. Allocates: call it before the audio thread runs.
    pub fn attach_body(&mut self, body: &BodyParams, on: bool) {
        let coupling = BodyCoupling::new(body, &self.string);
        // The lift `g_i = ρA(−1)^{i+1}/β_i` (mode `i` from 1), with the coupling weights where
        // the slide's vectors carry them, and its gain `C∘g`.
        let (string, v) = (&self.string, &mut self.vectors);
        let rho = string.params().linear_density;
        let (lift, gain) = (&mut v.shapes[BRIDGE_SLOT], &mut v.gains[BRIDGE_SLOT]);
        lift.fill(0.0);
        gain.fill(0.0);
        let weights = v.windows[SLIDE].as_deref();
        for (i, &beta) in string.wavenumbers().iter().enumerate() {
            let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
            lift[i] = sign * rho / beta * weights.map_or(1.0, |w| w[i]);
            gain[i] = lift[i] * string.input_gains()[i];
        }
        self.body = Some(BodyCoupling { on, ..coupling });
        self.plan_block();
        self.slide_jumped = false;
    }

    /// Reach every mode through the continuous mode's static stiffness `m̃ω0_i²` rather than the
    /// scheme's `K̂_i` (module docs): the slide's and the fingers' vectors, the pickup's weights
    /// and the body's lift (attached after) carry the string's coupling weights
    /// ([`ModalString::coupling_weights`]). Call it on a core at rest, before its first step and
    /// before [`attach_body`](Self::attach_body). Allocates: call it before the audio thread runs.
    pub fn couple_statically(&mut self) {
        let weights = self.string.coupling_weights();
        let v = &mut self.vectors;
        for window in v.windows[LEFT..=RIGHT].iter_mut().flatten() {
            window.iter_mut().zip(&weights).for_each(|(f, w)| *f *= w);
        }
        for pickup in [&mut self.pickup, &mut self.pickup_from] {
            pickup.iter_mut().zip(&weights).for_each(|(p, w)| *p *= w);
        }
        v.windows[SLIDE] = Some(weights);
        v.made_at = [f64::NAN; SLOTS];
        self.plan_block();
    }

    /// The string's coupling weights, if the core reaches the modes through them
    /// ([`couple_statically`](Self::couple_statically)).
    pub fn coupling_weights(&self) -> Option<&[f64]> {
        self.vectors.windows[SLIDE].as_deref()
    }

    /// Cut each control block from the next on into pieces over which no contact's vector turns
    /// by more than `turn` (rad) at the highest mode (module docs); `f64::INFINITY` keeps blocks
    /// whole, as made.
    pub fn cut_blocks(&mut self, turn: f64) {
        self.piece_turn = turn;
    }

    /// Bow the hand's path across the next control block (the one [`start_block`](Self::start_block)
    /// begins, or else the next the controls begin) into a parabola passing `sag` (m) below the
    /// straight line between the block's end heights halfway along; the block after is straight
    /// again unless bowed anew. Pieces of the block ([`cut_blocks`](Self::cut_blocks)) follow the
    /// parabola. The instrument's voices pull the hand along a path whose speed ramps within each
    /// block rather than jumping at its boundaries (`instrument::slide_voice::HandPath`).
    pub fn bow_hand(&mut self, sag: f64) {
        self.next_hand_sag = sag;
    }

    /// Couple the string's end to the attached body (`on`) or hold it still, and bring string,
    /// body and slide to rest as [`rest`](Self::rest) does with `controls`. Never allocates.
    pub fn set_body(&mut self, on: bool, controls: SlideControls) {
        if let Some(body) = &mut self.body {
            body.on = on;
        }
        self.rest(controls);
    }

    /// Whether the string's end moves with a body.
    pub fn body_on(&self) -> bool {
        self.body.as_ref().is_some_and(|b| b.on)
    }

    /// What the body's modes heard on the left and on the right ([`Side`]) radiated at the last
    /// step: shares of the output, the rest of it heard in the centre (zero without a body).
    pub fn heard_sides(&self) -> [f64; 2] {
        self.body.as_ref().filter(|b| b.on).map_or([0.0; 2], |b| b.sides_now)
    }

    /// The string, for tests that need to put a state into it by hand (the carried
    /// projections then no longer match it).
    #[cfg(test)]
    pub(crate) fn string_mut(&mut self) -> &mut ModalString {
        &mut self.string
    }

    /// `(y^{n−1}, y^n)` (m), to start a solver from.
    pub fn compressions(&self) -> (f64, f64) {
        (self.y_prev, self.y_now)
    }

    /// New slide-and-hand and finger-damping parameters and control block length N_b (samples),
    /// taking effect at once (the block length at the next block boundary). Keeps the motion: a
    /// new hand stiffness or slide mass under a pressed, moving slide changes the energy the hand
    /// and the slide hold, which the books do not count as work (the balance steps there).
    pub fn set_params(&mut self, slide: SlideParams, finger_damping: [f64; 2], block: usize) {
        self.sho.set_params(slide);
        self.r = finger_damping;
        self.next_block = block.max(1);
    }

    /// Begin a control block of `len` steps at the next step, in place of the rest of the block
    /// under way: a caller with blocks of its own (the instrument's, fixed in time) keeps the
    /// core's on them. The controls start from the latest block's target, so call it where that
    /// block has run whole or the controls stand still (a core at rest).
    pub fn start_block(&mut self, len: usize) {
        self.next_block = len.max(1);
        self.k = self.block;
        (self.pieces, self.piece) = (1, 0);
    }

    /// Move the pickup to `pickup` (the string's output weights), gliding over the next `glide`
    /// steps: each step's output is `(1 − t)·o_from + t·o_to` at `t = j/glide` for the `j`-th step,
    /// the outputs the weights heard now and the new weights give, so the output's weighting moves
    /// linearly across the glide instead of stepping (a step of the weights makes a step of the
    /// output proportional to the string's slope at the pickup). A change of output kind, or of the
    /// string's modes, does not glide. Never allocates.
    pub fn set_pickup(&mut self, pickup: Pickup, glide: usize) {
        let (done, len) = self.glide;
        if self.pickup_from.len() == self.pickup.len() {
            if done < len {
                let t = done as f64 / len as f64;
                for (from, to) in self.pickup_from.iter_mut().zip(&self.pickup) {
                    *from += t * (to - *from);
                }
            } else {
                self.pickup_from.copy_from_slice(&self.pickup);
            }
        }
        let s = &self.string;
        s.fit_vector(&mut self.pickup);
        pickup.weights(s, &mut self.pickup);
        if let Some(weights) = &self.vectors.windows[SLIDE] {
            self.pickup.iter_mut().zip(weights).for_each(|(p, w)| *p *= w);
        }
        let glides = glide > 0 && self.kind == pickup.kind && self.pickup_from.len() == self.pickup.len();
        self.kind = pickup.kind;
        self.out_now = s.project_state(&self.pickup).1;
        if !glides {
            // Within the capacity both vectors were made with: no allocation.
            self.pickup_from.clear();
            self.pickup_from.extend_from_slice(&self.pickup);
        }
        self.out_from = s.project_state(&self.pickup_from).1;
        self.glide = if glides { (0, glide) } else { (0, 0) };
    }

    /// One step's output while the pickup glides (see [`set_pickup`](Self::set_pickup)), from
    /// `output`, the new weights' output, after the string has advanced.
    #[cold]
    fn glide_output(&mut self, output: f64) -> f64 {
        let out_next = self.string.project_state(&self.pickup_from).1;
        let from = self.kind.sample(self.out_from, out_next, self.dt);
        self.out_from = out_next;
        self.glide.0 += 1;
        let t = self.glide.0 as f64 / self.glide.1 as f64;
        from + t * (output - from)
    }

    /// What a monitor shows: `(compression y^n (m), latest contact force (N), slide position x_o (m))`.
    pub fn contact(&self) -> (f64, f64, f64) {
        let (from, to) = (self.start.slide_position, self.target.slide_position);
        (self.y_now, self.last_force, from + (to - from) * self.k as f64 * self.inv_block)
    }

    /// Whether the slide touches the string (now or one step back).
    pub fn in_contact(&self) -> bool {
        self.y_now > 0.0 || self.y_prev > 0.0
    }

    /// String and slide energy of the current state (J), with the body's and the coupling's when
    /// the string's end moves with one, without the contact term.
    pub fn energy(&self) -> f64 {
        self.energies().1
    }

    /// The string's kinetic energy and the string and slide energy of the current state (J),
    /// without the contact term, from one pass over the modes.
    pub fn energies(&self) -> (f64, f64) {
        let (kinetic, string) = self.string.energies();
        let body = self.body.as_ref().filter(|b| b.on).map_or(0.0, |b| b.energy(self.dt));
        (kinetic, string + body + self.sho.energy(self.hand_prev, self.hand.at(self.k)))
    }

    /// Work the controls have done on the string and the slide since the core was made (J):
    /// the moving hand, the fingers' forces and the slide's travel (module docs).
    pub fn control_work(&self) -> f64 {
        self.control_work
    }

    /// The string.
    pub fn string(&self) -> &ModalString {
        &self.string
    }

    /// Plan the block that starts now, from the controls at its start (`self.start`) and end
    /// (`self.target`): which vectors the passes use, and make those that are missing. A
    /// contact's start vector is usually the last block's end vector (swapped in); vectors are
    /// made only for positions no slot holds, and the Gram matrix of every slot in use is
    /// recomputed whenever a vector or the set of touching contacts changed, so θ always belongs
    /// to the current positions and touching set.
    fn plan_block(&mut self) {
        let (start, end) = (self.start.positions(), self.target.positions());
        let touching = [true, self.start.left_force != 0.0 || self.target.left_force != 0.0, {
            self.start.right_force != 0.0 || self.target.right_force != 0.0
        }];
        // The plan's key is gathered bit by bit (see `Plan::touching_bit`).
        let mut key = if self.body_on() { Plan::BRIDGE_BIT } else { 0 };
        let was = self.plan;
        let v = &mut self.vectors;
        let mut fresh = [None; SLOTS];
        let mut any_fresh = false;
        // The slide's vector jumps at this block's first step unless the last step used exactly
        // this block's start vector (the last block held the slide still at this position).
        self.slide_jumped = was.moving[SLIDE];
        let mut end_tracked = was.moving[SLIDE];
        let mut swapped = false;
        for c in 0..3 {
            if !touching[c] {
                continue;
            }
            let (s, e) = (slot(c, false), slot(c, true));
            if v.made_at[s] != start[c] {
                // The end slot's vector serves as the start only if the last block used it: then
                // its projections and Gram entries are current. A vector left over from an older
                // block (the slide back where it once was, after blocks that did not move it)
                // is made afresh.
                if was.moving[c] && v.made_at[e] == start[c] {
                    v.swap_ends(c);
                    swapped = true;
                    if c == SLIDE {
                        self.slide_state.swap(0, 1);
                        end_tracked = true;
                    }
                } else {
                    fresh[s] = Some(start[c]);
                    any_fresh = true;
                }
                if c == SLIDE {
                    self.slide_jumped = true;
                }
            }
            let moving = self.block > 1 && end[c] != start[c];
            key |= Plan::touching_bit(c) | if moving { Plan::moving_bit(c) } else { 0 };
            if moving && v.made_at[e] != end[c] {
                fresh[e] = Some(end[c]);
                any_fresh = true;
            }
        }
        let plan = Plan::of(key);
        self.plan = plan;
        if plan.key == was.key && !any_fresh {
            if swapped {
                self.theta = block_theta(plan, &self.vectors.gram);
            }
            return;
        }
        // The state projections are needed for a fresh slide vector (the first in the Gram
        // pass, which sums them) and for an end vector whose projections were not kept.
        let (s, e) = (slot(SLIDE, false), slot(SLIDE, true));
        let first = if fresh[e].is_some() || (plan.moving[SLIDE] && !end_tracked) { e } else { s };
        let mut order = plan.slots;
        let at = order[..plan.count].iter().position(|&k| k == first).expect("the slide is in every plan");
        order[..plan.count].swap(0, at);
        let string = &self.string;
        let state = with_count!(plan.count, |V| v.update::<V>(string, std::array::from_fn(|j| order[j]), fresh));
        let state = [state.0, state.1];
        if first == e {
            self.slide_state[1] = state;
            if fresh[s].is_some() {
                let (p, n) = string.project_state(&v.shapes[s]);
                self.slide_state[0] = [p, n];
            }
        } else if fresh[s].is_some() {
            self.slide_state[0] = state;
        }
        self.theta = block_theta(plan, &v.gram);
    }

    /// Start a new block: move the targets on, cut the block into pieces if its contacts
    /// travel further than the core allows ([`cut_blocks`](Self::cut_blocks)), and begin the
    /// first.
    fn begin_block<C: ControlSource<SlideControls>>(&mut self, controls: &mut C) {
        let (start, end, len) = (self.target, controls.at(self.n + self.block as u64), self.block);
        (self.hand_from, self.hand_sag) = (start.hand_height, std::mem::take(&mut self.next_hand_sag));
        // The slide always touches; a finger only while it presses at either end of the block.
        let touching = [
            true,
            start.left_force != 0.0 || end.left_force != 0.0,
            start.right_force != 0.0 || end.right_force != 0.0,
        ];
        let moves = start.positions().into_iter().zip(end.positions()).zip(touching);
        let travel = moves.fold(0.0, |m: f64, ((a, b), on)| if on { m.max((b - a).abs()) } else { m });
        let pieces = (self.beta_max * travel / self.piece_turn).ceil();
        (self.whole_end, self.whole_len) = (end, len);
        self.pieces = if pieces > 1.0 { (pieces as usize).min(len).min(MAX_PIECES) } else { 1 };
        self.piece = 0;
        self.begin_piece();
    }

    /// The hand's path across the current whole block: from its height at the block's start to
    /// its height at the end, bowed as [`bow_hand`](Self::bow_hand) asked.
    fn whole_hand(&self) -> Bow {
        Bow { from: self.hand_from, to: self.whole_end.hand_height, sag: self.hand_sag }
    }

    /// Begin the block's next piece: steps `len·j/m` to `len·(j+1)/m` of the block, from where
    /// the last one ended to the controls there (linear across the block, as the ramps are, but
    /// for the hand, which keeps to the block's parabola),
    /// and plan its vectors.
    fn begin_piece(&mut self) {
        let (j, m, len) = (self.piece, self.pieces, self.whole_len);
        let (from, to) = (len * j / m, len * (j + 1) / m);
        self.start = self.target;
        self.target = if j + 1 == m {
            self.whole_end
        } else {
            self.start.lerp(&self.whole_end, (to - from) as f64 / (len - from) as f64)
        };
        self.block = to - from;
        self.inv_block = 1.0 / self.block as f64;
        let bow = self.whole_hand();
        if bow.sag != 0.0 && j + 1 < m {
            self.target.hand_height = bow.at(to as f64 / len as f64);
        }
        let sag = bow.sag_of_part(self.block as f64 / len as f64);
        let (s, t, len) = (&self.start, &self.target, self.block);
        self.hand = Bowed::new(s.hand_height, t.hand_height, len, sag);
        self.left_force = Ramp::new(s.left_force, t.left_force, len);
        self.right_force = Ramp::new(s.right_force, t.right_force, len);
        self.plan_block();
    }

    /// One step with the `V` vectors `slots` of the current plan (seed eqs. 65, 72–74;
    /// docs/physics.md §7.2–7.5): the controls at this step, `z̃` projected on the contacts, the
    /// vector-change term `J`, the finger damping eliminated, the scalar contact problem solved,
    /// the string and the slide advanced, and (with `MONITOR`) the energy balance.
    #[inline]
    fn step<S: ContactSolver, const MONITOR: bool, const V: usize>(
        &mut self,
        solver: &mut S,
        slots: [usize; V],
    ) -> Frame {
        let controls = self.step_controls(slots);
        let shapes = &self.vectors.shapes;
        let projections: [f64; V] = self.string.history(std::array::from_fn(|j| &shapes[slots[j]][..]));
        let (z, th) = self.contact_projections(slots, &controls, projections);
        let levers = if self.plan.bridge { self.levers(slots, &controls.weights) } else { [0.0; 3] };
        let bridge = self.plan.bridge.then(|| self.eliminate_bridge(slots, &controls.weights, z, th, levers));
        let (z, th) = bridge.map_or(([z[SLIDE], z[LEFT], z[RIGHT]], th), |b| (b.z, b.theta));
        let jump = self.vector_change(slots, &controls.weights, levers[SLIDE]);
        let fingers = Elimination::new(&th, z, controls.finger_forces, controls.gamma);
        let z_sho = self.sho.history(&controls.hand);
        let solution = self.solve(solver, &fingers, z_sho, jump);
        let force = solution.force;
        let y_next = self.y_prev + solution.s;
        let s_f = [0, 1].map(|i| fingers.s0[i] + fingers.s1[i] * force);
        let (f, gamma) = (controls.finger_forces, controls.gamma);
        // Modal force along each contact: the slide's F, each finger's F_φe + F_φR, and the
        // bridge's acceleration with its sign, along the lift.
        let contacts = [force, f[0] - gamma[0] * s_f[0], f[1] - gamma[1] * s_f[1]];
        let (accel, on_bridge) = bridge.map_or((0.0, 0.0), |b| {
            let a = b.a0 + (0..3).map(|i| b.a1[i] * contacts[i]).sum::<f64>();
            (a, (0..3).map(|i| b.kappa[i] * contacts[i]).sum::<f64>() - b.g0 + b.theta_e * a)
        });
        let along = [contacts[0], contacts[1], contacts[2], -accel];
        let (out_next, string_energy) = self.advance_string::<MONITOR, V>(slots, &controls.weights, along, projections);
        let (heard, body_energy) = match bridge {
            Some(_) => self.advance_body::<MONITOR>(on_bridge),
            None => (0.0, StringEnergy::default()),
        };
        let w_now = self.sho.position();
        let exchange = self.sho.advance(z_sho, force, &controls.hand);
        // The controls' work `Δt(P_H + Σ P_φ) − ½F J`, `Δt P_φ = F_φe s_φ/2` (docs/physics.md §7.5.3).
        self.control_work += -0.5 * force * jump + exchange.supplied + 0.5 * (f[0] * s_f[0] + f[1] * s_f[1]);
        let output = match bridge {
            Some(_) => heard,
            None => {
                let output = self.kind.sample(self.out_now, out_next, self.dt);
                if self.glide.0 < self.glide.1 { self.glide_output(output) } else { output }
            }
        };
        let mut frame = Frame {
            output,
            displacement: w_now,
            velocity: self.sho.velocity(),
            compression: self.y_now,
            force,
            energy: 0.0,
            losses: 0.0,
            control_work: 0.0,
            work: solver.last_work(),
        };
        if MONITOR {
            // `H^{n+1/2}` = string + SHO + contact (+ body and coupling), and the losses
            // `Δt(Q_str + Q_o + Σ Q_φ)` with `Δt Q_φ = γ_φ s_φ²/2` (docs/physics.md §7.4).
            let fingers = 0.5 * (gamma[0] * s_f[0] * s_f[0] + gamma[1] * s_f[1] * s_f[1]);
            self.losses += string_energy.dissipated + fingers + exchange.dissipated + body_energy.dissipated;
            let hand = &controls.hand;
            frame.energy = string_energy.stored
                + body_energy.stored
                + self.sho.energy(hand.now, hand.next)
                + solver.stored_energy(y_next, self.y_now);
            frame.losses = self.losses;
            frame.control_work = self.control_work;
        }
        self.move_on(out_next, y_next, controls.hand.now);
        frame
    }

    /// The controls at this step, fraction `a = k/N_b` into the block (docs/physics.md §7.5.1):
    /// the weights of the slots' vectors in the interpolated `ĥ_ζ = Σ_j w_j h_j` (`1 − a` and `a`
    /// for a moving contact's start and end vectors, 1 for one held still), the hand heights
    /// `w_H^{n−1}`, `w_H^n`, `w_H^{n+1}` and the finger forces `F_φe` from their ramps, and the
    /// fingers' damping coefficients `γ_φ = r_φ|F_φe|/(2Δt)` (N/m, §7.3).
    #[inline(always)]
    fn step_controls<const V: usize>(&self, slots: [usize; V]) -> StepControls<V> {
        let k = self.k;
        let a = k as f64 * self.inv_block;
        let f = [self.left_force.at(k), self.right_force.at(k)];
        StepControls {
            a,
            weights: std::array::from_fn(|j| self.plan.weight(slots[j], a)),
            hand: HandMotion { prev: self.hand_prev, now: self.hand.at(k), next: self.hand.at(k + 1) },
            finger_forces: f,
            gamma: [self.r[0] * f[0].abs() / (2.0 * self.dt), self.r[1] * f[1].abs() / (2.0 * self.dt)],
        }
    }

    /// The projections `z_ζ = ĥ_ζᵀz̃ = Σ_j w_j h_jᵀz̃` (m) of `z̃` on the interpolated contact
    /// vectors, from the slots' `projections`, and their Gram matrix in the C metric at this step,
    /// `θ_ζξ(a) = c0 + a(c1 + a·c2)` (m/N; docs/physics.md §7.5.1).
    #[inline(always)]
    fn contact_projections<const V: usize>(
        &self,
        slots: [usize; V],
        controls: &StepControls<V>,
        projections: [f64; V],
    ) -> ([f64; 4], [[f64; 3]; 3]) {
        let mut z = [0.0; 4];
        for j in 0..V {
            z[contact(slots[j])] += controls.weights[j] * projections[j];
        }
        let [c0, c1, c2] = &self.theta;
        let a = controls.a;
        let th = if self.plan.moving == [false; 3] {
            *c0
        } else {
            std::array::from_fn(|i| std::array::from_fn(|k| c0[i][k] + a * (c1[i][k] + a * c2[i][k])))
        };
        (z, th)
    }

    /// The vector-change term `J = ĥ_o^nᵀũ^{n−1} − w_o^{n−1} − y^{n−1}` (m; docs/physics.md
    /// §7.5.2): where the slide's vector moved since the compression `y^{n−1}` was measured, the
    /// string under it differs from the carried `y^{n−1} + w_o^{n−1}` by `J`; zero once the vector
    /// has stayed put for two steps.
    #[inline(always)]
    fn vector_change<const V: usize>(&mut self, slots: [usize; V], weights: &[f64; V], lever: f64) -> f64 {
        let (k, moving) = (self.k, self.plan.moving[SLIDE]);
        if (k == 0 && self.slide_jumped) || (k > 0 && moving) {
            self.slide_still = 0;
        }
        if self.slide_still >= 2 {
            return 0.0;
        }
        // With a body, the string under the slide also rides on the bridge: `ℓ_o b^{n−1}`.
        let mut under = self.body.as_ref().map_or(0.0, |body| lever * body.b.0);
        for j in 0..V {
            if contact(slots[j]) == SLIDE {
                under += weights[j] * self.slide_state[slots[j] % 2][0];
            }
        }
        (under - self.sho.previous()) - self.y_prev
    }

    /// Solve the slide's scalar contact problem with the fingers eliminated and the hand's
    /// oscillator folded in, `s + (z_str − z_sho − J) − (q_str + q_sho) F = 0` (seed eq. 74 with
    /// `J`; docs/physics.md §7.3), for `s = y^{n+1} − y^{n−1}` (m) and the force `F` (N).
    #[inline(always)]
    fn solve<S: ContactSolver>(
        &mut self,
        solver: &mut S,
        fingers: &Elimination,
        z_sho: f64,
        jump: f64,
    ) -> ContactSolution {
        let problem = ContactProblem {
            y_prev: self.y_prev,
            y_now: self.y_now,
            z: fingers.z_str - z_sho - jump,
            q: fingers.q_str + self.sho.coupling(),
        };
        let solution = solver.solve(&problem);
        self.last_force = solution.force;
        solution
    }

    /// Advance the string, `ũ^{n+1} = ũ^{n−1} − z̃ + Σ_j (C∘h_j) w_j F_ζ(j)` with `F_ζ` the force
    /// `along` each contact (seed eq. 65; docs/physics.md §7.2), and the slide vectors'
    /// projections with it ([`track_slide`](Self::track_slide)). Returns `outputᵀũ^{n+1}` and,
    /// with `MONITOR`, the string's energy terms.
    #[inline(always)]
    fn advance_string<const MONITOR: bool, const V: usize>(
        &mut self,
        slots: [usize; V],
        weights: &[f64; V],
        along: [f64; 4],
        projections: [f64; V],
    ) -> (f64, StringEnergy) {
        let gains = &self.vectors.gains;
        let forces: [(&[f64], f64); V] =
            std::array::from_fn(|j| (&gains[slots[j]][..], weights[j] * along[contact(slots[j])]));
        let advanced = if MONITOR {
            self.string.advance_monitored(forces, &self.pickup)
        } else {
            (self.string.advance(forces, &self.pickup), Default::default())
        };
        let forces = forces.map(|(_, force)| force);
        self.track_slide(slots, projections, forces);
        if self.plan.bridge {
            self.track_lift(slots, projections, forces);
        }
        advanced
    }

    /// Move `(gᵀũ^{n−1}, gᵀũ^n)` on by the string update's own recursion, as
    /// [`track_slide`](Self::track_slide) does for the slide's vectors (the lift's slot is the
    /// plan's last).
    #[inline(always)]
    fn track_lift<const V: usize>(&mut self, slots: [usize; V], projections: [f64; V], forces: [f64; V]) {
        let g = &self.vectors.gram[BRIDGE_SLOT];
        let Some(body) = self.body.as_mut() else { return };
        let mut next = body.lifted.0 - projections[V - 1];
        for i in 0..V {
            next += g[slots[i]] * forces[i];
        }
        body.lifted = (body.lifted.1, next);
    }

    /// The levers `ℓ_ζ = x_ζ/L` of the contacts at this step (docs/physics.md §13.5): where each
    /// sits along the string, interpolated as its vector is.
    #[inline(always)]
    fn levers<const V: usize>(&self, slots: [usize; V], weights: &[f64; V]) -> [f64; 3] {
        let per_length = 1.0 / self.string.params().length;
        let mut levers = [0.0; 3];
        for j in 0..V {
            let c = contact(slots[j]);
            if c < BRIDGE {
                levers[c] += weights[j] * self.vectors.made_at[slots[j]] * per_length;
            }
        }
        levers
    }

    /// Eliminate the bridge's acceleration (docs/physics.md §13.5 and §12): with the lift's
    /// Gram entries `θ_gζ`, `θ_gg`, the body's free step and the coupling's static terms, the
    /// acceleration is `a = a₀ + Σ_ζ a_ζ F_ζ`, and the contacts see `θ' = θ + (Δt²C_Σ/Δ)κκᵀ` and
    /// `z' = z − 2ℓ(b^n − b^{n−1}) − Δt²κ a₀`, `κ_ζ = ℓ_ζ − θ_gζ/Δt²`.
    #[inline(always)]
    fn eliminate_bridge<const V: usize>(
        &mut self,
        slots: [usize; V],
        weights: &[f64; V],
        z: [f64; 4],
        theta: [[f64; 3]; 3],
        levers: [f64; 3],
    ) -> BridgeStep {
        let dt2 = self.dt * self.dt;
        let g = &self.vectors.gram[BRIDGE_SLOT];
        let mut theta_g = [0.0; 3];
        for j in 0..V {
            let c = contact(slots[j]);
            if c < BRIDGE {
                theta_g[c] += weights[j] * g[slots[j]];
            }
        }
        let body = self.body.as_mut().expect("a plan with the bridge has a body");
        let [body_history] = body.bank.history([&body.sole]);
        let free = body.b.0 - body_history;
        let (b, lifted) = (body.b, body.lifted);
        let g0 = (2.0 * lifted.0 - z[BRIDGE] - 2.0 * lifted.1) / dt2 + body.lift_stiffness * b.1;
        // `Θ − E`: the lift's inertia through the modes less the string's static mass and stiffness.
        let theta_e = g[BRIDGE_SLOT] / dt2 - (body.lift_mass + 0.25 * body.lift_stiffness * dt2);
        let c = body.compliance;
        let delta = dt2 - c * theta_e;
        let a0 = (free - 2.0 * b.1 + b.0 - c * g0) / delta;
        let kappa: [f64; 3] = std::array::from_fn(|i| levers[i] - theta_g[i] / dt2);
        let w = dt2 * c / delta;
        BridgeStep {
            theta: std::array::from_fn(|i| std::array::from_fn(|k| theta[i][k] + w * kappa[i] * kappa[k])),
            z: std::array::from_fn(|i| z[i] - 2.0 * levers[i] * (b.1 - b.0) - dt2 * kappa[i] * a0),
            a0,
            a1: kappa.map(|k| c * k / delta),
            kappa,
            g0,
            theta_e,
        }
    }

    /// Step the body under the force `force` (N) the string and the contacts put on the bridge
    /// ([`BodyCoupling::advance`]).
    #[inline(always)]
    fn advance_body<const MONITOR: bool>(&mut self, force: f64) -> (f64, StringEnergy) {
        let dt = self.dt;
        self.body.as_mut().expect("a plan with the bridge has a body").advance::<MONITOR>(force, dt)
    }

    /// Move the slide vectors' state projections on by the string update's own recursion,
    /// `hᵀũ^{n+1} = hᵀũ^{n−1} − hᵀz̃ + Σ_j hᵀ(C∘h_j) F_j` (m; docs/physics.md §7.5.2), with
    /// `F_j` the modal force along slot `j` (N).
    #[inline(always)]
    fn track_slide<const V: usize>(&mut self, slots: [usize; V], projections: [f64; V], forces: [f64; V]) {
        let g = &self.vectors.gram;
        for j in 0..V {
            if contact(slots[j]) == SLIDE {
                let mut next = self.slide_state[slots[j] % 2][0] - projections[j];
                for i in 0..V {
                    next += g[slots[j]][slots[i]] * forces[i];
                }
                let state = &mut self.slide_state[slots[j] % 2];
                *state = [state[1], next];
            }
        }
    }

    /// Move the time index on: the output, the compressions `y^{n−1} ← y^n ← y^{n+1}` and the hand
    /// height `w_H^{n−1} ← w_H^n`.
    #[inline(always)]
    fn move_on(&mut self, out_next: f64, y_next: f64, hand_now: f64) {
        self.out_now = out_next;
        self.y_prev = self.y_now;
        self.y_now = y_next;
        self.hand_prev = hand_now;
        self.slide_still = self.slide_still.saturating_add(1);
        self.n += 1;
        self.k += 1;
    }

    /// Run `count` steps with `solver`, starting blocks where they fall and asking `controls`
    /// for their targets, handing each frame, and the core after its step, to `sink`.
    #[inline]
    pub fn run<S: ContactSolver, C: ControlSource<SlideControls>, const MONITOR: bool>(
        &mut self,
        solver: &mut S,
        controls: &mut C,
        count: usize,
        mut sink: impl FnMut(usize, Frame, &Self),
    ) {
        let mut done = 0;
        while done < count {
            if self.k == self.block {
                self.k = 0;
                if self.piece + 1 < self.pieces {
                    self.piece += 1;
                    self.begin_piece();
                } else {
                    self.block = self.next_block;
                    self.inv_block = 1.0 / self.block as f64;
                    if C::VARYING {
                        self.begin_block(controls);
                    }
                }
            }
            let run = (self.block - self.k).min(count - done);
            with_count!(self.plan.count, |V| {
                let slots = self.plan.slots::<V>();
                for i in done..done + run {
                    let frame = self.step::<S, MONITOR, V>(solver, slots);
                    sink(i, frame, self);
                }
            });
            done += run;
        }
    }

    /// Advance `out.len()` samples writing only the output signal, and with `sides` what the
    /// body's modes on the left and on the right radiated ([`heard_sides`](Self::heard_sides);
    /// slices as long as `out`).
    pub fn process_output<S: ContactSolver, C: ControlSource<SlideControls>>(
        &mut self,
        solver: &mut S,
        controls: &mut C,
        out: &mut [f64],
        sides: Option<[&mut [f64]; 2]>,
    ) {
        match sides {
            None => self.run::<S, C, false>(solver, controls, out.len(), |i, f, _| out[i] = f.output),
            Some([left, right]) => self.run::<S, C, false>(solver, controls, out.len(), |i, f, core| {
                out[i] = f.output;
                [left[i], right[i]] = core.heard_sides();
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::string::Damping;

    /// The guitar's body, coupled at the bridge, radiates what its transmittance says at every
    /// rate: driven by a sinusoidal force on the bridge, from 150 Hz to 10 kHz (on both sides of
    /// its top's highest modes, the notch at 2.5 kHz aside), its output's amplitude is within 4 %
    /// of the transmittance's at 22.05 kHz (measured 3.4 %; 10 % without the weights' correction),
    /// 1 % at 44.1 kHz (0.5 %; 3.0 % without) and 0.2 % at 96 kHz (0.1 %; 0.7 % without).
    #[test]
    fn a_coupled_body_radiates_its_transmittance_at_every_rate() {
        let params = BodyParams::guitar();
        let string_params = StringParams {
            length: 0.65,
            tension: 70.0,
            linear_density: 1.1e-3,
            bending_stiffness: 1e-5,
            damping: Damping::Viscous { eta0: 0.5, eta2: 1e-6 },
        };
        for (fs, tolerance) in [(22_050.0, 0.04), (44_100.0, 0.01), (96_000.0, 0.002)] {
            let string = ModalString::new(string_params, fs).expect("a valid string");
            for f in [150.0, 1_000.0, 4_000.0, 4_775.0, 6_741.0, 8_000.0, 10_000.0] {
                let mut body = BodyCoupling::new(&params, &string);
                let n = (2.0 * fs) as usize;
                let w = std::f64::consts::TAU * f / fs;
                let (mut s, mut c) = (0.0, 0.0);
                for k in 0..n {
                    body.bank.history([&body.sole]);
                    let (heard, _) = body.advance::<false>((k as f64 * w).sin(), 1.0 / fs);
                    // The second difference is centred on the force's own sample.
                    if k >= n / 2 {
                        s += heard * (k as f64 * w).sin();
                        c += heard * (k as f64 * w).cos();
                    }
                }
                let got = 2.0 * s.hypot(c) / (n - n / 2) as f64;
                let (re, im) = params.response(f);
                let want = re.hypot(im);
                println!("{f} Hz at {fs} Hz: {got:.6} against {want:.6} ({:+.2} %)", 100.0 * (got / want - 1.0));
                assert!((got - want).abs() < tolerance * want, "{f} Hz at {fs} Hz: {got} against {want}");
            }
        }
    }
}
