//! Modal string, hammer–string and slide–string physics. Reference numbers and their sources
//! are in docs/physics.md (cited as "docs/physics.md §x").

use qsa_dsp::body::BodyParams;
use qsa_dsp::contact::{
    ContactSolver, ExplicitSolver, Method, NewtonSolver, PowerLaw, QsaSolver, QuadSpline, SolverSettings,
};
use qsa_dsp::control::Fixed;
use qsa_dsp::exciter::HammerParams;
use qsa_dsp::preset::{chaigne_askenfelt_c4, slide_guitar};
use qsa_dsp::scene::{
    Frame, HammerString, HammerStringParams, OutputKind, Pickup, Scene, SlideControls, SlideString, SlideStringParams,
};
use qsa_dsp::scene_file::{SceneDescription, parse_scene, render, render_output};
use qsa_dsp::string::{Damping, ModalString};
use qsa_tests::fundamental;

const FS: f64 = 44100.0;

fn scene_file(name: &str) -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/").to_owned() + name;
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The Fig. 5 set-up of docs/physics.md §9.4: C4 string (η0 = b1, η2 = b3·T/ρA), hammer 2.97 g at 0.12 L,
/// gap 0.2 mm.
fn fig5(velocity: f64) -> HammerStringParams {
    let c4 = chaigne_askenfelt_c4();
    HammerStringParams {
        string: c4.string,
        hammer: HammerParams {
            mass: c4.hammer_mass,
            velocity,
            position: c4.strike_position,
            gap: HammerParams::DEFAULT_GAP,
        },
        pickup: Pickup::point(OutputKind::Displacement, 0.3),
    }
}

fn fig5_law() -> PowerLaw {
    PowerLaw::new(4.5e9, 2.5).unwrap()
}

fn run_hammer<S: ContactSolver>(params: &HammerStringParams, fs: f64, solver: S, samples: usize) -> (Vec<Frame>, f64) {
    let string = ModalString::new(params.string, fs).unwrap();
    let mut scene = HammerString::new(string, params, solver);
    let mut frames = vec![Frame::default(); samples];
    let e0 = scene.initial_energy();
    scene.process(&mut frames);
    (frames, e0)
}

fn qsa(law: PowerLaw, v_ref: f64, n: usize) -> QsaSolver {
    QsaSolver::new(QuadSpline::from_reference_energy(law, v_ref, n).unwrap())
}

/// log10 of the normalised L2 difference of two force signals.
fn force_error(a: &[Frame], reference: &[Frame]) -> f64 {
    let num: f64 = a.iter().zip(reference).map(|(x, r)| (x.force - r.force).powi(2)).sum();
    let den: f64 = reference.iter().map(|r| r.force.powi(2)).sum();
    0.5 * (num / den).log10()
}

/// Largest per-step violation of `H^{n+1/2} + L^{n+1/2} = H^{n−1/2} + L^{n−1/2}`, relative to
/// `H^{n+1/2}`.
fn worst_step_balance(frames: &[Frame], e0: f64) -> f64 {
    let mut prev = e0;
    let mut worst = 0.0_f64;
    for f in frames {
        let now = f.balance();
        worst = worst.max((now - prev).abs() / f.energy);
        prev = now;
    }
    worst
}

/// Free vibration of single modes follows `e^{−σt} cos(ωt)` with the damped ω exactly (physics
/// §9.3: the scheme is exact per mode; measured 5e-13 after 44 100 steps). Tolerance 1e-10.
#[test]
fn one_mode_rings_and_decays_exactly() {
    let string = ModalString::new(chaigne_askenfelt_c4().string, FS).unwrap();
    let m = string.modes();
    let dt = 1.0 / FS;
    for mode in [0, 9, m - 1] {
        let mut s = string.clone();
        let sigma = s.decay_rates()[mode];
        let omega0 = s.angular_frequencies()[mode];
        let omega = (omega0 * omega0 - sigma * sigma).sqrt();
        let exact = |n: f64| (-sigma * n * dt).exp() * (omega * n * dt).cos();
        let (mut prev, mut now) = (vec![0.0; m], vec![0.0; m]);
        prev[mode] = exact(-1.0);
        now[mode] = exact(0.0);
        s.set_state(&prev, &now);
        let mut worst = 0.0_f64;
        let silent = s.vector();
        for n in 1..=44_100 {
            s.history::<0>([]);
            s.advance::<0>([], &silent);
            worst = worst.max((s.state()[mode] - exact(n as f64)).abs());
        }
        assert!(worst < 1e-10, "mode {}: max error {worst:e}", mode + 1);
    }
}

