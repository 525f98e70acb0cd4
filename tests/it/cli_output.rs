//! What a render writes, and what it refuses before doing any work: memory, formats, the
//! output folder, interrupted and repeated runs.

use crate::common;
use common::*;

/// The partial files (`.NAME.partial-PID`) left in `dir`.
fn partial_files(dir: &std::path::Path) -> Vec<String> {
    file_names(dir)
        .into_iter()
        .filter(|n| n.contains(".partial-"))
        .collect()
}

#[test]
fn buffers_beyond_max_memory_are_refused_before_allocating() {
    let out = temp_dir("memory");
    let cube = fixture("gltf/cube.gltf");
    let result = raycast(&[
        arg(&cube),
        "--width",
        "24000",
        "--height",
        "24000",
        "--aov",
        "depth,normal,position,id",
        "--max-memory",
        "1G",
        "--threads",
        "1",
        "--out",
        arg(&out),
    ]);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "{stderr}");
    // 576e6 pixels × (60 buffers + 2 × 12 for the normal's EXR, one file encoded at a time
    // with one thread) bytes = 45.1 GiB (no array of hits: each ray's buffers are filled as
    // its hit is found).
    assert!(stderr.contains("need about 45.1 GiB"), "{stderr}");
    assert!(stderr.contains("--max-memory"), "{stderr}");
    assert!(file_names(&out).is_empty(), "{:?}", file_names(&out));
}

/// The acceleration structure counts too: the bunny's 69,451 primitives at 128 bytes each
/// (8.5 MiB) do not fit in 4 MiB though its 8×8 depth buffers do (the estimate used to count
/// the buffers only, and the run went ahead).
#[test]
fn the_octree_counts_in_the_memory_estimate() {
    let out = temp_dir("memory-octree");
    let bunny = fixture("assets/stanford-bunny.obj");
    let args = [
        arg(&bunny),
        "--width",
        "8",
        "--height",
        "8",
        "--out",
        arg(&out),
    ];
    let result = raycast(&[&args[..], &["--max-memory", "4M"]].concat());
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("the octree over 69451 primitives need about 8.5 MiB"),
        "{stderr}"
    );
    assert!(!out.exists());
    raycast_ok(&[&args[..], &["--max-memory", "40M"]].concat());
}

/// An accessor without a buffer view is zeros of any length: a file of a few hundred bytes
/// can ask for gigabytes. Each of these three asks for 6 million values, charged 24 bytes
/// each (144 MB): under a limit of 200 MB the first is read and the second refused, naming
/// it and the flag, before the scene is built. (Render used to allocate them all.)
#[test]
fn accessors_without_buffer_views_are_capped_by_the_memory_limit() {
    let accessor = r#"{"componentType": 5126, "count": 2000000, "type": "VEC3",
        "min": [0, 0, 0], "max": [0, 0, 0]}"#;
    let gltf = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0, 1, 2]}}],
        "nodes": [{{"mesh": 0}}, {{"mesh": 1}}, {{"mesh": 2}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}},
                   {{"primitives": [{{"attributes": {{"POSITION": 1}}}}]}},
                   {{"primitives": [{{"attributes": {{"POSITION": 2}}}}]}}],
        "accessors": [{accessor}, {accessor}, {accessor}]}}"#
    );
    let scene = temp_file("unbacked", "zeros.gltf", gltf);
    let out = temp_dir("unbacked-out");
    let result = raycast(&[arg(&scene), "--max-memory", "200M", "--out", arg(&out)]);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("zeros.gltf"), "{stderr}");
    assert!(
        stderr.contains("accessor 1 has no buffer view: its 2000000 elements"),
        "{stderr}"
    );
    assert!(stderr.contains("--max-memory"), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(!out.exists());
}

#[test]
fn repeated_formats_merge_and_leave_no_partial_files() {
    let out = temp_dir("png-png");
    let cube = fixture("gltf/cube.gltf");
    raycast_ok(&[
        arg(&cube),
        "--aov",
        "depth,id",
        "--format",
        "png,png",
        "--width",
        "16",
        "--out",
        arg(&out),
        "--quiet",
    ]);
    assert_eq!(file_names(&out), ["depth.png", "id.png", "raycast.json"]);
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("raycast.json")).unwrap()).unwrap();
    assert_eq!(
        json["files"],
        serde_json::json!(["depth.png", "id.png", "raycast.json"])
    );
}

