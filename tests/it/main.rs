//! raycast's integration tests, in one test binary: one link step instead of one per file
//! (`cargo test --test it`, or `cargo test --test it cli::` for one file's tests). Each module
//! is one file of tests; `common` holds what they share (fixture paths, the built binary,
//! temporary folders).

mod common;

mod accel_agreement;
mod check;
mod check_rules;
mod cli;
mod cli_cameras;
mod cli_check;
mod cli_check_scale;
mod cli_distance;
mod cli_hits;
mod cli_messages;
mod cli_output;
mod cli_sequence;
mod cli_views;
mod error_bounds;
mod exact_geometry;
mod gltf_compressed;
mod gltf_pose;
mod gltf_pose_cases;
mod import_gltf;
mod mesh_formats;
mod nearest_quadrics;
mod octree;
mod quadrics;
mod query;
mod readers;
mod stiff;
mod usd;
mod usd_pose;
mod watertight;
