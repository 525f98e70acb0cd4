use super::*;

/// The x = 1 side of the cube [-1, 1]³, the half that the ray of [`probe`] leaves through.
fn exit_face() -> [DVec3; 3] {
    [[1.0, -1.0, -1.0], [1.0, 1.0, -1.0], [1.0, 1.0, 1.0]].map(DVec3::from_array)
}

/// The ray from (0, 0, 3) along (0.3, 0.1, −1), which enters the cube through z = 1 at t = 2
/// and leaves it through x = 1 at t = 10/3 (at y = 1/3, z = −1/3: inside [`exit_face`]),
/// searched for competitors up to `limit`.
fn probe(limit: f64) -> Probe<'static> {
    let ray = Ray::new(DVec3::new(0.0, 0.0, 3.0), DVec3::new(0.3, 0.1, -1.0));
    let watertight = WatertightRay::new(ray.origin, ray.dir);
    Probe::new(&ray, watertight, limit, None, 2.0)
}

/// The exit face is crossed, so the f64 filters keep it; its plane lies beyond a limit just
/// past the entry, and not beyond one past the exit (by analysis: the exit is at t = 10/3).
#[test]
fn a_closed_objects_exit_face_lies_beyond_the_entry() {
    let face = exit_face();
    let entry = probe(2.0 + 1e-9);
    assert!(!triangle::certainly_apart(
        &entry.watertight,
        &face,
        0.0,
        entry.limit
    ));
    assert!(plane_beyond(&entry, &face, 0.0));
    assert!(!plane_beyond(&probe(10.0 / 3.0 + 1e-9), &face, 0.0));
    // The bound is a few ulps: 1e-12 short of the exit is certainly short, the f64 nearest
    // 10/3 is not.
    assert!(plane_beyond(&probe(10.0 / 3.0 - 1e-12), &face, 0.0));
    assert!(!plane_beyond(&probe(10.0 / 3.0), &face, 0.0));
    // Vertices that may be off by 1 may put the plane anywhere past the entry.
    assert!(!plane_beyond(&entry, &face, 1.0));
}

/// A face the ray misses is left to the other tests, whatever the limit.
#[test]
fn a_missed_face_is_not_beyond() {
    let top = [[-1.0, 1.0, -1.0], [1.0, 1.0, -1.0], [1.0, 1.0, 1.0]].map(DVec3::from_array);
    assert!(!plane_beyond(&probe(2.0), &top, 0.0));
}
