//! Wavefront OBJ through `tobj`: polygons triangulated, one object per OBJ object or group.

use crate::error::{Error, Result};
use crate::scene::{Scene, SceneBuilder};
use glam::DVec3;
use std::path::Path;

/// Loads an OBJ file. Materials are not read.
pub fn load(path: &Path) -> Result<Scene> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let file =
        std::fs::File::open(path).map_err(|e| Error::in_file(path, format!("cannot read: {e}")))?;
    let mut reader = std::io::BufReader::new(file);
    let (models, _materials) = tobj::load_obj_buf(&mut reader, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| Error::in_file(path, format!("not a valid OBJ file: {e}")))?;
    let mut builder = SceneBuilder::new();
    for (index, model) in models.iter().enumerate() {
        let triangles = model_triangles(&model.mesh)
            .map_err(|e| Error::in_file(path, format!("object '{}': {e}", model.name)))?;
        let name = if model.name.is_empty() {
            format!("object{index}")
        } else {
            model.name.clone()
        };
        builder.add_mesh(name.clone(), format!("obj:{name}"), triangles);
    }
    if builder.object_count() == 0 {
        builder.warn("the file holds no faces");
    }
    Ok(builder.finish(path.to_path_buf()))
}

/// The triangles of one OBJ model, with every index and coordinate checked.
fn model_triangles(mesh: &tobj::Mesh) -> std::result::Result<Vec<[DVec3; 3]>, String> {
    let positions: Vec<DVec3> = mesh
        .positions
        .chunks_exact(3)
        .map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
        .collect();
    if let Some(bad) = positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("vertex {} is not finite", bad + 1));
    }
    mesh.indices
        .chunks_exact(3)
        .map(|face| {
            let corner = |i: u32| {
                positions.get(i as usize).copied().ok_or_else(|| {
                    format!("face refers to vertex {} of {}", i + 1, positions.len())
                })
            };
            Ok([corner(face[0])?, corner(face[1])?, corner(face[2])?])
        })
        .collect()
}
