//! The cost of one contact-solver step, in contact and in free flight.
//!
//! Solvers: QSA at N = 1, 5, 20, 64 (warm-started segment search, V_ref = ½ m v0², as the scene
//! default), IMP (Newton on the exact law) and EXP (explicit, branched gradient).
//!
//! Inputs are real: each solver runs the seed's Fig. 4 mass–barrier (κ = 1e8 N/m^α, α = 1.3,
//! m = 10 g, v0 = 2 m/s, u0 = −1 mm) at 8 × 44.1 kHz, in [`PHASES`] runs whose initial gap is
//! shifted by a fraction of a sample so the contact is sampled at different phases. Every
//! `ContactProblem` (y_prev, y_now, z, q) the scene hands the solver is recorded with its
//! solution. Each solver is then benchmarked on *its own* recorded sequence:
//!
//! - `contact`: the runs of steps with a non-zero force (about 46 per contact at this rate);
//! - `free_flight`: runs of steps with `y^{n−1}`, `y^n` and the free-flight `y^{n+1}` all below
//!   −0.1 mm (more than the peak compression below the barrier).
//!
//! Each run is replayed as in the trajectory: the solver is reset with `start(y_prev, y_now)` of
//! the step just before the run (a free-flight step, so QSA's warm-start segment and EXP's ψ
//! are what they were there) and fed the run's problems in order. Before timing, a replay is
//! checked to reproduce the recorded solutions bit for bit, so the timed work is exactly the
//! trajectory's work. The reported throughput (elements = steps) gives the time per step; the
//! `start` call per run (one per ~46 contact steps) is included.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use qsa_dsp::contact::{
    ContactProblem, ContactSolution, ContactSolver, ExplicitSolver, Method, NewtonSolver, PowerLaw, QsaSolver,
    QuadSpline,
};
use qsa_dsp::scene::{Frame, MassBarrier, MassBarrierParams, Scene};

/// Sample rate of the recorded trajectories: 8 × 44.1 kHz.
const SAMPLE_RATE: f64 = 8.0 * 44_100.0;
/// Phases of the initial gap (fractions of one sample's travel).
const PHASES: usize = 16;
/// Samples per phase: 1.2 ms covers the approach (0.5 ms), the contact (0.13 ms) and a rebound.
const STEPS: usize = 424;
/// "Well below 0" for free flight (m): more than the peak compression 8.7e-5 m.
const FREE_BELOW: f64 = -1e-4;
/// QSA segment counts.
const BENCHED_SEGMENTS: [usize; 4] = [1, 5, 20, 64];

const KAPPA: f64 = 1e8;
const ALPHA: f64 = 1.3;
const MASS: f64 = 0.01;
const V0: f64 = 2.0;
const U0: f64 = -1e-3;

/// A solver wrapper that records every problem and solution.
#[derive(Debug, Clone)]
struct Recorder<S> {
    inner: S,
    log: Vec<(ContactProblem, ContactSolution)>,
    /// `last_work()` after each step (QSA sign tests, IMP iterations).
    work: Vec<u32>,
}

impl<S: ContactSolver> ContactSolver for Recorder<S> {
    const METHOD: Method = S::METHOD;

    fn start(&mut self, y_prev: f64, y_now: f64) {
        self.inner.start(y_prev, y_now);
    }

    fn solve(&mut self, problem: &ContactProblem) -> ContactSolution {
        let solution = self.inner.solve(problem);
        self.log.push((*problem, solution));
        self.work.push(self.inner.last_work());
        solution
    }

    fn stored_energy(&self, y_next: f64, y_now: f64) -> f64 {
        self.inner.stored_energy(y_next, y_now)
    }

    fn last_work(&self) -> u32 {
        self.inner.last_work()
    }

    fn segments(&self) -> usize {
        self.inner.segments()
    }
}

/// A stretch of consecutive steps, with the `start` state that reproduces the trajectory.
#[derive(Debug, Clone)]
struct Run {
    start: (f64, f64),
    problems: Vec<ContactProblem>,
    solutions: Vec<ContactSolution>,
}

/// The recorded steps of one solver, split into the two benchmark cases.
#[derive(Debug, Clone, Default)]
struct Sequences {
    contact: Vec<Run>,
    free: Vec<Run>,
    /// Total and largest solver work over the in-contact steps.
    contact_work: (u64, u32),
}

impl Sequences {
    fn steps(runs: &[Run]) -> usize {
        runs.iter().map(|r| r.problems.len()).sum()
    }
}

fn law() -> PowerLaw {
    PowerLaw::new(KAPPA, ALPHA).unwrap()
}

fn qsa(segments: usize) -> QsaSolver {
    let v_ref = 0.5 * MASS * V0 * V0;
    QsaSolver::new(QuadSpline::from_reference_energy(law(), v_ref, segments).unwrap())
}

