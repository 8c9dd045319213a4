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
//! The device keeps the packed bytes ([`pack_for_device`]) and glsl/prt/shade.vert decodes them:
//! the transfer buffer is 5/16 of fp32's.

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

/// Coefficients per vertex in the device buffer (16: four bands; fewer are zero-padded, which
/// neither grouping's exponents notice).
pub const DEVICE_DIM: usize = 16;
/// 32-bit words per block of the device layout (see [`pack_for_device`]): one vertex by
/// vertex, four by band (5 bytes per 4 coefficients either way).
pub fn block_words(grouping: Grouping) -> usize {
    match grouping {
        Grouping::ByVertex => DEVICE_DIM * GROUP_BYTES / 4 / GROUP,
        Grouping::ByBand => DEVICE_DIM * GROUP_BYTES / 4,
    }
}

/// The device layout of `values` (`keys` × `vertices` × [`DEVICE_DIM`] coefficients), read by
/// glsl/prt/shade.vert, and the words each key takes.
///
/// * `None`: fp32, 16 words a vertex.
/// * By vertex: a block of 5 words a vertex: word g holds the mantissas of coefficients
///   4g … 4g + 3 (byte c for coefficient 4g + c), word 4 the four groups' exponents (byte g).
/// * By band: a block of 20 words per 4 vertices of a key (the last block zero-padded): word i
///   holds coefficient i's mantissas of the four vertices (byte = vertex mod 4), words 16 … 19
///   the 16 groups' exponents (group i in byte i mod 4 of word 16 + i / 4).
///
/// Both packed layouts are 5 bytes per 4 coefficients; a group is the one [`encode`] forms, so
/// the device decodes exactly the values [`decode`] returns.
pub fn pack_for_device(values: &[f32], keys: usize, vertices: usize, grouping: Option<Grouping>) -> (Vec<u32>, usize) {
    let Some(grouping) = grouping else {
        return (values.iter().map(|v| v.to_bits()).collect(), vertices * DEVICE_DIM);
    };
    let blocks = match grouping {
        Grouping::ByVertex => vertices,
        Grouping::ByBand => vertices.div_ceil(GROUP),
    };
    let per_key = blocks * block_words(grouping);
    let mut words = vec![0u32; keys * per_key];
    let mut padded = vec![0.0f32; blocks * GROUP * DEVICE_DIM];
    for k in 0..keys {
        let key = &values[k * vertices * DEVICE_DIM..(k + 1) * vertices * DEVICE_DIM];
        let bytes = match grouping {
            Grouping::ByVertex => encode(key, DEVICE_DIM, grouping),
            Grouping::ByBand => {
                padded[..key.len()].copy_from_slice(key);
                encode(&padded, DEVICE_DIM, grouping)
            }
        };
        let out = &mut words[k * per_key..(k + 1) * per_key];
        match grouping {
            Grouping::ByVertex => pack_by_vertex(&bytes, out),
            Grouping::ByBand => pack_by_band(&bytes, blocks, out),
        }
    }
    (words, per_key)
}

/// [`encode`]'s by-vertex groups (vertex-major, 4 per vertex) into 5-word blocks.
fn pack_by_vertex(bytes: &[u8], out: &mut [u32]) {
    for (k, group) in bytes.chunks_exact(GROUP_BYTES).enumerate() {
        let (v, g) = (k / 4, k % 4);
        let words = block_words(Grouping::ByVertex);
        let block = &mut out[v * words..(v + 1) * words];
        block[g] = u32::from_le_bytes([group[0], group[1], group[2], group[3]]);
        block[4] |= (group[GROUP] as u32) << (8 * g);
    }
}

/// [`encode`]'s by-band groups (coefficient-major, `blocks` per coefficient) into 20-word blocks.
fn pack_by_band(bytes: &[u8], blocks: usize, out: &mut [u32]) {
    for (k, group) in bytes.chunks_exact(GROUP_BYTES).enumerate() {
        let (i, b) = (k / blocks, k % blocks);
        let words = block_words(Grouping::ByBand);
        let block = &mut out[b * words..(b + 1) * words];
        block[i] = u32::from_le_bytes([group[0], group[1], group[2], group[3]]);
        block[DEVICE_DIM + i / 4] |= (group[GROUP] as u32) << (8 * (i % 4));
    }
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
