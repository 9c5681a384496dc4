//! The Pareto front of a cost–error trade-off: the configurations no other configuration beats in
//! both run time and error. The plots draw it and the budget table picks from it.

/// The Pareto front of `(cost, error, label)` points: sorted by cost, each point better in error
/// by more than `margin` than the cheaper point before it on the front (0: strictly better than
/// every cheaper point; the report's tolerance: a difference it would call equal buys no place
/// on the front at a higher cost).
pub fn front<T: Clone>(points: &[(f64, f64, T)], margin: f64) -> Vec<(f64, f64, T)> {
    let mut sorted: Vec<(f64, f64, T)> =
        points.iter().filter(|p| p.0.is_finite() && p.1.is_finite()).cloned().collect();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut best = f64::INFINITY;
    sorted
        .into_iter()
        .filter(|p| {
            if p.1 < best - margin {
                best = p.1;
                true
            } else {
                false
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dearer point 0.002 decades better is on the strict front and off the one with a margin
    /// of 0.05 (the report's budget table: −3.4459 at RTF 7.1e-3 and −3.4477 at 1.8e-2); one
    /// 0.1 better is on both; a dearer point no better is on neither.
    #[test]
    fn a_margin_keeps_differences_below_it_off_the_front() {
        let points = [(7.1e-3, -3.4459, "a"), (1.8e-2, -3.4477, "b"), (3e-2, -3.55, "c"), (4e-2, -3.5, "d")];
        let labels = |margin| front(&points, margin).into_iter().map(|p| p.2).collect::<Vec<_>>();
        assert_eq!(labels(0.0), ["a", "b", "c"]);
        assert_eq!(labels(0.05), ["a", "c"]);
    }
}