/// The default formats write PNG previews only where an AOV asked for has one: `--aov
/// error,certain` alone writes EXR files, where asking for `png` by name is still refused.
#[test]
fn the_default_formats_leave_out_a_png_with_nothing_to_preview() {
    let out = temp_dir("no-preview");
    let cube = fixture("gltf/cube.gltf");
    let args = [
        arg(&cube),
        "--aov",
        "error,certain",
        "--width",
        "16",
        "--out",
        arg(&out),
    ];
    raycast_ok(&[&args[..], &["--quiet"]].concat());
    assert_eq!(
        file_names(&out),
        ["certain.exr", "error.exr", "raycast.json"]
    );
    let with_depth = [arg(&cube), "--aov", "depth,certain", "--width", "16"];
    let both = temp_dir("preview");
    raycast_ok(&[&with_depth[..], &["--out", arg(&both), "--quiet"]].concat());
    assert_eq!(
        file_names(&both),
        ["certain.exr", "depth.exr", "depth.png", "raycast.json"]
    );
    let named = raycast(&[&args[..], &["--format", "png"]].concat());
    let stderr = String::from_utf8_lossy(&named.stderr);
    assert_eq!(named.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--format png would write no file"),
        "{stderr}"
    );
}

#[test]
fn requests_that_write_no_file_are_usage_errors() {
    let dir = temp_dir("no-file");
    std::fs::create_dir_all(&dir).unwrap();
    let rays = dir.join("rays.npy");
    write_rays(&rays, &[[0.0, 0.0, 5.0, 0.0, 0.0, -1.0]]);
    let cube = fixture("gltf/cube.gltf");
    let out = dir.join("out");
    let cases: [(Vec<&str>, &str); 3] = [
        (vec!["--rays", arg(&rays), "--format", "png"], "png"),
        (vec!["--aov", "position", "--format", "png"], "position"),
        (vec!["--rays", arg(&rays), "--format", "npy,exr"], "exr"),
    ];
    for (extra, named) in cases {
        let mut args = vec![arg(&cube), "--out", arg(&out)];
        args.extend(extra.iter().copied());
        let result = raycast(&args);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{extra:?}: {stderr}");
        assert!(stderr.contains(named), "{extra:?}: {stderr}");
        assert!(!out.exists(), "{extra:?} created the output folder");
    }
}

#[test]
fn a_run_replaces_an_earlier_runs_files_and_nothing_else() {
    let out = temp_dir("reuse");
    let cube = fixture("gltf/cube.gltf");
    raycast_ok(&[arg(&cube), "--width", "16", "--out", arg(&out), "--quiet"]);
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    std::fs::write(out.join("normal.exr"), "not listed by the earlier run").unwrap();
    let rays = out.join("rays.npy");
    write_rays(&rays, &[[0.0, 0.0, 5.0, 0.0, 0.0, -1.0]]);
    raycast_ok(&[
        arg(&cube),
        "--rays",
        arg(&rays),
        "--out",
        arg(&out),
        "--quiet",
    ]);
    assert_eq!(
        file_names(&out),
        [
            "depth.npy",
            "normal.exr",
            "notes.txt",
            "raycast.json",
            "rays.npy"
        ]
    );
}

#[test]
fn output_folder_problems_are_found_before_loading() {
    let dir = temp_dir("out-problems");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("a-file");
    std::fs::write(&file, "x").unwrap();
    // A truncated scene: had it been loaded first, the error would be about the GLB.
    let broken = fixture("bad/truncated.glb");
    let result = raycast(&[arg(&broken), "--out", arg(&file)]);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("a-file: is a file, not a folder"),
        "{stderr}"
    );
    let below = file.join("out");
    let result = raycast(&[arg(&broken), "--out", arg(&below)]);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("a-file/out: cannot create the output folder"),
        "{stderr}"
    );
    assert!(!stderr.contains("partial"), "{stderr}");
}

#[test]
fn invalid_option_values_exit_with_2() {
    let cube = fixture("gltf/cube.gltf");
    for bad in [
        ["--width", "0"],
        ["--height", "0"],
        ["--width", "40000"],
        ["--fov", "0"],
        ["--fov", "180"],
        ["--ortho", "0"],
        ["--ortho", "inf"],
        ["--threads", "0"],
        ["--eye", "nan,0,0"],
    ] {
        let mut args = vec![arg(&cube)];
        args.extend(bad);
        if bad[0] == "--eye" {
            args.extend(["--target", "0,0,0"]);
        }
        let result = raycast(&args);
        assert_eq!(result.status.code(), Some(2), "{bad:?}");
    }
}

