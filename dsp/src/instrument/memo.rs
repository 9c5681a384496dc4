//! Per-block work that a one-sample control block would repeat every sample.

/// The fewest samples between two weighings of a voice's energy by its guard and its release
/// test: with shorter control blocks, a pass over the modes every block would cost as much as
/// the step's own passes.
pub const ENERGY_INTERVAL: usize = 64;

/// The latest value of a pure function of one argument, worked out again only when the argument
/// changes (compared bit for bit, so the value is always the function's own).
#[derive(Debug, Clone, Copy)]
pub struct Memo {
    arg: f64,
    value: f64,
}

impl Memo {
    /// Nothing kept yet (the NaN argument's bits are not those of the arithmetic's NaN).
    pub const EMPTY: Memo = Memo { arg: f64::from_bits(0x7ff8_dead_0000_0001), value: f64::NAN };

    /// `f(arg)`, from the last call's if `arg` is the same.
    pub fn get(&mut self, arg: f64, f: impl FnOnce(f64) -> f64) -> f64 {
        if arg.to_bits() != self.arg.to_bits() {
            *self = Memo { arg, value: f(arg) };
        }
        self.value
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A memo gives the function's own bits for every argument, NaN and both zeros included,
    /// and works the function out only when the argument changes.
    #[test]
    fn a_memo_is_the_function_and_calls_it_only_for_new_arguments() {
        let mut memo = Memo::EMPTY;
        let mut calls = 0;
        for x in [0.5, 0.5, -0.0, 0.0, 0.0, f64::NAN, f64::NAN, -3.0, 0.5] {
            let y = memo.get(x, |x| {
                calls += 1;
                (-x).exp()
            });
            assert_eq!(y.to_bits(), (-x).exp().to_bits(), "x = {x}");
        }
        assert_eq!(calls, 6);
    }
}
