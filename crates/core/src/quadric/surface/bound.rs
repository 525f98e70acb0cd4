//! The error bound of a ray/quadric crossing ([`Quadric::bound_roots`]).
//!
//! # What is bounded
//! The exact surface is the file's `Q`, `P`, `R` and clip box (as read into f64) placed by the
//! node matrix `[A* | T*]`, both taken as exact: the f64 matrix `[A | T]` as read, or for a
//! nested glTF node the exact product of its ancestors' matrices, within the entrywise bound
//! `[E_A | E_T]` of the f64 composition ([`crate::bound::transform`]). With the anchor
//! `c* = A*·a + T*` (`a` the local anchor, any fixed point; within `E_A|a| + E_T` of the f64
//! `A·a + T` beyond that product's own rounding) the exact local ray is `x₀* = A*⁻¹(o − c*)`,
//! `v* = A*⁻¹d` (the residual of [`crate::bound::mapped`] gains `E_A|x|`, and `‖A*⁻¹‖∞` is
//! bounded from `‖A⁻¹‖∞` by [`crate::bound::transform::perturbed_inverse_norm`]), and the exact
//! crossings are the roots of `g*(t) = K*t² + L*t + M*` for the polynomial about `a`: `Q`,
//! `∇f(a) = 2Qa + P`, `f(a)`. The same `t` in every frame.
//!
//! # Derivation
//! - The computed anchor, `∇f(a)` and `f(a)` carry the [`Bounded`] errors of their f64
//!   evaluation (kept from [`Quadric::new`]); the power-of-two normalisation is exact.
//! - `A⁻¹` is applied as the f64 inverse `L`: the computed `x₀ = L(o − c)` is within
//!   `‖A⁻¹‖∞(‖r‖∞ + e)` of the exact `A⁻¹(o − c*)`, `r = (o − c) − A·x₀` the residual evaluated in
//!   [`Bounded`] arithmetic and `e` the bound of `o − c` ([`crate::bound::mapped`]; `‖A⁻¹‖∞ ≤
//!   ‖L‖∞/(1 − ‖I − LA‖∞)`, [`crate::bound::inverse_norm`]); the same for `v = L d`.
//! - `K`, `L`, `M` are recomputed in [`Bounded`] arithmetic in the operations' order.
//! - A computed root `t` is checked, not propagated through the root formula (which loses the
//!   bound near tangents): `G ≥ |g*(t)|` from the bounded coefficients, `m₀ ≤ |g*'(t)|`. On
//!   `[t − r, t + r]`, `r = 2G/m₀`, `|g*'| ≥ m = m₀ − 2|K*|r`; if `m > 0` and `G/m ≤ r`, `g*` is
//!   monotonic there and changes sign, so exactly one exact root lies within `G/m` of `t`
//!   (*isolated*). Otherwise, if `K*` is certainly not zero and the exact roots are real, the
//!   nearer one is within `√(G/|K*|)` (`|g*(t)| = |K*||t − r₁||t − r₂|`): a bound, but the
//!   crossing is not isolated (a tangent ray), so no decision taken near it is certain.
//! - With two isolated roots, they are all of `g*`'s. With one, the other is `−L*/K* − t*`
//!   (Vieta) when `K*` is certainly not zero, else at least `(|L*| − …)/|K*|` away. With none,
//!   the ray certainly misses when the bounded `Δ = L² − 4KM` is certainly negative.
//! - The clip test is made against the clip box as the file gives it (not widened), with the
//!   bounded local point `x₀ + t·v + a`.

use super::Quadric;
use crate::bound::bounded::{bounded3, down, exact3, gamma, mat_vec, rows3, up, BVec3, Bounded};
use crate::bound::transform::BoundedMat4;
use crate::bound::{mapped, Side};
use crate::simd::with_avx2;
use glam::{DMat3, DVec3};
use std::ops::{Add, Div, Mul, Neg, Sub};
use std::sync::OnceLock;

