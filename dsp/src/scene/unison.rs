//! One piano key: a hammer striking a unison of one to three strings that end on a moving bridge
//! (docs/physics.md §12).
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
//! # The hammer shifted
//!
//! A grand's soft pedal (una corda) shifts the action sideways, so that the hammer meets only
//! the first `S_h < S` strings of the unison. The compression is then measured against their
//! mean and the force shared between them: `h_s/S` becomes `h_s/S_h` for those strings and zero
//! for the others, wherever it appears below. The strings it misses move with the bridge alone.
//! The hammer is the same, as heavy; its felt meets `S_h` strings' worth of wire, so it is
//! `S_h` times as stiff as one string's share ([`UnisonCore::set_struck`], the voice's rule).
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
//!
//! # Which modes feel the bridge
//!
//! The bridge drains a unison moving in phase at `σ_b = 2·S·f0·Z0·G` (Weinreich; `Z0 = √(Tρ)`, `G`
//! the bridge's mean conductance). A mode whose own decay rate exceeds [`COUPLING_RATIO`]`·σ_b`
//! loses its energy to its own damping ten times faster than to the bridge, so it ends on a still
//! bridge (`g_i = 0`). The modes on the bridge and the bridge's own form one [`ModalBank`] (the
//! coupled part), the others a second (the free part).
//!
//! # Sympathetic partners
//!
//! Other keys' strings on the same bridge ring with the key (docs/physics.md §14): a partner is
//! one string whose end moves with the bridge exactly as the unison's strings do (its own `g`,
//! `m_L`, `k_L`), with no hammer on it (`h = 0`), its lowest modes in the coupled part, and its
//! bridge force in the output. It only adds terms to the sums `Θ`, `E` and `G₀` above: the bridge
//! is still eliminated in closed form and the contact stays one scalar. A damper on the partners
//! is an extra decay rate on their modes ([`UnisonCore::set_partner_decays`]), set for each
//! partner as its damper lands or lifts.
//!
//! # Strings that already move in other keys' copies
//!
//! Each key carries its own copy of the bridge and of its partners (docs/physics.md §14.3).
//! Strings and bridge are linear, so the sum of the copies is what one shared bridge gives; the
//! contact is the one thing that is not, and it must meet the struck strings where they are in
//! all the copies together. When the key's strings already ring as a partner on other keys'
//! bridges, their motion there at the striking point, the background `β` (m), joins the
//! compression, `y = (1/S) Σ_s h_sᵀṽ_s + ℓ b + β − w`, and only changes the known part of the
//! scalar problem: `z` loses `β^{n+1} − β^{n−1}`. The copies that ring the strings run ahead of
//! this one in each block and hand it `β` at every step ([`Shared`]); a partner's motion at its
//! own key's striking point `ℓ_p` is `Σ_i sin(iπℓ_p) ṽ_i + ℓ_p b` over its modes
//! ([`UnisonCore::partner_motion`]). The background does work on the copy it enters,
//! `−½F(β^{n+1} − β^{n−1})` in each step, booked as control work: the copy's balance closes with
//! it as without.
//!
//! # Retiring the hammer
//!
//! As for a single string ([`HammerCore`](super::HammerCore)): with `H` the energy of strings and
//! bridge, which only decreases while no force acts and the coefficients stay,
//! `|u_h^n| ≤ √(2H)(ρ_V + ½Δt ρ_T)` with `ρ_V² = Σ c_i²/K̂_i` and `ρ_T² = cᵀM⁻¹c` for the contact
//! vector `c` (`h` on string modes, `ℓ` on bridge modes) and the coupled mass matrix `M`, whose
//! inverse has a closed form (docs/physics.md §12.6). Checked every [`RETIRE_CHECK`] steps; once
//! the hammer moves away beyond that reach, the contact is not solved any more, the free part runs
//! by its homogeneous recursion in register-resident runs and the coupled part steps without the
//! striking point. A change of coefficients (a damper) has the hammer judged again at once, with
//! `H` weighed by the new coefficients: it stays retired if it is still out of reach. A background
//! moves the strings further, by at most the reach its copies give it (the same bound over the
//! partner's vector, with their energies): the hammer must also be beyond that.

use std::ops::Range;

use crate::bridge::{BridgeMode, BridgeParams};
use crate::contact::{ContactProblem, ContactSolver};
use crate::exciter::{Hammer, HammerParams};
use crate::scene::Frame;
use crate::string::{ModalBank, ModalString, StringError, StringParams, Tail};

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
    Bridge(crate::bridge::BridgeError),
    /// The number of strings is outside 1 to [`MAX_UNISON`].
    Strings(usize),
}

/// How much faster than the bridge drains it a mode's own decay must be for the mode to be left
/// off the bridge (module docs).
pub const COUPLING_RATIO: f64 = 10.0;

/// Most partner strings a unison rings with (module docs, "Sympathetic partners").
pub const MAX_PARTNERS: usize = 12;

/// Most modes of a partner string.
pub const PARTNER_MODES: usize = 16;

/// Steps between checks whether the hammer is out of the unison's reach for good.
pub const RETIRE_CHECK: u32 = 64;

/// A partner whose motion another key's hammer meets (module docs, "Strings that already move
/// in other keys' copies").
#[derive(Debug, Clone, Copy, Default)]
pub struct Watch {
    /// Which of the unison's partners.
    pub partner: usize,
    /// Its own key's striking point `ℓ_p` (fraction of the length).
    pub ell: f64,
    /// `sin(iπℓ_p)` for its modes `i = 1, 2, …`: the modes' shapes there.
    pub sines: [f64; PARTNER_MODES],
    /// Which of [`Shared::sinks`] its motion goes to.
    pub sink: usize,
}

impl Watch {
    /// Watch partner `partner` at the striking point `ell` of its own key, into sink `sink`.
    pub fn new(partner: usize, ell: f64, sink: usize) -> Self {
        let (s1, c1) = (std::f64::consts::PI * ell).sin_cos();
        let mut sines = [0.0; PARTNER_MODES];
        let (mut sn, mut cn) = (s1, c1);
        for x in &mut sines {
            *x = sn;
            (sn, cn) = (sn * c1 + cn * s1, cn * c1 - sn * s1);
        }
        Self { partner, ell, sines, sink }
    }

    /// The partner's displacement at the striking point (m) for its modes' state `u` and the
    /// bridge's displacement `b`: `Σ_i sin(iπℓ_p) u_i + ℓ_p b`.
    #[inline]
    fn along(&self, u: &[f64], b: f64) -> f64 {
        u.iter().zip(&self.sines).map(|(u, s)| u * s).sum::<f64>() + self.ell * b
    }
}

/// What a key shares over one block with the other keys' copies of its strings and of its
/// partners (module docs).
#[derive(Debug, Default)]
pub struct Shared<'a> {
    /// The background `β` at the striking point after each step (m); steps past its end meet none.
    pub background: &'a [f64],
    /// The partners whose motion other keys' hammers meet.
    pub watches: &'a [Watch],
    /// Where the watched motions go: `sinks[w.sink][k]` gains the partner's motion after step `k`.
    pub sinks: &'a mut [Vec<f64>],
}

/// The vectors over one bank of modes (module docs), each padded to the bank's length.
#[derive(Debug, Clone)]
struct Part {
    /// `h_s/S` on each string's modes: `hᵀu` is the strings' mean displacement at `x_h`.
    shape: Vec<f64>,
    /// `g_s` (kg) on each string's modes (zero in the free part).
    lift: Vec<f64>,
    /// 1 on the bridge's modes, `eᵀu = b` (zero in the free part).
    sole: Vec<f64>,
    /// `C∘h`, `C∘g`, `C∘e`.
    shape_gain: Vec<f64>,
    lift_gain: Vec<f64>,
    sole_gain: Vec<f64>,
    /// Each string's bridge force weights over `S` (N/m): the output is the mean bridge force.
    pickup: Vec<f64>,
}

impl Part {
    fn new(bank: &ModalBank) -> Self {
        let v = || Vec::with_capacity(bank.capacity() + crate::string::LANES);
        Self { shape: v(), lift: v(), sole: v(), shape_gain: v(), lift_gain: v(), sole_gain: v(), pickup: v() }
    }

    /// Zero every vector at `b`'s length.
    fn clear_vectors(&mut self, b: &ModalBank) {
        for x in [&mut self.shape, &mut self.lift, &mut self.sole, &mut self.shape_gain, &mut self.lift_gain] {
            b.fit_vector(x);
        }
        b.fit_vector(&mut self.sole_gain);
        b.fit_vector(&mut self.pickup);
    }

    /// The gains `C∘v` from `bank`'s current coefficients.
    fn refresh(&mut self, bank: &ModalBank) {
        let c = bank.input_gains();
        for i in 0..c.len() {
            self.shape_gain[i] = self.shape[i] * c[i];
            self.lift_gain[i] = self.lift[i] * c[i];
            self.sole_gain[i] = self.sole[i] * c[i];
        }
    }
}

/// The scalars of the coupling that change only with the coefficients (module docs).
#[derive(Debug, Clone, Copy, Default)]
struct Coupling {
    /// `θ_hh = hᵀ(C∘h)` over both parts (m/N, with `h` over `S`: `Σ_s θ_hh,s/S²`).
    hh: f64,
    /// `θ_gh = Σ_s θ_gh,s/S`.
    gh: f64,
    /// `θ_gg = Σ_s θ_gg,s`.
    gg: f64,
    /// `C_Σ = eᵀ(C∘e)` (m/N).
    compliance: f64,
    /// `Σ_s m_L,s` (kg) and `Σ_s k_L,s` (N/m).
    lift_mass: f64,
    lift_stiffness: f64,
    /// `ρ = ρ_V + ½Δt ρ_T` (m/√J): how far the striking point can be from rest per `√(2H)`.
    reach: f64,
    /// What the bounds over other contact vectors share with it: `Σ g²/m` over the strings' and
    /// partners' modes (kg), `Σ 1/K` (m/N) and `Σ 1/m` (1/kg) over the bridge's.
    lifts_over_mass: f64,
    bridge_flexibility: f64,
    bridge_mobility: f64,
    /// `1/Δt²` (1/s²), `1/Δ` with `Δ = Δt² + C_Σ(E − Θ)` (s²) and `Θ − E` (kg), for the step
    /// after the hammer retires: it multiplies by them, so no division lies on the chain from one
    /// sample to the next.
    inverse_dt2: f64,
    inverse_delta: f64,
    theta_less_e: f64,
}