/// Lossless partials are `f_i = i f0 √(1 + B i²)` (docs/physics.md §6.1, §9.3): measured from the
/// simulated free vibration of every mode of the lossless C4 string via
/// `cos(ωΔt) = (u^{n+1} + u^{n−1})/(2u^n)`, to 1e-9 relative.
#[test]
fn lossless_partials_follow_the_stiff_string_formula() {
    let mut params = chaigne_askenfelt_c4().string;
    params.damping = Damping::LOSSLESS;
    let string = ModalString::new(params, FS).unwrap();
    let m = string.modes();
    let dt = 1.0 / FS;
    let mut s = string.clone();
    let omega: Vec<f64> = s.angular_frequencies().to_vec();
    let prev: Vec<f64> = omega.iter().map(|w| (w * dt).cos()).collect();
    s.set_state(&prev, &vec![1.0; m]);
    let mut trail = vec![s.previous_state().to_vec(), s.state().to_vec()];
    let silent = s.vector();
    for _ in 0..200 {
        s.history::<0>([]);
        s.advance::<0>([], &silent);
        trail.push(s.state().to_vec());
    }
    for i in 0..m {
        // Median of the per-sample estimates where u^n is not near a zero.
        let mut estimates: Vec<f64> = trail
            .windows(3)
            .filter(|w| w[1][i].abs() > 0.3)
            .map(|w| ((w[0][i] + w[2][i]) / (2.0 * w[1][i])).acos() / (2.0 * std::f64::consts::PI * dt))
            .collect();
        estimates.sort_by(f64::total_cmp);
        let measured = estimates[estimates.len() / 2];
        let expected = params.partial(i + 1);
        assert!((measured / expected - 1.0).abs() < 1e-9, "partial {}: {measured} Hz vs {expected} Hz", i + 1);
    }
    assert!((params.partial(1) - 262.239).abs() < 1e-3, "docs/physics.md §9.3: f1 = 262.239 Hz");
    assert!((params.partial(3) - 787.902).abs() < 1e-3, "docs/physics.md §9.3: f3 = 787.902 Hz");
}

/// Lossless hammer strike: `H^{n+1/2}` is conserved to 1e-12 by QSA and IMP over the whole strike
/// and 0.25 s of ringing (measured 4.3e-14 and 8.8e-14; the prototype 2.5e-14, docs/physics.md
/// §6.3).
#[test]
fn lossless_hammer_strike_conserves_energy() {
    let mut params = fig5(3.5);
    params.string.damping = Damping::LOSSLESS;
    let law = fig5_law();
    let v_ref = params.hammer.kinetic_energy();
    let samples = (0.25 * FS) as usize;
    let drift = |frames: &[Frame], e0: f64| frames.iter().map(|f| (f.energy - e0).abs()).fold(0.0, f64::max) / e0;
    let (frames, e0) = run_hammer(&params, FS, qsa(law, v_ref, 6), samples);
    assert!(frames.iter().all(|f| f.losses == 0.0));
    let d = drift(&frames, e0);
    println!("lossless drift QSA N=6: {d:e}");
    assert!(d <= 1e-12, "QSA drift {d:e}");
    let (frames, e0) = run_hammer(&params, FS, NewtonSolver::new(law), samples);
    let d = drift(&frames, e0);
    println!("lossless drift IMP: {d:e}");
    assert!(d <= 1e-12, "IMP drift {d:e}");
}

