use super::*;
use glam::DVec3;

const FACET: &str = "facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  \
                     vertex 0 1 0\n endloop\nendfacet\n";

fn binary(header: &[u8], triangles: &[[[f32; 3]; 3]], count: u32) -> Vec<u8> {
    let mut bytes = header.to_vec();
    bytes.resize(80, b' ');
    bytes.extend_from_slice(&count.to_le_bytes());
    for t in triangles {
        bytes.extend_from_slice(&[0; 12]);
        t.iter()
            .flatten()
            .for_each(|c| bytes.extend_from_slice(&c.to_le_bytes()));
        bytes.extend_from_slice(&[0, 0]);
    }
    bytes
}

const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.5]];

#[test]
fn a_binary_file_that_begins_with_solid_is_binary() {
    let bytes = binary(b"solid exported by a CAD tool", &[TRI, TRI], 2);
    let mesh = read(&bytes).unwrap();
    assert_eq!(mesh.solids.len(), 1);
    assert_eq!(mesh.solids[0].mesh.len(), 2);
    assert_eq!(mesh.solids[0].mesh.positions().len(), 3);
    assert_eq!(
        mesh.solids[0].mesh.triangle(1)[2],
        DVec3::new(0.0, 1.0, 0.5)
    );
}

#[test]
fn a_truncated_binary_file_and_trailing_bytes() {
    let mut bytes = binary(b"", &[TRI], 3);
    let e = read(&bytes).unwrap_err();
    assert_eq!(e.code(), Code::StlTruncated);
    assert_eq!(
        e.to_string(),
        "truncated: the binary header counts 3 triangles, 234 bytes, but the file has 134"
    );
    bytes[80] = 1;
    bytes.extend_from_slice(b"xyz");
    let mesh = read(&bytes).unwrap();
    assert_eq!(
        mesh.warnings,
        ["3 bytes after the last of the header's 1 triangles ignored"]
    );
    let nan = binary(b"", &[[[f32::NAN, 0.0, 0.0], TRI[1], TRI[2]]], 1);
    assert_eq!(read(&nan).unwrap_err().code(), Code::NonFinitePosition);
    assert_eq!(read(b"tiny").unwrap_err().code(), Code::StlNotStl);
}

#[test]
fn each_ascii_solid_is_an_object_and_keywords_ignore_case() {
    let text = format!(
        "solid first part\n{FACET}{FACET}endsolid first part\n\n\
         SOLID\n{}ENDSOLID\nsolid empty\nendsolid\n",
        FACET.to_uppercase()
    );
    let mesh = read(text.as_bytes()).unwrap();
    let solids: Vec<(&str, usize)> = mesh
        .solids
        .iter()
        .map(|s| (s.name.as_str(), s.mesh.len()))
        .collect();
    assert_eq!(solids, [("first part", 2), ("", 1)]);
    let scene = scene(mesh, Path::new("parts.stl"));
    let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["first part", "parts"]);
}

#[test]
fn broken_ascii_files_name_the_solid() {
    let cut = format!("solid a\n{FACET}");
    let e = read(cut.as_bytes()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "truncated: the solid of line 1 has no 'endsolid' line"
    );
    let bad = format!(
        "solid a\nendsolid\nsolid b\n{}endsolid\n",
        FACET.replace("1 0 0", "1 x 0")
    );
    let e = read(bad.as_bytes()).unwrap_err();
    assert_eq!(e.code(), Code::StlParseError);
    assert!(e.to_string().starts_with("the solid of line 3: "), "{e}");
    let stray = format!("solid a\n{FACET}endsolid\nfacet\n");
    assert_eq!(
        read(stray.as_bytes()).unwrap_err(),
        StlError::Stray { line: 10 }
    );
}
