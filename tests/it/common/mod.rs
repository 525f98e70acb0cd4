//! Helpers shared by the integration tests: fixture paths and casting rays through the library.
#![allow(dead_code)]

use glam::{DMat4, DQuat, DVec3};
use raycast::accel::{Octree, OctreeParams, PreparedRay, PrimitiveSet};
use raycast::geometry::Ray;
use raycast::import::{self, LoadOptions};
use raycast::quadric::{Quadric, QuadricSpec};
use raycast::render::{self, Aov};
use raycast::scene::{Scene, SceneBuilder};
use raycast::trace::Tracer;
use std::path::{Path, PathBuf};

/// Path of a file under `fixtures/`.
pub fn fixture(relative: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(relative)
}

/// Loads a fixture with default options.
/// The scene's warnings as the lines the command line prints.
pub fn lines(scene: &Scene) -> Vec<String> {
    scene.warnings.iter().map(ToString::to_string).collect()
}

pub fn load(relative: &str) -> Scene {
    import::load(&fixture(relative), &LoadOptions::default())
        .unwrap_or_else(|e| panic!("{relative} should load: {e}"))
}

/// What one ray found.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    pub depth: f64,
    pub normal: DVec3,
    pub position: DVec3,
    pub object: Option<String>,
    pub prim: u32,
}

/// Casts `rays` at `scene` through the octree and returns every AOV per ray.
pub fn cast(scene: &Scene, rays: &[Ray]) -> Vec<Sample> {
    let octree = Octree::build(scene, OctreeParams::default());
    let tracer = Tracer {
        scene,
        octree: &octree,
    };
    let aovs = [Aov::Depth, Aov::Normal, Aov::Position, Aov::Id, Aov::Prim];
    let b = render::render(&tracer, &rays.to_vec(), &aovs, |_| {});
    (0..rays.len())
        .map(|i| {
            let id = b.labels(Aov::Id).unwrap()[i];
            Sample {
                depth: b.floats(Aov::Depth).unwrap()[i],
                normal: DVec3::from_array(b.vectors(Aov::Normal).unwrap()[i]),
                position: DVec3::from_array(b.vectors(Aov::Position).unwrap()[i]),
                object: (id > 0).then(|| scene.objects[id as usize - 1].name.clone()),
                prim: b.labels(Aov::Prim).unwrap()[i],
            }
        })
        .collect()
}

/// Casts one ray.
pub fn cast_one(scene: &Scene, origin: [f64; 3], dir: [f64; 3]) -> Sample {
    cast(scene, &[ray(origin, dir)]).remove(0)
}

/// A ray from arrays.
pub fn ray(origin: [f64; 3], dir: [f64; 3]) -> Ray {
    Ray::new(DVec3::from_array(origin), DVec3::from_array(dir))
}

/// Asserts a hit on `object` at `depth` (relative 1e-12) with `normal` (1e-12) and one of `prims`.
pub fn assert_hit(s: &Sample, object: &str, depth: f64, normal: [f64; 3], prims: &[u32]) {
    assert_eq!(s.object.as_deref(), Some(object), "{s:?}");
    assert!(
        (s.depth - depth).abs() <= 1e-12 * depth.abs().max(1.0),
        "depth {} != {depth}: {s:?}",
        s.depth
    );
    assert!(
        (s.normal - DVec3::from_array(normal)).length() <= 1e-12,
        "normal {:?} != {normal:?}",
        s.normal
    );
    assert!(prims.contains(&s.prim), "prim {} not in {prims:?}", s.prim);
}

/// Asserts a miss with the documented miss values.
pub fn assert_miss(s: &Sample) {
    assert_eq!(s.object, None, "{s:?}");
    assert_eq!(s.depth, f64::INFINITY);
    assert_eq!(s.normal, DVec3::ZERO);
    assert_eq!(s.position, DVec3::INFINITY);
    assert_eq!(s.prim, u32::MAX);
}

/// A small deterministic generator (xorshift64*), so tests need no extra crate.
pub struct Rng(pub u64);

impl Rng {
    /// Next raw value.
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// A point with coordinates uniform in [lo, hi).
    pub fn point(&mut self, lo: f64, hi: f64) -> DVec3 {
        DVec3::new(
            self.uniform(lo, hi),
            self.uniform(lo, hi),
            self.uniform(lo, hi),
        )
    }
    /// A direction along a random axis (±1) whose other components are each +0.0, -0.0, one
    /// of `tiny` or a uniform value in [-1, 1): rays on cell planes and near-parallel rays.
    pub fn axis_direction(&mut self, tiny: &[f64]) -> DVec3 {
        let axis = (self.next_u64() % 3) as usize;
        let mut dir = DVec3::ZERO;
        dir[axis] = if self.next_u64().is_multiple_of(2) {
            1.0
        } else {
            -1.0
        };
        for other in (0..3).filter(|&a| a != axis) {
            let choices = 3 + tiny.len() as u64;
            dir[other] = match self.next_u64() % choices {
                0 => 0.0,
                1 => -0.0,
                2 => self.uniform(-1.0, 1.0),
                k => tiny[(k - 3) as usize],
            };
        }
        dir
    }

    /// A random unit vector.
    pub fn direction(&mut self) -> DVec3 {
        loop {
            let p = self.point(-1.0, 1.0);
            if p.length_squared() > 1e-4 && p.length_squared() <= 1.0 {
                return p.normalize();
            }
        }
    }
}

/// Reads the shape and raw little-endian payload of a `.npy` file written by raycast.
pub fn read_npy(path: &std::path::Path) -> (String, Vec<usize>, Vec<u8>) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    parse_npy(&bytes)
}

