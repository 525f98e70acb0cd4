//! `raycast info`: what the importer found in a scene.

use crate::camera::Projection;
use crate::scene::topology::topology;
use crate::scene::{ObjectKind, PoseInfo, Scene, StageInfo};
use rayon::prelude::*;
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
    /// glTF animations, skins and morph targets, and the pose drawn.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pose: Option<PoseInfo>,
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
    /// Whether its triangles form a closed, consistently wound surface (every edge, its
    /// vertices welded by their exact coordinates, shared by two triangles in opposite
    /// directions): where inside and outside, and so signed distances, are certain. Meshes only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub closed: Option<bool>,
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
        let bounds = scene.own_bounds();
        SceneInfo {
            scene: scene.path.display().to_string(),
            triangles: scene.triangle_count(),
            quadrics: scene.quadrics().len(),
            bounds: (!bounds.is_empty()).then(|| [bounds.min.to_array(), bounds.max.to_array()]),
            // In parallel: the closedness test welds every vertex (1.3 s of one core for the
            // chess set's 1.4 million triangles).
            objects: scene
                .objects
                .par_iter()
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
                        closed: (o.kind == ObjectKind::Mesh)
                            .then(|| topology(&scene.mesh_triangles(o)).closed()),
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
            pose: scene.pose.clone(),
            warnings: scene.warnings.iter().map(ToString::to_string).collect(),
        }
    }
}

/// Object lines [`SceneInfo`]'s text shows before it summarises the rest (about a screenful
/// with the header lines).
pub const OBJECT_LINES: usize = 40;

/// A [`SceneInfo`]'s text with every object listed (`raycast info --all`).
pub struct AllObjects<'a>(pub &'a SceneInfo);

impl fmt::Display for AllObjects<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.write_text(f, usize::MAX)
    }
}

impl fmt::Display for SceneInfo {
    /// The text for a person: at most [`OBJECT_LINES`] objects, then a line counting the rest.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.write_text(f, OBJECT_LINES)
    }
}

