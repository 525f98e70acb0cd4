//! Triangle meshes stored as the file gives them: indexed vertices in the mesh's own frame, in
//! f32 where every coordinate is an f32 value (glTF accessors, USD `points`) and in f64 otherwise
//! (OBJ text read as f64, or triangles already placed in the world by an f64 transform).
//!
//! # Layout
//! Indexed vertices: a closed mesh has about half as many vertices as triangles, so f64
//! vertices cost `24 · V + 12 · T ≈ 24` bytes per triangle and f32 vertices about 18, against 36
//! for the f32 triangle soup stored before (plus its 4-byte object index, kept here). The
//! triangle test fetches three indices and three vertices instead of one 36-byte record; the
//! branch on the storage kind is the same for every triangle of a mesh, so it predicts well.

use super::attributes::{Attributes, MaterialRun};
use crate::accel::{
    intersect_each, set_bits, PacketCrossings, PreparedRay, PrimitiveSet, GROUP, PACKET,
};
use crate::geometry::triangle::{self, WatertightRay};
use crate::geometry::triangle_box;
use crate::geometry::triangle_packet::{EdgeVerdict, WatertightPacket};
use crate::geometry::Aabb;
use crate::simd::Kernel;
use glam::{DAffine3, DVec3, Vec3};
use std::collections::HashMap;
use std::sync::Arc;

/// Vertex positions in the precision the file stores them.
#[derive(Debug, Clone, PartialEq)]
pub enum Positions {
    /// Every coordinate is an f32 value (stored exactly).
    F32(Vec<Vec3>),
    /// Coordinates that need f64.
    F64(Vec<DVec3>),
}

impl Positions {
    /// Stores `points` in f32 when that is exact for every coordinate, else in f64.
    pub fn exact(points: Vec<DVec3>) -> Positions {
        let fits = |p: &DVec3| p.as_vec3().as_dvec3() == *p;
        if points.iter().all(fits) {
            Positions::F32(points.iter().map(|p| p.as_vec3()).collect())
        } else {
            Positions::F64(points)
        }
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        match self {
            Positions::F32(p) => p.len(),
            Positions::F64(p) => p.len(),
        }
    }

    /// True when there is no vertex.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Vertex `i`, promoted to f64 (exact).
    #[inline(always)]
    pub fn get(&self, i: u32) -> DVec3 {
        match self {
            Positions::F32(p) => p[i as usize].as_dvec3(),
            Positions::F64(p) => p[i as usize],
        }
    }

    /// Bytes of vertex data.
    pub fn bytes(&self) -> usize {
        match self {
            Positions::F32(p) => p.len() * 12,
            Positions::F64(p) => p.len() * 24,
        }
    }
}

/// An indexed triangle mesh in its own frame. Counter-clockwise winding is the front.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    positions: Positions,
    triangles: Vec<[u32; 3]>,
    /// Shading attributes (texture coordinates, normals, materials); `None` when the file
    /// gives none. Read only after a trace ([`super::attributes`]).
    attributes: Option<Arc<Attributes>>,
}

