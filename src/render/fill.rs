//! The per-ray outputs (AOVs) of a trace, computed in the same parallel pass as the nearest-hit
//! search: each ray's values are written while its hit is at hand, with no array of hits in
//! between. The command line's buffers and the Python package's `cast` and `render` are all
//! made by [`trace`], so they share this loop.

use super::{Aov, RaySource, Tracer};
use crate::geometry::Ray;
use crate::scene::{Crossing, Located};
use glam::DVec3;
use rayon::prelude::*;

/// One AOV's values for every ray.
#[derive(Debug, Clone, PartialEq)]
pub enum Column {
    /// One number per ray (depth, z, t).
    Float(Vec<f64>),
    /// Three numbers per ray, flattened (normal, position, bary).
    Vector(Vec<f64>),
    /// One label per ray (id, prim).
    Index(Vec<u32>),
}

impl Column {
    fn new(aov: Aov, n: usize) -> Column {
        match miss(aov) {
            Value::Float(_) => Column::Float(vec![0.0; n]),
            Value::Vector(_) => Column::Vector(vec![0.0; 3 * n]),
            Value::Index(_) => Column::Index(vec![0; n]),
        }
    }

    /// The column cut into blocks of `BLOCK` rays.
    fn blocks(&mut self) -> Box<dyn Iterator<Item = Slot<'_>> + '_> {
        match self {
            Column::Float(v) => Box::new(v.chunks_mut(BLOCK).map(Slot::Float)),
            Column::Vector(v) => Box::new(v.chunks_mut(3 * BLOCK).map(Slot::Vector)),
            Column::Index(v) => Box::new(v.chunks_mut(BLOCK).map(Slot::Index)),
        }
    }
}

/// The buffers of a trace: one column per requested AOV, in the order requested.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Buffers {
    columns: Vec<(Aov, Column)>,
}

impl Buffers {
    /// The values of `aov`, if it was computed.
    pub fn column(&self, aov: Aov) -> Option<&Column> {
        self.columns.iter().find(|(a, _)| *a == aov).map(|(_, c)| c)
    }

    /// The values of a one-number AOV (depth, z, t).
    pub fn floats(&self, aov: Aov) -> Option<&[f64]> {
        match self.column(aov)? {
            Column::Float(v) => Some(v),
            _ => None,
        }
    }

    /// The values of a vector AOV (normal, position, bary).
    pub fn vectors(&self, aov: Aov) -> Option<&[[f64; 3]]> {
        match self.column(aov)? {
            Column::Vector(v) => Some(v.as_chunks().0),
            _ => None,
        }
    }

    /// The values of a label AOV (id, prim).
    pub fn labels(&self, aov: Aov) -> Option<&[u32]> {
        match self.column(aov)? {
            Column::Index(v) => Some(v),
            _ => None,
        }
    }

    /// The columns, in the order the AOVs were requested.
    pub fn into_columns(self) -> Vec<(Aov, Column)> {
        self.columns
    }
}

/// The value of `aov` on a miss.
fn miss(aov: Aov) -> Value {
    match aov {
        Aov::T | Aov::Depth | Aov::Z => Value::Float(f64::INFINITY),
        Aov::Position => Value::Vector(DVec3::INFINITY),
        Aov::Normal | Aov::Bary => Value::Vector(DVec3::ZERO),
        Aov::Id => Value::Index(0),
        Aov::Prim => Value::Index(u32::MAX),
    }
}

/// Whether `aov` needs the hit resolved to its object and primitive.
fn needs_locate(aov: Aov) -> bool {
    matches!(aov, Aov::Normal | Aov::Id | Aov::Prim)
}

/// What the outputs of one ray's hit are computed from.
struct At<'a> {
    tracer: &'a Tracer<'a>,
    ray: &'a Ray,
    hit: &'a Crossing,
    /// The hit's object and primitive, when an output needs them.
    located: Option<Located<'a>>,
    /// The camera's eye and view axis (zeros without a camera).
    eye: DVec3,
    forward: DVec3,
}

impl At<'_> {
    /// The value of `aov` at this hit.
    fn value(&self, aov: Aov) -> Value {
        let (ray, hit) = (self.ray, self.hit);
        let located = || self.located.as_ref();
        match aov {
            Aov::T => Value::Float(hit.t),
            Aov::Depth => Value::Float(hit.t * ray.dir.length()),
            Aov::Z => Value::Float((ray.at(hit.t) - self.eye).dot(self.forward)),
            Aov::Position => Value::Vector(ray.at(hit.t)),
            Aov::Normal => located().map_or(miss(aov), |l| Value::Vector(l.normal)),
            Aov::Id => located().map_or(miss(aov), |l| Value::Index(l.object.id)),
            Aov::Prim => located().map_or(miss(aov), |l| Value::Index(l.prim)),
            Aov::Bary => {
                let weights = self.tracer.scene.barycentric(hit, ray.origin, ray.dir);
                Value::Vector(weights.map_or(DVec3::ZERO, DVec3::from_array))
            }
        }
    }
}

