//! Modal stiff string with damping (seed §5.1–5.2, docs/physics.md §6).
//!
//! # Model (seed eq. 27, with the seed's `ρA ∂x²u` misprint read as `ρA ∂t²u`)
//!
//! ```text
//! ρA u_tt = T u_xx − EI u_xxxx + 2ρA(η2 ∂x² − η0) u_t + Σ forces
//! ```
//!
//! simply supported at `x = 0` and `x = L`. Modes `v_i(x) = sin(β_i x)`, `β_i = iπ/L`, modal
//! mass `m̃ = ρAL/2`, `ω0_i² = (Tβ_i² + EIβ_i⁴)/ρA`, decay rate `σ_i` (1/s) from a [`Damping`]
//! law, damped frequency `ω_i = √(ω0_i² − σ_i²)`. Lossless partials: `f_i = i f0 √(1 + B i²)`
//! with `f0 = √(T/ρA)/(2L)` and `B = π² EI/(T L²)`.
//!
//! # Exact-per-mode scheme (seed eq. 37–40, docs/physics.md §6.2)
//!
//! `m̃ δ_tt ũ + R̂ δ_t· ũ + K̂ μ_t² ũ = Σ F h` with `K̂`, `R̂` chosen so the homogeneous recursion
//! of each mode is `ũ^{n+1} = 2P ũ^n − Q ũ^{n−1}`, `P = e^{−σΔt} cos(ωΔt)` (overdamped:
//! `cosh(γΔt)`, `γ = √(σ² − ω0²)`), `Q = e^{−2σΔt}`: every mode rings at exactly `ω_i` and
//! decays at exactly `σ_i`, at any sample rate. Per mode:
//!
//! ```text
//! K̂ = (4m̃/Δt²)(1 − 2P + Q)/(1 + 2P + Q),   R̂ = (4m̃/Δt)(1 − Q)/(1 + 2P + Q)
//! ũ^{n+1} = ũ^{n−1} − z̃ + C·h·F,   z̃ = B ũ^{n−1} − A ũ^n
//! A = 2P,   B = 1 + Q,   C = Δt²(1 + 2P + Q)/(4m̃)
//! ```
//!
//! `K̂` diverges for an undamped mode at Nyquist, so the string keeps the modes with
//! `ω_i < π·fs` (strict) whose `1 + 2P + Q`, which `C` is proportional to, is at least `10⁻⁶`
//! (rounded, it would reach 0 within about `3e-9` of Nyquist); counting stops at the first
//! failure (an overdamped mode, which does not ring, is kept while `ω0_i < π·fs`).
//!
//! # Energy (docs/physics.md §6.3)
//!
//! ```text
//! H^{n+1/2} = ½ m̃ ‖(ũ^{n+1} − ũ^n)/Δt‖² + ½ Σ K̂_i ((ũ_i^{n+1} + ũ_i^n)/2)²
//! H^{n+1/2} − H^{n−1/2} = −Δt (δ_t·ũ)ᵀ R̂ (δ_t·ũ) + (work of the forces)
//! ```
//!
//! # Layout
//!
//! Structure of arrays: every per-mode coefficient is a contiguous `Vec<f64>`, padded with inert
//! zero modes to a whole number of SIMD chunks ([`ModalString::padded_len`]; vectors handed to
//! the string come from [`ModalString::vector`]), and a step is two branch-free passes over the
//! modes (see `kernel`). [`ModalString::history`] projects `z̃` on the contact vectors;
//! [`ModalString::advance`] applies the forces, moves the state on, projects the new state on the
//! output vector and computes the next step's `z̃`, all in one pass. So the first pass of a step
//! that follows an `advance` only reads `z̃`; after anything else it computes `z̃` as well.
//!
//! # Files
//!
//! - `params`: [`StringParams`], [`Damping`] and their checks;
//! - `modes`: which modes a string keeps and each mode's coefficients;
//! - `setup`: making and retuning a [`ModalString`], and what it is made of;
//! - `step`: the state and the per-sample update;
//! - `bank`: the modes of several bodies in one set of arrays, stepped together;
//! - `decay`: extra decay rates (dampers, fades);
//! - `energy`: the numerical energy and the losses;
//! - `vectors`: mode shapes, output weights, projections and contact vectors;
//! - `kernel` and `simd`: the loops over the modes, one code for every vector unit.

