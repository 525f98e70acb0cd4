//! The stiff and extreme cases of fixtures/stiff/cases.json: expected values computed offline
//! in mpmath at 200 bits (`raycast_tools stiff-cases`), each with its own error bound and ambiguous
//! band (derivations in fixtures/stiff/README.md). No output may be NaN; bad data must be
//! refused.
//!
//! Set `RAYCAST_STIFF_REPORT=FILE` to also write a Markdown table of every case's measured
//! error against its bound.

use crate::common;
use common::fixture;
use glam::{DMat4, DVec3};
use raycast::quadric::{Quadric, QuadricSpec};
use serde_json::Value;
use std::fmt::Write;

fn vec3(v: &Value) -> DVec3 {
    DVec3::new(
        v[0].as_f64().unwrap(),
        v[1].as_f64().unwrap(),
        v[2].as_f64().unwrap(),
    )
}

fn numbers<const N: usize>(v: &Value) -> [f64; N] {
    std::array::from_fn(|i| v[i].as_f64().unwrap())
}

fn spec(case: &Value) -> raycast::Result<QuadricSpec> {
    let bounds = case["bounds"]
        .as_array()
        .map(|b| [vec3(&b[0]), vec3(&b[1])]);
    let q = &case["quadric"];
    match q.get("coefficients") {
        Some(c) => QuadricSpec::from_coefficients(numbers::<10>(c), bounds),
        None => QuadricSpec::from_matrices(
            numbers::<9>(&q["Q"]),
            numbers::<3>(&q["P"]),
            q["R"].as_f64().unwrap(),
            bounds,
        ),
    }
}

/// What raycast computed for one case.
struct Outcome {
    depth: Option<f64>,
    normal: Option<DVec3>,
}

fn angle(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// Checks one case; returns a report row (name, family, expected, measured error, bound, verdict).
fn check(case: &Value, depths: &std::collections::HashMap<String, f64>) -> (String, Option<f64>) {
    let name = case["name"].as_str().unwrap();
    let expected = &case["expected"];
    let spec = spec(case);
    if expected["error"].as_bool().unwrap() {
        let refused = match expected["error_stage"].as_str().unwrap() {
            "spec" => spec.is_err(),
            _ => spec
                .and_then(|s| {
                    Quadric::new(&s, DMat4::from_cols_array(&numbers::<16>(&case["world"])))
                })
                .is_err(),
        };
        assert!(refused, "{name}: bad data must be refused");
        return ("refused, as expected".into(), None);
    }
    let spec = spec.unwrap_or_else(|e| panic!("{name}: {e}"));
    let world = DMat4::from_cols_array(&numbers::<16>(&case["world"]));
    let quadric = Quadric::new(&spec, world).unwrap_or_else(|e| panic!("{name}: {e}"));
    let (origin, dir) = (vec3(&case["origin"]), vec3(&case["dir"]));
    let outcome = match quadric.intersect(origin, dir, f64::INFINITY) {
        None => Outcome {
            depth: None,
            normal: None,
        },
        Some(t) => {
            let n = quadric.normal(origin, dir, t);
            assert!(t > 0.0 && t.is_finite(), "{name}: t = {t}");
            assert!(
                n.is_finite() && (n.length() - 1.0).abs() < 1e-12,
                "{name}: normal {n:?}"
            );
            Outcome {
                depth: Some(t * dir.length()),
                normal: Some(n),
            }
        }
    };
    let ambiguous = case["ambiguous"].as_bool().unwrap();
    let want_hit = expected["hit"].as_bool();
    match (outcome.depth, ambiguous) {
        (None, true) => return ("miss (ambiguous: either accepted)".into(), None),
        (None, false) => {
            assert_eq!(want_hit, Some(false), "{name}: missed an expected hit");
            return ("miss, as expected".into(), None);
        }
        (Some(_), false) => assert_eq!(
            want_hit,
            Some(true),
            "{name}: hit where a miss was expected"
        ),
        (Some(_), true) if case["ambiguous_kind"] == "on_surface" => {
            return (
                "hit on a surface containing the ray (accepted)".into(),
                None,
            )
        }
        (Some(_), true) => {}
    }
    let depth = outcome.depth.unwrap();
    let want = expected["depth"]
        .as_f64()
        .unwrap_or_else(|| panic!("{name}: hit without expected depth"));
    let error = (depth - want).abs() / want;
    let bound = case["rel_depth_bound"].as_f64().unwrap();
    assert!(
        error <= bound,
        "{name}: relative depth error {error:e} > bound {bound:e} ({depth} vs {want})"
    );
    if let (Some(n), Some(bound)) = (outcome.normal, case["normal_bound_rad"].as_f64()) {
        let a = angle(n, vec3(&expected["normal"]));
        assert!(a <= bound, "{name}: normal off by {a:e} rad > {bound:e}");
    }
    if let (Some(base), Some(ratio)) =
        (case["same_depth_as"].as_str(), case["depth_ratio"].as_f64())
    {
        let base_depth = depths[base];
        let scaled_error = (depth - ratio * base_depth).abs() / depth;
        assert!(
            scaled_error <= bound,
            "{name}: depth does not scale with the scene ({scaled_error:e})"
        );
    }
    (format!("{depth:.17e}"), Some(error))
}

#[test]
fn stiff_cases_meet_their_bounds() {
    let text = std::fs::read_to_string(fixture("stiff/cases.json")).unwrap();
    let cases: Vec<Value> = serde_json::from_str(&text).unwrap();
    assert!(cases.len() >= 60, "{} cases", cases.len());
    let mut depths = std::collections::HashMap::new();
    let mut table = String::from("| case | family | result | relative depth error | bound |\n| --- | --- | --- | --- | --- |\n");
    for case in &cases {
        let (result, error) = check(case, &depths);
        let name = case["name"].as_str().unwrap();
        if let Ok(depth) = result.parse::<f64>() {
            depths.insert(name.to_string(), depth);
        }
        let bound = case["rel_depth_bound"]
            .as_f64()
            .map_or("-".into(), |b| format!("{b:.0e}"));
        let error = error.map_or("-".into(), |e| format!("{e:.1e}"));
        let _ = writeln!(
            table,
            "| {name} | {} | {result} | {error} | {bound} |",
            case["family"].as_str().unwrap()
        );
    }
    if let Ok(path) = std::env::var("RAYCAST_STIFF_REPORT") {
        std::fs::write(&path, table).unwrap();
    }
}
