//! Per-mode vectors and what the state looks like through them (docs/physics.md §6.1): mode
//! shapes `sin(β_i x)`, the bridge's force weights, projections `vᵀũ`, contact vectors with their
//! Gram matrix in the C metric, and the displacement `u(x) = Σ sin(β_i x) ũ_i`.

use super::{GramVector, LANES, ModalString, kernel};

impl ModalString {
    /// Write the mode shapes at `x` (m), `sin(β_i x)`, into `out` (dimensionless; entries past M
    /// are zeroed). One sine and one cosine for all modes: the rest by rotations (see
    /// `kernel::sines`), eight modes at a time when `out` holds whole chunks.
    pub fn mode_shapes(&self, x: f64, out: &mut [f64]) {
        let (s1, c1) = self.shape_angle(x);
        let m = self.modes().min(out.len());
        let whole = m.div_ceil(LANES) * LANES;
        if whole <= out.len() {
            kernel::sines(self.isa, s1, c1, &mut out[..whole]);
        } else {
            let (mut sn, mut cs) = (s1, c1);
            for o in &mut out[..m] {
                *o = sn;
                (sn, cs) = (sn * c1 + cs * s1, cs * c1 - sn * s1);
            }
        }
        out[m..].fill(0.0);
    }

    /// `(sin θ, cos θ)` for `θ = πx/L` (`x` in m), the angle the mode shapes at `x` are made from
    /// (`β_i x = iθ`): what a fresh [`GramVector`] takes.
    #[inline]
    pub fn shape_angle(&self, x: f64) -> (f64, f64) {
        (std::f64::consts::PI * x / self.params.length).sin_cos()
    }

    /// The weights that turn the modal state into the transverse force on the support (N/m):
    /// `T β_i + EI β_i³` at `x = 0`, and `(−1)^(i+1)(T β_i + EI β_i³)` at `x = L` (the mirror
    /// image, since `sin(β_i (L − x)) = (−1)^(i+1) sin(β_i x)`).
    pub fn bridge_weights(&self, at_far_end: bool, out: &mut [f64]) {
        out.fill(0.0);
        let (t, ei) = (self.params.tension, self.params.bending_stiffness);
        for (i, (o, &b)) in out.iter_mut().zip(&self.beta).enumerate() {
            let sign = if at_far_end && i % 2 == 1 { -1.0 } else { 1.0 };
            *o = sign * (t * b + ei * b * b * b);
        }
    }

    /// `xᵀy` for two per-mode vectors of [`padded_len`](Self::padded_len) entries, with the
    /// kernels' fixed summation order.
    #[inline]
    pub fn project(&self, x: &[f64], y: &[f64]) -> f64 {
        kernel::dot(self.isa, x, y)
    }

    /// `(vᵀũ^{n−1}, vᵀũ^n)` for a per-mode vector `v` of [`padded_len`](Self::padded_len) entries.
    #[inline]
    pub fn project_state(&self, v: &[f64]) -> (f64, f64) {
        (kernel::dot(self.isa, &self.u_prev, v), kernel::dot(self.isa, &self.u_now, v))
    }

    /// Make the contact vectors marked fresh (the mode shapes at their angle, see
    /// [`shape_angle`](Self::shape_angle), times their window, and their gains; see
    /// [`GramVector`]) and return their Gram matrix in the C metric `θ_ab = h_aᵀ(C∘h_b)` for
    /// `a ≤ b` (m/N; zero below the diagonal) and the projections `(h_0ᵀũ^{n−1}, h_0ᵀũ^n)` (m)
    /// of the state on the first. A fresh shape is the [`mode_shapes`](Self::mode_shapes) at
    /// the same angle times the window, and every sum equals the [`project`](Self::project) or
    /// [`project_state`](Self::project_state) of the finished vectors, bit for bit.
    #[inline]
    pub fn gram<const K: usize>(&self, vectors: [GramVector<'_>; K]) -> ([[f64; K]; K], (f64, f64)) {
        let (c, modes) = (&self.coef_c, self.modes());
        let (gram, [prev, now]) = kernel::gram(self.isa, c, &self.u_prev, &self.u_now, modes, vectors);
        (gram, (prev, now))
    }

    /// String displacement `u(x) = Σ w_i sin(β_i x) ũ_i^n` (m) at `x` (m), with the coupling
    /// `weights` `w_i` of a core that reaches the modes through them
    /// ([`coupling_weights`](Self::coupling_weights)), else `w_i = 1`: one pass over the modes.
    pub fn displacement_at(&self, x: f64, weights: Option<&[f64]>) -> f64 {
        let theta = std::f64::consts::PI * x / self.params.length;
        let (s1, c1) = theta.sin_cos();
        let two_c = 2.0 * c1;
        let (mut prev, mut now, mut sum) = (0.0, s1, 0.0);
        for (i, &u) in self.u_now[..self.modes()].iter().enumerate() {
            sum += now * u * weights.map_or(1.0, |w| w[i]);
            let next = two_c * now - prev;
            prev = now;
            now = next;
        }
        sum
    }
}