mod bank;
mod decay;
mod energy;
mod kernel;
mod modes;
mod params;
mod setup;
pub(crate) mod simd;
mod step;
mod vectors;

pub use bank::ModalBank;
pub use energy::StringEnergy;
pub use kernel::{GramVector, Tail};
pub use params::{Damping, StringError, StringParams};
pub use simd::{Isa, LANES};

/// Most modes a string may have (bounds memory and cost for extreme parameters).
pub const MAX_MODES: usize = 4096;

/// Modal amplitudes below this (m) are set to zero (docs/physics.md §10.11): decaying modes would
/// otherwise become subnormal numbers, which are slower by orders of magnitude.
pub const FLUSH_BELOW: f64 = 1e-30;

/// Steps between flushes of tiny amplitudes (counted from the start, so independent of how a
/// render is split into calls).
pub const FLUSH_INTERVAL: u32 = 64;

/// A modal string prepared for one sample rate: coefficients and state.
#[derive(Debug, Clone)]
pub struct ModalString {
    params: StringParams,
    sample_rate: f64,
    /// Modal mass m̃ = ρAL/2 (kg).
    modal_mass: f64,
    /// Wavenumbers β_i = iπ/L (1/m).
    beta: Vec<f64>,
    /// Undamped angular frequencies ω0_i (rad/s).
    omega0: Vec<f64>,
    /// Decay rates σ_i (1/s).
    sigma: Vec<f64>,
    /// The string's own `P_i = e^{−σ_iΔt} cos(ω_iΔt)` and `Q_i = e^{−2σ_iΔt}`, before any extra
    /// decay ([`ModalString::set_extra_decay`]).
    own_p: Vec<f64>,
    own_q: Vec<f64>,
    /// `A_i = 2P_i`.
    coef_a: Vec<f64>,
    /// `B_i = 1 + Q_i`.
    coef_b: Vec<f64>,
    /// `C_i = Δt²(1 + 2P + Q)/(4m̃)` (m/N).
    coef_c: Vec<f64>,
    /// `K̂_i` (N/m).
    stiffness: Vec<f64>,
    /// The string's own `K̂_i` (N/m), before any extra decay.
    own_stiffness: Vec<f64>,
    /// `R̂_i` (kg/s).
    resistance: Vec<f64>,
    /// `ũ^{n−1}` (m).
    u_prev: Vec<f64>,
    /// `ũ^n` (m).
    u_now: Vec<f64>,
    /// `z̃` of the current step (m), from [`ModalString::history`] or left by
    /// [`ModalString::advance`].
    history: Vec<f64>,
    /// Whether `history` holds `z̃ = B ũ^{n−1} − A ũ^n` for the current state. Everything that
    /// changes the state otherwise clears it.
    history_ready: bool,
    /// Steps since the last flush of tiny amplitudes.
    since_flush: u32,
    /// The vector unit the kernels run on.
    isa: Isa,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c4() -> StringParams {
        StringParams {
            length: 0.62,
            tension: 670.0,
            linear_density: 3.93e-3 / 0.62,
            bending_stiffness: 3.82e-5 * 670.0 * 0.62 * 0.62,
            damping: Damping::Viscous { eta0: 0.5, eta2: 6.25e-9 * 670.0 / (3.93e-3 / 0.62) },
        }
    }

    #[test]
    fn mode_count_is_every_mode_below_nyquist() {
        // docs/physics.md §8.2: M = 34 / 56 / 59 / 90 / 132 for the C4 string.
        for (fs, m) in [(22050.0, 34), (44100.0, 56), (48000.0, 59), (96000.0, 90), (192000.0, 132)] {
            assert_eq!(ModalString::new(c4(), fs).unwrap().modes(), m, "fs = {fs}");
        }
    }

