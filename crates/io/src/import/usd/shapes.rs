//! UsdGeom intrinsic gprims as analytic quadrics (plus planar caps and the cube's triangles).
//!
//! Shapes with an `axis` are built in a canonical frame whose third coordinate `w` is the
//! axis, then placed with a cyclic permutation matrix (determinant +1) that maps the
//! canonical `(u, v, w)` to the prim's local `(x, y, z)`. Unauthored attributes take USD's
//! fallback values (openusd 0.6 has no schema registry to supply them).
//!
//! | prim | surfaces |
//! | --- | --- |
//! | Sphere | `x² + y² + z² = r²`, unclipped |
//! | Cylinder, Cylinder_1 | `u² + v² = (a + b w)²` clipped to `|w| ≤ h/2` (a cylinder when the radii agree, else a cone frustum), plus two cap discs |
//! | Cone | the same with radius `r` at `w = −h/2` and the apex at `w = +h/2`, plus the base disc |
//! | Capsule | cylinder `|w| ≤ h/2` plus two hemispheres (spheres clipped by half boxes) |
//! | Cube | 12 triangles (exact for a cube) |
//! | Plane | the plane `w = 0` clipped to `width × length`, normal `+axis` |
//!
//! Cap discs are meshes: a quadric clipped by an axis-aligned box cannot be a disc (a plane
//! clipped by a box is a rectangle). Each disc is a fan of [`CAP_SEGMENTS`] triangles whose
//! outer vertices lie on the rim circle: depth and normal on the disc are exact (it is
//! planar), the rim is a polygon inscribed in the circle (largest gap `r·(1 − cos(π/N))`,
//! 1.9e-5 of the radius).

use super::value::{self, At};
use crate::error::{Error, Result};
use crate::quadric::QuadricSpec;
use glam::{DMat4, DVec3, DVec4};
use openusd::usd::Prim;
use std::f64::consts::PI;

/// Segments of a cap disc.
pub const CAP_SEGMENTS: usize = 512;

/// One surface of a gprim.
pub enum Part {
    /// An analytic quadric given in the canonical frame `frame` (canonical → prim local).
    Quadric {
        /// The quadric in canonical coordinates.
        spec: Box<QuadricSpec>,
        /// Canonical → local matrix.
        frame: DMat4,
    },
    /// Triangles in the prim's local space.
    Mesh {
        /// Local-space triangles, counter-clockwise front.
        triangles: Vec<[DVec3; 3]>,
    },
}

/// The gprim type names this module draws.
pub fn is_shape(type_name: &str) -> bool {
    matches!(
        type_name,
        "Sphere" | "Cube" | "Cylinder" | "Cylinder_1" | "Cone" | "Capsule" | "Capsule_1" | "Plane"
    )
}

/// A positive, finite size attribute with its fallback.
fn size(prim: &Prim, name: &str, fallback: f64, at: At) -> Result<f64> {
    let x = value::scalar(prim, name, at)?.unwrap_or(fallback);
    if x.is_finite() && x >= 0.0 {
        Ok(x)
    } else {
        Err(Error::at(
            format!("{}.{name}", prim.path()),
            format!("{x} is not a finite non-negative number"),
        ))
    }
}

/// The `axis` token (fallback `Z`) as the canonical → local permutation.
fn axis_frame(prim: &Prim, at: At) -> Result<(char, DMat4)> {
    let axis = value::token(prim, "axis", at)?.unwrap_or_else(|| "Z".into());
    let cols = |u: DVec3, v: DVec3, w: DVec3| {
        DMat4::from_cols(
            u.extend(0.0),
            v.extend(0.0),
            w.extend(0.0),
            DVec4::new(0.0, 0.0, 0.0, 1.0),
        )
    };
    match axis.as_str() {
        "X" => Ok(('X', cols(DVec3::Y, DVec3::Z, DVec3::X))),
        "Y" => Ok(('Y', cols(DVec3::Z, DVec3::X, DVec3::Y))),
        "Z" => Ok(('Z', DMat4::IDENTITY)),
        other => Err(Error::at(
            format!("{}.axis", prim.path()),
            format!("'{other}' is not X, Y or Z"),
        )),
    }
}

