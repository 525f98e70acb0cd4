//! The OBJ text as `tobj` and the checker read it: `\` line continuations joined, empty and
//! unknown statements blanked out with one warning per kind, `#` comments dropped, every line
//! kept at its number.
//!
//! `tobj` reads one physical line per statement and refuses an empty `usemtl` (a material
//! must never stop a render), so the text is rewritten first. A joined statement stands on
//! the first of its physical lines and the lines it swallowed become blank, so that line `n`
//! of the result is line `n` of the file and messages name the file's own lines.

use super::obj::STATEMENTS;
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
    let mut warnings = Vec::new();
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
            super::obj::quoted(keyword),
            more(s.count)
        ));
    }
    ObjText {
        text: out,
        warnings,
    }
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

#[cfg(test)]
mod tests {
    use super::*;

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
    fn comments_and_the_byte_order_mark() {
        let t = normalise("\u{feff}# a\nv 0 0 0 # b\n\n");
        assert_eq!(t.text, "\nv 0 0 0\n\n");
    }
}
