//! The slide scene's automation vocabulary: the six control targets a scene file names, and
//! breakpoint automation of them that drives a [`SlideString`](crate::scene::SlideString).
//!
//! Each lane is piecewise linear in time (see [`Breakpoints`]); sample `n` reads the lanes at
//! `t = n/fs`.

use crate::control::{Breakpoints, ControlSource};
use crate::scene::SlideControls;

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
    pub lanes: [Breakpoints; 6],
    /// Sample rate (Hz).
    pub sample_rate: f64,
    /// Each lane's segment at the latest sample asked for (see `Breakpoints::at_cursor`).
    cursors: [usize; 6],
}

impl SlideAutomation {
    /// Automation from its lanes (in [`CONTROL_TARGETS`] order) at `sample_rate` (Hz).
    pub fn new(lanes: [Breakpoints; 6], sample_rate: f64) -> Self {
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