/// The surfaces of a gprim; `Ok(Err(reason))` when it has nothing to draw (a warning), `Err`
/// for an attribute that cannot be read as its schema says.
pub fn parts(prim: &Prim, type_name: &str, at: At) -> Result<Result<Vec<Part>>> {
    let path = prim.path();
    let empty = |what: &str| {
        Ok(Err(Error::at(
            path.to_string(),
            format!("{type_name} with {what}: skipped"),
        )))
    };
    match type_name {
        "Sphere" => {
            let r = size(prim, "radius", 1.0, at)?;
            if r == 0.0 {
                return empty("radius 0");
            }
            let part = sphere(r, 0.0, None).map_err(|e| e.context(path))?;
            Ok(Ok(vec![part]))
        }
        "Cube" => {
            let s = size(prim, "size", 2.0, at)?;
            if s == 0.0 {
                return empty("size 0");
            }
            Ok(Ok(vec![Part::Mesh {
                triangles: cube_triangles(s / 2.0),
            }]))
        }
        "Cylinder" | "Cylinder_1" | "Cone" => {
            let h = size(prim, "height", 2.0, at)?;
            let (bottom, top) = match type_name {
                "Cone" => (size(prim, "radius", 1.0, at)?, 0.0),
                "Cylinder" => {
                    let r = size(prim, "radius", 1.0, at)?;
                    (r, r)
                }
                _ => (
                    size(prim, "radiusBottom", 1.0, at)?,
                    size(prim, "radiusTop", 1.0, at)?,
                ),
            };
            if h == 0.0 || (top == 0.0 && bottom == 0.0) {
                return empty("zero height or radius");
            }
            let (_, frame) = axis_frame(prim, at)?;
            let parts = frustum(bottom, top, h, frame).map_err(|e| e.context(path))?;
            Ok(Ok(parts))
        }
        "Capsule" | "Capsule_1" => {
            let h = size(prim, "height", 1.0, at)?;
            let r = if type_name == "Capsule" {
                size(prim, "radius", 0.5, at)?
            } else {
                let top = size(prim, "radiusTop", 0.5, at)?;
                let bottom = size(prim, "radiusBottom", 0.5, at)?;
                if top != bottom {
                    return empty("different radiusTop and radiusBottom (not supported)");
                }
                top
            };
            if r == 0.0 {
                return empty("radius 0");
            }
            let (_, frame) = axis_frame(prim, at)?;
            let mut parts = Vec::new();
            if h > 0.0 {
                parts.push(Part::Quadric {
                    spec: Box::new(side(r, r, h).map_err(|e| e.context(path))?),
                    frame,
                });
            }
            for centre in [h / 2.0, -h / 2.0] {
                parts.push(sphere(r, centre, Some(frame)).map_err(|e| e.context(path))?);
            }
            Ok(Ok(parts))
        }
        "Plane" => {
            let width = size(prim, "width", 2.0, at)?;
            let length = size(prim, "length", 2.0, at)?;
            let (axis, _) = axis_frame(prim, at)?;
            let (w, l) = (width / 2.0, length / 2.0);
            // Extents as usd-core computes them: axis X spans (y: length, z: width),
            // Y spans (x: width, z: length), Z spans (x: width, y: length).
            let (normal, half) = match axis {
                'X' => (DVec3::X, DVec3::new(0.0, l, w)),
                'Y' => (DVec3::Y, DVec3::new(w, 0.0, l)),
                _ => (DVec3::Z, DVec3::new(w, l, 0.0)),
            };
            let spec = QuadricSpec::from_coefficients(
                [
                    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, normal.x, normal.y, normal.z, 0.0,
                ],
                Some([-half, half]),
            )
            .map_err(|e| e.context(path))?;
            Ok(Ok(vec![Part::Quadric {
                spec: Box::new(spec),
                frame: DMat4::IDENTITY,
            }]))
        }
        _ => Ok(Err(Error::at(
            path.to_string(),
            format!("{type_name} is not an intrinsic shape"),
        ))),
    }
}

