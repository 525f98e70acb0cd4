//! Reading a USD file in a child process, so that a reader that aborts (an allocation
//! failure), panics or hangs on a file ends the run with a one-line error: [`probe`] for a
//! render and `raycast info`, [`run_child`] and the words of a dead child for `raycast check`.

use crate::error::{Error, Result};
use std::path::Path;

/// Runs `command` with null stdin and piped output, killing it after `timeout`; returns its
/// exit status (`None` when it was stopped or could not be waited for), stdout and stderr.
pub fn run_child(
    mut command: std::process::Command,
    timeout: std::time::Duration,
) -> std::io::Result<(Option<std::process::ExitStatus>, String, String)> {
    use std::io::Read;
    use std::process::Stdio;
    let mut child = command
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    // Drain both pipes on threads so that a chatty child cannot block.
    let drain = |pipe: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut text = String::new();
            if let Some(mut pipe) = pipe {
                let _ = pipe.read_to_string(&mut text);
            }
            text
        })
    };
    let out = drain(
        child
            .stdout
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let err = drain(
        child
            .stderr
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let started = std::time::Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break Some(status),
            Ok(None) if started.elapsed() > timeout => {
                let _ = child.kill();
                let _ = child.wait();
                break None;
            }
            Ok(None) => std::thread::sleep(std::time::Duration::from_millis(5)),
            Err(_) => break None,
        }
    };
    Ok((
        status,
        out.join().unwrap_or_default(),
        err.join().unwrap_or_default(),
    ))
}

/// The reader's own last words in a dead child's stderr: an allocation failure, a panic, a
/// stack overflow, else its last non-empty line.
pub fn last_words(stderr: &str) -> &str {
    let telling = |l: &&str| {
        [
            "memory allocation",
            "panicked",
            "overflow",
            "fatal",
            "error",
        ]
        .iter()
        .any(|w| l.contains(w))
    };
    stderr
        .lines()
        .find(telling)
        .or_else(|| stderr.lines().rev().find(|l| !l.trim().is_empty()))
        .unwrap_or("")
        .trim()
}

/// How a child ended that did not exit normally.
pub fn stopped_how(
    status: Option<std::process::ExitStatus>,
    timeout: std::time::Duration,
) -> String {
    match status {
        None => format!("ran longer than {}s and was stopped", timeout.as_secs_f64()),
        Some(status) => format!("crashed ({status})"),
    }
}

/// Environment variable set for the child of [`probe`], so that it reads the file itself.
pub const PROBE_CHILD: &str = "RAYCAST_USD_PROBE_CHILD";

/// Reads the USD file `path` in a child `raycast info` (`exe`, with `args`) first, so that a reader that
/// aborts (an allocation failure), panics or hangs on it ends the render or `info` with a
/// one-line error instead: `Ok` when the child read it (the caller then reads it itself),
/// `Err` with the child's one-line error, or with how the reader died or that it was stopped
/// after `timeout`.
pub fn probe(
    exe: &Path,
    path: &Path,
    args: &[std::ffi::OsString],
    timeout: std::time::Duration,
) -> Result<()> {
    let mut command = std::process::Command::new(exe);
    command
        .arg("info")
        .arg(path)
        .args(args)
        .env(PROBE_CHILD, "1");
    let (status, _, stderr) = run_child(command, timeout)
        .map_err(|e| Error::msg(format!("cannot start the USD reader: {e}")))?;
    match status.and_then(|s| s.code()) {
        Some(0) => Ok(()),
        Some(1) => Err(Error::msg(
            stderr
                .lines()
                .find_map(|l| l.strip_prefix("raycast: error: "))
                .unwrap_or_else(|| last_words(&stderr)),
        )),
        _ => {
            let last = last_words(&stderr);
            let how = stopped_how(status, timeout);
            Err(Error::msg(format!(
                "{}: the USD reader {how} on this file{}",
                path.display(),
                if last.is_empty() {
                    String::new()
                } else {
                    format!(": {last}")
                }
            )))
        }
    }
}
