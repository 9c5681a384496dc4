//! Slide gestures on the `slide-guitar` preset, shared by the report's control-block table, the
//! stability sweep and the tests: a glide, a vibrato, and random control trajectories.
//!
//! The glide and the vibrato are timed on a grid of 256-sample blocks at 44.1 kHz: every control
//! block length that divides 256 samples their breakpoints exactly, so renders at N_b = 1 … 256
//! differ only by what happens inside the blocks (docs/physics.md §7.5).

use std::ops::Range;

use qsa_dsp::contact::PowerLaw;
use qsa_dsp::control::Breakpoints;
use qsa_dsp::exciter::{FingerParams, SlideParams};
use qsa_dsp::preset::slide_guitar;
use qsa_dsp::scene::{OutputKind, Pickup, SlideStringParams};
use qsa_dsp::scene_file::SlideAutomation;
use qsa_dsp::string::{Damping, ModalString};
use rand::RngExt;
use rand_pcg::Pcg64;

use super::sim::{CaseScene, Setup};

/// Sample rate of the glide and the vibrato (Hz).
pub const FS: f64 = 44_100.0;

/// Slide position (m from the nut) `p` semitones above the open string.
pub fn semitone_position(p: f64) -> f64 {
    slide_guitar().string.length * (1.0 - 2f64.powf(-p / 12.0))
}

/// The glide's first and last slide positions (semitones above the open string).
pub const GLIDE: (f64, f64) = (5.0, 7.0);

/// The vibrato's depth (m) and rate (Hz), about [`GLIDE`]'s last position.
pub const VIBRATO: (f64, f64) = (3e-3, 5.5);

/// Grid steps (of 256 samples) at which the gestures start moving, and the glide's length.
const START: f64 = 86.0;
const GLIDE_STEPS: f64 = 17.0;

/// The glide's duration (s) and mean speed along the string (m/s).
pub fn glide_motion() -> (f64, f64) {
    let seconds = grid(GLIDE_STEPS);
    (seconds, (semitone_position(GLIDE.1) - semitone_position(GLIDE.0)) / seconds)
}

/// Time (s) of `blocks` blocks of 256 samples at [`FS`].
pub fn grid(blocks: f64) -> f64 {
    blocks * 256.0 / FS
}

/// The slide-guitar preset's scene at control block `block`, displacement output at 0.9 L.
pub fn preset_params(block: usize) -> SlideStringParams {
    let g = slide_guitar();
    SlideStringParams {
        string: g.string,
        slide: g.slide,
        left: g.left,
        right: g.right,
        block,
        pickup: Pickup::point(OutputKind::Displacement, 0.9),
    }
}

/// QSA's fit range for the preset's gestures (m): the scene-file rule, twice the hand's deepest
/// static push, `2·(k_H·(1.5 mm + 1 mm) + 0.3 N + 1.5 N)`.
pub fn preset_y_ref() -> f64 {
    let g = slide_guitar();
    let push = 2.0 * (g.slide.stiffness * 2.5e-3 + 1.8);
    (push / g.kappa).powf(1.0 / g.alpha)
}

/// Automation lanes in `CONTROL_TARGETS` order, the left finger trailing the slide by 2 cm.
pub fn lanes(
    slide: Vec<(f64, f64)>,
    hand: Vec<(f64, f64)>,
    left_force: Vec<(f64, f64)>,
    right: f64,
    right_force: Vec<(f64, f64)>,
) -> [Breakpoints; 6] {
    let lane = |points| Breakpoints::new(points).expect("gesture breakpoints increase in time");
    let left = slide.iter().map(|&(t, x)| (t, x - 0.02)).collect();
    [lane(slide), lane(hand), lane(left), lane(left_force), Breakpoints::constant(right), lane(right_force)]
}

/// The pluck of the glide and the vibrato: the right finger pushes 1.5 N over one grid step and
/// lets go over the next, at grid step 34 (about 0.2 s).
fn pluck() -> Vec<(f64, f64)> {
    vec![(grid(34.0), 0.0), (grid(35.0), 1.5), (grid(36.0), 0.0)]
}

/// A named gesture on the preset: its lanes, its length and the window where it moves.
#[derive(Debug, Clone)]
pub struct Gesture {
    /// Short name.
    pub name: &'static str,
    /// The controls, in `CONTROL_TARGETS` order.
    pub lanes: [Breakpoints; 6],
    /// Simulated length (s).
    pub seconds: f64,
    /// Where the slide moves (s).
    pub moving: Range<f64>,
}