/// A sphere of radius `r` centred at `w = centre` on the canonical axis; with a frame it is
/// the hemisphere on the far side of `w = centre` (`+` for a centre of positive sign, `−` else).
fn sphere(r: f64, centre: f64, frame: Option<DMat4>) -> Result<Part> {
    let coefficients = [
        1.0,
        1.0,
        1.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        -2.0 * centre,
        centre * centre - r * r,
    ];
    let bounds = frame.map(|_| {
        let (lo, hi) = if centre.is_sign_positive() {
            (centre, centre + r)
        } else {
            (centre - r, centre)
        };
        [DVec3::new(-r, -r, lo), DVec3::new(r, r, hi)]
    });
    let spec = Box::new(QuadricSpec::from_coefficients(coefficients, bounds)?);
    Ok(Part::Quadric {
        spec,
        frame: frame.unwrap_or(DMat4::IDENTITY),
    })
}

/// The side of a cone frustum along `w`: radius `bottom` at `w = −h/2`, `top` at `+h/2`:
/// `u² + v² − (a + b w)² = 0` with `a = (top + bottom)/2`, `b = (top − bottom)/h`.
fn side(bottom: f64, top: f64, h: f64) -> Result<QuadricSpec> {
    let a = (top + bottom) / 2.0;
    let b = (top - bottom) / h;
    let r = top.max(bottom);
    QuadricSpec::from_coefficients(
        [
            1.0,
            1.0,
            -b * b,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            -2.0 * a * b,
            -a * a,
        ],
        Some([DVec3::new(-r, -r, -h / 2.0), DVec3::new(r, r, h / 2.0)]),
    )
}

/// Side and caps of a cylinder, cone or frustum, placed by `frame`.
fn frustum(bottom: f64, top: f64, h: f64, frame: DMat4) -> Result<Vec<Part>> {
    let mut parts = vec![Part::Quadric {
        spec: Box::new(side(bottom, top, h)?),
        frame,
    }];
    let mut caps = Vec::new();
    if bottom > 0.0 {
        caps.extend(disc(bottom, -h / 2.0, false));
    }
    if top > 0.0 {
        caps.extend(disc(top, h / 2.0, true));
    }
    parts.push(Part::Mesh {
        triangles: crate::import::place(&caps, &frame),
    });
    Ok(parts)
}

/// A disc of radius `r` in the plane `w = height`, facing `+w` when `up`, else `−w`.
pub fn disc(r: f64, height: f64, up: bool) -> Vec<[DVec3; 3]> {
    let centre = DVec3::new(0.0, 0.0, height);
    let rim = |k: usize| {
        let angle = 2.0 * PI * (k % CAP_SEGMENTS) as f64 / CAP_SEGMENTS as f64;
        DVec3::new(r * angle.cos(), r * angle.sin(), height)
    };
    (0..CAP_SEGMENTS)
        .map(|k| {
            if up {
                [centre, rim(k), rim(k + 1)]
            } else {
                [centre, rim(k + 1), rim(k)]
            }
        })
        .collect()
}

/// The cube `[-h, h]³` as 12 outward counter-clockwise triangles, in the same order as the
/// glTF fixture cube (`fixtures/README.md`): +Z, −Z, +X, −X, +Y, −Y, two triangles each.
pub fn cube_triangles(h: f64) -> Vec<[DVec3; 3]> {
    let v = [
        DVec3::new(-h, -h, -h),
        DVec3::new(h, -h, -h),
        DVec3::new(h, h, -h),
        DVec3::new(-h, h, -h),
        DVec3::new(-h, -h, h),
        DVec3::new(h, -h, h),
        DVec3::new(h, h, h),
        DVec3::new(-h, h, h),
    ];
    const FACES: [[usize; 3]; 12] = [
        [4, 5, 6],
        [4, 6, 7],
        [0, 2, 1],
        [0, 3, 2],
        [1, 2, 6],
        [1, 6, 5],
        [0, 4, 7],
        [0, 7, 3],
        [3, 7, 6],
        [3, 6, 2],
        [0, 1, 5],
        [0, 5, 4],
    ];
    FACES.iter().map(|f| f.map(|i| v[i])).collect()
}