/// One AOV's value for one ray.
enum Value {
    Float(f64),
    Vector(DVec3),
    Index(u32),
}

/// One block of a column.
enum Slot<'a> {
    Float(&'a mut [f64]),
    Vector(&'a mut [f64]),
    Index(&'a mut [u32]),
}

impl Slot<'_> {
    /// Stores the `j`-th value of the block (a column holds its AOV's type of value).
    fn set(&mut self, j: usize, value: Value) {
        match (self, value) {
            (Slot::Float(s), Value::Float(v)) => s[j] = v,
            (Slot::Vector(s), Value::Vector(v)) => {
                s[3 * j..3 * j + 3].copy_from_slice(&v.to_array())
            }
            (Slot::Index(s), Value::Index(v)) => s[j] = v,
            _ => unreachable!("a column is made for its AOV's type"),
        }
    }
}

/// Rays per parallel task.
const BLOCK: usize = 1024;

/// Tasks between two progress reports (64 Ki rays).
const BLOCKS_PER_REPORT: usize = 64;

/// The rays of a trace: their source, each ray's `(t_min, t_max]`, and which rays without a
/// hit are refused. Generic, so that reading a ray and its range is inlined into the search
/// loop.
pub struct Rays<'a, S: ?Sized, R, F> {
    /// The rays.
    pub source: &'a S,
    /// Ray `i`'s parameter range `(t_min, t_max]`.
    pub range: R,
    /// Whether ray `i`, which has no hit, is one that cannot be traced (an error).
    pub refused: F,
}

/// Finds the nearest hit of every ray in its range ([`Tracer::nearest`]) and computes `aovs`
/// from it, in one parallel pass over blocks of rays. `progress` is told how many rays are
/// done after every 64 Ki rays. Returns the buffers, or the first refused ray.
pub fn trace<S, R, F>(
    tracer: &Tracer,
    rays: &Rays<S, R, F>,
    aovs: &[Aov],
    mut progress: impl FnMut(usize),
) -> Result<Buffers, usize>
where
    S: RaySource + ?Sized,
    R: Fn(usize) -> (f64, f64) + Sync,
    F: Fn(usize) -> bool + Sync,
{
    let n = rays.source.len();
    let mut columns: Vec<(Aov, Column)> = aovs.iter().map(|&a| (a, Column::new(a, n))).collect();
    let mut blocks: Vec<Vec<Slot>> = (0..n.div_ceil(BLOCK)).map(|_| Vec::new()).collect();
    for (_, column) in &mut columns {
        for (block, slot) in blocks.iter_mut().zip(column.blocks()) {
            block.push(slot);
        }
    }
    let locate = aovs.iter().any(|&a| needs_locate(a));
    let (eye, forward) = rays
        .source
        .view_axis()
        .unwrap_or((DVec3::ZERO, DVec3::ZERO));
    let fill = |b: usize, slots: &mut [Slot]| -> Option<usize> {
        let mut refused = None;
        for i in b * BLOCK..n.min((b + 1) * BLOCK) {
            let ray = rays.source.ray(i);
            let (t_min, t_max) = (rays.range)(i);
            let hit = tracer.nearest(&ray, t_min, t_max);
            let at = hit.as_ref().map(|hit| At {
                tracer,
                ray: &ray,
                hit,
                located: locate.then(|| tracer.scene.locate_crossing(hit, ray.origin, ray.dir)),
                eye,
                forward,
            });
            if at.is_none() && refused.is_none() && (rays.refused)(i) {
                refused = Some(i);
            }
            for (slot, &aov) in slots.iter_mut().zip(aovs) {
                let value = at.as_ref().map_or(miss(aov), |at| at.value(aov));
                slot.set(i - b * BLOCK, value);
            }
        }
        refused
    };
    let mut blocks = blocks.into_iter().enumerate().peekable();
    while blocks.peek().is_some() {
        let group: Vec<_> = blocks.by_ref().take(BLOCKS_PER_REPORT).collect();
        let end = group.last().map_or(0, |(b, _)| n.min((b + 1) * BLOCK));
        let refused = group
            .into_par_iter()
            .filter_map(|(b, mut slots)| fill(b, &mut slots))
            .min();
        if let Some(i) = refused {
            return Err(i);
        }
        progress(end);
    }
    Ok(Buffers { columns })
}
