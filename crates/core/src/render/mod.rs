//! Tracing: rays from a camera or a list, in parallel, into the requested AOV buffers.
//!
//! Every ray is traced independently and results are stored by ray index, so the buffers are
//! bit-identical for any thread count. Only the requested AOVs are computed.

mod fill;
pub mod samples;

pub use fill::{trace, Buffers, Column, Rays};

use crate::accel::{prepare_ray, Bvh, BvhKind, Hit, Octree, OctreeParams, PACKET};
use crate::camera::Camera;
use crate::geometry::{Ray, RaySource};
use crate::query::Query;
use crate::scene::{Crossing, Scene};
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
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Aov::ALL.into_iter().find(|a| a.name() == s).ok_or_else(|| {
            let names: Vec<&str> = Aov::ALL.iter().map(|a| a.name()).collect();
            format!("unknown AOV '{s}' (choose from {})", names.join(", "))
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

/// Which acceleration structure to build: the octree (the default) or an obvhs BVH.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum AccelKind {
    /// The octree of [`crate::accel::octree`].
    #[default]
    Octree,
    /// An obvhs hierarchy (see [`crate::accel::bvh`]).
    Bvh(BvhKind),
}

impl AccelKind {
    /// All choices, in the order the command line lists them.
    pub const ALL: [AccelKind; 3] = [
        AccelKind::Octree,
        AccelKind::Bvh(BvhKind::Bvh2),
        AccelKind::Bvh(BvhKind::Cwbvh),
    ];

    /// The name used on the command line and in the sidecar.
    pub fn name(self) -> &'static str {
        match self {
            AccelKind::Octree => "octree",
            AccelKind::Bvh(kind) => kind.name(),
        }
    }
}

impl fmt::Display for AccelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for AccelKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        AccelKind::ALL
            .into_iter()
            .find(|a| a.name() == s)
            .ok_or_else(|| {
                format!("unknown acceleration structure '{s}' (choose octree, bvh, cwbvh)")
            })
    }
}

/// Memory per primitive that building an acceleration structure takes, for the estimate a
/// render checks against its memory limit: each primitive's box (48 bytes) and, measured
/// as the growth of peak memory from loading to building on the shared assets, 25 to 74
/// bytes for the tree (4 to 6 references per primitive). A scene of large crossing
/// triangles may take up to 256 references per primitive (about 1 KiB), the octree's bound.
pub const ACCEL_BYTES_PER_PRIMITIVE: u64 = 128;

/// A built acceleration structure of either backend.
#[derive(Debug, Clone)]
pub enum AccelStructure {
    /// The octree.
    Octree(Octree),
    /// An obvhs hierarchy.
    Bvh(Bvh),
}

impl AccelStructure {
    /// Builds the structure of `kind` over `scene` (`params` apply to the octree only).
    /// The octrees of instanced meshes are built first ([`Scene::build_instances`]). Building
    /// them alongside with `rayon::join` runs the whole build on a pool thread, whose
    /// allocator keeps what it frees: six builds in a row (benches/trace.rs) then peaked at 34
    /// instead of 24 MiB on the bunny.
    pub fn build(scene: &Scene, kind: AccelKind, params: OctreeParams) -> AccelStructure {
        scene.build_instances();
        match kind {
            AccelKind::Octree => AccelStructure::Octree(Octree::build(scene, params)),
            AccelKind::Bvh(kind) => AccelStructure::Bvh(Bvh::build(scene, kind)),
        }
    }

    /// An estimate of the memory building the structures over `scene` takes: the top-level
    /// one over its primitives and one per stored instanced mesh, at
    /// [`ACCEL_BYTES_PER_PRIMITIVE`] each.
    pub fn estimated_bytes(scene: &Scene) -> u64 {
        (scene.accel_primitive_count() as u64).saturating_mul(ACCEL_BYTES_PER_PRIMITIVE)
    }

    /// A borrowed view for a [`Tracer`].
    pub fn view(&self) -> Accel<'_> {
        match self {
            AccelStructure::Octree(o) => Accel::Octree(o),
            AccelStructure::Bvh(b) => Accel::Bvh(b),
        }
    }
}

/// The acceleration structure a [`Tracer`] traverses.
#[derive(Debug, Clone, Copy)]
pub enum Accel<'a> {
    /// The octree.
    Octree(&'a Octree),
    /// An obvhs hierarchy.
    Bvh(&'a Bvh),
}

impl<'a> From<&'a Octree> for Accel<'a> {
    fn from(octree: &'a Octree) -> Self {
        Accel::Octree(octree)
    }
}

