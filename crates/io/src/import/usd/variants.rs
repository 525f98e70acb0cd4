//! Variant sets: what `info` lists, and `--variant SET=NAME`.
//!
//! A choice applies to every drawn prim that has a variant set named `SET`. It is authored
//! as the prim's `variantSelection` on the root layer, in memory (the file is not written),
//! before anything else of the prim is read: the strongest selection but for a session
//! layer's, which raycast never opens, so the stage composes as usd-core composes it with
//! `GetVariantSets().SetSelection(SET, NAME)` on a session layer. The walk goes down from
//! the root, so variant sets that a selection brings in are met and chosen in turn.

use crate::error::{Error, Result};
use crate::scene::VariantSetInfo;
use openusd::sdf::{self, AbstractData, Value};
use openusd::usd::{Prim, Stage};
use std::collections::HashMap;

/// One `--variant SET=NAME`, parsed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Choice {
    /// The variant set's name.
    pub set: String,
    /// The variant to select.
    pub name: String,
}

/// Parses `SET=NAME` (a usage error otherwise).
pub fn parse_choice(text: &str) -> Result<Choice> {
    match text.split_once('=') {
        Some((set, name)) if !set.trim().is_empty() && !name.trim().is_empty() => Ok(Choice {
            set: set.trim().to_string(),
            name: name.trim().to_string(),
        }),
        _ => Err(Error::msg(format!("--variant '{text}': expected SET=NAME"))),
    }
}

/// The variant sets met during a walk, and the choices to apply.
pub struct Variants {
    choices: Vec<Choice>,
    /// Prims whose sets were listed (a prim may be visited again through an instancer).
    listed: HashMap<String, ()>,
    sets: Vec<VariantSetInfo>,
    /// The selections composed before a choice replaced them, by (prim, set).
    authored: HashMap<(String, String), String>,
    /// Selections made on the prim being visited (nested sets chosen in turn).
    depth: usize,
}

/// Most nested variant sets chosen on one prim.
const MAX_NESTED_SELECTIONS: usize = 64;

impl Variants {
    /// Applies `choices` (none: only lists the sets).
    pub fn new(choices: Vec<Choice>) -> Self {
        Variants {
            choices,
            listed: HashMap::new(),
            sets: Vec::new(),
            authored: HashMap::new(),
            depth: 0,
        }
    }

    /// Lists `prim`'s variant sets and applies the choices that name one of them. Instance
    /// proxies are skipped (usd-core cannot author on them either).
    pub fn visit(&mut self, stage: &Stage, prim: &Prim) -> Result<()> {
        let path = prim.path().to_string();
        if self.listed.contains_key(&path) {
            return Ok(());
        }
        let selections = prim
            .variant_sets()
            .get_all_variant_selections()
            .map_err(|e| {
                Error::at(
                    path.to_string(),
                    format!("cannot read its variant selections: {e:#}"),
                )
            })?;
        if selections.is_empty() || prim.is_instance_proxy().unwrap_or(false) {
            return Ok(());
        }
        self.listed.insert(path.clone(), ());
        let choices = variant_choices(stage, prim)?;
        let mut chosen = Vec::new();
        for (set, authored) in selections {
            let names = choices.get(&set).cloned().unwrap_or_default();
            let wanted = self
                .choices
                .iter()
                .find(|c| c.set == set)
                .map(|c| c.name.clone());
            if let Some(name) = &wanted {
                if !names.contains(name) {
                    return Err(Error::msg(format!(
                        "--variant {set}={name}: {path} has no variant '{name}' in its set \
                         '{set}' (choices: {})",
                        names.join(", ")
                    )));
                }
                if *name != authored {
                    self.authored
                        .insert((path.clone(), set.clone()), authored.clone());
                    chosen.push((set.clone(), name.clone()));
                }
            }
            let authored = self
                .authored
                .get(&(path.clone(), set.clone()))
                .cloned()
                .unwrap_or(authored);
            self.sets.push(VariantSetInfo {
                prim: path.clone(),
                set,
                choices: names,
                selected: wanted.or_else(|| Some(authored.clone())),
                authored: Some(authored),
            });
        }
        if !chosen.is_empty() {
            // The selection may bring in nested variant sets: list the prim again.
            select(stage, prim, &chosen)?;
            self.listed.remove(&path);
            self.sets.retain(|s| s.prim != path);
            self.depth += 1;
            if self.depth > MAX_NESTED_SELECTIONS {
                return Err(Error::at(
                    path.to_string(),
                    format!("variant selections nest deeper than {MAX_NESTED_SELECTIONS}"),
                ));
            }
            let relisted = self.visit(stage, prim);
            self.depth -= 1;
            return relisted;
        }
        Ok(())
    }