/// Record `solver` on the Fig. 4 trajectory at every phase and split the log into runs.
fn record<S: ContactSolver + Clone>(solver: &S) -> Sequences {
    let dt = 1.0 / SAMPLE_RATE;
    let mut seq = Sequences::default();
    for phase in 0..PHASES {
        let params =
            MassBarrierParams { mass: MASS, u0: U0 - V0 * dt * phase as f64 / PHASES as f64, v0: V0, barrier: 0.0 };
        let recorder = Recorder { inner: solver.clone(), log: Vec::with_capacity(STEPS), work: Vec::new() };
        let mut scene = MassBarrier::new(params, SAMPLE_RATE, recorder);
        let mut frames = vec![Frame::default(); STEPS];
        scene.process(&mut frames);
        let log = &scene.solver().log;
        let work = &scene.solver().work;
        assert_eq!(log.len(), STEPS);
        assert!(frames.last().unwrap().velocity < 0.0, "phase {phase}: the mass has rebounded");

        let in_contact = |i: usize| log[i].1.force != 0.0;
        let free = |i: usize| {
            let p = &log[i].0;
            log[i].1.force == 0.0 && p.y_prev < FREE_BELOW && p.y_now < FREE_BELOW && p.y_prev - p.z < FREE_BELOW
        };
        for (i, w) in work.iter().enumerate() {
            if in_contact(i) {
                seq.contact_work.0 += u64::from(*w);
                seq.contact_work.1 = seq.contact_work.1.max(*w);
            }
        }
        for (class, runs) in [(&in_contact as &dyn Fn(usize) -> bool, &mut seq.contact), (&free, &mut seq.free)] {
            let mut i = 0;
            while i < log.len() {
                if !class(i) {
                    i += 1;
                    continue;
                }
                let begin = i;
                while i < log.len() && class(i) {
                    i += 1;
                }
                // Start from the step before the run (or the run's own first step at the very
                // beginning of the trajectory).
                let before = &log[begin.saturating_sub(1)].0;
                runs.push(Run {
                    start: (before.y_prev, before.y_now),
                    problems: log[begin..i].iter().map(|(p, _)| *p).collect(),
                    solutions: log[begin..i].iter().map(|(_, s)| *s).collect(),
                });
            }
        }
    }
    assert_eq!(seq.contact.len(), PHASES, "one contact per phase");
    seq
}

/// Solve every run in order, as the benchmark does. Returns a checksum of the forces.
#[inline]
fn replay<S: ContactSolver>(solver: &mut S, runs: &[Run]) -> f64 {
    let mut sum = 0.0;
    for run in runs {
        solver.start(black_box(run.start.0), black_box(run.start.1));
        for problem in &run.problems {
            sum += black_box(solver.solve(black_box(problem))).force;
        }
    }
    sum
}

/// Replaying must reproduce the recorded solutions exactly: the solver state evolves as in the
/// trajectory.
fn check_replay<S: ContactSolver>(solver: &mut S, runs: &[Run], label: &str) {
    for (r, run) in runs.iter().enumerate() {
        solver.start(run.start.0, run.start.1);
        for (k, (problem, want)) in run.problems.iter().zip(&run.solutions).enumerate() {
            let got = solver.solve(problem);
            assert!(
                got.s.to_bits() == want.s.to_bits() && got.force.to_bits() == want.force.to_bits(),
                "{label}: run {r} step {k}: replay gives {got:?}, trajectory had {want:?}"
            );
        }
    }
}

/// One benchmark case: a solver and its recorded sequences.
struct Case<S> {
    name: String,
    solver: S,
    seq: Sequences,
}

fn case<S: ContactSolver + Clone>(name: String, solver: S) -> Case<S> {
    let seq = record(&solver);
    let mut check = solver.clone();
    check_replay(&mut check, &seq.contact, &format!("{name} contact"));
    check_replay(&mut check, &seq.free, &format!("{name} free flight"));
    assert!(seq.contact.iter().all(|r| r.solutions.iter().all(|s| s.force != 0.0)));
    assert!(seq.free.iter().all(|r| r.solutions.iter().all(|s| s.force == 0.0)));
    Case { name, solver, seq }
}

fn bench_case<S: ContactSolver + Clone>(c: &mut Criterion, case: &Case<S>) {
    for (group_name, runs) in [("contact", &case.seq.contact), ("free_flight", &case.seq.free)] {
        let steps = Sequences::steps(runs);
        let mut group = c.benchmark_group(group_name);
        group.warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2)).sample_size(50);
        group.throughput(Throughput::Elements(steps as u64));
        let mut solver = case.solver.clone();
        group.bench_function(BenchmarkId::from_parameter(&case.name), |b| {
            b.iter(|| replay(&mut solver, black_box(runs)))
        });
        group.finish();
    }
}

fn solver_step(c: &mut Criterion) {
    let mut summary = Vec::new();
    fn note<S>(summary: &mut Vec<String>, case: &Case<S>) {
        let contact = Sequences::steps(&case.seq.contact);
        let (work, max_work) = case.seq.contact_work;
        summary.push(format!(
            "recorded {}: {contact} in-contact steps (work per step: mean {:.2}, max {max_work}), {} free-flight steps",
            case.name,
            work as f64 / contact as f64,
            Sequences::steps(&case.seq.free)
        ));
    }
    for n in BENCHED_SEGMENTS {
        let case = case(format!("qsa_N{n}"), qsa(n));
        note(&mut summary, &case);
        bench_case(c, &case);
    }
    let imp = case("imp".to_owned(), NewtonSolver::new(law()));
    note(&mut summary, &imp);
    bench_case(c, &imp);
    let exp = case("exp".to_owned(), ExplicitSolver::new(law()));
    note(&mut summary, &exp);
    bench_case(c, &exp);
    for line in summary {
        eprintln!("{line} ({PHASES} phases at {SAMPLE_RATE} Hz)");
    }
}

criterion_group!(benches, solver_step);
criterion_main!(benches);
