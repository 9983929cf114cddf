//! The time alignment of bag topics (`session::align`) on arbitrary stamps, against a plain
//! search: the nearest message is the one of least distance (the earlier stamp on a tie),
//! and only within the tolerance; the default tolerance is half the median period.
//!
//! Input: a mode byte (bit 0: 64-bit stamps, else 16-bit ones, which repeat and tie more
//! often; the other bits: where the reference ends), then the query time, the tolerance and
//! the stamps.
#![no_main]

use libfuzzer_sys::fuzz_target;
use tactile_workbench::session::align::{default_tolerance, nearest};

fn nearest_by_search(stamps: &[u64], t: u64, tolerance: u64) -> Option<u64> {
    stamps
        .iter()
        .map(|&s| (s.abs_diff(t), s))
        .min()
        .filter(|&(d, _)| d <= tolerance)
        .map(|(_, s)| s)
}

fuzz_target!(|data: &[u8]| {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    let values: Vec<u64> = if mode & 1 == 1 {
        rest.chunks_exact(8)
            .map(|c| u64::from_le_bytes(c.try_into().unwrap_or_default()))
            .collect()
    } else {
        rest.chunks_exact(2)
            .map(|c| u64::from(u16::from_le_bytes([c[0], c[1]])))
            .collect()
    };
    let [t, tolerance, stamps @ ..] = values.as_slice() else {
        return;
    };
    let split = usize::from(mode >> 1) % (stamps.len() + 1);
    let mut reference = stamps[..split].to_vec();
    let mut other = stamps[split..].to_vec();
    reference.sort_unstable();
    other.sort_unstable();

    let mut periods: Vec<u64> = reference.windows(2).map(|w| w[1] - w[0]).collect();
    periods.sort_unstable();
    let median_half = periods.get(periods.len() / 2).map_or(0, |p| p / 2);
    assert_eq!(default_tolerance(&reference), median_half);

    let check = |t: u64, tolerance: u64| {
        let got = nearest(&other, t, tolerance).map(|i| other[i]);
        assert_eq!(
            got,
            nearest_by_search(&other, t, tolerance),
            "t {t}, tolerance {tolerance}"
        );
    };
    check(*t, *tolerance);
    for &r in &reference {
        check(r, median_half);
    }
});