impl<'a> From<&'a Bvh> for Accel<'a> {
    fn from(bvh: &'a Bvh) -> Self {
        Accel::Bvh(bvh)
    }
}

/// A scene with its acceleration structure, ready to trace.
#[derive(Debug, Clone, Copy)]
pub struct Tracer<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The acceleration structure built over the scene.
    pub accel: Accel<'a>,
}

impl<'a> Tracer<'a> {
    /// A tracer of `scene` through `accel` (an `&Octree` or a `&Bvh`).
    pub fn new(scene: &'a Scene, accel: impl Into<Accel<'a>>) -> Self {
        Tracer {
            scene,
            accel: accel.into(),
        }
    }

    /// The nearest hit of `ray` with `t > 0`.
    pub fn trace(&self, ray: &Ray) -> Option<Hit> {
        if !ray.is_valid() {
            return None;
        }
        let local = ray.origin - self.scene.anchor;
        match self.accel {
            Accel::Octree(octree) => {
                octree.intersect_ray(self.scene, local, ray.dir, f64::INFINITY)
            }
            Accel::Bvh(bvh) => {
                let prepared = prepare_ray(self.scene, local, ray.dir);
                bvh.intersect(self.scene, &prepared, f64::INFINITY)
            }
        }
    }

    /// The nearest crossing with `t_min < t <= t_max` (and `t > 0`); `None` for a miss or a
    /// ray [`Query::nearest`] refuses. With `t_min = 0` it is [`Tracer::trace`]'s hit. The
    /// BVH backends search from `t = 0` only: they give `None` for `t_min > 0` (ranges need
    /// the octree, see [`Tracer::query`]).
    #[inline]
    pub fn nearest(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<Crossing> {
        match self.accel {
            Accel::Octree(octree) => Query {
                scene: self.scene,
                octree,
            }
            .nearest(ray, t_min, t_max),
            Accel::Bvh(bvh) => {
                if !ray.is_valid() || t_min != 0.0 || t_max.is_nan() {
                    return None;
                }
                let local = ray.origin - self.scene.anchor;
                let prepared = prepare_ray(self.scene, local, ray.dir);
                bvh.intersect(self.scene, &prepared, t_max)
                    .map(Crossing::from)
            }
        }
    }

    /// [`Tracer::nearest`] for every ray of `rays` with its range in `ranges`: with the octree,
    /// runs of [`PACKET`] rays that can go together are traced as packets (the same answers,
    /// fewer node visits for coherent rays such as a camera's), the others one by one.
    pub fn nearest_all(&self, rays: &[Ray], ranges: &[(f64, f64)]) -> Vec<Option<Crossing>> {
        let one = |(ray, &(t_min, t_max)): (&Ray, &(f64, f64))| self.nearest(ray, t_min, t_max);
        let Some(query) = self.query() else {
            return rays.iter().zip(ranges).map(one).collect();
        };
        let mut hits = Vec::with_capacity(rays.len());
        let (packets, rest) = rays.as_chunks::<PACKET>();
        let (packet_ranges, rest_ranges) = ranges.as_chunks::<PACKET>();
        // Directions' signs first: incoherent rays stop here, before any set-up.
        let octant = |ray: &Ray| ray.dir.cmplt(DVec3::ZERO).bitmask();
        for (packet, range) in packets.iter().zip(packet_ranges) {
            let first = octant(&packet[0]);
            let coherent = packet.iter().all(|ray| octant(ray) == first);
            if coherent {
                let start = hits.len();
                hits.resize(start + PACKET, None);
                let found = hits[start..].as_mut_array().expect("PACKET slots");
                if query.nearest_packet(packet, range, found) {
                    continue;
                }
                hits.truncate(start);
            }
            hits.extend(packet.iter().zip(range).map(one));
        }
        hits.extend(rest.iter().zip(rest_ranges).map(one));
        hits
    }

    /// The queries beyond the nearest hit ([`Query`]), which need the octree.
    pub fn query(&self) -> Option<Query<'a>> {
        match self.accel {
            Accel::Octree(octree) => Some(Query {
                scene: self.scene,
                octree,
            }),
            Accel::Bvh(_) => None,
        }
    }
}

/// Traces every ray of `source` from `t > 0` and fills the buffers of `aovs` (see [`trace`]).
/// `progress` is told how many rays are done after each chunk.
pub fn render(
    tracer: &Tracer,
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