/// Damped hammer strike: the energy never rises, and the balance
/// `H^{n+1/2} − H^{n−1/2} = −Δt (δ_t·ũ)ᵀR̂(δ_t·ũ)` closes to 1e-12 relative at every step, for
/// all three solvers.
#[test]
fn damped_hammer_strike_balances_every_step() {
    let params = fig5(3.5);
    let law = fig5_law();
    let samples = (0.5 * FS) as usize;
    let runs = [
        ("qsa", run_hammer(&params, FS, qsa(law, params.hammer.kinetic_energy(), 6), samples)),
        ("imp", run_hammer(&params, FS, NewtonSolver::new(law), samples)),
        ("exp", run_hammer(&params, FS, ExplicitSolver::new(law), samples)),
    ];
    for (name, (frames, e0)) in runs {
        let mut prev = e0;
        for (n, f) in frames.iter().enumerate() {
            assert!(f.energy <= prev, "{name}: energy rose at step {n}: {prev:e} -> {:e}", f.energy);
            prev = f.energy;
        }
        let worst = worst_step_balance(&frames, e0);
        println!("{name}: worst per-step balance {worst:e}");
        assert!(worst <= 1e-12, "{name}: balance violated by {worst:e}");
    }
}

/// Fig. 5 (docs/physics.md §9.4): IMP peak force 17.98 N (3 %) in one contact of 87 samples = 1.97 ms
/// (5 %); QSA against IMP, log10 normalised force difference ≤ −1.0 at N = 3, ≤ −1.4 at N = 6,
/// ≤ −3.5 at N = 50 (measured there: −1.18, −1.62, −4.01).
#[test]
fn fig5_reproduces_the_reference_strike() {
    let params = fig5(3.5);
    let law = fig5_law();
    let samples = (0.1 * FS) as usize;
    let (imp, _) = run_hammer(&params, FS, NewtonSolver::new(law), samples);
    let peak = imp.iter().map(|f| -f.force).fold(0.0, f64::max);
    let in_contact: Vec<usize> = (0..imp.len()).filter(|&n| imp[n].force != 0.0).collect();
    let contiguous = in_contact.windows(2).all(|w| w[1] == w[0] + 1);
    let duration = in_contact.len() as f64 / FS;
    println!("IMP: peak {peak} N, {} contact samples ({duration} s)", in_contact.len());
    assert!((peak / 17.98 - 1.0).abs() < 0.03, "peak force {peak} N");
    assert!(contiguous, "one contact expected");
    assert!((duration / 1.97e-3 - 1.0).abs() < 0.05, "contact duration {duration} s");
    for (n, bound) in [(3, -1.0), (6, -1.4), (50, -3.5)] {
        let (frames, _) = run_hammer(&params, FS, qsa(law, params.hammer.kinetic_energy(), n), samples);
        let e = force_error(&frames, &imp);
        println!("QSA N = {n}: dF = {e:.3}");
        assert!(e <= bound, "N = {n}: dF = {e} > {bound}");
    }
}

