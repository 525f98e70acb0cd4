//! The real roots of a polynomial of low degree, in f64, by isolation: the roots of the
//! derivative (found the same way) split the line into intervals where the polynomial is
//! monotone, and each interval whose ends differ in sign holds one root, found by
//! bisection. The bisection halves the interval in the order of the doubles (not of the
//! reals), so it ends after at most 64 halvings however wide the interval is. Roots are found
//! to a few ulps of the larger of their magnitude and 1.

/// Coefficients above this many times the largest one's bound on the roots' size are cut
/// off: `|x| ≤ 1 + max |cᵢ / cₙ|` (Cauchy), capped so that evaluating cannot overflow.
const LARGEST_ROOT: f64 = 1e100;

/// The real roots of `c[0] + c[1]·x + … + c[n]·xⁿ` in ascending order (a root of even
/// multiplicity, where the sign does not change, may be missed), and the roots of its
/// derivative found on the way (where such a root would lie).
pub(super) fn real_roots(c: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let degree = match c.iter().rposition(|&x| x != 0.0) {
        Some(d) => d,
        None => return (Vec::new(), Vec::new()),
    };
    let c = &c[..=degree];
    match degree {
        0 => (Vec::new(), Vec::new()),
        1 => (vec![-c[0] / c[1]], Vec::new()),
        _ => {
            let derivative: Vec<f64> = (1..=degree).map(|i| i as f64 * c[i]).collect();
            let (turns, _) = real_roots(&derivative);
            (roots_between_turns(c, &turns), turns)
        }
    }
}

/// The roots of `c` (degree at least 2) given the sorted roots of its derivative.
fn roots_between_turns(c: &[f64], turns: &[f64]) -> Vec<f64> {
    let lead = c[c.len() - 1];
    let bound = c[..c.len() - 1]
        .iter()
        .map(|x| (x / lead).abs())
        .fold(0.0, f64::max);
    let bound = (1.0 + bound).min(LARGEST_ROOT);
    let mut ends = vec![-bound];
    ends.extend(turns.iter().copied().filter(|t| t.abs() < bound));
    ends.push(bound);
    let mut roots = Vec::new();
    for pair in ends.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let (fa, fb) = (horner(c, a), horner(c, b));
        if fa == 0.0 {
            roots.push(a);
        } else if fb != 0.0 && (fa < 0.0) != (fb < 0.0) {
            roots.push(bisect(c, a, b, fa));
        }
    }
    if horner(c, bound) == 0.0 {
        roots.push(bound);
    }
    roots.dedup();
    roots
}

/// `c(x)` by Horner's rule (multiply, then add: `mul_add` is a library call on the baseline
/// x86-64 target, a tenth of the distance search's time).
fn horner(c: &[f64], x: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ci| acc * x + ci)
}

/// A root of `c` in `[a, b]`, where `c(a) = fa` and `c(b)` differ in strict sign: Illinois
/// steps (regula falsi, halving the value kept at an end that stays twice), every fourth
/// step a halving in the order of the doubles, until the ends are within a few ulps of the
/// larger of their magnitudes and 1 (the callers' roots are of size 1, `1 − x·κ` with
/// `|κ| ≤ 1` needing no more than that).
fn bisect(c: &[f64], mut a: f64, mut b: f64, mut fa: f64) -> f64 {
    let mut fb = horner(c, b);
    let mut kept = 0i8; // +1: `a` kept last step, −1: `b`.
    for step in 0..256 {
        if b - a <= 2.0 * f64::EPSILON * a.abs().max(b.abs()).max(1.0) {
            break;
        }
        let secant = a - fa * (b - a) / (fb - fa);
        let x = if step % 4 != 3 && secant > a && secant < b {
            secant
        } else {
            midpoint(a, b)
        };
        if x <= a || x >= b {
            break;
        }
        let fx = horner(c, x);
        if fx == 0.0 {
            return x;
        }
        if (fx < 0.0) == (fa < 0.0) {
            (a, fa) = (x, fx);
            if kept == -1 {
                fb *= 0.5;
            }
            kept = -1;
        } else {
            (b, fb) = (x, fx);
            if kept == 1 {
                fa *= 0.5;
            }
            kept = 1;
        }
    }
    if fa.abs() <= fb.abs() {
        a
    } else {
        b
    }
}

/// The double halfway between `a < b` in the order of the doubles.
fn midpoint(a: f64, b: f64) -> f64 {
    let (ka, kb) = (order_key(a), order_key(b));
    from_order_key(ka + (kb - ka) / 2)
}

/// A key that orders the doubles as the reals they stand for (−0 just below +0).
fn order_key(x: f64) -> u64 {
    let bits = x.to_bits();
    if bits >> 63 == 1 {
        !bits
    } else {
        bits | 1 << 63
    }
}

/// The inverse of [`order_key`].
fn from_order_key(k: u64) -> f64 {
    if k >> 63 == 1 {
        f64::from_bits(k & !(1 << 63))
    } else {
        f64::from_bits(!k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roots_of_products_of_known_factors() {
        // (x − 1)(x + 2)(x − 3e-9)(x − 1e6) expanded by hand.
        let r = [1.0, -2.0, 3e-9, 1e6];
        let mut c = vec![1.0];
        for root in r {
            let mut next = vec![0.0; c.len() + 1];
            for (i, ci) in c.iter().enumerate() {
                next[i + 1] += ci;
                next[i] -= root * ci;
            }
            c = next;
        }
        let (roots, _) = real_roots(&c);
        let mut want = r.to_vec();
        want.sort_by(f64::total_cmp);
        assert_eq!(roots.len(), 4, "{roots:?}");
        for (got, want) in roots.iter().zip(want) {
            assert!(
                (got - want).abs() <= 1e-12 * want.abs().max(1.0),
                "{got} {want}"
            );
        }
    }

    #[test]
    fn no_real_roots_and_a_linear_one() {
        assert!(real_roots(&[1.0, 0.0, 1.0]).0.is_empty());
        assert_eq!(real_roots(&[3.0, -1.5, 0.0]).0, vec![2.0]);
        assert!(real_roots(&[0.0, 0.0]).0.is_empty());
    }

    #[test]
    fn halving_in_the_order_of_the_doubles() {
        for (a, b) in [(-1e300, 1e300), (1e-300, 1e300), (-2.0, -1.0), (-0.0, 0.0)] {
            let m = midpoint(a, b);
            assert!(a <= m && m <= b, "{a} {m} {b}");
            assert_eq!(from_order_key(order_key(a)).to_bits(), a.to_bits());
        }
        assert_eq!(midpoint(1.0, 1.0f64.next_up()), 1.0);
    }
}
