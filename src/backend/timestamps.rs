//! Turning raw timestamp query values into per-pass milliseconds.

/// GPU time of one scope (a pass, or the whole frame).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PassTiming {
    pub name: String,
    pub ms: f64,
}

/// Whether this device/queue can time passes at all.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum TimestampSupport {
    Supported {
        valid_bits: u32,
    },
    /// `timestampValidBits` is 0 on the queue: no timings can be taken.
    Unsupported,
}

/// Elapsed nanoseconds between two raw timestamps of a counter with `valid_bits` bits that may
/// have wrapped once between them. Bits above `valid_bits` are undefined, so they are masked.
pub fn elapsed_ns(start: u64, end: u64, valid_bits: u32, period_ns: f32) -> f64 {
    let mask = if valid_bits >= 64 {
        u64::MAX
    } else {
        (1u64 << valid_bits) - 1
    };
    let (s, e) = (start & mask, end & mask);
    let ticks = if e >= s { e - s } else { (mask - s) + e + 1 };
    ticks as f64 * period_ns as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elapsed_masks_and_wraps() {
        assert_eq!(elapsed_ns(100, 250, 64, 1.0), 150.0);
        // Garbage above 36 valid bits is ignored.
        let hi = 0xABCD_u64 << 40;
        assert_eq!(elapsed_ns(hi | 10, (hi << 1) | 30, 36, 2.0), 40.0);
        // A counter of 8 bits wrapping from 250 to 4 advanced by 10 ticks.
        assert_eq!(elapsed_ns(250, 4, 8, 1.0), 10.0);
    }
}