/// Bounds of the numbers a quadric's intersection starts from, kept by [`Quadric::new`].
#[derive(Debug, Clone, PartialEq)]
pub(in crate::quadric) struct Errors {
    /// The object→world linear map `A`, a bound on its entries' distance from the exactly
    /// composed one ([`crate::bound::transform`]), and a bound on `‖A*⁻¹‖∞` for every `A*`
    /// within it.
    pub linear: DMat3,
    pub linear_error: DMat3,
    pub inverse_norm: f64,
    /// Bound on each component of the computed anchor.
    pub anchor: DVec3,
    /// Bounds on the local polynomial's `P` (normalised) components and `R`.
    pub gradient: DVec3,
    pub constant: f64,
    /// The clip box as the file gives it (local coordinates).
    pub clip: Option<[DVec3; 2]>,
}

/// One computed root with its bound.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RootBound {
    /// The root and a bound on its distance from the nearest exact root.
    pub t: Bounded,
    /// Whether exactly one exact root lies within the bound (see the module docs).
    pub isolated: bool,
    /// Where the exact crossing lies against the clip box.
    pub clip: Side,
}

/// Where exact roots other than the listed ones may lie.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Others {
    /// Nowhere: the listed roots are all of them.
    None,
    /// In this interval (value ± error).
    Within(Bounded),
    /// At `|t| ≥` this.
    Beyond(f64),
    /// Anywhere.
    Unknown,
}

/// The bounded crossings of one ray with a quadric's surface (clipped or not).
#[derive(Debug, Clone, PartialEq)]
pub struct QuadricBound {
    /// The roots the intersection computes, nearest first.
    pub roots: Vec<RootBound>,
    /// Where other exact roots may be.
    pub others: Others,
}

/// What [`Errors`] are made from, kept by [`Quadric::new`] and turned into them the first time
/// a bound is asked for: a run without the `error` and `certain` AOVs never pays for them (a
/// pointer per quadric, and a copy of its spec and matrix).
#[derive(Debug, Clone)]
pub(in crate::quadric) struct LazyErrors(Box<(ErrorInputs, OnceLock<Errors>)>);

/// The quadric's spec as read, its object→world matrix and the power-of-two normalisation of
/// its local polynomial.
#[derive(Debug, Clone, PartialEq)]
struct ErrorInputs {
    spec: crate::quadric::QuadricSpec,
    world: BoundedMat4,
    scale: [f64; 2],
}

impl PartialEq for LazyErrors {
    /// Equal inputs make equal bounds.
    fn eq(&self, other: &LazyErrors) -> bool {
        self.0 .0 == other.0 .0
    }
}

impl LazyErrors {
    /// Keeps the inputs; nothing is computed yet.
    pub fn new(spec: &crate::quadric::QuadricSpec, world: BoundedMat4, scale: [f64; 2]) -> Self {
        let inputs = ErrorInputs {
            spec: spec.clone(),
            world,
            scale,
        };
        LazyErrors(Box::new((inputs, OnceLock::new())))
    }

    /// The same inputs with the node matrix's bound from its composition.
    pub fn composed(mut self, world: BoundedMat4) -> Self {
        self.0 .0.world = world;
        self.0 .1 = OnceLock::new();
        self
    }
}

