//! Many times in one run (`--time START:STOP:STEP`): the scene file is opened once
//! ([`import::open`]: a glTF file read, parsed and decoded once; a USD stage read again at each
//! time) and each time is rendered into its own folder under the output folder, named
//! `NNNN-tTIME` (the index, four digits, then the time): `0000-t0.0`, `0001-t0.1`, … sort in
//! time order. Each folder is what a single run at that time (`--time TIME --out FOLDER`)
//! writes, with the same ownership rules (see [`crate::output::ownership`]); they are all
//! claimed before any is written.

use super::{check_request, run_from, Progress, RenderJob};
use crate::error::{Error, Result};
use crate::import::{self, LoadOptions};
use crate::output::{ownership, sidecar::Sidecar};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Most times one sequence may render.
pub const MAX_TIMES: usize = 10_000;

/// Most decimals a time is written with in a folder name.
const MAX_DECIMALS: usize = 12;

/// The times START, START + STEP, … up to STOP (inclusive when STOP falls on a step within
/// rounding, 1e-9 of the steps' count).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Times {
    start: f64,
    step: f64,
    count: usize,
    /// The fewest decimals that write START and STEP exactly (`None`: no such count up to
    /// [`MAX_DECIMALS`]); the times are rounded to them, so that the time a folder's name
    /// says is the time it was rendered at (`--time 0.3`, not 0.30000000000000004).
    decimals: Option<usize>,
}

impl std::str::FromStr for Times {
    type Err = Error;

    /// Reads `START:STOP:STEP`; what is wrong, in a few words, otherwise.
    fn from_str(text: &str) -> Result<Times> {
        let parts: Vec<&str> = text.split(':').collect();
        let [start, stop, step] = parts[..] else {
            return Err(Error::usage("expected START:STOP:STEP (three numbers)"));
        };
        let number = |p: &str| match p.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(Error::usage(format!("'{p}' is not a finite number"))),
        };
        let (start, stop, step) = (number(start)?, number(stop)?, number(step)?);
        if step <= 0.0 {
            return Err(Error::usage("STEP must be positive"));
        }
        if stop < start {
            return Err(Error::usage("STOP is before START"));
        }
        let steps = (stop - start) / step;
        // Finite, or infinite when STOP - START overflows: never NaN (STEP is positive).
        let steps = (steps + steps.max(1.0) * 1e-9).floor();
        if steps >= MAX_TIMES as f64 {
            return Err(Error::usage(format!("more than {MAX_TIMES} times")));
        }
        Ok(Times {
            start,
            step,
            count: steps as usize + 1,
            decimals: decimals(&[start, step]),
        })
    }
}

/// The fewest decimals (up to [`MAX_DECIMALS`]) that write each of `values` exactly.
fn decimals(values: &[f64]) -> Option<usize> {
    (0..=MAX_DECIMALS).find(|&d| {
        values
            .iter()
            .all(|&v| format!("{v:.d$}").parse::<f64>() == Ok(v))
    })
}

impl Times {
    /// How many times.
    pub fn len(&self) -> usize {
        self.count
    }

    /// Whether there are none (never: STOP ≥ START gives START at least).
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// The `i`-th time's text: START + i·STEP (not accumulated) written with the decimals of
    /// START and STEP.
    fn text(&self, i: usize) -> String {
        let time = self.start + i as f64 * self.step;
        match self.decimals {
            Some(d) => format!("{time:.d$}"),
            None => format!("{time:?}"),
        }
    }

    /// The `i`-th time: the number its text says.
    pub fn time(&self, i: usize) -> f64 {
        self.text(i)
            .parse()
            .unwrap_or(self.start + i as f64 * self.step)
    }

    /// The `i`-th time's folder name: `NNNN-tTIME`.
    pub fn folder_name(&self, i: usize) -> String {
        format!("{i:04}-t{}", self.text(i))
    }
}

/// One time of a sequence: its time and the folder it is written to.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// The time (glTF seconds, USD time code).
    pub time: f64,
    /// The output folder, `<out>/NNNN-tTIME`.
    pub folder: PathBuf,
}

/// What a sequence did.
#[derive(Debug)]
pub struct Outcome {
    /// Each time's sidecar, in order.
    pub sidecars: Vec<Sidecar>,
    /// Each time's folder.
    pub frames: Vec<Frame>,
    /// Seconds taken to open the scene file (read and decode it, for glTF).
    pub open: f64,
}

