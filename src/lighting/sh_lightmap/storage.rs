//! Storage of SH light-maps: range-encoded RGBA8 layers, float layers, VQ tables and index maps
//! (the Ca3D-Engine thesis §5.6, digest §1.6, §2.4, §5.3).
//!
//! Conventions: "n bands" means n² coefficients per texel; coefficient vectors are texel-major
//! `&[f32]` (texel t's coefficients at `t·n² .. (t+1)·n²`, texels row-major). Every texture packs
//! four coefficients per RGBA texel, so a texel's vector spans `P = ⌈n²/4⌉` RGBA values.

use std::fmt;

use crate::sh::MAX_BANDS;

/// Most representatives a codebook may hold: the index map stores 16-bit indices (R = low byte,
/// G = high byte), so 2^16 entries are addressable.
pub const MAX_REPS: usize = 1 << 16;

/// Height of the representative table: one row per value of an index's low byte. Cutting the
/// table every 256 entries is what lets a shader address it with the two index bytes directly,
/// without rebuilding a 16-bit integer in float arithmetic (the seed's "fatal" rounding, §5.6.2).
pub const TABLE_HEIGHT: u32 = 256;

/// Bytes per kB in the seed's Table 4 (its numbers only fit with kB = 1024 B).
pub const KB: u64 = 1024;

/// Everything the packers can reject.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum StorageError {
    #[error("band count {0} is outside 1..={MAX_BANDS}")]
    Bands(usize),
    #[error("representative count {0} is outside 1..={MAX_REPS} (indices are 16 bits)")]
    Reps(usize),
    #[error("{what}: expected {expected} values, got {got}")]
    Length {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    #[error("{width}×{height} texels overflow the address space")]
    Size { width: u32, height: u32 },
}

/// Result type of this module.
pub type StorageResult<T> = Result<T, StorageError>;

/// RGBA layers (or table pixels) per texel vector: `⌈n²/4⌉`.
pub fn layers(bands: usize) -> usize {
    (bands * bands).div_ceil(4)
}

/// The seed's range compression of a coefficient into a byte: `round((c/4 + 0.5)·255)`, which
/// maps [−2, 2] onto 0..=255. Values outside ±2 clamp (the seed normalises transfers to
/// |c| ≤ 1, so clamping means something upstream went wrong, not lost precision). NaN encodes
/// 128, the byte nearest 0, so a bad coefficient darkens nothing rather than saturating.
pub fn encode_range(c: f32) -> u8 {
    if c.is_nan() {
        return 128;
    }
    ((c / 4.0 + 0.5) * 255.0).round().clamp(0.0, 255.0) as u8
}

/// Inverse of [`encode_range`], as the seed's shaders do it: `4·(t/255 − 0.5)`. The round trip
/// is within half a step, 2/255, for |c| ≤ 2.
pub fn decode_range(t: u8) -> f32 {
    4.0 * (f32::from(t) / 255.0 - 0.5)
}

fn check_bands(bands: usize) -> StorageResult<usize> {
    if (1..=MAX_BANDS).contains(&bands) {
        Ok(bands * bands)
    } else {
        Err(StorageError::Bands(bands))
    }
}

fn texel_count(width: u32, height: u32) -> StorageResult<usize> {
    (width as usize)
        .checked_mul(height as usize)
        .ok_or(StorageError::Size { width, height })
}

