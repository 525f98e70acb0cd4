//! UsdSkel: prims posed by their skeleton at the load's time code, as usd-core's
//! `UsdSkel.BakeSkinning` poses them (in f64, where usd-core stores float points).
//!
//! - Skinning happens under a `SkelRoot` only. Walking down from it, each Imageable prim passes
//!   on the binding properties it authors or inherits (`skel:skeleton`,
//!   `primvars:skel:jointIndices`, `jointWeights`, `geomBindTransform`, `skel:joints`), as
//!   usd-core's `UsdSkelCache::Populate` does; a prim that is not Imageable (an untyped `def`)
//!   ends skinning below it, and so does a skinnable (Boundable) prim.
//! - A skeleton's joints are posed by the SkelAnimation its `skel:animationSource` (on it or an
//!   ancestor) names, mapped by joint name, and by its `restTransforms` for the joints the
//!   animation does not pose or when it gives no value at the time ([`skeleton`]).
//! - A prim with `vertex` influences (a Mesh) gets linear-blend-skinned points in the
//!   skeleton's space, drawn under the skeleton's world transform; one with `constant`
//!   influences (any drawn prim) is moved rigidly: its world transform becomes the skinned
//!   transform under the skeleton's ([`influences`]). The prim's own transform is ignored.
//!
//! - A skinned mesh's blend shapes move its rest points first, at the weights of the
//!   skeleton's animation ([`blend_shapes`]).
//!
//! Dual-quaternion skinning is not applied, nor are blend shapes on a prim that is not skinned
//! as a mesh: a warning names each prim that has them.

mod blend_shapes;
mod influences;
mod skeleton;

use super::value;
use super::{err, Loader};
use super::{warning_at, warning_because};
use crate::error::{Error, Result};
use crate::scene::SkeletonInfo;
use blend_shapes::BlendShapes;
use glam::{DMat4, DVec3};
use influences::Influences;
use openusd::usd::Prim;
use skeleton::{Animation, BlendWeights, Skeleton};
use std::collections::{BTreeMap, HashMap};
use std::rc::Rc;

/// The binding properties a prim under a SkelRoot inherits: the prim that authors each one.
#[derive(Clone, Default)]
pub(super) struct Binding {
    skeleton: Option<Prim>,
    joint_indices: Option<Prim>,
    joint_weights: Option<Prim>,
    geom_bind: Option<Prim>,
    joints: Option<Prim>,
}

/// How a skinned prim is drawn.
pub(super) enum Pose {
    /// A mesh's skinned points, in its skeleton's space, and the skeleton's world transform.
    Points {
        points: Vec<DVec3>,
        skel_world: DMat4,
    },
    /// A rigidly bound prim's new world transform.
    Rigid(DMat4),
}

/// A skeleton posed at the load's time code.
struct Posed {
    joints: Vec<String>,
    skinning: Vec<DMat4>,
    world: DMat4,
    /// The animation's blend shape weights at the time, if it has any.
    blend_weights: Option<BlendWeights>,
}

/// The skeletons met while walking, posed once each, and what they skin (for `info`).
#[derive(Default)]
pub(super) struct Skels {
    posed: HashMap<String, Option<Rc<Posed>>>,
    info: BTreeMap<String, SkeletonInfo>,
}

impl Skels {
    /// The skeletons met, by path.
    pub fn finish(self) -> Vec<SkeletonInfo> {
        self.info.into_values().collect()
    }
}

/// Prims that pass skinning properties down (UsdGeomImageable): every typed prim but these.
fn is_imageable(type_name: &str) -> bool {
    !matches!(
        type_name,
        "" | "SkelAnimation" | "BlendShape" | "GeomSubset" | "Material" | "Shader" | "NodeGraph"
    )
}

/// Prims UsdSkel skins (`UsdSkelIsSkinnablePrim`: Boundable, not a Skeleton or SkelRoot).
pub(super) fn is_skinnable(type_name: &str) -> bool {
    super::shapes::is_shape(type_name)
        || matches!(
            type_name,
            "Mesh"
                | "Points"
                | "BasisCurves"
                | "NurbsCurves"
                | "HermiteCurves"
                | "NurbsPatch"
                | "TetMesh"
                | "PointInstancer"
        )
}