/// The frames of `times` under the job's output folder.
pub fn frames(job: &RenderJob, times: &Times) -> Vec<Frame> {
    let out = job.out_dir();
    (0..times.len())
        .map(|i| Frame {
            time: times.time(i),
            folder: out.join(times.folder_name(i)),
        })
        .collect()
}

/// Renders `job` at each of `times`, one folder each; `progress` is told which frame a
/// render's progress is of. Every folder is claimed before the file is opened; a time that
/// fails ends the run (the folders of the times before it stay written).
pub fn run(
    job: &RenderJob,
    times: &Times,
    mut progress: impl FnMut(&Frame, Progress) + Send,
) -> Result<Outcome> {
    let formats = check_request(job)?;
    let frames = frames(job, times);
    let names = job.file_names(&formats);
    let inputs: Vec<&Path> = std::iter::once(job.scene.as_path())
        .chain(job.rays.as_deref())
        .collect();
    ownership::claim(&job.out_dir(), &job.scene, &[])?;
    for frame in &frames {
        ownership::refuse_inputs(&frame.folder, &names, &inputs)?;
        ownership::claim(&frame.folder, &job.scene, &names)?;
    }
    let started = Instant::now();
    let first = LoadOptions {
        time: frames.first().map(|f| f.time),
        ..job.load.clone()
    };
    let source = import::open(&job.scene, &first)?;
    let open = started.elapsed().as_secs_f64();
    let mut sidecars = Vec::with_capacity(frames.len());
    for frame in &frames {
        let mut one = job.clone();
        one.out = Some(frame.folder.clone());
        one.load.time = Some(frame.time);
        let sidecar = run_from(&one, Some(&source), |event| progress(frame, event))
            .map_err(|e| at_time(e, frame))?;
        sidecars.push(sidecar);
    }
    Ok(Outcome {
        sidecars,
        frames,
        open,
    })
}

/// `error` saying which time of the sequence it happened at.
fn at_time(mut error: Error, frame: &Frame) -> Error {
    error.message = format!("{} (at --time {})", error.message, frame.time);
    error
}

#[cfg(test)]
mod tests {
    use super::*;

    fn times(text: &str) -> Vec<f64> {
        let times: Times = text.parse().unwrap();
        (0..times.len()).map(|i| times.time(i)).collect()
    }

    #[test]
    fn ranges_include_stop_within_rounding() {
        let tenths = times("0:1:0.1");
        assert_eq!(tenths.len(), 11);
        assert_eq!(tenths[3], 0.3);
        assert_eq!(tenths[10], 1.0);
        assert_eq!(times("0:0.3:0.1"), [0.0, 0.1, 0.2, 0.3]);
        assert_eq!(times("0:0.35:0.1"), [0.0, 0.1, 0.2, 0.3]);
        assert_eq!(times("-1:1:0.75"), [-1.0, -0.25, 0.5]);
        assert_eq!(times("2:2:1"), [2.0]);
        let third = 1.0_f64 / 3.0;
        assert_eq!(times(&format!("0:1:{third:?}"))[2], 2.0 * third);
    }

    #[test]
    fn folder_names_sort_in_time_order() {
        let t: Times = "0:1:0.1".parse().unwrap();
        let names: Vec<String> = (0..t.len()).map(|i| t.folder_name(i)).collect();
        assert_eq!(names[0], "0000-t0.0");
        assert_eq!(names[10], "0010-t1.0");
        let mut sorted = names.clone();
        sorted.sort();
        assert_eq!(sorted, names);
    }

    #[test]
    fn bad_ranges_say_why() {
        for (text, said) in [
            ("0:1:0", "STEP must be positive"),
            ("0:1:-1", "STEP must be positive"),
            ("1:0:0.1", "STOP is before START"),
            ("0:1:1e-5", "more than 10000 times"),
            ("0:x:1", "'x' is not a finite number"),
            ("0:1", "expected START:STOP:STEP"),
            ("0:inf:1", "'inf' is not a finite number"),
        ] {
            let error = text.parse::<Times>().unwrap_err();
            assert!(error.message.contains(said), "{text}: {error}");
        }
    }
}
