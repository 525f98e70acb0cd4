use super::*;

fn header(format: &str, vertices: u64, faces: u64, index: &str) -> Vec<u8> {
    format!(
        "ply\nformat {format} 1.0\nelement vertex {vertices}\nproperty float x\n\
         property float y\nproperty float z\nproperty uchar red\nelement face {faces}\n\
         property list uchar {index} vertex_indices\nproperty int flags\nend_header\n"
    )
    .into_bytes()
}

const SQUARE: [[f32; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
];

#[test]
fn an_ascii_quad_fans_from_its_first_corner() {
    let mut bytes = header("ascii", 4, 2, "int");
    bytes.extend_from_slice(b"0 0 0 9\n1 0 0 9\n1 1 0 9\n0 1 0 9\n4 0 1 2 3 7\n2 0 1 7\n");
    let mesh = read(&bytes).unwrap();
    assert_eq!(mesh.triangles, [[0, 1, 2], [0, 2, 3]]);
    assert_eq!(mesh.positions.len(), 4);
    assert_eq!(mesh.warnings, ["1 faces with fewer than 3 corners skipped"]);
}

#[test]
fn binary_bodies_in_both_byte_orders_read_the_same() {
    for (format, big) in [("binary_little_endian", false), ("binary_big_endian", true)] {
        let mut bytes = header(format, 4, 1, "uint");
        let f = |v: f32| {
            if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            }
        };
        let u = |v: u32| {
            if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            }
        };
        for p in SQUARE {
            p.iter().for_each(|&c| bytes.extend_from_slice(&f(c)));
            bytes.push(200);
        }
        bytes.push(4);
        [3, 2, 1, 0]
            .iter()
            .for_each(|&i| bytes.extend_from_slice(&u(i)));
        bytes.extend_from_slice(&u(0));
        let mesh = read(&bytes).unwrap();
        assert_eq!(mesh.triangles, [[3, 2, 1], [3, 1, 0]], "{format}");
        assert_eq!(mesh.positions[2], DVec3::new(1.0, 1.0, 0.0), "{format}");
        assert!(mesh.warnings.is_empty(), "{format}: {:?}", mesh.warnings);
    }
}

#[test]
fn a_header_that_claims_more_than_the_file_holds_is_refused_before_reading() {
    let mut bytes = header("binary_little_endian", 1_000_000_000, 1, "int");
    bytes.extend_from_slice(&[0; 1024]);
    let e = read(&bytes).unwrap_err();
    assert_eq!(e.code(), Code::PlyTruncated);
    assert_eq!(
        e.to_string(),
        "truncated: the header declares 1000000000 'vertex' records, at least 13000000000 \
         bytes, but 1024 bytes are left in the file"
    );
    // A list count past the end of the body.
    let mut bytes = header("binary_little_endian", 0, 1, "int");
    bytes.extend_from_slice(&[255, 0, 0, 0, 0, 0, 0, 0, 0]);
    let e = read(&bytes).unwrap_err();
    assert_eq!(
        e.to_string(),
        "truncated: the file ends in 'face' record 0 of 1"
    );
}

#[test]
fn indices_out_of_range_and_bad_values_are_named() {
    let mut bytes = header("ascii", 3, 1, "int");
    bytes.extend_from_slice(b"0 0 0 1\n1 0 0 1\n0 1 0 1\n3 0 1 3 0\n");
    let e = read(&bytes).unwrap_err();
    assert_eq!(e.code(), Code::IndexOob);
    assert_eq!(
        e.to_string(),
        "face 0 refers to vertex 3, but the file has 3 vertices (numbered from 0)"
    );
    let mut bytes = header("ascii", 3, 1, "int");
    bytes.extend_from_slice(b"0 0 0 1\n1 zero 0 1\n0 1 0 1\n3 0 1 2 0\n");
    let e = read(&bytes).unwrap_err();
    assert_eq!(e.code(), Code::PlyParseError);
    assert_eq!(e.to_string(), "'vertex' record 1: 'zero' is not a float");
    let mut bytes = header("ascii", 3, 1, "int");
    bytes.extend_from_slice(b"0 0 0 1\nnan 0 0 1\n0 1 0 1\n3 0 1 2 0\n");
    assert_eq!(
        read(&bytes).unwrap_err().to_string(),
        "vertex 1 is not finite"
    );
}

#[test]
fn points_only_and_faces_without_a_list_name() {
    let points = b"ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\n\
                   property double y\nproperty double z\nend_header\n0 0 0\nnan 1 2\n";
    let mesh = read(points).unwrap();
    assert!(mesh.triangles.is_empty() && mesh.positions.is_empty());
    let unnamed = b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\n\
                    property float y\nproperty float z\nelement face 1\n\
                    property list uchar int corners\nend_header\n";
    let e = read(unnamed).unwrap_err();
    assert_eq!(
        e.to_string(),
        "PLY header line 7: element 'face' has no 'vertex_indices' list"
    );
}

#[test]
fn doubles_stay_doubles() {
    let bytes = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\n\
                  property double y\nproperty double z\nelement face 1\n\
                  property list uchar uint vertex_index\nend_header\n\
                  0.1 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let mesh = read(bytes).unwrap();
    assert_eq!(mesh.positions[0].x, 0.1);
    let scene = scene(mesh, Path::new("dir/part.ply"));
    assert_eq!(scene.objects[0].name, "part");
    assert_eq!(scene.objects[0].source, "ply:part");
}
