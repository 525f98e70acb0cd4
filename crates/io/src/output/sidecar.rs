//! The JSON sidecar `raycast.json` that travels with every set of buffers.

use crate::accel::{OctreeParams, OctreeStats};
use crate::camera::{Camera, Projection};
use crate::scene::{Object, PoseInfo, StageInfo};
use serde::Serialize;
use std::collections::BTreeMap;

/// Everything `raycast.json` records about a run.
#[derive(Debug, Clone, Serialize)]
pub struct Sidecar {
    /// Version of raycast that wrote it.
    pub raycast_version: &'static str,
    /// The scene file, as given.
    pub scene: String,
    /// The scene file's canonical path: a later render into the same folder replaces these
    /// outputs only when it renders the same file (see [`super::ownership`]).
    pub scene_file: String,
    /// `camera` or `rays`.
    pub mode: &'static str,
    /// Image width (camera mode).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub width: Option<usize>,
    /// Image height (camera mode).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height: Option<usize>,
    /// Number of rays (rays mode).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rays: Option<usize>,
    /// The camera actually used (camera mode).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub camera: Option<CameraInfo>,
    /// AOVs written.
    pub aovs: Vec<String>,
    /// What each AOV means, including its miss value.
    pub conventions: BTreeMap<&'static str, &'static str>,
    /// Files written, besides this one.
    pub files: Vec<String>,
    /// What `hits.npz` holds (with `--hits`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hits: Option<HitsInfo>,
    /// Depth range mapped into `depth.png` (near = light, far = dark).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub depth_png_range: Option<[f64; 2]>,
    /// With `--colormap viridis|turbo`: the colour map of the distance previews.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub depth_png_colormap: Option<&'static str>,
    /// With `--depth-png u16`: depth.png and z.png hold 16-bit integers, each this many scene
    /// units (distance / scale, rounded); 0 is no data (a miss, or out of range).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub depth_png_scale: Option<f64>,
    /// With `--aov error` or `--aov certain`: the largest bound and the uncertain rays.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bounds: Option<BoundsInfo>,
    /// With `--cryptomatte`: the samples per pixel of `cryptomatte.exr`'s object mattes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cryptomatte_spp: Option<usize>,
    /// The object table; `id` indexes it from 1.
    pub objects: Vec<Object>,
    /// With `--aov material` or `--cryptomatte`: the materials, named as the file names
    /// them; `material` indexes it from 1.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub materials: Option<Vec<String>>,
    /// Totals.
    pub stats: Stats,
    /// Seconds per stage.
    pub timings: Timings,
    /// USD stage metadata (`upAxis`, `metersPerUnit`), for USD scenes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stage: Option<StageInfo>,
    /// What the importer decoded (Draco, meshopt, GPU instancing), one line per extension.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub decoded: Vec<String>,
    /// glTF animations, skins and morph targets, and the pose drawn: the `--time` and the
    /// animations applied (glTF files that have any).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pose: Option<PoseInfo>,
    /// Importer and render warnings.
    pub warnings: Vec<String>,
}

/// A summary of the `error` and `certain` buffers.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct BoundsInfo {
    /// The largest finite `error` (scene units), with `--aov error`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub largest_error: Option<f64>,
    /// Hits whose `error` is `+∞` (no bound could be made), with `--aov error`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unbounded_hits: Option<usize>,
    /// Rays whose `certain` is 0, with `--aov certain`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub uncertain_rays: Option<usize>,
}

impl BoundsInfo {
    /// The summary of `buffers`, or `None` when neither AOV was computed.
    pub fn of(buffers: &crate::render::Buffers) -> Option<BoundsInfo> {
        use crate::render::Aov;
        let errors = buffers.floats(Aov::Error);
        let flags = buffers.flags(Aov::Certain);
        if errors.is_none() && flags.is_none() {
            return None;
        }
        let finite = |e: &&f64| e.is_finite();
        Some(BoundsInfo {
            largest_error: errors.map(|e| e.iter().filter(finite).fold(0.0, |a, &b| b.max(a))),
            unbounded_hits: errors.map(|e| e.iter().filter(|e| e.is_infinite()).count()),
            uncertain_rays: flags.map(|f| f.iter().filter(|&&c| c == 0).count()),
        })
    }
}

/// The crossing lists of `--hits`.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct HitsInfo {
    /// The most crossings listed per ray; `None` (null) for all.
    pub limit: Option<usize>,
    /// Crossings listed in all.
    pub crossings: usize,
}