    /// A lossless harmonic string whose top mode falls on Nyquist but for rounding (50 Hz at
    /// 44.1 kHz and at 88.2 kHz, 100 Hz at 88.2 kHz): that mode would have `C = 0` and `K̂ = ∞`, so
    /// the string keeps the modes below it, each with a finite, positive `C` and `K̂` and at
    /// least `10⁻⁶` in `1 + 2P + Q`, and its energy at rest is 0 and struck is finite.
    #[test]
    fn a_mode_a_rounding_below_nyquist_is_left_out() {
        for (f0, fs) in [(50.0_f64, 44100.0), (50.0, 88200.0), (100.0, 88200.0)] {
            let (length, linear_density) = (0.65, 0.006);
            let tension = (2.0 * length * f0).powi(2) * linear_density;
            let p =
                StringParams { length, tension, linear_density, bending_stiffness: 0.0, damping: Damping::LOSSLESS };
            let mut s = ModalString::new(p, fs).unwrap();
            assert_eq!(s.modes(), (fs / (2.0 * f0)) as usize - 1, "f0 {f0}, fs {fs}");
            for i in 0..s.modes() {
                let (a, b, c, k) = (s.coef_a[i], s.coef_b[i], s.coef_c[i], s.stiffness()[i]);
                assert!(c > 0.0 && c.is_finite() && k > 0.0 && k.is_finite(), "mode {}: C {c}, K {k}", i + 1);
                assert!(a + b >= 1e-6, "mode {}: 1 + 2P + Q = {}", i + 1, a + b);
            }
            assert_eq!(s.energy(), 0.0);
            let ones = vec![1e-6; s.modes()];
            s.set_state(&vec![0.0; s.modes()], &ones);
            assert!(s.energy().is_finite() && s.energy() > 0.0, "f0 {f0}, fs {fs}: {}", s.energy());
        }
    }

    /// A string set to rest after a step under a force that was not finite sounds nothing: the
    /// NaN the step left in every mode, the padding beyond the modes too (the C4 string keeps 59
    /// modes at 48 kHz, in arrays of 64), is gone, and free steps output zeros.
    #[test]
    fn a_string_set_to_rest_after_a_nan_force_outputs_zero() {
        let mut s = ModalString::new(c4(), 48_000.0).unwrap();
        assert!(s.padded_len() > s.modes(), "the case has padding");
        let (shape, output) = (vec![1.0; s.padded_len()], s.vector());
        let mut gain = s.vector();
        gain.iter_mut().zip(s.input_gains()).for_each(|(g, c)| *g = *c);
        s.history([&shape]);
        s.advance_projecting([(&gain[..], f64::NAN)], &output, [&shape]);
        let rest = vec![0.0; s.modes()];
        s.set_state(&rest, &rest);
        let mut out = vec![1.0; 64];
        let pickup = vec![1.0; s.padded_len()];
        s.free_steps(&pickup, &mut out);
        assert!(out.iter().all(|&x| x == 0.0), "{:?}", &out[..4]);
        assert_eq!(s.energy(), 0.0);
    }

    /// Damping so heavy that `A = 2P` rounds to `B = 1 + Q` (`P → ½`, `Q → 0`) leaves the modes
    /// no stiffness in their recursion: held under a force they stay at 0 rather than at `f/0`.
    #[test]
    fn a_mode_without_stiffness_rests_at_zero_under_a_force() {
        let mut p = c4();
        p.damping = Damping::Viscous { eta0: 1e18, eta2: 0.0 };
        let mut s = ModalString::new(p, 44100.0).unwrap();
        assert!((0..s.modes()).any(|i| s.coef_b[i] == s.coef_a[i]), "the case arises");
        s.rest_under(|_| 1.0);
        for (i, (&now, &before)) in s.state().iter().zip(s.previous_state()).enumerate() {
            let k = s.coef_b[i] - s.coef_a[i];
            let expected = if k > 0.0 { s.coef_c[i] / k } else { 0.0 };
            assert!(now.is_finite() && now == expected && before == now, "mode {}: {now}", i + 1);
        }
    }