impl Binding {
    /// The binding `prim` passes on given its parent's (`None`: outside any SkelRoot).
    pub fn below(
        parent: Option<&Rc<Binding>>,
        prim: &Prim,
        type_name: &str,
    ) -> Result<Option<Rc<Binding>>> {
        let parent = match parent {
            Some(parent) => parent.clone(),
            None if type_name == "SkelRoot" => Rc::new(Binding::default()),
            None => return Ok(None),
        };
        if !is_imageable(type_name) {
            return Ok(None);
        }
        let mut binding = (*parent).clone();
        let mut changed = false;
        for (slot, name) in [
            (&mut binding.joint_indices, "primvars:skel:jointIndices"),
            (&mut binding.joint_weights, "primvars:skel:jointWeights"),
            (&mut binding.geom_bind, "primvars:skel:geomBindTransform"),
            (&mut binding.joints, "skel:joints"),
        ] {
            if value::is_authored(prim, name)? {
                *slot = Some(prim.clone());
                changed = true;
            }
        }
        let targets = prim
            .relationship("skel:skeleton")
            .targets()
            .map_err(|e| err(prim, e))?;
        if let Some(target) = targets.first() {
            binding.skeleton = Some(prim.stage().prim(target.clone()));
            changed = true;
        }
        Ok(Some(if changed { Rc::new(binding) } else { parent }))
    }
}

impl Loader {
    /// How `prim` (skinnable, under a SkelRoot) is posed by its bound skeleton; `None` when
    /// nothing skins it (no skeleton or influences, or usd-core would refuse them: a warning).
    pub(super) fn skin(
        &mut self,
        prim: &Prim,
        type_name: &str,
        binding: &Binding,
    ) -> Result<Option<Pose>> {
        let (Some(skel), Some(indices), Some(weights)) = (
            &binding.skeleton,
            &binding.joint_indices,
            &binding.joint_weights,
        ) else {
            return Ok(None);
        };
        let path = prim.path().to_string();
        let Some(posed) = self.posed_skeleton(skel)? else {
            return Ok(None);
        };
        self.warn_unsupported_skinning(prim)?;
        let not_skinned =
            |why: Error| warning_because(path.to_string(), &why, format!("{why}: not skinned"));
        let influences = match Influences::read(indices, weights, self.at)? {
            Ok(influences) => influences,
            Err(why) => {
                self.warnings.push(not_skinned(why));
                return Ok(None);
            }
        };
        let joints = match &binding.joints {
            None => posed.skinning.clone(),
            Some(owner) => {
                let names = value::tokens(owner, "skel:joints", self.at)?.unwrap_or_default();
                let index = |name: &String| posed.joints.iter().position(|j| j == name);
                names
                    .iter()
                    .map(|n| index(n).map_or(DMat4::IDENTITY, |i| posed.skinning[i]))
                    .collect()
            }
        };
        let geom_bind = match &binding.geom_bind {
            Some(owner) => value::matrix(owner, "primvars:skel:geomBindTransform", self.at)?
                .unwrap_or(DMat4::IDENTITY),
            None => DMat4::IDENTITY,
        };
        let pose = if influences.rigid {
            self.warn_unapplied_blend_shapes(prim)?;
            influences
                .skin_transform(&joints, geom_bind)
                .map(|m| Pose::Rigid(posed.world * m))
        } else if type_name != "Mesh" {
            self.warn_unapplied_blend_shapes(prim)?;
            Err(Error::msg(format!(
                "{type_name} prims with vertex influences are not skinned here"
            )))
        } else {
            let Some(mesh) = self.mesh(prim)? else {
                return Ok(None);
            };
            let mut rest: Vec<DVec3> = (0..mesh.mesh.positions().len() as u32)
                .map(|i| mesh.mesh.positions().get(i))
                .collect();
            self.blend((prim, skel), posed.blend_weights.as_ref(), &mut rest)?;
            influences
                .skin_points(&rest, &joints, geom_bind)
                .map(|points| Pose::Points {
                    points,
                    skel_world: posed.world,
                })
        };
        match pose {
            Ok(pose) => {
                if let Some(info) = self.skels.info.get_mut(&skel.path().to_string()) {
                    info.skinned.push(path);
                }
                Ok(Some(pose))
            }
            Err(why) => {
                self.warnings.push(not_skinned(why));
                Ok(None)
            }
        }
    }

    /// Warnings for what a skinned prim asks for that is not applied.
    fn warn_unsupported_skinning(&mut self, prim: &Prim) -> Result<()> {
        let method = value::token(prim, "primvars:skel:skinningMethod", self.at)?;
        if let Some(method) = method.filter(|m| m != "classicLinear") {
            self.warnings.push(warning_at(
                prim.path().to_string(),
                format!(
                    "skel:skinningMethod {method} is not supported: drawn with linear blend \
                     skinning"
                ),
            ));
        }
        Ok(())
    }

