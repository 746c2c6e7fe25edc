//! Sizes and durations for a person, as the refusals and notices write them.

/// Bytes for a person: "512 B", "3.4 kB", "12 GB", "1.2e6 TB" (SI prefixes).
pub fn human_bytes(bytes: f64) -> String {
    if !bytes.is_finite() {
        return "an unbounded amount".into();
    }
    const UNITS: [&str; 5] = ["B", "kB", "MB", "GB", "TB"];
    let mut v = bytes;
    let mut u = 0;
    while v >= 1000.0 && u + 1 < UNITS.len() {
        v /= 1000.0;
        u += 1;
    }
    if v >= 1e4 {
        format!("{v:.1e} {}", UNITS[u])
    } else if u == 0 || v >= 100.0 {
        format!("{v:.0} {}", UNITS[u])
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

/// A duration for a person: "45 s", "12 min", "3.5 h", "41 days", "2.3e4 years".
pub fn human_duration(seconds: f64) -> String {
    if !seconds.is_finite() {
        return "forever".into();
    }
    let s = seconds.max(0.0);
    if s < 90.0 {
        format!("{s:.0} s")
    } else if s < 5400.0 {
        format!("{:.0} min", s / 60.0)
    } else if s < 2.0 * 86400.0 {
        format!("{:.1} h", s / 3600.0)
    } else if s < 365.25 * 86400.0 {
        format!("{:.0} days", s / 86400.0)
    } else {
        let y = s / (365.25 * 86400.0);
        if y < 1e4 {
            format!("{y:.0} years")
        } else {
            format!("{y:.1e} years")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_durations_read_at_a_glance() {
        assert_eq!(human_bytes(512.0), "512 B");
        assert_eq!(human_bytes(3.4e9), "3.4 GB");
        assert_eq!(human_bytes(5.36e11), "536 GB");
        assert_eq!(human_bytes(1e20), "1.0e8 TB");
        assert_eq!(human_duration(30.0), "30 s");
        assert_eq!(human_duration(720.0), "12 min");
        assert_eq!(human_duration(3.5 * 3600.0), "3.5 h");
        assert_eq!(human_duration(1e12), "3.2e4 years");
    }
}
