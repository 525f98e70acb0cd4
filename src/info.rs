//! `raycast info`: what the importer found in a scene.

use crate::camera::Projection;
use crate::scene::{ObjectKind, Scene, StageInfo};
use serde::Serialize;
use std::fmt;

/// A summary of a loaded scene.
#[derive(Debug, Clone, Serialize)]
pub struct SceneInfo {
    /// The file.
    pub scene: String,
    /// Triangle count.
    pub triangles: usize,
    /// Quadric count.
    pub quadrics: usize,
    /// World bounds `[min, max]`, or null for an empty scene.
    pub bounds: Option<[[f64; 3]; 2]>,
    /// One entry per object.
    pub objects: Vec<ObjectInfo>,
    /// The file's cameras.
    pub cameras: Vec<CameraSummary>,
    /// Extensions the file declares.
    pub extensions_used: Vec<String>,
    /// What the importer decoded (Draco, meshopt, GPU instancing), one line per extension.
    pub decoded: Vec<String>,
    /// USD stage metadata.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stage: Option<StageInfo>,
    /// Importer warnings.
    pub warnings: Vec<String>,
}

/// One object of [`SceneInfo`].
#[derive(Debug, Clone, Serialize)]
pub struct ObjectInfo {
    /// Object id.
    pub id: u32,
    /// Name.
    pub name: String,
    /// `mesh` or `quadric`.
    pub kind: ObjectKind,
    /// Source location in the file.
    pub source: String,
    /// Triangle count.
    pub triangles: u32,
    /// Quadric type name (quadrics only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub quadric_type: Option<&'static str>,
    /// World bounds `[min, max]`.
    pub bounds: [[f64; 3]; 2],
}

/// One camera of [`SceneInfo`].
#[derive(Debug, Clone, Serialize)]
pub struct CameraSummary {
    /// Index for `--camera`.
    pub index: usize,
    /// Name for `--camera`.
    pub name: String,
    /// Projection.
    #[serde(flatten)]
    pub projection: Projection,
    /// Eye position.
    pub eye: [f64; 3],
}

impl SceneInfo {
    /// Summarises `scene`.
    pub fn new(scene: &Scene) -> SceneInfo {
        let bounds = scene.world_bounds();
        SceneInfo {
            scene: scene.path.display().to_string(),
            triangles: scene.triangle_count(),
            quadrics: scene.quadrics().len(),
            bounds: (!bounds.is_empty()).then(|| [bounds.min.to_array(), bounds.max.to_array()]),
            objects: scene
                .objects
                .iter()
                .map(|o| {
                    let b = scene.object_bounds(o);
                    ObjectInfo {
                        id: o.id,
                        name: o.name.clone(),
                        kind: o.kind,
                        source: o.source.clone(),
                        triangles: o.triangles,
                        quadric_type: o
                            .quadric
                            .map(|q| scene.quadrics()[q as usize].kind().name()),
                        bounds: [b.min.to_array(), b.max.to_array()],
                    }
                })
                .collect(),
            cameras: scene
                .cameras
                .iter()
                .enumerate()
                .map(|(index, c)| CameraSummary {
                    index,
                    name: c.name.clone(),
                    projection: c.projection,
                    eye: c.eye().to_array(),
                })
                .collect(),
            extensions_used: scene.extensions_used.clone(),
            decoded: scene.decoded.clone(),
            stage: scene.stage.clone(),
            warnings: scene.warnings.clone(),
        }
    }
}

impl fmt::Display for SceneInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{}", self.scene)?;
        writeln!(
            f,
            "  {} objects, {} triangles, {} quadrics",
            self.objects.len(),
            self.triangles,
            self.quadrics
        )?;
        if let Some([min, max]) = self.bounds {
            writeln!(f, "  bounds {min:?} .. {max:?}")?;
        }
        for o in &self.objects {
            let what = match o.quadric_type {
                Some(kind) => format!("quadric ({kind})"),
                None => format!("{} triangles", o.triangles),
            };
            writeln!(
                f,
                "  object {:>4}  {:<32} {what:<24} {}",
                o.id, o.name, o.source
            )?;
        }
        for c in &self.cameras {
            let projection = match c.projection {
                Projection::Perspective { yfov } => format!("perspective yfov {yfov:.4} rad"),
                Projection::Orthographic { ymag } => format!("orthographic ymag {ymag}"),
            };
            writeln!(
                f,
                "  camera {:>4}  {:<32} {projection}, eye {:?}",
                c.index, c.name, c.eye
            )?;
        }
        if let Some(stage) = &self.stage {
            writeln!(
                f,
                "  stage: upAxis {}, metersPerUnit {}",
                stage.up_axis, stage.meters_per_unit
            )?;
        }
        if !self.extensions_used.is_empty() {
            writeln!(f, "  extensions used: {}", self.extensions_used.join(", "))?;
        }
        for d in &self.decoded {
            writeln!(f, "  decoded: {d}")?;
        }
        for w in &self.warnings {
            writeln!(f, "  warning: {w}")?;
        }
        Ok(())
    }
}