/// Starts a large render into `out` and sends it `signal` once its first temporary file
/// exists (or, with `during_trace`, as soon as it runs); returns its exit status and stderr.
fn interrupted_render(out: &std::path::Path, signal: &str, during_trace: bool) -> (i32, String) {
    let cube = fixture("gltf/cube.gltf");
    let child = std::process::Command::new(raycast_bin())
        .args([arg(&cube), "--width", "2000", "--height", "2000"])
        .args(["--aov", "depth,normal,position", "--format", "exr,png,npy"])
        .args(["--out", arg(out), "--quiet"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    let mut sent = false;
    let mut child = child;
    while child.try_wait().unwrap().is_none() && started.elapsed().as_secs() < 120 {
        if (during_trace && out.exists()) || !partial_files(out).is_empty() {
            std::process::Command::new("kill")
                .args([&format!("-{signal}"), &child.id().to_string()])
                .status()
                .unwrap();
            sent = true;
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    let output = child.wait_with_output().unwrap();
    assert!(sent, "the render ended before writing: {:?}", output.status);
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    (output.status.code().unwrap_or(-1), stderr)
}

/// SIGINT, SIGTERM and SIGHUP alike: no temporary file, not even the folder the run created,
/// "interrupted" on stderr, and the exit status a shell gives a process the signal killed.
#[test]
fn signals_remove_partial_files_and_the_created_folder() {
    for (signal, code) in [("INT", 130), ("TERM", 143), ("HUP", 129)] {
        for during_trace in [false, true] {
            let out = temp_dir(&format!("interrupt-{signal}-{during_trace}"));
            let (status, stderr) = interrupted_render(&out, signal, during_trace);
            assert!(!out.exists(), "{signal}: {:?}", file_names(&out));
            assert_eq!(status, code, "{signal}: {stderr}");
            assert_eq!(stderr.trim(), "raycast: interrupted", "{signal}");
        }
    }
}

/// An interrupted run into a folder that already holds outputs leaves them as they were.
#[test]
fn an_interrupted_run_leaves_an_existing_folder_and_its_files() {
    let out = temp_dir("interrupt-existing");
    let cube = fixture("gltf/cube.gltf");
    raycast_ok(&[arg(&cube), "--width", "8", "--out", arg(&out), "--quiet"]);
    let before = std::fs::read(out.join("depth.exr")).unwrap();
    let (status, _) = interrupted_render(&out, "TERM", false);
    assert_eq!(status, 143);
    assert_eq!(file_names(&out), ["depth.exr", "depth.png", "raycast.json"]);
    assert_eq!(std::fs::read(out.join("depth.exr")).unwrap(), before);
}

/// A render of another scene file into a folder that holds a scene's outputs (the default
/// folder is named by the stem: `Box/Box.gltf` and `Box.glb` share `Box.raycast/`) is refused
/// before any work, and removes nothing; so is one that would replace a file no run of its
/// scene wrote. A second run of the same scene still replaces and removes its own outputs.
#[test]
fn outputs_of_another_scene_or_person_are_never_replaced_or_removed() {
    let dir = temp_dir("ownership");
    std::fs::create_dir_all(dir.join("a")).unwrap();
    let first = dir.join("a/cube.gltf");
    let second = dir.join("cube.gltf");
    for folder in [dir.join("a"), dir.clone()] {
        for name in ["cube.gltf", "cube.bin"] {
            std::fs::copy(fixture(&format!("gltf/{name}")), folder.join(name)).unwrap();
        }
    }
    let out = dir.join("cube.raycast");
    let run = |scene: &std::path::Path, aov: &str| {
        raycast(&[
            arg(scene),
            "--aov",
            aov,
            "--width",
            "8",
            "--out",
            arg(&out),
            "--quiet",
        ])
    };
    assert!(run(&first, "depth,normal").status.success());
    let owned = file_names(&out);
    let refused = run(&second, "id");
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("holds the outputs of another scene"),
        "{stderr}"
    );
    assert!(stderr.contains("--out"), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert_eq!(file_names(&out), owned);
    // the same scene by another path (`a/../a/cube.gltf`) is the same file
    let again = dir.join("a/../a/cube.gltf");
    assert!(run(&again, "id").status.success());
    assert_eq!(file_names(&out), ["id.exr", "id.png", "raycast.json"]);
    // a file of a person's in a folder without a sidecar
    let mine = dir.join("mine");
    std::fs::create_dir_all(&mine).unwrap();
    std::fs::write(mine.join("depth.png"), b"my picture").unwrap();
    let refused = raycast(&[arg(&second), "--width", "8", "--out", arg(&mine), "--quiet"]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("already has depth.png"));
    assert_eq!(
        std::fs::read(mine.join("depth.png")).unwrap(),
        b"my picture"
    );
    assert_eq!(file_names(&mine), ["depth.png"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn untraceable_rays_are_misses_counted_in_the_warnings() {
    let dir = temp_dir("nan-rays");
    std::fs::create_dir_all(&dir).unwrap();
    let rays = dir.join("rays.npy");
    write_rays(
        &rays,
        &[
            [0.0, 0.0, 5.0, 0.0, 0.0, -1.0],
            [f64::NAN, 0.0, 5.0, 0.0, 0.0, -1.0],
            [0.0, 0.0, 5.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 5.0, f64::INFINITY, 0.0, -1.0],
        ],
    );
    let out = dir.join("out");
    let depth = cube_depths(&rays, &out);
    assert_eq!(depth, [4.0, f64::INFINITY, f64::INFINITY, f64::INFINITY]);
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("raycast.json")).unwrap()).unwrap();
    let warnings = json["warnings"].to_string();
    assert!(
        warnings.contains("3 rays have a non-finite origin or direction or a zero direction"),
        "{warnings}"
    );
    assert!(
        warnings.contains("first: ray 1: the origin is not finite"),
        "{warnings}"
    );
    let strict = dir.join("strict");
    let cube = fixture("gltf/cube.gltf");
    let result = raycast(&[
        arg(&cube),
        "--rays",
        arg(&rays),
        "--out",
        arg(&strict),
        "--strict-rays",
    ]);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("rays.npy: ray 1: the origin is not finite"),
        "{stderr}"
    );
    assert!(!strict.exists());
}

#[test]
fn fortran_ordered_ray_files_are_read() {
    let dir = temp_dir("fortran-rays");
    std::fs::create_dir_all(&dir).unwrap();
    // What numpy writes for `rays.T` of a C-order (6, 2) array: a (2, 6) array with
    // 'fortran_order': True whose data holds the columns one after another.
    let rows = [
        [0.0f64, 0.0, 5.0, 0.0, 0.0, -1.0],
        [3.0, 0.0, 5.0, 0.0, 0.0, -1.0],
    ];
    let header = "{'descr': '<f8', 'fortran_order': True, 'shape': (2, 6), }";
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    let padded = format!("{header}{}\n", " ".repeat(63 - (10 + header.len()) % 64));
    bytes.extend_from_slice(&(padded.len() as u16).to_le_bytes());
    bytes.extend_from_slice(padded.as_bytes());
    for c in 0..6 {
        for row in &rows {
            bytes.extend_from_slice(&row[c].to_le_bytes());
        }
    }
    let rays = dir.join("rays.npy");
    std::fs::write(&rays, bytes).unwrap();
    let out = dir.join("out");
    assert_eq!(cube_depths(&rays, &out), [4.0, f64::INFINITY]);
}

/// Traces the ray file `rays` against the cube fixture into `out`; the depths it wrote.
fn cube_depths(rays: &std::path::Path, out: &std::path::Path) -> Vec<f64> {
    let cube = fixture("gltf/cube.gltf");
    raycast_ok(&[
        arg(&cube),
        "--rays",
        arg(rays),
        "--out",
        arg(out),
        "--quiet",
    ]);
    read_f64(&out.join("depth.npy")).1
}

/// Distinct grey levels of the depth preview inside the centre square (the near quad).
fn quad_grey_levels(png: &std::path::Path) -> usize {
    let image = image::open(png).unwrap().to_rgb8();
    let mut levels: Vec<u8> = (40..88)
        .flat_map(|y| (40..88).map(move |x| (x, y)))
        .map(|(x, y)| image.get_pixel(x, y).0[0])
        .collect();
    levels.sort_unstable();
    levels.dedup();
    levels.len()
}

#[test]
fn a_far_outlier_does_not_wash_out_the_depth_preview() {
    let dir = temp_dir("depth-preview");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("near-and-far.obj");
    // A 2×2 quad 3 units away fills the centre; a small triangle 1000 units away sits in a
    // corner of the view (a few pixels).
    std::fs::write(
        &scene,
        "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nv 375 375 -1000\nv 410 375 -1000\nv 375 410 -1000\n\
         f 1 2 3\nf 1 3 4\nf 5 6 7\n",
    )
    .unwrap();
    let out = dir.join("out");
    let view = [
        "--eye", "0,0,3", "--target", "0,0,0", "--width", "128", "--height", "128",
    ];
    let mut args = vec![
        arg(&scene),
        "--format",
        "png",
        "--out",
        arg(&out),
        "--quiet",
    ];
    args.extend(view);
    raycast_ok(&args);
    // The hits' depths run from 3 to 3.32 (the quad) and 1003 (a few pixels): with the range
    // from the 1st to 99th percentile the centre of the quad (3 to 3.05) shows some fifty grey
    // levels; mapped from the full range it is one flat white.
    let levels = quad_grey_levels(&out.join("depth.png"));
    assert!(levels >= 40, "the quad shows {levels} grey levels");
    args.extend(["--depth-range", "3,1003"]);
    raycast_ok(&args);
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("raycast.json")).unwrap()).unwrap();
    assert_eq!(json["depth_png_range"], serde_json::json!([3.0, 1003.0]));
    assert!(quad_grey_levels(&out.join("depth.png")) <= 2);
}

/// The library's render reports tracing, then writing, file by file, to its end.
#[test]
fn progress_covers_tracing_and_writing() {
    use raycast::job::{self, Progress, RenderJob};
    let out = temp_dir("progress");
    let job = RenderJob {
        scene: fixture("gltf/cube.gltf"),
        load: Default::default(),
        aovs: vec![raycast::render::Aov::Depth, raycast::render::Aov::Normal],
        camera: Default::default(),
        width: Some(64),
        height: Some(32),
        rays: None,
        out: Some(out.clone()),
        formats: None,
        octree: Default::default(),
        strict_rays: false,
        pngs: Default::default(),
        cryptomatte: None,
        max_memory: None,
        hits: None,
    };
    let mut events = Vec::new();
    let sidecar = job::run(&job, |event| events.push(event)).unwrap();
    let split = events
        .iter()
        .position(|e| matches!(e, Progress::Writing { .. }))
        .expect("no writing reported");
    assert!(events[..split]
        .iter()
        .all(|e| matches!(e, Progress::Tracing { total: 2048, .. })));
    assert_eq!(
        events[split - 1],
        Progress::Tracing {
            done: 2048,
            total: 2048
        }
    );
    // depth.exr, depth.png, normal.exr, normal.png; the sidecar is written after them.
    let writing: Vec<_> = events[split..].to_vec();
    let done: Vec<usize> = writing
        .iter()
        .map(|e| match e {
            Progress::Writing { done, total: 4 } => *done,
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(done, [0, 1, 2, 3, 4]);
    assert_eq!(sidecar.files.len(), 5);
}

/// Without --max-memory a render may take half the physical memory (or what is available,
/// if less): all eight AOVs in all formats at 32768² need about 152 GiB (104 bytes of buffers
/// and twice the largest encoder's 24 per pixel, one thread), refused in one line that names
/// the estimate and the flag, before anything is written. (It used to run for minutes at
/// 15.8 of 24 GB: the default was all the available memory.)
#[test]
fn the_default_memory_limit_refuses_a_render_that_would_take_the_machine() {
    let meminfo = std::fs::read_to_string("/proc/meminfo").unwrap_or_default();
    let total_kib: u64 = meminfo
        .lines()
        .find(|l| l.starts_with("MemTotal:"))
        .and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
        .unwrap_or(0);
    if total_kib == 0 || total_kib / 2 > 150 << 20 {
        return; // no /proc/meminfo, or a machine where such a render fits the default
    }
    let out = temp_dir("default-memory");
    let cube = fixture("gltf/cube.gltf");
    let result = raycast(&[
        arg(&cube),
        "--width",
        "32768",
        "--height",
        "32768",
        "--aov",
        "depth,z,t,normal,position,bary,id,prim",
        "--format",
        "exr,png,npy",
        "--threads",
        "1",
        "--out",
        arg(&out),
    ]);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("need about 152.0 GiB"), "{stderr}");
    assert!(stderr.contains("half the physical memory"), "{stderr}");
    assert!(stderr.contains("--max-memory"), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(!out.exists());
}

/// `--depth-scale`: depth.png and z.png hold 16-bit integers of that many scene units (the
/// distance divided by the scale and rounded, within half a step of the float64 buffer), 0
/// for a miss and for a distance past 65535 steps; the sidecar records the scale.
#[test]
fn depth_scale_writes_16_bit_depth() {
    let out = temp_dir("depth-u16");
    let scene = fixture("gltf/plane.gltf");
    let run = |out: &std::path::Path, scale: &str| {
        raycast_ok(&[
            arg(&scene),
            "--eye",
            "0.3,0.2,4",
            "--target",
            "0,0,0",
            "--width",
            "40",
            "--height",
            "30",
            "--aov",
            "depth,z",
            "--format",
            "npy,png",
            "--depth-scale",
            scale,
            "--out",
            arg(out),
            "-q",
        ]);
    };
    run(&out, "0.0001");
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("raycast.json")).unwrap()).unwrap();
    assert_eq!(json["depth_png_scale"], serde_json::json!(0.0001));
    assert!(json.get("depth_png_range").is_none());
    for aov in ["depth", "z"] {
        let (_, values) = read_f64(&out.join(format!("{aov}.npy")));
        let png = image::open(out.join(format!("{aov}.png"))).unwrap();
        let png = png.as_luma16().expect("a 16-bit grey PNG");
        let (mut hits, mut misses) = (0, 0);
        for (v, p) in values.iter().zip(png.pixels()) {
            let step = p.0[0];
            if v.is_finite() {
                hits += 1;
                assert!(
                    (f64::from(step) * 0.0001 - v).abs() <= 0.00005 + 1e-12,
                    "{aov} {v} {step}"
                );
            } else {
                misses += 1;
                assert_eq!(step, 0);
            }
        }
        assert!(hits > 100 && misses > 100, "{hits} {misses}");
    }
    // At 1e-5 units per step every hit (about 4 units away) is past 65535 steps: no data.
    let far = temp_dir("depth-u16-far");
    run(&far, "0.00001");
    let png = image::open(far.join("depth.png")).unwrap();
    assert!(png.as_luma16().unwrap().pixels().all(|p| p.0[0] == 0));
}

/// `--format ply`: position.ply holds one vertex per hit, in ray order, with the position,
/// normal, id and prim buffers' values exactly (read back from the binary records here) and
/// the ray's index; without `position` asked the format is a usage error.
#[test]
fn point_clouds_hold_the_hits() {
    let out = temp_dir("points");
    let scene = fixture("gltf/cube.gltf");
    let args = [
        arg(&scene),
        "--width",
        "24",
        "--height",
        "18",
        "--aov",
        "position,normal,id,prim",
        "--format",
        "ply,npy",
        "--out",
        arg(&out),
        "-q",
    ];
    raycast_ok(&args);
    let bytes = std::fs::read(out.join("position.ply")).unwrap();
    let end = b"end_header\n";
    let split = bytes.windows(end.len()).position(|w| w == end).unwrap() + end.len();
    let header = String::from_utf8(bytes[..split].to_vec()).unwrap();
    let (_, positions) = read_f64(&out.join("position.npy"));
    let (_, normals) = read_f64(&out.join("normal.npy"));
    let (_, ids) = read_u32(&out.join("id.npy"));
    let (_, prims) = read_u32(&out.join("prim.npy"));
    let hits: Vec<usize> = (0..ids.len()).filter(|&i| ids[i] != 0).collect();
    assert!(
        header.contains(&format!("element vertex {}\n", hits.len())),
        "{header}"
    );
    assert!(header.contains("property double nx\n") && header.contains("property uint ray\n"));
    let record = 6 * 8 + 3 * 4;
    let body = &bytes[split..];
    assert_eq!(body.len(), hits.len() * record);
    let f64_at = |r: &[u8], k: usize| f64::from_le_bytes(r[8 * k..8 * k + 8].try_into().unwrap());
    let u32_at =
        |r: &[u8], k: usize| u32::from_le_bytes(r[48 + 4 * k..52 + 4 * k].try_into().unwrap());
    for (r, &i) in body.chunks_exact(record).zip(&hits) {
        for c in 0..3 {
            assert_eq!(f64_at(r, c).to_bits(), positions[3 * i + c].to_bits());
            assert_eq!(f64_at(r, 3 + c).to_bits(), normals[3 * i + c].to_bits());
        }
        assert_eq!(
            [u32_at(r, 0), u32_at(r, 1), u32_at(r, 2)],
            [ids[i], prims[i], i as u32]
        );
    }
    assert!(hits.len() > 50 && hits.len() < ids.len());
    let refused = raycast(&[
        arg(&scene),
        "--aov",
        "depth",
        "--format",
        "ply",
        "--out",
        arg(&out),
    ]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("add position to --aov"));
}
