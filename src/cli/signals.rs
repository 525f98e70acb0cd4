//! What the command line does when it is told to stop: SIGINT (Ctrl-C), SIGTERM (`kill`,
//! `timeout`, a cancelled CI job) and SIGHUP (a closed terminal) alike. The temporary files of
//! every unfinished output and the output folders the run created (when still empty) are
//! removed, "interrupted" is said on stderr, and the process exits with 128 + the signal's
//! number, as shells report a process killed by it (130, 143, 129).

/// Starts the handler (a thread that waits for the signals).
#[cfg(unix)]
pub fn install() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
        return;
    };
    std::thread::spawn(move || {
        if let Some(signal) = signals.forever().next() {
            stop(signal);
        }
    });
}

/// Starts the handler (Ctrl-C only where there are no Unix signals).
#[cfg(not(unix))]
pub fn install() {
    let _ = ctrlc::set_handler(|| stop(2));
}

/// Says so and exits as a process stopped by `signal`, after the clean-up.
fn stop(signal: i32) -> ! {
    eprintln!("raycast: interrupted");
    raycast::output::remove_partial_files_and_exit(128 + signal)
}