/// Scene and acceleration totals.
#[derive(Debug, Clone, Serialize)]
pub struct Stats {
    /// Triangles.
    pub triangles: usize,
    /// Quadrics.
    pub quadrics: usize,
    /// Objects.
    pub objects: usize,
    /// The acceleration structure used: always `octree` (the obvhs BVH is a test oracle;
    /// the field stays for the readers of sidecars written when `--accel` could choose it).
    pub accel: &'static str,
    /// Octree size figures.
    pub octree: OctreeStats,
    /// Octree build parameters.
    pub octree_params: OctreeParams,
}

/// Seconds spent per stage.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct Timings {
    /// Reading and importing the scene.
    pub load: f64,
    /// Building the octree.
    pub build: f64,
    /// Tracing rays and filling buffers.
    pub trace: f64,
    /// Writing buffers.
    pub write: f64,
}

/// The camera as recorded in the sidecar (enough to regenerate every ray).
#[derive(Debug, Clone, Serialize)]
pub struct CameraInfo {
    /// Where the camera came from.
    pub source: String,
    /// Its name.
    pub name: String,
    /// Projection type and its parameters (`yfov`, `ymag`, or a pinhole's `k`, `width` and
    /// `height`).
    #[serde(flatten)]
    pub projection: Projection,
    /// Image width / height used for the rays.
    pub aspect_ratio: f64,
    /// Half the view width (orthographic only): `ymag · aspect_ratio`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub xmag: Option<f64>,
    /// Near clipping distance from the file (rays start at the eye regardless).
    pub znear: f64,
    /// Far clipping distance from the file; null = infinite.
    pub zfar: Option<f64>,
    /// Camera-to-world matrix, row-major.
    pub camera_to_world: [[f64; 4]; 4],
}

impl CameraInfo {
    /// The record of `camera` used for a `width`×`height` image.
    pub fn new(camera: &Camera, width: usize, height: usize) -> CameraInfo {
        let aspect_ratio = width as f64 / height as f64;
        let rows = camera.to_world.transpose().to_cols_array_2d();
        CameraInfo {
            source: camera.source.clone(),
            name: camera.name.clone(),
            projection: camera.projection,
            aspect_ratio,
            xmag: match camera.projection {
                Projection::Orthographic { ymag } => Some(ymag * aspect_ratio),
                Projection::Perspective { .. } | Projection::Pinhole(_) => None,
            },
            znear: camera.znear,
            zfar: camera.zfar,
            camera_to_world: rows,
        }
    }
}

/// The meaning of each AOV, as written to the sidecar.
pub fn conventions() -> BTreeMap<&'static str, &'static str> {
    BTreeMap::from([
        ("depth", "distance from the ray origin to the hit, |hit - origin|, in scene units; miss = +inf"),
        ("t", "ray parameter of the hit, hit = origin + t * direction, in units of |direction|; miss = +inf"),
        ("bary", "barycentric weights (w0, w1, w2) of the hit triangle's vertices in the mesh's order; miss or quadric = (0, 0, 0)"),
        ("hits", "hits.npz: ray i's crossings are entries ray_splits[i]:ray_splits[i+1] of t, id and prim, nearest first; each surface crossing once"),
        ("z", "camera-space depth along the view axis; miss = +inf"),
        ("normal", "world-space unit geometric normal; triangles: counter-clockwise winding is the front, not flipped toward the ray; quadrics: gradient direction, toward f > 0; miss = (0, 0, 0)"),
        ("position", "world-space hit point; miss = (+inf, +inf, +inf)"),
        ("id", "1-based object id indexing `objects`; miss = 0"),
        ("uv", "the file's texture coordinates (glTF TEXCOORD_0, OBJ vt, USD primvars:st, PLY u v / s t) interpolated with the hit's barycentric weights, as stored (glTF's origin is the top left; nothing is flipped); miss, quadric or none in the file = (+inf, +inf)"),
        ("shading_normal", "world-space unit shading normal: the file's normals interpolated, mapped by the inverse transpose of the placement; quadrics: the analytic normal (as normal); miss or none in the file = (0, 0, 0)"),
        ("material", "1-based material id indexing `materials`; miss or no material = 0"),
        ("error", "bound on |depth - exact depth| where the exact depth is that of the ray (its f64 numbers) with the same primitive's exact surface (the file's numbers as read, placed by its f64 node matrix); scene units; +inf = no bound; miss = 0"),
        ("certain", "1 when no value within the bounds could change the decision (which primitive is nearest, hit or miss); 0 otherwise; needs the octree"),
        ("prim", "triangle index inside the object in the object's own order, 0 for quadrics; miss = 4294967295"),
        ("pixels", "one ray per pixel through the pixel centre; row 0 is the top row; the camera looks down its local -Z with +Y up; yfov is vertical"),
    ])
}
