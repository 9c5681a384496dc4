//! Scenes: concrete physical set-ups composed from a contact solver and the bodies it couples.
//!
//! A scene holds only what it needs (a mass–barrier has no string) and is generic over its
//! [`ContactSolver`](crate::contact::ContactSolver), so its sample loop has no branch for a part
//! it lacks and no dynamic dispatch. Each call of [`Scene::process`] advances one sample per
//! [`Frame`]; splitting a render into calls of any size gives bit-identical frames.

mod hammer_string;
mod mass_barrier;
mod slide_string;
mod unison;

pub use hammer_string::{HammerCore, HammerString, HammerStringParams, OutputKind, Pickup};
pub use mass_barrier::{MassBarrier, MassBarrierParams};
pub use slide_string::{MAX_PIECES, PIECE_TURN, SlideControls, SlideCore, SlideString, SlideStringParams};
pub use unison::{
    HammerUnison, MAX_PARTNERS, MAX_UNISON, PARTNER_MODES, Shared, UnisonCore, UnisonError, UnisonParams, Watch,
};

/// One sample `n` of a scene's signals.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Frame {
    /// The scene's audio output at `n` (unit depends on the chosen output signal).
    pub output: f64,
    /// Displacement of the exciter (mass, hammer or slide) `u^n` (m).
    pub displacement: f64,
    /// Exciter velocity `(u^{n+1} − u^n)/Δt` (m/s).
    pub velocity: f64,
    /// Contact compression `y^n` (m); positive means in contact.
    pub compression: f64,
    /// Contact force `F^n` (N); ≤ 0.
    pub force: f64,
    /// Numerical energy `H^{n+1/2}` (J).
    pub energy: f64,
    /// Energy that has left the system up to `n+1/2` through damping (J), ≥ 0 and
    /// non-decreasing.
    pub losses: f64,
    /// Work the control inputs have done on the system up to `n+1/2` (J, either sign): the
    /// moving hand, the fingers' forces and the slide's travel along the string (zero in scenes
    /// without controls).
    pub control_work: f64,
    /// Solver work in this step (QSA sign tests, IMP Newton iterations; 0 for EXP).
    pub work: u32,
}

impl Frame {
    /// `energy + losses − control_work` (J): what the energy balance keeps constant, to
    /// rounding, from the initial energy on.
    #[inline]
    pub fn balance(&self) -> f64 {
        self.energy + self.losses - self.control_work
    }
}

/// A scene that can be rendered sample by sample.
pub trait Scene {
    /// Sample rate (Hz).
    fn sample_rate(&self) -> f64;

    /// The numerical energy of the initial state, `H^{−1/2}` (J).
    fn initial_energy(&self) -> f64;

    /// Advance `frames.len()` samples, writing one frame per sample. Never allocates.
    fn process(&mut self, frames: &mut [Frame]);

    /// Advance `out.len()` samples, writing only the output signal: the real-time path, with no
    /// energy bookkeeping. Gives the same output as [`process`](Self::process).
    fn process_output(&mut self, out: &mut [f64]);
}

/// The largest difference (in the output's unit) between `scene` stepped on for `samples` by the
/// real-time path and by frames: the two paths give the same output from any state, the one the
/// real-time path left included.
#[cfg(test)]
pub(crate) fn frames_against_the_real_time_path<S: Scene + Clone>(scene: &S, samples: usize) -> f64 {
    let mut fast = scene.clone();
    let mut tail = vec![0.0; samples];
    fast.process_output(&mut tail);
    let mut frames = vec![Frame::default(); samples];
    scene.clone().process(&mut frames);
    tail.iter().zip(&frames).map(|(x, f)| (x - f.output).abs()).fold(0.0, f64::max)
}
