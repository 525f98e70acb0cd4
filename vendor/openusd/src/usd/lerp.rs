//! Linear interpolation of two time samples with the arithmetic of C++ OpenUSD's `Usd_Lerp`
//! (`pxr/usd/usd/interpolators.cpp`), so that a value read between two samples is the value
//! usd-core reads, to the last bit.
//!
//! `Usd_Lerp` is `GfLerp(alpha, a, b) = (1 - alpha) * a + alpha * b` for every type but the
//! quaternions, which use `GfSlerp`. Where the rounding happens depends on the C++ types:
//!
//! - `float`, `double`, `GfHalf` scalars: the sum is formed in `double` (a `float` or half
//!   operand is promoted), then rounded once to the value's type (a half through `float`);
//! - `GfVec*f` (and matrices, vectors and quaternions of any precision): `double * vec`
//!   scales each component in place (`_data[i] *= s`), rounding each product to the
//!   component type, and the two vectors are added in the component type;
//! - `GfVec*h`: `half *= double` resolves to `half *= float`: the factor is first rounded to
//!   `float`, each product to half, and the sum is a half sum (formed in `float`);
//! - `GfQuat*`: `GfSlerp` in the precision of the quaternion: its `cos θ` is the dot
//!   product in that precision, `θ` and `sin θ` are rounded to it, the two weights are
//!   `double` and are rounded to it before they scale the quaternions.

use crate::gf::{self, f16};
use crate::sdf::Value;

/// `GfLerp` of two doubles.
fn lerp_d(a: f64, b: f64, alpha: f64) -> f64 {
    (1.0 - alpha) * a + alpha * b
}

/// `GfLerp` of two floats: formed in double, rounded once.
fn lerp_f(a: f32, b: f32, alpha: f64) -> f32 {
    ((1.0 - alpha) * f64::from(a) + alpha * f64::from(b)) as f32
}

/// `GfLerp` of two halves: formed in double, rounded to float, then to half (C++'s
/// `half(float)` is the only conversion from a double).
fn lerp_h(a: f16, b: f16, alpha: f64) -> f16 {
    f16::from_f32(((1.0 - alpha) * a.to_f64() + alpha * b.to_f64()) as f32)
}

/// One component of `(1 - alpha) * u + alpha * v` for `GfVec*f` and `GfMatrix*f`-like types.
fn comp_f(a: f32, b: f32, alpha: f64) -> f32 {
    (f64::from(a) * (1.0 - alpha)) as f32 + (f64::from(b) * alpha) as f32
}

/// One component of `(1 - alpha) * u + alpha * v` for `GfVec*h`.
fn comp_h(a: f16, b: f16, alpha: f64) -> f16 {
    let p = f16::from_f32(a.to_f32() * (1.0 - alpha) as f32);
    let q = f16::from_f32(b.to_f32() * alpha as f32);
    f16::from_f32(p.to_f32() + q.to_f32())
}

/// Component-wise interpolation of two `Pod` values made of `N` components of type `C`.
fn components<T, C, const N: usize>(a: T, b: T, f: impl Fn(C, C) -> C) -> T
where
    T: bytemuck::Pod,
    C: bytemuck::Pod,
    [C; N]: bytemuck::Pod,
{
    let (a, b): ([C; N], [C; N]) = (bytemuck::cast(a), bytemuck::cast(b));
    bytemuck::cast(std::array::from_fn::<C, N, _>(|i| f(a[i], b[i])))
}

/// The two `GfSlerp` weights (`double`) for `cos θ` (the dot product, formed in the
/// quaternion's precision); `trig` gives `θ` and `sin θ` as that precision rounds them. The
/// second weight is negated for the short arc.
fn slerp_weights(cos: f64, alpha: f64, trig: impl Fn(f64) -> (f64, f64)) -> (f64, f64) {
    let (cos, flip) = if cos < 0.0 { (-cos, true) } else { (cos, false) };
    let (s0, s1) = if 1.0 - cos > 0.00001 {
        let (theta, sin_theta) = trig(cos);
        (((1.0 - alpha) * theta).sin() / sin_theta, (alpha * theta).sin() / sin_theta)
    } else {
        (1.0 - alpha, alpha)
    };
    (s0, if flip { -s1 } else { s1 })
}