impl Errors {
    /// The bounds for a quadric with local polynomial coefficients `gradient` and `constant`
    /// (as computed, before normalisation by `scale`), `spec_q`, the local anchor, the
    /// object→world matrix's linear part and translation and its f64 inverse.
    fn new(
        spec: &crate::quadric::QuadricSpec,
        local_anchor: DVec3,
        placement: &BoundedMat4,
        to_local: DMat3,
        scale: [f64; 2],
    ) -> Errors {
        let world = placement.value;
        let linear = DMat3::from_mat4(world);
        let linear_error = DMat3::from_mat4(placement.error);
        let a = exact3(local_anchor);
        let q = rows3(spec.q, 0.0);
        let qa = mat_vec(&q, &a);
        let gradient = [0, 1, 2].map(|i| {
            Bounded::exact(2.0)
                .mul(qa[i])
                .add(Bounded::exact(spec.p[i]))
        });
        let constant = crate::bound::bounded::dot3(&a, &qa)
            .add(crate::bound::bounded::dot3(&exact3(spec.p), &a))
            .add(Bounded::exact(spec.r));
        let scaled = |e: f64| up(up(e * scale[0]) * scale[1]);
        let placed = mat_vec(&rows3(linear, 0.0), &a);
        let translation = world.w_axis.truncate();
        let composed = crate::bound::transform::moved(&placement.error, local_anchor);
        let anchor = [0, 1, 2].map(|i| {
            let rounded = placed[i].add(Bounded::exact(translation[i])).error;
            if composed == 0.0 {
                rounded
            } else {
                up(rounded + composed)
            }
        });
        let norm = crate::bound::inverse_norm(linear, to_local);
        Errors {
            linear,
            linear_error,
            inverse_norm: crate::bound::transform::perturbed_inverse_norm(norm, &linear_error),
            anchor: DVec3::from_array(anchor),
            gradient: DVec3::from_array(gradient.map(|g| scaled(g.error))),
            constant: scaled(constant.error),
            clip: spec.bounds,
        }
    }
}

/// The quadratic `K t² + L t + M` along the ray, bounded.
struct Coefficients {
    k: Bounded,
    l: Bounded,
    m: Bounded,
}

impl Quadric {
    /// The bounds of the quadric's numbers ([`Errors`]), made on the first call.
    fn errors(&self) -> &Errors {
        let (inputs, errors) = &*self.errors.0;
        errors.get_or_init(|| {
            let (spec, world) = (&inputs.spec, inputs.world);
            Errors::new(spec, self.local_anchor, &world, self.to_local, inputs.scale)
        })
    }

    /// The quadric with the bound of its node matrix's composition from nested nodes
    /// ([`crate::bound::transform`]); `world.value` must be the matrix it was placed by.
    pub fn with_composition(mut self, world: &BoundedMat4) -> Quadric {
        self.errors = self.errors.composed(*world);
        self
    }

    /// The crossings of the world ray `origin + t·dir` (exact numbers) with the quadric's
    /// whole surface, the roots as [`Quadric::intersect`] computes them, each with its bound
    /// and its place against the clip box (see the module docs). Compiled for AVX2 and FMA where
    /// the CPU has them ([`with_avx2`]), as is [`Quadric::bound_root_at`].
    pub fn bound_roots(&self, origin: DVec3, dir: DVec3) -> QuadricBound {
        with_avx2(
            #[inline(always)]
            || self.bound_roots_here(&self.bounded_origin_here(origin), origin, dir),
        )
    }

    /// [`Quadric::bound_roots`] with the bounded local origin already made
    /// ([`Quadric::bounded_origin`] of `origin`).
    pub fn bound_roots_from(&self, x0b: &BVec3, origin: DVec3, dir: DVec3) -> QuadricBound {
        with_avx2(
            #[inline(always)]
            || self.bound_roots_here(x0b, origin, dir),
        )
    }

    /// [`Quadric::bound_roots`], inlined into its caller.
    #[inline(always)]
    fn bound_roots_here(&self, x0b: &BVec3, origin: DVec3, dir: DVec3) -> QuadricBound {
        let x0 = self.to_local * (origin - self.anchor);
        let v = self.to_local * dir;
        let (x0b, vb) = (*x0b, self.bounded_dir(dir));
        let c = self.coefficients(&x0b, &vb);
        let Some(roots) = self.local.ray_roots(x0, v) else {
            let disc = c.l.mul(c.l).sub(Bounded::exact(4.0).mul(c.k).mul(c.m));
            let none = disc.value + disc.error < 0.0;
            return QuadricBound {
                roots: Vec::new(),
                others: if none { Others::None } else { Others::Unknown },
            };
        };
        // Pushed one by one: an iterator's fold would be compiled apart, without FMA.
        let mut bounded = Vec::with_capacity(2);
        bounded.push(self.root_bound(roots[0], &c, &x0b, &vb));
        if roots[1] != roots[0] {
            bounded.push(self.root_bound(roots[1], &c, &x0b, &vb));
        }
        let others = others(&bounded, &c);
        QuadricBound {
            roots: bounded,
            others,
        }
    }