    /// The sets met, or an error naming a chosen set that no drawn prim has.
    pub fn finish(self) -> Result<Vec<VariantSetInfo>> {
        for choice in &self.choices {
            if !self.sets.iter().any(|s| s.set == choice.set) {
                let mut known: Vec<&str> = self.sets.iter().map(|s| s.set.as_str()).collect();
                known.sort_unstable();
                known.dedup();
                let known = if known.is_empty() {
                    "the drawn prims have no variant sets".to_string()
                } else {
                    format!("variant sets: {}", known.join(", "))
                };
                return Err(Error::msg(format!(
                    "--variant {}={}: no drawn prim has a variant set '{}' ({known})",
                    choice.set, choice.name, choice.set
                )));
            }
        }
        Ok(self.sets)
    }
}

/// Each variant set's variants over the prim's stack, sorted (as usd-core lists them).
fn variant_choices(stage: &Stage, prim: &Prim) -> Result<HashMap<String, Vec<String>>> {
    let stack = prim.prim_stack().map_err(|e| {
        Error::at(
            prim.path().to_string(),
            format!("cannot read its prim stack: {e:#}"),
        )
    })?;
    let mut choices: HashMap<String, Vec<String>> = HashMap::new();
    for (layer, path) in &stack {
        let Some(layer) = stage.layer(layer) else {
            continue;
        };
        let data = layer.data();
        for set in tokens(data, path, sdf::ChildrenKey::VariantSetChildren.as_str()) {
            let set_path = path.append_variant_selection(&set, "");
            let names = choices.entry(set).or_default();
            for name in tokens(data, &set_path, sdf::ChildrenKey::VariantChildren.as_str()) {
                if !names.contains(&name) {
                    names.push(name);
                }
            }
        }
    }
    // usd-core's GetVariantNames lists them sorted.
    for names in choices.values_mut() {
        names.sort();
    }
    Ok(choices)
}

/// A token-vector field of a spec (empty when absent or of another type).
fn tokens(data: &dyn AbstractData, path: &sdf::Path, field: &str) -> Vec<String> {
    match data.try_field(path, field).ok().flatten().as_deref() {
        Some(Value::TokenVec(v)) => v.iter().map(|t| t.as_str().to_string()).collect(),
        Some(Value::StringVec(v)) => v.clone(),
        _ => Vec::new(),
    }
}

/// Authors `chosen` into the prim's `variantSelection` on the root layer, keeping the
/// selections that layer already authors for other sets.
fn select(stage: &Stage, prim: &Prim, chosen: &[(String, String)]) -> Result<()> {
    let fail = |e: &dyn std::fmt::Display| {
        Error::at(
            prim.path().to_string(),
            format!("cannot select its variants: {e}"),
        )
    };
    stage
        .set_edit_target(stage.edit_target_root())
        .map_err(|e| fail(&e))?;
    stage
        .override_prim(prim.path().clone())
        .and_then(|p| {
            p.update_metadata("variantSelection", |old| {
                let mut map = match old {
                    Some(Value::VariantSelectionMap(map)) => map,
                    _ => HashMap::new(),
                };
                for (set, name) in chosen {
                    map.insert(set.clone(), name.clone());
                }
                Value::VariantSelectionMap(map)
            })
        })
        .map_err(|e| fail(&e))?;
    Ok(())
}
