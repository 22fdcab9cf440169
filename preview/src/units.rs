//! Numbers as people read them: bytes in KB and MB, times in ms and s, shares in %.
//! Shared by the preview pages and `frond sweep`'s charts.

/// Bytes with a binary unit (1 KB = 1024 bytes, as engines and file browsers count texture
/// memory): `812 B`, `3.4 KB`, `12 MB`. Three significant digits at most.
pub fn bytes(n: f64) -> String {
    const UNITS: [&str; 4] = ["B", "KB", "MB", "GB"];
    let mut v = n;
    let mut unit = 0;
    while v.abs() >= 1024.0 && unit + 1 < UNITS.len() {
        v /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{} B", v.round())
    } else {
        format!("{} {}", significant(v), UNITS[unit])
    }
}

/// Seconds as `850 ms`, `2.4 s` or `3 min 20 s`.
pub fn duration(seconds: f64) -> String {
    if seconds < 1.0 {
        format!("{} ms", significant(seconds * 1000.0))
    } else if seconds < 120.0 {
        format!("{} s", significant(seconds))
    } else {
        let m = (seconds / 60.0).floor();
        format!("{m} min {} s", (seconds - 60.0 * m).round())
    }
}

/// A count with thousands separated by thin spaces: `116 208`.
pub fn count(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push('\u{2009}');
        }
        out.push(c);
    }
    out
}

/// `x` with 4 significant digits, in scientific notation outside 1e-4 to 1e6: how the sweep's
/// tables and chart ticks write a number.
pub fn four_significant(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let mag = x.abs().log10().floor() as i32;
    if !(-4..6).contains(&mag) {
        return format!("{x:.3e}");
    }
    let decimals = (3 - mag).max(0) as usize;
    format!("{x:.decimals$}")
}

/// `v` with three significant digits, no trailing zeros: 3.40 → `3.4`, 812.4 → `812`.
pub fn significant(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_read_as_people_write_them() {
        assert_eq!(bytes(812.0), "812 B");
        assert_eq!(bytes(3481.6), "3.4 KB");
        assert_eq!(bytes(524288.0), "512 KB");
        assert_eq!(bytes(12.0 * 1024.0 * 1024.0), "12 MB");
        assert_eq!(bytes(1536.0 * 1024.0), "1.5 MB");
    }

    #[test]
    fn durations_and_counts() {
        assert_eq!(duration(0.85), "850 ms");
        assert_eq!(duration(2.44), "2.44 s");
        assert_eq!(duration(200.0), "3 min 20 s");
        assert_eq!(count(116208), "116\u{2009}208");
        assert_eq!(count(999), "999");
        assert_eq!(significant(0.01234), "0.0123");
    }
}