/// Native (uncompressed) storage: `⌈n²/4⌉` layers one after the other, each `width×height` RGBA
/// values row-major; layer k holds coefficients `4k .. 4k+3` of every texel, and coefficients
/// past n² (the last layer's padding) encode 0. `encode` maps one coefficient to a channel.
fn pack_layers<T: Copy>(
    coeffs: &[f32],
    bands: usize,
    width: u32,
    height: u32,
    encode: impl Fn(f32) -> T,
) -> StorageResult<Vec<T>> {
    let dim = check_bands(bands)?;
    let texels = texel_count(width, height)?;
    let expected = texels.checked_mul(dim).ok_or(StorageError::Size { width, height })?;
    if coeffs.len() != expected {
        return Err(StorageError::Length {
            what: "SH light-map coefficients (texels·n²)",
            expected,
            got: coeffs.len(),
        });
    }
    let p = layers(bands);
    let zero = encode(0.0);
    let mut out = vec![zero; p * texels * 4];
    // One texel's coefficients are contiguous in the input and scattered over the layers in the
    // output, so walk the input once and write each group of four where its layer wants it.
    for (t, vector) in coeffs.chunks_exact(dim).enumerate() {
        for (k, group) in vector.chunks(4).enumerate() {
            let at = (k * texels + t) * 4;
            for (dst, &c) in out[at..at + group.len()].iter_mut().zip(group) {
                *dst = encode(c);
            }
        }
    }
    Ok(out)
}

/// Native SHL-map as RGBA8 layers with the seed's range encoding (see [`pack_layers_f32`] for
/// the layout). This is what the seed's native renderer uploads: 1 byte per coefficient.
pub fn pack_layers_rgba8(coeffs: &[f32], bands: usize, width: u32, height: u32) -> StorageResult<Vec<u8>> {
    pack_layers(coeffs, bands, width, height, encode_range)
}

/// Native SHL-map as RGBA16F layers (raw `f16` bits), for a corrected mode that keeps the
/// coefficients' range and sign without the ±2 clamp at half the memory of f32.
pub fn pack_layers_f16(coeffs: &[f32], bands: usize, width: u32, height: u32) -> StorageResult<Vec<u16>> {
    pack_layers(coeffs, bands, width, height, |c| half::f16::from_f32(c).to_bits())
}

/// Native SHL-map as RGBA32F layers: `⌈n²/4⌉` layers one after the other, each `width×height`
/// texels row-major; layer k's RGBA are coefficients `4k .. 4k+3` of the texel, 0 past n².
pub fn pack_layers_f32(coeffs: &[f32], bands: usize, width: u32, height: u32) -> StorageResult<Vec<f32>> {
    pack_layers(coeffs, bands, width, height, |c| c)
}

/// Size of the representative table for `reps` representatives of n bands:
/// `(nextPow2(⌈reps/256⌉·⌈n²/4⌉), 256)`, CAFU's layout (Fig. 21: 4096 reps at 4 bands → 64×256).
/// The power-of-two width was an old-hardware requirement; it is kept so table sizes match the
/// seed's. Rejects counts a 16-bit index cannot address and band counts outside the SH module's.
pub fn table_size(reps: usize, bands: usize) -> StorageResult<(u32, u32)> {
    check_bands(bands)?;
    if !(1..=MAX_REPS).contains(&reps) {
        return Err(StorageError::Reps(reps));
    }
    // At most 256 columns × 64 pixels (16 bands): no overflow is possible past the checks.
    let width = (reps.div_ceil(TABLE_HEIGHT as usize) * layers(bands)).next_power_of_two();
    Ok((width as u32, TABLE_HEIGHT))
}

/// Pixel `(x, y)` of representative r's k-th group of four coefficients (`k < ⌈n²/4⌉`). The
/// shader does the same integer arithmetic on the index map's bytes: `x = (r >> 8)·P + k`,
/// `y = r & 255`, then `texelFetch` — exact, unlike the seed's normalised coordinates, which
/// address texel edges and rely on rounding (digest §1.6, DERIVED note).
pub fn table_texel(r: u16, k: usize, bands: usize) -> (u32, u32) {
    let r = usize::from(r);
    let x = (r / TABLE_HEIGHT as usize) * layers(bands) + k;
    (x as u32, (r % TABLE_HEIGHT as usize) as u32)
}

