//! OBJ: a line scanner that reports every bad line (numbers, non-finite vertices, face
//! indices out of range, short faces, material libraries outside the asset), before `tobj`
//! loads the file.

use super::{resolve_inside, CheckOptions, Findings};
use crate::Code;
use std::path::Path;

/// Checks an OBJ file held in `bytes`; returns whether the importer may run.
pub fn check(
    path: &Path,
    root: &Path,
    bytes: &[u8],
    options: &CheckOptions,
    f: &mut Findings,
) -> bool {
    let text = match crate::import::obj::text(bytes) {
        Ok(text) => text,
        Err(line) => {
            f.error(
                Code::ObjNotText,
                format!("line {line}"),
                "the file is not UTF-8 text",
            );
            return false;
        }
    };
    if let Err(why) = crate::import::obj::check_statements(text) {
        f.error(Code::ObjNoStatement, "", why.to_string());
        return false;
    }
    let base = path.parent().unwrap_or(Path::new("."));
    let mut vertices = 0usize;
    let mut faces = 0usize;
    // The text as the importer reads it: continuations joined, empty and unknown statements
    // blanked (the importer's warnings about them come back as notes), lines at their numbers.
    let normal = crate::import::obj_text::normalise(text);
    for (n, raw) in normal.text.lines().enumerate() {
        let at = format!("line {}", n + 1);
        let line = raw.split('#').next().unwrap_or("").trim();
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        let args: Vec<&str> = words.collect();
        match keyword {
            "v" => {
                vertices += 1;
                if args.len() < 3 {
                    f.error(Code::ObjParseError, at, "a vertex needs x y z");
                    continue;
                }
                match args
                    .iter()
                    .take(3)
                    .map(|a| a.parse::<f64>())
                    .collect::<Result<Vec<f64>, _>>()
                {
                    Err(_) => f.error(Code::ObjParseError, at, format!("bad vertex '{line}'")),
                    Ok(v) if v.iter().any(|x| !x.is_finite()) => {
                        f.error(Code::NonFinitePosition, at, "the vertex is NaN or infinite")
                    }
                    Ok(_) => {}
                }
            }
            "f" => {
                faces += 1;
                if args.len() < 3 {
                    f.warn(
                        Code::DegenerateFace,
                        at.clone(),
                        format!("a face with {} vertices", args.len()),
                    );
                }
                for corner in &args {
                    let first = corner.split('/').next().unwrap_or("");
                    match first.parse::<i64>() {
                        Err(_) => {
                            f.error(
                                Code::ObjParseError,
                                at.clone(),
                                format!("bad face index '{corner}'"),
                            );
                            break;
                        }
                        Ok(i) => {
                            let resolved = if i < 0 { vertices as i64 + i } else { i - 1 };
                            if i == 0 || resolved < 0 || resolved >= vertices as i64 {
                                f.error(
                                    Code::IndexOob,
                                    at.clone(),
                                    format!(
                                        "face index {i} with {vertices} vertices defined so far"
                                    ),
                                );
                                break;
                            }
                        }
                    }
                }
            }
            "mtllib" => {
                for name in &args {
                    match resolve_inside(base, root, name, options.allow_outside) {
                        Err(why) => f.error(Code::PathOutsideAsset, at.clone(), why.to_string()),
                        Ok(p) if !p.is_file() => f.warn(
                            Code::MissingReference,
                            at.clone(),
                            format!("material library '{name}' cannot be found (materials are not read)"),
                        ),
                        Ok(_) => {}
                    }
                }
            }
            _ => {}
        }
    }
    if faces == 0 && vertices == 0 && !text.trim().is_empty() && !f.has_errors() {
        f.warn(
            Code::ObjNoData,
            "",
            "no vertex or face lines: is this an OBJ file?",
        );
    }
    true
}