impl Mesh {
    /// A mesh from vertices and index triples; `None` when an index is out of range or a
    /// vertex is not finite.
    pub fn new(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Option<Mesh> {
        let in_range = triangles
            .iter()
            .flatten()
            .all(|&i| (i as usize) < positions.len());
        (in_range && positions.iter().all(|p| p.is_finite())).then(|| Mesh {
            positions: Positions::exact(positions),
            triangles,
            attributes: None,
        })
    }

    /// The same triangles over new vertices (a posed mesh), with the same attributes: `None`
    /// when the vertex count differs or a vertex is not finite.
    pub fn with_positions(&self, positions: Vec<DVec3>) -> Option<Mesh> {
        (positions.len() == self.positions.len()).then_some(())?;
        let mesh = Mesh::new(positions, self.triangles.clone())?;
        Some(Mesh {
            attributes: self.attributes.clone(),
            ..mesh
        })
    }

    /// The mesh with `attributes` (kept only where they fit: a corner list that does not hold
    /// one entry per triangle is dropped, so a lookup never reads past it).
    pub fn with_attributes(self, mut attributes: Attributes) -> Mesh {
        let n = self.triangles.len();
        if attributes.uv.len() != n {
            attributes.uv = Vec::new();
        }
        if attributes.normals.len() != n {
            attributes.normals = Vec::new();
        }
        Mesh {
            attributes: (!attributes.is_empty()).then(|| Arc::new(attributes)),
            ..self
        }
    }

    /// The mesh with its triangles bound to materials by `runs` (its other attributes kept).
    pub fn with_materials(self, runs: Vec<MaterialRun>) -> Mesh {
        let mut attributes = self.attributes.as_deref().cloned().unwrap_or_default();
        attributes.materials = runs;
        self.with_attributes(attributes)
    }

    /// The mesh without shading normals (its other attributes kept).
    pub fn without_normals(self) -> Mesh {
        let mut attributes = self.attributes.as_deref().cloned().unwrap_or_default();
        attributes.normals = Vec::new();
        self.with_attributes(attributes)
    }

    /// The shading attributes, if the file gave any.
    pub fn attributes(&self) -> Option<&Arc<Attributes>> {
        self.attributes.as_ref()
    }

    /// A mesh from stored vertices and index triples that are known to be in range.
    pub fn from_parts(positions: Positions, triangles: Vec<[u32; 3]>) -> Mesh {
        debug_assert!(triangles
            .iter()
            .flatten()
            .all(|&i| (i as usize) < positions.len()));
        Mesh {
            positions,
            triangles,
            attributes: None,
        }
    }

    /// A mesh from a triangle soup: corners with the same bits become one vertex.
    pub fn from_soup(soup: &[[DVec3; 3]]) -> Mesh {
        let mut index: HashMap<[u64; 3], u32> = HashMap::with_capacity(soup.len());
        let mut positions = Vec::with_capacity(soup.len());
        let triangles = soup
            .iter()
            .map(|tri| {
                tri.map(|p| {
                    *index
                        .entry(p.to_array().map(f64::to_bits))
                        .or_insert_with(|| {
                            positions.push(p);
                            positions.len() as u32 - 1
                        })
                })
            })
            .collect();
        Mesh {
            positions: Positions::exact(positions),
            triangles,
            attributes: None,
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// A hash of the stored vertices' bits and the index triples: equal meshes hash equally.
    pub fn content_hash(&self) -> u64 {
        use std::hash::Hasher;
        // FxHash: the meshes it finds equal are compared in full afterwards, so speed
        // matters more here than resistance to chosen collisions.
        let mut h = rustc_hash::FxHasher::default();
        match &self.positions {
            Positions::F32(p) => p
                .iter()
                .flat_map(|v| v.to_array())
                .for_each(|x| h.write_u32(x.to_bits())),
            Positions::F64(p) => p
                .iter()
                .flat_map(|v| v.to_array())
                .for_each(|x| h.write_u64(x.to_bits())),
        }
        self.triangles
            .iter()
            .flatten()
            .for_each(|&i| h.write_u32(i));
        h.finish()
    }

    /// True when the mesh has no triangle.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The stored vertices.
    pub fn positions(&self) -> &Positions {
        &self.positions
    }

    /// The index triples, one per triangle.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Triangle `i`'s corners, in the mesh frame.
    #[inline(always)]
    pub fn triangle(&self, i: usize) -> [DVec3; 3] {
        let [a, b, c] = self.triangles[i].map(|v| v as usize);
        // One branch per triangle on the storage kind.
        match &self.positions {
            Positions::F32(p) => [p[a].as_dvec3(), p[b].as_dvec3(), p[c].as_dvec3()],
            Positions::F64(p) => [p[a], p[b], p[c]],
        }
    }

    /// Bytes of vertex, index and attribute data.
    pub fn bytes(&self) -> usize {
        let attributes = self.attributes.as_ref().map_or(0, |a| a.bytes());
        self.trace_bytes() + attributes
    }

    /// Bytes of what a ray test reads: the vertices and the index triples.
    pub fn trace_bytes(&self) -> usize {
        self.positions.bytes() + self.triangles.len() * 12
    }

    /// Bounds of all vertices used by a triangle, in the mesh frame.
    pub fn bounds(&self) -> Aabb {
        (0..self.len())
            .flat_map(|i| self.triangle(i))
            .fold(Aabb::EMPTY, Aabb::grow)
    }

    /// False when the projective transform `world` sends a vertex to infinity.
    pub fn places_finitely(&self, world: &glam::DMat4) -> bool {
        world.row(3) == glam::DVec4::W
            || (0..self.positions.len() as u32)
                .all(|i| world.project_point3(self.positions.get(i)).is_finite())
    }

    /// Appends this mesh placed by `world` (f64) to the f64 point and index lists, flipping the
    /// winding under a mirroring transform so that counter-clockwise stays the front.
    /// Projective transforms divide by `w`, as USD does.
    pub(crate) fn place_into(
        &self,
        world: &glam::DMat4,
        points: &mut Vec<DVec3>,
        triangles: &mut Vec<[u32; 3]>,
    ) {
        let base = points.len() as u32;
        let projective = world.row(3) != glam::DVec4::W;
        points.extend((0..self.positions.len() as u32).map(|i| {
            let p = self.positions.get(i);
            if projective {
                world.project_point3(p)
            } else {
                world.transform_point3(p)
            }
        }));
        let flip = world.determinant() < 0.0;
        triangles.extend(self.triangles.iter().map(|&[a, b, c]| {
            if flip {
                [base + a, base + c, base + b]
            } else {
                [base + a, base + b, base + c]
            }
        }));
    }
}

/// A mesh as a [`PrimitiveSet`]: the acceleration structure works in coordinates relative to
/// `anchor` (so that cells deep in a far-away mesh keep their digits), while the ray test runs
/// on the stored vertices with the ray in the mesh frame.
#[derive(Debug, Clone)]
pub struct MeshSet {
    /// The mesh (shared with the importer's cache while the scene is built).
    pub mesh: Arc<Mesh>,
    /// Frame position that the acceleration structure's coordinates are relative to.
    pub anchor: DVec3,
}

/// The lanes `hits` with what the pre-filter's `verdict` says of the others.
#[inline(always)]
fn crossings(hits: u32, verdict: &EdgeVerdict) -> PacketCrossings {
    PacketCrossings {
        hits,
        apart: verdict.apart,
        inside: verdict.inside,
    }
}

impl MeshSet {
    /// Triangle `i` relative to the anchor. Where the anchor is not zero the vertices lie
    /// within 1/64 of their distance from the origin (see `Scene`), so the subtraction is exact
    /// on large coordinates and rounds by far less than the octree's margin on small ones.
    fn local(&self, i: usize) -> [DVec3; 3] {
        self.mesh.triangle(i).map(|p| p - self.anchor)
    }

    /// The watertight test of triangle `i` against a ray prepared in the mesh frame.
    #[inline]
    pub fn intersect_triangle(&self, i: usize, ray: &WatertightRay, t_max: f64) -> Option<f64> {
        ray.intersect(&self.mesh.triangle(i), t_max)
    }

    /// [`PrimitiveSet::intersect_packet`] for triangle `i` and the rays `active` of a packet,
    /// `ray(i)` being ray `i` prepared in the mesh frame: the packet's pre-filter (for two
    /// rays or more), then the single-ray test for the rays it keeps.
    #[inline(always)]
    pub fn intersect_triangle_packet<'r>(
        &self,
        i: usize,
        packet: &WatertightPacket,
        ray: impl Fn(usize) -> &'r WatertightRay,
        active: u32,
        limits: (&[f64; PACKET], &mut [f64; PACKET]),
    ) -> u32 {
        self.triangle_packet::<false>(i, packet, ray, (active, 0.0), limits)
            .hits
    }

    /// [`MeshSet::intersect_triangle_packet`]'s hits; with `APART`, also the rays whose exact
    /// ray certainly misses the exact triangle, within `placement` of the stored one, and
    /// those that certainly cross its interior ([`WatertightPacket::candidates_apart`], for a
    /// lone ray too: a rival it reports apart is one the decision need not weigh again, at
    /// some 500 instructions a ray).
    #[inline(always)]
    pub(crate) fn triangle_packet<'r, const APART: bool>(
        &self,
        i: usize,
        packet: &WatertightPacket,
        ray: impl Fn(usize) -> &'r WatertightRay,
        (active, placement): (u32, f64),
        (t_max, ts): (&[f64; PACKET], &mut [f64; PACKET]),
    ) -> PacketCrossings {
        let tri = self.mesh.triangle(i);
        // Without `APART`, a lone ray goes straight to its own test: the filter costs more than
        // it saves.
        let verdict = if APART {
            packet.candidates_apart(&tri, placement, active, &ray)
        } else if active.is_power_of_two() {
            EdgeVerdict::kept(active)
        } else {
            EdgeVerdict::kept(packet.candidates(&tri, active))
        };
        let mut hits = 0;
        for lane in set_bits(verdict.kept) {
            if let Some(t) = ray(lane).intersect(&tri, t_max[lane]) {
                ts[lane] = t;
                hits |= 1 << lane;
            }
        }
        crossings(hits, &verdict)
    }

    /// [`PrimitiveSet::intersect_group`] for the triangles `indices` and one ray prepared in
    /// the mesh frame: the four-triangle pre-filter (for two triangles or more), then the
    /// single-ray test for the triangles it keeps; the pre-filter by `kernel`.
    #[inline(always)]
    pub fn intersect_triangles(
        &self,
        indices: &[u32],
        ray: &WatertightRay,
        kernel: Kernel,
        t_max: f64,
        ts: &mut [f64; GROUP],
    ) -> u32 {
        self.triangle_group::<false>(indices, (ray, kernel), (t_max, ts), &[0.0; GROUP])
            .hits
    }

    /// [`MeshSet::intersect_triangles`]'s hits; with `APART`, also the triangles the exact ray
    /// certainly misses and those whose interior it certainly crosses, triangle `indices[k]`
    /// taken within `placement[k]` of the stored one
    /// ([`WatertightRay::candidates_apart`]).
    #[inline(always)]
    pub(crate) fn triangle_group<const APART: bool>(
        &self,
        indices: &[u32],
        (ray, kernel): (&WatertightRay, Kernel),
        (t_max, ts): (f64, &mut [f64; GROUP]),
        placement: &[f64; GROUP],
    ) -> PacketCrossings {
        let Some(last) = indices.len().checked_sub(1) else {
            return PacketCrossings::default();
        };
        if last == 0 && !APART {
            let t = self.intersect_triangle(indices[0] as usize, ray, t_max);
            ts[0] = t.unwrap_or(0.0);
            return PacketCrossings::hits_only(u32::from(t.is_some()));
        }
        // The lanes left over in a group of fewer than four hold its first triangle.
        let mut tris = [self.mesh.triangle(indices[0] as usize); GROUP];
        for (tri, &i) in tris.iter_mut().zip(indices).skip(1) {
            *tri = self.mesh.triangle(i as usize);
        }
        let active = (1 << indices.len()) - 1;
        let verdict = if APART {
            ray.candidates_apart(kernel, &tris, active, placement)
        } else {
            EdgeVerdict::kept(ray.candidates(kernel, &tris, active))
        };
        let mut hits = 0;
        for k in set_bits(verdict.kept) {
            if let Some(t) = ray.intersect(&tris[k], t_max) {
                ts[k] = t;
                hits |= 1 << k;
            }
        }
        crossings(hits, &verdict)
    }

    /// Unit normal of triangle `i` from its winding, mapped to the world by `to_world` (the
    /// cofactor matrix keeps it perpendicular and, with the winding flip of a mirroring
    /// placement, on the front side); `None` for a degenerate triangle.
    pub fn normal(&self, i: usize, to_world: Option<&DAffine3>) -> Option<DVec3> {
        let n = triangle::geometric_normal(&self.mesh.triangle(i))?;
        match to_world {
            None => Some(n),
            Some(m) => (m.matrix3.inverse().transpose() * n).try_normalize(),
        }
    }
}

impl PrimitiveSet for MeshSet {
    type RayData = WatertightRay;

