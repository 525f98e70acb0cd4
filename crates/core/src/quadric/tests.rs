//! Exact-expectation tests for the quadric module.

use glam::{DMat3, DMat4, DQuat, DVec3};

use super::{Quadric, QuadricKind, QuadricSpec};

/// Deterministic xorshift64* generator, so the random tests are reproducible.
struct Rng(u64);

impl Rng {
    /// A uniform number in `[lo, hi)`.
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
        lo + (hi - lo) * (bits as f64 / (1u64 << 53) as f64)
    }

    /// A vector with components uniform in `[lo, hi)`.
    fn vec3(&mut self, lo: f64, hi: f64) -> DVec3 {
        DVec3::new(
            self.uniform(lo, hi),
            self.uniform(lo, hi),
            self.uniform(lo, hi),
        )
    }

    /// A random rotation.
    fn rotation(&mut self) -> DQuat {
        let axis = self.vec3(-1.0, 1.0).normalize();
        DQuat::from_axis_angle(axis, self.uniform(-3.1, 3.1))
    }

    /// Translation · rotation · shear (up to 0.3) · non-uniform scale (0.5..2).
    fn transform(&mut self) -> DMat4 {
        let shear = DMat3::from_cols(
            DVec3::X,
            DVec3::new(self.uniform(-0.3, 0.3), 1.0, 0.0),
            DVec3::new(self.uniform(-0.3, 0.3), self.uniform(-0.3, 0.3), 1.0),
        );
        let scale = DMat3::from_diagonal(self.vec3(0.5, 2.0));
        let linear = DMat3::from_quat(self.rotation()) * shear * scale;
        let mut world = DMat4::from_mat3(linear);
        world.w_axis = self.vec3(-10.0, 10.0).extend(1.0);
        world
    }
}

/// A spec from ten coefficients, panicking on error.
fn coefficients(c: [f64; 10], bounds: Option<[DVec3; 2]>) -> QuadricSpec {
    QuadricSpec::from_coefficients(c, bounds).unwrap()
}

/// The cube `[-h, h]³`.
fn cube(h: f64) -> Option<[DVec3; 2]> {
    Some([DVec3::splat(-h), DVec3::splat(h)])
}

/// A quadric at the identity placement.
fn placed(spec: &QuadricSpec) -> Quadric {
    Quadric::new(spec, DMat4::IDENTITY).unwrap()
}

