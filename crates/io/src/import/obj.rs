//! Wavefront OBJ through `tobj`: polygons triangulated, one object per OBJ object or group.
//! Coordinates are read as f64 (tobj's `use_f64`), so the file's decimal numbers keep the
//! digits an f64 holds; each object is an indexed mesh in world coordinates.
//!
//! `tobj` skips lines it does not know, as the format allows (exporters write their own
//! statements), so before it runs the text is checked to be OBJ at all: UTF-8 (see [`text`]),
//! with at least one line that is an OBJ statement if it has any (see [`check_statements`]);
//! then continuations are joined and empty or unknown statements skipped with a warning
//! (see [`super::obj_text`]).

use super::obj_text::{quoted, STATEMENTS};
use crate::error::{Error, Result};
use crate::scene::attributes::{corners, runs};
use crate::scene::{Attributes, Mesh, Scene, SceneBuilder};
use glam::{DMat4, DVec3};
use std::path::Path;
use std::sync::Arc;

/// Loads an OBJ file. Materials are named by `usemtl`; MTL files are not read.
pub fn load(path: &Path) -> Result<Scene> {
    let bytes = std::fs::read(path).map_err(|e| super::read_error(path, e))?;
    load_bytes(&bytes, path)
}

/// Loads OBJ `bytes`; `path` names them in messages and in the scene. Refuses bytes that are
/// not UTF-8 text and text in which no line is an OBJ statement.
pub fn load_bytes(bytes: &[u8], path: &Path) -> Result<Scene> {
    let text = text(bytes).map_err(|line| {
        Error::in_file(
            path,
            format!("line {line}: not UTF-8 text: this is no OBJ file (binary data?)"),
        )
    })?;
    check_statements(text).map_err(|e| e.with_path(path))?;
    let normal = super::obj_text::normalise(text);
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (mut models, _materials) =
        tobj::load_obj_buf(&mut normal.text.as_bytes(), &options, |_| {
            Err(tobj::LoadError::OpenFileFailed)
        })
        .map_err(|e| Error::in_file(path, format!("not a valid OBJ file: {e}")))?;
    // tobj ends every file with the object being read, also one that got no face (a file
    // of vertices only, or nothing at all); that one is no scene object.
    if models.last().is_some_and(|m| m.mesh.indices.is_empty()) {
        models.pop();
    }
    let mut builder = SceneBuilder::new();
    for warning in normal.warnings {
        builder.note(warning);
    }
    let materials = model_materials(&normal.text, &models, &mut builder);
    let mut triangles = 0;
    for (index, (model, materials)) in models.iter().zip(materials).enumerate() {
        triangles += model.mesh.indices.len() / 3;
        let mesh = model_mesh(&model.mesh).map_err(|e| {
            e.context(format!("object '{}'", model.name))
                .with_path(path)
        })?;
        let mesh = mesh.with_attributes(model_attributes(&model.mesh, materials));
        let name = if model.name.is_empty() {
            format!("object{index}")
        } else {
            model.name.clone()
        };
        let id = builder.new_object(name.clone(), format!("obj:{name}"));
        builder.place_mesh(id, Arc::new(mesh), DMat4::IDENTITY);
    }
    if triangles == 0 {
        // The words of the glTF and USD readers' warning for an empty scene.
        builder.warn(super::empty_scene());
    }
    Ok(builder.finish(path.to_path_buf()))
}

/// The bytes as text, or the number (from 1) of the first line that is not UTF-8.
pub fn text(bytes: &[u8]) -> std::result::Result<&str, usize> {
    std::str::from_utf8(bytes).map_err(|e| {
        let valid = &bytes[..e.valid_up_to()];
        valid.iter().filter(|&&b| b == b'\n').count() + 1
    })
}

/// Refuses text that has lines but none of them an OBJ statement, quoting the first line
/// that is not one. Blank lines and `#` comments are neither, so an empty file or one of
/// comments only passes (an empty scene).
///
/// The rule is deliberately loose: a file with statements of its own among OBJ ones loads
/// (tobj skips them, as the format allows), while text with nothing of OBJ in it (another
/// format, random bytes) is refused instead of rendering an empty scene.
pub fn check_statements(text: &str) -> Result<()> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut foreign = None;
    for (n, line) in text.lines().enumerate() {
        let content = line.split('#').next().unwrap_or("").trim();
        let Some(keyword) = content.split_whitespace().next() else {
            continue;
        };
        if STATEMENTS.contains(&keyword) {
            return Ok(());
        }
        foreign.get_or_insert((n + 1, content));
    }
    match foreign {
        Some((line, content)) => Err(Error::msg(format!(
            "line {line}: '{}' is not an OBJ statement, and no line of the file is one",
            quoted(content)
        ))),
        None => Ok(()),
    }
}

