//! Materials, as the Khronos glTF-Validator reads them (`lib/src/base/material.dart`): the
//! types and ranges of their factors, their texture infos (an `index` is required), and
//! whether a primitive gives the tangent space its material's normal maps need.
//!
//! A ray caster draws no material, but a CI check that passes a material the validator
//! refuses would pass a file viewers refuse. The `gltf` crate's validation does not see these:
//! it cannot read such a document at all.

use super::{readable, Walker};
use crate::Code;
use serde_json::{Map, Value};

/// A number a texture info holds beside its index: (key, least, greatest value).
type Extra = (&'static str, f64, f64);

/// Texture infos of the material object itself: (key, the extra number it holds).
const TEXTURE_INFOS: &[(&str, Option<Extra>)] = &[
    (
        "normalTexture",
        Some(("scale", f64::NEG_INFINITY, f64::INFINITY)),
    ),
    ("occlusionTexture", Some(("strength", 0.0, 1.0))),
    ("emissiveTexture", None),
];

/// Texture infos of `pbrMetallicRoughness`.
const PBR_TEXTURE_INFOS: &[&str] = &["baseColorTexture", "metallicRoughnessTexture"];

impl<'a> Walker<'a, '_> {
    /// The validator's schema rules for every material.
    pub(super) fn materials(&mut self) {
        for (i, material) in self.list("materials").iter().enumerate() {
            let Some(material) = material.as_object() else {
                continue; // TYPE_MISMATCH already (schema)
            };
            let at = format!("/materials/{i}");
            if let Some(pbr) = self.object(material, "pbrMetallicRoughness", &at) {
                let pbr_at = format!("{at}/pbrMetallicRoughness");
                self.numbers(pbr, "baseColorFactor", &pbr_at, 4);
                self.number(pbr, "metallicFactor", &pbr_at, 0.0, 1.0);
                self.number(pbr, "roughnessFactor", &pbr_at, 0.0, 1.0);
                for key in PBR_TEXTURE_INFOS {
                    self.texture_info(pbr, key, &pbr_at, None);
                }
            }
            for &(key, extra) in TEXTURE_INFOS {
                self.texture_info(material, key, &at, extra);
            }
            self.numbers(material, "emissiveFactor", &at, 3);
            self.number(material, "alphaCutoff", &at, 0.0, f64::INFINITY);
            if material.get("doubleSided").is_some_and(|v| !v.is_boolean()) {
                self.type_mismatch(&format!("{at}/doubleSided"), "a boolean");
            }
        }
    }

    /// The tangent-space rule for a primitive at `at` that uses `material`: a normal map
    /// (the material's `normalTexture`, KHR_materials_clearcoat's `clearcoatNormalTexture`,
    /// KHR_materials_anisotropy's `anisotropyTexture`) needs NORMAL and TANGENT. Without
    /// both, a `normalTexture` lets a viewer generate the tangents (a warning); without it
    /// the material cannot be drawn as meant (an error).
    pub(super) fn tangent_space(&mut self, at: &str, has_both: bool, material: &Value) {
        if has_both || !needs_tangent(material) {
            return;
        }
        let at = format!("{at}/material");
        if material.get("normalTexture").is_some() {
            self.f.warn(
                Code::MeshPrimitiveGeneratedTangentSpace,
                at,
                "the material needs a tangent space the primitive does not give (NORMAL and TANGENT): a viewer generates it",
            );
        } else {
            self.f.error(
                Code::MeshPrimitiveNoTangentSpace,
                at,
                "the material needs a tangent space the primitive does not give (NORMAL and TANGENT), and has no normalTexture to generate it",
            );
        }
    }

    /// `owner[key]` when it is an object; a TYPE_MISMATCH when it is something else.
    fn object(
        &mut self,
        owner: &'a Map<String, Value>,
        key: &str,
        at: &str,
    ) -> Option<&'a Map<String, Value>> {
        let value = owner.get(key)?;
        if value.is_object() {
            value.as_object()
        } else {
            self.type_mismatch(&format!("{at}/{key}"), "an object");
            None
        }
    }

    /// A texture info: an object with an integer `index` (required), an integer `texCoord`
    /// and maybe one number (`scale`, `strength`) in its range.
    fn texture_info(
        &mut self,
        owner: &'a Map<String, Value>,
        key: &str,
        at: &str,
        extra: Option<Extra>,
    ) {
        let Some(info) = self.object(owner, key, at) else {
            return;
        };
        let at = format!("{at}/{key}");
        match info.get("index") {
            None => self.f.error(
                Code::UndefinedProperty,
                format!("{at}/index"),
                "property 'index' must be defined",
            ),
            Some(index) if !index.is_number() => {
                self.type_mismatch(&format!("{at}/index"), "an integer")
            }
            Some(_) => {} // an integer out of range: VALUE_NOT_IN_RANGE (schema)
        }
        if let Some((name, min, max)) = extra {
            self.number(info, name, &at, min, max);
        }
    }

    /// An optional number `owner[key]` in `min..=max`.
    fn number(&mut self, owner: &Map<String, Value>, key: &str, at: &str, min: f64, max: f64) {
        let Some(value) = owner.get(key) else {
            return;
        };
        let at = format!("{at}/{key}");
        match value.as_f64() {
            None => self.type_mismatch(&at, "a number"),
            Some(x) if x < min || x > max => self.f.error(
                Code::ValueNotInRange,
                at,
                format!("{} is not in [{min}, {max}]", readable(x)),
            ),
            Some(_) => {}
        }
    }

    /// An optional array `owner[key]` of `len` numbers in [0, 1] (a colour factor).
    fn numbers(&mut self, owner: &Map<String, Value>, key: &str, at: &str, len: usize) {
        let Some(value) = owner.get(key) else {
            return;
        };
        let at = format!("{at}/{key}");
        let Some(items) = value.as_array() else {
            return self.type_mismatch(&at, "an array");
        };
        if items.len() != len {
            return self.f.error(
                Code::ArrayLengthNotInList,
                at,
                format!("{} numbers, not {len}", items.len()),
            );
        }
        for (i, item) in items.iter().enumerate() {
            match item.as_f64() {
                None => self.f.error(
                    Code::ArrayTypeMismatch,
                    format!("{at}/{i}"),
                    "expected a number",
                ),
                Some(x) if !(0.0..=1.0).contains(&x) => self.f.error(
                    Code::ValueNotInRange,
                    format!("{at}/{i}"),
                    format!("{} is not in [0, 1]", readable(x)),
                ),
                Some(_) => {}
            }
        }
    }

    fn type_mismatch(&mut self, at: &str, expected: &str) {
        self.f.error(
            Code::TypeMismatch,
            at.to_string(),
            format!("expected {expected}"),
        );
    }
}

/// Whether a material has a normal map of some kind (see [`Walker::tangent_space`]).
fn needs_tangent(material: &Value) -> bool {
    let extension = |name: &str, key: &str| {
        material
            .get("extensions")
            .and_then(|e| e.get(name))
            .and_then(|e| e.get(key))
            .is_some()
    };
    material.get("normalTexture").is_some()
        || extension("KHR_materials_clearcoat", "clearcoatNormalTexture")
        || extension("KHR_materials_anisotropy", "anisotropyTexture")
}
