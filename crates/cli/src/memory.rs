//! The memory budget: large allocations whose size follows from user input (the film, path
//! records) are estimated first and refused with exit 2 above the budget, instead of the
//! process aborting when the allocation fails.

use std::sync::OnceLock;

use crate::Failure;

static LIMIT: OnceLock<u64> = OnceLock::new();

/// The share of physical memory the default budget allows.
const DEFAULT_SHARE: f64 = 0.75;

/// Set the budget from `--memory-limit` (call once, before any check).
pub(crate) fn set_limit(bytes: Option<u64>) {
    let _ = LIMIT.set(bytes.unwrap_or_else(default_limit));
}

/// The budget in bytes: `--memory-limit`, else 75 % of physical memory.
pub(crate) fn limit() -> u64 {
    *LIMIT.get_or_init(default_limit)
}

fn default_limit() -> u64 {
    let total = physical_memory().unwrap_or(8 << 30);
    (total as f64 * DEFAULT_SHARE) as u64
}

/// `MemTotal` of /proc/meminfo (Linux); `None` elsewhere.
fn physical_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Fail with exit 2 when `what` needs more than the budget.
pub(crate) fn check(what: &str, needed: u64) -> Result<(), Failure> {
    let limit = limit();
    if needed > limit {
        return Err(Failure::input(format!(
            "{what} needs about {} of memory, more than the limit of {} \
             (75 % of physical memory by default; raise it with --memory-limit SIZE, \
             or lower the resolution or count)",
            human(needed),
            human(limit)
        )));
    }
    Ok(())
}

/// `1.5 GiB`-style sizes.
pub(crate) fn human(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["bytes", "KiB", "MiB", "GiB", "TiB"];
    let mut v = bytes as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{bytes} bytes")
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

/// Parse `--memory-limit`: a number of bytes with an optional K, M, G or T suffix (powers of
/// 1024, an optional trailing `B` or `iB`).
pub(crate) fn parse_size(s: &str) -> Result<u64, String> {
    let err = || format!("expected a size such as 512M or 4G, found '{s}'");
    let lower = s.trim().to_ascii_lowercase();
    let t = lower
        .strip_suffix("ib")
        .or_else(|| lower.strip_suffix('b'))
        .unwrap_or(&lower);
    let (num, shift) = match t.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => {
            let shift = match c.to_ascii_uppercase() {
                'K' => 10,
                'M' => 20,
                'G' => 30,
                'T' => 40,
                _ => return Err(err()),
            };
            (&t[..i], shift)
        }
        _ => (t, 0),
    };
    let v: f64 = num.trim().parse().map_err(|_| err())?;
    if !(v.is_finite() && v > 0.0) {
        return Err(err());
    }
    let bytes = v * (1u64 << shift) as f64;
    if bytes >= u64::MAX as f64 {
        return Err(err());
    }
    Ok(bytes as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_suffixes() {
        assert_eq!(parse_size("1000"), Ok(1000));
        assert_eq!(parse_size("512M"), Ok(512 << 20));
        assert_eq!(parse_size("4G"), Ok(4 << 30));
        assert_eq!(parse_size("1.5GiB"), Ok(3 << 29));
        assert_eq!(parse_size("2kb"), Ok(2048));
        for bad in ["", "G", "-1G", "0", "4X", "nanG", "1e30T"] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn human_sizes() {
        assert_eq!(human(12), "12 bytes");
        assert_eq!(human(3 << 29), "1.5 GiB");
    }
}
