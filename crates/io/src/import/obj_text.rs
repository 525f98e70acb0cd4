//! The OBJ text as `tobj` and the checker read it: `\` line continuations joined, empty and
//! unknown statements blanked out with one warning per kind, `#` comments dropped, `v` lines
//! cut to their position (vertex colours, which no ray needs, dropped: tobj refuses a file
//! where only some vertices have them, trimesh reads it), every line kept at its number.
//!
//! `tobj` reads one physical line per statement and refuses an empty `usemtl` (a material
//! must never stop a render), so the text is rewritten first. A joined statement stands on
//! the first of its physical lines and the lines it swallowed become blank, so that line `n`
//! of the result is line `n` of the file and messages name the file's own lines.

use std::collections::BTreeMap;

/// Statements that mean something without arguments (`g` and `o` start an unnamed group or
/// object, `s` and `end` take no argument or an optional one); any other OBJ statement with
/// no argument is empty and skipped.
const BARE_STATEMENTS: &[&str] = &["g", "o", "s", "end", "bevel", "c_interp", "d_interp"];

/// The rewritten text and what was skipped.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ObjText {
    /// The text, as many lines as the file, each statement on its first physical line.
    pub text: String,
    /// One warning per kind of skipped statement (the first line, and how many more).
    pub warnings: Vec<String>,
}

/// What is skipped of one kind: the first line and the count.
#[derive(Default)]
struct Skipped {
    first: usize,
    count: usize,
}

/// Rewrites OBJ `text` (a leading byte-order mark dropped). A physical line ending in `\`
/// continues on the next one; the backslash is a word break, as Blender reads it (trimesh
/// removes the backslash and the line break, which reads the same where a space stands
/// before the backslash, as exporters write it).
pub fn normalise(text: &str) -> ObjText {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut out = String::with_capacity(text.len());
    let mut empty: BTreeMap<String, Skipped> = BTreeMap::new();
    let mut unknown: BTreeMap<String, Skipped> = BTreeMap::new();
    let mut misspelt = Misspelt::default();
    let mut lines = text.lines().enumerate();
    while let Some((n, first)) = lines.next() {
        let mut statement = first.to_string();
        let mut swallowed = 0;
        while let Some(head) = statement.strip_suffix('\\') {
            let head_len = head.len();
            statement.truncate(head_len);
            statement.push(' ');
            match lines.next() {
                Some((_, next)) => {
                    statement.push_str(next);
                    swallowed += 1;
                }
                None => break,
            }
        }
        let line = n + 1;
        // A `#` starts a comment to the end of the line (the checker reads it so too).
        let content = statement.split('#').next().unwrap_or("").trim();
        let mut words = content.split_whitespace();
        match words.next() {
            None => {}
            Some(keyword) if !STATEMENTS.contains(&keyword) => note(&mut unknown, keyword, line),
            Some(keyword) if words.next().is_none() && !BARE_STATEMENTS.contains(&keyword) => {
                note(&mut empty, keyword, line)
            }
            Some("v") => out.push_str(&vertex_line(content, line, &mut misspelt)),
            Some("usemtl") => {
                // tobj takes the name after the first space; a tab is a word break too.
                let name = content["usemtl".len()..].trim();
                out.push_str("usemtl ");
                out.push_str(name);
            }
            Some(_) => out.push_str(content),
        }
        out.push('\n');
        for _ in 0..swallowed {
            out.push('\n');
        }
    }
    let mut warnings: Vec<String> = misspelt.warning().into_iter().collect();
    for (keyword, s) in &empty {
        warnings.push(format!(
            "line {}: empty '{keyword}' statement skipped{}",
            s.first,
            more(s.count)
        ));
    }
    for (keyword, s) in &unknown {
        warnings.push(format!(
            "line {}: '{}' is not an OBJ statement: skipped{}",
            s.first,
            quoted(keyword),
            more(s.count)
        ));
    }
    ObjText {
        text: out,
        warnings,
    }
}

/// Numbers in `v` lines that Rust cannot read but trimesh does: an exponent with its sign
/// before the `e` (`3.1+e2`, `3.1-e2`), which trimesh reads after deleting the `+e` and `-e`
/// signs (so both are 3.1e2). The first one, and on how many lines.
#[derive(Default)]
struct Misspelt {
    first: Option<(usize, String, String)>,
    lines: usize,
}

impl Misspelt {
    fn warning(&self) -> Option<String> {
        let (line, written, read) = self.first.as_ref()?;
        Some(format!(
            "line {line}: '{}' is not a number: read as {read}, as trimesh reads it{}",
            quoted(written),
            more(self.lines)
        ))
    }
}

