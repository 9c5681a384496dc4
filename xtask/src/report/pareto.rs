//! The Pareto front of a cost–error trade-off: the configurations no other configuration beats in
//! both run time and error. The plots draw it and the budget table picks from it.

/// The Pareto front of `(cost, error, label)` points: sorted by cost, each point strictly better in
/// error than every cheaper one.
pub fn front<T: Clone>(points: &[(f64, f64, T)]) -> Vec<(f64, f64, T)> {
    let mut sorted: Vec<(f64, f64, T)> =
        points.iter().filter(|p| p.0.is_finite() && p.1.is_finite()).cloned().collect();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut best = f64::INFINITY;
    sorted
        .into_iter()
        .filter(|p| {
            if p.1 < best {
                best = p.1;
                true
            } else {
                false
            }
        })
        .collect()
}
