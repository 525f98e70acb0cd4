//! The OBJ text as `tobj` and the checker read it: `\` line continuations joined, empty and
//! unknown statements blanked out with one warning per kind, `#` comments dropped, `v` lines
//! cut to their position (vertex colours, which no ray needs, dropped: tobj refuses a file
//! where only some vertices have them, trimesh reads it) with trimesh's reading of a number
//! misspelt `3.1+e2`, a leading byte-order mark dropped, every line kept at its number.
//!
//! `tobj` reads one physical line per statement and refuses an empty `usemtl` (a material
//! must never stop a render), so the text is rewritten first. A joined statement stands on
//! the first of its physical lines and the lines it swallowed become blank, so that line `n`
//! of the result is line `n` of the file and messages name the file's own lines.
//!
//! Both passes here read every byte of every OBJ file (as much as tobj's parse itself, for a
//! scanned mesh), so they allocate nothing per line, find lines, comments and words with
//! plain byte loops (the library's searches are made for long texts, an OBJ line is short)
//! and try to read a number only where it may be misspelt. The results are exactly those of
//! `str::lines` and `str::split_whitespace` (the tests hold them to the former code).

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::str::SplitWhitespace;

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
///
/// This runs over every line of every OBJ file, so it allocates nothing per line where it
/// can: a line is borrowed unless it continues, and each statement is written straight into
/// the result.
pub fn normalise(text: &str) -> ObjText {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut out = String::with_capacity(text.len());
    let mut empty: BTreeMap<String, Skipped> = BTreeMap::new();
    let mut unknown: BTreeMap<String, Skipped> = BTreeMap::new();
    let mut misspelt = Misspelt::default();
    let mut lines = lines(text).enumerate();
    while let Some((n, first)) = lines.next() {
        let (statement, swallowed) = statement(first, &mut lines);
        let line = n + 1;
        // A `#` starts a comment to the end of the line (the checker reads it so too).
        let content = match find_byte(&statement, b'#') {
            Some(comment) => &statement[..comment],
            None => &statement,
        }
        .trim();
        let mut words = words(content);
        let keyword = words.next();
        let arguments = words.clone();
        match keyword {
            None => {}
            Some(keyword) if !is_statement(keyword) => note(&mut unknown, keyword, line),
            Some(keyword) if words.next().is_none() && !BARE_STATEMENTS.contains(&keyword) => {
                note(&mut empty, keyword, line)
            }
            Some("v") => push_vertex(&mut out, arguments, line, &mut misspelt),
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

/// One warning for the misspelt numbers, then one per kind of empty statement, then one per
/// kind of unknown statement.
fn warnings(
    misspelt: &Misspelt,
    empty: &BTreeMap<String, Skipped>,
    unknown: &BTreeMap<String, Skipped>,
) -> Vec<String> {
    let mut warnings: Vec<String> = misspelt.warning().into_iter().collect();
    for (keyword, s) in empty {
        warnings.push(format!(
            "line {}: empty '{keyword}' statement skipped{}",
            s.first,
            more(s.count)
        ));
    }
    for (keyword, s) in unknown {
        warnings.push(format!(
            "line {}: '{}' is not an OBJ statement: skipped{}",
            s.first,
            quoted(keyword),
            more(s.count)
        ));
    }
    warnings
}

/// The statement that starts on physical line `first` and how many of the following `lines`
/// it swallowed: `first` itself (borrowed) unless it ends in `\`, else the lines joined, each
/// trailing `\` read as a space, for as long as the line last joined ends in `\` (one on the
/// last line continues onto nothing).
fn statement<'a>(
    first: &'a str,
    lines: &mut impl Iterator<Item = (usize, &'a str)>,
) -> (Cow<'a, str>, usize) {
    if !first.ends_with('\\') {
        return (Cow::Borrowed(first), 0);
    }
    let mut statement = first.to_string();
    let mut swallowed = 0;
    while let Some(head) = statement.strip_suffix('\\') {
        statement.truncate(head.len());
        statement.push(' ');
        match lines.next() {
            Some((_, next)) => {
                statement.push_str(next);
                swallowed += 1;
            }
            None => break,
        }
    }
    (Cow::Owned(statement), swallowed)
}

/// The lines of `text` as [`str::lines`] gives them: split after each `\n`, which is dropped
/// with a `\r` before it, and no empty line after a last `\n`.
fn lines(text: &str) -> Lines<'_> {
    Lines(text)
}

/// The iterator of [`lines`]: the text not yet read.
struct Lines<'a>(&'a str);

impl<'a> Iterator for Lines<'a> {
    type Item = &'a str;

    fn next(&mut self) -> Option<&'a str> {
        if self.0.is_empty() {
            return None;
        }
        let line = match find_byte(self.0, b'\n') {
            Some(end) => {
                let line = &self.0[..end];
                self.0 = &self.0[end + 1..];
                line.strip_suffix('\r').unwrap_or(line)
            }
            None => std::mem::take(&mut self.0),
        };
        Some(line)
    }
}