impl Gesture {
    /// A glide over [`GLIDE`] (5 to 7 semitones, about 0.5 m/s): the slide pressed at the first,
    /// plucked, gliding over 17 grid steps (0.1 s) from step 86 (0.5 s).
    pub fn glide() -> Self {
        let (a, b) = (semitone_position(GLIDE.0), semitone_position(GLIDE.1));
        let end = START + GLIDE_STEPS;
        let lanes =
            lanes(vec![(grid(START), a), (grid(end), b)], vec![(0.0, -1.5e-3)], vec![(0.0, 0.3)], 0.58, pluck());
        Self { name: "glide", lanes, seconds: grid(end) + 0.01, moving: grid(START)..grid(end) }
    }

    /// A [`VIBRATO`] (±3 mm at 5.5 Hz) about 7 semitones from 0.5 s, as breakpoints every grid
    /// step.
    pub fn vibrato() -> Self {
        let centre = semitone_position(GLIDE.1);
        let (depth, rate) = VIBRATO;
        let slide = (86..=140)
            .map(|k| {
                let t = grid(f64::from(k));
                (t, centre + depth * (2.0 * std::f64::consts::PI * rate * (t - grid(START))).sin())
            })
            .collect();
        let lanes = lanes(slide, vec![(0.0, -1.5e-3)], vec![(0.0, 0.3)], 0.58, pluck());
        Self { name: "vibrato", lanes, seconds: grid(140.0) + 0.01, moving: grid(86.0)..grid(140.0) }
    }

    /// The gesture as a report case at control block `block`, with the preset's contact law.
    pub fn scene(&self, block: usize) -> CaseScene {
        let g = slide_guitar();
        let law = PowerLaw::new(g.kappa, g.alpha).expect("the preset's law is valid");
        CaseScene {
            setup: Setup::Slide(preset_params(block), SlideAutomation::new(self.lanes.clone(), FS)),
            law,
            sample_rate: FS as u32,
            samples: (self.seconds * FS).round() as usize,
            v_ref: law.potential(preset_y_ref()),
        }
    }

    /// The samples where the slide moves.
    pub fn window(&self) -> Range<usize> {
        (self.moving.start * FS) as usize..(self.moving.end * FS) as usize
    }
}

/// A random control trajectory on the slide-guitar string, at the plugin's extremes and beyond.
///
/// Drawn (log-uniform unless noted): κ ∈ [1e2, 1e16] N/m^α; α = 1 in a third of them, else
/// uniform in [1, 4]; slide mass ∈ [0.1 g, 1 kg] (the plugin: 5–200 g); hand stiffness k_H ∈
/// [1e2, 1e6] N/m; hand damping r_H = 0 in a third, else uniform in [0, 100] kg/s; finger damping
/// uniform in [0, 50] s/m; the string lossless in a quarter; N_b = 1 in a third, else uniform in
/// [1, 256]; fs ∈ [22.05, `max_fs`] kHz (the stability sweep: 192 kHz, 96 kHz for its runs of
/// seconds). Over the run the slide moves between random positions in
/// [0.15, 0.45] L at random speeds up to 5 m/s, with a vibrato of up to ±5 mm at up to 10 Hz;
/// the hand jumps between random heights in ±3 mm (pressing, rattling and lifting); each
/// finger's force switches between 0 and up to 3 N. Changes come at random times, three in ten
/// of them one sample after the last (a jump), the rest up to a fifth of the run apart.
#[derive(Debug, Clone)]
pub struct Trajectory {
    /// The contact law.
    pub law: PowerLaw,
    /// The scene (string, slide, fingers, N_b, pickup).
    pub params: SlideStringParams,
    /// Sample rate (Hz, whole).
    pub fs: u32,
    /// Simulated length (s).
    pub seconds: f64,
    /// The controls, in `CONTROL_TARGETS` order.
    pub lanes: [Breakpoints; 6],
}

