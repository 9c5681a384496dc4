//! The modal state and its update, one sample at a time (docs/physics.md §6.2).
//!
//! ```text
//! ũ^{n+1} = ũ^{n−1} − z̃ + Σ_k (C∘h_k) F_k,   z̃ = B ũ^{n−1} − A ũ^n
//! ```
//!
//! in two passes over the modes ([`ModalString::history`], [`ModalString::advance`]), or, with no
//! force, by the homogeneous recursion `ũ^{n+1} = 2P ũ^n − Q ũ^{n−1}` for a run of steps
//! ([`ModalString::free_steps`]). Every [`FLUSH_INTERVAL`] steps amplitudes below [`FLUSH_BELOW`]
//! are set to zero (docs/physics.md §10.11).

use super::{FLUSH_BELOW, FLUSH_INTERVAL, ModalString, kernel};

/// Set the amplitudes below [`FLUSH_BELOW`] (m) to zero. Written as a select, not a branch, so
/// it compiles to a few vector instructions per chunk instead of a mispredicted branch per mode.
#[inline]
fn flush_tiny(u: &mut [f64]) {
    for u in u {
        *u = if u.abs() < FLUSH_BELOW { 0.0 } else { *u };
    }
}

/// The two-step state of a set of modes as it moves on: `u^{n−1}`, `u^n` and the steps since the
/// last flush of tiny amplitudes. Shared by [`ModalString`] and [`ModalBank`](super::ModalBank).
pub(super) struct Stepping<'a> {
    pub(super) u_prev: &'a mut Vec<f64>,
    pub(super) u_now: &'a mut Vec<f64>,
    pub(super) since_flush: &'a mut u32,
}

impl Stepping<'_> {
    /// Step the state on, flushing tiny amplitudes every [`FLUSH_INTERVAL`] steps. Returns
    /// whether it flushed (which makes the next `z̃` stale).
    #[inline]
    pub(super) fn finish(&mut self) -> bool {
        std::mem::swap(self.u_prev, self.u_now);
        *self.since_flush += 1;
        if *self.since_flush == FLUSH_INTERVAL {
            *self.since_flush = 0;
            flush_tiny(self.u_prev);
            flush_tiny(self.u_now);
            return true;
        }
        false
    }

    /// `outputs.len()` steps with no force by the homogeneous recursion with coefficients
    /// `a = 2P`, `b = 1 + Q`, writing each step's `outputᵀu^{n+1}` (see `kernel::free_run`).
    pub(super) fn free_steps(&mut self, isa: super::Isa, a: &[f64], b: &[f64], output: &[f64], outputs: &mut [f64]) {
        let mut done = 0;
        while done < outputs.len() {
            let until_flush = (FLUSH_INTERVAL - *self.since_flush) as usize;
            let n = (outputs.len() - done).min(until_flush).min(kernel::RUN);
            kernel::free_run(isa, a, b, self.u_prev, self.u_now, output, &mut outputs[done..done + n]);
            // `free_run` leaves the last state in `u_now`; `finish` swaps, so undo that.
            std::mem::swap(self.u_prev, self.u_now);
            *self.since_flush += n as u32 - 1;
            self.finish();
            done += n;
        }
    }
}

impl ModalString {
    /// Modal displacements `ũ^n` (m), M entries.
    pub fn state(&self) -> &[f64] {
        &self.u_now[..self.modes()]
    }

    /// Modal displacements `ũ^{n−1}` (m), M entries.
    pub fn previous_state(&self) -> &[f64] {
        &self.u_prev[..self.modes()]
    }

    /// Set the modal state `ũ^{n−1}`, `ũ^n` (m). Slices must have [`modes`](Self::modes) entries.
    /// The padding beyond them is zeroed: a step under a force that was not finite leaves NaN
    /// there, which the projections' zero weights would carry (`0·NaN`) into every output.
    pub fn set_state(&mut self, previous: &[f64], now: &[f64]) {
        let m = self.modes();
        self.u_prev[..m].copy_from_slice(previous);
        self.u_now[..m].copy_from_slice(now);
        self.u_prev[m..].fill(0.0);
        self.u_now[m..].fill(0.0);
        self.history_ready = false;
    }

    /// `(ũ^{n−1}, ũ^n)` (m, M entries each) to be written in place (what follows must not rely
    /// on a `z̃` computed before); the padding is zeroed, as by [`set_state`](Self::set_state).
    pub(crate) fn state_mut(&mut self) -> (&mut [f64], &mut [f64]) {
        let m = self.modes();
        self.history_ready = false;
        self.u_prev[m..].fill(0.0);
        self.u_now[m..].fill(0.0);
        (&mut self.u_prev[..m], &mut self.u_now[..m])
    }

    /// Hold the string still under the static modal forces `force(i)` (N, mode `i` from 0):
    /// `ũ_i^{n−1} = ũ_i^n = C_i force(i)/(B_i − A_i)`, which is `force(i)/K̂_i`, the scheme's own
    /// equilibrium (a state its update leaves where it is under those forces); 0 for a mode whose
    /// `K̂` is 0. Never allocates.
    pub fn rest_under(&mut self, force: impl Fn(usize) -> f64) {
        let coefficients = (&self.coef_a[..], &self.coef_b[..], &self.coef_c[..]);
        hold_still(coefficients, self.modes(), (&mut self.u_prev, &mut self.u_now), force);
        self.history_ready = false;
    }