/// The representative table: representative r in row `r % 256`, pixels `(r / 256)·P + k` for
/// `k < P = ⌈n²/4⌉`, each RGBA = coefficients `4k .. 4k+3`; everything else encodes 0.
fn pack_table<T: Copy>(codebook: &[f32], bands: usize, encode: impl Fn(f32) -> T) -> StorageResult<(u32, u32, Vec<T>)> {
    let dim = check_bands(bands)?;
    if !codebook.len().is_multiple_of(dim) {
        let expected = codebook.len().div_ceil(dim) * dim;
        return Err(StorageError::Length {
            what: "codebook (representatives·n²)",
            expected,
            got: codebook.len(),
        });
    }
    let reps = codebook.len() / dim;
    let (width, height) = table_size(reps, bands)?;
    let mut out = vec![encode(0.0); width as usize * height as usize * 4];
    for (r, vector) in codebook.chunks_exact(dim).enumerate() {
        // r < MAX_REPS, checked by table_size.
        for (k, group) in vector.chunks(4).enumerate() {
            let (x, y) = table_texel(r as u16, k, bands);
            let at = (y as usize * width as usize + x as usize) * 4;
            for (dst, &c) in out[at..at + group.len()].iter_mut().zip(group) {
                *dst = encode(c);
            }
        }
    }
    Ok((width, height, out))
}

/// The representative table as RGBA8 with the seed's range encoding: `(width, height, bytes)`.
/// Unused pixels are 128 (≈ 0). See [`table_size`] and [`table_texel`] for the layout.
pub fn pack_table_rgba8(codebook: &[f32], bands: usize) -> StorageResult<(u32, u32, Vec<u8>)> {
    pack_table(codebook, bands, encode_range)
}

/// The representative table as RGBA32F, same layout as [`pack_table_rgba8`], for a corrected
/// mode: the table is small (≤ 16384×256 pixels), so exact coefficients cost little, and the
/// range clamp and 8-bit steps then no longer add to the quantisation error.
pub fn pack_table_f32(codebook: &[f32], bands: usize) -> StorageResult<(u32, u32, Vec<f32>)> {
    pack_table(codebook, bands, |c| c)
}

/// The index map, same layout as the SHL-map: per texel R = low byte, G = high byte of its
/// representative's index, B = 0, A = 255. Two separate bytes rather than one 16-bit channel
/// because the table's 2-D layout is addressed by those bytes separately (see [`table_texel`]).
pub fn pack_indices_rgba8(indices: &[u16]) -> Vec<u8> {
    indices
        .iter()
        .flat_map(|&i| {
            let [low, high] = i.to_le_bytes();
            [low, high, 0, 255]
        })
        .collect()
}

/// A world's SH storage under the seed's model (Table 4, digest §2.4) and what penumbra uploads.
///
/// The model counts 4-byte floats per stored coefficient and 2 bytes per texel index; with
/// kB = 1024 B it reproduces DmBase's file sizes exactly (S = 307,200 texels), so it is the
/// accounting to compare against the seed's compression ratios. The GPU figure is separate
/// because the GPU layout differs: RGBA8 coefficients, padded layers, a 4-byte index texel and a
/// power-of-two table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StorageReport {
    /// SHL texels S (vectors).
    pub texels: usize,
    /// SH bands n (n² coefficients per texel).
    pub bands: usize,
    /// Representatives |R|; 0 = uncompressed (the seed's "0 Reps.").
    pub reps: usize,
    /// Seed model: `S·n²·4` uncompressed, `S·2 + |R|·n²·4` compressed.
    pub payload_bytes_model: u64,
    /// Bytes uploaded: RGBA8 layers `S·4·P` uncompressed, or the RGBA8 index map `S·4` plus the
    /// RGBA8 table `W·256·4` compressed.
    pub gpu_bytes: u64,
}

impl StorageReport {
    /// Native storage of `texels` vectors of n bands.
    pub fn uncompressed(texels: usize, bands: usize) -> StorageResult<StorageReport> {
        let dim = check_bands(bands)? as u64;
        let s = texels as u64;
        Ok(StorageReport {
            texels,
            bands,
            reps: 0,
            payload_bytes_model: s * dim * 4,
            gpu_bytes: s * 4 * layers(bands) as u64,
        })
    }