/// The Fig. 5 strike at 44.1, 48 and 96 kHz: the same fundamental (0.1 %), measured from the
/// renders, and the same peak force within 2 % at 48 kHz.
///
/// At 96 kHz the peak force is 2.16 % below 44.1 kHz (IMP: 2.06 %), outside a 2 % band. This is
/// the scheme, not the solver: the exact-frequency modes have `K̂ = m̃(2/Δt)² tan²(ωΔt/2) ≥ m̃ω²`
/// (docs/physics.md §6.2), so the discrete string is slightly stiffer at the strike point, more so
/// at low rates; the peak converges at second order (the 44.1→96 kHz change is 3.5 times the
/// 96→192 kHz change, against 5 for a pure Δt² law) and the same 56 modes at 96 kHz still give
/// −1.9 %. So 96 kHz is checked for that convergence: its
/// peak lies between the 44.1 kHz and 192 kHz peaks, at least three times closer to 192 kHz.
#[test]
fn fig5_is_consistent_across_sample_rates() {
    let params = fig5(3.5);
    let law = fig5_law();
    let mut results = Vec::new();
    for fs in [44100.0, 48000.0, 96000.0, 192000.0] {
        let (frames, _) = run_hammer(&params, fs, qsa(law, params.hammer.kinetic_energy(), 6), (0.6 * fs) as usize);
        let out: Vec<f64> = frames[(0.1 * fs) as usize..].iter().map(|f| f.output).collect();
        let f0 = fundamental(&out, fs, 150.0, 400.0);
        let peak = frames.iter().map(|f| -f.force).fold(0.0, f64::max);
        println!("fs {fs}: f0 {f0:.4} Hz, peak {peak:.4} N");
        results.push((f0, peak));
    }
    let [(f44, p44), (f48, p48), (f96, p96), (_, p192)] = results[..] else { unreachable!() };
    assert!((f44 / params.string.partial(1) - 1.0).abs() < 1e-3, "f0 {f44} vs partial 1");
    for f0 in [f48, f96] {
        assert!((f0 / f44 - 1.0).abs() < 1e-3, "fundamental {f0} vs {f44}");
    }
    assert!((p48 / p44 - 1.0).abs() < 0.02, "peak force at 48 kHz {p48} vs {p44}");
    assert!(p44 > p96 && p96 > p192, "peak force converges monotonically: {p44} {p96} {p192}");
    assert!(p44 - p96 > 3.0 * (p96 - p192), "second-order convergence: {p44} {p96} {p192}");
}

/// A band-limited string keeps the same modes at every sample rate.
#[test]
fn band_limited_string_has_the_same_modes_at_every_rate() {
    let params = chaigne_askenfelt_c4().string;
    let counts: Vec<usize> = [44100.0, 96000.0, 192000.0]
        .iter()
        .map(|&fs| ModalString::band_limited(params, fs, 20_000.0).unwrap().modes())
        .collect();
    let expected = (1..).take_while(|&i| params.partial(i) < 20_000.0).count();
    assert_eq!(counts, vec![expected; 3]);
}

fn slide_params(block: usize) -> SlideStringParams {
    xtask::report::gestures::preset_params(block)
}

/// Slide–string with fixed positions and constant controls (slide pressed, both fingers pressing
/// and damping, lossy string): the per-step balance `ΔH = −Δt(Q_str + Q_o + ΣQ_φ) + Δt(P_H + ΣP_φ)`
/// closes to 1e-12 relative (measured 9.4e-15; the prototype 5.6e-14, docs/physics.md §7.4), for
/// all three solvers, and the contact comes and goes (rattle); and so it does with the string's end
/// on the acoustic guitar's body (docs/physics.md §13.5), the body's energy and the coupling's
/// terms counted (measured 9.4e-15).
#[test]
fn slide_balance_closes_with_fixed_controls() {
    let params = slide_params(64);
    let g = slide_guitar();
    let law = PowerLaw::new(g.kappa, g.alpha).unwrap();
    let controls = SlideControls {
        slide_position: 0.2,
        hand_height: 5e-5,
        left_position: 0.18,
        left_force: 0.5,
        right_position: 0.6,
        right_force: 2.0,
    };
    fn run<S: ContactSolver>(
        params: &SlideStringParams,
        solver: S,
        controls: SlideControls,
        body: Option<&BodyParams>,
    ) -> (Vec<Frame>, f64) {
        let string = ModalString::new(params.string, FS).unwrap();
        let scene = SlideString::new(string, params, solver, Fixed(controls));
        let mut scene = match body {
            Some(body) => scene.with_body(body),
            None => scene,
        };
        let mut frames = vec![Frame::default(); 20_000];
        let e0 = scene.initial_energy();
        scene.process(&mut frames);
        (frames, e0)
    }
    let guitar = BodyParams::guitar();
    for body in [None, Some(&guitar)] {
        let runs = [
            ("qsa", run(&params, qsa(law, 1e-3, 5), controls, body)),
            ("imp", run(&params, NewtonSolver::new(law), controls, body)),
            ("exp", run(&params, ExplicitSolver::new(law), controls, body)),
        ];
        for (name, (frames, e0)) in runs {
            assert!(frames.iter().any(|f| f.force != 0.0), "{name}: the string must reach the slide");
            let worst = worst_step_balance(&frames, e0);
            println!("{name}, body {}: worst per-step balance {worst:e} (H0 = {e0:e})", body.is_some());
            assert!(worst <= 1e-12, "{name}: balance violated by {worst:e}");
        }
    }
}

