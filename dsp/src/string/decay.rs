//! Changes of the decay rates while the string sounds: a damper landing, a stolen voice's fade
//! (docs/physics.md §6.5). An extra rate `σ_e` scales a mode's `P` by `e^{−σ_eΔt}` and `Q` by its
//! square, so the mode decays at `σ + σ_e` and still rings at `ω`; the state is untouched.

use super::ModalString;
use super::modes::Coefficients;

impl ModalString {
    /// Add the decay rates `extra` (1/s, ≥ 0, one per mode; missing entries count as 0) to the
    /// string's own: each mode then decays at `σ_i + extra_i` and still rings at `ω_i`, since
    /// `P = e^{−(σ+σ_e)Δt} cos(ωΔt)` and `Q = e^{−2(σ+σ_e)Δt}` are the string's own scaled by
    /// `e^{−σ_eΔt}` and its square. The state is untouched, so the signal stays continuous: a
    /// damper or a fade changes how fast the modes decay from here on, never where they are. All
    /// zeros restore the string's own coefficients exactly. Changes `C` (and with it every contact
    /// gain `C∘h` and coupling `q` built on it) and the stored-energy weights `K̂`. Never
    /// allocates.
    pub fn set_extra_decay(&mut self, extra: &[f64]) {
        let (dt, m) = (1.0 / self.sample_rate, self.modal_mass);
        for i in 0..self.modes() {
            let extra = extra.get(i).copied().unwrap_or(0.0);
            let c = Coefficients::with_extra_decay(self.own_p[i], self.own_q[i], extra, dt, m);
            self.coef_a[i] = c.a;
            self.coef_b[i] = c.b;
            self.coef_c[i] = c.c;
            self.stiffness[i] = c.stiffness;
            self.resistance[i] = c.resistance;
        }
        self.history_ready = false;
    }
}