    /// VQ-compressed storage: `reps` representatives plus one index per texel.
    pub fn compressed(texels: usize, bands: usize, reps: usize) -> StorageResult<StorageReport> {
        let (width, height) = table_size(reps, bands)?;
        let (s, dim) = (texels as u64, (bands * bands) as u64);
        let payload_bytes_model = s * 2 + reps as u64 * dim * 4;
        let gpu_bytes = s * 4 + u64::from(width) * u64::from(height) * 4;
        Ok(StorageReport {
            texels,
            bands,
            reps,
            payload_bytes_model,
            gpu_bytes,
        })
    }
}

/// The seed's compression ratio: model payload of the uncompressed world over the compressed
/// one (Table 4 subtracts the no-SHL file; the model has no base to subtract).
pub fn compression_ratio(uncompressed: &StorageReport, compressed: &StorageReport) -> f64 {
    uncompressed.payload_bytes_model as f64 / compressed.payload_bytes_model as f64
}

impl fmt::Display for StorageReport {
    /// One row like the seed's Table 4: `307200 texels | 4 SH bands | 4096 Reps. | payload 856 kB | GPU 1264 kB`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let kb = |b: u64| b as f64 / KB as f64;
        write!(f, "{} texels | {} SH bands | ", self.texels, self.bands)?;
        if self.reps == 0 {
            write!(f, "0 Reps. (no compression)")?;
        } else {
            write!(f, "{} Reps.", self.reps)?;
        }
        write!(
            f,
            " | payload {:.0} kB | GPU {:.0} kB",
            kb(self.payload_bytes_model),
            kb(self.gpu_bytes)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// DmBase's SHL texel count implied by Table 4's 600 kB of 16-bit indices.
    const DMBASE_TEXELS: usize = 307_200;

    #[test]
    fn layers_are_groups_of_four_coefficients() {
        assert_eq!([1, 2, 3, 4, 5, 8].map(layers), [1, 1, 3, 4, 7, 16]);
    }

    #[test]
    fn range_round_trip_is_within_half_a_step() {
        let steps = 200_000;
        let worst = (0..=steps)
            .map(|i| -2.0 + 4.0 * i as f32 / steps as f32)
            .map(|c| (decode_range(encode_range(c)) - c).abs())
            .fold(0.0f32, f32::max);
        assert!(worst <= 2.0 / 255.0 + 1e-6, "worst round-trip error {worst}");
        // The bound is tight: a value midway between two codes is half a step off.
        assert!(worst >= 2.0 / 255.0 - 1e-4, "worst round-trip error {worst}");
        assert_eq!((encode_range(-2.0), encode_range(2.0)), (0, 255));
        assert_eq!(decode_range(0), -2.0);
        assert_eq!(decode_range(255), 2.0);
    }

    #[test]
    fn range_clamps_outside_two_and_maps_nan_to_zero() {
        for c in [2.01, 3.0, 1e9, f32::INFINITY] {
            assert_eq!(encode_range(c), 255, "{c}");
            assert_eq!(encode_range(-c), 0, "{}", -c);
        }
        assert_eq!(encode_range(f32::NAN), 128);
        assert_eq!(encode_range(0.0), 128);
        assert!(decode_range(128).abs() <= 2.0 / 255.0 + 1e-6);
    }

    #[test]
    fn native_layers_hold_four_coefficients_each_and_pad_with_zero() {
        // 3 bands = 9 coefficients → 3 layers, the last with one coefficient and three zeros.
        let (width, height, bands) = (3u32, 2u32, 3);
        let texels = (width * height) as usize;
        let coeffs: Vec<f32> = (0..texels * 9).map(|i| (i as f32 - 27.0) / 16.0).collect();
        let bytes = pack_layers_rgba8(&coeffs, bands, width, height).unwrap();
        let floats = pack_layers_f32(&coeffs, bands, width, height).unwrap();
        let halves = pack_layers_f16(&coeffs, bands, width, height).unwrap();
        assert_eq!(bytes.len(), 3 * texels * 4);
        assert_eq!((floats.len(), halves.len()), (bytes.len(), bytes.len()));
        for t in 0..texels {
            for k in 0..3 {
                for ch in 0..4 {
                    let at = (k * texels + t) * 4 + ch;
                    let i = 4 * k + ch;
                    let c = if i < 9 { coeffs[t * 9 + i] } else { 0.0 };
                    assert_eq!(bytes[at], encode_range(c), "texel {t} layer {k} channel {ch}");
                    assert_eq!(floats[at], c, "texel {t} layer {k} channel {ch}");
                    assert_eq!(
                        halves[at],
                        half::f16::from_f32(c).to_bits(),
                        "texel {t} layer {k} channel {ch}"
                    );
                }
            }
        }
    }

    #[test]
    fn packers_reject_bad_lengths_and_bands() {
        assert!(matches!(
            pack_layers_rgba8(&[0.0; 15], 4, 1, 1),
            Err(StorageError::Length {
                expected: 16,
                got: 15,
                ..
            })
        ));
        assert_eq!(pack_layers_f32(&[], 0, 1, 1), Err(StorageError::Bands(0)));
        assert!(matches!(
            pack_table_rgba8(&[0.0; 17], 4),
            Err(StorageError::Length { .. })
        ));
        assert_eq!(pack_table_f32(&[], 4).map(|t| t.0), Err(StorageError::Reps(0)));
        assert_eq!(table_size(MAX_REPS + 1, 4), Err(StorageError::Reps(MAX_REPS + 1)));
        assert_eq!(table_size(16, MAX_BANDS + 1), Err(StorageError::Bands(MAX_BANDS + 1)));
    }

    #[test]
    fn table_size_follows_cafu() {
        assert_eq!(table_size(4096, 4), Ok((64, 256)));
        // 1 column of 3 pixels (3 bands) rounds up to 4.
        assert_eq!(table_size(1, 3), Ok((4, 256)));
        assert_eq!(table_size(257, 4), Ok((8, 256)));
        assert_eq!(table_size(16384, 8), Ok((1024, 256)));
        assert_eq!(table_size(MAX_REPS, MAX_BANDS), Ok((16384, 256)));
    }

    #[test]
    fn table_puts_every_representative_at_its_documented_pixels() {
        let (reps, bands) = (4096, 4);
        let codebook: Vec<f32> = (0..reps * 16)
            .map(|i| ((i * 37 % 509) as f32 / 509.0) * 4.0 - 2.0)
            .collect();
        let (width, height, bytes) = pack_table_rgba8(&codebook, bands).unwrap();
        let (fw, fh, floats) = pack_table_f32(&codebook, bands).unwrap();
        assert_eq!((width, height, fw, fh), (64, 256, 64, 256));
        assert_eq!((bytes.len(), floats.len()), (64 * 256 * 4, 64 * 256 * 4));
        let mut touched = vec![false; 64 * 256];
        for r in 0..reps {
            for k in 0..4 {
                let (x, y) = table_texel(r as u16, k, bands);
                // The shader's integer arithmetic on the index bytes.
                assert_eq!((x, y), (((r >> 8) * 4 + k) as u32, (r & 255) as u32));
                let pixel = y as usize * 64 + x as usize;
                assert!(!touched[pixel], "two representatives share pixel ({x}, {y})");
                touched[pixel] = true;
                let expected = &codebook[r * 16 + 4 * k..r * 16 + 4 * k + 4];
                assert_eq!(&floats[pixel * 4..pixel * 4 + 4], expected, "rep {r} group {k}");
                let encoded: Vec<u8> = expected.iter().map(|&c| encode_range(c)).collect();
                assert_eq!(&bytes[pixel * 4..pixel * 4 + 4], &encoded[..], "rep {r} group {k}");
            }
        }
        // 4096 reps fill the table exactly.
        assert!(touched.iter().all(|&t| t));
    }

    #[test]
    fn table_pads_unused_pixels_and_channels_with_zero() {
        // 3 reps of 3 bands: 9 coefficients → 3 pixels, the last with 3 padding channels;
        // the 4th column pixel and rows 3.. are unused.
        let codebook: Vec<f32> = (0..27).map(|i| i as f32 / 16.0 - 0.8).collect();
        let (width, height, bytes) = pack_table_rgba8(&codebook, 3).unwrap();
        let (_, _, floats) = pack_table_f32(&codebook, 3).unwrap();
        assert_eq!((width, height), (4, 256));
        for y in 0..256usize {
            for x in 0..4usize {
                for ch in 0..4 {
                    let at = (y * 4 + x) * 4 + ch;
                    let i = 4 * x + ch;
                    let c = if y < 3 && x < 3 && i < 9 {
                        codebook[y * 9 + i]
                    } else {
                        0.0
                    };
                    assert_eq!(floats[at], c, "pixel ({x}, {y}) channel {ch}");
                    assert_eq!(bytes[at], encode_range(c), "pixel ({x}, {y}) channel {ch}");
                }
            }
        }
    }

    #[test]
    fn index_map_is_low_byte_high_byte() {
        let bytes = pack_indices_rgba8(&[0, 1, 255, 256, 0x1234, 65535]);
        assert_eq!(
            bytes,
            [0, 0, 0, 255, 1, 0, 0, 255, 255, 0, 0, 255, 0, 1, 0, 255, 0x34, 0x12, 0, 255, 255, 255, 0, 255]
        );
        // Every index survives the two bytes.
        let all: Vec<u16> = (0..=u16::MAX).collect();
        let bytes = pack_indices_rgba8(&all);
        assert!(all
            .iter()
            .zip(bytes.chunks_exact(4))
            .all(|(&i, px)| u16::from(px[0]) | u16::from(px[1]) << 8 == i));
    }

    #[test]
    fn storage_model_reproduces_dmbase() {
        let kb = |r: StorageReport| r.payload_bytes_model / KB;
        let native = StorageReport::uncompressed(DMBASE_TEXELS, 4).unwrap();
        let small = StorageReport::compressed(DMBASE_TEXELS, 4, 4096).unwrap();
        let large = StorageReport::compressed(DMBASE_TEXELS, 4, 16384).unwrap();
        let eight = StorageReport::compressed(DMBASE_TEXELS, 8, 16384).unwrap();
        assert_eq!(
            [native, small, large, eight].map(|r| r.payload_bytes_model % KB),
            [0; 4]
        );
        assert_eq!([kb(native), kb(small), kb(large), kb(eight)], [19_200, 856, 1624, 4696]);
        assert!((compression_ratio(&native, &large) - 19_200.0 / 1624.0).abs() < 1e-12);
        // The seed's 11.83 is this ratio with the file's 12 kB of headers on the native side.
        assert_eq!(format!("{:.2}", (19_200.0 + 12.0) / 1624.0), "11.83");
        // Uploaded: 4 RGBA8 layers; or a 4-byte index texel plus the 64×256 / 1024×256 table.
        assert_eq!(native.gpu_bytes, 307_200 * 16);
        assert_eq!(small.gpu_bytes, 307_200 * 4 + 64 * 256 * 4);
        assert_eq!(eight.gpu_bytes, 307_200 * 4 + 1024 * 256 * 4);
        assert_eq!(
            small.to_string(),
            "307200 texels | 4 SH bands | 4096 Reps. | payload 856 kB | GPU 1264 kB"
        );
        assert_eq!(
            native.to_string(),
            "307200 texels | 4 SH bands | 0 Reps. (no compression) | payload 19200 kB | GPU 4800 kB"
        );
    }
}
