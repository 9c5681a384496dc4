//! What a render measured: the physics of the one-line JSON summary of `cargo xtask render`
//! (which adds the wall-clock timing).

use serde::Serialize;

use super::build::Run;
use super::parse::SceneDescription;
use crate::scene::Frame;

/// Measurements of one render, in the order of the summary line of `cargo xtask render`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Measurements {
    /// Scene kind.
    pub scene: &'static str,
    /// Solver: `qsa`, `imp` or `exp`.
    pub method: &'static str,
    /// QSA segment count N (0 for IMP and EXP).
    pub segments: usize,
    /// Sample rate (Hz).
    pub sample_rate: u32,
    /// Samples rendered.
    pub samples: usize,
    /// Samples with a non-zero contact force.
    pub contact_samples: usize,
    /// Separate contacts: runs of samples with a non-zero force.
    pub contacts: usize,
    /// Total time with positive compression, entry and exit instants interpolated linearly
    /// between samples (s).
    pub contact_duration: f64,
    /// Largest contact force magnitude (N).
    pub peak_force: f64,
    /// Largest compression `y` (m).
    pub max_compression: f64,
    /// Exciter velocity at the end of the render, after its last contact (m/s); `null` if there
    /// was no contact or the render ended in contact.
    pub rebound_velocity: Option<f64>,
    /// Largest deviation of the energy balance `H^{n+1/2} + losses − control_work − H^{−1/2}`,
    /// relative to the largest energy in the render.
    pub energy_drift_rel: f64,
    /// Largest solver work in one step (QSA sign tests, IMP iterations).
    pub max_work: u32,
    /// Mean solver work per step with a non-zero force.
    pub mean_contact_work: f64,
}

impl Measurements {
    /// Measure a finished run of `scene`.
    pub fn measure(scene: &SceneDescription, run: &Run) -> Self {
        let common = scene.common();
        let frames = &run.frames;
        let dt = 1.0 / common.sample_rate as f64;
        let mut contact_samples = 0;
        let mut contacts = 0;
        let mut in_contact = false;
        let mut peak_force = 0.0_f64;
        let mut max_compression = f64::NEG_INFINITY;
        let mut max_work = 0;
        let mut contact_work = 0u64;
        let mut scale = run.initial_energy.abs();
        let mut drift = 0.0_f64;
        for f in frames {
            let touching = f.force != 0.0;
            if touching {
                contact_samples += 1;
                contact_work += u64::from(f.work);
                if !in_contact {
                    contacts += 1;
                }
            }
            in_contact = touching;
            peak_force = peak_force.max(f.force.abs());
            max_compression = max_compression.max(f.compression);
            max_work = max_work.max(f.work);
            scale = scale.max(f.energy.abs());
            drift = drift.max((f.balance() - run.initial_energy).abs());
        }
        let last = frames.last();
        let rebound_velocity = match last {
            Some(f) if contacts > 0 && f.force == 0.0 => Some(f.velocity),
            _ => None,
        };
        Self {
            scene: scene.kind(),
            method: common.solver.method.name(),
            segments: run.segments,
            sample_rate: common.sample_rate,
            samples: frames.len(),
            contact_samples,
            contacts,
            contact_duration: contact_intervals(frames, dt).iter().map(|(a, b)| b - a).sum(),
            peak_force,
            max_compression,
            rebound_velocity,
            energy_drift_rel: if scale > 0.0 { drift / scale } else { 0.0 },
            max_work,
            mean_contact_work: if contact_samples > 0 { contact_work as f64 / contact_samples as f64 } else { 0.0 },
        }
    }
}

/// The intervals `(entry, exit)` (s) during which the compression is positive, with each
/// crossing interpolated linearly between the samples around it. A contact still open at the end
/// closes at the last sample's time; one open at the start opens at 0.
pub fn contact_intervals(frames: &[Frame], dt: f64) -> Vec<(f64, f64)> {
    let mut intervals = Vec::new();
    let mut entry = None;
    for (n, f) in frames.iter().enumerate() {
        let y = f.compression;
        match entry {
            None if y > 0.0 => {
                entry = Some(if n == 0 {
                    0.0
                } else {
                    let y0 = frames[n - 1].compression;
                    (n as f64 - 1.0 + y0 / (y0 - y)) * dt
                });
            }
            Some(t_in) if y <= 0.0 => {
                let y0 = frames[n - 1].compression;
                intervals.push((t_in, (n as f64 - 1.0 + y0 / (y0 - y)) * dt));
                entry = None;
            }
            _ => {}
        }
    }
    if let Some(t_in) = entry {
        intervals.push((t_in, (frames.len() - 1) as f64 * dt));
    }
    intervals
}
