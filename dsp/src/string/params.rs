//! The physical parameters of a stiff string, their loss laws and their checks (docs/physics.md
//! §6.1): length `L`, tension `T`, linear density `ρA`, bending stiffness `EI` and the modal decay
//! rates `σ_i`.

use serde::Serialize;

/// How the modal decay rates `σ_i` (1/s) are set.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "law", rename_all = "kebab-case")]
pub enum Damping {
    /// Seed eq. 27: `σ_i = η0 + η2 β_i²`, with `η0` (1/s) and `η2` (m²/s).
    Viscous {
        /// Frequency-independent loss η0 (1/s).
        eta0: f64,
        /// Frequency-dependent loss η2 (m²/s).
        eta2: f64,
    },
    /// Chaigne–Askenfelt style per-mode law: `σ_i = b1 + b3 ω0_i²`, with `b1` (1/s) and `b3` (s).
    PerMode {
        /// Frequency-independent loss b1 (1/s).
        b1: f64,
        /// Loss growing with the square of the mode's frequency, b3 (s).
        b3: f64,
    },
}

impl Damping {
    /// No loss at all.
    pub const LOSSLESS: Damping = Damping::Viscous { eta0: 0.0, eta2: 0.0 };

    /// Decay rate `σ` (1/s) of a mode with wavenumber `beta` (1/m) and angular frequency `omega0`
    /// (rad/s).
    pub fn sigma(&self, beta: f64, omega0: f64) -> f64 {
        match *self {
            Damping::Viscous { eta0, eta2 } => eta0 + eta2 * beta * beta,
            Damping::PerMode { b1, b3 } => b1 + b3 * omega0 * omega0,
        }
    }

    fn terms(&self) -> [(&'static str, f64); 2] {
        match *self {
            Damping::Viscous { eta0, eta2 } => [("eta0", eta0), ("eta2", eta2)],
            Damping::PerMode { b1, b3 } => [("b1", b1), ("b3", b3)],
        }
    }
}

/// Physical parameters of a stiff string.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StringParams {
    /// Length L (m).
    pub length: f64,
    /// Tension T (N).
    pub tension: f64,
    /// Linear density ρA (kg/m).
    pub linear_density: f64,
    /// Bending stiffness EI (N·m²).
    pub bending_stiffness: f64,
    /// Loss law.
    pub damping: Damping,
}

/// An invalid string parameter: names the key and the reason.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{key}: {reason}")]
pub struct StringError {
    /// Parameter name (as in scene files).
    pub key: &'static str,
    /// What is wrong.
    pub reason: String,
}

impl StringParams {
    /// Nominal fundamental of the flexible string, `f0 = √(T/ρA)/(2L)` (Hz).
    pub fn fundamental(&self) -> f64 {
        (self.tension / self.linear_density).sqrt() / (2.0 * self.length)
    }

    /// Inharmonicity coefficient `B = π² EI/(T L²)`.
    pub fn inharmonicity(&self) -> f64 {
        std::f64::consts::PI.powi(2) * self.bending_stiffness / (self.tension * self.length * self.length)
    }

    /// Lossless partial `f_i = i f0 √(1 + B i²)` (Hz), `i ≥ 1`.
    pub fn partial(&self, i: usize) -> f64 {
        let i = i as f64;
        i * self.fundamental() * (1.0 + self.inharmonicity() * i * i).sqrt()
    }

    /// Check every parameter, naming the first invalid one.
    pub fn validate(&self) -> Result<(), StringError> {
        let positive = |key, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(StringError { key, reason: format!("must be finite and > 0 (got {v})") })
            }
        };
        positive("length", self.length)?;
        positive("tension", self.tension)?;
        positive("linear_density", self.linear_density)?;
        if !(self.bending_stiffness.is_finite() && self.bending_stiffness >= 0.0) {
            return Err(StringError {
                key: "bending_stiffness",
                reason: format!("must be finite and >= 0 (got {})", self.bending_stiffness),
            });
        }
        for (key, v) in self.damping.terms() {
            if !(v.is_finite() && v >= 0.0) {
                return Err(StringError { key, reason: format!("must be finite and >= 0 (got {v})") });
            }
        }
        Ok(())
    }
}

/// Check a sample rate (Hz) and a frequency limit (Hz), naming the first invalid one.
pub(super) fn check_rates(sample_rate: f64, max_frequency: f64) -> Result<(), StringError> {
    if !(sample_rate.is_finite() && sample_rate > 0.0) {
        return Err(StringError { key: "sample_rate", reason: format!("must be finite and > 0 (got {sample_rate})") });
    }
    if !(max_frequency > 0.0) {
        return Err(StringError { key: "max_frequency", reason: format!("must be > 0 (got {max_frequency})") });
    }
    Ok(())
}
