//! Wavefront OBJ through `tobj`: polygons triangulated, one object per OBJ object or group.
//! Coordinates are read as f64 (tobj's `use_f64`), so the file's decimal numbers keep the
//! digits an f64 holds; each object is an indexed mesh in world coordinates.

use crate::error::{Error, Result};
use crate::scene::{Mesh, Scene, SceneBuilder};
use glam::{DMat4, DVec3};
use std::path::Path;
use std::sync::Arc;

/// Loads an OBJ file. Materials are not read.
pub fn load(path: &Path) -> Result<Scene> {
    let file = std::fs::File::open(path).map_err(|e| super::read_error(path, e))?;
    load_reader(&mut std::io::BufReader::new(file), path)
}

/// Loads OBJ text from `reader`; `path` names it in messages and in the scene.
pub fn load_reader(reader: &mut impl std::io::BufRead, path: &Path) -> Result<Scene> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) =
        tobj::load_obj_buf(reader, &options, |_| Err(tobj::LoadError::OpenFileFailed))
            .map_err(|e| Error::in_file(path, format!("not a valid OBJ file: {e}")))?;
    let mut builder = SceneBuilder::new();
    for (index, model) in models.iter().enumerate() {
        let mesh = model_mesh(&model.mesh)
            .map_err(|e| Error::in_file(path, format!("object '{}': {e}", model.name)))?;
        let name = if model.name.is_empty() {
            format!("object{index}")
        } else {
            model.name.clone()
        };
        let id = builder.new_object(name.clone(), format!("obj:{name}"));
        builder.place_mesh(id, Arc::new(mesh), DMat4::IDENTITY);
    }
    if builder.object_count() == 0 {
        builder.warn("the file holds no faces");
    }
    Ok(builder.finish(path.to_path_buf()))
}

/// The indexed mesh of one OBJ model, with every index and coordinate checked.
fn model_mesh(mesh: &tobj::Mesh) -> std::result::Result<Mesh, String> {
    let positions: Vec<DVec3> = mesh
        .positions
        .chunks_exact(3)
        .map(|p| DVec3::new(p[0], p[1], p[2]))
        .collect();
    if let Some(bad) = positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("vertex {} is not finite", bad + 1));
    }
    if let Some(&bad) = mesh
        .indices
        .iter()
        .find(|&&i| i as usize >= positions.len())
    {
        return Err(format!(
            "face refers to vertex {} of {}",
            bad + 1,
            positions.len()
        ));
    }
    let triangles = mesh
        .indices
        .chunks_exact(3)
        .map(|f| [f[0], f[1], f[2]])
        .collect();
    Mesh::new(positions, triangles).ok_or_else(|| "invalid mesh".to_string())
}