/// Where ASCII `byte` first is in `s`: a plain loop, which on lines as short as an OBJ
/// file's costs about two thirds of [`str::find`]'s search.
fn find_byte(s: &str, byte: u8) -> Option<usize> {
    s.bytes().position(|b| b == byte)
}

/// Whether `word` is one of the [`STATEMENTS`]; those of nearly every line are tried first.
fn is_statement(word: &str) -> bool {
    matches!(word, "v" | "f" | "vt" | "vn") || STATEMENTS.contains(&word)
}

/// The words of `s` exactly as [`str::split_whitespace`] finds them, found byte by byte
/// (without decoding characters) where `s` is ASCII, as nearly every OBJ line is.
fn words(s: &str) -> Words<'_> {
    if s.is_ascii() {
        Words::Ascii(s)
    } else {
        Words::Unicode(s.split_whitespace())
    }
}

/// The iterator of [`words`]: the rest of an ASCII string, or the words of any other.
#[derive(Clone)]
enum Words<'a> {
    Ascii(&'a str),
    Unicode(SplitWhitespace<'a>),
}

impl<'a> Iterator for Words<'a> {
    type Item = &'a str;

    fn next(&mut self) -> Option<&'a str> {
        let rest = match self {
            Words::Ascii(rest) => rest,
            Words::Unicode(words) => return words.next(),
        };
        let bytes = rest.as_bytes();
        let mut start = 0;
        while start < bytes.len() && is_ascii_space(bytes[start]) {
            start += 1;
        }
        if start == bytes.len() {
            *rest = "";
            return None;
        }
        let mut end = start + 1;
        while end < bytes.len() && !is_ascii_space(bytes[end]) {
            end += 1;
        }
        let word = &rest[start..end];
        *rest = &rest[end..];
        Some(word)
    }

    fn count(self) -> usize {
        match self {
            Words::Ascii(rest) => word_starts(rest.as_bytes()),
            Words::Unicode(words) => words.count(),
        }
    }
}

/// How many words ASCII `bytes` has: the bytes that are not white space and follow one that
/// is, or the start.
fn word_starts(bytes: &[u8]) -> usize {
    let mut after_space = true;
    let mut starts = 0;
    for &b in bytes {
        let space = is_ascii_space(b);
        starts += usize::from(after_space && !space);
        after_space = space;
    }
    starts
}

/// Whether ASCII byte `b` is white space as [`char::is_whitespace`] reads it: a space or `\t`
/// to `\r` (with the vertical tab, which [`u8::is_ascii_whitespace`] leaves out).
fn is_ascii_space(b: u8) -> bool {
    b == b' ' || (b'\t'..=b'\r').contains(&b)
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

/// Writes a `v` statement with these `values` as tobj is to read it: `v X Y Z`, with `W`
/// where the line has exactly four numbers; colours after the position dropped; a number
/// misspelt as [`Misspelt`] says read as trimesh reads it. A line with fewer than three
/// numbers is left for tobj to refuse.
fn push_vertex<'a>(
    out: &mut String,
    values: impl Iterator<Item = &'a str>,
    line: usize,
    misspelt: &mut Misspelt,
) {
    // Five tell a line of four numbers from a longer one.
    let mut first = [""; 5];
    let mut count = 0;
    for (slot, value) in first.iter_mut().zip(values) {
        *slot = value;
        count += 1;
    }
    let kept = if count == 4 { 4 } else { count.min(3) };
    out.push('v');
    let mut fixed = false;
    for &value in &first[..kept] {
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
}

/// The number trimesh reads for `word` where Rust reads none but deleting a sign before
/// an `e` makes one (`3.1+e2` → `3.1e2`).
fn trimesh_number(word: &str) -> Option<String> {
    // Without a `+e` or `-e` the deletions change nothing, so a word Rust does not read stays
    // unread: only a word with one can be misspelt (and no number Rust reads has one), and
    // nearly no word is parsed here.
    if !has_signed_e(word) || word.parse::<f64>().is_ok() {
        return None;
    }
    let read = word.replace("+e", "e").replace("-e", "e");
    read.parse::<f64>().is_ok().then_some(read)
}

/// Whether `word` has a `+e` or `-e` in it.
fn has_signed_e(word: &str) -> bool {
    word.as_bytes()
        .windows(2)
        .any(|pair| matches!(pair, [b'+' | b'-', b'e']))
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
    for line in lines(text) {
        let mut words = words(line);
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
mod tests;
