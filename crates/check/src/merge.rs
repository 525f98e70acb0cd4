//! Shard outputs and their merge. A shard (`--shard K/N --json`) prints a header line, then
//! one line per asset; `--merge` reads the shards of one run back and rebuilds the report of
//! the whole library: the same records in the same order as an unsharded run, and the same
//! verdict. Every way the files can fail to fit together is an error naming the file.

use super::select::Shard;
use super::{report_order, AssetReport};
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// What a shard's first line says about it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShardHeader {
    /// K.
    pub index: usize,
    /// N.
    pub count: usize,
    /// Asset records that follow.
    pub assets: usize,
    /// Assets of the whole run (all shards), after `--exclude` and `--root-layers-only`.
    pub total: usize,
    /// Seconds the shard took.
    pub seconds: f64,
    /// The options that shape the findings and the verdict; every shard of a run has the
    /// same.
    pub settings: serde_json::Value,
}

/// The header line as JSON: `{"raycast_check_shard": {...}}`.
#[derive(Debug, Serialize, Deserialize)]
struct HeaderLine {
    raycast_check_shard: ShardHeader,
}

impl ShardHeader {
    /// The header as one line of JSON (with the newline).
    pub fn line(&self) -> String {
        let line = HeaderLine {
            raycast_check_shard: self.clone(),
        };
        serde_json::to_string(&line).unwrap_or_default() + "\n"
    }

    fn shard(&self) -> Shard {
        Shard {
            index: self.index,
            count: self.count,
        }
    }
}

/// The whole run rebuilt from its shards.
#[derive(Debug)]
pub struct Merged {
    /// Every asset's record, in report order.
    pub reports: Vec<AssetReport>,
    /// The shards' settings (the same for all).
    pub settings: serde_json::Value,
    /// The shards' seconds added up.
    pub seconds: f64,
}

/// One shard file, read.
struct ShardFile {
    path: PathBuf,
    header: ShardHeader,
    reports: Vec<AssetReport>,
}

fn read(path: &Path) -> Result<ShardFile> {
    let fail = |what: String| Error::in_file(path, what).as_usage();
    let text = std::fs::read_to_string(path).map_err(|e| fail(format!("cannot read: {e}")))?;
    let mut lines = text.lines().enumerate();
    let header = lines
        .next()
        .and_then(|(_, line)| serde_json::from_str::<HeaderLine>(line).ok())
        .ok_or_else(|| {
            fail("not the output of 'raycast check --shard K/N --json' (no shard header on its first line)".into())
        })?
        .raycast_check_shard;
    if header.index == 0 || header.index > header.count {
        return Err(fail(format!(
            "shard header names shard {}/{}",
            header.index, header.count
        )));
    }
    let mut reports = Vec::new();
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let report = serde_json::from_str::<AssetReport>(line)
            .map_err(|e| fail(format!("line {}: not an asset record ({e})", i + 1)))?;
        reports.push(report);
    }
    if reports.len() != header.assets {
        return Err(fail(format!(
            "holds {} asset records, its header says {} (cut short?)",
            reports.len(),
            header.assets
        )));
    }
    Ok(ShardFile {
        path: path.to_path_buf(),
        header,
        reports,
    })
}

/// The first setting whose value differs between `a` and `b`, as `name: A vs B`.
fn first_difference(a: &serde_json::Value, b: &serde_json::Value) -> String {
    let (Some(a), Some(b)) = (a.as_object(), b.as_object()) else {
        return format!("{a} vs {b}");
    };
    a.keys()
        .chain(b.keys())
        .find(|k| a.get(*k) != b.get(*k))
        .map(|k| {
            let show = |v: Option<&serde_json::Value>| v.map_or("(none)".into(), |v| v.to_string());
            format!("{k}: {} vs {}", show(a.get(k)), show(b.get(k)))
        })
        .unwrap_or_default()
}

/// Checks that the shards are exactly the N shards of one run.
fn fit_together(shards: &[ShardFile]) -> Result<()> {
    let first = &shards[0];
    let mut owner: Vec<Option<&Path>> = vec![None; first.header.count];
    for s in shards {
        let fail = |what: String| Err(Error::in_file(&s.path, what).as_usage());
        let (h, f) = (&s.header, &first.header);
        if h.count != f.count {
            return fail(format!(
                "shard {} does not belong with shard {} of {}",
                h.shard(),
                f.shard(),
                first.path.display()
            ));
        }
        if h.settings != f.settings {
            return fail(format!(
                "shard of a run with other settings than {} ({})",
                first.path.display(),
                first_difference(&h.settings, &f.settings)
            ));
        }
        if h.total != f.total {
            return fail(format!(
                "its run found {} assets, the run of {} found {}",
                h.total,
                first.path.display(),
                f.total
            ));
        }
        if h.assets != h.shard().size(h.total) {
            return fail(format!(
                "holds {} assets, but shard {} of {} assets holds {}",
                h.assets,
                h.shard(),
                h.total,
                h.shard().size(h.total)
            ));
        }
        if let Some(other) = owner[h.index - 1] {
            return fail(format!(
                "shard {} is given twice (also {})",
                h.shard(),
                other.display()
            ));
        }
        owner[h.index - 1] = Some(&s.path);
    }
    let missing: Vec<String> = (1..=first.header.count)
        .filter(|k| owner[k - 1].is_none())
        .map(|k| format!("{k}/{}", first.header.count))
        .collect();
    if !missing.is_empty() {
        return Err(Error::usage(format!(
            "shard {} missing: merge the output of every shard of the run",
            missing.join(", ")
        )));
    }
    Ok(())
}

/// Reads and merges the shard files of one run.
pub fn merge(files: &[PathBuf]) -> Result<Merged> {
    let shards = files.iter().map(|f| read(f)).collect::<Result<Vec<_>>>()?;
    if shards.is_empty() {
        return Err(Error::usage("--merge needs the shard files"));
    }
    fit_together(&shards)?;
    let settings = shards[0].header.settings.clone();
    let seconds = shards.iter().map(|s| s.header.seconds).sum();
    let places: Vec<(Shard, PathBuf)> = shards
        .iter()
        .map(|s| (s.header.shard(), s.path.clone()))
        .collect();
    let mut all: Vec<(usize, AssetReport)> = shards
        .into_iter()
        .enumerate()
        .flat_map(|(i, s)| s.reports.into_iter().map(move |r| (i, r)))
        .collect();
    all.sort_by(|(_, a), (_, b)| report_order((&a.relpath, &a.path), (&b.relpath, &b.path)));
    for pair in all.windows(2) {
        if pair[0].1.path == pair[1].1.path {
            return Err(Error::in_file(
                &places[pair[1].0].1,
                format!(
                    "{} is also in {}",
                    pair[1].1.path,
                    places[pair[0].0].1.display()
                ),
            )
            .as_usage());
        }
    }
    // Each record must sit where its shard's share of the sorted list puts it.
    for (position, (i, report)) in all.iter().enumerate() {
        let (shard, path) = &places[*i];
        if !shard.holds(position) {
            return Err(Error::in_file(
                path,
                format!(
                    "{} does not belong to shard {shard} of the merged list: the shards did not see the same assets",
                    report.path
                ),
            )
            .as_usage());
        }
    }
    Ok(Merged {
        reports: all.into_iter().map(|(_, r)| r).collect(),
        settings,
        seconds,
    })
}
