//! The outputs of `raycast check`: a human summary, JSON Lines, JUnit XML and GitHub
//! annotations.

use super::{AssetReport, Severity, Status};
use crate::info::count;
use std::fmt::Write as _;

/// Text for a person: one line per asset with problems and one per finding.
pub fn human(reports: &[AssetReport], verbose: bool) -> String {
    let mut out = String::new();
    for r in reports {
        if r.findings.is_empty() && !verbose {
            continue;
        }
        let visible: Vec<_> = r
            .findings
            .iter()
            .filter(|f| verbose || f.severity != Severity::Info)
            .collect();
        if visible.is_empty() && !verbose {
            continue;
        }
        let _ = writeln!(
            out,
            "{}: {} ({}, {})",
            r.path,
            r.status.name(),
            count(r.errors, "error"),
            count(r.warnings, "warning")
        );
        for f in visible {
            let at = if f.location.is_empty() {
                String::new()
            } else {
                format!(" {}", f.location)
            };
            let _ = writeln!(
                out,
                "  {:<7} {}{}: {}",
                f.severity.name(),
                f.code,
                at,
                f.message
            );
        }
        if r.omitted > 0 {
            let _ = writeln!(
                out,
                "  ({} not listed: --max-findings)",
                count(r.omitted, "more finding")
            );
        }
    }
    out
}

/// The last line: counts of assets by verdict.
pub fn summary(reports: &[AssetReport], seconds: f64) -> String {
    let errors = reports.iter().filter(|r| r.status == Status::Error).count();
    let warnings = reports
        .iter()
        .filter(|r| r.status == Status::Warning)
        .count();
    let ok = reports.len() - errors - warnings;
    format!(
        "checked {} in {seconds:.2}s: {ok} ok, {warnings} with warnings, {errors} with errors",
        count(reports.len(), "asset")
    )
}

/// One JSON object per asset, one per line.
pub fn json_lines(reports: &[AssetReport]) -> String {
    let mut out = String::new();
    for r in reports {
        match serde_json::to_string(r) {
            Ok(line) => {
                out.push_str(&line);
                out.push('\n');
            }
            Err(e) => {
                let _ = writeln!(
                    out,
                    "{{\"path\":{:?},\"error\":{:?}}}",
                    r.path,
                    e.to_string()
                );
            }
        }
    }
    out
}

fn xml(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            // Characters XML 1.0 cannot hold.
            c if (c as u32) < 0x20 && !matches!(c, '\t' | '\n' | '\r') => out.push('\u{FFFD}'),
            c => out.push(c),
        }
    }
    out
}

/// JUnit XML: one testsuite, one testcase per asset; errors are failures (warnings too when
/// `strict`), the other findings go to the testcase's system-out.
pub fn junit(reports: &[AssetReport], seconds: f64, strict: bool) -> String {
    let failing = |severity: Severity| {
        severity == Severity::Error || (strict && severity == Severity::Warning)
    };
    let failures = reports.iter().filter(|r| r.fails(strict)).count();
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let _ = writeln!(
        out,
        "<testsuites name=\"raycast check\" tests=\"{}\" failures=\"{failures}\" errors=\"0\" time=\"{seconds:.3}\">",
        reports.len()
    );
    let _ = writeln!(
        out,
        "  <testsuite name=\"raycast check\" tests=\"{}\" failures=\"{failures}\" errors=\"0\" skipped=\"0\" time=\"{seconds:.3}\">",
        reports.len()
    );
    for r in reports {
        let _ = write!(
            out,
            "    <testcase classname=\"raycast.check.{}\" name=\"{}\" time=\"{:.3}\"",
            xml(&r.format),
            xml(&r.path),
            r.seconds
        );
        if r.findings.is_empty() && r.omitted == 0 {
            out.push_str("/>\n");
            continue;
        }
        out.push_str(">\n");
        let line = |f: &super::Finding| {
            format!(
                "{} {} {}: {}",
                f.severity.name(),
                f.code,
                f.location,
                f.message
            )
        };
        if r.fails(strict) {
            let first = r
                .findings
                .iter()
                .find(|f| failing(f.severity))
                .map(|f| format!("{}: {}", f.code, f.message))
                .unwrap_or_default();
            let body: Vec<String> = r
                .findings
                .iter()
                .filter(|f| failing(f.severity))
                .map(line)
                .collect();
            let _ = writeln!(
                out,
                "      <failure message=\"{}\" type=\"{}\">{}</failure>",
                xml(&first),
                r.errors + if strict { r.warnings } else { 0 },
                xml(&body.join("\n"))
            );
        }
        let rest: Vec<String> = r
            .findings
            .iter()
            .filter(|f| !failing(f.severity))
            .map(line)
            .collect();
        if !rest.is_empty() {
            let _ = writeln!(
                out,
                "      <system-out>{}</system-out>",
                xml(&rest.join("\n"))
            );
        }
        out.push_str("    </testcase>\n");
    }
    out.push_str("  </testsuite>\n</testsuites>\n");
    out
}