    #[test]
    fn mode_shape_recurrence_matches_sine() {
        let s = ModalString::new(c4(), 44100.0).unwrap();
        let mut shapes = vec![0.0; s.modes()];
        let x = 0.12 * 0.62;
        s.mode_shapes(x, &mut shapes);
        for (i, (&got, &beta)) in shapes.iter().zip(s.wavenumbers()).enumerate() {
            assert!((got - (beta * x).sin()).abs() < 1e-12, "mode {}", i + 1);
        }
    }

    /// A decaying string never holds a subnormal amplitude: every [`FLUSH_INTERVAL`] steps the
    /// amplitudes below [`FLUSH_BELOW`] become exact zeros and the others are left alone, so the
    /// string comes to rest. With η0 = 2000/s, 1e-3 m falls below 1e-30 m in about 0.03 s (1,400
    /// steps at 44.1 kHz; without the flush it would still be about 1e-129 m after the 6,400 steps
    /// here), and no amplitude is anywhere near the threshold in the first 500 steps.
    #[test]
    fn tiny_amplitudes_are_flushed_to_zero() {
        let mut p = c4();
        p.damping = Damping::Viscous { eta0: 2000.0, eta2: 0.0 };
        let mut s = ModalString::new(p, 44100.0).unwrap();
        let start: Vec<f64> = (0..s.modes()).map(|i| 1e-3 / (i + 1) as f64).collect();
        s.set_state(&start, &start);
        let pickup = s.vector();
        let mut out = [0.0; 37];
        for call in 0..173 {
            s.free_steps(&pickup, &mut out);
            let steps = (call + 1) * out.len();
            for &u in s.state().iter().chain(s.previous_state()) {
                assert!(!u.is_subnormal(), "step {steps}: subnormal {u:e}");
                assert!(steps > 500 || u != 0.0, "step {steps}: an audible amplitude was flushed");
            }
        }
        assert!(s.state().iter().chain(s.previous_state()).all(|u| *u == 0.0), "the string comes to rest");
    }

    /// The one-pass energy is the per-mode definition (docs/physics.md §6.3) to rounding.
    #[test]
    fn energy_is_the_stored_term_of_every_mode() {
        let mut s = ModalString::new(c4(), 44100.0).unwrap();
        let m = s.modes();
        let prev: Vec<f64> = (0..m).map(|i| 1e-4 * ((i * 7 % 11) as f64 - 5.0) / (i + 1) as f64).collect();
        let now: Vec<f64> = (0..m).map(|i| 1e-4 * ((i * 5 % 13) as f64 - 6.0) / (i + 1) as f64).collect();
        s.set_state(&prev, &now);
        let (fs, mass) = (s.sample_rate(), s.modal_mass());
        let (mut kinetic, mut potential) = (0.0, 0.0);
        for i in 0..m {
            let v = (now[i] - prev[i]) * fs;
            let mean = 0.5 * (now[i] + prev[i]);
            kinetic += 0.5 * mass * v * v;
            potential += 0.5 * s.stiffness()[i] * mean * mean;
        }
        assert!((s.kinetic_energy() / kinetic - 1.0).abs() < 1e-13, "{} vs {kinetic}", s.kinetic_energy());
        assert!((s.energy() / (kinetic + potential) - 1.0).abs() < 1e-13, "{} vs {}", s.energy(), kinetic + potential);
    }

