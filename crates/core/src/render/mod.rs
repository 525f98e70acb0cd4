//! Tracing: rays from a camera or a list, in parallel, into the requested AOV buffers.
//!
//! Every ray is traced independently and results are stored by ray index, so the buffers are
//! bit-identical for any thread count. Only the requested AOVs are computed.

mod bounds;
mod fill;
mod order;
pub mod samples;

pub use fill::{trace, Buffers, Column, Rays};

use crate::camera::Camera;
use crate::geometry::{Ray, RaySource};
use crate::scene::Scene;
use crate::trace::NearestHits;
use glam::DVec3;
use std::fmt;
use std::str::FromStr;

/// An output buffer kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Aov {
    /// Distance from the ray origin to the hit, `|hit - origin|`; +inf on a miss.
    Depth,
    /// Camera-space depth along the view axis (camera mode only); +inf on a miss.
    Z,
    /// The ray parameter of the hit, `hit = origin + t · direction` (units of |direction|);
    /// +inf on a miss.
    T,
    /// World-space unit geometric normal; (0, 0, 0) on a miss.
    Normal,
    /// World-space hit point; (+inf, +inf, +inf) on a miss.
    Position,
    /// Barycentric weights of the hit triangle's three vertices, in the mesh's order;
    /// (0, 0, 0) on a miss or a quadric.
    Bary,
    /// 1-based object id; 0 on a miss.
    Id,
    /// Primitive index inside the object; `u32::MAX` on a miss.
    Prim,
    /// A bound on the depth's distance from the exact depth of the same primitive's crossing
    /// (scene units; see [`crate::bound`]); `+∞` where none can be made, 0 on a miss.
    Error,
    /// 1 when no value within the bounds could change the ray's decision (nearest primitive,
    /// hit or miss), else 0 (see [`crate::bound`]); needs the octree (0 with a BVH).
    Certain,
    /// The file's texture coordinates (glTF `TEXCOORD_0`, OBJ `vt`, USD `primvars:st`, PLY
    /// `u v`/`s t`) interpolated at the hit, as stored; (+inf, +inf) on a miss, a quadric or
    /// a mesh without them.
    Uv,
    /// Unit world shading normal: the file's normals interpolated and mapped by the inverse
    /// transpose of the placement; quadrics: the analytic normal; (0, 0, 0) on a miss or a
    /// mesh without normals.
    ShadingNormal,
    /// 1-based material id, indexing the scene's materials; 0 on a miss or without material.
    Material,
}

impl Aov {
    /// All AOVs, in output order.
    pub const ALL: [Aov; 13] = [
        Aov::Depth,
        Aov::Z,
        Aov::T,
        Aov::Normal,
        Aov::Position,
        Aov::Bary,
        Aov::Id,
        Aov::Prim,
        Aov::Error,
        Aov::Certain,
        Aov::Uv,
        Aov::ShadingNormal,
        Aov::Material,
    ];

    /// The name used on the command line and in file names.
    pub fn name(self) -> &'static str {
        match self {
            Aov::Depth => "depth",
            Aov::Z => "z",
            Aov::T => "t",
            Aov::Normal => "normal",
            Aov::Position => "position",
            Aov::Bary => "bary",
            Aov::Id => "id",
            Aov::Prim => "prim",
            Aov::Error => "error",
            Aov::Certain => "certain",
            Aov::Uv => "uv",
            Aov::ShadingNormal => "shading_normal",
            Aov::Material => "material",
        }
    }
}

/// One warning for each of `aovs` that reads a shading attribute some of the scene's objects
/// lack (`uv`, `shading_normal`, `material`): their hits hold the AOV's miss value.
pub fn attribute_warnings(scene: &Scene, aovs: &[Aov]) -> Vec<String> {
    use crate::scene::Attribute;
    let mut warnings = Vec::new();
    for &aov in aovs {
        let attribute = match aov {
            Aov::Uv => Attribute::Uv,
            Aov::ShadingNormal => Attribute::Normal,
            Aov::Material => Attribute::Material,
            _ => continue,
        };
        if let Some(line) = scene.missing_attribute(attribute) {
            warnings.push(format!("{aov}: {line}"));
        }
    }
    warnings
}

impl fmt::Display for Aov {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Aov {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        Aov::ALL.into_iter().find(|a| a.name() == s).ok_or_else(|| {
            let names: Vec<&str> = Aov::ALL.iter().map(|a| a.name()).collect();
            let message = format!("unknown AOV '{s}' (choose from {})", names.join(", "));
            crate::Error::usage(message)
        })
    }
}

/// A camera image: one ray per pixel, row-major from the top row.
#[derive(Debug, Clone)]
pub struct CameraView {
    /// The camera.
    pub camera: Camera,
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// The camera's [`Camera::half_height`], computed once rather than per pixel.
    pub(crate) half_height: f64,
}

impl CameraView {
    /// A `width`×`height` image seen by `camera`.
    pub fn new(camera: Camera, width: usize, height: usize) -> CameraView {
        let half_height = camera.half_height();
        CameraView {
            camera,
            width,
            height,
            half_height,
        }
    }
}

impl RaySource for CameraView {
    fn len(&self) -> usize {
        self.width * self.height
    }
    fn ray(&self, index: usize) -> Ray {
        self.camera.screen_ray(
            index % self.width,
            index / self.width,
            self.width,
            self.height,
            self.half_height,
        )
    }
    fn view_axis(&self) -> Option<(DVec3, DVec3)> {
        Some((self.camera.eye(), self.camera.forward()))
    }
    fn row_width(&self) -> Option<usize> {
        Some(self.width)
    }
}

/// Traces every ray of `source` from `t > 0` and fills the buffers of `aovs` (see [`trace`]).
/// `progress` is told how many rays are done after each chunk.
pub fn render(
    tracer: &dyn NearestHits,
    source: &(impl RaySource + ?Sized),
    aovs: &[Aov],
    progress: impl FnMut(usize) + Send,
) -> Buffers {
    let rays = Rays {
        source,
        range: |_| (0.0, f64::INFINITY),
        refuse_untraceable: false,
    };
    match trace(tracer, &rays, aovs, progress) {
        Ok(buffers) => buffers,
        Err(_) => unreachable!("no ray is refused"),
    }
}
