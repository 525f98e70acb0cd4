//! The topology of a triangle mesh: its edges, boundary, non-manifold and misoriented edges,
//! degenerate triangles and the area its holes would need to be capped.
//!
//! Closedness is topological: vertices are welded by their exact stored coordinates, and a
//! mesh is closed when every edge is shared by exactly two triangles that use it in opposite
//! directions. An open mesh is taken to be meant closed when its holes are small: the area
//! that would cap its boundary loops is at most [`NEARLY_CLOSED`] of the capped surface. An
//! open box or a pipe is then open on purpose, while a scan with a few missing triangles is
//! meant closed.

use glam::DVec3;
use std::collections::HashMap;

/// Largest share of the capped surface that holes may cover for a mesh to count as meant
/// to be closed.
pub const NEARLY_CLOSED: f64 = 0.02;

/// Topology of one mesh.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Topology {
    /// Edges (welded vertex pairs).
    pub edges: usize,
    /// Edges used by one triangle.
    pub boundary: usize,
    /// Edges used by more than two triangles.
    pub non_manifold: usize,
    /// Edges used twice in the same direction (inconsistent winding).
    pub misoriented: usize,
    /// Triangles with zero area (including repeated corners).
    pub degenerate: usize,
    /// Surface area of the triangles.
    pub area: f64,
    /// Area that would cap the boundary loops: the sum over loops of the length of the loop's
    /// vector area (exact for planar holes). Infinite when the boundary does not form simple
    /// loops.
    pub hole_area: f64,
}

impl Topology {
    /// Every edge shared by exactly two triangles in opposite directions.
    pub fn closed(&self) -> bool {
        self.edges > 0 && self.boundary == 0 && self.non_manifold == 0 && self.misoriented == 0
    }

    /// Open, but with holes covering at most [`NEARLY_CLOSED`] of the capped surface.
    pub fn meant_closed(&self) -> bool {
        self.boundary > 0 && self.hole_area <= NEARLY_CLOSED * (self.area + self.hole_area)
    }
}

/// Welds vertices by their exact bits and counts edge uses.
pub fn topology(triangles: &[[DVec3; 3]]) -> Topology {
    let mut ids: HashMap<[u64; 3], u32> = HashMap::new();
    let mut points: Vec<DVec3> = Vec::new();
    let mut id = |v: DVec3| {
        let key = [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
        let next = ids.len() as u32;
        *ids.entry(key).or_insert_with(|| {
            points.push(v);
            next
        })
    };
    // (low, high) -> (uses low->high, uses high->low)
    let mut edges: HashMap<(u32, u32), (u32, u32)> = HashMap::new();
    let mut topo = Topology::default();
    for tri in triangles {
        let [a, b, c] = tri.map(|v| v);
        let doubled = (b - a).cross(c - a).length();
        if doubled == 0.0 {
            topo.degenerate += 1;
        }
        topo.area += 0.5 * doubled;
        let v = tri.map(&mut id);
        if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
            continue;
        }
        for k in 0..3 {
            let (p, q) = (v[k], v[(k + 1) % 3]);
            let entry = edges.entry((p.min(q), p.max(q))).or_insert((0, 0));
            if p < q {
                entry.0 += 1;
            } else {
                entry.1 += 1;
            }
        }
    }
    topo.edges = edges.len();
    // Boundary edges in the direction their triangle runs them: start -> ends.
    let mut outgoing: HashMap<u32, Vec<u32>> = HashMap::new();
    for (&(p, q), &(f, b)) in &edges {
        if f + b == 1 {
            let (from, to) = if f == 1 { (p, q) } else { (q, p) };
            outgoing.entry(from).or_default().push(to);
        }
    }
    topo.hole_area = hole_area(outgoing, &points);
    for &(f, b) in edges.values() {
        match f + b {
            1 => topo.boundary += 1,
            2 if f != 1 => topo.misoriented += 1,
            2 => {}
            _ => topo.non_manifold += 1,
        }
    }
    topo
}

/// Sum over the boundary loops of the length of each loop's vector area (the area of a flat
/// cap; a lower bound for a curved one).
///
/// The boundary edges are walked into chains, each edge once, in sorted vertex order so the
/// sum is deterministic. Where a vertex starts several boundary edges (two holes touching at a
/// corner) any pairing is taken; a chain that cannot return to its start (triangles wound
/// inconsistently) is closed by the straight segment back to it.
fn hole_area(mut outgoing: HashMap<u32, Vec<u32>>, points: &[DVec3]) -> f64 {
    let mut starts: Vec<u32> = outgoing.keys().copied().collect();
    starts.sort_unstable();
    for ends in outgoing.values_mut() {
        ends.sort_unstable_by(|a, b| b.cmp(a));
    }
    let mut total = 0.0;
    for start in starts {
        let origin = points[start as usize];
        while outgoing.get(&start).is_some_and(|ends| !ends.is_empty()) {
            let mut vector = DVec3::ZERO;
            let mut at = start;
            while let Some(to) = outgoing.get_mut(&at).and_then(Vec::pop) {
                vector += (points[at as usize] - origin).cross(points[to as usize] - origin);
                at = to;
                if at == start {
                    break;
                }
            }
            total += 0.5 * vector.length();
        }
    }
    total
}