/// `GfSlerp` of two `GfQuatd`.
fn slerp_d(a: gf::Quatd, b: gf::Quatd, alpha: f64) -> gf::Quatd {
    let cos = (a.x * b.x + a.y * b.y + a.z * b.z) + a.w * b.w;
    let (s0, s1) = slerp_weights(cos, alpha, |c| (c.acos(), c.acos().sin()));
    let mix = |p: f64, q: f64| p * s0 + q * s1;
    gf::Quatd {
        w: mix(a.w, b.w),
        x: mix(a.x, b.x),
        y: mix(a.y, b.y),
        z: mix(a.z, b.z),
    }
}

/// `GfSlerp` of two `GfQuatf`: the dot product, `θ`, `sin θ` (`std::sin(float)` is `sinf`),
/// the weights and the result in float.
fn slerp_f(a: gf::Quatf, b: gf::Quatf, alpha: f64) -> gf::Quatf {
    let cos = f64::from((a.x * b.x + a.y * b.y + a.z * b.z) + a.w * b.w);
    let (s0, s1) = slerp_weights(cos, alpha, |c| {
        let theta = c.acos() as f32;
        (f64::from(theta), f64::from(theta.sin()))
    });
    let (s0, s1) = (s0 as f32, s1 as f32);
    let mix = |p: f32, q: f32| p * s0 + q * s1;
    gf::Quatf {
        w: mix(a.w, b.w),
        x: mix(a.x, b.x),
        y: mix(a.y, b.y),
        z: mix(a.z, b.z),
    }
}

/// `GfSlerp` of two `GfQuath`: the imaginary dot product in float rounded to half (GfVec3h's
/// dot returns a half), plus the real product in float; `θ` and `sin θ` halves; the weights
/// rounded to half; products and sums of halves formed in float.
fn slerp_h(a: gf::Quath, b: gf::Quath, alpha: f64) -> gf::Quath {
    let f = |h: f16| h.to_f32();
    let dot = f16::from_f32(f(a.x) * f(b.x) + f(a.y) * f(b.y) + f(a.z) * f(b.z));
    let cos = f64::from(dot.to_f32() + f(a.w) * f(b.w));
    let (s0, s1) = slerp_weights(cos, alpha, |c| {
        let theta = f16::from_f32(c.acos() as f32);
        (theta.to_f64(), f16::from_f32(theta.to_f32().sin()).to_f64())
    });
    let (s0, s1) = (f16::from_f32(s0 as f32), f16::from_f32(s1 as f32));
    let mix = |p: f16, q: f16| {
        let p = f16::from_f32(f(p) * f(s0));
        let q = f16::from_f32(f(q) * f(s1));
        f16::from_f32(f(p) + f(q))
    };
    gf::Quath {
        w: mix(a.w, b.w),
        x: mix(a.x, b.x),
        y: mix(a.y, b.y),
        z: mix(a.z, b.z),
    }
}

/// Element-wise interpolation of two arrays of the same length (`None` otherwise: held).
/// At `alpha == 1` the upper array is returned as is, as C++ does.
fn array<T: Copy>(a: &[T], b: &[T], alpha: f64, f: impl Fn(T, T, f64) -> T) -> Option<Vec<T>> {
    if a.len() != b.len() {
        return None;
    }
    if alpha == 1.0 {
        return Some(b.to_vec());
    }
    Some(a.iter().zip(b).map(|(&x, &y)| f(x, y, alpha)).collect())
}