    /// Whether the exact ray `origin + t·dir` may meet the clipped surface with `0 <= t <=
    /// limit`: the trace's bounds pre-test ([`crate::geometry::ReachBox::may_reach`]), whose
    /// margin (1e-9 of the box and the origin's distance) is far above the rounding of the
    /// bounds and of the slab test, so it holds for the exact surface and ray too.
    pub fn may_reach(&self, origin: DVec3, dir: DVec3, limit: f64) -> bool {
        self.may_reach_bounds(origin, dir.recip(), limit)
    }

    /// The local origin as computed, `x₀ = L(o − c)`, bounded ([`crate::bound::mapped`]): the
    /// part of a ray's mapping that rays from one point share (see
    /// [`crate::scene::Origins`]); with FMA where the CPU has it ([`with_avx2`]).
    pub fn bounded_origin(&self, origin: DVec3) -> BVec3 {
        with_avx2(
            #[inline(always)]
            || self.bounded_origin_here(origin),
        )
    }

    /// [`Quadric::bounded_origin`], inlined into its caller.
    #[inline(always)]
    fn bounded_origin_here(&self, origin: DVec3) -> BVec3 {
        let e = self.errors();
        let anchor = bounded3(self.anchor, e.anchor);
        let from = exact3(origin);
        let offset = [
            from[0].sub(anchor[0]),
            from[1].sub(anchor[1]),
            from[2].sub(anchor[2]),
        ];
        let x0 = self.to_local * (origin - self.anchor);
        mapped(e.linear, &e.linear_error, e.inverse_norm, &offset, x0)
    }

    /// The local direction as computed, `v = L d`, bounded ([`crate::bound::mapped`]).
    #[inline(always)]
    fn bounded_dir(&self, dir: DVec3) -> BVec3 {
        let e = self.errors();
        let v = self.to_local * dir;
        mapped(e.linear, &e.linear_error, e.inverse_norm, &exact3(dir), v)
    }

    /// `K`, `L`, `M` of the local polynomial along the bounded ray.
    #[inline(always)]
    fn coefficients(&self, x0: &BVec3, v: &BVec3) -> Coefficients {
        use crate::bound::bounded::dot3;
        let q = rows3(self.local.q, 0.0);
        let p = bounded3(self.local.p, self.errors().gradient);
        let r = Bounded::new(self.local.r, self.errors().constant);
        let qv = mat_vec(&q, v);
        let two = Bounded::exact(2.0);
        Coefficients {
            k: dot3(v, &qv),
            l: two.mul(dot3(x0, &qv)).add(dot3(&p, v)),
            m: dot3(x0, &mat_vec(&q, x0)).add(dot3(&p, x0)).add(r),
        }
    }

    /// `g*(t) = f(x₀ + t·v)` and `g*'(t) = ∇f(x₀ + t·v)·v`, bounded. Evaluated at the point
    /// rather than from `K`, `L`, `M`: the errors of the start point then enter weighted by the
    /// gradient at the crossing, not by the (larger) gradient at the ray's origin.
    #[inline(always)]
    fn value_and_slope(&self, t: f64, x0: &BVec3, v: &BVec3) -> (Bounded, Bounded) {
        use crate::bound::bounded::dot3;
        let tb = Bounded::exact(t);
        let along = |i: usize| x0[i].add(tb.mul(v[i]));
        let point: BVec3 = [along(0), along(1), along(2)];
        let q = rows3(self.local.q, 0.0);
        let p = bounded3(self.local.p, self.errors().gradient);
        let r = Bounded::new(self.local.r, self.errors().constant);
        let qp = mat_vec(&q, &point);
        let value = dot3(&point, &qp).add(dot3(&p, &point)).add(r);
        let slope = |i: usize| Bounded::exact(2.0).mul(qp[i]).add(p[i]);
        let gradient: BVec3 = [slope(0), slope(1), slope(2)];
        (value, dot3(&gradient, v))
    }

