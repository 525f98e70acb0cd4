//! The implementation of [`normalise`] before it stopped allocating per line (commit
//! b8f1813), kept word for word (renamed, `reference_`) as the oracle of the
//! equivalence test: the two must give the same output for every input. Test code only. The
//! warnings are made by the module's own `warnings`, which the change did not touch.

use super::super::{note, warnings, Misspelt, ObjText, Skipped, BARE_STATEMENTS, STATEMENTS};
use std::collections::BTreeMap;

/// Rewrites OBJ `text` (a leading byte-order mark dropped). A physical line ending in `\`
/// continues on the next one; the backslash is a word break, as Blender reads it (trimesh
/// removes the backslash and the line break, which reads the same where a space stands
/// before the backslash, as exporters write it).
pub(super) fn reference_normalise(text: &str) -> ObjText {
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
            Some("v") => out.push_str(&reference_vertex_line(content, line, &mut misspelt)),
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
    ObjText {
        text: out,
        warnings: warnings(&misspelt, &empty, &unknown),
    }
}

/// A `v` statement as tobj is to read it: `v X Y Z`, with `W` where the line has exactly
/// four numbers; colours after the position dropped; a number misspelt as [`Misspelt`]
/// says read as trimesh reads it. A line with fewer than three numbers is left for tobj to
/// refuse.
fn reference_vertex_line(content: &str, line: usize, misspelt: &mut Misspelt) -> String {
    let values: Vec<&str> = content.split_whitespace().skip(1).collect();
    let kept = if values.len() == 4 { 4 } else { 3 };
    let mut out = String::from("v");
    let mut fixed = false;
    for &value in values.iter().take(kept) {
        out.push(' ');
        match reference_trimesh_number(value) {
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
fn reference_trimesh_number(word: &str) -> Option<String> {
    if word.parse::<f64>().is_ok() {
        return None;
    }
    let read = word.replace("+e", "e").replace("-e", "e");
    read.parse::<f64>().is_ok().then_some(read)
}
