//! Many views in one run (`--views FILE`, see [`crate::camera::views`]): the scene is read and
//! its acceleration structure built once, then each view is traced and written into its own
//! folder under the output folder, `NNNN` or `NNNN-NAME` (the view's index, four digits, and
//! its name: a nerfstudio frame's image stem). Each folder holds what a single run with that
//! view's `--K`, `--cam-to-world`, `--width` and `--height` writes (the same buffers, bit for
//! bit; the sidecar's timings differ, its load and build times being the shared ones), with
//! the same ownership rules ([`crate::output::ownership`]); all are claimed before the scene
//! is read.

use super::stages::{self, Target};
use super::{check_request, into_job_folder, Progress, RenderJob};
use crate::camera::views::View;
use crate::error::{Error, Result};
use crate::output::sidecar::Sidecar;
use crate::output::{ownership, Layout};
use std::path::PathBuf;

/// Most characters of a view's name kept in its folder's name.
const MAX_NAME: usize = 64;

/// What a run of many views did.
#[derive(Debug)]
pub struct Outcome {
    /// Each view's sidecar, in order.
    pub sidecars: Vec<Sidecar>,
    /// Each view's folder.
    pub folders: Vec<PathBuf>,
    /// Seconds taken to read the scene, once.
    pub load: f64,
    /// Seconds taken to build the acceleration structure, once.
    pub build: f64,
}

/// The folder name of view `index`: `NNNN`, or `NNNN-NAME` with the name's characters other
/// than letters, digits, `.`, `_` and `-` written as `_`.
pub fn folder_name(index: usize, view: &View) -> String {
    match &view.name {
        Some(name) if !name.is_empty() => {
            let name: String = name
                .chars()
                .take(MAX_NAME)
                .map(|c| match c {
                    'a'..='z' | 'A'..='Z' | '0'..='9' | '.' | '_' | '-' => c,
                    _ => '_',
                })
                .collect();
            format!("{index:04}-{name}")
        }
        _ => format!("{index:04}"),
    }
}

/// The single-view job of `view`, written into `folder`.
pub fn view_job(job: &RenderJob, view: &View, folder: PathBuf) -> RenderJob {
    let mut one = job.clone();
    one.camera.intrinsics = Some(view.pinhole.k);
    one.camera.to_world = Some(view.to_world);
    one.width = Some(view.pinhole.width);
    one.height = Some(view.pinhole.height);
    one.out = Some(folder);
    one
}

/// Renders `job` from each of `views`, one folder each; `progress` is told which view (its
/// index) a render's progress is of. A view that fails ends the run (the folders of the
/// views before it stay written).
pub fn run(
    job: &RenderJob,
    views: &[View],
    mut progress: impl FnMut(usize, Progress) + Send,
) -> Result<Outcome> {
    if job.rays.is_some() {
        return Err(Error::usage(
            "--views renders cameras; it cannot be given with --rays",
        ));
    }
    let formats = check_request(job)?;
    let out = job.out_dir();
    let jobs: Vec<RenderJob> = views
        .iter()
        .enumerate()
        .map(|(i, v)| view_job(job, v, out.join(folder_name(i, v))))
        .collect();
    let names = job.file_names(&formats);
    ownership::claim(&out, &job.scene, &[])?;
    for one in &jobs {
        ownership::refuse_inputs(&one.out_dir(), &names, &[job.scene.as_path()])?;
        ownership::claim(&one.out_dir(), &job.scene, &names)?;
    }
    let loaded = stages::load(job, None)?;
    let targets = jobs
        .iter()
        .enumerate()
        .map(|(i, one)| stages::target(one, &loaded).map_err(|e| at_view(e, i, &views[i])))
        .collect::<Result<Vec<Target>>>()?;
    let largest = targets
        .iter()
        .map(|t| t.layout)
        .max_by_key(|l| l.rays())
        .unwrap_or(Layout::Rays(0));
    stages::check_memory_for(job, &formats, largest, &loaded.scene)?;
    let built = stages::build(job, &loaded.scene);
    let mut sidecars = Vec::with_capacity(jobs.len());
    for (i, (one, target)) in jobs.iter().zip(&targets).enumerate() {
        let sidecar = into_job_folder(one, &formats, || {
            stages::trace_and_write(one, &formats, &loaded, &built, target, |e| progress(i, e))
        })
        .map_err(|e| at_view(e, i, &views[i]))?;
        sidecars.push(sidecar);
    }
    Ok(Outcome {
        sidecars,
        folders: jobs.iter().map(RenderJob::out_dir).collect(),
        load: loaded.seconds,
        build: built.seconds,
    })
}

/// `error` saying which view it happened at.
fn at_view(mut error: Error, index: usize, view: &View) -> Error {
    let name = view
        .name
        .as_ref()
        .map(|n| format!(" '{n}'"))
        .unwrap_or_default();
    error.message = format!("{} (at view {index}{name})", error.message);
    error
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Pinhole;
    use glam::DMat4;

    fn view(name: Option<&str>) -> View {
        View {
            name: name.map(String::from),
            pinhole: Pinhole::from_focal([1.0, 1.0, 0.5, 0.5], 1, 1).unwrap(),
            to_world: DMat4::IDENTITY,
        }
    }

    #[test]
    fn folder_names_keep_the_index_first_and_plain_characters() {
        assert_eq!(folder_name(3, &view(None)), "0003");
        assert_eq!(folder_name(12, &view(Some("r_12"))), "0012-r_12");
        assert_eq!(folder_name(0, &view(Some("a b/c"))), "0000-a_b_c");
        assert_eq!(folder_name(0, &view(Some(""))), "0000");
        let long = "x".repeat(100);
        assert_eq!(folder_name(1, &view(Some(&long))).len(), 5 + MAX_NAME);
    }
}