    fn len(&self) -> usize {
        self.mesh.len()
    }

    fn bounds(&self, index: usize) -> Aabb {
        Aabb::from_points(self.local(index))
    }

    fn triangles_only(&self) -> bool {
        true
    }

    fn overlaps(&self, index: usize, cell: &Aabb) -> bool {
        triangle_box::overlaps_box(&self.local(index), cell)
    }

    fn child_mask(&self, index: usize, cell: &Aabb, margin: f64, candidates: u8) -> u8 {
        triangle_box::octant_mask(&self.local(index), cell, margin, candidates)
    }

    fn clipped_bounds(&self, index: usize, cell: &Aabb) -> Option<Aabb> {
        // Clipping a triangle that only touches the cell can round away to nothing.
        triangle_box::clipped_bounds(&self.local(index), cell)
            .or_else(|| self.bounds(index).common(*cell))
    }

    fn prepare(&self, local_origin: DVec3, dir: DVec3) -> WatertightRay {
        WatertightRay::new(local_origin + self.anchor, dir)
    }

    fn intersect(&self, index: usize, ray: &PreparedRay<WatertightRay>, t_max: f64) -> Option<f64> {
        self.intersect_triangle(index, &ray.extra, t_max)
    }

    fn intersect_group(
        &self,
        indices: &[u32],
        ray: &PreparedRay<WatertightRay>,
        t_max: f64,
        ts: &mut [f64; GROUP],
    ) -> u32 {
        self.intersect_triangles(indices, &ray.extra, ray.kernel, t_max, ts)
    }

    type PacketData = Option<WatertightPacket>;

    fn prepare_packet(&self, rays: &[PreparedRay<WatertightRay>; PACKET]) -> Self::PacketData {
        WatertightPacket::new(rays[0].kernel, |i| &rays[i].extra)
    }

    fn intersect_packet(
        &self,
        index: usize,
        rays: &[PreparedRay<WatertightRay>; PACKET],
        packet: &Self::PacketData,
        active: u32,
        t_max: &[f64; PACKET],
        ts: &mut [f64; PACKET],
    ) -> u32 {
        match packet {
            Some(packet) => {
                let ray = |i: usize| &rays[i].extra;
                self.intersect_triangle_packet(index, packet, ray, active, (t_max, ts))
            }
            None => intersect_each(self, index, rays, active, t_max, ts),
        }
    }
}
