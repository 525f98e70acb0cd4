//! One rule for `--threads` (render) and `--jobs` (check): 0 is refused by the parser, and
//! more than the machine's cores is brought down to the cores with a warning (the work is
//! bound by the cores: 1000 threads on 2 cores ran 90 times slower).

/// `requested` workers for `flag`, at most the available cores; says so on stderr when it
/// brings the number down (unless `quiet`).
pub fn clamp(requested: usize, flag: &str, quiet: bool) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if requested <= cores {
        return requested;
    }
    if !quiet {
        eprintln!(
            "raycast: warning: {flag} {requested} is more than the {cores} cores; using {cores}"
        );
    }
    cores
}