    /// A bound on the distance from `t` (a reported crossing of the world ray `origin +
    /// t·dir`, `x0` its [`Quadric::bounded_origin`]) to the nearest exact root, and whether
    /// exactly one exact root lies within it (see the module docs): the check of one root,
    /// without the other root, the clip box or the other coefficients that
    /// [`Quadric::bound_roots`] adds for a decision.
    pub fn bound_root_at(&self, x0: &BVec3, dir: DVec3, t: f64) -> (f64, bool) {
        with_avx2(
            #[inline(always)]
            || {
                let v = self.bounded_dir(dir);
                let q = rows3(self.local.q, 0.0);
                let k = crate::bound::bounded::dot3(&v, &mat_vec(&q, &v));
                let (value, slope) = self.value_and_slope(t, x0, &v);
                isolate(value, slope, k)
            },
        )
    }

    /// The bound of the computed root `t` (see the module docs) and its clip side.
    #[inline(always)]
    fn root_bound(&self, t: f64, c: &Coefficients, x0: &BVec3, v: &BVec3) -> RootBound {
        let (value, slope) = self.value_and_slope(t, x0, v);
        let (bound, isolated) = isolate(value, slope, c.k);
        let root = Bounded::new(t, bound);
        RootBound {
            t: root,
            isolated,
            clip: self.clip_side(root, x0, v),
        }
    }

    /// Where the exact point `x₀ + t·v + a` lies against the file's clip box.
    #[inline(always)]
    fn clip_side(&self, t: Bounded, x0: &BVec3, v: &BVec3) -> Side {
        let Some([min, max]) = self.errors().clip else {
            return Side::Inside;
        };
        if !t.error.is_finite() {
            return Side::Edge;
        }
        let mut side = Side::Inside;
        for i in 0..3 {
            let x = x0[i]
                .add(t.mul(v[i]))
                .add(Bounded::exact(self.local_anchor[i]));
            let (lo, hi) = (x.value - x.error, x.value + x.error);
            if hi < min[i] || lo > max[i] {
                return Side::Outside;
            }
            if !(lo > min[i] && hi < max[i]) {
                side = Side::Edge;
            }
        }
        side
    }
}

/// From `g*(t)` (`value`), `g*'(t)` (`slope`) and `K*`, all bounded: a bound on the distance
/// from `t` to the nearest exact root, and whether exactly one exact root lies within it (see
/// the module docs).
#[inline(always)]
fn isolate(value: Bounded, slope: Bounded, k: Bounded) -> (f64, bool) {
    let g = value.magnitude();
    let m0 = down(slope.value.abs() - slope.error);
    let mut bound = f64::INFINITY;
    let mut isolated = false;
    if m0 > 0.0 {
        let r = up(2.0 * g / m0);
        let m = down(m0 - up(2.0 * k.magnitude() * r));
        if m > 0.0 && up(g / m) <= r {
            bound = up(g / m);
            isolated = true;
        }
    }
    let k_low = down(k.value.abs() - k.error);
    if k_low > 0.0 {
        bound = bound.min(up(up(g / k_low).sqrt() * (1.0 + gamma(2))));
    }
    (bound, isolated)
}

