//! Multiple importance sampling: the heuristics that weigh one strategy's sample against the
//! others that could have made it (Veach 1997, ch. 9).

pub use base::MisHeuristic;

/// The weight, by heuristic `h` (the power heuristic with β = 2, Mitsuba's and pbrt's
/// choice, or the balance heuristic), of a sample drawn with density `a` when a strategy of
/// density `b` could have drawn it too; 0 where the ratio is not finite (both densities 0,
/// or infinite).
#[inline(always)]
pub fn weight(h: MisHeuristic, a: f32, b: f32) -> f32 {
    let w = match h {
        MisHeuristic::Power => {
            let (a2, b2) = (a * a, b * b);
            a2 / (a2 + b2)
        }
        MisHeuristic::Balance => a / (a + b),
    };
    if w.is_finite() { w } else { 0.0 }
}

/// [`weight`] with the power heuristic.
#[inline(always)]
pub fn power(a: f32, b: f32) -> f32 {
    weight(MisHeuristic::Power, a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_of_two_strategies_sum_to_one() {
        for (a, b) in [(0.3f32, 2.0f32), (5.0, 5.0), (1e-3, 7.0)] {
            for h in [MisHeuristic::Power, MisHeuristic::Balance] {
                let s = weight(h, a, b) + weight(h, b, a);
                assert!((s - 1.0).abs() < 1e-6, "{h:?} {a} {b}: {s}");
            }
        }
        assert_eq!(power(0.0, 0.0), 0.0);
        assert_eq!(power(f32::INFINITY, 1.0), 0.0);
        assert_eq!(power(1.0, 0.0), 1.0);
    }
}