impl Trajectory {
    /// Draw a trajectory from `rng` at a sample rate up to `max_fs` (Hz, at least 22.05 kHz);
    /// `seconds(fs, modes)` gives the run's length (s) for the drawn sample rate (Hz) and the
    /// number of modes the string has there.
    pub fn draw(rng: &mut Pcg64, max_fs: f64, seconds: impl Fn(f64, usize) -> f64) -> Self {
        let g = slide_guitar();
        let length = g.string.length;
        let pick = |rng: &mut Pcg64, lo: f64, hi: f64| lo + (hi - lo) * rng.random::<f64>();
        let log = |rng: &mut Pcg64, lo: f64, hi: f64| (lo.ln() + rng.random::<f64>() * (hi / lo).ln()).exp();
        let fs = log(rng, 22_050.0, max_fs.max(22_050.0)).round();
        let lossless = rng.random_bool(0.25);
        let string =
            if lossless { qsa_dsp::string::StringParams { damping: Damping::LOSSLESS, ..g.string } } else { g.string };
        let modes = ModalString::new(string, fs).map_or(1, |s| s.modes());
        let seconds = seconds(fs, modes);
        let (vib_f, vib_a) = (pick(rng, 0.0, 10.0), pick(rng, 0.0, 5e-3));
        let mut slide = vec![];
        let (mut t, mut x) = (0.0, pick(rng, 0.15, 0.45) * length);
        while t <= seconds {
            slide.push((t, x));
            let next = pick(rng, 0.15, 0.45) * length;
            let speed = pick(rng, 0.05, 5.0);
            t += ((next - x).abs() / speed).max(1.0 / fs) + pick(rng, 0.0, 0.2 * seconds);
            x = next;
        }
        let moving = Breakpoints::new(slide).expect("increasing times");
        let step = (seconds / 200.0).max(1.0 / fs);
        let slide = (0..=(seconds / step).ceil() as usize)
            .map(|i| i as f64 * step)
            .map(|t| (t, moving.at(t) + vib_a * (2.0 * std::f64::consts::PI * vib_f * t).sin()))
            .collect();
        let steps = |rng: &mut Pcg64, value: &dyn Fn(&mut Pcg64) -> f64| {
            let (mut t, mut points) = (0.0, vec![]);
            while t <= seconds {
                points.push((t, value(rng)));
                t += if rng.random_bool(0.3) { 1.0 / fs } else { pick(rng, 1.0 / fs, 0.2 * seconds) };
            }
            points
        };
        let hand = steps(rng, &|rng| pick(rng, -3e-3, 3e-3));
        let force = |rng: &mut Pcg64| if rng.random_bool(0.5) { 0.0 } else { pick(rng, 0.0, 3.0) };
        let left_force = steps(rng, &force);
        let right_force = steps(rng, &force);
        let lanes = lanes(slide, hand, left_force, pick(rng, 0.5, 0.98) * length, right_force);
        let alpha = if rng.random_bool(1.0 / 3.0) { 1.0 } else { pick(rng, 1.0, 4.0) };
        let law = PowerLaw::new(log(rng, 1e2, 1e16), alpha).expect("a valid law");
        let slide = SlideParams {
            mass: log(rng, 1e-4, 1.0),
            stiffness: log(rng, 1e2, 1e6),
            damping: if rng.random_bool(1.0 / 3.0) { 0.0 } else { pick(rng, 0.0, 100.0) },
        };
        let finger_damping = pick(rng, 0.0, 50.0);
        let block = if rng.random_bool(1.0 / 3.0) { 1 } else { rng.random_range(1..=256) };
        let params = SlideStringParams {
            string,
            slide,
            left: FingerParams { damping: finger_damping, ..g.left },
            right: FingerParams { damping: finger_damping, ..g.right },
            block,
            pickup: Pickup::point(OutputKind::Displacement, 0.9),
        };
        Self { law, params, fs: fs as u32, seconds, lanes }
    }

    /// QSA's fit range (m): the scene-file rule, twice the largest static push the hand (3 mm
    /// deep, plus 1 mm) and both fingers (3 N each) can make.
    pub fn y_ref(&self) -> f64 {
        let push = 2.0 * (self.params.slide.stiffness * 4e-3 + 6.0);
        (push / self.law.kappa()).powf(1.0 / self.law.alpha())
    }

    /// The trajectory as a report case (the base rate is the drawn one).
    pub fn scene(&self) -> CaseScene {
        let fs = f64::from(self.fs);
        CaseScene {
            setup: Setup::Slide(self.params, SlideAutomation::new(self.lanes.clone(), fs)),
            law: self.law,
            sample_rate: self.fs,
            samples: (self.seconds * fs).round().max(1.0) as usize,
            v_ref: self.law.potential(self.y_ref()),
        }
    }

    /// A compact description of the drawn parameters.
    pub fn about(&self) -> String {
        let p = &self.params;
        format!(
            "κ {:.3e}, α {:.3}, fs {} Hz, slide {:.3e} kg, k_H {:.3e} N/m, r_H {:.3e} kg/s, finger r {:.3} s/m, {}, N_b {}, {:.4} s",
            self.law.kappa(),
            self.law.alpha(),
            self.fs,
            p.slide.mass,
            p.slide.stiffness,
            p.slide.damping,
            p.left.damping,
            if p.string.damping == Damping::LOSSLESS { "lossless string" } else { "lossy string" },
            p.block,
            self.seconds
        )
    }
}
