//! Nearest points on quadrics whose answers follow from the geometry: centres, axes, points
//! on the surface and 1e-12 off it, far points, and answers on the clip box's rim or at a
//! cone's apex.

use crate::quadric::{Quadric, QuadricSpec};
use glam::{DMat3, DMat4, DVec3};

const EPS: f64 = f64::EPSILON / 2.0;

fn quadric(diagonal: [f64; 3], p: [f64; 3], r: f64, bounds: Option<[[f64; 3]; 2]>) -> Quadric {
    let spec = QuadricSpec {
        q: DMat3::from_diagonal(DVec3::from_array(diagonal)),
        p: DVec3::from_array(p),
        r,
        bounds: bounds.map(|b| b.map(DVec3::from_array)),
    };
    Quadric::new(&spec, DMat4::IDENTITY).unwrap()
}

/// The distance from `point`, checked against `want` to `ulps` ε of `scale`, and the point.
fn check(q: &Quadric, point: [f64; 3], want: f64, scale: f64) -> DVec3 {
    let point = DVec3::from_array(point);
    let found = q.closest(point, f64::INFINITY).expect("a nearest point");
    let error = (found.distance - want).abs() / (EPS * scale);
    assert!(
        error <= 8.0,
        "{point}: {} against {want} ({error} ε)",
        found.distance
    );
    assert!(((found.offset).length() - found.distance).abs() <= 2.0 * EPS * scale);
    point + found.offset
}

#[test]
fn a_sphere_s_centre_axis_surface_and_far_points() {
    let sphere = quadric([1.0; 3], [0.0; 3], -4.0, None);
    let at = check(&sphere, [0.0; 3], 2.0, 2.0);
    assert!((at.length() - 2.0).abs() <= 4.0 * EPS);
    assert_eq!(
        check(&sphere, [0.0, 0.0, 5.0], 3.0, 5.0),
        DVec3::new(0.0, 0.0, 2.0)
    );
    check(&sphere, [0.0, 2.0, 0.0], 0.0, 2.0);
    check(&sphere, [0.0, 0.0, 2.0 - 1e-12], 1e-12, 2.0);
    check(&sphere, [1e6, 0.0, 0.0], 1e6 - 2.0, 1e6);
    assert!(sphere.closest(DVec3::NAN, f64::INFINITY).is_none());
}

#[test]
fn a_cylinder_s_axis_and_its_rim() {
    let box_ = Some([[-1.0; 3], [1.0; 3]]);
    let cylinder = quadric([1.0, 1.0, 0.0], [0.0; 3], -1.0, box_);
    check(&cylinder, [0.0, 0.0, 0.3], 1.0, 1.0);
    // Beyond the top: the rim circle z = 1.
    check(&cylinder, [0.0, 0.0, 5.0], 17f64.sqrt(), 5.0);
    let at = check(&cylinder, [2.0, 0.0, 5.0], 17f64.sqrt(), 5.0);
    assert!((at - DVec3::new(1.0, 0.0, 1.0)).length() <= 4.0 * EPS);
}

#[test]
fn one_nappe_of_a_cone_is_nearest_at_its_apex() {
    let nappe = quadric(
        [1.0, 1.0, -1.0],
        [0.0; 3],
        0.0,
        Some([[-2.0, -2.0, 0.0], [2.0; 3]]),
    );
    let at = check(&nappe, [0.0, 0.0, -1.0], 1.0, 2.0);
    assert!(at.length() <= 4.0 * EPS, "{at}");
    // Beside it, the nearest generator: 45° lines, so 3/√2 from (3, 0, 0).
    check(&nappe, [3.0, 0.0, 0.0], 3.0 / 2f64.sqrt(), 3.0);
}

#[test]
fn the_box_may_cut_the_unclipped_nearest_point_away() {
    // z² − x² − y² = 1, only its upper sheet: from below, (0, 0, 1) at 2.5.
    let sheet = quadric(
        [-1.0, -1.0, 1.0],
        [0.0; 3],
        -1.0,
        Some([[-3.0, -3.0, 0.5], [3.0; 3]]),
    );
    check(&sheet, [0.0, 0.0, -1.5], 2.5, 3.0);
    // The unit sphere's lower half: from (0, 0, 0.5) the rim at z = 0 (√1.25) beats the far
    // pole (1.5); from (0, 0, −0.5) the pole, at 0.5.
    let bowl = quadric(
        [1.0; 3],
        [0.0; 3],
        -1.0,
        Some([[-1.0, -1.0, -1.0], [1.0, 1.0, 0.0]]),
    );
    check(&bowl, [0.0, 0.0, 0.5], 1.25f64.sqrt(), 1.0);
    check(&bowl, [0.0, 0.0, -0.5], 0.5, 1.0);
}

#[test]
fn a_paraboloid_s_vertex_and_a_saddle_point_on_the_surface() {
    let bowl = quadric(
        [1.0, 1.0, 0.0],
        [0.0, 0.0, -1.0],
        0.0,
        Some([[-2.0; 3], [2.0; 3]]),
    );
    check(&bowl, [0.0, 0.0, -1.0], 1.0, 2.0);
    check(&bowl, [0.0, 0.0, 1.0], 0.75f64.sqrt(), 2.0);
    let saddle = quadric(
        [1.0, -1.0, 0.0],
        [0.0, 0.0, -1.0],
        0.0,
        Some([[-2.0; 3], [2.0; 3]]),
    );
    check(&saddle, [0.0; 3], 0.0, 2.0);
}

#[test]
fn which_quadrics_enclose_a_volume_and_their_sides() {
    let sphere = quadric([1.0; 3], [0.0; 3], -1.0, None);
    assert!(sphere.encloses());
    assert_eq!(sphere.inside(DVec3::splat(0.1)), Some(true));
    assert_eq!(sphere.inside(DVec3::splat(2.0)), Some(false));
    assert_eq!(sphere.inside(DVec3::X), None);
    // Its bounding box as the clip box keeps it closed; a box that cuts it does not.
    assert!(quadric([1.0; 3], [0.0; 3], -1.0, Some([[-1.0; 3], [1.0; 3]])).encloses());
    assert!(!quadric([1.0; 3], [0.0; 3], -1.0, Some([[-1.0; 3], [1.0, 1.0, 0.5]])).encloses());
    assert!(!quadric([1.0, 1.0, 0.0], [0.0; 3], -1.0, Some([[-1.0; 3], [1.0; 3]])).encloses());
    // A negated sphere is inside where f > 0.
    let negated = quadric([-1.0; 3], [0.0; 3], 1.0, None);
    assert_eq!(negated.inside(DVec3::ZERO), Some(true));
}