impl SceneInfo {
    /// Writes the text, listing at most `object_lines` objects.
    fn write_text(&self, f: &mut fmt::Formatter<'_>, object_lines: usize) -> fmt::Result {
        writeln!(f, "{}", self.scene)?;
        writeln!(
            f,
            "  {}, {}, {}",
            count(self.objects.len(), "object"),
            count(self.triangles, "triangle"),
            count(self.quadrics, "quadric")
        )?;
        if let Some([min, max]) = self.bounds {
            let scale = min.iter().chain(&max).fold(0.0, |m: f64, v| m.max(v.abs()));
            let point = |p: [f64; 3]| p.map(|v| tidy(v, scale)).join(", ");
            writeln!(f, "  bounds [{}] .. [{}]", point(min), point(max))?;
        }
        // One name column for objects and cameras, as wide as the longest name (USD paths).
        let names = self.objects.iter().map(|o| o.name.chars().count());
        let camera_names = self.cameras.iter().map(|c| c.name.chars().count());
        let width = names.chain(camera_names).fold(32, usize::max);
        let shown = if self.objects.len() > object_lines {
            object_lines.min(OBJECT_LINES / 2)
        } else {
            self.objects.len()
        };
        for o in &self.objects[..shown] {
            let what = match o.quadric_type {
                Some(kind) => format!("quadric ({kind})"),
                None => count(o.triangles as usize, "triangle"),
            };
            let what = match o.closed {
                Some(true) => format!("{what}, closed"),
                Some(false) => format!("{what}, open"),
                None => what,
            };
            writeln!(
                f,
                "  object {:>4}  {:<width$} {what:<24} {}",
                o.id, o.name, o.source
            )?;
        }
        if shown < self.objects.len() {
            writeln!(
                f,
                "  ... {} (--all lists every object, --json gives them all)",
                count(self.objects.len() - shown, "more object")
            )?;
        }
        for c in &self.cameras {
            let projection = match c.projection {
                Projection::Perspective { yfov } => format!("perspective yfov {yfov:.4} rad"),
                Projection::Orthographic { ymag } => format!("orthographic ymag {ymag}"),
                Projection::Pinhole(p) => format!("pinhole K {:?}", p.k),
            };
            writeln!(
                f,
                "  camera {:>4}  {:<width$} {projection}, eye {:?}",
                c.index, c.name, c.eye
            )?;
        }
        if let Some(stage) = &self.stage {
            writeln!(
                f,
                "  stage: upAxis {}, metersPerUnit {}",
                stage.up_axis, stage.meters_per_unit
            )?;
            write_stage_time(f, stage)?;
        }
        if let Some(pose) = &self.pose {
            write_pose(f, pose)?;
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

/// `n` and the noun, plural unless `n` is 1: `1 object`, `2 objects`.
pub fn count(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("{n} {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

/// `v` to ten significant digits of `scale` (the box's size), trailing zeros dropped: the
/// bounds' rounding padding (`2.000000000002`) is noise at that scale.
fn tidy(v: f64, scale: f64) -> String {
    let magnitude = if scale > 0.0 {
        scale.log10().floor() as i32
    } else {
        0
    };
    let decimals = (9 - magnitude).clamp(0, 17) as usize;
    let text = format!("{v:.decimals$}");
    let text = if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    };
    if text == "-0" {
        "0".into()
    } else {
        text
    }
}

/// The `info` lines of a USD stage's time range, the time code drawn and its variant sets.
fn write_stage_time(f: &mut fmt::Formatter<'_>, stage: &StageInfo) -> fmt::Result {
    if let Some(rate) = stage.time_codes_per_second {
        let range = match stage.time_code_range {
            Some([start, end]) => format!("time codes {start} to {end}"),
            None => "no authored time range".into(),
        };
        let drawn = match stage.time {
            Some(time) => format!("drawn at time code {time}"),
            None if stage.time_sampled_attributes > 0 => format!(
                "drawn at the default time code ({} time-sampled attributes; --time CODE)",
                stage.time_sampled_attributes
            ),
            None => "drawn at the default time code".into(),
        };
        writeln!(f, "  time: {range}, {rate} per second; {drawn}")?;
    }
    for skel in &stage.skeletons {
        let posed = match &skel.animation {
            Some(anim) => format!("posed by {anim}"),
            None => "at its rest transforms".into(),
        };
        write!(
            f,
            "  skeleton {}: {} joints, {posed}; skins {} prims: {}",
            skel.path,
            skel.joints,
            skel.skinned.len(),
            skel.skinned.join(", ")
        )?;
        if !skel.blend_shaped.is_empty() {
            write!(f, "; blend shapes on {}", skel.blend_shaped.join(", "))?;
        }
        writeln!(f)?;
    }
    for v in &stage.variant_sets {
        let chosen = match (&v.selected, &v.authored) {
            (Some(s), Some(a)) if s != a => format!("{s} (chosen; authored {a})"),
            (Some(s), _) => s.clone(),
            (None, _) => "none".into(),
        };
        writeln!(
            f,
            "  variant set {} {{{}}}: {chosen}; choices {}",
            v.prim,
            v.set,
            v.choices.join(", ")
        )?;
    }
    Ok(())
}

/// The `info` lines of a glTF file's animations, skins and morph targets.
fn write_pose(f: &mut fmt::Formatter<'_>, pose: &PoseInfo) -> fmt::Result {
    writeln!(
        f,
        "  posing: {} animations, {} skins, {} meshes with morph targets; drawn {}",
        pose.animations.len(),
        pose.skins,
        pose.morphed_meshes,
        match pose.time {
            Some(t) => format!("at --time {t}"),
            None => "without animation (the nodes' own transforms and default weights)".into(),
        }
    )?;
    for a in &pose.animations {
        let range = a.range.map_or("no keyframe bounds".into(), |[lo, hi]| {
            format!("{lo} .. {hi} s")
        });
        writeln!(
            f,
            "  animation {:>3}  {:<24} {range}, {} channels{}",
            a.index,
            a.name.as_deref().unwrap_or("-"),
            a.channels,
            if a.applied { ", applied" } else { "" }
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_print_without_rounding_noise() {
        assert_eq!(tidy(-2.000000000002, 28.0), "-2");
        assert_eq!(tidy(15.000000000015, 28.0), "15");
        assert_eq!(tidy(1.000000002001, 2.0), "1.000000002");
        assert_eq!(tidy(0.125, 1.0), "0.125");
        assert_eq!(tidy(-1e-13, 1.0), "0");
        assert_eq!(tidy(123456789012.0, 1e11), "123456789012");
        assert_eq!(count(1, "object"), "1 object");
        assert_eq!(count(0, "quadric"), "0 quadrics");
    }
}
