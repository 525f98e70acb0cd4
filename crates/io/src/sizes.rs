//! Sizes in bytes: parsing `--max-memory`'s `2G`, writing `1.5 GiB` for people, and the
//! default memory limit that the importers and the render share.

use crate::error::{Error, Result};

/// Parses a size such as `512M`, `2G`, `100000` (bytes; K, M, G, T are powers of 1024).
pub fn parse_size(text: &str) -> Result<u64> {
    let t = text.trim();
    let (digits, unit) = match t.char_indices().find(|(_, c)| c.is_ascii_alphabetic()) {
        Some((i, _)) => (&t[..i], t[i..].to_ascii_uppercase()),
        None => (t, String::new()),
    };
    let scale: u64 = match unit.trim_end_matches("IB").trim_end_matches('B') {
        "" => 1,
        "K" => 1 << 10,
        "M" => 1 << 20,
        "G" => 1 << 30,
        "T" => 1 << 40,
        _ => {
            return Err(Error::msg(format!(
                "'{text}': unknown unit (use K, M, G or T)"
            )))
        }
    };
    let n: f64 = digits
        .trim()
        .parse()
        .map_err(|_| Error::msg(format!("'{text}' is not a size")))?;
    if !(n.is_finite() && n > 0.0) {
        return Err(Error::msg(format!("'{text}' must be a positive size")));
    }
    Ok((n * scale as f64).min(u64::MAX as f64) as u64)
}

/// The default memory limit of a render: half the physical memory (Linux `MemTotal`), or the
/// memory the system reports available (`MemAvailable`) if that is less, so that one render
/// never takes a machine's memory from everything else on it; `None` where `/proc/meminfo`
/// cannot be read.
pub fn default_memory_limit() -> Option<u64> {
    limit_of_meminfo(&std::fs::read_to_string("/proc/meminfo").ok()?)
}

/// [`default_memory_limit`] for the text of `/proc/meminfo`.
fn limit_of_meminfo(text: &str) -> Option<u64> {
    let read = |key: &str| -> Option<u64> {
        let line = text.lines().find(|l| l.starts_with(key))?;
        let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some(kib * 1024)
    };
    let half = read("MemTotal:")? / 2;
    Some(read("MemAvailable:").map_or(half, |available| available.min(half)))
}

/// A byte count for people: `1.5 GiB`.
pub fn human_bytes(bytes: u64) -> String {
    let units = ["bytes", "KiB", "MiB", "GiB", "TiB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < units.len() {
        value /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} bytes")
    } else {
        format!("{value:.1} {}", units[unit])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_in_powers_of_1024() {
        assert_eq!(parse_size("512M"), Ok(512 << 20));
        assert_eq!(parse_size("2GiB"), Ok(2 << 30));
        assert_eq!(parse_size("100"), Ok(100));
        assert!(parse_size("-1").is_err());
        assert!(parse_size("3X").is_err());
    }

    #[test]
    fn sizes_print_in_binary_units() {
        assert_eq!(human_bytes(3 << 29), "1.5 GiB");
        assert_eq!(human_bytes(1000), "1000 bytes");
    }

    #[test]
    fn the_default_limit_is_half_the_memory_or_what_is_available() {
        let text = "MemTotal:       16000 kB\nMemFree: 1 kB\nMemAvailable:    6000 kB\n";
        assert_eq!(limit_of_meminfo(text), Some(6000 * 1024));
        assert_eq!(limit_of_meminfo("MemTotal: 16000 kB\n"), Some(8000 * 1024));
        assert_eq!(limit_of_meminfo("nothing"), None);
    }
}
