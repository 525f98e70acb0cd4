//! The points that frame the automatic camera ([`Scene::framing_points`]).

use super::mesh::Mesh;
use super::{PartKind, Scene, FRAMING_POINTS};
use glam::DVec3;

impl Scene {
    /// Points whose projections frame the scene for the automatic camera: every vertex of
    /// the scene's triangles in world coordinates (instances placed) and the corners of each
    /// quadric's bounds; past [`FRAMING_POINTS`] vertices, the corners of the remaining
    /// objects' bounds instead. Each vertex once (a mesh's triangles repeat its shared
    /// vertices about six times): the framing takes only extremes over the points, which
    /// repeats do not change, and its bisection passes over them some 120 times. Repeats are
    /// found by vertex index, not by hashing positions: an instanced mesh's used vertices are
    /// listed once and placed per instance.
    pub fn framing_points(&self) -> Vec<DVec3> {
        let mut points = Vec::new();
        let mut world_seen = vec![false; self.world.mesh.positions().len()];
        let mut stored_used: Vec<Option<Vec<u32>>> = vec![None; self.meshes.len()];
        // The limit counts every triangle's three corners, repeats included, so that which
        // objects give their vertices does not depend on how many of them repeat.
        let mut corners = 0;
        for object in &self.objects {
            if object.quadric.is_some() || corners + 3 * object.triangles as usize > FRAMING_POINTS
            {
                let bounds = self.object_bounds(object);
                if !bounds.is_empty() {
                    points.extend(bounds.corners());
                    corners += 8;
                }
                continue;
            }
            for part in self.object_parts(object) {
                match part.kind {
                    PartKind::World { first, count } => {
                        corners += 3 * count as usize;
                        let triangles = first as usize..(first + count) as usize;
                        let mesh = &self.world.mesh;
                        for &v in mesh.triangles()[triangles].as_flattened() {
                            if !std::mem::replace(&mut world_seen[v as usize], true) {
                                points.push(mesh.positions().get(v));
                            }
                        }
                    }
                    PartKind::Instance(k) => {
                        let instance = &self.instances[k as usize];
                        let mesh = &self.meshes[instance.mesh as usize].set.mesh;
                        corners += 3 * mesh.len();
                        let used = stored_used[instance.mesh as usize]
                            .get_or_insert_with(|| used_vertices(mesh));
                        let placed = used.iter().map(|&v| mesh.positions().get(v));
                        points.extend(placed.map(|p| instance.to_world.transform_point3(p)));
                    }
                    PartKind::Quadric(_) => {}
                }
            }
        }
        points
    }
}

/// The vertices `mesh`'s triangles use, each once, in order of first use.
fn used_vertices(mesh: &Mesh) -> Vec<u32> {
    let mut seen = vec![false; mesh.positions().len()];
    let all = mesh.triangles().as_flattened().iter().copied();
    all.filter(|&v| !std::mem::replace(&mut seen[v as usize], true))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::SceneBuilder;
    use glam::DMat4;
    use std::sync::Arc;

    /// The points are the triangles' vertices, meshes as placed, each vertex once: a 5 × 5
    /// grid of 32 triangles drawn twice (stored once, as instances), a soup whose corners
    /// repeat, and a vertex no triangle uses, which is left out.
    #[test]
    fn every_used_vertex_once_as_placed() {
        let grid: Vec<DVec3> = (0..25)
            .map(|i| DVec3::new(f64::from(i % 5), f64::from(i / 5), 0.5 * f64::from(i % 3)))
            .collect();
        let mut positions = grid.clone();
        positions.push(DVec3::splat(99.0));
        let cells = (0..16u32).map(|c| (c % 4) + 5 * (c / 4));
        let triangles = cells
            .flat_map(|a| [[a, a + 1, a + 6], [a, a + 6, a + 5]])
            .collect();
        let mesh = Arc::new(Mesh::new(positions, triangles).expect("a valid mesh"));
        let mut builder = SceneBuilder::new();
        let shift = DVec3::new(10.0, 0.0, 0.0);
        for (name, at) in [("a", DVec3::ZERO), ("b", shift)] {
            let id = builder.new_object(name.into(), "test".into());
            builder.place_mesh(id, mesh.clone(), DMat4::from_translation(at));
        }
        let soup = [DVec3::NEG_X, DVec3::NEG_Y, DVec3::NEG_Z, DVec3::NEG_ONE];
        builder.add_mesh(
            "c".into(),
            "test".into(),
            vec![[soup[0], soup[1], soup[2]], [soup[0], soup[2], soup[3]]],
        );
        let scene = builder.finish("framing".into());
        assert_eq!(scene.instances.len(), 2, "the grid is drawn as instances");
        let sorted =
            |points: &mut Vec<[f64; 3]>| points.sort_by(|a, b| a.partial_cmp(b).expect("no NaN"));
        let mut points: Vec<[f64; 3]> = scene
            .framing_points()
            .iter()
            .map(|p| p.to_array())
            .collect();
        sorted(&mut points);
        let placed = grid.iter().flat_map(|&p| [p, p + shift]);
        let mut expected: Vec<[f64; 3]> = placed.chain(soup).map(|p| p.to_array()).collect();
        sorted(&mut expected);
        assert_eq!(points, expected);
    }
}
