use super::*;

#[test]
fn face_materials_follow_usemtl_over_fanned_faces() {
    let text = "f 1 2 3\nusemtl red\nf 1 2 3 4\nusemtl blue\nf 1 2\nf 1 2 3\nusemtl red\nf 1 2 3\n";
    let (names, per_triangle) = face_materials(text);
    assert_eq!(names, ["red", "blue"]);
    assert_eq!(per_triangle, [0, 1, 1, 2, 1]);
}

#[test]
fn continuations_join_on_the_first_line_and_keep_the_count() {
    let t = normalise("v 0 0 0\nf 1 2 \\\n  3 \\\n 4\nv 1 1 1\n");
    assert_eq!(t.text, "v 0 0 0\nf 1 2    3   4\n\n\nv 1 1 1\n");
    assert!(t.warnings.is_empty());
    let crlf = normalise("f 1 \\\r\n2 3\r\n");
    assert_eq!(crlf.text, "f 1  2 3\n\n");
    // A backslash on the last line continues onto nothing.
    assert_eq!(normalise("f 1 2 3 \\").text, "f 1 2 3\n");
}

#[test]
fn empty_and_unknown_statements_warn_once_per_kind() {
    let t = normalise("usemtl\nvc 1 0 0\nusemtl  \nvc 0 1 0\nvc 1\nfoo\ng\nusemtl\tred\n");
    assert_eq!(t.text, "\n\n\n\n\n\ng\nusemtl red\n");
    assert_eq!(
        t.warnings,
        [
            "line 1: empty 'usemtl' statement skipped (and 1 more line)",
            "line 6: 'foo' is not an OBJ statement: skipped",
            "line 2: 'vc' is not an OBJ statement: skipped (and 2 more lines)",
        ]
    );
}

#[test]
fn vertex_lines_keep_their_position_as_trimesh_reads_it() {
    let t = normalise("v 1 2 3 0.5 0.5 0.5\nv 1 2 3\nv 1 2 3 2\nv 3.1+e2 -1-e1 1e2\nv 1+e1 0 0\n");
    assert_eq!(
        t.text,
        "v 1 2 3\nv 1 2 3\nv 1 2 3 2\nv 3.1e2 -1e1 1e2\nv 1e1 0 0\n"
    );
    assert_eq!(
        t.warnings,
        ["line 4: '3.1+e2' is not a number: read as 3.1e2, as trimesh reads it (and 1 more line)"]
    );
    // Not numbers however read: left for tobj's "position parse error".
    assert_eq!(normalise("v 1 x 3\n").text, "v 1 x 3\n");
}

#[test]
fn comments_and_the_byte_order_mark() {
    let t = normalise("\u{feff}# a\nv 0 0 0 # b\n\n");
    assert_eq!(t.text, "\nv 0 0 0\n\n");
}

mod reference;

/// Asserts that [`normalise`] gives what its former implementation ([`reference`]) gives for
/// `text`, and that [`lines`] and [`words`] split `text` and the normalised text as the
/// library does: [`face_materials`] is its former self with those splitters in place of
/// [`str::lines`] and [`str::split_whitespace`], so it then gives what it gave.
fn assert_as_before(text: &str) {
    let new = normalise(text);
    assert_eq!(
        new,
        reference::reference_normalise(text),
        "normalise({text:?})"
    );
    for text in [text, &new.text] {
        assert_splits_as_the_library(text);
    }
}

/// Asserts that [`lines`] and [`words`] (its items and its count, whole and after a word)
/// split `text` as [`str::lines`] and [`str::split_whitespace`] do.
fn assert_splits_as_the_library(text: &str) {
    assert_eq!(
        lines(text).collect::<Vec<_>>(),
        text.lines().collect::<Vec<_>>()
    );
    for line in text.lines() {
        let mut words = words(line);
        assert_eq!(
            words.clone().collect::<Vec<_>>(),
            line.split_whitespace().collect::<Vec<_>>()
        );
        assert_eq!(words.clone().count(), line.split_whitespace().count());
        words.next();
        assert_eq!(
            words.count(),
            line.split_whitespace().count().saturating_sub(1)
        );
    }
}