/// A `v` statement as tobj is to read it: `v X Y Z`, with `W` where the line has exactly
/// four numbers; colours after the position dropped; a number misspelt as [`Misspelt`]
/// says read as trimesh reads it. A line with fewer than three numbers is left for tobj to
/// refuse.
fn vertex_line(content: &str, line: usize, misspelt: &mut Misspelt) -> String {
    let values: Vec<&str> = content.split_whitespace().skip(1).collect();
    let kept = if values.len() == 4 { 4 } else { 3 };
    let mut out = String::from("v");
    let mut fixed = false;
    for &value in values.iter().take(kept) {
        out.push(' ');
        match trimesh_number(value) {
            Some(read) => {
                fixed = true;
                if misspelt.first.is_none() {
                    misspelt.first = Some((line, value.to_string(), read.clone()));
                }
                out.push_str(&read);
            }
            None => out.push_str(value),
        }
    }
    misspelt.lines += usize::from(fixed);
    out
}

/// The number trimesh reads for `word` where Rust reads none but deleting a sign before
/// an `e` makes one (`3.1+e2` → `3.1e2`).
fn trimesh_number(word: &str) -> Option<String> {
    if word.parse::<f64>().is_ok() {
        return None;
    }
    let read = word.replace("+e", "e").replace("-e", "e");
    read.parse::<f64>().is_ok().then_some(read)
}

fn note(kinds: &mut BTreeMap<String, Skipped>, keyword: &str, line: usize) {
    let s = kinds.entry(keyword.to_string()).or_default();
    if s.count == 0 {
        s.first = line;
    }
    s.count += 1;
}

fn more(count: usize) -> String {
    match count {
        0 | 1 => String::new(),
        2 => " (and 1 more line)".into(),
        n => format!(" (and {} more lines)", n - 1),
    }
}

/// The material of each triangle tobj makes of normalised `text` (faces fanned from their
/// first corner, in file order): the name of the `usemtl` in force at the face, as an index
/// into the names returned (in the order first used), from 1; 0 before any `usemtl`.
pub fn face_materials(text: &str) -> (Vec<String>, Vec<u32>) {
    let mut names: Vec<String> = Vec::new();
    let mut current = 0;
    let mut per_triangle = Vec::new();
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("usemtl") => {
                let name = line.trim().split_once(' ').unwrap_or_default().1.trim();
                current = match names.iter().position(|n| n == name) {
                    Some(i) => i as u32 + 1,
                    None => {
                        names.push(name.to_string());
                        names.len() as u32
                    }
                };
            }
            Some("f") => {
                let corners = words.count();
                per_triangle.extend(std::iter::repeat_n(current, corners.saturating_sub(2)));
            }
            _ => {}
        }
    }
    (names, per_triangle)
}

/// The keywords of the OBJ format (Wavefront's specification: vertex data, free-form curve
/// and surface attributes and bodies, elements, connectivity, grouping, display and render
/// attributes, and the superseded and general statements).
pub(crate) const STATEMENTS: &[&str] = &[
    "v",
    "vt",
    "vn",
    "vp",
    "cstype",
    "deg",
    "bmat",
    "step",
    "p",
    "l",
    "f",
    "curv",
    "curv2",
    "surf",
    "parm",
    "trim",
    "hole",
    "scrv",
    "sp",
    "end",
    "con",
    "g",
    "s",
    "mg",
    "o",
    "bevel",
    "c_interp",
    "d_interp",
    "lod",
    "usemtl",
    "mtllib",
    "shadow_obj",
    "trace_obj",
    "ctech",
    "stech",
    "maplib",
    "usemap",
    "call",
    "csh",
    "bsp",
    "bzp",
    "cdc",
    "cdp",
    "res",
];

/// Characters of a foreign line quoted in a message.
const QUOTED_CHARS: usize = 24;

/// The start of a foreign line, for a message: at most [`QUOTED_CHARS`] characters, control
/// characters escaped.
pub(crate) fn quoted(line: &str) -> String {
    let mut out: String = line
        .chars()
        .take(QUOTED_CHARS)
        .flat_map(char::escape_debug)
        .collect();
    if line.chars().nth(QUOTED_CHARS).is_some() {
        out.push('…');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn face_materials_follow_usemtl_over_fanned_faces() {
        let text =
            "f 1 2 3\nusemtl red\nf 1 2 3 4\nusemtl blue\nf 1 2\nf 1 2 3\nusemtl red\nf 1 2 3\n";
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
        let t =
            normalise("v 1 2 3 0.5 0.5 0.5\nv 1 2 3\nv 1 2 3 2\nv 3.1+e2 -1-e1 1e2\nv 1+e1 0 0\n");
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
}