/// A hammer, a unison of strings and their bridge: everything of a piano key except the solver.
/// The modes that feel the bridge and the bridge's own modes live in one [`ModalBank`] (the
/// coupled part), stepped in one pass; the strings' higher modes in another (the free part).
/// Prepared once with room for the most modes a string may need, then retuned and struck note
/// after note without allocating.
#[derive(Debug, Clone)]
pub struct UnisonCore {
    /// Each string prepared on its own (where the banks' coefficients come from); the first
    /// also holds a copy of its state after every call, for monitors.
    strings: Vec<ModalString>,
    /// What each string was last prepared for, `(parameters, highest frequency (Hz))`: a key
    /// struck again on the same voice finds its strings ready and only brings them to rest.
    prepared: [Option<(StringParams, f64)>; MAX_UNISON],
    /// How many of each string's modes (a prefix) are on the bridge.
    split: [usize; MAX_UNISON],
    /// Each string's modes in the coupled and in the free part.
    coupled_ranges: [Range<usize>; MAX_UNISON],
    free_ranges: [Range<usize>; MAX_UNISON],
    count: usize,
    /// How many of the strings the hammer meets, the first ones (module docs, "The hammer
    /// shifted"): all of them but under the una corda.
    struck: usize,
    /// The coupled part: the strings' modes on the bridge, then the bridge's.
    coupled_bank: ModalBank,
    coupled: Part,
    /// The free part: the strings' higher modes.
    free_bank: ModalBank,
    free: Part,
    /// The partner strings' modes in the coupled part (module docs), and how many partners.
    partner_ranges: [Range<usize>; MAX_PARTNERS],
    partners: usize,
    /// The bridge's modes in the coupled part.
    bridge_range: Range<usize>,
    bridge: Vec<BridgeMode>,
    /// The bridge's mean driving-point conductance (s/kg), what decides which modes it couples.
    conductance: f64,
    coupling: Coupling,
    hammer: Hammer,
    /// `ℓ = x_h/L`.
    ell: f64,
    /// `(hᵀu^{n−1}, hᵀu^n)` (m), `(gᵀu^{n−1}, gᵀu^n)` (kg·m), `(b^{n−1}, b^n)` (m).
    hv: (f64, f64),
    gv: (f64, f64),
    b: (f64, f64),
    /// `(hᵀz̃, gᵀz̃, eᵀz̃)` of the coupled part's coming step and `hᵀz̃` of the free part's, when
    /// the last pass already projected them.
    next_coupled: Option<[f64; 3]>,
    next_free: Option<[f64; 1]>,
    /// `(gᵀz̃, eᵀz̃)` of the coming step once the hammer is retired.
    next_retired: Option<[f64; 2]>,
    /// Whether the hammer is out of the strings' reach for good (module docs).
    retired: bool,
    /// Steps since the strike, modulo [`RETIRE_CHECK`].
    since_check: u32,
    /// The background `(β^{n−1}, β^n)` (m), `β^{n+1}` for the coming step, how far it can reach
    /// (m) and the work it has done when monitored (J) (module docs).
    background: (f64, f64),
    background_next: f64,
    background_reach: f64,
    background_work: f64,
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
        bridge.validate().map_err(UnisonError::Bridge)?;
        if !(sample_rate > 0.0 && sample_rate.is_finite()) {
            return Err(UnisonError::Bridge(crate::bridge::BridgeError("the sample rate must be positive".into())));
        }
        let hammer = Hammer::new(&HammerParams { mass: 1e-2, velocity: 0.0, position: 0.1, gap: 1e-3 }, sample_rate);
        let coupled_bank = ModalBank::with_capacity(MAX_UNISON * modes + bridge.modes.len(), sample_rate);
        let free_bank = ModalBank::with_capacity(MAX_UNISON * modes, sample_rate);
        Ok(Self {
            strings: (0..MAX_UNISON).map(|_| ModalString::with_capacity(modes)).collect(),
            prepared: [None; MAX_UNISON],
            split: [0; MAX_UNISON],
            coupled_ranges: [0..0, 0..0, 0..0],
            free_ranges: [0..0, 0..0, 0..0],
            count: 0,
            struck: 0,
            coupled: Part::new(&coupled_bank),
            free: Part::new(&free_bank),
            coupled_bank,
            free_bank,
            partner_ranges: [(); MAX_PARTNERS].map(|_| 0..0),
            partners: 0,
            bridge_range: 0..0,
            bridge: bridge.modes.clone(),
            conductance: bridge.mean_conductance(),
            coupling: Coupling::default(),
            hammer,
            ell: 0.1,
            hv: (0.0, 0.0),
            gv: (0.0, 0.0),
            b: (0.0, 0.0),
            next_coupled: None,
            next_free: None,
            next_retired: None,
            retired: false,
            since_check: 0,
            background: (0.0, 0.0),
            background_next: 0.0,
            background_reach: 0.0,
            background_work: 0.0,
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
        self.retune_with_partners(params, max_frequency, position, &[])
    }

    /// [`retune`](Self::retune), with the lowest modes of other keys' strings on the same bridge
    /// (module docs, "Sympathetic partners"): `(string, modes)` for each partner, at most
    /// [`MAX_PARTNERS`] of them (the rest are left out). Their modes start at rest and free.
    pub fn retune_with_partners(
        &mut self,
        params: &UnisonParams,
        max_frequency: f64,
        position: f64,
        partners: &[(&ModalString, usize)],
    ) -> Result<(), UnisonError> {
        if !(1..=MAX_UNISON).contains(&params.strings) {
            return Err(UnisonError::Strings(params.strings));
        }
        let fs = 1.0 / self.dt;
        for s in 0..params.strings {
            // Preparing a string (its modes' coefficients) is most of a note-on's work: a string
            // prepared for the same parameters (the key played again) has the same coefficients
            // and only comes to rest, as `retune` leaves it.
            let wanted = (params.string(s), max_frequency);
            if self.prepared[s] == Some(wanted) {
                self.strings[s].reset();
            } else {
                self.prepared[s] = None;
                self.strings[s].retune(wanted.0, fs, max_frequency).map_err(UnisonError::String)?;
                self.prepared[s] = Some(wanted);
            }
        }
        self.count = params.strings;
        self.struck = params.strings;
        self.ell = position;
        self.coupled_bank.clear();
        self.free_bank.clear();
        for s in 0..self.count {
            let string = &self.strings[s];
            let p = string.params();
            // The rate at which the bridge drains the unison's in-phase motion (Weinreich):
            // `σ_b = 2·S·f0·Z0·G`, with the string's wave impedance `Z0 = √(Tρ)`.
            let drain =
                2.0 * self.count as f64 * p.fundamental() * (p.tension * p.linear_density).sqrt() * self.conductance;
            let split = string.decay_rates().iter().take_while(|&&sigma| sigma <= COUPLING_RATIO * drain).count();
            self.split[s] = split;
            self.coupled_ranges[s] = self.coupled_bank.push_modes(string, 0..split);
            self.free_ranges[s] = self.free_bank.push_modes(string, split..string.modes());
        }
        self.partners = partners.len().min(MAX_PARTNERS);
        for (range, (string, modes)) in self.partner_ranges.iter_mut().zip(partners) {
            *range = self.coupled_bank.push_modes(string, 0..(*modes).min(string.modes()).min(PARTNER_MODES));
        }
        let start = self.coupled_bank.modes();
        for m in self.bridge.iter().filter(|m| m.frequency < 0.49 * fs) {
            let omega0 = std::f64::consts::TAU * m.frequency;
            self.coupled_bank.push_oscillator(omega0, 0.5 * m.loss_factor * omega0, m.mass);
        }
        self.bridge_range = start..self.coupled_bank.modes();
        self.coupled_bank.finish();
        self.free_bank.finish();
        self.place();
        self.place_partners(&partners[..self.partners], 0);
        self.losses = 0.0;
        self.last_force = 0.0;
        self.clear_background();
        self.measure();
        Ok(())
    }

    /// Make the vectors over both parts for the current strings and striking point, the
    /// partners' entries empty: [`place_partners`](Self::place_partners) fills them and
    /// refreshes the coupling.
    fn place(&mut self) {
        let n = self.count as f64;
        self.coupled.clear_vectors(&self.coupled_bank);
        self.free.clear_vectors(&self.free_bank);
        let (mut lift_mass, mut lift_stiffness) = (0.0, 0.0);
        for s in 0..self.count {
            let string = &self.strings[s];
            let p = *string.params();
            // The weights of every mode of the string (in one of the free part's gain vectors,
            // refreshed below), then shared out between the parts.
            let mut weights = std::mem::take(&mut self.free.sole_gain);
            weights.resize(string.padded_len().max(weights.len()), 0.0);
            string.bridge_weights(true, &mut weights[..string.padded_len()]);
            for k in 0..string.modes() {
                let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                match self.mode_index(s, k) {
                    (true, Some(i)) => {
                        self.coupled.pickup[i] = weights[k] / n;
                        self.coupled.lift[i] = sign * p.linear_density / string.wavenumbers()[k];
                    }
                    (false, Some(i)) => self.free.pickup[i] = weights[k] / n,
                    (_, None) => {}
                }
            }
            self.free.sole_gain = weights;
            lift_mass += p.linear_density * p.length / 3.0;
            lift_stiffness += p.tension / p.length;
        }
        self.free_bank.fit_vector(&mut self.free.sole_gain);
        self.place_shapes();
        self.coupled.sole[self.bridge_range.clone()].fill(1.0);
        self.coupling.lift_mass = lift_mass;
        self.coupling.lift_stiffness = lift_stiffness;
    }

    /// Where mode `k` of string `s` lives: whether in the coupled part, and its index there
    /// (`None` past the part's length).
    fn mode_index(&self, s: usize, k: usize) -> (bool, Option<usize>) {
        let (coupled, i, len) = if k < self.split[s] {
            (true, self.coupled_ranges[s].start + k, self.coupled_bank.modes())
        } else {
            (false, self.free_ranges[s].start + k - self.split[s], self.free_bank.modes())
        };
        (coupled, (i < len).then_some(i))
    }

    /// Write the striking shapes into both parts: `h_s/S_h` on the modes of each of the `S_h`
    /// strings the hammer meets, zero on those it misses (module docs, "The hammer shifted").
    fn place_shapes(&mut self) {
        let n = self.struck as f64;
        for s in 0..self.count {
            let string = &self.strings[s];
            let length = string.params().length;
            // The shapes of every mode of the string, in the free part's gain vector (refreshed
            // with the coupling).
            let mut shape = std::mem::take(&mut self.free.shape_gain);
            shape.resize(string.padded_len().max(shape.len()), 0.0);
            string.mode_shapes(self.ell * length, &mut shape[..string.padded_len()]);
            let met = s < self.struck;
            for k in 0..string.modes() {
                let h = if met { shape[k] / n } else { 0.0 };
                match self.mode_index(s, k) {
                    (true, Some(i)) => self.coupled.shape[i] = h,
                    (false, Some(i)) => self.free.shape[i] = h,
                    (_, None) => {}
                }
            }
            self.free.shape_gain = shape;
        }
        self.free_bank.fit_vector(&mut self.free.shape_gain);
    }

    /// Have the hammer meet the first `struck` strings of the unison only (module docs, "The
    /// hammer shifted"), clamped to 1 to all of them: the una corda shifts it off the others.
    /// Takes effect at once, the compression measured anew over the strings now met, so call it
    /// just before a [`strike`](Self::strike) (and a solver started afresh): a solver under way
    /// holds compressions measured over the old ones. The strings keep their state. Never
    /// allocates.
    pub fn set_struck(&mut self, struck: usize) {
        let struck = struck.clamp(1, self.count.max(1));
        if struck != self.struck {
            self.struck = struck;
            self.place_shapes();
            self.refresh_coupling();
            self.measure();
        }
    }

    /// How many of the strings the hammer meets.
    pub fn struck(&self) -> usize {
        self.struck
    }

    /// Put the lowest modes of more partner strings (as
    /// [`retune_with_partners`](Self::retune_with_partners)) on the bridge while the unison
    /// sounds, beside any it has, as many as [`MAX_PARTNERS`] allows. The strings, the bridge and
    /// the partners already there keep their state and coefficients; the new partners start at
    /// rest on the bridge's line (`u_p = b·x/L`, where a damped string lies), which adds their
    /// static share `½m_L(δ_t−b)² + ½k_L(μ_t−b)²` to the energy. Returns how many partners were
    /// added. Never allocates.
    pub fn add_partners(&mut self, partners: &[(&ModalString, usize)]) -> usize {
        let had = self.partners;
        let added = partners.len().min(MAX_PARTNERS - had);
        if added == 0 {
            return 0;
        }
        // The partners' modes lie between the strings' and the bridge's: the new ones go last, so
        // those there keep their places, and their lifts and weights (which `place` clears) are
        // put back as they were, with their shares of the bridge's mass and stiffness.
        let bridge = self.bridge_range.clone();
        let kept = if had > 0 { self.partner_ranges[0].start..bridge.start } else { bridge.start..bridge.start };
        let (mut lift, mut pickup) = ([0.0; MAX_PARTNERS * PARTNER_MODES], [0.0; MAX_PARTNERS * PARTNER_MODES]);
        let n = kept.len().min(lift.len());
        lift[..n].copy_from_slice(&self.coupled.lift[kept.start..kept.start + n]);
        pickup[..n].copy_from_slice(&self.coupled.pickup[kept.start..kept.start + n]);
        let (mass, stiffness) = (self.coupling.lift_mass, self.coupling.lift_stiffness);
        let mut end = bridge.start;
        for (range, (string, modes)) in self.partner_ranges[had..had + added].iter_mut().zip(partners) {
            let modes = 0..(*modes).min(string.modes()).min(PARTNER_MODES);
            *range = self.coupled_bank.insert_modes(end, string, modes);
            end = range.end;
        }
        self.partners = had + added;
        let shift = end - bridge.start;
        self.bridge_range = bridge.start + shift..bridge.end + shift;
        self.coupled_bank.finish();
        self.place();
        self.coupled.lift[kept.start..kept.start + n].copy_from_slice(&lift[..n]);
        self.coupled.pickup[kept.start..kept.start + n].copy_from_slice(&pickup[..n]);
        (self.coupling.lift_mass, self.coupling.lift_stiffness) = (mass, stiffness);
        self.place_partners(&partners[..added], had);
        self.measure();
        added
    }

    /// The lifts and bridge force weights (over the unison's `S`, as its own strings' output) of
    /// the partners from the `first`-th on, and their static shares of the bridge's mass and
    /// stiffness; then the coupling follows the vectors.
    fn place_partners(&mut self, partners: &[(&ModalString, usize)], first: usize) {
        let n = self.count as f64;
        let mut weights = [0.0; PARTNER_MODES];
        for (range, (string, _)) in self.partner_ranges[first..].iter().zip(partners) {
            let p = string.params();
            // The lowest modes' weights (the weights run over as many modes as they are given).
            string.bridge_weights(true, &mut weights);
            for (k, i) in range.clone().enumerate() {
                let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                self.coupled.lift[i] = sign * p.linear_density / string.wavenumbers()[k];
                self.coupled.pickup[i] = weights[k] / n;
            }
            self.coupling.lift_mass += p.linear_density * p.length / 3.0;
            self.coupling.lift_stiffness += p.tension / p.length;
        }
        self.refresh_coupling();
    }

    /// Set the extra decay rate of each partner `j` with `rates[j] = Some(rate)` (1/s): a damper
    /// on its strings, or 0 to lift it; those with `None` keep theirs. The state is untouched;
    /// the coupling follows.
    pub fn set_partner_decays(&mut self, rates: &[Option<f64>]) {
        for (range, rate) in self.partner_ranges[..self.partners].iter().cloned().zip(rates) {
            if let Some(rate) = *rate {
                let n = range.len().min(PARTNER_MODES);
                self.coupled_bank.set_extra_decay(range, &[rate; PARTNER_MODES][..n]);
            }
        }
        self.refresh_coupling();
        if self.retired {
            self.judge_again();
        }
    }

    /// Partner `j`'s energy and the bridge's, weighed with their own stiffnesses (J): the
    /// energy of what moves the partner at a striking point (module docs).
    pub fn partner_energy(&self, j: usize) -> f64 {
        if j >= self.partners {
            return 0.0;
        }
        let bank = &self.coupled_bank;
        bank.own_energy(self.partner_ranges[j].clone()) + bank.own_energy(self.bridge_range.clone())
    }

    /// The amplitude (m) of the unison's widest swing at the fraction `x` of the strings' length:
    /// the largest of its strings' ([`ModalBank::swing_at`]).
    pub fn swing_at(&self, x: f64) -> f64 {
        (0..self.count)
            .map(|s| {
                let coupled = self.coupled_bank.swing_at(self.coupled_ranges[s].clone(), 1, x);
                let free = self.free_bank.swing_at(self.free_ranges[s].clone(), self.split[s] + 1, x);
                (coupled + free).sqrt()
            })
            .fold(0.0, f64::max)
    }

    /// The amplitude (m) of partner `j`'s swing at the fraction `x` of its length, 0 for a
    /// partner the bridge does not hold ([`ModalBank::swing_at`]).
    pub fn partner_swing_at(&self, j: usize, x: f64) -> f64 {
        if j >= self.partners {
            return 0.0;
        }
        self.coupled_bank.swing_at(self.partner_ranges[j].clone(), 1, x).sqrt()
    }

    /// The partner strings' energy weighed with their own stiffnesses (J).
    pub fn partners_energy(&self) -> f64 {
        self.partner_ranges[..self.partners].iter().map(|r| self.coupled_bank.own_energy(r.clone())).sum()
    }

    /// How many partner strings ring with the unison.
    pub fn partners(&self) -> usize {
        self.partners
    }

    /// After the banks' coefficients changed (a damper): the gains, the coupling and the reach
    /// follow, and the hammer is judged again.
    fn refresh_coupling(&mut self) {
        self.coupled.refresh(&self.coupled_bank);
        self.free.refresh(&self.free_bank);
        let (c, f, cb, fb) = (&self.coupled, &self.free, &self.coupled_bank, &self.free_bank);
        self.coupling.hh = cb.project(&c.shape, &c.shape_gain) + fb.project(&f.shape, &f.shape_gain);
        self.coupling.gh = cb.project(&c.lift, &c.shape_gain);
        self.coupling.gg = cb.project(&c.lift, &c.lift_gain);
        self.coupling.compliance = cb.project(&c.sole, &c.sole_gain);
        self.coupling.reach = self.reach();
        let (c, dt2) = (&mut self.coupling, self.dt * self.dt);
        let (theta, inertia) = (c.gg / dt2, c.lift_mass + 0.25 * c.lift_stiffness * dt2);
        c.inverse_dt2 = 1.0 / dt2;
        c.theta_less_e = theta - inertia;
        c.inverse_delta = 1.0 / (dt2 - c.compliance * c.theta_less_e);
        self.next_coupled = None;
        self.next_free = None;
        self.next_retired = None;
    }

    /// `ρ_V + ½Δt ρ_T` (module docs), keeping the sums over the bridge's modes and the lifts
    /// that the partners' bounds share with it.
    fn reach(&mut self) -> f64 {
        let (mut potential, mut cc, mut gc) = (0.0, 0.0, 0.0);
        let (mut lifts, mut flexibility, mut mobility) = (0.0, 0.0, 0.0);
        for (part, bank) in [(&self.coupled, &self.coupled_bank), (&self.free, &self.free_bank)] {
            let modes = part.shape.iter().zip(&part.lift).zip(&part.sole);
            for (((h, g), e), (k, m)) in modes.zip(bank.stiffness().iter().zip(bank.masses())) {
                if *e > 0.0 {
                    if *k > 0.0 {
                        flexibility += 1.0 / k;
                    }
                    mobility += 1.0 / m;
                } else {
                    if *k > 0.0 {
                        potential += h * h / k;
                    }
                    cc += h * h / m;
                    gc += g * h / m;
                    lifts += g * g / m;
                }
            }
        }
        let c = &mut self.coupling;
        (c.lifts_over_mass, c.bridge_flexibility, c.bridge_mobility) = (lifts, flexibility, mobility);
        self.bound(potential, cc, gc, self.ell)
    }

    /// `ρ_V + ½Δt ρ_T` for the contact vector `c` that is `h` on the strings' and partners' modes
    /// and `ell` on the bridge's, from `Σ h²/K`, `Σ h²/m` and `Σ gh/m` over the former: the
    /// potential part `Σ c²/K` and `cᵀM⁻¹c` for the coupled mass matrix, in closed form.
    fn bound(&self, potential: f64, cc: f64, gc: f64, ell: f64) -> f64 {
        let c = &self.coupling;
        let potential = potential + ell * ell * c.bridge_flexibility;
        let (r, mu) = (ell - gc, c.lift_mass - c.lifts_over_mass);
        let beta = r * c.bridge_mobility / (1.0 + mu * c.bridge_mobility);
        let kinetic = (cc - beta * gc + ell * beta).max(0.0);
        let reach = potential.sqrt() + 0.5 * self.dt * kinetic.sqrt();
        if reach.is_finite() { reach } else { f64::INFINITY }
    }

    /// The strings' mean displacement at the striking point plus the bridge's share and the
    /// background, `(u_h^{n−1}, u_h^n)` (m).
    fn under_hammer(&self) -> (f64, f64) {
        let (b, beta) = (self.b, self.background);
        (self.hv.0 + self.ell * b.0 + beta.0, self.hv.1 + self.ell * b.1 + beta.1)
    }

    /// The background `β^n` (m): the strings' motion at the striking point in the other keys'
    /// copies, as the hammer last met it (module docs).
    pub fn background(&self) -> f64 {
        self.background.1
    }

    /// The strings' motion at the striking point in the other keys' copies, `(β^{n−1}, β^n)`
    /// (m), and how far it can reach (m) (module docs): set before [`strike`](Self::strike),
    /// which throws the hammer over the strings where they are in all the copies. It lasts until
    /// the strings are retuned or brought to rest.
    pub fn set_background(&mut self, motion: (f64, f64), reach: f64) {
        let finite = |x: f64| if x.is_finite() { x } else { 0.0 };
        self.background = (finite(motion.0), finite(motion.1));
        self.background_next = self.background.1;
        self.background_reach = if reach >= 0.0 { reach } else { 0.0 };
    }

    fn clear_background(&mut self) {
        self.set_background((0.0, 0.0), 0.0);
        self.background_work = 0.0;
    }

    /// The watched partner's displacement at its own key's striking point, `(u^{n−1}, u^n)` (m):
    /// its modes' there and its end's share of the bridge's motion (module docs). Zero for a
    /// partner the unison does not have.
    pub fn partner_motion(&self, watch: &Watch) -> (f64, f64) {
        if watch.partner >= self.partners {
            return (0.0, 0.0);
        }
        let (prev, now) = self.coupled_bank.state(self.partner_ranges[watch.partner].clone());
        (watch.along(prev, self.b.0), watch.along(now, self.b.1))
    }

    /// How far the watched partner's displacement at its key's striking point can be from rest
    /// per `√(2H)` (m/√J), `H` the energy of this key's strings and bridge: the hammer's bound
    /// (module docs) over the partner's vector.
    pub fn partner_reach(&self, watch: &Watch) -> f64 {
        if watch.partner >= self.partners {
            return 0.0;
        }
        let range = self.partner_ranges[watch.partner].clone();
        let (bank, lift) = (&self.coupled_bank, &self.coupled.lift[range.clone()]);
        let (k, m) = (&bank.stiffness()[range.clone()], &bank.masses()[range]);
        let (mut potential, mut cc, mut gc) = (0.0, 0.0, 0.0);
        for (((h, g), k), m) in watch.sines.iter().zip(lift).zip(k).zip(m) {
            if *k > 0.0 {
                potential += h * h / k;
            }
            cc += h * h / m;
            gc += g * h / m;
        }
        self.bound(potential, cc, gc, watch.ell)
    }

    /// Recompute every projection of the state (the hammer is judged again).
    fn project(&mut self) {
        let (c, f, cb, fb) = (&self.coupled, &self.free, &self.coupled_bank, &self.free_bank);
        let (hc, hf) = (cb.project_state(&c.shape), fb.project_state(&f.shape));
        self.hv = (hc.0 + hf.0, hc.1 + hf.1);
        self.gv = cb.project_state(&c.lift);
        self.b = cb.project_state(&c.sole);
        self.next_coupled = None;
        self.next_free = None;
        self.next_retired = None;
        self.retired = false;
    }

    /// Recompute every projection, the compressions and the output from the state.
    fn measure(&mut self) {
        self.project();
        self.out_now =
            self.coupled_bank.project_state(&self.coupled.pickup).1 + self.free_bank.project_state(&self.free.pickup).1;
        let (prev, now) = self.under_hammer();
        self.y_prev = prev - self.hammer.previous();
        self.y_now = now - self.hammer.position();
        self.since_check = 0;
        self.mirror();
    }

    /// Copy the first string's state from the banks into it (what [`string`](Self::string) shows).
    fn mirror(&mut self) {
        let (cp, cn) = self.coupled_bank.state(self.coupled_ranges[0].clone());
        let (fp, fn_) = self.free_bank.state(self.free_ranges[0].clone());
        let string = &mut self.strings[0];
        if string.modes() != cp.len() + fp.len() {
            return;
        }
        let (prev, now) = string.state_mut();
        let m = cp.len();
        prev[..m].copy_from_slice(cp);
        now[..m].copy_from_slice(cn);
        prev[m..].copy_from_slice(fp);
        now[m..].copy_from_slice(fn_);
    }

    /// Throw the hammer (its whole mass) again, `gap` beyond the string under it: see
    /// [`HammerCore::strike`](super::HammerCore::strike). Restart the solver with
    /// [`compressions`](Self::compressions) afterwards.
    pub fn strike(&mut self, hammer: &HammerParams) {
        self.project();
        let (before, now) = self.under_hammer();
        let under = now.max(before - hammer.velocity * self.dt);
        self.hammer = Hammer::above(under, hammer, 1.0 / self.dt);
        self.measure();
    }

    /// Add the decay rates `extra` (1/s, one per mode of a string, the same for every string of
    /// the unison) to the strings' own, and `bridge` (1/s) to every bridge mode's (see
    /// [`ModalBank::set_extra_decay`]): a damper, or a stolen voice's fade. The state is
    /// untouched; the coupling follows the new coefficients.
    pub fn set_extra_decay(&mut self, extra: &[f64], bridge: f64) {
        for s in 0..self.count {
            let split = self.split[s].min(extra.len());
            self.coupled_bank.set_extra_decay(self.coupled_ranges[s].clone(), &extra[..split]);
            self.free_bank.set_extra_decay(self.free_ranges[s].clone(), &extra[split..]);
        }
        let rates = [bridge; crate::bridge::MAX_BRIDGE_MODES];
        self.coupled_bank.set_extra_decay(self.bridge_range.clone(), &rates[..self.bridge_range.len()]);
        self.refresh_coupling();
        if self.retired {
            self.judge_again();
        }
    }

    /// After the coefficients of a retired hammer's unison changed: every projection again from
    /// the state, and the hammer judged again at once, the energy weighed with the new
    /// coefficients (module docs). It stays retired if it is still out of reach, as the next
    /// check would find it, instead of being stepped with its contact until that check: a damper
    /// landing updates the coefficients at every block.
    fn judge_again(&mut self) {
        self.measure();
        self.retire_if_out_of_reach();
    }

    /// Retire the hammer if it has moved away beyond its reach for good (module docs).
    fn retire_if_out_of_reach(&mut self) {
        if self.out_of_reach() {
            self.retired = true;
            self.last_force = 0.0;
            self.next_retired = None;
        }
    }

    /// Bring strings and bridge to rest.
    pub fn reset(&mut self) {
        self.coupled_bank.reset();
        self.free_bank.reset();
        self.clear_background();
        self.last_force = 0.0;
        self.measure();
    }

    /// `(y^{n−1}, y^n)` (m), to start a solver from.
    pub fn compressions(&self) -> (f64, f64) {
        (self.y_prev, self.y_now)
    }

    /// The first string, with its state as of the latest call (what a monitor draws).
    pub fn string(&self) -> &ModalString {
        &self.strings[0]
    }

    /// How many modes are in the coupled part and in the free part.
    pub fn parts(&self) -> (usize, usize) {
        (self.coupled_bank.modes(), self.free_bank.modes())
    }

    /// Set every mode's state (tests of what follows a corrupt state): `value` (m) everywhere.
    pub fn fill_state(&mut self, value: f64) {
        self.coupled_bank.fill(value);
        self.free_bank.fill(value);
        self.measure();
    }

    /// Whether the hammer is out of the strings' reach for good (module docs).
    pub fn retired(&self) -> bool {
        self.retired
    }

    /// The most modes any string of the unison has.
    pub fn modes(&self) -> usize {
        self.strings[..self.count].iter().map(ModalString::modes).max().unwrap_or(0)
    }

    /// `(what rings, the bridge)`: the strings' and the partners' energy, and the bridge's and
    /// soundboard's modes', each weighed with the modes' own stiffnesses (J), in vector passes
    /// over the two banks. What rings decides that a voice is silent (the strings are what sounds,
    /// and the partners without dampers ring on and feed them; the bridge's slowest modes ring on
    /// at their own rate); the guard reads both.
    pub fn weigh(&self) -> (f64, f64) {
        // The coupled bank holds the strings' modes, then the partners', then the bridge's.
        let (coupled, bridge) = self.coupled_bank.own_energy_split(self.bridge_range.start);
        let (free, _) = self.free_bank.own_energy_split(self.free_bank.modes());
        (coupled + free, bridge)
    }

    /// The strings' and the bridge's energy weighed with their own stiffnesses (J), the
    /// coupling's cross terms left out: what a voice's guard reads.
    pub fn own_energy(&self) -> f64 {
        let (ringing, bridge) = self.weigh();
        ringing + bridge
    }

    /// The strings' and bridge's numerical energy and the hammer's (J), without the coupling's
    /// cross terms and the contact term.
    pub fn energy(&self) -> f64 {
        self.coupled_bank.energy() + self.free_bank.energy() + self.hammer.energy()
    }

    /// The numerical energy `H^{n−1/2}` of strings and bridge with the coupling's terms (J).
    fn system_energy(&self) -> f64 {
        let c = self.coupling;
        let (db, mean) = ((self.b.1 - self.b.0) / self.dt, 0.5 * (self.b.1 + self.b.0));
        let cross = (self.gv.1 - self.gv.0) / self.dt * db;
        self.coupled_bank.energy()
            + self.free_bank.energy()
            + cross
            + 0.5 * c.lift_mass * db * db
            + 0.5 * c.lift_stiffness * mean * mean
    }

    /// `(compression y^n (m), latest contact force (N))`. Once the hammer is retired its
    /// projections are no longer kept: the compression is measured from the state.
    pub fn contact(&self) -> (f64, f64) {
        if self.retired {
            let (c, f) = (&self.coupled, &self.free);
            let strings = self.coupled_bank.project_state(&c.shape).1 + self.free_bank.project_state(&f.shape).1;
            (strings + self.ell * self.b.1 - self.hammer.position(), 0.0)
        } else {
            (self.y_now, self.last_force)
        }
    }

    /// Whether the felt is touching or about to.
    pub fn in_contact(&self) -> bool {
        !self.retired && (self.y_now > 0.0 || self.y_prev > 0.0)
    }

    /// Whether the hammer flies away from the strings, clear of them.
    pub fn hammer_leaving(&self) -> bool {
        self.retired || (self.hammer.velocity() > 0.0 && self.y_now < 0.0 && self.y_prev < 0.0)
    }

    /// Whether the hammer moves away and is beyond what the strings' and bridge's energy can
    /// reach (module docs).
    fn out_of_reach(&self) -> bool {
        self.hammer.velocity() > 0.0
            && self.y_now < 0.0
            && self.y_prev < 0.0
            && self.hammer.position()
                > self.coupling.reach * (2.0 * self.system_energy().max(0.0)).sqrt() + self.background_reach
    }

    /// One step with `solver`; with `MONITOR` the frame also carries the energy terms. A hammer
    /// retired by [`process_output`](Self::process_output) is back in play: every projection and
    /// the compressions are measured again from the state, which the retired steps moved on.
    #[inline]
    pub fn step<S: ContactSolver, const MONITOR: bool>(&mut self, solver: &mut S) -> Frame {
        if self.retired {
            self.measure();
        }
        let (dt, ell) = (self.dt, self.ell);
        let dt2 = dt * dt;
        let c = self.coupling;
        let (cp, fp) = (&self.coupled, &self.free);
        let [hz_c, gz, ez] = match self.next_coupled.take() {
            Some(z) => z,
            None => self.coupled_bank.history([&cp.shape, &cp.lift, &cp.sole]),
        };
        let [hz_f] = match self.next_free.take() {
            Some(z) => z,
            None => self.free_bank.history([&fp.shape]),
        };
        let hz = hz_c + hz_f;
        let (b_prev, b_now) = self.b;
        // The known part of the force on the bridge, and where the bridge would go without it.
        let g0 = (2.0 * self.gv.0 - gz - 2.0 * self.gv.1) / dt2 + c.lift_stiffness * b_now;
        let b_free = b_prev - ez;
        let gamma = c.gh / dt2;
        let theta = c.gg / dt2;
        let inertia = c.lift_mass + 0.25 * c.lift_stiffness * dt2;
        let den = dt2 + c.compliance * (inertia - theta);
        let a0 = (b_free - 2.0 * b_now + b_prev - c.compliance * g0) / den;
        let a1 = c.compliance * (ell - gamma) / den;
        let lever = dt2 * (ell - gamma);
        let (beta_next, beta_prev) = (self.background_next, self.background.0);
        let problem = ContactProblem {
            y_prev: self.y_prev,
            y_now: self.y_now,
            z: hz - self.hammer.history() - lever * a0 - 2.0 * ell * (b_now - b_prev) - (beta_next - beta_prev),
            q: c.hh + self.hammer.coupling() + lever * a1,
        };
        let solution = solver.solve(&problem);
        let force = solution.force;
        let a = a0 + a1 * force;
        let f = (ell - gamma) * force - g0 + (theta - inertia) * a;
        let forces = [(&cp.shape_gain[..], force), (&cp.lift_gain[..], -a), (&cp.sole_gain[..], f)];
        let hv_next = self.hv.0 - hz + c.hh * force - c.gh * a;
        let gv_next = self.gv.0 - gz + c.gh * force - c.gg * a;
        let b_next = b_free + c.compliance * f;
        let mut frame = Frame { force, ..Frame::default() };
        let fresh;
        let out_next = if MONITOR {
            let (out_c, stored_c, lost_c) = self.coupled_bank.advance_monitored(forces, &cp.pickup);
            let (out_f, stored_f, lost_f) = self.free_bank.advance_monitored([(&fp.shape_gain[..], force)], &fp.pickup);
            self.losses += lost_c + lost_f;
            let db = (b_next - b_now) / dt;
            let mean = 0.5 * (b_next + b_now);
            let cross = (gv_next - self.gv.1) / dt * db;
            frame.energy =
                stored_c + stored_f + cross + 0.5 * c.lift_mass * db * db + 0.5 * c.lift_stiffness * mean * mean;
            fresh = true;
            out_c + out_f
        } else {
            // The bridge's modes come last: only the sole is nonzero there, and only there.
            let [shape, lift, sole] = forces;
            let bridge = Tail { start: self.bridge_range.start, forces: [sole], next: [&cp.sole[..]] };
            let (out_c, next_c) =
                self.coupled_bank.advance_split([shape, lift], &cp.pickup, [&cp.shape, &cp.lift], bridge);
            let next_c = next_c.map(|([h, g], [e])| [h, g, e]);
            let (out_f, next_f) =
                self.free_bank.advance_projecting([(&fp.shape_gain[..], force)], &fp.pickup, [&fp.shape]);
            self.next_coupled = next_c;
            self.next_free = next_f;
            fresh = next_c.is_some() && next_f.is_some();
            out_c + out_f
        };
        if fresh {
            self.hv = (self.hv.1, hv_next);
            self.gv = (self.gv.1, gv_next);
            self.b = (self.b.1, b_next);
        } else {
            // A bank flushed tiny amplitudes: project the state afresh.
            let (c, f, cb, fb) = (&self.coupled, &self.free, &self.coupled_bank, &self.free_bank);
            let (hc, hf) = (cb.project_state(&c.shape), fb.project_state(&f.shape));
            self.hv = (hc.0 + hf.0, hc.1 + hf.1);
            self.gv = cb.project_state(&c.lift);
            self.b = cb.project_state(&c.sole);
        }
        let w_now = self.hammer.position();
        self.hammer.advance(force);
        let y_next = self.y_prev + solution.s;
        frame.output = self.out_now;
        frame.displacement = w_now;
        frame.velocity = self.hammer.velocity();
        frame.compression = self.y_now;
        frame.work = solver.last_work();
        self.background = (self.background.1, beta_next);
        if MONITOR {
            self.background_work -= 0.5 * force * (beta_next - beta_prev);
            frame.energy += self.hammer.energy() + solver.stored_energy(y_next, self.y_now);
            frame.losses = self.losses;
            frame.control_work = self.background_work;
        }
        self.last_force = force;
        self.out_now = out_next;
        self.y_prev = self.y_now;
        self.y_now = y_next;
        frame
    }

    /// One step of the coupled part once the hammer is retired: no force, no striking point.
    /// Returns the coupled part's output at `n+1`.
    #[inline]
    fn retired_step(&mut self) -> f64 {
        let c = self.coupling;
        let cp = &self.coupled;
        let [gz, ez] = match self.next_retired.take() {
            Some(z) => z,
            None => self.coupled_bank.history([&cp.lift, &cp.sole]),
        };
        let (b_prev, b_now) = self.b;
        let g0 = (2.0 * self.gv.0 - gz - 2.0 * self.gv.1) * c.inverse_dt2 + c.lift_stiffness * b_now;
        let b_free = b_prev - ez;
        let a = (b_free - 2.0 * b_now + b_prev - c.compliance * g0) * c.inverse_delta;
        let f = -g0 + c.theta_less_e * a;
        let bridge = Tail { start: self.bridge_range.start, forces: [(&cp.sole_gain[..], f)], next: [&cp.sole[..]] };
        let (out, next) = self.coupled_bank.advance_split([(&cp.lift_gain[..], -a)], &cp.pickup, [&cp.lift], bridge);
        let next = next.map(|([g], [e])| [g, e]);
        self.next_retired = next;
        if next.is_some() {
            self.gv = (self.gv.1, self.gv.0 - gz - c.gg * a);
            self.b = (self.b.1, b_free + c.compliance * f);
        } else {
            self.gv = self.coupled_bank.project_state(&self.coupled.lift);
            self.b = self.coupled_bank.project_state(&self.coupled.sole);
        }
        out
    }

    /// Advance `out.len()` samples with `solver`, writing the output (the mean bridge force per
    /// string, N); once the hammer is out of reach for good, the free part runs on its own and
    /// the coupled part without the contact (module docs).
    pub fn process_output<S: ContactSolver>(&mut self, solver: &mut S, out: &mut [f64]) {
        self.process_shared(solver, out, Shared::default());
    }

    /// [`process_output`](Self::process_output), the hammer meeting the strings' motion in the
    /// other keys' copies too (`shared.background`), and the watched partners' motion at their
    /// keys' striking points added to the sinks after every step (module docs).
    pub fn process_shared<S: ContactSolver>(&mut self, solver: &mut S, out: &mut [f64], shared: Shared) {
        let Shared { background, watches, sinks } = shared;
        let mut done = 0;
        while done < out.len() && !self.retired {
            // Motion handed on by a voice gone wrong (not finite) is not met: the fault stays
            // with that voice, whose guard silences it, instead of spreading to this one.
            self.background_next = background.get(done).copied().filter(|b| b.is_finite()).unwrap_or(0.0);
            out[done] = self.step::<S, false>(solver).output;
            self.report(watches, sinks, done);
            done += 1;
            self.since_check += 1;
            if self.since_check == RETIRE_CHECK {
                self.since_check = 0;
                self.retire_if_out_of_reach();
            }
        }
        let rest = &mut out[done..];
        if !rest.is_empty() {
            // The free part's outputs at n+1, n+2, …; the coupled part's added step by step.
            self.free_bank.free_steps(&self.free.pickup, rest);
            if watches.is_empty() {
                rest.iter_mut().for_each(|o| self.retired_sample(o));
            } else {
                for (k, o) in rest.iter_mut().enumerate() {
                    self.retired_sample(o);
                    self.report(watches, sinks, done + k);
                }
            }
        }
        self.mirror();
    }

    /// One sample once the hammer is retired: `o` holds the free part's output at `n+1` and
    /// becomes the whole output at `n`.
    #[inline]
    fn retired_sample(&mut self, o: &mut f64) {
        let next = *o + self.retired_step();
        *o = self.out_now;
        self.out_now = next;
        self.hammer.advance(0.0);
    }

    /// Add each watched partner's motion after step `k` to its sink.
    #[inline]
    fn report(&self, watches: &[Watch], sinks: &mut [Vec<f64>], k: usize) {
        for w in watches.iter().filter(|w| w.partner < self.partners) {
            let (_, now) = self.coupled_bank.state(self.partner_ranges[w.partner].clone());
            if let Some(x) = sinks.get_mut(w.sink).and_then(|sink| sink.get_mut(k)) {
                *x += w.along(now, self.b.1);
            }
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
    /// `core` retuned and struck; the solver is started from its compressions, and the books
    /// are opened on the whole energy `H^{n−1/2}`, the bridge's and the coupling's terms with it
    /// (a core struck while it rings has them).
    pub fn new(mut core: UnisonCore, mut solver: S) -> Self {
        let (y_prev, y_now) = core.compressions();
        solver.start(y_prev, y_now);
        (core.losses, core.background_work) = (0.0, 0.0);
        let initial_energy = core.system_energy() + core.hammer.energy() + solver.stored_energy(y_now, y_prev);
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
        c4_unison_with(strings, detune, bridge, &[])
    }

    /// [`c4_unison`] ringing with `partners` from the strike.
    fn c4_unison_with(
        strings: usize,
        detune: [f64; 3],
        bridge: &BridgeParams,
        partners: &[(&ModalString, usize)],
    ) -> UnisonCore {
        let c4 = chaigne_askenfelt_c4();
        let params = UnisonParams { string: c4.string, strings, detune };
        let mut core = UnisonCore::new(200, bridge, FS).unwrap();
        core.retune_with_partners(&params, f64::INFINITY, c4.strike_position, partners).unwrap();
        let mass = c4.hammer_mass * strings as f64;
        core.strike(&HammerParams { mass, velocity: 3.5, position: c4.strike_position, gap: 2e-4 });
        core
    }

    /// Key `key`'s unison as one partner string (its mass, tension and bending stiffness
    /// together), up to the modes below 4.3 times its fundamental.
    fn partner(key: u8) -> ModalString {
        let note = crate::preset::piano_note(key);
        let mut p = note.string;
        p.linear_density *= note.strings as f64;
        p.tension *= note.strings as f64;
        p.bending_stiffness *= note.strings as f64;
        let mut s = ModalString::with_capacity(PARTNER_MODES + 1);
        s.retune(p, FS, 4.3 * p.fundamental()).unwrap();
        s
    }

    /// 50 ms of the bridge force (N) of one C4 string on a still bridge, struck at 3.5 m/s by
    /// `shares` of the rule's hammer (one string's share) with one share's felt, solved by QSA
    /// fitted up to `y_ref`.
    fn single_c4(shares: f64, y_ref: f64) -> Vec<f64> {
        let c4 = chaigne_askenfelt_c4();
        let mass = shares * c4.hammer_mass;
        let params = HammerStringParams {
            string: c4.string,
            hammer: HammerParams { mass, velocity: 3.5, position: c4.strike_position, gap: 2e-4 },
            pickup: Pickup::point(OutputKind::BridgeForce, 0.5),
        };
        let string = ModalString::new(c4.string, FS).unwrap();
        let mut single = HammerString::new(string, &params, QsaSolver::new(QuadSpline::new(law(1), y_ref, 6).unwrap()));
        let mut out = vec![0.0; 2400];
        single.process_output(&mut out);
        out
    }

    fn law(strings: usize) -> PowerLaw {
        let c4 = chaigne_askenfelt_c4();
        PowerLaw::new(c4.kappa * strings as f64, c4.alpha).unwrap()
    }

    /// A key struck again on the same unison finds its strings prepared and only brings them to
    /// rest; another key is prepared afresh. Rung, then retuned key after key (C4, another, C4,
    /// C4) and struck each time, a unison gives each key's fresh output bit for bit.
    #[test]
    fn a_key_struck_again_sounds_as_on_a_fresh_unison() {
        let board = BridgeParams::soundboard(SOUNDBOARD_CONDUCTANCE);
        let c4 = chaigne_askenfelt_c4();
        let params = UnisonParams { string: c4.string, strings: 3, detune: [-1.0, 0.2, 0.8] };
        let mut other = params;
        other.string.tension *= 1.5;
        let y_ref = law(3).compression_at_energy(0.5 * 3.0 * 2.97e-3 * 3.5 * 3.5);
        let hammer =
            HammerParams { mass: c4.hammer_mass * 3.0, velocity: 3.5, position: c4.strike_position, gap: 2e-4 };
        let strike = |core: &mut UnisonCore, params: &UnisonParams| {
            core.retune_with_partners(params, f64::INFINITY, c4.strike_position, &[]).unwrap();
            core.strike(&hammer);
        };
        let render = |core: UnisonCore| {
            let mut scene = HammerUnison::new(core, QsaSolver::new(QuadSpline::new(law(3), y_ref, 6).unwrap()));
            let mut out = vec![0.0; 6_000];
            scene.core.process_output(&mut scene.solver, &mut out);
            (out.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), scene.core)
        };
        let fresh = |params: &UnisonParams| {
            let mut core = UnisonCore::new(200, &board, FS).unwrap();
            strike(&mut core, params);
            render(core).0
        };
        let (fresh_c4, fresh_other) = (fresh(&params), fresh(&other));
        assert_ne!(fresh_c4, fresh_other);
        let (_, mut core) = render(c4_unison(3, params.detune, &board));
        for (name, key, want) in [
            ("another key", &other, &fresh_other),
            ("C4 after it", &params, &fresh_c4),
            ("C4 again", &params, &fresh_c4),
        ] {
            strike(&mut core, key);
            let (out, rung) = render(core);
            assert!(&out == want, "{name}");
            core = rung;
        }
    }

    /// Strings and bridge are linear, so a key's copies add up to one system but for the
    /// contact (module docs): a unison at rest struck while a copy of it rings, its hammer
    /// meeting the copy's motion at the striking point as the background, must sound with the
    /// copy as the ringing unison struck again. Struck at 2 m/s 0.3 s after a strike at 3.5 m/s,
    /// for each solver over 0.1 s: the contact forces agree to 1e-9 of their peak and the
    /// outputs to 1e-9 of theirs, and the struck copy's `H + losses − W` (the background's work
    /// `W` booked) stays at its initial value to 1e-9 of the peak energy. Without the background
    /// the peak force differs by far more (printed).
    #[test]
    fn a_hammer_meets_the_strings_where_another_copy_rings_them() {
        let board = BridgeParams::soundboard(SOUNDBOARD_CONDUCTANCE);
        let c4 = chaigne_askenfelt_c4();
        let y_ref = law(3).compression_at_energy(0.5 * 3.0 * 2.97e-3 * 3.5 * 3.5);
        let mut ringing = c4_unison(3, [-1.0, 0.2, 0.8], &board);
        let mut qsa = QsaSolver::new(QuadSpline::new(law(3), y_ref, 6).unwrap());
        let (y_prev, y_now) = ringing.compressions();
        qsa.start(y_prev, y_now);
        ringing.process_output(&mut qsa, &mut vec![0.0; 14_400]);
        let hammer =
            HammerParams { mass: c4.hammer_mass * 3.0, velocity: 2.0, position: c4.strike_position, gap: 2e-4 };
        fn compare<S: ContactSolver>(ringing: &UnisonCore, hammer: &HammerParams, make: impl Fn() -> S, name: &str) {
            let n = 4_800;
            let started = |core: &UnisonCore| {
                let mut solver = make();
                let (y_prev, y_now) = core.compressions();
                solver.start(y_prev, y_now);
                solver
            };
            // One system: the ringing strings struck again.
            let mut one = ringing.clone();
            one.strike(hammer);
            let mut solver = started(&one);
            let whole: Vec<Frame> = (0..n).map(|_| one.step::<S, true>(&mut solver)).collect();
            // Two copies: the ringing one left alone, and one at rest struck over its motion.
            let (mut copy, mut fresh, mut alone) = (ringing.clone(), ringing.clone(), ringing.clone());
            // The retired hammer's path does not follow the striking point: project it again.
            copy.project();
            let mut idle = started(&copy);
            fresh.reset();
            fresh.set_background(copy.under_hammer(), 0.0);
            fresh.strike(hammer);
            let mut solver = started(&fresh);
            let initial = fresh.energy() + solver.stored_energy(fresh.y_now, fresh.y_prev);
            let (mut force, mut output, mut drift, mut peak) = (0.0f64, 0.0f64, 0.0f64, initial);
            for frame in &whole {
                let rung = copy.step::<S, true>(&mut idle);
                fresh.background_next = copy.under_hammer().1;
                let struck = fresh.step::<S, true>(&mut solver);
                force = force.max((struck.force - frame.force).abs());
                output = output.max((struck.output + rung.output - frame.output).abs());
                peak = peak.max(struck.energy);
                drift = drift.max((struck.balance() - initial).abs());
            }
            let peak_force = whole.iter().map(|f| f.force.abs()).fold(0.0, f64::max);
            let peak_output = whole.iter().map(|f| f.output.abs()).fold(0.0, f64::max);
            let (force, output, drift) = (force / peak_force, output / peak_output, drift / peak);
            // The same strike on strings at rest: what the background changes.
            alone.reset();
            alone.strike(hammer);
            let mut solver = started(&alone);
            let unaware = (0..n).map(|_| alone.step::<S, true>(&mut solver).force.abs()).fold(0.0, f64::max);
            println!(
                "{name}: force {force:.1e}, output {output:.1e}, drift {drift:.1e} (peak {peak_force:.1} N, at rest {unaware:.1} N)"
            );
            assert!(force < 1e-9 && output < 1e-9 && drift < 1e-9, "{name}: {force:e} {output:e} {drift:e}");
            // The background matters: met on strings at rest, the strike's peak force differs
            // from the copy's by over a tenth (measured 23 %), so the match above is not trivial.
            assert!((unaware - peak_force).abs() > 0.1 * peak_force, "{name}: {unaware} N at rest, {peak_force} N");
        }
        compare(&ringing, &hammer, || QsaSolver::new(QuadSpline::new(law(3), y_ref, 6).unwrap()), "qsa");
        compare(&ringing, &hammer, || NewtonSolver::new(law(3)), "imp");
        compare(&ringing, &hammer, || ExplicitSolver::new(law(3)), "exp");
    }

    /// Motion elsewhere that is not finite (handed on by a voice gone wrong) is not met: C4
    /// struck with NaN and infinities among its background samples sounds as with zeros there,
    /// to the bit, and stays finite.
    #[test]
    fn a_background_that_is_not_finite_is_not_met() {
        let board = BridgeParams::soundboard(SOUNDBOARD_CONDUCTANCE);
        let render = |bad: f64| {
            let mut core = c4_unison(3, [-1.0, 0.2, 0.8], &board);
            let y_ref = law(3).compression_at_energy(0.5 * 3.0 * 2.97e-3 * 3.5 * 3.5);
            let mut solver = QsaSolver::new(QuadSpline::new(law(3), y_ref, 6).unwrap());
            let (y_prev, y_now) = core.compressions();
            solver.start(y_prev, y_now);
            let mut background = vec![1e-7; 64];
            for k in [3, 20, 41] {
                background[k] = if k == 20 { -bad } else { bad };
            }
            let (mut out, mut all) = (vec![0.0; 64], Vec::new());
            for _ in 0..20 {
                let shared = Shared { background: &background, watches: &[], sinks: &mut [] };
                core.process_shared(&mut solver, &mut out, shared);
                all.extend(out.iter().map(|x| x.to_bits()));
            }
            all
        };
        let zeros = render(0.0);
        assert!(zeros.iter().all(|&x| f64::from_bits(x).is_finite()));
        for bad in [f64::NAN, f64::INFINITY] {
            assert!(render(bad) == zeros, "{bad}");
        }
    }

    /// The partners' motion at their own keys' striking points, handed on after every step
    /// while the key is struck and rings (C4 with C5 and G5, 1 s in blocks of 64 samples, the
    /// hammer live and then retired), is what [`UnisonCore::partner_motion`] reads at each
    /// block's end, bit for bit, and never leaves its bound: `partner_reach · √(2E)`, with `E`
    /// the strike's energy (measured at most 0.054 of it for C5, 0.013 for G5).
    #[test]
    fn the_partners_motion_handed_on_stays_within_its_reach() {
        let board = BridgeParams::soundboard(SOUNDBOARD_CONDUCTANCE);
        let (c5, g5) = (partner(72), partner(79));
        let mut core = c4_unison_with(3, [-1.0, 0.2, 0.8], &board, &[(&c5, 4), (&g5, 3)]);
        let y_ref = law(3).compression_at_energy(0.5 * 3.0 * 2.97e-3 * 3.5 * 3.5);
        let mut solver = QsaSolver::new(QuadSpline::new(law(3), y_ref, 6).unwrap());
        let (y_prev, y_now) = core.compressions();
        solver.start(y_prev, y_now);
        let energy = core.energy();
        let ells = [0.12, 0.1];
        let watches = [Watch::new(0, ells[0], 0), Watch::new(1, ells[1], 1)];
        let bounds = [0, 1].map(|j| core.partner_reach(&watches[j]) * (2.0 * energy).sqrt());
        let (mut out, mut sinks) = (vec![0.0; 64], vec![vec![0.0; 64]; 2]);
        let mut most = [0.0f64; 2];
        for _ in 0..750 {
            sinks.iter_mut().for_each(|s| s.fill(0.0));
            let shared = Shared { background: &[], watches: &watches, sinks: &mut sinks };
            core.process_shared(&mut solver, &mut out, shared);
            for j in 0..2 {
                assert_eq!(sinks[j][63].to_bits(), core.partner_motion(&watches[j]).1.to_bits(), "partner {j}");
                most[j] = most[j].max(sinks[j].iter().fold(0.0f64, |m, x| m.max(x.abs())) / bounds[j]);
            }
        }
        assert!(core.retired());
        println!("largest motion over its bound: C5 {:.3}, G5 {:.3}", most[0], most[1]);
        assert!(most.iter().all(|&m| m > 0.0 && m <= 1.0), "{most:?}");
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

    /// With partner strings on the bridge (C5 and G5, whose fundamentals C4's 2nd and 3rd
    /// partials meet, each its unison's mass, tension and bending stiffness in one string), a
    /// strike and 1 s of ringing keep `H + losses` at its initial value to 1e-9 relative, for each
    /// solver; the partners take energy from the key, at least 0.01 % of it at 1 s (measured
    /// 0.118 %), as nothing else gives them any; and the real-time path, which retires the
    /// hammer, gives the monitored output to 1e-9 of its peak.
    #[test]
    fn partner_strings_ring_from_the_key_and_keep_the_energy_balance() {
        let board = BridgeParams::soundboard(SOUNDBOARD_CONDUCTANCE);
        let (c5, g5) = (partner(72), partner(79));
        let keyed = || c4_unison_with(3, [-1.0, 0.2, 0.8], &board, &[(&c5, 4), (&g5, 3)]);
        let y_ref = law(3).compression_at_energy(0.5 * 3.0 * 2.97e-3 * 3.5 * 3.5);
        let qsa = || QsaSolver::new(QuadSpline::new(law(3), y_ref, 6).unwrap());
        let n = 48_000;
        fn check<S: ContactSolver>(mut scene: HammerUnison<S>, name: &str, n: usize) -> Vec<Frame> {
            let mut frames = vec![Frame::default(); n];
            scene.process(&mut frames);
            let start = scene.initial_energy();
            let peak = frames.iter().map(|f| f.energy).fold(start, f64::max);
            let drift = frames.iter().map(|f| (f.balance() - start).abs()).fold(0.0, f64::max) / peak;
            let share = scene.core().partners_energy() / scene.core().own_energy();
            println!("{name}: drift {drift:.2e}; the partners hold {:.3} % of the key's energy at 1 s", 100.0 * share);
            assert!(drift < 1e-9, "{name}: {drift:e}");
            assert!(share > 1e-4, "{name}: {share}");
            frames
        }
        let frames = check(HammerUnison::new(keyed(), qsa()), "qsa", n);
        check(HammerUnison::new(keyed(), NewtonSolver::new(law(3))), "imp", n);
        check(HammerUnison::new(keyed(), ExplicitSolver::new(law(3))), "exp", n);
        let mut fast = HammerUnison::new(keyed(), qsa());
        let mut out = vec![0.0; n];
        out.chunks_mut(64).for_each(|block| fast.process_output(block));
        assert!(fast.core().retired());
        let peak = frames.iter().fold(0.0f64, |m, f| m.max(f.output.abs()));
        let worst = out.iter().zip(&frames).map(|(x, f)| (x - f.output).abs()).fold(0.0, f64::max);
        println!("real-time path: worst {worst:.2e} of the peak {peak:.3}");
        assert!(worst < 1e-9 * peak, "{worst:e}");
    }

    /// Partners added to a ringing key (the pedal pressed after the strike) start at rest on the
    /// bridge's line: the energy steps up by exactly their static share of the bridge's motion,
    /// `½Σm_L(δ_t−b)² + ½Σk_L(μ_t−b)²`, and from there `H + losses` holds to 1e-9 of the peak
    /// energy over 0.75 s while they take up energy from the key (measured 0.2 % at the end); the
    /// real-time path, given the partners at the same step, gives the monitored output to 1e-9 of
    /// its peak. The same when the key already rings with a partner that has no damper (C7, from
    /// the strike): the new ones join beside it, which keeps its state.
    #[test]
    fn partners_added_to_a_ringing_key_start_on_the_bridge_and_keep_the_balance() {
        let board = BridgeParams::soundboard(SOUNDBOARD_CONDUCTANCE);
        let (c5, g5, c7) = (partner(72), partner(79), partner(96));
        let y_ref = law(3).compression_at_energy(0.5 * 3.0 * 2.97e-3 * 3.5 * 3.5);
        let solver = || QsaSolver::new(QuadSpline::new(law(3), y_ref, 6).unwrap());
        for from_strike in [&[][..], &[(&c7, 2)][..]] {
            let unison = || c4_unison_with(3, [-1.0, 0.2, 0.8], &board, from_strike);
            let (mut slow, mut fast) = (HammerUnison::new(unison(), solver()), HammerUnison::new(unison(), solver()));
            let (before, after) = (12_032, 36_032);
            let mut frames = vec![Frame::default(); before + after];
            slow.process(&mut frames[..before]);
            let mut out = vec![0.0; before + after];
            out[..before].chunks_mut(64).for_each(|block| fast.process_output(block));
            let core = &slow.core;
            let c = core.coupling;
            let (db, mean) = ((core.b.1 - core.b.0) / core.dt, 0.5 * (core.b.1 + core.b.0));
            let (lift_mass, lift_stiffness) = [&c5, &g5].iter().fold((0.0, 0.0), |(m, k), s| {
                let p = s.params();
                (m + p.linear_density * p.length / 3.0, k + p.tension / p.length)
            });
            let jump = 0.5 * lift_mass * db * db + 0.5 * lift_stiffness * mean * mean;
            let had = from_strike.len();
            let partner_state = |core: &UnisonCore| {
                let state = |r: &Range<usize>| {
                    let (prev, now) = core.coupled_bank.state(r.clone());
                    prev.iter().chain(now).map(|x| x.to_bits()).collect::<Vec<_>>()
                };
                core.partner_ranges[..had].iter().flat_map(state).collect::<Vec<_>>()
            };
            let kept = partner_state(&slow.core);
            assert_eq!(slow.core.add_partners(&[(&c5, 4), (&g5, 3)]), 2);
            assert_eq!(fast.core.add_partners(&[(&c5, 4), (&g5, 3)]), 2);
            assert_eq!(slow.core.partners(), had + 2);
            assert_eq!(partner_state(&slow.core), kept, "the partners there keep their state");
            assert!((slow.core.coupling.lift_mass - (c.lift_mass + lift_mass)).abs() < 1e-12 * lift_mass);
            slow.process(&mut frames[before..]);
            out[before..].chunks_mut(64).for_each(|block| fast.process_output(block));
            let start = slow.initial_energy();
            let peak = frames.iter().map(|f| f.energy).fold(start, f64::max);
            let expected = frames[before - 1].balance() + jump;
            let drift = frames[before..].iter().map(|f| (f.balance() - expected).abs()).fold(0.0, f64::max) / peak;
            let share = slow.core.partners_energy() / slow.core.own_energy();
            println!(
                "{had} partner(s) from the strike: jump {:.2e} of the peak; drift {drift:.2e}; partners hold {:.2} %",
                jump / peak,
                100.0 * share
            );
            assert!(drift < 1e-9, "{drift:e}");
            assert!(share > 1e-3, "{share}");
            let top = frames.iter().fold(0.0f64, |m, f| m.max(f.output.abs()));
            let worst = out.iter().zip(&frames).map(|(x, f)| (x - f.output).abs()).fold(0.0, f64::max);
            println!("real-time path: worst {worst:.2e} of the peak {top:.3}");
            assert!(worst < 1e-9 * top, "{worst:e}");
        }
    }

    /// The real-time path (the hammer retired once out of reach, the free part run on its own)
    /// gives the monitored path's output to rounding (1e-9 of the peak over 1 s, which the
    /// hammer leaves within 0.1 s), for a detuned trichord on the soundboard; and a damper landing
    /// on the retired voice has the hammer judged again at once: still out of reach, it stays
    /// retired, and the sound is still the monitored path's.
    #[test]
    fn the_real_time_path_retires_the_hammer_and_matches_the_monitored_path() {
        let board = BridgeParams::soundboard(SOUNDBOARD_CONDUCTANCE);
        let y_ref = law(3).compression_at_energy(0.5 * 3.0 * 2.97e-3 * 3.5 * 3.5);
        let solver = || QsaSolver::new(QuadSpline::new(law(3), y_ref, 6).unwrap());
        let mut fast = HammerUnison::new(c4_unison(3, [-1.0, 0.2, 0.8], &board), solver());
        let mut slow = HammerUnison::new(c4_unison(3, [-1.0, 0.2, 0.8], &board), solver());
        let n = 48_000;
        let (mut a, mut frames) = (vec![0.0; n], vec![Frame::default(); n]);
        for (k, block) in a.chunks_mut(64).enumerate() {
            if k == 400 {
                // A damper on every mode of both at the same step.
                let extra = [40.0; 200];
                fast.core.set_extra_decay(&extra, 0.0);
                slow.core.set_extra_decay(&extra, 0.0);
                assert!(fast.core.retired(), "judged again at once, the hammer is still out of reach");
            }
            fast.process_output(block);
            slow.process(&mut frames[k * 64..(k + 1) * 64]);
            if k == 100 {
                assert!(fast.core.retired(), "the hammer is retired 0.13 s after the strike");
            }
        }
        let peak = frames.iter().fold(0.0f64, |m, f| m.max(f.output.abs()));
        let worst = a.iter().zip(&frames).map(|(x, f)| (x - f.output).abs()).fold(0.0, f64::max);
        println!("peak {peak:.3} N, worst difference {worst:.2e} N, retired at the end: {}", fast.core.retired());
        assert!(worst < 1e-9 * peak, "{worst:e} of {peak}");
        assert!(fast.core.retired());
    }

    /// Frames stepped after the real-time path retired the hammer go on from where that path
    /// left the strings and the bridge: a detuned trichord on the soundboard, 0.5 s of the
    /// real-time path (the hammer retired), then 0.1 s of frames gives what 0.1 s more of the
    /// real-time path gives, to 1e-9 of the peak; and the retired hammer's compression is its
    /// distance from the strings as they are, measured afresh from the state.
    #[test]
    fn frames_after_the_hammer_retired_go_on_from_the_real_time_path() {
        let board = BridgeParams::soundboard(SOUNDBOARD_CONDUCTANCE);
        let y_ref = law(3).compression_at_energy(0.5 * 3.0 * 2.97e-3 * 3.5 * 3.5);
        let solver = QsaSolver::new(QuadSpline::new(law(3), y_ref, 6).unwrap());
        let mut scene = HammerUnison::new(c4_unison(3, [-1.0, 0.2, 0.8], &board), solver);
        let mut head = vec![0.0; 24_000];
        scene.process_output(&mut head);
        assert!(scene.core.retired());
        let mut measured = scene.core.clone();
        measured.measure();
        let (y, force) = scene.core.contact();
        println!("retired hammer: compression {y:.4} m, measured {:.4} m", measured.y_now);
        assert!((y - measured.y_now).abs() < 1e-12 && y < -0.1 && force == 0.0);
        let peak = head.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let worst = crate::scene::frames_against_the_real_time_path(&scene, 4_800);
        println!("peak {peak:.3} N, worst difference {worst:.2e} N");
        assert!(worst < 1e-9 * peak, "{worst:e} of {peak}");
    }

    /// A scene made on a trichord that rings (struck, 0.1 s on the soundboard, struck again)
    /// opens its books on the whole energy, the bridge's and the coupling's terms with it: its
    /// balance holds from the first frame, to 1e-9 of the peak energy over 0.1 s.
    #[test]
    fn a_scene_made_on_a_ringing_unison_balances_from_its_first_frame() {
        let board = BridgeParams::soundboard(SOUNDBOARD_CONDUCTANCE);
        let y_ref = law(3).compression_at_energy(2.0 * 0.5 * 3.0 * 2.97e-3 * 3.5 * 3.5);
        let solver = || QsaSolver::new(QuadSpline::new(law(3), y_ref, 6).unwrap());
        let mut first = HammerUnison::new(c4_unison(3, [-1.0, 0.2, 0.8], &board), solver());
        first.process(&mut vec![Frame::default(); 4_800]);
        let mut core = first.core;
        let c4 = chaigne_askenfelt_c4();
        core.strike(&HammerParams {
            mass: 3.0 * c4.hammer_mass,
            velocity: 3.5,
            position: c4.strike_position,
            gap: 0.0,
        });
        let mut scene = HammerUnison::new(core, solver());
        let mut frames = vec![Frame::default(); 4_800];
        scene.process(&mut frames);
        let start = scene.initial_energy();
        let peak = frames.iter().map(|f| f.energy).fold(start, f64::max);
        let drift = frames.iter().map(|f| (f.balance() - start).abs()).fold(0.0, f64::max) / peak;
        println!("drift {drift:.2e} of the peak energy");
        assert!(drift < 1e-9, "{drift:e}");
    }

    /// With a bridge that does not move (one mode of 10¹² kg) and three identical strings, the
    /// unison is the single string of the other scenes struck by a third of the hammer: the
    /// output (mean bridge force per string) equals the single string's bridge force to 1e-9 of
    /// its peak over a strike and 2,000 steps after it.
    #[test]
    fn a_unison_of_identical_strings_on_a_still_bridge_is_one_string() {
        let rigid = BridgeParams { modes: vec![BridgeMode { frequency: 50.0, mass: 1e12, loss_factor: 0.0 }] };
        let y_ref = law(1).compression_at_energy(0.5 * 2.97e-3 * 3.5 * 3.5);
        let mut unison = HammerUnison::new(
            c4_unison(3, [0.0; 3], &rigid),
            QsaSolver::new(QuadSpline::new(law(3), y_ref, 6).unwrap()),
        );
        let b = single_c4(1.0, y_ref);
        let mut a = vec![0.0; b.len()];
        unison.process_output(&mut a);
        let peak = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let worst = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
        println!("peak {peak:.3} N, worst difference {worst:.2e} N");
        assert!(peak > 1.0 && worst < 1e-9 * peak, "{worst:e} of {peak}");
    }

    /// The una corda on a still bridge: a hammer meeting two of three identical strings, its
    /// mass three strings' shares and its felt two shares as stiff, is for each of the two one
    /// string struck by a hammer of 1.5 shares (the force shared between them), and the string it
    /// misses stays at rest. The unison's output (the mean bridge force over its three strings)
    /// is then 2/3 of that one string's: measured over 50 ms, to 1e-9 of the peak.
    #[test]
    fn a_hammer_shifted_off_one_string_strikes_the_others_as_one_and_leaves_it_at_rest() {
        let rigid = BridgeParams { modes: vec![BridgeMode { frequency: 50.0, mass: 1e12, loss_factor: 0.0 }] };
        let c4 = chaigne_askenfelt_c4();
        let y_ref = law(1).compression_at_energy(0.5 * 1.5 * 2.97e-3 * 3.5 * 3.5);
        let mut core = UnisonCore::new(200, &rigid, FS).unwrap();
        let params = UnisonParams { string: c4.string, strings: 3, detune: [0.0; 3] };
        core.retune(&params, f64::INFINITY, c4.strike_position).unwrap();
        core.set_struck(2);
        assert_eq!(core.struck(), 2);
        let hammer =
            HammerParams { mass: 3.0 * c4.hammer_mass, velocity: 3.5, position: c4.strike_position, gap: 2e-4 };
        core.strike(&hammer);
        let mut unison = HammerUnison::new(core, QsaSolver::new(QuadSpline::new(law(2), y_ref, 6).unwrap()));
        let b = single_c4(1.5, y_ref);
        let mut a = vec![0.0; b.len()];
        unison.process_output(&mut a);
        let peak = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let worst = a.iter().zip(&b).map(|(x, y)| (x - 2.0 / 3.0 * y).abs()).fold(0.0, f64::max);
        println!("peak {peak:.3} N, worst difference {worst:.2e} N");
        assert!(peak > 1.0 && worst < 1e-9 * peak, "{worst:e} of {peak}");
    }

    /// A unison brought to rest, or retuned, in the middle of a contact reports no contact
    /// force (what a monitor draws): the force is the latest step's, and no step has come since.
    #[test]
    fn a_unison_brought_to_rest_in_contact_reports_no_force() {
        let board = BridgeParams::soundboard(SOUNDBOARD_CONDUCTANCE);
        let y_ref = law(3).compression_at_energy(0.5 * 3.0 * 2.97e-3 * 3.5 * 3.5);
        let c4 = chaigne_askenfelt_c4();
        let params = UnisonParams { string: c4.string, strings: 3, detune: [-1.0, 0.2, 0.8] };
        for retune in [false, true] {
            let mut core = c4_unison(3, params.detune, &board);
            let mut solver = QsaSolver::new(QuadSpline::new(law(3), y_ref, 6).unwrap());
            core.process_output(&mut solver, &mut [0.0; 48]);
            assert!(core.contact().1.abs() > 1.0, "in contact after 1 ms: {:?}", core.contact());
            if retune {
                core.retune(&params, f64::INFINITY, c4.strike_position).unwrap();
            } else {
                core.reset();
            }
            assert_eq!(core.contact().1, 0.0, "retuned {retune}");
        }
    }

    /// A trichord struck on two strings (the una corda), then struck again on all three while
    /// it rings and again on two, 0.25 s apart, with each solver: from the first step after each
    /// strike on, `H + losses` stays at its value to 1e-9 of the peak energy, as without the
    /// shift.
    #[test]
    fn a_shifted_hammer_keeps_the_energy_balance_through_strikes_on_two_and_three_strings() {
        fn drift<S: ContactSolver>(solver: impl Fn(usize, f64) -> S) -> f64 {
            let board = BridgeParams::soundboard(SOUNDBOARD_CONDUCTANCE);
            let c4 = chaigne_askenfelt_c4();
            let params = UnisonParams { string: c4.string, strings: 3, detune: [-1.0, 0.2, 0.8] };
            let mut core = UnisonCore::new(200, &board, FS).unwrap();
            core.retune(&params, f64::INFINITY, c4.strike_position).unwrap();
            let (mut worst, mut peak) = (0.0f64, 0.0f64);
            for (struck, velocity) in [(2, 3.5), (3, 2.0), (2, 3.0)] {
                core.set_struck(struck);
                assert_eq!(core.struck(), struck);
                let mass = 3.0 * c4.hammer_mass;
                core.strike(&HammerParams { mass, velocity, position: c4.strike_position, gap: 2e-4 });
                let reference = 0.5 * mass * velocity * velocity + core.own_energy();
                let mut scene = HammerUnison::new(core, solver(struck, reference));
                let mut frames = vec![Frame::default(); 12_000];
                scene.process(&mut frames);
                let start = frames[0].balance();
                peak = frames.iter().map(|f| f.energy).fold(peak.max(scene.initial_energy()), f64::max);
                worst = frames.iter().map(|f| (f.balance() - start).abs()).fold(worst, f64::max);
                core = scene.core;
            }
            worst / peak
        }
        let qsa = |struck: usize, energy: f64| {
            let y_ref = law(struck).compression_at_energy(energy);
            QsaSolver::new(QuadSpline::new(law(struck), y_ref, 6).unwrap())
        };
        for (name, drift) in [
            ("qsa", drift(qsa)),
            ("imp", drift(|struck, _| NewtonSolver::new(law(struck)))),
            ("exp", drift(|struck, _| ExplicitSolver::new(law(struck)))),
        ] {
            println!("{name}: drift {drift:.2e} of the peak energy");
            assert!(drift < 1e-9, "{name}: {drift:e}");
        }
    }
}
