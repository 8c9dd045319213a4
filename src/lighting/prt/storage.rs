//! The document's compressed coefficient storage (§3.2, digest §1.9 and checklist): an
//! RGBE-like shared exponent per group of four coefficients, with signed 8-bit mantissas
//! (5 bytes for 4 coefficients against 16 in fp32). The document groups **by band**: the same
//! coefficient of four neighbouring vertices (similar magnitudes), rather than four coefficients
//! of one vertex (where T00 ≈ 0.9 sets the exponent of band-3 values a tenth its size).
//!
//! A group with exponent e stores `m_k = round(v_k / 2^e · 128)`, |m_k| ≤ 127, where 2^e is the
//! smallest power of two with the group's largest magnitude M at most 127.5/128 of it (so that
//! it rounds inside the range): every value comes back within half a step, 2^(e−8) < M/127.5
//! (a group whose M lies just below a power of two takes the next exponent; measured on the
//! bunny: 0.0078157·M, just over 1/128, tests/methods/prt_scenes.rs).
//! The transfer is decoded when loaded; the GPU keeps fp32 (what is measured is the storage's
//! error, which the chart shows in the image).

/// Coefficients per shared exponent.
pub const GROUP: usize = 4;
/// Bytes per group: four mantissas and the exponent.
pub const GROUP_BYTES: usize = GROUP + 1;

/// How coefficients are grouped under one exponent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Grouping {
    /// Coefficient i of vertices 4k … 4k + 3.
    ByBand,
    /// Coefficients 4k … 4k + 3 of one vertex.
    ByVertex,
}

/// One group's exponent and mantissas.
fn encode_group(values: &[f32]) -> [u8; GROUP_BYTES] {
    let max = values.iter().fold(0.0f32, |m, v| m.max(v.abs()));
    let mut out = [0u8; GROUP_BYTES];
    if max == 0.0 || !max.is_finite() {
        out[GROUP] = 0;
        return out;
    }
    // 2^e > max with max / 2^e · 128 ≤ 127.5, so the largest value rounds within range.
    let mut e = max.log2().floor() as i32 + 1;
    if max / 2f32.powi(e) * 128.0 > 127.5 {
        e += 1;
    }
    let e = e.clamp(-127, 127);
    let scale = 128.0 / 2f32.powi(e);
    for (k, v) in values.iter().enumerate() {
        out[k] = ((v * scale).round().clamp(-127.0, 127.0) as i8) as u8;
    }
    out[GROUP] = (e + 128) as u8;
    out
}

fn decode_group(bytes: &[u8], out: &mut [f32]) {
    let e = bytes[GROUP] as i32 - 128;
    let scale = 2f32.powi(e) / 128.0;
    for (k, o) in out.iter_mut().enumerate() {
        *o = (bytes[k] as i8) as f32 * scale;
    }
}

/// The groups of `dim`-coefficient vectors of `n` vertices, as lists of flat indices.
fn groups(n: usize, dim: usize, grouping: Grouping) -> Vec<Vec<usize>> {
    let mut out = Vec::new();
    match grouping {
        Grouping::ByBand => {
            for i in 0..dim {
                for first in (0..n).step_by(GROUP) {
                    out.push((first..(first + GROUP).min(n)).map(|v| v * dim + i).collect());
                }
            }
        }
        Grouping::ByVertex => {
            for v in 0..n {
                for first in (0..dim).step_by(GROUP) {
                    out.push((first..(first + GROUP).min(dim)).map(|i| v * dim + i).collect());
                }
            }
        }
    }
    out
}

/// The encoded bytes of `values` (`dim` per vertex).
pub fn encode(values: &[f32], dim: usize, grouping: Grouping) -> Vec<u8> {
    let n = values.len() / dim.max(1);
    let mut out = Vec::new();
    for g in groups(n, dim, grouping) {
        let v: Vec<f32> = g.iter().map(|&i| values[i]).collect();
        out.extend(encode_group(&v));
    }
    out
}

/// The values back from [`encode`]'s bytes (`None` when the sizes do not match).
pub fn decode(bytes: &[u8], n: usize, dim: usize, grouping: Grouping) -> Option<Vec<f32>> {
    let gs = groups(n, dim, grouping);
    if bytes.len() != gs.len() * GROUP_BYTES {
        return None;
    }
    let mut out = vec![0.0f32; n * dim];
    let mut tmp = [0.0f32; GROUP];
    for (k, g) in gs.iter().enumerate() {
        decode_group(&bytes[k * GROUP_BYTES..(k + 1) * GROUP_BYTES], &mut tmp);
        for (j, &i) in g.iter().enumerate() {
            out[i] = tmp[j];
        }
    }
    Some(out)
}

/// Errors of a round trip: the largest and the RMS absolute error, and the largest error
/// relative to its group's largest magnitude.
#[derive(Clone, Copy, Debug, Default)]
pub struct RoundTrip {
    pub max_abs: f64,
    pub rms: f64,
    pub max_over_group: f64,
    pub bytes: usize,
}

pub fn round_trip(values: &[f32], dim: usize, grouping: Grouping) -> RoundTrip {
    let n = values.len() / dim.max(1);
    let bytes = encode(values, dim, grouping);
    let back = decode(&bytes, n, dim, grouping).unwrap_or_default();
    let mut r = RoundTrip {
        bytes: bytes.len(),
        ..RoundTrip::default()
    };
    let mut sum = 0.0;
    for g in groups(n, dim, grouping) {
        let max = g.iter().fold(0.0f64, |m, &i| m.max(values[i].abs() as f64));
        for &i in &g {
            let e = (back[i] as f64 - values[i] as f64).abs();
            r.max_abs = r.max_abs.max(e);
            sum += e * e;
            if max > 0.0 {
                r.max_over_group = r.max_over_group.max(e / max);
            }
        }
    }
    r.rms = (sum / values.len().max(1) as f64).sqrt();
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Test 15: every value comes back within 1/127.5 of its group's largest magnitude (8-bit
    /// signed mantissas), zeros exactly, and the sizes are 5 bytes per 4 coefficients.
    #[test]
    fn shared_exponent_error_is_bounded() {
        let mut x = 12345u32;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x as f32 / u32::MAX as f32) * 2.0 - 1.0
        };
        let values: Vec<f32> = (0..16 * 257).map(|i| next() * 10f32.powi((i % 7) - 3)).collect();
        for grouping in [Grouping::ByBand, Grouping::ByVertex] {
            let r = round_trip(&values, 16, grouping);
            assert!(r.max_over_group <= 1.0 / 127.5, "{grouping:?}: {}", r.max_over_group);
            assert!(
                r.max_over_group > 1.0 / 1024.0,
                "{grouping:?}: a quantiser this fine is not 8 bits: {}",
                r.max_over_group
            );
            assert_eq!(
                r.bytes,
                if grouping == Grouping::ByBand {
                    16 * 257usize.div_ceil(4)
                } else {
                    257 * 4
                } * GROUP_BYTES
            );
        }
        let zeros = vec![0.0f32; 32];
        assert_eq!(
            decode(&encode(&zeros, 16, Grouping::ByBand), 2, 16, Grouping::ByBand).unwrap(),
            zeros
        );
        // The largest value of a group rounds inside the mantissa range.
        let edge = [0.999f32, 1.0, -1.0, 0.5];
        let back = decode(&encode(&edge, 4, Grouping::ByVertex), 1, 4, Grouping::ByVertex).unwrap();
        for (a, b) in edge.iter().zip(&back) {
            assert!((a - b).abs() <= 1.0 / 128.0, "{a} → {b}");
        }
    }
}
