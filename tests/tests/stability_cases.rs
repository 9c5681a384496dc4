//! Cases from the report's stability sweep (`cargo xtask report`, `docs/report/stability.md`) that
//! exercise a guard in the engine, kept as regression tests.
//!
//! **EXP on a rattling slide.** In the report's slide excerpt (a slide pressed onto a plucked
//! string, contact coming and going every few samples) a step that drains the auxiliary variable
//! with `g = g_max` can leave a rounding residue ψ ≈ 1e-18 √J. When the next step is out of contact
//! (`y^n ≤ 0`) with the bodies approaching (`z < 0`), the branch chooses `g = g_max` again, and the
//! naive `g_max = 4ψ/(z + √(z² + 4qψ²))` divides by `z + |z| = 0` (4qψ² is far below the rounding
//! of z²): `g = ∞` and `s = ∞/∞ = NaN`. The guard (`dsp/src/contact/explicit.rs`): `g_max` in the
//! cancellation-free form for each sign of z, and a step with `g = g_max` ends with ψ exactly 0 and
//! `s = −2ψ/g_max` evaluated without forming `g_max`. Out of contact, ψ is drained only while the
//! bodies move apart: draining a residue while they approach would stop them dead.

use std::path::Path;

use qsa_dsp::contact::{ContactProblem, ContactSolver, ExplicitSolver, Method, PowerLaw, SolverSettings};
use xtask::report::cases::cases;

/// The slide contact of the `slide-guitar` preset: κ = 1e9 N/m^1.5, α = 1.5.
fn slide_law() -> PowerLaw {
    PowerLaw::new(1e9, 1.5).expect("a valid law")
}

/// The step that produced NaN, with its values from the failing render (n = 1797 of the excerpt at
/// 44.1 kHz): out of contact, approaching, and ψ a rounding residue. ψ is set through `start`, which
/// puts ψ = √(2V((y^{−1} + y^0)/2)): a mean compression of 1.06e-18 m gives ψ ≈ 1e-18 √J.
#[test]
fn exp_step_out_of_contact_with_a_tiny_psi_is_finite() {
    let law = slide_law();
    let mut exp = ExplicitSolver::new(law);
    exp.start(2.12e-18, 0.0);
    let psi = exp.psi();
    assert!(psi > 0.0 && psi < 1e-17, "ψ = {psi:e}");
    let (z, q) = (-1.5668543570102507e-5, 1.5257989860832829e-5);
    // The naive form of g_max divides by zero here: 4ψ/(z + √(z² + 4qψ²)) is 4ψ/0.
    assert_eq!(z + (z * z + 4.0 * q * psi * psi).sqrt(), 0.0, "the cancellation this case exercises");
    let problem = ContactProblem { y_prev: 5.809656546435903e-6, y_now: -2.0800705664472905e-6, z, q };
    let solution = exp.solve(&problem);
    println!("s = {:e}, F = {:e}, ψ after = {:e}", solution.s, solution.force, exp.psi());
    assert!(solution.s.is_finite() && solution.force.is_finite(), "s = {}, F = {}", solution.s, solution.force);
    // Approaching out of contact, the residue stays in ψ and the step is free flight: draining it
    // now would take a force of about z/q and stop the bodies dead (a bounce off nothing).
    assert_eq!((solution.s, solution.force, exp.psi()), (-z, 0.0, psi), "free flight, ψ kept");
    // Moving apart, the residue is handed back: ψ ends exactly 0, and the bodies gain F·s/2 (for the
    // mass–barrier, ½m((δ^{n+1})² − (δ^n)²)/Δt² = F·s/2) out of ½ψ² (≈ 5e-37 J), so |F·s| ≤ ψ² up to
    // rounding.
    let apart = ContactProblem { y_prev: -2.0800705664472905e-6, y_now: -1.0e-5, z: -z, q };
    let solution = exp.solve(&apart);
    assert!(solution.s.is_finite() && solution.force.is_finite());
    assert_eq!(exp.psi(), 0.0, "the drain ends with ψ exactly 0");
    let work = solution.force * solution.s;
    println!("F·s = {work:e}, ψ² = {:e}", psi * psi);
    assert!(work.abs() <= psi * psi * (1.0 + 1e-9), "work {work:e} > ψ² = {:e}", psi * psi);
}

/// A drain step (`g = g_max`, the bodies separating faster than ψ can push) leaves no residue in ψ,
/// so the next step out of contact is plain free flight.
#[test]
fn exp_drain_leaves_psi_exactly_zero_then_free_flight() {
    let law = slide_law();
    let mut exp = ExplicitSolver::new(law);
    exp.start(2e-6, 2e-6);
    assert!(exp.psi() > 0.0);
    // Barely in contact and separating fast: dψ/dy(1e-9) ≈ 199 exceeds g_max ≈ 2ψ/z ≈ 4.
    let drain = ContactProblem { y_prev: 2e-6, y_now: 1e-9, z: 1e-3, q: 1.5e-5 };
    let s = exp.solve(&drain);
    assert!(s.s.is_finite() && s.force <= 0.0, "{s:?}");
    assert_eq!(exp.psi(), 0.0, "ψ after the drain");
    // Out of contact and approaching again: free flight, no force.
    let approach = ContactProblem { y_prev: 2e-6 + s.s, y_now: -1e-6, z: -1e-5, q: 1.5e-5 };
    let free = exp.solve(&approach);
    assert_eq!((free.s, free.force), (1e-5, 0.0));
}

/// The render that failed: the report's slide excerpt with EXP, at every oversampling of the error
/// sweep. Every frame must be finite.
#[test]
fn exp_renders_the_slide_excerpt_without_nan() {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let all = cases(&scenes).expect("the report's cases build from the shipped scenes");
    let slide = all.iter().find(|c| c.name == "slide-excerpt").expect("the slide excerpt");
    for k in [1, 2, 4, 8] {
        let frames = slide.scene.frames(SolverSettings { method: Method::Exp, segments: 1, v_ref: None }, k);
        let bad = frames.iter().position(|f| {
            ![f.output, f.displacement, f.velocity, f.compression, f.force, f.energy, f.losses, f.control_work]
                .iter()
                .all(|v| v.is_finite())
        });
        let contact = frames.iter().filter(|f| f.force != 0.0).count();
        println!("{k}x: {} samples, {contact} in contact", frames.len());
        assert_eq!(bad, None, "{k}x: first non-finite frame");
        assert!(contact > frames.len() / 2, "{k}x: the slide should press on the string most of the time");
    }
}