/// The `.obj` files under `dir`, recursively.
fn obj_files(dir: &std::path::Path, found: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            obj_files(&path, found);
        } else if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
        {
            found.push(path);
        }
    }
}

#[test]
fn the_fixtures_read_as_before() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut files = Vec::new();
    obj_files(&root.join("fixtures"), &mut files);
    obj_files(&root.join("fuzz/seeds"), &mut files);
    assert!(files.len() >= 18, "{files:?}");
    for path in files {
        let bytes = std::fs::read(&path).unwrap();
        let text = String::from_utf8_lossy(&bytes);
        assert_as_before(&text);
        // The same lines with Windows line ends and a byte-order mark.
        assert_as_before(&format!("\u{feff}{}", text.replace('\n', "\r\n")));
    }
}

/// Lines that take each path of the rewrite, and its edges.
const LINES: &[&str] = &[
    "",
    " ",
    "\t \x0b\x0c",
    "\u{a0}",
    "# comment",
    "#",
    "v 1 2 3",
    "v  1\t2   3 ",
    "v 1 2 3 4",
    "v 1 2 3 0.5 0.5 0.5",
    "v 1 2 3 0.5 0.5 0.5 1",
    "v 1 2",
    "v",
    "v 1.0+e2 -2-e3 +e",
    "v e+5 1e+5 nan",
    "v inf -inf 1.0-e",
    "v 1+e1 1-e1 1+e1 1-e1",
    "v 3.1+e2 0 0 1.0+e2 9 9",
    "v 1E1 1e01 -0.0",
    "v 1\x0b2 3",
    "v 1\u{a0}2 3",
    "v\u{2003}1 2 3",
    "v 1 2 3 # colour \\",
    "f 1 2 3",
    "f 1/1/1 2/2/2 3/3/3 4/4/4",
    "f 1 2",
    "f",
    "f 1 # 2 3",
    "f 1 2 3\x0b4",
    "f 1\u{2028}2 3 4",
    "usemtl",
    "usemtl red",
    "usemtl\tred",
    "usemtl   red  ",
    "usemtl red green",
    "usemtl \t ",
    "usemtl\u{a0}red",
    "usemtlred",
    "vt 0 0",
    "vn 0 0 1",
    "g",
    "o",
    "s off",
    "end",
    "mtllib",
    "mtllib a.mtl",
    "vc 1 0 0",
    "foo",
    "é 1",
    "\\",
    "f 1 \\",
    "f 1\\",
    "v 1 \\",
    "\\\\",
    "# a comment \\",
    "2 3",
    "\u{feff}v 1 2 3",
];

#[test]
fn every_pair_and_triple_of_lines_reads_as_before() {
    for a in LINES {
        assert_as_before(a);
        for b in LINES {
            for end in ["\n", "\r\n"] {
                assert_as_before(&format!("{a}{end}{b}"));
                assert_as_before(&format!("\u{feff}{a}{end}{b}{end}"));
                for c in ["", "\\", "v 1 2 3", "usemtl x", "f 1 2 3 4"] {
                    assert_as_before(&format!("{a}{end}{b}{end}{c}{end}"));
                    assert_as_before(&format!("{c}{end}{a}{end}{b}"));
                }
            }
        }
    }
}

#[test]
fn random_texts_read_as_before() {
    const PIECES: &[&str] = &[
        "v", "f", "vt", "usemtl", "g", "vc", "#", "\\", "\n", "\n", "\n", "\r\n", "\r", " ", " ",
        "\t", "\x0b", "\u{a0}", "\u{85}", "\u{feff}", "1", "-2.5", "3/4/5", "1.0+e2", "-2-e3",
        "+e", "-e", "e", "+", "E", "e+5", "1e+5", "nan", "inf", "1.0-e", "red", "é",
    ];
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    let mut next = move |bound: usize| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state % bound as u64) as usize
    };
    for _ in 0..50_000 {
        let length = next(40);
        let text: String = (0..length).map(|_| PIECES[next(PIECES.len())]).collect();
        assert_as_before(&text);
    }
}
