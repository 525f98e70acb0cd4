//! Which of the assets found a run checks: `--exclude GLOB`, `--root-layers-only` (see
//! [`super::layers`]) and `--shard K/N`, applied in that order to the assets in
//! [`super::report_order`], so every shard of a library agrees on the whole list.

use super::Asset;
use crate::error::{Error, Result};
use std::str::FromStr;

/// `--shard K/N`: the K-th (1-based) of N disjoint parts of the assets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// K, from 1 to `count`.
    pub index: usize,
    /// N, at least 1.
    pub count: usize,
}

impl FromStr for Shard {
    type Err = Error;

    fn from_str(text: &str) -> Result<Shard> {
        let bad = || Error::usage(format!("'{text}': expected K/N with 1 <= K <= N, e.g. 2/7"));
        let (k, n) = text.split_once('/').ok_or_else(bad)?;
        let index: usize = k.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if index == 0 || count == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    /// Whether the asset at `position` (0-based, in report order) belongs to this shard:
    /// positions are dealt round-robin, so shards differ in size by at most one and a
    /// folder of slow assets is spread over all of them.
    pub fn holds(&self, position: usize) -> bool {
        position % self.count == self.index - 1
    }

    /// How many of `total` assets this shard holds.
    pub fn size(&self, total: usize) -> usize {
        (0..total).filter(|&p| self.holds(p)).count()
    }
}

/// `--exclude GLOB` patterns, matched against an asset's relative path: a pattern without
/// `/` matches the file name or any folder name on the way (`*.usdc`, `materials`), one
/// with `/` the whole relative path (`kit/**/materials/*.usda`); `*` and `?` never match `/`.
#[derive(Debug, Clone, Default)]
pub struct Excludes(Vec<glob::Pattern>);

impl Excludes {
    /// Parses the patterns; a malformed one is a usage error naming it.
    pub fn new(patterns: &[String]) -> Result<Excludes> {
        patterns
            .iter()
            .map(|p| {
                glob::Pattern::new(p)
                    .map_err(|e| Error::usage(format!("--exclude '{p}': {}", e.msg)))
            })
            .collect::<Result<Vec<_>>>()
            .map(Excludes)
    }

    /// Whether `relpath` (`/`-separated) is excluded.
    pub fn excludes(&self, relpath: &str) -> bool {
        let options = glob::MatchOptions {
            case_sensitive: true,
            require_literal_separator: true,
            require_literal_leading_dot: false,
        };
        self.0.iter().any(|pattern| {
            if pattern.as_str().contains('/') {
                pattern.matches_with(relpath, options)
            } else {
                relpath
                    .split('/')
                    .any(|part| pattern.matches_with(part, options))
            }
        })
    }
}

/// The assets left after `excludes`; an error when they exclude everything.
pub fn exclude(assets: Vec<Asset>, excludes: &Excludes) -> Result<Vec<Asset>> {
    let found = assets.len();
    let kept: Vec<Asset> = assets
        .into_iter()
        .filter(|a| !excludes.excludes(&a.relpath))
        .collect();
    if kept.is_empty() && found > 0 {
        return Err(Error::usage(format!(
            "--exclude leaves none of the {found} assets found"
        )));
    }
    Ok(kept)
}

/// The assets of `shard` (all of them without one).
pub fn shard(assets: Vec<Asset>, shard: Option<Shard>) -> Vec<Asset> {
    match shard {
        None => assets,
        Some(shard) => assets
            .into_iter()
            .enumerate()
            .filter(|(p, _)| shard.holds(*p))
            .map(|(_, a)| a)
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_values() {
        assert_eq!("2/7".parse(), Ok(Shard { index: 2, count: 7 }));
        for bad in ["0/3", "4/3", "1/0", "3", "a/b", "-1/3", "1/3/5", ""] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }

    #[test]
    fn shards_partition_every_position_once() {
        for count in 1..9 {
            for total in 0..30 {
                let mut seen = vec![0; total];
                for index in 1..=count {
                    let shard = Shard { index, count };
                    let mine: Vec<usize> = (0..total).filter(|&p| shard.holds(p)).collect();
                    assert_eq!(mine.len(), shard.size(total));
                    for p in mine {
                        seen[p] += 1;
                    }
                }
                assert!(seen.iter().all(|&n| n == 1), "{count} {total}");
            }
        }
    }

    #[test]
    fn excludes_match_names_folders_and_paths() {
        let ex =
            Excludes::new(&["*.usdc".into(), "materials".into(), "kit/*/x.obj".into()]).unwrap();
        assert!(ex.excludes("a/b.usdc"));
        assert!(ex.excludes("car/materials/red.usda"));
        assert!(ex.excludes("kit/a/x.obj"));
        assert!(!ex.excludes("kit/a/b/x.obj"));
        assert!(!ex.excludes("car/material.usda"));
        let deep = Excludes::new(&["kit/**/x.obj".into()]).unwrap();
        assert!(deep.excludes("kit/a/b/x.obj") && deep.excludes("kit/x.obj"));
        assert!(!deep.excludes("other/kit/x.obj"));
        assert!(Excludes::new(&["[".into()]).is_err());
    }
}
