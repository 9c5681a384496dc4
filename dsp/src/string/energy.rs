//! The string's numerical energy and its losses (docs/physics.md §6.3):
//!
//! ```text
//! H^{n+1/2} = ½ m̃ ‖(ũ^{n+1} − ũ^n)/Δt‖² + ½ Σ K̂_i ((ũ_i^{n+1} + ũ_i^n)/2)²
//! H^{n+1/2} − H^{n−1/2} = −Δt (δ_t·ũ)ᵀ R̂ (δ_t·ũ) + (work of the forces)
//! ```
//!
//! each from unscaled sums over the modes in one pass.

use super::{ModalString, kernel};

/// Energy terms of one string step (J), returned by [`ModalString::advance_monitored`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StringEnergy {
    /// `½ m̃ ‖(ũ^{n+1} − ũ^n)/Δt‖² + ½ Σ K̂ ((ũ^{n+1} + ũ^n)/2)²` (J).
    pub stored: f64,
    /// Energy dissipated in the step, `Δt (δ_t·ũ)ᵀ R̂ (δ_t·ũ)` (J).
    pub dissipated: f64,
}

impl ModalString {
    /// [`advance`](Self::advance), also returning the string's energy terms for this step.
    pub fn advance_monitored<const K: usize>(
        &mut self,
        forces: [(&[f64], f64); K],
        output: &[f64],
    ) -> (f64, StringEnergy) {
        debug_assert!(self.history_ready, "advance follows history");
        let (projection, [step2, k_sum2, r_diff2]) = kernel::advance_monitored(
            &mut self.u_prev,
            &self.u_now,
            &self.history,
            forces,
            output,
            &self.stiffness,
            &self.resistance,
        );
        self.finish_step();
        self.history_ready = false;
        // Δt·ΣR̂(δ_t·ũ)² from the unscaled sum.
        let dissipated = 0.25 * r_diff2 * self.sample_rate;
        (projection, StringEnergy { stored: self.stored_energy(step2, k_sum2), dissipated })
    }

    /// The string's energy `H^{n−1/2}` of the current state (J): the stored term between
    /// `ũ^{n−1}` and `ũ^n`, `½ m̃ ‖(ũ^n − ũ^{n−1})/Δt‖² + ½ Σ K̂ ((ũ^n + ũ^{n−1})/2)²`, from the
    /// unscaled sums in one pass (as [`advance_monitored`](Self::advance_monitored) does).
    pub fn energy(&self) -> f64 {
        let (step2, k_sum2) = kernel::energy_sums(self.isa, &self.u_prev, &self.u_now, &self.stiffness);
        self.stored_energy(step2, k_sum2)
    }

    /// Kinetic energy of the latest step, `½ m̃ ‖(ũ^n − ũ^{n−1})/Δt‖²` (J): zero for a string held
    /// still however far it is deflected.
    pub fn kinetic_energy(&self) -> f64 {
        let (step2, _) = kernel::energy_sums(self.isa, &self.u_prev, &self.u_now, &self.stiffness);
        self.kinetic_from(step2)
    }

    /// [`kinetic_energy`](Self::kinetic_energy) and [`energy`](Self::energy) (J) from one pass
    /// over the modes.
    pub fn energies(&self) -> (f64, f64) {
        let (step2, k_sum2) = kernel::energy_sums(self.isa, &self.u_prev, &self.u_now, &self.stiffness);
        (self.kinetic_from(step2), self.stored_energy(step2, k_sum2))
    }

    /// The string's energy of the current state weighed with its own modal stiffnesses (J): as
    /// [`energy`](Self::energy), but with the `K̂_i` the string has without any extra decay
    /// ([`set_extra_decay`](Self::set_extra_decay)). A damper or a fade changes `K̂` (it depends
    /// on the decay rate), so the numerical energy of an unchanged state jumps when they land, by
    /// up to hundreds of times for a low mode damped far beyond its frequency; this measure does
    /// not, and it decays as the damped motion does (docs/physics.md §6.5). What a piano voice's
    /// guard and release test read.
    pub fn own_energy(&self) -> f64 {
        let (step2, k_sum2) = kernel::energy_sums(self.isa, &self.u_prev, &self.u_now, &self.own_stiffness);
        self.stored_energy(step2, k_sum2)
    }

    /// `½ m̃ ‖δ/Δt‖² + ½ Σ K̂ (σ/2)²` (J) between two states, from the unscaled sums `Σ δ²` and
    /// `Σ K̂ σ²` of their difference δ and their sum σ.
    #[inline]
    fn stored_energy(&self, step2: f64, k_sum2: f64) -> f64 {
        self.kinetic_from(step2) + 0.125 * k_sum2
    }

    /// `½ m̃ ‖δ/Δt‖²` (J) from `Σ δ²`.
    #[inline]
    fn kinetic_from(&self, step2: f64) -> f64 {
        let fs = self.sample_rate;
        0.5 * self.modal_mass * step2 * fs * fs
    }
}
