//! The automatic camera's eye: every scene point inside the view pyramid, as close as that
//! allows, the image centred in both axes.

use glam::DVec3;

#[cfg(test)]
mod tests;

/// The eye, in the camera's axes `[right, up, back]` about `origin`, from which every point
/// lies inside a centred pyramid of half-widths `tan = [tx, ty]`, as close as that allows;
/// and the largest `back` coordinate of a point (the nearest point's).
///
/// With the eye at `(e_u, e_v, e_w)`, a point `(u, v, w)` is inside when `|u − e_u| ≤ tx·(e_w
/// − w)`, that is `e_u + tx·e_w ≥ u + tx·w` and `tx·e_w − e_u ≥ tx·w − u`. The tightest eye
/// meets the largest of each side: `e_w = (max(u + tx·w) + max(tx·w − u)) / (2 tx)` and `e_u`
/// half their difference (the extreme points at equal angles either side); the same in `v`,
/// and the farther `e_w` of the two axes binds.
pub(super) fn fit_eye(
    points: &[DVec3],
    origin: DVec3,
    axes: [DVec3; 3],
    tan: [f64; 2],
) -> ([f64; 3], f64) {
    let [right, up, back] = axes;
    let mut most = [f64::NEG_INFINITY; 4];
    let mut nearest = f64::NEG_INFINITY;
    for p in points {
        let d = *p - origin;
        let (u, v, w) = (d.dot(right), d.dot(up), d.dot(back));
        most[0] = most[0].max(u + tan[0] * w);
        most[1] = most[1].max(tan[0] * w - u);
        most[2] = most[2].max(v + tan[1] * w);
        most[3] = most[3].max(tan[1] * w - v);
        nearest = nearest.max(w);
    }
    let e_w = ((most[0] + most[1]) / (2.0 * tan[0])).max((most[2] + most[3]) / (2.0 * tan[1]));
    let local: Vec<[f64; 3]> = points
        .iter()
        .map(|p| {
            let d = *p - origin;
            [d.dot(right), d.dot(up), e_w - d.dot(back)]
        })
        .collect();
    let e_u = centring_shift(&local, 0, (most[0] - most[1]) / 2.0);
    let e_v = centring_shift(&local, 1, (most[2] - most[3]) / 2.0);
    ([e_u, e_v, e_w], nearest)
}

