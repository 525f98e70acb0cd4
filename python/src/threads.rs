//! `nthreads=` of each query: the work runs on a rayon pool of that many threads (0: the
//! global pool, one thread per core). Pools are made once per size and kept. As on the command
//! line (`--threads`), more threads than cores are brought down to the cores: the work is bound
//! by the cores, and a thousand threads on two cores ran 90 times slower.

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use rayon::prelude::*;
use rayon::{ThreadPool, ThreadPoolBuilder};
use std::sync::{Arc, Mutex};

/// `each(i)` for `i` in `0..n`, in parallel on `nthreads` threads (0: all cores), with the GIL
/// released: the loop of every per-ray and per-point query.
pub fn map<T: Send>(
    py: Python<'_>,
    nthreads: usize,
    n: usize,
    each: impl Fn(usize) -> T + Sync + Send,
) -> PyResult<Vec<T>> {
    py.detach(|| run(nthreads, || (0..n).into_par_iter().map(each).collect()))
}

/// The pools made so far, by thread count.
static POOLS: Mutex<Vec<(usize, Arc<ThreadPool>)>> = Mutex::new(Vec::new());

/// Runs `work` on `nthreads` threads (0: all cores); the answer does not depend on it.
pub fn run<T: Send>(nthreads: usize, work: impl FnOnce() -> T + Send) -> PyResult<T> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if nthreads == 0 || nthreads >= cores && rayon::current_num_threads() == cores {
        return Ok(work());
    }
    Ok(pool(nthreads.min(cores))?.install(work))
}

/// The pool of `n` threads, made on first use.
fn pool(n: usize) -> PyResult<Arc<ThreadPool>> {
    let mut pools = POOLS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, pool)) = pools.iter().find(|(size, _)| *size == n) {
        return Ok(pool.clone());
    }
    let pool = ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start {n} threads: {e}")))?;
    let pool = Arc::new(pool);
    pools.push((n, pool.clone()));
    Ok(pool)
}