/// `|a − b| / |b|`.
fn relative(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn unit_sphere_from_both_forms_is_identical() {
    let a = coefficients([1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0], None);
    let b = QuadricSpec::from_matrices(
        [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        [0.0; 3],
        -1.0,
        None,
    )
    .unwrap();
    assert_eq!(a, b);
    let (qa, qb) = (placed(&a), placed(&b));
    assert_eq!(qa, qb);
    let mut rng = Rng(7);
    for _ in 0..100 {
        let origin = rng.vec3(-3.0, 3.0);
        let dir = rng.vec3(-1.0, 1.0);
        let hit = qa.intersect(origin, dir, f64::INFINITY);
        assert_eq!(hit, qb.intersect(origin, dir, f64::INFINITY));
        if let Some(t) = hit {
            assert_eq!(qa.normal(origin, dir, t), qb.normal(origin, dir, t));
        }
    }
}

#[test]
fn cross_terms_enter_q_halved() {
    let c =
        QuadricSpec::from_coefficients([1.0, 2.0, 3.0, 4.0, 6.0, 8.0, 1.0, 2.0, 3.0, -9.0], None);
    let m = QuadricSpec::from_matrices(
        [1.0, 2.0, 3.0, 2.0, 2.0, 4.0, 3.0, 4.0, 3.0],
        [1.0, 2.0, 3.0],
        -9.0,
        cube(1.0),
    );
    // Q = [[1,2,3],[2,2,4],[3,4,3]] is indefinite: unbounded without bounds.
    assert!(c.is_err());
    let c = coefficients(
        [1.0, 2.0, 3.0, 4.0, 6.0, 8.0, 1.0, 2.0, 3.0, -9.0],
        cube(1.0),
    );
    assert_eq!(c, m.unwrap());
}

#[test]
fn sphere_radius_two_hit_from_plus_z() {
    let q = placed(&coefficients(
        [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -4.0],
        None,
    ));
    let (origin, dir) = (DVec3::new(0.0, 0.0, 5.0), DVec3::NEG_Z);
    assert_eq!(q.intersect(origin, dir, f64::INFINITY), Some(3.0));
    assert_eq!(q.normal(origin, dir, 3.0), DVec3::Z);
    assert_eq!(q.intersect(origin, dir, 2.5), None);
    assert_eq!(q.intersect(origin, -dir, f64::INFINITY), None);
    assert_eq!(q.kind(), QuadricKind::Ellipsoid);
}

#[test]
fn ray_from_inside_ellipsoid_hits_far_side() {
    let q = placed(&coefficients(
        [0.25, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        None,
    ));
    assert_eq!(q.intersect(DVec3::ZERO, DVec3::X, f64::INFINITY), Some(2.0));
    let t = q.intersect(DVec3::ZERO, DVec3::new(3.0, 0.0, 0.0), f64::INFINITY);
    assert!(relative(t.unwrap(), 2.0 / 3.0) < 1e-15);
    // The normal at the far side points outwards (f > 0), along the ray.
    assert_eq!(q.normal(DVec3::ZERO, DVec3::X, 2.0), DVec3::X);
}

#[test]
fn ray_starting_on_surface_skips_t_zero() {
    let q = placed(&coefficients(
        [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        None,
    ));
    let hit = q.intersect(DVec3::new(0.0, 0.0, 1.0), DVec3::NEG_Z, f64::INFINITY);
    assert_eq!(hit, Some(2.0));
}

#[test]
fn open_cylinder_seen_through_its_end_hits_inside_wall() {
    let spec = coefficients(
        [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        cube(1.0),
    );
    let q = placed(&spec);
    assert_eq!(q.kind(), QuadricKind::EllipticCylinder);
    // Near root at x = -1, z = 2 lies outside the clip box; the far root at x = 1, z = 0 inside.
    let (origin, dir) = (DVec3::new(-1.5, 0.0, 2.5), DVec3::new(1.0, 0.0, -1.0));
    assert_eq!(q.intersect(origin, dir, f64::INFINITY), Some(2.5));
    assert_eq!(q.normal(origin, dir, 2.5), DVec3::X);
    // Both roots outside the box: miss.
    let high = DVec3::new(-1.5, 0.0, 5.0);
    assert_eq!(q.intersect(high, dir, f64::INFINITY), None);
}

#[test]
fn cylinder_ray_along_axis_never_hits() {
    let spec = coefficients(
        [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        cube(1.0),
    );
    let mut rng = Rng(11);
    for placement in [DMat4::IDENTITY, rng.transform(), rng.transform()] {
        let q = Quadric::new(&spec, placement).unwrap();
        let axis = placement.transform_vector3(DVec3::Z);
        for local in [
            DVec3::new(0.5, 0.0, 5.0),
            DVec3::new(1.0, 0.0, 5.0),
            DVec3::new(2.0, 0.0, 5.0),
        ] {
            let origin = placement.transform_point3(local);
            assert_eq!(q.intersect(origin, -axis, f64::INFINITY), None, "{local}");
        }
        // The same line tilted across the axis hits the wall inside the box.
        let origin = placement.transform_point3(DVec3::new(0.0, 5.0, 0.5));
        let across = placement.transform_vector3(DVec3::NEG_Y);
        let t = q.intersect(origin, across, f64::INFINITY).unwrap();
        assert!(relative(t, 4.0) < 1e-14, "{t}");
    }
}

#[test]
fn paraboloid_along_axis_uses_linear_root() {
    let bounds = Some([DVec3::new(-3.0, -3.0, -1.0), DVec3::new(3.0, 3.0, 9.0)]);
    let q = placed(&coefficients(
        [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0],
        bounds,
    ));
    assert_eq!(q.kind(), QuadricKind::EllipticParaboloid);
    let down = DVec3::NEG_Z;
    assert_eq!(
        q.intersect(DVec3::new(0.0, 0.0, 5.0), down, f64::INFINITY),
        Some(5.0)
    );
    assert_eq!(
        q.intersect(DVec3::new(1.0, 0.0, 5.0), down, f64::INFINITY),
        Some(4.0)
    );
    assert_eq!(
        q.intersect(DVec3::new(1.0, 0.0, 5.0), 2.0 * down, f64::INFINITY),
        Some(2.0)
    );
    // Apex normal points to f = x² + y² − z > 0, i.e. down.
    assert_eq!(q.normal(DVec3::new(0.0, 0.0, 5.0), down, 5.0), DVec3::NEG_Z);
    // From below, outside the bowl, upwards: the same linear root, here behind the clip box top.
    assert_eq!(
        q.intersect(DVec3::new(2.0, 0.0, -0.5), DVec3::Z, f64::INFINITY),
        Some(4.5)
    );
}

#[test]
fn cone_generator_ray_hits_once() {
    let q = placed(&coefficients(
        [1.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        cube(5.0),
    ));
    assert_eq!(q.kind(), QuadricKind::Cone);
    let t = q.intersect(
        DVec3::new(0.0, 1.0, -5.0),
        DVec3::new(1.0, 0.0, 1.0),
        f64::INFINITY,
    );
    assert!(relative(t.unwrap(), 2.4) < 1e-15);
}

#[test]
fn degenerate_gradients_give_finite_normals() {
    let cone = placed(&coefficients(
        [1.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        cube(5.0),
    ));
    let (origin, dir) = (DVec3::new(0.0, 0.0, 5.0), DVec3::new(0.0, 0.0, -2.0));
    let t = cone.intersect(origin, dir, f64::INFINITY).unwrap();
    assert_eq!(t, 2.5);
    assert_eq!(cone.normal(origin, dir, t), DVec3::Z);
    let planes = placed(&coefficients(
        [1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        cube(5.0),
    ));
    assert_eq!(planes.normal(DVec3::ZERO, DVec3::X, 0.0), DVec3::NEG_X);
    let point = placed(&coefficients(
        [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        None,
    ));
    assert_eq!(point.normal(DVec3::ZERO, DVec3::ZERO, 0.0), DVec3::Z);
    let n = point.normal(DVec3::splat(1e-200), DVec3::X, 0.0);
    assert!((n.length() - 1.0).abs() < 1e-15);
}

/// Places `spec` with 20 random transforms and casts rays through the world images of
/// `targets`; returns the worst relative difference between the world-space `t` and the `t` of
/// the unplaced quadric hit by the inverse-transformed ray, and the number of hits compared.
fn compare_transformed(spec: &QuadricSpec, targets: &[DVec3], rng: &mut Rng) -> (f64, usize) {
    let (mut worst, mut hits) = (0.0_f64, 0);
    let local = placed(spec);
    for _ in 0..20 {
        let world = rng.transform();
        let placed_world = Quadric::new(spec, world).unwrap();
        let inverse = world.inverse();
        for &target in targets {
            let aim = world.transform_point3(target + rng.vec3(-0.1, 0.1));
            let dir = rng.vec3(-1.0, 1.0) * rng.uniform(0.2, 5.0);
            let origin = aim - dir * rng.uniform(2.0, 6.0);
            let t_world = placed_world.intersect(origin, dir, f64::INFINITY);
            let (o, d) = (
                inverse.transform_point3(origin),
                inverse.transform_vector3(dir),
            );
            let t_local = local.intersect(o, d, f64::INFINITY);
            assert_eq!(t_world.is_some(), t_local.is_some(), "{origin} {dir}");
            if let (Some(a), Some(b)) = (t_world, t_local) {
                worst = worst.max(relative(a, b));
                hits += 1;
            }
        }
    }
    (worst, hits)
}

#[test]
fn transformed_quadric_matches_inverse_transformed_rays() {
    let mut rng = Rng(2024);
    let ellipsoid = coefficients([1.0, 2.0, 0.5, 0.3, -0.2, 0.1, 0.4, -0.6, 0.2, -1.5], None);
    let (e_err, e_hits) =
        compare_transformed(&ellipsoid, &[DVec3::new(-0.2, 0.15, -0.2)], &mut rng);
    let hyperboloid = coefficients(
        [1.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        cube(2.0),
    );
    let axis = [
        DVec3::new(0.0, 0.0, -0.5),
        DVec3::ZERO,
        DVec3::new(0.0, 0.0, 0.5),
    ];
    let (h_err, h_hits) = compare_transformed(&hyperboloid, &axis, &mut rng);
    eprintln!("transform vs ray transform: ellipsoid {e_err:.2e} ({e_hits} hits), hyperboloid {h_err:.2e} ({h_hits} hits)");
    assert!(e_hits == 20 && h_hits > 40);
    assert!(e_err <= 1e-12 && h_err <= 1e-12);
}

#[test]
fn far_sphere_keeps_relative_depth_accuracy() {
    let spec = coefficients([1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0], None);
    // |centre| ≈ 6.38e6; binary fractions keep `centre + offset` exact but make |centre|² inexact.
    let centre = DVec3::new(3.2e6 + 0.3671875, 4.0e6 - 0.71875, 3.8e6 + 0.140625);
    let q = Quadric::new(&spec, DMat4::from_translation(centre)).unwrap();
    let offset = DVec3::new(3.0, 4.0, 0.0); // origin 5 units from the centre
    let origin = centre + offset;
    let mut worst = 0.0_f64;
    for tilt in [0.0, 0.25, 0.5, 0.75, 0.9] {
        let dir = DVec3::new(-3.0, -4.0, tilt);
        // Analytic root from the exact small-number geometry relative to the centre.
        let (b, c) = (offset.dot(dir), offset.length_squared() - 1.0);
        let k = dir.length_squared();
        let t_exact = (-b - (b * b - k * c).sqrt()) / k;
        let t = q.intersect(origin, dir, f64::INFINITY).unwrap();
        worst = worst.max(relative(t * dir.length(), t_exact * dir.length()));
    }
    let plain = plain_world_form_depth(centre, origin, DVec3::new(-3.0, -4.0, 0.0));
    eprintln!(
        "far sphere at 6.4e6: anchored {worst:.2e}, plain world form {:.2e}",
        relative(plain, 4.0)
    );
    assert!(worst <= 1e-9);
    // Through the centre the depth is exactly 5 - 1 = 4.
    let t = q
        .intersect(origin, DVec3::new(-3.0, -4.0, 0.0), f64::INFINITY)
        .unwrap();
    assert!(relative(t * 5.0, 4.0) <= 1e-15);
}

/// Depth of the unit sphere at `centre` from the un-anchored world coefficients
/// (`P = −2c`, `R = |c|² − 1`), for comparison.
fn plain_world_form_depth(centre: DVec3, origin: DVec3, dir: DVec3) -> f64 {
    let k = dir.length_squared();
    let l = 2.0 * origin.dot(dir) - 2.0 * centre.dot(dir);
    let m = origin.length_squared() - 2.0 * origin.dot(centre) + centre.length_squared() - 1.0;
    let disc = (l * l - 4.0 * k * m).max(0.0);
    let q = -0.5 * (l + disc.sqrt().copysign(l));
    (m / q) * dir.length()
}

#[test]
fn distant_ray_origin_keeps_root_accuracy() {
    // Unit sphere at the origin, ray from 1e6 away with impact parameter b (16 bits, so b² and
    // 1 − b² are exact): the near root is 1e6 − sqrt(1 − b²).
    let q = placed(&coefficients(
        [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        None,
    ));
    let b = 0.6999969482421875;
    let (origin, dir) = (DVec3::new(0.0, b, -1e6), DVec3::Z);
    let exact = 1e6 - (1.0 - b * b).sqrt();
    let t = q.intersect(origin, dir, f64::INFINITY).unwrap();
    let (k, l) = (1.0, 2.0 * origin.dot(dir));
    let m = origin.length_squared() - 1.0;
    let classic_disc = l * l - 4.0 * k * m;
    let classic = m / (-0.5 * (l + classic_disc.sqrt().copysign(l)));
    eprintln!(
        "distant origin: |t error| completed square {:.1e}, plain L²−4KM {:.1e}",
        (t - exact).abs(),
        (classic - exact).abs()
    );
    assert!((t - exact).abs() <= 4.0 * f64::EPSILON * 1e6);
}

#[test]
fn non_unit_directions_scale_t() {
    let sphere = placed(&coefficients(
        [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        None,
    ));
    let cylinder = placed(&coefficients(
        [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        cube(1.0),
    ));
    let origin = DVec3::new(0.25, 0.0, 5.0);
    for s in [1e-6, 1e-3, 1.0, 1e3, 1e6] {
        let dir = DVec3::new(0.0, 0.0, -s);
        let t = sphere.intersect(origin, dir, f64::INFINITY).unwrap();
        assert!(relative(t * s, 5.0 - 0.9375_f64.sqrt()) < 1e-15);
        assert_eq!(cylinder.intersect(origin, dir, f64::INFINITY), None);
    }
}

#[test]
fn classification_survives_random_placement() {
    let box_ = Some([DVec3::new(-1.5, -2.0, -2.5), DVec3::new(2.5, 2.0, 1.5)]);
    let cases: [([f64; 10], QuadricKind); 16] = [
        (
            [1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
            QuadricKind::Ellipsoid,
        ),
        (
            [1.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0],
            QuadricKind::EllipticParaboloid,
        ),
        (
            [1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0],
            QuadricKind::HyperbolicParaboloid,
        ),
        (
            [1.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
            QuadricKind::HyperboloidOneSheet,
        ),
        (
            [-1.0, -1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
            QuadricKind::HyperboloidTwoSheets,
        ),
        (
            [1.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            QuadricKind::Cone,
        ),
        (
            [1.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
            QuadricKind::EllipticCylinder,
        ),
        (
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0],
            QuadricKind::ParabolicCylinder,
        ),
        (
            [1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
            QuadricKind::HyperbolicCylinder,
        ),
        (
            [1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            QuadricKind::IntersectingPlanes,
        ),
        (
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
            QuadricKind::ParallelPlanes,
        ),
        (
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, -1.0],
            QuadricKind::Plane,
        ),
        (
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            QuadricKind::CoincidentPlanes,
        ),
        (
            [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            QuadricKind::Line,
        ),
        (
            [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            QuadricKind::Point,
        ),
        (
            [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
            QuadricKind::Empty,
        ),
    ];
    let mut rng = Rng(99);
    for (c, expected) in cases {
        let spec = coefficients(c, box_);
        for _ in 0..25 {
            let kind = Quadric::new(&spec, rng.transform()).unwrap().kind();
            assert_eq!(kind, expected, "{c:?}");
        }
    }
    assert_eq!(
        QuadricKind::HyperboloidOneSheet.name(),
        "hyperboloid_one_sheet"
    );
}

#[test]
fn placement_errors() {
    let spec = coefficients([1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0], None);
    let singular = DMat4::from_scale(DVec3::new(1.0, 0.0, 1.0));
    assert!(Quadric::new(&spec, singular)
        .unwrap_err()
        .message
        .contains("singular"));
    let nearly = DMat4::from_scale(DVec3::new(1.0, 1e-20, 1.0));
    assert!(Quadric::new(&spec, nearly)
        .unwrap_err()
        .message
        .contains("singular"));
    let mut nan = DMat4::IDENTITY;
    nan.w_axis.x = f64::NAN;
    assert!(Quadric::new(&spec, nan)
        .unwrap_err()
        .message
        .contains("non-finite"));
    let mut projective = DMat4::IDENTITY;
    projective.x_axis.w = 0.5;
    assert!(Quadric::new(&spec, projective)
        .unwrap_err()
        .message
        .contains("affine"));
    let mut unbounded = coefficients(
        [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        cube(1.0),
    );
    unbounded.bounds = None;
    assert!(Quadric::new(&unbounded, DMat4::IDENTITY)
        .unwrap_err()
        .message
        .contains("bounds"));
}

/// Asserts two boxes agree to `tolerance` relative to their size.
fn assert_box_near(a: [DVec3; 2], b: [DVec3; 2], tolerance: f64) {
    let size = (b[1] - b[0]).length().max(b[0].abs().max_element());
    assert!(
        (a[0] - b[0]).abs().max_element() <= tolerance * size,
        "{a:?} vs {b:?}"
    );
    assert!(
        (a[1] - b[1]).abs().max_element() <= tolerance * size,
        "{a:?} vs {b:?}"
    );
    assert!(
        a[0].cmple(b[0]).all() && a[1].cmpge(b[1]).all(),
        "not conservative"
    );
}

#[test]
fn ellipsoid_bounds_are_tight() {
    // Semi-axes (2, 1, 0.5), turned 90° about Z, at (10, 20, 30): extents (1, 2, 0.5).
    let spec = coefficients([0.25, 1.0, 4.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0], None);
    let world = DMat4::from_translation(DVec3::new(10.0, 20.0, 30.0))
        * DMat4::from_rotation_z(std::f64::consts::FRAC_PI_2);
    let q = Quadric::new(&spec, world).unwrap();
    let half = DVec3::new(1.0, 2.0, 0.5);
    let centre = DVec3::new(10.0, 20.0, 30.0);
    assert_box_near(q.bounds(), [centre - half, centre + half], 1e-11);
    // A general ellipsoid under a random placement: the box touches sampled surface points.
    let spec = coefficients([1.0, 2.0, 0.5, 0.3, -0.2, 0.1, 0.4, -0.6, 0.2, -1.5], None);
    let world = Rng(5).transform();
    let q = Quadric::new(&spec, world).unwrap();
    let [lo, hi] = q.bounds();
    let centre = (lo + hi) * 0.5;
    for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
        let t = q.intersect(centre + 100.0 * axis * (hi - lo), -axis, f64::INFINITY);
        assert!(t.is_some());
    }
}

#[test]
fn clipped_bounds_use_the_box_corners() {
    let spec = coefficients(
        [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        cube(1.0),
    );
    let world = DMat4::from_translation(DVec3::new(5.0, 0.0, 0.0))
        * DMat4::from_rotation_z(std::f64::consts::FRAC_PI_4);
    let q = Quadric::new(&spec, world).unwrap();
    let r = std::f64::consts::SQRT_2;
    let expected = [DVec3::new(5.0 - r, -r, -1.0), DVec3::new(5.0 + r, r, 1.0)];
    // The clip box is widened by 1e-9 of its side (see `CLIP_TOLERANCE`).
    assert_box_near(q.bounds(), expected, 1e-8);
    // A sphere clipped by a larger box keeps its own tight box.
    let clipped = coefficients(
        [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        cube(3.0),
    );
    assert_box_near(
        placed(&clipped).bounds(),
        [DVec3::splat(-1.0), DVec3::ONE],
        1e-11,
    );
    // ... and one clipped by a half box gets the intersection.
    let half = Some([DVec3::new(0.0, -3.0, -3.0), DVec3::splat(3.0)]);
    let clipped = coefficients([1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0], half);
    assert_box_near(
        placed(&clipped).bounds(),
        [DVec3::new(0.0, -1.0, -1.0), DVec3::ONE],
        1e-8,
    );
}

#[test]
fn box_overlap_rejects_cells_without_surface() {
    let q = placed(&coefficients(
        [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        None,
    ));
    assert!(!q.may_overlap_box(DVec3::splat(-0.5), DVec3::splat(0.5)));
    assert!(!q.may_overlap_box(DVec3::splat(0.8), DVec3::splat(1.0)));
    assert!(!q.may_overlap_box(DVec3::splat(2.0), DVec3::splat(3.0)));
    assert!(q.may_overlap_box(DVec3::splat(0.5), DVec3::splat(1.0)));
    assert!(q.may_overlap_box(DVec3::splat(-2.0), DVec3::splat(2.0)));
    // Random cells: never reject a cell containing a hit point.
    let mut rng = Rng(3);
    let spec = coefficients(
        [1.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        cube(2.0),
    );
    let q = Quadric::new(&spec, rng.transform()).unwrap();
    let [lo, hi] = q.bounds();
    for _ in 0..500 {
        let origin = lo + (hi - lo) * rng.vec3(-0.5, 1.5);
        let dir = rng.vec3(-1.0, 1.0);
        if let Some(t) = q.intersect(origin, dir, f64::INFINITY) {
            let hit = origin + t * dir;
            let size = (hi - lo) * rng.uniform(1e-6, 0.1);
            assert!(q.may_overlap_box(hit - size * rng.uniform(0.0, 1.0), hit + size));
        }
    }
}

#[test]
fn bounds_pre_test_never_changes_the_answer() {
    // Rays aimed at the bounding box's faces, edges and corners (and just beside them) of
    // randomly placed, clipped and unclipped quadrics: the pre-test must agree with the exact
    // test on every ray, and it must reject some (else it tests nothing).
    let specs = [
        coefficients([1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0], None),
        coefficients(
            [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
            cube(1.5),
        ),
        coefficients(
            [1.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            cube(1.0),
        ),
        coefficients(
            [1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0],
            cube(2.0),
        ),
    ];
    let mut rng = Rng(99);
    let mut rejected = 0;
    for spec in &specs {
        for _ in 0..10 {
            let quadric = Quadric::new(spec, rng.transform()).unwrap();
            let [min, max] = quadric.bounds();
            for _ in 0..500 {
                // A target on the box surface (one coordinate pinned to a face), nudged by up to
                // 1e-6 of the box size inwards or outwards.
                let mut target = min + (max - min) * rng.vec3(0.0, 1.0);
                let axis = (rng.uniform(0.0, 3.0) as usize).min(2);
                let face = if rng.uniform(0.0, 1.0) < 0.5 {
                    min
                } else {
                    max
                };
                target[axis] = face[axis] + rng.uniform(-1e-6, 1e-6) * (max - min)[axis];
                let origin = target + rng.vec3(-1.0, 1.0).normalize() * rng.uniform(1.0, 50.0);
                let mut dir = target - origin;
                if rng.uniform(0.0, 1.0) < 0.2 {
                    dir[axis] = 0.0; // parallel to a face
                }
                let t_max = if rng.uniform(0.0, 1.0) < 0.3 {
                    rng.uniform(0.0, 2.0)
                } else {
                    f64::INFINITY
                };
                let exact = quadric.intersect_exact(origin, dir, t_max);
                assert_eq!(quadric.intersect(origin, dir, t_max), exact);
                rejected += usize::from(!quadric.may_reach_bounds(origin, dir.recip(), t_max));
            }
        }
    }
    assert!(rejected > 1000, "only {rejected} rays rejected");
}

/// The bounds pre-test on rays parallel to two axes (two infinite reciprocals), from origins
/// inside, outside and exactly on the bounds' planes: it never rejects a hit the exact test
/// finds, and it rejects the rays that pass beside the box.
#[test]
fn bounds_pretest_on_axis_parallel_rays() {
    let sphere = coefficients([1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0], None);
    let quadric = Quadric::new(&sphere, DMat4::IDENTITY).unwrap();
    let [min, max] = quadric.bounds();
    let mut rejected = 0;
    for axis in 0..3 {
        for &(u, v) in &[
            (0.0, 0.0),
            (0.5, -0.25),
            (min.x, 0.0),
            (max.x, max.y),
            (1.5, 0.0),
        ] {
            for sign in [1.0, -1.0] {
                let mut dir = DVec3::ZERO;
                dir[axis] = sign;
                let mut origin = DVec3::ZERO;
                origin[axis] = -3.0 * sign;
                origin[(axis + 1) % 3] = u;
                origin[(axis + 2) % 3] = v;
                let exact = quadric.intersect_exact(origin, dir, f64::INFINITY);
                assert_eq!(quadric.intersect(origin, dir, f64::INFINITY), exact);
                rejected += usize::from(!quadric.may_reach_bounds(origin, dir.recip(), 10.0));
            }
        }
    }
    // The origins at u = 1.5 lie beside the unit sphere's box.
    assert_eq!(rejected, 6);
}
