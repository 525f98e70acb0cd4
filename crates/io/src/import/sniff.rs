//! Checks that a scene file's content is the format its name says, from its first bytes, so
//! that a GLB named `.obj` is reported as what it is instead of failing deep in a reader.

use crate::error::{Error, Result};
use std::io::Read;
use std::path::Path;

/// A format recognised by its leading bytes, with the extensions that may hold it.
struct Magic {
    prefix: &'static [u8],
    what: &'static str,
    extensions: &'static [&'static str],
}

/// Formats with an unambiguous signature. A `.gltf` may hold a GLB and a `.usd` either USD
/// encoding, as their readers accept. Text that starts with `solid` is an STL file, ASCII or
/// binary (binary exporters often begin their header with the word).
const MAGICS: [Magic; 7] = [
    Magic {
        prefix: b"glTF",
        what: "a binary glTF (GLB)",
        extensions: &["glb", "gltf"],
    },
    Magic {
        prefix: b"PXR-USDC",
        what: "a binary USD layer (usdc)",
        extensions: &["usdc", "usd"],
    },
    Magic {
        prefix: b"#usda",
        what: "a text USD layer (usda)",
        extensions: &["usda", "usd"],
    },
    Magic {
        prefix: b"PK\x03\x04",
        what: "a zip archive (usdz)",
        extensions: &["usdz"],
    },
    Magic {
        prefix: b"ply\n",
        what: "a PLY mesh (ply)",
        extensions: &["ply"],
    },
    Magic {
        prefix: b"ply\r\n",
        what: "a PLY mesh (ply)",
        extensions: &["ply"],
    },
    Magic {
        prefix: b"solid",
        what: "an STL mesh (stl)",
        extensions: &["stl"],
    },
];

/// Refuses a folder given as a scene, and a file whose leading bytes show another format than
/// its extension `extension` (lower case), naming what the content is.
pub fn check_content(path: &Path, extension: &str) -> Result<()> {
    if path.is_dir() {
        return Err(Error::in_file(
            path,
            "is a folder, not a scene file (raycast check searches folders)",
        ));
    }
    if path.metadata().is_ok_and(|m| !m.is_file()) {
        return Err(Error::in_file(
            path,
            "is not a regular file (a pipe or a device): give the path of a scene file",
        ));
    }
    let mut head = [0u8; 8];
    // A file that cannot be read is left to the importer, which says why.
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut head))
        .unwrap_or(0);
    check_head(path, &head[..n], extension)
}

/// Refuses content whose leading bytes `head` show another format than the extension
/// `extension` (lower case) of `path`, naming what the content is. A `.stl` file is not
/// judged by its first bytes: a binary STL's header is free text, which may begin with any
/// of the signatures (`glTF` in a converter's name, say); its reader tells what it is not.
pub fn check_head(path: &Path, head: &[u8], extension: &str) -> Result<()> {
    if extension == "stl" {
        return Ok(());
    }
    match MAGICS.iter().find(|m| head.starts_with(m.prefix)) {
        Some(m) if !m.extensions.contains(&extension) => Err(Error::in_file(
            path,
            format!(
                "the content is {}, not what the .{extension} name says; rename it to .{}",
                m.what, m.extensions[0]
            ),
        )),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_glb_named_obj_is_named_for_what_it_is() {
        let dir = std::env::temp_dir().join(format!("raycast-sniff-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("model.obj");
        std::fs::write(&file, b"glTF\x02\x00\x00\x00rest").unwrap();
        let e = check_content(&file, "obj").unwrap_err();
        assert!(e.message.contains("binary glTF (GLB)"), "{e}");
        assert!(e.message.contains("rename it to .glb"), "{e}");
        assert!(check_content(&file, "glb").is_ok());
        assert!(check_content(&dir, "obj")
            .unwrap_err()
            .message
            .contains("is a folder"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn ply_and_stl_content_is_named_and_stl_headers_are_free_text() {
        let e = check_head(Path::new("scan.obj"), b"ply\r\nformat", "obj").unwrap_err();
        assert!(e.message.contains("a PLY mesh (ply)"), "{e}");
        let e = check_head(Path::new("part.ply"), b"solid part", "ply").unwrap_err();
        assert!(e.message.contains("rename it to .stl"), "{e}");
        assert!(check_head(Path::new("scan.ply"), b"ply\n", "ply").is_ok());
        assert!(check_head(Path::new("x.stl"), b"glTF converter", "stl").is_ok());
    }
}