    /// An overdamped mode with a decay rate far beyond the sample rate (σΔt ≈ 2000, where
    /// `e^{−σΔt}` underflows to 0 and `cosh(γΔt)` overflows, and σ = 1e160/s, whose square
    /// overflows) gets finite coefficients, and its recursion `ũ^{n+1} = 2P ũ^n − Q ũ^{n−1}` has
    /// `P` within rounding of the exact `½(e^{(γ−σ)Δt} + e^{(−γ−σ)Δt})`, computed here with the
    /// slowest part alone, its rate `γ − σ = −ω0²/(σ + γ)` by its Taylor series in `(ω0/σ)²`
    /// (its next term is below 1e-16 of the rate for `(ω0/σ)² < 1e-5`, as here).
    #[test]
    fn overdamped_modes_with_huge_damping_stay_finite() {
        for eta0 in [1e8, 1e160] {
            let mut p = c4();
            p.damping = Damping::Viscous { eta0, eta2: 0.0 };
            let mut s = ModalString::new(p, 44100.0).unwrap();
            assert!(s.modes() > 0);
            for i in 0..s.modes() {
                let (a, b, c) = (s.coef_a[i], s.coef_b[i], s.coef_c[i]);
                let (k, r) = (s.stiffness()[i], s.resistance[i]);
                let finite = [a, b, c, k, r].iter().all(|x| x.is_finite());
                assert!(finite, "eta0 {eta0:e}, mode {i}: A {a} B {b} C {c} K {k} R {r}");
                let (sigma, omega0) = (s.decay_rates()[i], s.angular_frequencies()[i]);
                let x = (omega0 / sigma).powi(2);
                assert!(x < 1e-5, "the series needs ω0 ≪ σ");
                let rate = -omega0 * omega0 / (2.0 * sigma) * (1.0 + x / 4.0 + x * x / 8.0);
                let slow = 0.5 * (rate / 44100.0).exp();
                let tolerance = 1e-12 * slow.max(f64::MIN_POSITIVE);
                assert!((0.5 * a - slow).abs() <= tolerance, "eta0 {eta0:e}, mode {i}: P {} vs {slow}", 0.5 * a);
            }
            let ones = vec![1e-3; s.modes()];
            s.set_state(&ones, &ones);
            let pickup = s.vector();
            let mut out = [0.0; 128];
            s.free_steps(&pickup, &mut out);
            let decays = s.state().iter().all(|u| u.is_finite() && u.abs() <= 1e-3);
            assert!(decays && out.iter().all(|y| y.is_finite()), "eta0 {eta0:e}: the state decays and stays finite");
        }
    }

    /// With an extra decay rate the free vibration of a mode is `e^{−(σ+σ_e)t} cos(ωt)` with the
    /// string's own damped `ω` (the exact recursion, to 1e-10 over 4,410 steps as for the plain
    /// string), and a zero extra rate gives back the string's own coefficients bit for bit.
    #[test]
    fn extra_decay_adds_to_each_modes_rate_and_keeps_its_frequency() {
        let mut s = ModalString::new(c4(), 44100.0).unwrap();
        let m = s.modes();
        let own = (s.coef_a.clone(), s.coef_b.clone(), s.coef_c.clone(), s.stiffness.clone());
        let extra: Vec<f64> = (0..m).map(|i| 30.0 + 5.0 * i as f64).collect();
        s.set_extra_decay(&extra);
        let dt = 1.0 / 44100.0;
        for mode in [0, 7, m - 1] {
            let (sigma, omega0) = (s.decay_rates()[mode] + extra[mode], s.angular_frequencies()[mode]);
            let omega = (omega0 * omega0 - s.decay_rates()[mode].powi(2)).sqrt();
            let exact = |n: f64| (-sigma * n * dt).exp() * (omega * n * dt).cos();
            let (mut prev, mut now) = (vec![0.0; m], vec![0.0; m]);
            prev[mode] = exact(-1.0);
            now[mode] = exact(0.0);
            let mut t = s.clone();
            t.set_state(&prev, &now);
            let mut out = vec![0.0; 4410];
            let mut probe = t.vector();
            probe[mode] = 1.0;
            t.free_steps(&probe, &mut out);
            for (n, &y) in out.iter().enumerate() {
                assert!(
                    (y - exact(n as f64 + 1.0)).abs() < 1e-10,
                    "mode {mode}, step {n}: {y} vs {}",
                    exact(n as f64 + 1.0)
                );
            }
        }
        s.set_extra_decay(&[]);
        assert_eq!((s.coef_a.clone(), s.coef_b.clone(), s.coef_c.clone(), s.stiffness.clone()), own);
    }

    #[test]
    fn invalid_parameters_name_their_key() {
        let mut p = c4();
        p.tension = -1.0;
        assert_eq!(ModalString::new(p, 44100.0).unwrap_err().key, "tension");
        let mut p = c4();
        p.damping = Damping::Viscous { eta0: f64::NAN, eta2: 0.0 };
        assert_eq!(ModalString::new(p, 44100.0).unwrap_err().key, "eta0");
    }
}
