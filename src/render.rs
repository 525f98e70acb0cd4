//! Tracing: rays from a camera or a list, in parallel, into the requested AOV buffers.
//!
//! Every ray is traced independently and results are stored by ray index, so the buffers are
//! bit-identical for any thread count. Only the requested AOVs are computed.

use crate::accel::{prepare_ray, Bvh, BvhKind, Hit, Octree, OctreeParams};
use crate::camera::Camera;
use crate::geometry::Ray;
use crate::scene::Scene;
use glam::DVec3;
use rayon::prelude::*;
use std::fmt;
use std::str::FromStr;

/// An output buffer kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Aov {
    /// Distance from the ray origin to the hit, `|hit - origin|`; +inf on a miss.
    Depth,
    /// Camera-space depth along the view axis (camera mode only); +inf on a miss.
    Z,
    /// World-space unit geometric normal; (0, 0, 0) on a miss.
    Normal,
    /// World-space hit point; (+inf, +inf, +inf) on a miss.
    Position,
    /// 1-based object id; 0 on a miss.
    Id,
    /// Primitive index inside the object; `u32::MAX` on a miss.
    Prim,
}

impl Aov {
    /// All AOVs, in output order.
    pub const ALL: [Aov; 6] = [
        Aov::Depth,
        Aov::Z,
        Aov::Normal,
        Aov::Position,
        Aov::Id,
        Aov::Prim,
    ];

    /// The name used on the command line and in file names.
    pub fn name(self) -> &'static str {
        match self {
            Aov::Depth => "depth",
            Aov::Z => "z",
            Aov::Normal => "normal",
            Aov::Position => "position",
            Aov::Id => "id",
            Aov::Prim => "prim",
        }
    }
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
            format!("unknown AOV '{s}' (choose from depth, z, normal, position, id, prim)")
        })
    }
}

/// Something that yields rays by index: a camera image or a list of rays.
pub trait RaySource: Sync {
    /// Number of rays.
    fn len(&self) -> usize;
    /// True when there are no rays.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Ray number `index`.
    fn ray(&self, index: usize) -> Ray;
    /// Eye and unit view direction, for the `z` AOV (cameras only).
    fn view_axis(&self) -> Option<(DVec3, DVec3)> {
        None
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
    half_height: f64,
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
}

impl RaySource for Vec<Ray> {
    fn len(&self) -> usize {
        Vec::len(self)
    }
    fn ray(&self, index: usize) -> Ray {
        self[index]
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
}

/// The requested buffers, one value per ray (row-major pixels in camera mode).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Buffers {
    /// `depth` values.
    pub depth: Option<Vec<f64>>,
    /// `z` values.
    pub z: Option<Vec<f64>>,
    /// `normal` values.
    pub normal: Option<Vec<DVec3>>,
    /// `position` values.
    pub position: Option<Vec<DVec3>>,
    /// `id` values.
    pub id: Option<Vec<u32>>,
    /// `prim` values.
    pub prim: Option<Vec<u32>>,
}

/// Rays traced per progress report.
const CHUNK: usize = 1 << 16;

/// Traces every ray of `source` and fills the buffers of `aovs`. `progress` is told how many
/// rays are done after each chunk.
pub fn render(
    tracer: &Tracer,
    source: &(impl RaySource + ?Sized),
    aovs: &[Aov],
    mut progress: impl FnMut(usize),
) -> Buffers {
    let n = source.len();
    let mut hits: Vec<Option<Hit>> = Vec::with_capacity(n);
    for start in (0..n).step_by(CHUNK) {
        let end = (start + CHUNK).min(n);
        hits.par_extend(
            (start..end)
                .into_par_iter()
                .map(|i| tracer.trace(&source.ray(i))),
        );
        progress(end);
    }
    let fill = |f: &(dyn Fn(usize, &Hit) -> f64 + Sync), miss: f64| {
        (0..n)
            .into_par_iter()
            .map(|i| hits[i].as_ref().map_or(miss, |h| f(i, h)))
            .collect::<Vec<f64>>()
    };
    let fill3 = |f: &(dyn Fn(usize, &Hit) -> DVec3 + Sync), miss: DVec3| {
        (0..n)
            .into_par_iter()
            .map(|i| hits[i].as_ref().map_or(miss, |h| f(i, h)))
            .collect::<Vec<DVec3>>()
    };
    let fill_u32 = |f: &(dyn Fn(usize, &Hit) -> u32 + Sync), miss: u32| {
        (0..n)
            .into_par_iter()
            .map(|i| hits[i].as_ref().map_or(miss, |h| f(i, h)))
            .collect::<Vec<u32>>()
    };
    let point = |i: usize, h: &Hit| source.ray(i).at(h.t);
    let mut buffers = Buffers::default();
    for aov in aovs {
        match aov {
            Aov::Depth => {
                buffers.depth = Some(fill(
                    &|i, h| h.t * source.ray(i).dir.length(),
                    f64::INFINITY,
                ))
            }
            Aov::Z => {
                let (eye, forward) = source.view_axis().unwrap_or((DVec3::ZERO, DVec3::ZERO));
                buffers.z = Some(fill(
                    &|i, h| (point(i, h) - eye).dot(forward),
                    f64::INFINITY,
                ))
            }
            Aov::Normal => {
                let normal = |i: usize, h: &Hit| {
                    let ray = source.ray(i);
                    tracer.scene.locate(h, ray.origin, ray.dir).normal
                };
                buffers.normal = Some(fill3(&normal, DVec3::ZERO))
            }
            Aov::Position => buffers.position = Some(fill3(&point, DVec3::INFINITY)),
            Aov::Id => buffers.id = Some(fill_u32(&|_, h| tracer.scene.object(h.prim).id, 0)),
            Aov::Prim => {
                let prim = |i: usize, h: &Hit| {
                    let ray = source.ray(i);
                    tracer.scene.locate(h, ray.origin, ray.dir).prim
                };
                buffers.prim = Some(fill_u32(&prim, u32::MAX))
            }
        }
    }
    buffers
}
