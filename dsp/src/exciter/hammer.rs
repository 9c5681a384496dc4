//! A lumped piano hammer (seed eq. 36–42, docs/physics.md §6.4).
//!
//! `m_h δ_tt w = −F^n`, so `w^{n+1} = w^{n−1} − z_h − ξ_h F^n` with `z_h = 2(w^{n−1} − w^n)` and
//! `ξ_h = Δt²/m_h`. The hammer sits at `w` (m) on the positive side of the string and moves
//! towards it with velocity `−v` (m/s); compression `y = hᵀũ − w > 0` means the felt is pressed.
//!
//! The state is `w^n` and the increment `δ^n = w^n − w^{n−1}`, updated as `δ^{n+1} = δ^n − ξ_h F^n`:
//! the velocity and `z_h = −2δ^n` then never come from the difference of two large positions
//! (a rebounding hammer travels far), so the kinetic energy keeps full precision.

/// Hammer parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HammerParams {
    /// Hammer mass m_h (kg), > 0.
    pub mass: f64,
    /// Striking speed towards the string (m/s), ≥ 0.
    pub velocity: f64,
    /// Striking position as a fraction of the string length, in (0, 1).
    pub position: f64,
    /// Initial distance between felt and string (m), > 0.
    pub gap: f64,
}

impl HammerParams {
    /// The default initial gap: 0.2 mm, as in the seed's Fig. 5 set-up (docs/physics.md §9.4).
    pub const DEFAULT_GAP: f64 = 2e-4;

    /// Largest energy the hammer can put into the felt: its kinetic energy `½ m v²` (J).
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self.mass * self.velocity * self.velocity
    }
}

/// Hammer state: displacement at two time steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hammer {
    mass: f64,
    /// `ξ_h = Δt²/m_h` (m/N).
    xi: f64,
    dt: f64,
    /// `w^n` (m).
    w_now: f64,
    /// `δ^n = w^n − w^{n−1}` (m).
    step: f64,
}

impl Hammer {
    /// A hammer at `w^0 = gap`, moving towards the string: `w^{−1} = gap + v Δt`.
    pub fn new(params: &HammerParams, sample_rate: f64) -> Self {
        Self::above(0.0, params, sample_rate)
    }

    /// A hammer `gap` beyond the string point at `u` (m), moving towards it: `w^0 = u + gap`,
    /// `w^{−1} = w^0 + v Δt`. Launched at a string that is already moving, it meets the string
    /// wherever the string is, as a hammer flying free from the action does.
    pub fn above(u: f64, params: &HammerParams, sample_rate: f64) -> Self {
        let dt = 1.0 / sample_rate;
        Self { mass: params.mass, xi: dt * dt / params.mass, dt, w_now: u + params.gap, step: -params.velocity * dt }
    }

    /// `ξ_h = Δt²/m_h` (m/N): the hammer's share of the coupling `q`.
    #[inline]
    pub fn coupling(&self) -> f64 {
        self.xi
    }

    /// `w^{n−1}` (m).
    #[inline]
    pub fn previous(&self) -> f64 {
        self.w_now - self.step
    }

    /// `w^n` (m).
    #[inline]
    pub fn position(&self) -> f64 {
        self.w_now
    }

    /// History term `z_h = 2(w^{n−1} − w^n)` (m).
    #[inline]
    pub fn history(&self) -> f64 {
        -2.0 * self.step
    }

    /// Apply the contact force `F^n` (N; the hammer feels `−F`) and step on. Returns `w^{n+1}`.
    #[inline]
    pub fn advance(&mut self, force: f64) -> f64 {
        self.step -= self.xi * force;
        self.w_now += self.step;
        self.w_now
    }

    /// Velocity `δ^n/Δt = (w^n − w^{n−1})/Δt` (m/s) of the latest step.
    #[inline]
    pub fn velocity(&self) -> f64 {
        self.step / self.dt
    }

    /// Kinetic energy `½ m_h ((w^n − w^{n−1})/Δt)²` (J) of the latest step.
    #[inline]
    pub fn energy(&self) -> f64 {
        let v = self.velocity();
        0.5 * self.mass * v * v
    }
}