/// Each model's triangles' materials (scene material ids, 0: none), from the `usemtl`
/// statements of `text` (tobj's models hold the faces in file order). Where the faces counted
/// in the text do not match tobj's triangles, materials are left out with a warning.
fn model_materials(
    text: &str,
    models: &[tobj::Model],
    builder: &mut SceneBuilder,
) -> Vec<Vec<u32>> {
    let (names, per_triangle) = super::obj_text::face_materials(text);
    let counts: Vec<usize> = models.iter().map(|m| m.mesh.indices.len() / 3).collect();
    if per_triangle.len() != counts.iter().sum::<usize>() {
        if !names.is_empty() {
            builder.note("usemtl: the faces could not be matched to their materials: left out");
        }
        return counts.iter().map(|&n| vec![0; n]).collect();
    }
    let ids: Vec<u32> = names.iter().map(|n| builder.material(n)).collect();
    let mut rest = per_triangle.as_slice();
    counts
        .iter()
        .map(|&n| {
            let (mine, after) = rest.split_at(n);
            rest = after;
            mine.iter()
                .map(|&m| m.checked_sub(1).map_or(0, |m| ids[m as usize]))
                .collect()
        })
        .collect()
}

/// The texture coordinates (`vt`) and normals (`vn`) of a model's triangle corners, each
/// only where every corner has one, and the triangles' `materials`.
fn model_attributes(mesh: &tobj::Mesh, materials: Vec<u32>) -> Attributes {
    let triangles = |indices: &[u32]| -> Vec<[u32; 3]> {
        match indices.len() == mesh.indices.len() {
            true => indices
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect(),
            false => Vec::new(),
        }
    };
    let uv: Vec<[f32; 2]> = (mesh.texcoords.chunks_exact(2))
        .map(|c| [c[0] as f32, c[1] as f32])
        .collect();
    let normals: Vec<[f32; 3]> = (mesh.normals.chunks_exact(3))
        .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
        .collect();
    Attributes {
        uv: corners(&uv, &triangles(&mesh.texcoord_indices)),
        normals: corners(&normals, &triangles(&mesh.normal_indices)),
        materials: runs(&materials),
    }
}

/// The indexed mesh of one OBJ model, with every index and coordinate checked.
fn model_mesh(mesh: &tobj::Mesh) -> Result<Mesh> {
    let positions: Vec<DVec3> = mesh
        .positions
        .chunks_exact(3)
        .map(|p| DVec3::new(p[0], p[1], p[2]))
        .collect();
    if let Some(bad) = positions.iter().position(|p| !p.is_finite()) {
        return Err(Error::msg(format!("vertex {} is not finite", bad + 1)));
    }
    if let Some(&bad) = mesh
        .indices
        .iter()
        .find(|&&i| i as usize >= positions.len())
    {
        return Err(Error::msg(format!(
            "face refers to vertex {} of {}",
            bad + 1,
            positions.len()
        )));
    }
    let triangles = mesh
        .indices
        .chunks_exact(3)
        .map(|f| [f[0], f[1], f[2]])
        .collect();
    Mesh::new(positions, triangles).ok_or_else(|| Error::msg("invalid mesh"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_with_no_obj_statement_is_refused() {
        let garbage =
            "# made by hand\n\naGVsbG8gd29ybGQsIHRoaXMgaXMgbm90IGFuIE9CSg==\nc29tZSBtb3Jl\n";
        assert_eq!(
            check_statements(garbage).unwrap_err().message,
            "line 3: 'aGVsbG8gd29ybGQsIHRoaXMg…' is not an OBJ statement, and no line of the file is one"
        );
        assert!(check_statements("\t\x01 tab\n")
            .unwrap_err()
            .message
            .contains(r"'\u{1} tab'"));
    }

    #[test]
    fn foreign_statements_beside_obj_ones_pass() {
        for text in [
            "vc 1 0 0\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "\u{feff}v 0 0 0\n",
            "exporter-note hello\n# comment\nmtllib a.mtl\n",
            "",
            "# only a comment\n\n",
        ] {
            assert_eq!(check_statements(text), Ok(()), "{text:?}");
        }
    }

    #[test]
    fn the_first_line_that_is_not_utf8_is_named() {
        assert_eq!(text(b"v 0 0 0\n"), Ok("v 0 0 0\n"));
        assert_eq!(text(b"v 0 0 0\nv 1 \xff 0\n"), Err(2));
        assert_eq!(text(b"\xc3"), Err(1));
    }
}
