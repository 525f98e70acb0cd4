//! Affine classification of a quadric surface.

use glam::{DMat3, DVec3};

use super::eigen::{symmetric_eigen, ZERO_EIGENVALUE};

/// Terms below this fraction of the function's magnitude over the region of interest count as zero.
const NEGLIGIBLE_TERM: f64 = 1e-9;

/// The affine type of a quadric surface `p·Q·p + P·p + R = 0`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum QuadricKind {
    /// Closed surface with a definite `Q` (a sphere after an affine map).
    Ellipsoid,
    /// Bowl `z = x² + y²` up to an affine map.
    EllipticParaboloid,
    /// Saddle `z = x² − y²` up to an affine map.
    HyperbolicParaboloid,
    /// Connected hyperboloid `x² + y² − z² = 1` up to an affine map.
    HyperboloidOneSheet,
    /// Two-piece hyperboloid `x² − y² − z² = 1` up to an affine map.
    HyperboloidTwoSheets,
    /// Double cone `x² + y² = z²` up to an affine map.
    Cone,
    /// Cylinder `x² + y² = 1` up to an affine map.
    EllipticCylinder,
    /// Cylinder over a parabola, `y = x²` up to an affine map.
    ParabolicCylinder,
    /// Cylinder over a hyperbola, `x² − y² = 1` up to an affine map.
    HyperbolicCylinder,
    /// Two planes crossing in a line, `x² = y²` up to an affine map.
    IntersectingPlanes,
    /// Two distinct parallel planes, `x² = 1` up to an affine map.
    ParallelPlanes,
    /// A single plane (`Q = 0`).
    Plane,
    /// One plane counted twice, `x² = 0`: the gradient vanishes on the whole surface.
    CoincidentPlanes,
    /// A single line, `x² + y² = 0`.
    Line,
    /// A single point, `x² + y² + z² = 0`.
    Point,
    /// No real points, for example `x² + y² + z² = −1`.
    Empty,
}

impl QuadricKind {
    /// The snake_case name used in reports, e.g. `"hyperboloid_one_sheet"`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Ellipsoid => "ellipsoid",
            Self::EllipticParaboloid => "elliptic_paraboloid",
            Self::HyperbolicParaboloid => "hyperbolic_paraboloid",
            Self::HyperboloidOneSheet => "hyperboloid_one_sheet",
            Self::HyperboloidTwoSheets => "hyperboloid_two_sheets",
            Self::Cone => "cone",
            Self::EllipticCylinder => "elliptic_cylinder",
            Self::ParabolicCylinder => "parabolic_cylinder",
            Self::HyperbolicCylinder => "hyperbolic_cylinder",
            Self::IntersectingPlanes => "intersecting_planes",
            Self::ParallelPlanes => "parallel_planes",
            Self::Plane => "plane",
            Self::CoincidentPlanes => "coincident_planes",
            Self::Line => "line",
            Self::Point => "point",
            Self::Empty => "empty",
        }
    }
}

/// The quadric in its principal frame: `Σ λᵢ yᵢ² + linear·w + constant = 0`.
struct Canonical {
    /// Signs (±1) of the non-zero eigenvalues of `Q`.
    signs: Vec<f64>,
    /// Whether a linear term survives in the null space of `Q`.
    linear: bool,
    /// The constant after completing the squares, or `None` when it is negligible.
    constant: Option<f64>,
}

/// Classifies `u·Q·u + P·u + R = 0`, where `u` is measured from a point of interest and
/// `length` is the radius (about that point) of the region the surface is used in; terms that
/// are negligible over that region count as zero. `length` may be 0 for a bounded surface.
pub(super) fn classify(q: DMat3, p: DVec3, r: f64, length: f64) -> QuadricKind {
    let canonical = canonical_form(q, p, r, length);
    let rank = canonical.signs.len();
    let positive = canonical.signs.iter().filter(|&&s| s > 0.0).count();
    let definite = positive == rank || positive == 0;
    if canonical.linear {
        return match rank {
            2 if definite => QuadricKind::EllipticParaboloid,
            2 => QuadricKind::HyperbolicParaboloid,
            1 => QuadricKind::ParabolicCylinder,
            _ => QuadricKind::Plane,
        };
    }
    match canonical.constant {
        None => classify_homogeneous(rank, definite),
        Some(k) => {
            let agreeing = canonical.signs.iter().filter(|&&s| s * k < 0.0).count();
            classify_central(rank, agreeing)
        }
    }
}

/// Rotates into the eigenframe of `Q`, completes the squares and decides which terms vanish.
fn canonical_form(q: DMat3, p: DVec3, r: f64, length: f64) -> Canonical {
    let (values, vectors) = symmetric_eigen(q);
    let b = vectors.transpose() * p;
    let largest = values.abs().max_element();
    let mut scale = largest * length * length + p.length() * length + r.abs();
    let mut constant = r;
    let mut signs = Vec::new();
    let mut null_linear = 0.0_f64;
    for i in 0..3 {
        if values[i].abs() > ZERO_EIGENVALUE * largest {
            let shift = b[i] * b[i] / (4.0 * values[i]);
            constant -= shift;
            scale += shift.abs();
            signs.push(values[i].signum());
        } else {
            null_linear = null_linear.hypot(b[i]);
        }
    }
    let tolerance = NEGLIGIBLE_TERM * scale;
    Canonical {
        signs,
        linear: null_linear * length > tolerance,
        constant: (constant.abs() > tolerance).then_some(constant),
    }
}

/// `Σ λᵢ yᵢ² = 0`: the zero set is a point, a line, a cone or plane pairs.
fn classify_homogeneous(rank: usize, definite: bool) -> QuadricKind {
    match rank {
        3 if definite => QuadricKind::Point,
        3 => QuadricKind::Cone,
        2 if definite => QuadricKind::Line,
        2 => QuadricKind::IntersectingPlanes,
        1 => QuadricKind::CoincidentPlanes,
        // A non-zero constant function; the zero function is rejected on input.
        _ => QuadricKind::Empty,
    }
}

/// `Σ λᵢ yᵢ² = −k` with `k ≠ 0`; `agreeing` counts the eigenvalues with the sign of `−k`.
fn classify_central(rank: usize, agreeing: usize) -> QuadricKind {
    match (rank, agreeing) {
        (3, 3) => QuadricKind::Ellipsoid,
        (3, 2) => QuadricKind::HyperboloidOneSheet,
        (3, 1) => QuadricKind::HyperboloidTwoSheets,
        (2, 2) => QuadricKind::EllipticCylinder,
        (2, 1) => QuadricKind::HyperbolicCylinder,
        (1, 1) => QuadricKind::ParallelPlanes,
        _ => QuadricKind::Empty,
    }
}
