//! The Markdown summary of a run (`--summary FILE`), written for `$GITHUB_STEP_SUMMARY`:
//! GitHub shows only a few annotations, so the whole picture is here: counts by status and
//! by code, the worst assets and the slowest.

use super::{AssetReport, Severity, Status};
use crate::info::count;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// Rows in the worst-assets and slowest-assets tables.
pub const TOP: usize = 10;

/// Text safe inside a Markdown table cell: `|` and Markdown punctuation escaped, line breaks
/// and control characters made spaces, at most 160 characters.
fn cell(text: &str) -> String {
    let mut out = String::new();
    for (i, c) in text.chars().enumerate() {
        if i == 160 {
            out.push('…');
            break;
        }
        match c {
            '|' | '\\' | '`' | '*' | '_' | '[' | ']' | '<' | '>' | '#' | '~' | '&' => {
                out.push('\\');
                out.push(c);
            }
            c if c.is_control() => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

/// Text as a code span in a table cell: backticks become `'`, control characters spaces,
/// and `|` is escaped (GitHub splits cells at a `|` even inside code).
fn code(text: &str) -> String {
    let inner: String = text
        .chars()
        .map(|c| match c {
            '`' => "'".to_string(),
            '|' => "\\|".to_string(),
            c if c.is_control() => " ".to_string(),
            c => c.to_string(),
        })
        .collect();
    format!("`{inner}`")
}

/// The summary of `reports`; `strict` when warnings fail the run, `seconds` the run's time.
pub fn markdown(reports: &[AssetReport], strict: bool, seconds: f64) -> String {
    let mut out = String::from("## raycast check\n\n");
    let failing = reports.iter().filter(|r| r.fails(strict)).count();
    let verdict = if failing == 0 {
        "passed".to_string()
    } else {
        format!("**failed**: {} fail", count(failing, "asset"))
    };
    let _ = writeln!(
        out,
        "{} checked in {seconds:.2} s: {verdict}{}.\n",
        count(reports.len(), "asset"),
        if strict {
            " (strict: warnings fail)"
        } else {
            ""
        }
    );
    status_table(&mut out, reports);
    code_table(&mut out, reports);
    worst_table(&mut out, reports, strict);
    slowest_table(&mut out, reports);
    out
}

fn status_table(out: &mut String, reports: &[AssetReport]) {
    out.push_str("| status | assets |\n| --- | ---: |\n");
    for status in [Status::Error, Status::Warning, Status::Ok] {
        let n = reports.iter().filter(|r| r.status == status).count();
        let _ = writeln!(out, "| {} | {n} |", status.name());
    }
    out.push('\n');
}

fn code_table(out: &mut String, reports: &[AssetReport]) {
    // (severity, code) -> (findings, assets)
    let mut codes: BTreeMap<(Severity, &str), (usize, usize)> = BTreeMap::new();
    for r in reports {
        let mut seen = std::collections::BTreeSet::new();
        for f in &r.findings {
            let entry = codes.entry((f.severity, f.code.name())).or_default();
            entry.0 += 1;
            if seen.insert((f.severity, f.code.name())) {
                entry.1 += 1;
            }
        }
    }
    if codes.is_empty() {
        out.push_str("No findings.\n\n");
        return;
    }
    out.push_str("### Findings by code\n\n| severity | code | findings | assets |\n| --- | --- | ---: | ---: |\n");
    for ((severity, code_name), (findings, assets)) in codes {
        let _ = writeln!(
            out,
            "| {} | {} | {findings} | {assets} |",
            severity.name(),
            code(code_name)
        );
    }
    let omitted: usize = reports.iter().map(|r| r.omitted).sum();
    if omitted > 0 {
        let _ = writeln!(
            out,
            "\n{} left out by `--max-findings` are not counted here.",
            count(omitted, "finding")
        );
    }
    out.push('\n');
}

fn worst_table(out: &mut String, reports: &[AssetReport], strict: bool) {
    let mut worst: Vec<&AssetReport> = reports.iter().filter(|r| r.status != Status::Ok).collect();
    if worst.is_empty() {
        return;
    }
    // Most errors first, then most warnings, then report order (the sort is stable).
    worst.sort_by_key(|r| std::cmp::Reverse((r.errors, r.warnings)));
    let _ = writeln!(
        out,
        "### Worst assets ({} of {})\n\n| asset | errors | warnings | first problem |\n| --- | ---: | ---: | --- |",
        worst.len().min(TOP),
        worst.len()
    );
    for r in worst.iter().take(TOP) {
        let first = r
            .findings
            .iter()
            .filter(|f| f.severity != Severity::Info)
            .min_by_key(|f| f.severity)
            .map(|f| format!("{}: {}", f.code, f.message))
            .unwrap_or_default();
        let mark = if r.fails(strict) { " ✗" } else { "" };
        let _ = writeln!(
            out,
            "| {}{mark} | {} | {} | {} |",
            code(&r.path),
            r.errors,
            r.warnings,
            cell(&first)
        );
    }
    out.push('\n');
}

fn slowest_table(out: &mut String, reports: &[AssetReport]) {
    let mut slow: Vec<&AssetReport> = reports.iter().collect();
    slow.sort_by(|a, b| b.seconds.total_cmp(&a.seconds));
    if slow.is_empty() {
        return;
    }
    out.push_str("### Slowest assets\n\n| asset | seconds |\n| --- | ---: |\n");
    for r in slow.iter().take(TOP) {
        let _ = writeln!(out, "| {} | {:.3} |", code(&r.path), r.seconds);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_cannot_break_the_table() {
        assert_eq!(cell("a|b\nc"), "a\\|b c");
        assert_eq!(code("x`|y"), "`x'\\|y`");
    }
}
