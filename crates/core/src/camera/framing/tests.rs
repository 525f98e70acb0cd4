//! The pruned bisection against the plain one, to the bit.

use super::centring_shift;
use crate::test_rng::Rng;

/// The plain bisection, every point weighed at every step: the oracle.
fn reference(local: &[[f64; 3]], axis: usize, guess: f64) -> f64 {
    let imbalance = |e: f64| {
        let (lo, hi) = local
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                let slope = (p[axis] - e) / p[2];
                (lo.min(slope), hi.max(slope))
            });
        lo + hi
    };
    let span = local
        .iter()
        .map(|p| (p[axis] - guess).abs())
        .fold(0.0, f64::max);
    let (mut lo, mut hi) = (guess - span, guess + span);
    if span.is_nan() || span <= 0.0 || imbalance(lo) < 0.0 || imbalance(hi) > 0.0 {
        return guess;
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if imbalance(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// A random cloud of one of several kinds, in the eye's frame (right, up, depth).
fn cloud(rng: &mut Rng, kind: usize) -> Vec<[f64; 3]> {
    let n = [1, 2, 3, 5, 20, 300][rng.below(6)];
    let point = |rng: &mut Rng| {
        [
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(0.2, 3.0),
        ]
    };
    let mut points: Vec<[f64; 3]> = (0..n).map(|_| point(rng)).collect();
    match kind {
        // near-ties: on rays from a few eyes, nudged by a few ulps
        0 => {
            let eyes = [rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5)];
            let slopes = [rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)];
            for p in &mut points {
                let (e, s) = (eyes[rng.below(2)], slopes[rng.below(2)]);
                p[0] = rng.nudge(e + s * p[2], 3);
                p[1] = rng.nudge(e - s * p[2], 3);
            }
        }
        // duplicated points, among them a distant one whose slope is flat over the last brackets
        1 => {
            let far = rng.uniform(-1.0, 1.0) * 1e12;
            points.push([far, -far, 1e12]);
            points.extend(points.clone());
        }
        // equal slopes about the origin: scaled copies
        2 => {
            for i in 0..n {
                let k = [0.5, 2.0, 3.0][rng.below(3)];
                points.push(points[i].map(|x| x * k));
            }
        }
        // huge, tiny and subnormal scales
        3 => {
            let scale = [1e300, 1e150, 1e-150, 1e-300, 1e-310][rng.below(5)];
            points.iter_mut().for_each(|p| *p = p.map(|x| x * scale));
        }
        // far off the origin along the axes, or far away in depth
        4 => {
            let offset = [1e9, -3e12, 1e15][rng.below(3)];
            for p in &mut points {
                p[0] += offset;
                p[1] -= offset;
                p[2] += offset.abs() * rng.below(2) as f64;
            }
        }
        // depths at and about zero, as an extreme point at the eye's depth gives
        5 => {
            for p in &mut points {
                p[2] = [0.0, 1e-300, -1e-300, -1e-17, p[2]][rng.below(5)];
            }
        }
        // a few non-finite coordinates
        6 => {
            let i = rng.below(n);
            points[i][rng.below(3)] = [f64::INFINITY, f64::NEG_INFINITY, f64::NAN][rng.below(3)];
        }
        // points on a few depths: the binding axis's shape
        7 => {
            let depths = [rng.uniform(0.2, 3.0), rng.uniform(0.2, 3.0)];
            points.iter_mut().for_each(|p| p[2] = depths[rng.below(2)]);
        }
        _ => {}
    }
    points
}

/// A starting guess for `points` along `axis`: near their middle, one of them, or far off.
fn guess(rng: &mut Rng, points: &[[f64; 3]], axis: usize) -> f64 {
    let p = points[rng.below(points.len())];
    match rng.below(4) {
        0 => p[axis],
        1 => p[axis] * rng.uniform(-2.0, 2.0),
        2 => rng.uniform(-0.1, 0.1),
        _ => [1e308, -1e308, f64::INFINITY, 0.0][rng.below(4)],
    }
}

#[test]
fn centring_shift_matches_the_plain_bisection_to_the_bit() {
    let mut rng = Rng(0x5eed_f4a3);
    let mut bisected = 0;
    for case in 0..20_000 {
        let kind = case % 9;
        let points = cloud(&mut rng, kind);
        let axis = rng.below(2);
        let guess = guess(&mut rng, &points, axis);
        let want = reference(&points, axis, guess);
        let got = centring_shift(&points, axis, guess);
        assert_eq!(
            got.to_bits(),
            want.to_bits(),
            "case {case} (kind {kind}), axis {axis}, guess {guess:e}: {got:e} != {want:e}, points {points:?}"
        );
        bisected += usize::from(want.to_bits() != guess.to_bits());
    }
    // most cases bisect rather than return the guess
    assert!(bisected > 10_000, "{bisected}");
}

#[test]
fn centring_shift_of_huge_brackets_matches_the_plain_bisection() {
    // lo + hi overflows after the full weighings (the middle leaves the bracket), or the
    // bracket is infinite from the start
    let cases = [
        (
            vec![[8.875963515261563e307, 1.0], [9.065909229378932e307, 1.0]],
            8.684065248854831e307,
        ),
        (
            vec![
                [9.011011869519526e307, 0.3693126730321834],
                [8.969087538090279e307, 6.773167867052998],
            ],
            8.602949505694981e307,
        ),
        (vec![[9e307, 1.0], [1e308, 2.0], [1.1e308, 0.5]], -1e308),
    ];
    for (points, guess) in cases {
        let points: Vec<[f64; 3]> = points.iter().map(|&[c, depth]| [c, 0.0, depth]).collect();
        let want = reference(&points, 0, guess);
        assert_eq!(centring_shift(&points, 0, guess).to_bits(), want.to_bits());
    }
}