/// Where exact roots other than `roots` may lie (see the module docs).
#[inline(always)]
fn others(roots: &[RootBound], c: &Coefficients) -> Others {
    match roots {
        [a, b] if a.isolated && b.isolated && a.t.value + a.t.error < b.t.value - b.t.error => {
            Others::None
        }
        [a] if a.isolated => {
            if c.k.sign_certain() {
                Others::Within(c.l.div(c.k).neg().sub(a.t))
            } else {
                let reach = down(c.l.value.abs() - c.l.error) / up(c.k.magnitude());
                Others::Beyond(down(down(reach) - a.t.magnitude()))
            }
        }
        _ => Others::Unknown,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadric::QuadricSpec;
    use glam::DMat4;

    fn sphere_at(centre: DVec3, bounds: Option<[DVec3; 2]>) -> Quadric {
        let spec = QuadricSpec::from_coefficients(
            [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
            bounds,
        )
        .unwrap();
        Quadric::new(&spec, DMat4::from_translation(centre)).unwrap()
    }

    /// A unit sphere 1e7 from the origin, hit head-on from 10 units above its centre: the
    /// exact roots are t = 9 and 11 (analysis); both are isolated, each bound covers its root
    /// and is at most a few hundred ulps of the distance travelled.
    #[test]
    fn far_sphere_roots_are_isolated_and_contain_the_exact_ones() {
        let centre = DVec3::new(1e7, 0.0, 0.0);
        let q = sphere_at(centre, None);
        let b = q.bound_roots(centre + DVec3::new(0.0, 0.0, 10.0), DVec3::NEG_Z);
        assert_eq!(b.others, Others::None);
        for (root, exact) in b.roots.iter().zip([9.0, 11.0]) {
            assert!(root.isolated && root.clip == Side::Inside, "{root:?}");
            assert!((root.t.value - exact).abs() <= root.t.error, "{root:?}");
            assert!(root.t.error < 1e-12, "{root:?}");
        }
    }

    /// A ray tangent to the sphere (the double root t = 5) is not isolated.
    #[test]
    fn tangent_rays_are_not_isolated() {
        let q = sphere_at(DVec3::ZERO, None);
        let b = q.bound_roots(DVec3::new(1.0, 0.0, 5.0), DVec3::NEG_Z);
        assert!(b.roots.iter().all(|r| !r.isolated), "{b:?}");
        assert_eq!(b.others, Others::Unknown);
    }

    /// The bounds compiled with FMA ([`with_avx2`], on a CPU that has it) are those of the
    /// same code compiled without (the runtime's `fma`), bit for bit: random quadrics of every
    /// sign pattern, placed by random matrices, against random rays.
    #[test]
    fn the_fma_build_gives_the_same_bits() {
        let mut rng = crate::test_rng::Rng(0x5eed_f3a5);
        let mut roots = 0;
        for _ in 0..300 {
            let c = std::array::from_fn(|_| rng.uniform(-2.0, 2.0));
            let cut = Some([rng.point(-3.0, -0.5), rng.point(0.5, 3.0)]);
            let Ok(spec) = QuadricSpec::from_coefficients(c, cut) else {
                continue;
            };
            let (axes, move_by) = (rng.point(0.2, 3.0), rng.point(-1e3, 1e3));
            let turn = glam::DQuat::from_euler(
                glam::EulerRot::XYZ,
                rng.uniform(-3.0, 3.0),
                rng.uniform(-3.0, 3.0),
                rng.uniform(-3.0, 3.0),
            );
            let matrix = DMat4::from_scale_rotation_translation(axes, turn, move_by);
            let Ok(q) = Quadric::new(&spec, matrix) else {
                continue;
            };
            for _ in 0..10 {
                let origin = move_by + rng.point(-8.0, 8.0);
                let dir = move_by + rng.point(-1.0, 1.0) - origin;
                let fused = q.bound_roots(origin, dir);
                assert_eq!(
                    fused,
                    q.bound_roots_here(&q.bounded_origin_here(origin), origin, dir)
                );
                roots += fused.roots.len();
            }
        }
        assert!(roots > 1000, "{roots} roots");
    }

    /// A crossing on a face of the clip box is at its edge; one well inside or outside is
    /// certain.
    #[test]
    fn clip_box_faces_are_edges() {
        let cut = [DVec3::splat(-2.0), DVec3::new(2.0, 2.0, 0.5)];
        let q = sphere_at(DVec3::ZERO, Some(cut));
        // Down the z axis: roots at z = 1 (outside the box, z <= 0.5) and z = -1 (inside).
        let b = q.bound_roots(DVec3::new(0.0, 0.0, 5.0), DVec3::NEG_Z);
        assert_eq!(b.roots[0].clip, Side::Outside);
        assert_eq!(b.roots[1].clip, Side::Inside);
        // Through the circle z = 0.5, x = √0.75 (0.75 and 0.5 exact): on the face.
        let x = 0.75f64.sqrt();
        let b = q.bound_roots(DVec3::new(x, -5.0, 0.5), DVec3::Y);
        assert!(b.roots.iter().all(|r| r.clip == Side::Edge), "{b:?}");
    }
}