    /// Moves a skinned mesh's rest `points` by its blend shapes at the animation's `weights`;
    /// a warning when usd-core would not apply them (the mesh is skinned without them).
    fn blend(
        &mut self,
        (prim, skel): (&Prim, &Prim),
        weights: Option<&BlendWeights>,
        points: &mut [DVec3],
    ) -> Result<()> {
        let Some(shapes) = BlendShapes::read(prim, self.at)? else {
            return Ok(());
        };
        let Some(weights) = weights else {
            return Ok(());
        };
        let applied = shapes.and_then(|shapes| {
            let mut moved = points.to_vec();
            shapes.apply((&weights.names, &weights.weights), &mut moved)?;
            points.copy_from_slice(&moved);
            Ok(())
        });
        match applied {
            Ok(()) => {
                if let Some(info) = self.skels.info.get_mut(&skel.path().to_string()) {
                    info.blend_shaped.push(prim.path().to_string());
                }
            }
            Err(why) => self.warnings.push(warning_because(
                prim.path().to_string(),
                &why,
                format!("{why}: blend shapes not applied"),
            )),
        }
        Ok(())
    }

    /// A warning for blend shapes on a prim skinned rigidly or not as a mesh.
    fn warn_unapplied_blend_shapes(&mut self, prim: &Prim) -> Result<()> {
        if value::is_authored(prim, "skel:blendShapes")? {
            self.warnings.push(warning_at(
                prim.path().to_string(),
                "blend shapes are applied to meshes with vertex influences only (drawn without \
                 them)",
            ));
        }
        Ok(())
    }

    /// The skeleton at `prim` posed at the load's time code, once per skeleton; `None` (with
    /// one warning) when it cannot be posed.
    fn posed_skeleton(&mut self, prim: &Prim) -> Result<Option<Rc<Posed>>> {
        let path = prim.path().to_string();
        if let Some(posed) = self.skels.posed.get(&path) {
            return Ok(posed.clone());
        }
        let posed = self.pose_skeleton(prim)?;
        let posed = match posed {
            Ok(posed) => Some(Rc::new(posed)),
            Err(why) => {
                self.warnings.push(warning_because(
                    path.to_string(),
                    &why,
                    format!("{why}: the prims it binds are not skinned"),
                ));
                None
            }
        };
        self.skels.posed.insert(path, posed.clone());
        Ok(posed)
    }

    fn pose_skeleton(&mut self, prim: &Prim) -> Result<Result<Posed>> {
        let type_name = prim.type_name().map_err(|e| err(prim, e))?;
        if type_name.as_deref() != Some("Skeleton") {
            return Ok(Err(Error::msg(
                "skel:skeleton targets a prim that is not a Skeleton",
            )));
        }
        let skeleton = match Skeleton::read(prim, self.at)? {
            Ok(skeleton) => skeleton,
            Err(why) => return Ok(Err(Error::msg(format!("skeleton {why}")))),
        };
        let source = animation_source(prim)?;
        let animation = match &source {
            Some(source) => Animation::read(source, self.at)?,
            None => None,
        };
        if let (Some(source), None) = (&source, &animation) {
            self.warnings.push(warning_at(
                prim.path().to_string(),
                format!(
                    "skel:animationSource {} is not a SkelAnimation: rest pose drawn",
                    source.path()
                ),
            ));
        }
        let skinning = match skeleton.skinning_transforms(animation.as_ref(), self.at)? {
            Ok(skinning) => skinning,
            Err(why) => return Ok(Err(Error::msg(format!("skeleton {why}")))),
        };
        let world = self.world_of_prim(prim)?;
        let blend_weights = match &animation {
            Some(animation) => animation.blend_shape_weights(self.at)?,
            None => None,
        };
        self.skels.info.insert(
            prim.path().to_string(),
            SkeletonInfo {
                path: prim.path().to_string(),
                joints: skeleton.joints.len(),
                animation: animation.and(source).map(|s| s.path().to_string()),
                skinned: Vec::new(),
                blend_shaped: Vec::new(),
            },
        );
        Ok(Ok(Posed {
            joints: skeleton.joints,
            skinning,
            world,
            blend_weights,
        }))
    }
}

/// The `skel:animationSource` bound on `skeleton` or its nearest ancestor that binds one
/// (usd-core's `GetInheritedAnimationSource`).
fn animation_source(skeleton: &Prim) -> Result<Option<Prim>> {
    let stage = skeleton.stage();
    let mut path = Some(skeleton.path().clone());
    while let Some(p) = path.filter(|p| !p.is_abs_root()) {
        let prim = stage.prim(p.clone());
        let targets = prim
            .relationship("skel:animationSource")
            .targets()
            .map_err(|e| err(&prim, e))?;
        if let Some(target) = targets.first() {
            return Ok(Some(stage.prim(target.clone())));
        }
        path = p.parent();
    }
    Ok(None)
}