/// The shipped slide phrase on the acoustic guitar's body (`[body] kind = "guitar"`, the output
/// table's pickup left out): it renders finite, its energy balance with the body closes to 1e-9
/// (measured 3.5e-11), and what the body radiates is another signal than the pickup's velocity
/// (their normalized outputs differ by more than a tenth of the pickup's level).
#[test]
fn the_slide_phrase_renders_on_the_acoustic_body() {
    let pickup = scene_file("slide-phrase.toml");
    let text =
        pickup.replace("kind = \"velocity\"", "").replace("position = 0.9\n", "") + "\n[body]\nkind = \"guitar\"\n";
    let body = render(&parse_scene(&text).unwrap(), std::iter::empty()).unwrap();
    let plain = render(&parse_scene(&pickup).unwrap(), std::iter::empty()).unwrap();
    let drift = body.measurements.energy_drift_rel;
    println!("energy drift on the body {drift:e}");
    assert!(drift <= 1e-9, "{drift:e}");
    assert!(body.frames.iter().all(|f| f.output.is_finite()));
    // Each output scaled to unit RMS, as the renderer's normalisation would.
    let unit = |r: &qsa_dsp::scene_file::Rendered| {
        let x: Vec<f64> = r.frames.iter().map(|f| f.output).collect();
        let rms = (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt();
        x.into_iter().map(|v| v / rms).collect::<Vec<f64>>()
    };
    let (a, b) = (unit(&body), unit(&plain));
    let difference = (a.iter().zip(&b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt();
    println!("normalized outputs differ by {difference:.2} RMS");
    assert!(difference > 0.1, "{difference}");
}

/// The shipped slide phrase: the slide attaches, rattles and detaches (more than one contact);
/// while attached the fundamental follows the speaking length `L − x_o` within 1 %.
#[test]
fn slide_phrase_attaches_rattles_and_follows_the_speaking_length() {
    let scene = parse_scene(&scene_file("slide-phrase.toml")).unwrap();
    let SceneDescription::SlideString(d) = &scene else { panic!("slide scene expected") };
    let length = d.params.string.length;
    let flexible_f0 = d.params.string.fundamental();
    let out = render(&scene, std::iter::empty()).unwrap();
    println!("{:?}", out.measurements);
    assert!(out.measurements.contacts > 5, "rattle: {} contacts", out.measurements.contacts);
    let fs = f64::from(d.common.sample_rate);
    let signal: Vec<f64> = out.frames.iter().map(|f| f.output).collect();
    // Windows where the slide is attached and still: after the first pluck, after the glissando.
    for (t0, t1) in [(0.45, 0.75), (1.32, 1.5)] {
        let mid = 0.5 * (t0 + t1);
        let x = d.controls.at_time(mid).slide_position;
        let expected = flexible_f0 * length / (length - x);
        let window = &signal[(t0 * fs) as usize..(t1 * fs) as usize];
        let f = fundamental(window, fs, 60.0, 400.0);
        println!("t {t0}-{t1} s: x_o {x:.4} m, f0 {f:.2} Hz, from L - x_o {expected:.2} Hz");
        assert!((f / expected - 1.0).abs() < 0.01, "f0 {f} Hz vs {expected} Hz");
        assert!(
            out.frames[(t0 * fs) as usize..(t1 * fs) as usize].iter().all(|f| f.force < 0.0),
            "attached in {t0}-{t1} s"
        );
    }
    // Lifted at the end: no contact, the open string.
    let tail = &out.frames[(3.5 * fs) as usize..];
    assert!(tail.iter().all(|f| f.force == 0.0));
}

/// Output is bit-identical for calls of 1, 64, 1000 and seeded random samples (fixed N_b), for
/// every solver, on the slide phrase (automated controls) and the Fig. 5 strike.
#[test]
fn renders_are_block_size_invariant() {
    for file in ["slide-phrase.toml", "fig5-hammer-c4.toml"] {
        let base = parse_scene(&scene_file(file)).unwrap();
        for method in [Method::Qsa, Method::Imp, Method::Exp] {
            let mut scene = base.with_solver(SolverSettings { method, segments: 5, v_ref: None });
            if let SceneDescription::SlideString(d) = &mut scene {
                d.common.samples = 30_000;
            } else if let SceneDescription::HammerString(d) = &mut scene {
                d.common.samples = 10_000;
            }
            let whole = render(&scene, std::iter::empty()).unwrap().frames;
            for chunk in [Some(1), Some(64), Some(1000), Some(0)] {
                let frames = render(&scene, xtask::render::chunk_sizes(chunk)).unwrap().frames;
                let same = frames.iter().zip(&whole).all(|(a, b)| {
                    a.output.to_bits() == b.output.to_bits()
                        && a.force.to_bits() == b.force.to_bits()
                        && a.energy.to_bits() == b.energy.to_bits()
                });
                assert!(same && frames.len() == whole.len(), "{file} {method:?}: --chunk {chunk:?} differs");
            }
        }
    }
}

/// The real-time path (`render_output`: output only, no frames, no energy bookkeeping) gives the
/// harness path's output bit for bit over the whole slide phrase (attach, plucks with both
/// fingers, glissando, vibrato, rattle, lift-off) at N_b = 1, 8 and 64, in calls of 64 and 37
/// samples; and with the left finger lifted and put down again where it was (the touching
/// fingers change while no vector moves).
#[test]
fn slide_real_time_path_matches_the_harness() {
    let phrase = scene_file("slide-phrase.toml");
    let left_force = "points = [[0.0, 0.0], [0.2, 0.0], [0.25, 0.3], [2.9, 0.3], [3.0, 0.0]]";
    let retouch = phrase.replace(
        left_force,
        "points = [[0.0, 0.0], [0.2, 0.0], [0.25, 0.3], [2.9, 0.3], [3.0, 0.0], [3.3, 0.0], [3.35, 0.3]]",
    );
    assert_ne!(retouch, phrase, "the edit must apply");
    for (text, block) in [(&phrase, 1), (&phrase, 8), (&phrase, 64), (&retouch, 1), (&retouch, 64)] {
        let mut scene = parse_scene(text).unwrap();
        if let SceneDescription::SlideString(d) = &mut scene {
            d.params.block = block;
        }
        let frames = render(&scene, std::iter::empty()).unwrap().frames;
        for chunk in [64, 37] {
            let out = render_output(&scene, chunk).unwrap();
            assert_eq!(out.len(), frames.len());
            let first = out.iter().zip(&frames).position(|(o, f)| o.to_bits() != f.output.to_bits());
            assert_eq!(first, None, "N_b = {block}, calls of {chunk}: first differing sample");
        }
    }
}

/// Bad input names its key: positions outside (0, L), a pickup position the bridge force would
/// ignore, a negative mass, unknown automation targets, breakpoints not increasing in time or not
/// of two numbers.
#[test]
fn bad_string_scenes_are_errors_naming_the_key() {
    let slide = scene_file("slide-phrase.toml");
    let hammer = scene_file("fig5-hammer-c4.toml");
    let cases = [
        (hammer.replace("position = 0.12", "position = 1.2"), "hammer.position"),
        (hammer.replace("position = 0.12", "position = 0.0"), "hammer.position"),
        (hammer.replace("mass = 2.97e-3", "mass = -2.97e-3"), "hammer.mass"),
        (hammer.replace("preset = \"c4\"", "preset = \"c4\"\ntension = -5.0"), "string.tension"),
        (hammer.replace("preset = \"c4\"", "preset = \"c5\""), "string.preset"),
        // A MIDI key only the piano-note preset reads.
        (hammer.replace("preset = \"c4\"", "preset = \"c4\"\nnote = 64"), "string.note"),
        (slide.replace("preset = \"slide-guitar\"", "preset = \"slide-guitar\"\nnote = 64"), "string.note"),
        (hammer.replace("kind = \"bridge-force\"", "kind = \"bridge-force\"\nposition = 1.5"), "output.position"),
        // A pickup position the bridge force would ignore.
        (hammer.replace("kind = \"bridge-force\"", "kind = \"bridge-force\"\nposition = 0.3"), "output.position"),
        (
            slide.replace("finger.right.position = 0.58", "finger.right.position = 0.7"),
            "controls.finger.right.position",
        ),
        (slide.replace("target = \"hand.height\"", "target = \"hand.heigth\""), "automation[2].target"),
        (slide.replace("[[0.0, 3e-3], [0.15, 3e-3]", "[[0.0, 3e-3], [0.0, 3e-3]"), "automation[2].points"),
        (slide.replace("[[0.0, 3e-3], [0.15, 3e-3]", "[[0.2, 3e-3], [0.15, 3e-3]"), "automation[2].points"),
        // A point of three numbers or of one: not silently cut or padded.
        (slide.replace("[[0.0, 3e-3], [0.15, 3e-3]", "[[0.0, 3e-3, 7.0], [0.15, 3e-3]"), "automation[2].points"),
        (slide.replace("[[0.0, 3e-3], [0.15, 3e-3]", "[[0.0], [0.15, 3e-3]"), "automation[2].points"),
        (slide.replace("block = 64", "block = 0"), "control.block"),
        (
            slide.replace("preset = \"slide-guitar\"", "preset = \"slide-guitar\"\n\n[slide]\nmass = -0.03"),
            "slide.mass",
        ),
        (
            slide.replace("finger.right.position = 0.58", "finger.right.position = 0.58\nslide.position = 0.3"),
            "automation[0].target",
        ),
        // A damping form other than the preset's replaces it whole: both coefficients, or the
        // missing one is named (c4 gives eta0/eta2).
        (hammer.replace("preset = \"c4\"", "preset = \"c4\"\nb1 = 0.5"), "string.b3"),
        (hammer.replace("preset = \"c4\"", "preset = \"c4\"\nb3 = 1e-9"), "string.b1"),
        (format!("{slide}\n[body]\nkind = \"banjo\"\n"), "body.kind"),
        (format!("{slide}\n[body]\nkind = \"guitar\"\n"), "output"),
    ];
    for (text, key) in cases {
        let err = parse_scene(&text).expect_err(key).to_string();
        assert!(err.contains(key), "error for {key} does not name it: {err}");
    }
    // A slide position leaving the string in the automation.
    let bad = slide.replacen(
        "target = \"slide.position\"\npoints = [[0, ",
        "target = \"slide.position\"\npoints = [[0, 0.7], [0.01, ",
        1,
    );
    assert_ne!(bad, slide, "the edit must apply");
    let err = parse_scene(&bad).expect_err("slide outside").to_string();
    assert!(err.contains("automation[0].points") && err.contains("outside"), "{err}");
}

/// A damping form other than the preset's, given whole, replaces the preset's damping; in the
/// preset's own form, a coefficient not given is the preset's.
#[test]
fn a_scene_replaces_or_amends_its_presets_damping() {
    let hammer = scene_file("fig5-hammer-c4.toml");
    let damping = |text: &str| match parse_scene(text).unwrap() {
        SceneDescription::HammerString(d) => d.params.string.damping,
        other => panic!("not a hammer scene: {other:?}"),
    };
    let Damping::Viscous { eta2, .. } = damping(&hammer) else { panic!("c4 gives eta0/eta2") };
    let with = |extra: &str| hammer.replace("preset = \"c4\"", &format!("preset = \"c4\"\n{extra}"));
    assert_eq!(damping(&with("b1 = 0.5\nb3 = 1e-9")), Damping::PerMode { b1: 0.5, b3: 1e-9 });
    assert_eq!(damping(&with("eta0 = 0.7")), Damping::Viscous { eta0: 0.7, eta2 });
}

/// A slide scene whose every control is automated needs no `[controls]` table.
#[test]
fn a_slide_scene_with_every_control_automated_needs_no_controls_table() {
    let phrase = scene_file("slide-phrase.toml");
    let start = phrase.find("[controls]").expect("a [controls] table");
    let end = start + phrase[start..].find("\n\n").expect("a blank line after it");
    let constants: Vec<&str> = phrase[start..end].lines().skip(1).collect();
    let mut text = format!("{}{}", &phrase[..start], &phrase[end..]);
    for line in &constants {
        let (target, value) = line.split_once('=').expect("key = value");
        let value = value.split('#').next().expect("a value");
        let (target, value) = (target.trim(), value.trim());
        text.push_str(&format!("\n[[automation]]\ntarget = \"{target}\"\npoints = [[0.0, {value}]]\n"));
    }
    assert!(!constants.is_empty() && !text.contains("[controls]"), "the edit must apply");
    let automated = render(&parse_scene(&text).unwrap(), std::iter::empty()).unwrap().frames;
    let constant = render(&parse_scene(&phrase).unwrap(), std::iter::empty()).unwrap().frames;
    assert_eq!(automated.len(), constant.len());
    let first = automated.iter().zip(&constant).position(|(a, c)| a.output.to_bits() != c.output.to_bits());
    assert_eq!(first, None, "first sample where the automated constants differ");
}

/// The real-time path retires the hammer once the string's energy can no longer reach it
/// (`scene::hammer_string` module docs) and then steps the string alone: its output must equal
/// the harness path's, which never retires, for every solver and output kind, up to rounding.
/// The two paths compute the same free recursion in two forms that differ by a few ulps per mode
/// and step (`string::kernel::free_run`; `u = 2⁻⁵³`, the unit roundoff, half of `f64::EPSILON`);
/// in a stable, lightly damped recursion such errors add up
/// at most linearly, so after the N = 8,820 steps of the run they stay below `N·12u ≈ 1.2e-11` of
/// the state's scale, and the velocity's difference quotient multiplies that by at most
/// `2fs/ω_1 ≈ 54`. The bound is 1e-9 of the output's peak; a wrong free step misses it by orders
/// of magnitude.
#[test]
fn retired_hammer_leaves_the_output_unchanged() {
    let law = fig5_law();
    for kind in [OutputKind::Displacement, OutputKind::Velocity, OutputKind::BridgeForce] {
        let mut params = fig5(3.5);
        params.pickup.kind = kind;
        check_retired_output("qsa", &params, || qsa(law, 3.5, 6));
        check_retired_output("imp", &params, || NewtonSolver::new(law));
        check_retired_output("exp", &params, || ExplicitSolver::new(law));
    }
}

/// Render 0.2 s of `params` through the real-time path in uneven calls (retirement is checked on
/// a fixed sample grid, not per call) and through the harness path, with solvers from `solver`:
/// the hammer must retire and the outputs must agree to 1e-9 of their peak, sample for sample.
fn check_retired_output<S: ContactSolver>(name: &str, params: &HammerStringParams, solver: impl Fn() -> S) {
    let samples = 8820;
    let (frames, _) = run_hammer(params, FS, solver(), samples);
    let mut scene = HammerString::new(ModalString::new(params.string, FS).unwrap(), params, solver());
    let mut out = vec![0.0; samples];
    for chunk in out.chunks_mut(37) {
        scene.process_output(chunk);
    }
    let kind = params.pickup.kind;
    assert!(scene.retired(), "{name} {kind:?}: the hammer was never retired");
    let peak = frames.iter().map(|f| f.output.abs()).fold(0.0, f64::max);
    let worst = out.iter().zip(&frames).map(|(o, f)| (o - f.output).abs()).fold(0.0, f64::max);
    assert!(worst <= 1e-9 * peak, "{name} {kind:?}: outputs differ by {:.2e} of the peak", worst / peak);
}