/// The header, shape and raw little-endian payload of `.npy` bytes written by raycast.
pub fn parse_npy(bytes: &[u8]) -> (String, Vec<usize>, Vec<u8>) {
    assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
    let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + len])
        .unwrap()
        .to_string();
    let shape_text = header
        .split("'shape': (")
        .nth(1)
        .unwrap()
        .split(')')
        .next()
        .unwrap();
    let shape = shape_text
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|s| s.trim().parse().unwrap())
        .collect();
    (header, shape, bytes[10 + len..].to_vec())
}

/// The values of a float64 `.npy` file.
pub fn read_f64(path: &std::path::Path) -> (Vec<usize>, Vec<f64>) {
    let (header, shape, data) = read_npy(path);
    assert!(header.contains("'<f8'"), "{header}");
    (
        shape,
        data.chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect(),
    )
}

/// The values of a uint32 `.npy` file.
pub fn read_u32(path: &std::path::Path) -> (Vec<usize>, Vec<u32>) {
    let (header, shape, data) = read_npy(path);
    assert!(header.contains("'<u4'"), "{header}");
    (
        shape,
        data.chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect(),
    )
}

/// Writes an (N, 6) or (N, 8) float64 ray file.
pub fn write_rays<const C: usize>(path: &std::path::Path, rays: &[[f64; C]]) {
    let header = format!(
        "{{'descr': '<f8', 'fortran_order': False, 'shape': ({}, {C}), }}\n",
        rays.len()
    );
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    for v in rays.iter().flatten() {
        out.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(path, out).unwrap();
}

/// Random triangles of mixed sizes (some spanning most of the scene) and random quadrics
/// (spheres and clipped cylinders), all shifted by `offset`.
pub fn random_scene(rng: &mut Rng, triangles: usize, quadrics: usize, offset: DVec3) -> Scene {
    let mut builder = SceneBuilder::new();
    let mut tris = Vec::new();
    for i in 0..triangles {
        let size = if i % 50 == 0 {
            8.0
        } else {
            rng.uniform(0.01, 1.0)
        };
        let c = rng.point(-10.0, 10.0) + offset;
        tris.push([c, c + rng.direction() * size, c + rng.direction() * size]);
    }
    if !tris.is_empty() {
        builder.add_mesh("triangles".into(), "test".into(), tris);
    }
    for i in 0..quadrics {
        let world = DMat4::from_scale_rotation_translation(
            DVec3::new(
                rng.uniform(0.3, 2.0),
                rng.uniform(0.3, 2.0),
                rng.uniform(0.3, 2.0),
            ),
            DQuat::from_scaled_axis(rng.direction() * rng.uniform(0.0, 3.0)),
            rng.point(-8.0, 8.0) + offset,
        );
        let spec = if i % 2 == 0 {
            QuadricSpec::from_coefficients(
                [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
                None,
            )
        } else {
            let bounds = Some([DVec3::splat(-1.5), DVec3::splat(1.5)]);
            QuadricSpec::from_coefficients(
                [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
                bounds,
            )
        };
        let quadric = Quadric::new(&spec.unwrap(), world).unwrap();
        builder.add_quadric(format!("q{i}"), "test".into(), quadric);
    }
    builder.finish("random".into())
}

/// What a naive octree traversal would report for `ray`: the first hit found in the first leaf
/// holding one, with that leaf's exit parameter (the lecture's boundary trap when `t > exit`).
pub fn naive_first_hit(
    scene: &Scene,
    octree: &Octree,
    ray: &PreparedRay<<Scene as PrimitiveSet>::RayData>,
) -> (u32, f64, f64) {
    let mut naive: Option<(u32, f64, f64)> = None;
    octree.traverse(ray.local_origin, ray.dir, f64::INFINITY, |refs, _, exit| {
        for &prim in refs {
            if let Some(t) = scene.intersect(prim as usize, ray, f64::INFINITY) {
                naive = naive.or(Some((prim, t, exit)));
            }
        }
        f64::INFINITY
    });
    naive.expect("the ray hits something")
}

/// The `raycast` binary under test: this build's, or the one `RAYCAST_BIN` names (to run the
/// command-line tests against another build, such as the one before a fix).
pub fn raycast_bin() -> PathBuf {
    std::env::var_os("RAYCAST_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_BIN_EXE_raycast")))
}

/// Runs the `raycast` binary with `args`.
pub fn raycast(args: &[&str]) -> std::process::Output {
    std::process::Command::new(raycast_bin())
        .args(args)
        .output()
        .expect("the binary runs")
}

/// Runs raycast and asserts that it succeeded, showing its error output otherwise.
pub fn raycast_ok(args: &[&str]) -> std::process::Output {
    let result = raycast(args);
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    result
}

/// A fresh (removed) temporary folder path for one test. `name` need only be unique within the
/// calling test file: the folder is named for the file too, since every file's tests run in
/// the one process of the `it` test binary.
#[track_caller]
pub fn temp_dir(name: &str) -> PathBuf {
    let caller = Path::new(std::panic::Location::caller().file());
    let file = caller.file_stem().and_then(|s| s.to_str()).unwrap_or("it");
    let pid = std::process::id();
    let dir = std::env::temp_dir().join(format!("raycast-cli-{pid}-{file}-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// Writes `contents` as file `name` in a fresh temporary folder for test `test`; returns its
/// path.
#[track_caller]
pub fn temp_file(test: &str, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
    let dir = temp_dir(test);
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, contents).unwrap();
    path
}

/// A path as a command-line argument.
pub fn arg(p: &std::path::Path) -> &str {
    p.to_str().unwrap()
}

/// The sorted file names in `dir` (empty when it does not exist).
pub fn file_names(dir: &std::path::Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    names
}