fn gh_data(text: &str) -> String {
    text.replace('%', "%25")
        .replace('\r', "%0D")
        .replace('\n', "%0A")
}

fn gh_property(text: &str) -> String {
    gh_data(text).replace(':', "%3A").replace(',', "%2C")
}

/// Annotations of one type GitHub shows per step (it shows at most 50 per job).
pub const GITHUB_PER_TYPE: usize = 10;

/// GitHub workflow commands: `::error file=F,line=L,title=CODE::message` for errors and
/// warnings (infos are left out), at most [`GITHUB_PER_TYPE`] of each type: GitHub drops the
/// rest. When some are left out, a `::notice` says how many and points to `see` (the summary
/// or the JUnit report).
pub fn github(reports: &[AssetReport], see: &str) -> String {
    let mut out = String::new();
    let (mut errors, mut warnings) = (0, 0);
    for r in reports {
        for f in &r.findings {
            let (kind, shown) = match f.severity {
                Severity::Error => ("error", &mut errors),
                Severity::Warning => ("warning", &mut warnings),
                Severity::Info => continue,
            };
            *shown += 1;
            if *shown > GITHUB_PER_TYPE {
                continue;
            }
            let line = f
                .location
                .strip_prefix("line ")
                .and_then(|l| l.parse::<usize>().ok())
                .map_or(String::new(), |l| format!(",line={l}"));
            let at = if f.location.is_empty() || !line.is_empty() {
                String::new()
            } else {
                format!(" at {}", f.location)
            };
            let _ = writeln!(
                out,
                "::{kind} file={}{line},title={}::{}{}",
                gh_property(&r.path),
                gh_property(f.code.name()),
                gh_data(&f.message),
                gh_data(&at)
            );
        }
    }
    let hidden =
        |n: usize, what: &str| (n > GITHUB_PER_TYPE).then(|| count(n - GITHUB_PER_TYPE, what));
    let hidden: Vec<String> = [
        hidden(errors, "more error"),
        hidden(warnings, "more warning"),
    ]
    .into_iter()
    .flatten()
    .collect();
    if !hidden.is_empty() {
        let _ = writeln!(
            out,
            "::notice title=raycast check::{} not annotated (GitHub shows {GITHUB_PER_TYPE} of each type per step): see {}",
            hidden.join(" and "),
            gh_data(see)
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Finding;

    fn report() -> AssetReport {
        AssetReport {
            path: "a,b:c.obj".into(),
            relpath: "a,b:c.obj".into(),
            format: "obj".into(),
            status: Status::Error,
            errors: 1,
            warnings: 0,
            infos: 0,
            seconds: 0.0,
            scene: None,
            findings: vec![Finding::error(
                crate::Code::IndexOob,
                "line 7",
                "50% <bad>\nnext",
            )],
            omitted: 0,
        }
    }

    #[test]
    fn annotations_are_escaped() {
        let text = github(&[report()], "the summary");
        assert_eq!(
            text,
            "::error file=a%2Cb%3Ac.obj,line=7,title=INDEX_OOB::50%25 <bad>%0Anext\n"
        );
    }

    #[test]
    fn junit_is_escaped() {
        let text = junit(&[report()], 1.0, false);
        assert!(text.contains("&lt;bad&gt;"));
        assert!(text.contains("failures=\"1\""));
    }
}