/// `Usd_Lerp` of two samples of the same type at parameter `alpha` (neither 0 nor blocked).
/// `None` when the type does not interpolate or the arrays differ in length: the caller
/// then holds the lower sample, as usd-core does.
pub(super) fn lerp_value(a: &Value, b: &Value, alpha: f64) -> Option<Value> {
    use crate::sdf::Value as V;
    let t = alpha;
    macro_rules! vf {
        ($x:expr, $y:expr, $n:literal) => {
            components::<_, f32, $n>(*$x, *$y, |p, q| comp_f(p, q, t))
        };
    }
    macro_rules! vd {
        ($x:expr, $y:expr, $n:literal) => {
            components::<_, f64, $n>(*$x, *$y, |p, q| lerp_d(p, q, t))
        };
    }
    macro_rules! vh {
        ($x:expr, $y:expr, $n:literal) => {
            components::<_, f16, $n>(*$x, *$y, |p, q| comp_h(p, q, t))
        };
    }
    macro_rules! arr {
        ($x:expr, $y:expr, $f:expr) => {
            array($x, $y, t, $f)?
        };
    }
    Some(match (a, b) {
        (V::Half(x), V::Half(y)) => V::Half(lerp_h(*x, *y, t)),
        (V::Float(x), V::Float(y)) => V::Float(lerp_f(*x, *y, t)),
        (V::Double(x), V::Double(y)) => V::Double(lerp_d(*x, *y, t)),
        (V::TimeCode(x), V::TimeCode(y)) => V::TimeCode(lerp_d(x.0, y.0, t).into()),

        (V::Matrix2d(x), V::Matrix2d(y)) => V::Matrix2d(gf::Mat2d(vd!(&x.0, &y.0, 4))),
        (V::Matrix3d(x), V::Matrix3d(y)) => V::Matrix3d(gf::Mat3d(vd!(&x.0, &y.0, 9))),
        (V::Matrix4d(x), V::Matrix4d(y)) => V::Matrix4d(gf::Matrix4d(vd!(&x.0, &y.0, 16))),

        (V::Vec2h(x), V::Vec2h(y)) => V::Vec2h(vh!(x, y, 2)),
        (V::Vec2f(x), V::Vec2f(y)) => V::Vec2f(vf!(x, y, 2)),
        (V::Vec2d(x), V::Vec2d(y)) => V::Vec2d(vd!(x, y, 2)),
        (V::Vec3h(x), V::Vec3h(y)) => V::Vec3h(vh!(x, y, 3)),
        (V::Vec3f(x), V::Vec3f(y)) => V::Vec3f(vf!(x, y, 3)),
        (V::Vec3d(x), V::Vec3d(y)) => V::Vec3d(vd!(x, y, 3)),
        (V::Vec4h(x), V::Vec4h(y)) => V::Vec4h(vh!(x, y, 4)),
        (V::Vec4f(x), V::Vec4f(y)) => V::Vec4f(vf!(x, y, 4)),
        (V::Vec4d(x), V::Vec4d(y)) => V::Vec4d(vd!(x, y, 4)),

        (V::Quath(x), V::Quath(y)) => V::Quath(slerp_h(*x, *y, t)),
        (V::Quatf(x), V::Quatf(y)) => V::Quatf(slerp_f(*x, *y, t)),
        (V::Quatd(x), V::Quatd(y)) => V::Quatd(slerp_d(*x, *y, t)),

        (V::HalfVec(x), V::HalfVec(y)) => V::HalfVec(arr!(x, y, lerp_h)),
        (V::FloatVec(x), V::FloatVec(y)) => V::FloatVec(arr!(x, y, lerp_f)),
        (V::DoubleVec(x), V::DoubleVec(y)) => V::DoubleVec(arr!(x, y, lerp_d)),
        (V::TimeCodeVec(x), V::TimeCodeVec(y)) => {
            V::TimeCodeVec(arr!(x, y, |p: crate::sdf::TimeCode, q: crate::sdf::TimeCode, t| {
                lerp_d(p.0, q.0, t).into()
            }))
        }

        (V::Matrix2dVec(x), V::Matrix2dVec(y)) => {
            V::Matrix2dVec(arr!(x, y, |p: gf::Mat2d, q: gf::Mat2d, _| gf::Mat2d(vd!(&p.0, &q.0, 4))))
        }
        (V::Matrix3dVec(x), V::Matrix3dVec(y)) => {
            V::Matrix3dVec(arr!(x, y, |p: gf::Mat3d, q: gf::Mat3d, _| gf::Mat3d(vd!(&p.0, &q.0, 9))))
        }
        (V::Matrix4dVec(x), V::Matrix4dVec(y)) => V::Matrix4dVec(arr!(x, y, |p: gf::Matrix4d, q: gf::Matrix4d, _| {
            gf::Matrix4d(vd!(&p.0, &q.0, 16))
        })),

        (V::Vec2hVec(x), V::Vec2hVec(y)) => V::Vec2hVec(arr!(x, y, |p, q, _| vh!(&p, &q, 2))),
        (V::Vec2fVec(x), V::Vec2fVec(y)) => V::Vec2fVec(arr!(x, y, |p, q, _| vf!(&p, &q, 2))),
        (V::Vec2dVec(x), V::Vec2dVec(y)) => V::Vec2dVec(arr!(x, y, |p, q, _| vd!(&p, &q, 2))),
        (V::Vec3hVec(x), V::Vec3hVec(y)) => V::Vec3hVec(arr!(x, y, |p, q, _| vh!(&p, &q, 3))),
        (V::Vec3fVec(x), V::Vec3fVec(y)) => V::Vec3fVec(arr!(x, y, |p, q, _| vf!(&p, &q, 3))),
        (V::Vec3dVec(x), V::Vec3dVec(y)) => V::Vec3dVec(arr!(x, y, |p, q, _| vd!(&p, &q, 3))),
        (V::Vec4hVec(x), V::Vec4hVec(y)) => V::Vec4hVec(arr!(x, y, |p, q, _| vh!(&p, &q, 4))),
        (V::Vec4fVec(x), V::Vec4fVec(y)) => V::Vec4fVec(arr!(x, y, |p, q, _| vf!(&p, &q, 4))),
        (V::Vec4dVec(x), V::Vec4dVec(y)) => V::Vec4dVec(arr!(x, y, |p, q, _| vd!(&p, &q, 4))),

        (V::QuathVec(x), V::QuathVec(y)) => V::QuathVec(arr!(x, y, slerp_h)),
        (V::QuatfVec(x), V::QuatfVec(y)) => V::QuatfVec(arr!(x, y, slerp_f)),
        (V::QuatdVec(x), V::QuatdVec(y)) => V::QuatdVec(arr!(x, y, slerp_d)),

        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// usd-core 26.11, `Gf.Lerp`-style reads of a `float3` sampled `(0.1, 0.2, 0.3)` at 0 and
    /// `(1.7, -2.9, 3.3)` at 3, read at 1: each component rounded after its product.
    #[test]
    fn vec3f_rounds_each_product_to_float() {
        let a = gf::vec3f(0.1, 0.2, 0.3);
        let b = gf::vec3f(1.7, -2.9, 3.3);
        let alpha = 1.0 / 3.0;
        let got = lerp_value(&Value::Vec3f(a), &Value::Vec3f(b), alpha).unwrap();
        let expect = |p: f32, q: f32| (f64::from(p) * (1.0 - alpha)) as f32 + (f64::from(q) * alpha) as f32;
        assert_eq!(
            got,
            Value::Vec3f(gf::vec3f(expect(0.1, 1.7), expect(0.2, -2.9), expect(0.3, 3.3)))
        );
    }

    #[test]
    fn float_scalar_rounds_once() {
        let alpha = 0.3;
        let got = lerp_value(&Value::Float(0.1), &Value::Float(0.7), alpha).unwrap();
        assert_eq!(got, Value::Float((0.7 * 0.1f32 as f64 + 0.3 * 0.7f32 as f64) as f32));
    }

    #[test]
    fn arrays_of_other_lengths_do_not_interpolate() {
        let a = Value::FloatVec(vec![1.0, 2.0]);
        let b = Value::FloatVec(vec![1.0]);
        assert_eq!(lerp_value(&a, &b, 0.5), None);
    }

    #[test]
    fn quatd_slerp_is_unit_between_unit_ends() {
        let a = gf::quatd(1.0, 0.0, 0.0, 0.0);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let b = gf::quatd(h, 0.0, h, 0.0);
        let Some(Value::Quatd(q)) = lerp_value(&Value::Quatd(a), &Value::Quatd(b), 0.5) else {
            panic!("a quatd");
        };
        let angle = std::f64::consts::PI / 8.0;
        assert!((q.w - angle.cos()).abs() < 1e-15 && (q.y - angle.sin()).abs() < 1e-15);
    }
}