/// The eye's shift along image axis `axis` (0: right, 1: up) that centres the points' image:
/// the largest and the smallest `(c − e) / depth` equal and opposite. In the axis that binds
/// [`fit_eye`]'s closed form is that shift (`guess`); in the other the points lie at several
/// depths, so it is found by bisection ([`HALVINGS`] halvings of a bracket; the sum of the
/// two extremes falls as `e` grows). `local` holds each point's right, up and depth from the
/// eye's plane.
///
/// The first [`WEIGHED_IN_FULL`] halvings weigh every point; the later ones only those that
/// can still hold an extreme in the narrowed bracket ([`Bracket`]), and so decide, and return
/// to the bit, what weighing every point at every step does.
fn centring_shift(local: &[[f64; 3]], axis: usize, guess: f64) -> f64 {
    let imbalance =
        |e: f64| Extremes::of(local.iter().map(|p| slope(p[axis], p[2], e))).imbalance();
    let span = local
        .iter()
        .map(|p| (p[axis] - guess).abs())
        .fold(0.0, f64::max);
    let (mut lo, mut hi) = (guess - span, guess + span);
    if span.is_nan() || span <= 0.0 || imbalance(lo) < 0.0 || imbalance(hi) > 0.0 {
        return guess;
    }
    for _ in 0..WEIGHED_IN_FULL {
        let mid = 0.5 * (lo + hi);
        if imbalance(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let mut bracket = Bracket::new(local, axis, lo, hi);
    for _ in WEIGHED_IN_FULL..HALVINGS {
        bracket.halve();
    }
    bracket.centre()
}

/// How many times [`centring_shift`] halves its bracket.
const HALVINGS: usize = 60;

/// How many of the [`HALVINGS`] weigh every point: before them the bracket is so wide that
/// nearly every point may hold an extreme somewhere in it (on the Stanford bunny, a third of
/// the points still may after two, an eighth after three).
const WEIGHED_IN_FULL: usize = 3;

/// A point's slope `(c − e) / depth` at the shift `e`, `c` its coordinate along the axis.
fn slope(c: f64, depth: f64, e: f64) -> f64 {
    (c - e) / depth
}

/// The smallest and the largest of some slopes, NaNs left out (as `f64::min` and `max` leave
/// them; of a `+0` and a `−0`, the first).
#[derive(Clone, Copy)]
struct Extremes {
    least: f64,
    most: f64,
}

impl Extremes {
    /// Of no slope.
    const NONE: Extremes = Extremes {
        least: f64::INFINITY,
        most: f64::NEG_INFINITY,
    };

    /// With `slope` too.
    fn with(self, slope: f64) -> Extremes {
        Extremes {
            least: if slope < self.least {
                slope
            } else {
                self.least
            },
            most: if slope > self.most { slope } else { self.most },
        }
    }

    /// Of `slopes`.
    fn of(slopes: impl Iterator<Item = f64>) -> Extremes {
        slopes.fold(Extremes::NONE, Extremes::with)
    }

    /// Their sum: positive while the image leans to the larger side.
    fn imbalance(self) -> f64 {
        self.least + self.most
    }
}

/// Whether a point's computed slope over a bracket lies between its slopes at the ends:
/// `fl(c − e)` falls as `e` grows and dividing by a positive `depth` keeps the order (rounding
/// is monotone), and neither is NaN for a finite `c`, a finite positive `depth` and any `e`
/// but NaN.
fn bounded(c: f64, depth: f64) -> bool {
    c.is_finite() && depth.is_finite() && depth > 0.0
}

/// A bounded point still weighed by a [`Bracket`], with its slopes at the bracket's ends.
struct Candidate {
    /// Coordinate along the axis.
    c: f64,
    /// Depth from the eye's plane.
    depth: f64,
    /// Slope at the bracket's low end.
    at_lo: f64,
    /// Slope at the bracket's high end.
    at_hi: f64,
    /// Slope at the bracket's middle, while a halving weighs it.
    at_mid: f64,
}

impl Candidate {
    /// Whether it may still hold the smallest slope (its least is not above `least_top`, the
    /// smallest greatest) or the largest (its greatest is not below `most_bottom`).
    fn may_be_extreme(&self, least_top: f64, most_bottom: f64) -> bool {
        self.at_hi <= least_top || self.at_lo >= most_bottom
    }
}

/// The bisection's bracket `[lo, hi]`, the [`bounded`] points that can still hold the
/// smallest or the largest slope somewhere in it, and the other points.
///
/// A bounded point `i` has, at every `e` in the bracket, a computed slope `s_i(e)` in
/// `[at_hi_i, at_lo_i]`. Let `k` have the smallest `at_lo` of the kept points: `at_hi_k ≤
/// at_lo_k`, so `k` stays. A point `i` with `at_hi_i > at_lo_k` then has `s_i(e) ≥ at_hi_i >
/// at_lo_k ≥ s_k(e)`, strictly above a kept point's slope at every `e` in the bracket: never
/// the smallest. Likewise a point whose `at_lo` is below the largest `at_hi` is never the
/// largest. The bracket drops the points that are neither ([`Candidate::may_be_extreme`]);
/// by the strict inequalities a point never drops its own witness, however many points tie.
/// The argument needs no rounding margin, for it compares the very values that weighing
/// every point would compute.
///
/// As the bracket shrinks its points stay in the old one, so a point dropped earlier stays
/// strictly beyond its witness, which stays strictly beyond a kept point if dropped itself.
/// The smallest and the largest slope of the kept and the other points are therefore, at
/// every `e` in the bracket, those of all points (at most up to the sign of a zero, which
/// their sum's sign does not see), and so is each halving's decision. The kept points answer
/// only for a middle inside the bracket: any other (once `lo + hi` overflowed) is weighed
/// over all points, and the points are taken up again.
struct Bracket<'a> {
    /// Every point: right, up, depth.
    local: &'a [[f64; 3]],
    /// Which coordinate of `local` is `c`.
    axis: usize,
    /// Low end.
    lo: f64,
    /// High end.
    hi: f64,
    /// The bounded points that may hold an extreme in `[lo, hi]`.
    kept: Vec<Candidate>,
    /// The smallest `at_lo` of the kept points (the point holding it is never dropped).
    least_top: f64,
    /// The largest `at_hi` of the kept points (the point holding it is never dropped).
    most_bottom: f64,
    /// The other points' coordinates and depths, weighed at every step.
    others: Vec<[f64; 2]>,
}

impl<'a> Bracket<'a> {
    /// The bracket `[lo, hi]` with the points of `local` that may hold an extreme in it.
    ///
    /// A point is weighed against the thresholds of the points before it, which are those of
    /// kept points (the point that sets one passes), so it is dropped only beyond a kept point.
    fn new(local: &'a [[f64; 3]], axis: usize, lo: f64, hi: f64) -> Bracket<'a> {
        let (mut tops, mut bottoms) = (Extremes::NONE, Extremes::NONE);
        let (mut kept, mut others) = (Vec::new(), Vec::new());
        for p in local {
            let (c, depth) = (p[axis], p[2]);
            if !bounded(c, depth) {
                others.push([c, depth]);
                continue;
            }
            let candidate = Candidate {
                c,
                depth,
                at_lo: slope(c, depth, lo),
                at_hi: slope(c, depth, hi),
                at_mid: f64::NAN,
            };
            (tops, bottoms) = (tops.with(candidate.at_lo), bottoms.with(candidate.at_hi));
            if candidate.may_be_extreme(tops.least, bottoms.most) {
                kept.push(candidate);
            }
        }
        Bracket {
            local,
            axis,
            lo,
            hi,
            kept,
            least_top: tops.least,
            most_bottom: bottoms.most,
            others,
        }
    }

    /// The middle of the bracket.
    fn centre(&self) -> f64 {
        0.5 * (self.lo + self.hi)
    }

    /// Keeps the half where the imbalance changes sign, and drops the points that can no
    /// longer hold an extreme in it.
    fn halve(&mut self) {
        let mid = self.centre();
        if !(self.lo <= mid && mid <= self.hi) {
            let axis = self.axis;
            let slopes = self.local.iter().map(|p| slope(p[axis], p[2], mid));
            let (lo, hi) = if Extremes::of(slopes).imbalance() > 0.0 {
                (mid, self.hi)
            } else {
                (self.lo, mid)
            };
            *self = Bracket::new(self.local, axis, lo, hi);
            return;
        }
        let mut at_mid = Extremes::NONE;
        for c in &mut self.kept {
            c.at_mid = slope(c.c, c.depth, mid);
            at_mid = at_mid.with(c.at_mid);
        }
        let others = self.others.iter().map(|&[c, depth]| slope(c, depth, mid));
        let rises = others.fold(at_mid, Extremes::with).imbalance() > 0.0;
        if rises {
            (self.lo, self.least_top) = (mid, at_mid.least);
        } else {
            (self.hi, self.most_bottom) = (mid, at_mid.most);
        }
        let (least_top, most_bottom) = (self.least_top, self.most_bottom);
        self.kept.retain_mut(|c| {
            if rises {
                c.at_lo = c.at_mid;
            } else {
                c.at_hi = c.at_mid;
            }
            c.may_be_extreme(least_top, most_bottom)
        });
    }
}