    /// Bring the string to rest.
    pub fn reset(&mut self) {
        self.u_prev.fill(0.0);
        self.u_now.fill(0.0);
        self.since_flush = 0;
        self.history_ready = false;
    }

    /// First pass of a step: compute `z̃ = B ũ^{n−1} − A ũ^n` and return its projections on
    /// each of the `K` vectors (m). Vectors have [`padded_len`](Self::padded_len) entries.
    /// When the previous step was an [`advance`](Self::advance), `z̃` is already there and this
    /// pass only projects it.
    #[inline]
    pub fn history<const K: usize>(&mut self, vectors: [&[f64]; K]) -> [f64; K] {
        if self.history_ready {
            return kernel::projections(self.isa, &self.history, vectors);
        }
        self.history_ready = true;
        kernel::history(self.isa, &self.coef_a, &self.coef_b, &self.u_prev, &self.u_now, &mut self.history, vectors)
    }

    /// Second pass: `ũ^{n+1} = ũ^{n−1} − z̃ + Σ_k gains_k · F_k`, where `gains_k = C∘h_k` (m/N,
    /// see [`input_gains`](Self::input_gains)) and `F_k` (N) are the modal forces along each contact
    /// vector; then step the state on. Returns `outputᵀ ũ^{n+1}`. The same pass computes the next
    /// step's `z̃`, so that the next [`history`](Self::history) only projects it.
    #[inline]
    pub fn advance<const K: usize>(&mut self, forces: [(&[f64], f64); K], output: &[f64]) -> f64 {
        self.advance_projecting(forces, output, []).0
    }

    /// [`advance`](Self::advance), also projecting the next step's `z̃` on the `J` vectors `next`
    /// in the same pass: the second value is what [`history(next)`](Self::history) would return
    /// next, bit for bit, so a caller whose vectors stay put can skip that pass. It is `None`
    /// when this step flushed tiny amplitudes (the new `z̃` is then recomputed from the flushed
    /// state by the next `history`).
    #[inline]
    pub fn advance_projecting<const K: usize, const J: usize>(
        &mut self,
        forces: [(&[f64], f64); K],
        output: &[f64],
        next: [&[f64]; J],
    ) -> (f64, Option<[f64; J]>) {
        debug_assert!(self.history_ready, "advance follows history");
        let (a, b) = (&self.coef_a, &self.coef_b);
        let (projection, next) =
            kernel::advance(self.isa, a, b, &mut self.u_prev, &self.u_now, &mut self.history, forces, output, next);
        self.finish_step();
        (projection, self.history_ready.then_some(next))
    }

    /// `outputs.len()` steps with no force on the string, by the homogeneous recursion
    /// `ũ^{n+1} = 2P ũ^n − Q ũ^{n−1}` with the coefficients of [`history`](Self::history) and
    /// [`advance`](Self::advance) (which compute `ũ^{n−1} − z̃`, the same recursion rounded
    /// differently: a few ulps per step), writing each step's `outputᵀ ũ^{n+1}` into `outputs`.
    /// The state stays in registers between steps (see `kernel::free_run`).
    pub fn free_steps(&mut self, output: &[f64], outputs: &mut [f64]) {
        let mut stepping =
            Stepping { u_prev: &mut self.u_prev, u_now: &mut self.u_now, since_flush: &mut self.since_flush };
        stepping.free_steps(self.isa, &self.coef_a, &self.coef_b, output, outputs);
        self.history_ready = false;
    }

    /// Step the state on, flushing tiny amplitudes every [`FLUSH_INTERVAL`] steps (a flush makes
    /// the next `z̃` stale).
    #[inline]
    pub(super) fn finish_step(&mut self) {
        let mut stepping =
            Stepping { u_prev: &mut self.u_prev, u_now: &mut self.u_now, since_flush: &mut self.since_flush };
        if stepping.finish() {
            self.history_ready = false;
        }
    }
}

/// The first `modes` entries of `(u^{n−1}, u^n)` held still under the static forces `force(i)`
/// (N): the recursion `u^{n+1} = 2P_i u^n − Q_i u^{n−1} + C_i f_i`, with the coefficients
/// `(A_i, B_i, C_i) = (2P_i, 1 + Q_i, C_i)`, leaves `u_i = C_i f_i/(B_i − A_i)` where it is. A
/// mode without stiffness in its recursion (`B_i = A_i`: a free mass, or damping so heavy that
/// `2P_i` rounds to `1 + Q_i`) has no such rest and is held at 0. The padding beyond them is
/// zeroed.
pub(super) fn hold_still(
    (a, b, c): (&[f64], &[f64], &[f64]),
    modes: usize,
    (u_prev, u_now): (&mut [f64], &mut [f64]),
    force: impl Fn(usize) -> f64,
) {
    for i in 0..modes {
        let stiffness = b[i] - a[i];
        let u = if stiffness > 0.0 { c[i] * force(i) / stiffness } else { 0.0 };
        u_prev[i] = u;
        u_now[i] = u;
    }
    u_prev[modes..].fill(0.0);
    u_now[modes..].fill(0.0);
}
