//! LDR-ꟻLIP (Andersson et al. 2020, "FLIP: A Difference Evaluator for Alternating Images",
//! HPG 2020), implemented from the paper's description and checked against NVIDIA's
//! published reference implementation (NVlabs/flip) for its constants and border handling.
//!
//! Both images are first put through the display transform penumbra uses for PNGs, stopping
//! before the sRGB encoding: c ↦ aces_fit(c · exposure), linear in [0, 1]. (ꟻLIP decodes sRGB
//! input to linear as its first step, so skipping the encode/decode pair is equivalent, minus
//! the 8-bit quantisation of a PNG.) Then, per image:
//!
//! * colour pipeline: linear RGB → YCxCz; each opponent channel is convolved with the spatial
//!   filter of its contrast sensitivity function (CSF), a sum of Gaussians
//!   S(x) = a₁·√(π/b₁)·exp(−π²x²/b₁) + a₂·√(π/b₂)·exp(−π²x²/b₂), x in degrees, normalised to
//!   unit sum; back to linear RGB, clamped to [0, 1]; → L*a*b* → Hunt adjustment.
//! * feature pipeline: on the luminance y = (Y + 16)/116 of the unfiltered YCxCz, edge (first
//!   derivative of Gaussian) and point (second derivative) detectors with σ = ½·0.082°,
//!   kernel radius ⌈3σ⌉ pixels, positive weights normalised to sum 1 and negative to −1.
//!
//! and per pixel:
//!
//! * ΔE_c = redistribute(HyAB(ref, test)^q_c): errors below p_c·c_max map linearly to
//!   [0, p_t], the rest linearly from p_t to 1 at c_max, with c_max = HyAB(green, blue)^q_c in
//!   Hunt-adjusted L*a*b*;
//! * ΔE_f = (max(|‖edge_ref‖ − ‖edge_test‖|, |‖point_ref‖ − ‖point_test‖|) / √2)^q_f;
//! * ΔE = ΔE_c^(1 − ΔE_f).
//!
//! All convolutions clamp to the edge (replicate the border pixel), as the reference does: this
//! keeps constant images constant under the CSF filters and gives them zero feature response.
//! The 2D kernels are all separable (the blue-yellow CSF as a weighted sum of two separable
//! Gaussians), so they are applied as row and column passes with the exact same weights as the
//! 2D kernels would have.
//!
//! Against NVIDIA's own implementation (flip-evaluator 1.7, LDR, linear input) this code agrees
//! to within 1.1e-5 per pixel on the pattern of `flip_matches_nvidia_reference_implementation`.

use super::color::{hunt, hyab, linear_rgb_to_lab, linear_rgb_to_xyz, xyz_to_linear_rgb, xyz_to_ycxcz, ycxcz_to_xyz};
use super::{CompareOptions, MetricsError};
use crate::util::image_io::{aces_fit, HdrImage};

/// Colour-error exponent q_c.
pub const QC: f32 = 0.7;
/// Feature-error exponent q_f.
pub const QF: f32 = 0.5;
/// Fraction p_c of c_max below which colour errors are mapped to [0, p_t].
pub const PC: f32 = 0.4;
/// Share p_t of [0, 1] given to colour errors below p_c·c_max.
pub const PT: f32 = 0.95;
/// Peak-to-trough width (2σ) of the human edge detector, in degrees.
pub const FEATURE_WIDTH_DEG: f32 = 0.082;

/// Parameters of one contrast sensitivity function as a sum of two Gaussians (see module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Csf {
    pub a1: f32,
    pub b1: f32,
    pub a2: f32,
    pub b2: f32,
}

/// Achromatic CSF. b2 is a placeholder (a2 = 0) that avoids a division by zero.
pub const CSF_A: Csf = Csf {
    a1: 1.0,
    b1: 0.0047,
    a2: 0.0,
    b2: 1e-5,
};
/// Red-green CSF.
pub const CSF_RG: Csf = Csf {
    a1: 1.0,
    b1: 0.0053,
    a2: 0.0,
    b2: 1e-5,
};
/// Blue-yellow CSF.
pub const CSF_BY: Csf = Csf {
    a1: 34.1,
    b1: 0.04,
    a2: 13.5,
    b2: 0.025,
};

/// Per-pixel FLIP errors in [0, 1], rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct FlipMap {
    pub width: u32,
    pub height: u32,
    pub values: Vec<f32>,
}

impl FlipMap {
    /// Mean over pixels, accumulated in f64; 0 for an empty map.
    pub fn mean(&self) -> f64 {
        if self.values.is_empty() {
            return 0.0;
        }
        self.values.iter().map(|&v| f64::from(v)).sum::<f64>() / self.values.len() as f64
    }
}

/// The per-pixel FLIP map of `test` against `reference` (same validation as `compare`).
pub fn flip_error_map(test: &HdrImage, reference: &HdrImage, opts: &CompareOptions) -> Result<FlipMap, MetricsError> {
    super::validate(test, reference, opts)?;
    Ok(flip_map_unchecked(test, reference, opts))
}

/// c_max = HyAB(Hunt(Lab(green)), Hunt(Lab(blue)))^q_c: the largest colour difference FLIP
/// expects between two in-gamut colours, used to normalise ΔE_c.
pub fn cmax() -> f32 {
    let green = hunt(linear_rgb_to_lab([0.0, 1.0, 0.0]));
    let blue = hunt(linear_rgb_to_lab([0.0, 0.0, 1.0]));
    hyab(green, blue).powf(QC)
}

/// Maps an exponentiated HyAB distance to [0, 1]: the first p_c of the range [0, c_max]
/// takes the share p_t, so small and medium errors are spread out and only the largest
/// approach 1.
pub fn redistribute(power_hyab: f32, cmax: f32) -> f32 {
    let pccmax = PC * cmax;
    if power_hyab < pccmax {
        PT / pccmax * power_hyab
    } else {
        PT + (power_hyab - pccmax) / (cmax - pccmax) * (1.0 - PT)
    }
}

/// Inputs must already be validated (same size, buffers match, finite, ppd > 0).
pub(crate) fn flip_map_unchecked(test: &HdrImage, reference: &HdrImage, opts: &CompareOptions) -> FlipMap {
    let (w, h) = (test.width as usize, test.height as usize);
    let filters = Filters::new(opts.pixels_per_degree);
    // The two images are independent until the per-pixel comparison; on penumbra's 2-core
    // machines preparing them side by side halves the wall time.
    let (r, t) = std::thread::scope(|s| {
        let handle = s.spawn(|| prepare(reference, opts.exposure, &filters, w, h));
        let t = prepare(test, opts.exposure, &filters, w, h);
        let r = handle.join().unwrap_or_else(|e| std::panic::resume_unwind(e));
        (r, t)
    });
    let cmax = cmax();
    let values = (0..w * h)
        .map(|i| {
            let color = redistribute(hyab(r.lab[i], t.lab[i]).powf(QC), cmax);
            let edge = (r.edge[i] - t.edge[i]).abs();
            let point = (r.point[i] - t.point[i]).abs();
            let feature = (edge.max(point) * std::f32::consts::FRAC_1_SQRT_2).powf(QF);
            color.powf(1.0 - feature)
        })
        .collect();
    FlipMap {
        width: test.width,
        height: test.height,
        values,
    }
}

/// What the per-pixel comparison needs from one image.
struct Prepared {
    /// Hunt-adjusted L*a*b* of the CSF-filtered image.
    lab: Vec<[f32; 3]>,
    /// Magnitude of the (x, y) edge-detector response.
    edge: Vec<f32>,
    /// Magnitude of the (x, y) point-detector response.
    point: Vec<f32>,
}

fn prepare(img: &HdrImage, exposure: f32, f: &Filters, w: usize, h: usize) -> Prepared {
    let n = w * h;
    let mut opp = [vec![0.0f32; n], vec![0.0f32; n], vec![0.0f32; n]];
    for (i, p) in img.pixels.iter().enumerate() {
        // The ACES fit is saturated (exactly 1) from about 7.3 on, but its x² terms overflow
        // f32 above ~1e19 and give inf/inf = NaN; capping the input keeps huge (finite)
        // fireflies white.
        let rgb = [0, 1, 2].map(|c| aces_fit((p[c] * exposure).min(1.0e4)));
        let ycxcz = xyz_to_ycxcz(linear_rgb_to_xyz(rgb));
        for c in 0..3 {
            opp[c][i] = ycxcz[c];
        }
    }
    let lum: Vec<f32> = opp[0].iter().map(|&y| (y + 16.0) / 116.0).collect();

    let [y, cx, cz] = opp;
    let (y, cx, cz) = (
        f.csf_a.apply(&y, w, h),
        f.csf_rg.apply(&cx, w, h),
        f.csf_by.apply(&cz, w, h),
    );
    let lab = (0..n)
        .map(|i| {
            let rgb = xyz_to_linear_rgb(ycxcz_to_xyz([y[i], cx[i], cz[i]])).map(|c| c.clamp(0.0, 1.0));
            hunt(linear_rgb_to_lab(rgb))
        })
        .collect();

    // Gx = d(x)·g(y) and Gy = g(x)·d(y) share their passes: smooth rows once, differentiate
    // rows once per detector.
    let smooth_rows = filter_rows(&lum, w, h, &f.gauss);
    let edge_x = filter_cols(&filter_rows(&lum, w, h, &f.edge), w, h, &f.gauss);
    let edge_y = filter_cols(&smooth_rows, w, h, &f.edge);
    let point_x = filter_cols(&filter_rows(&lum, w, h, &f.point), w, h, &f.gauss);
    let point_y = filter_cols(&smooth_rows, w, h, &f.point);
    let edge = edge_x.iter().zip(&edge_y).map(|(a, b)| a.hypot(*b)).collect();
    let point = point_x.iter().zip(&point_y).map(|(a, b)| a.hypot(*b)).collect();
    Prepared { lab, edge, point }
}

/// All 1D kernels for one viewing distance.
struct Filters {
    csf_a: CsfFilter,
    csf_rg: CsfFilter,
    csf_by: CsfFilter,
    /// Gaussian of the feature detectors, unit sum.
    gauss: Vec<f32>,
    /// First derivative of that Gaussian (−x·g), positive part sums to 1, negative to −1.
    edge: Vec<f32>,
    /// Second derivative (x²/σ² − 1)·g, normalised the same way.
    point: Vec<f32>,
}

impl Filters {
    fn new(ppd: f32) -> Self {
        // One support for all three CSFs, wide enough for the widest Gaussian (b = 0.04) to
        // three standard deviations, as in the reference.
        let b_max = [CSF_A, CSF_RG, CSF_BY]
            .iter()
            .flat_map(|c| [c.b1, c.b2])
            .fold(0.0f32, f32::max);
        let csf_radius = (3.0 * (b_max / (2.0 * std::f32::consts::PI.powi(2))).sqrt() * ppd).ceil() as i32;

        let sigma = 0.5 * FEATURE_WIDTH_DEG * ppd;
        let radius = (3.0 * sigma).ceil() as i32;
        let xs: Vec<f32> = (-radius..=radius).map(|x| x as f32).collect();
        let g: Vec<f32> = xs.iter().map(|x| (-x * x / (2.0 * sigma * sigma)).exp()).collect();
        let edge: Vec<f32> = xs.iter().zip(&g).map(|(x, g)| -x * g).collect();
        let point: Vec<f32> = xs
            .iter()
            .zip(&g)
            .map(|(x, g)| (x * x / (sigma * sigma) - 1.0) * g)
            .collect();
        Filters {
            csf_a: CsfFilter::new(CSF_A, ppd, csf_radius),
            csf_rg: CsfFilter::new(CSF_RG, ppd, csf_radius),
            csf_by: CsfFilter::new(CSF_BY, ppd, csf_radius),
            gauss: normalise_sum(g),
            edge: normalise_signed(edge),
            point: normalise_signed(point),
        }
    }
}

/// A CSF as a weighted sum of separable Gaussians. The 2D kernel Σₖ aₖ√(π/bₖ)·gₖ(x)gₖ(y),
/// divided by its total, equals Σₖ wₖ·(gₖ/Gₖ)(x)·(gₖ/Gₖ)(y) with Gₖ = Σ gₖ and
/// wₖ ∝ aₖ√(π/bₖ)·Gₖ², the wₖ summing to 1.
struct CsfFilter {
    terms: Vec<(f32, Vec<f32>)>,
}

impl CsfFilter {
    fn new(csf: Csf, ppd: f32, radius: i32) -> Self {
        let mut terms: Vec<(f32, Vec<f32>)> = [(csf.a1, csf.b1), (csf.a2, csf.b2)]
            .into_iter()
            .filter(|&(a, _)| a != 0.0)
            .map(|(a, b)| {
                let g: Vec<f32> = (-radius..=radius)
                    .map(|x| {
                        let deg = x as f32 / ppd;
                        (-std::f32::consts::PI.powi(2) * deg * deg / b).exp()
                    })
                    .collect();
                let sum: f32 = g.iter().sum();
                (a * (std::f32::consts::PI / b).sqrt() * sum * sum, normalise_sum(g))
            })
            .collect();
        let total: f32 = terms.iter().map(|t| t.0).sum();
        for t in &mut terms {
            t.0 /= total;
        }
        CsfFilter { terms }
    }

    fn apply(&self, src: &[f32], w: usize, h: usize) -> Vec<f32> {
        let mut out = vec![0.0f32; src.len()];
        for (weight, k) in &self.terms {
            let filtered = filter_cols(&filter_rows(src, w, h, k), w, h, k);
            for (o, v) in out.iter_mut().zip(filtered) {
                *o += weight * v;
            }
        }
        out
    }
}

/// Scales `k` to unit sum (the centre tap is exp(0) = 1, so the sum is never zero).
fn normalise_sum(mut k: Vec<f32>) -> Vec<f32> {
    let sum: f32 = k.iter().sum();
    if sum > 0.0 {
        k.iter_mut().for_each(|v| *v /= sum);
    }
    k
}

/// Scales positive taps to sum 1 and negative taps to sum −1, so that a feature detector's
/// response to a unit step is bounded by 1 whatever the viewing distance. A side that is all
/// zero (kernels too narrow to sample, at absurdly low ppd) is left alone.
fn normalise_signed(mut k: Vec<f32>) -> Vec<f32> {
    let pos: f32 = k.iter().filter(|v| **v > 0.0).sum();
    let neg: f32 = -k.iter().filter(|v| **v < 0.0).sum::<f32>();
    for v in &mut k {
        if *v > 0.0 && pos > 0.0 {
            *v /= pos;
        } else if *v < 0.0 && neg > 0.0 {
            *v /= neg;
        }
    }
    k
}

/// Correlates every row with the odd-length kernel `k` centred on each pixel, replicating the
/// border pixels.
fn filter_rows(src: &[f32], w: usize, h: usize, k: &[f32]) -> Vec<f32> {
    let r = k.len() / 2;
    let mut out = vec![0.0f32; w * h];
    let mut padded = vec![0.0f32; w + 2 * r];
    for (row, out_row) in src.chunks_exact(w).zip(out.chunks_exact_mut(w)) {
        for (i, p) in padded.iter_mut().enumerate() {
            *p = row[(i as isize - r as isize).clamp(0, w as isize - 1) as usize];
        }
        for (x, o) in out_row.iter_mut().enumerate() {
            *o = k.iter().zip(&padded[x..x + k.len()]).map(|(a, b)| a * b).sum();
        }
    }
    out
}

/// Correlates every column with `k`, replicating the border rows. Works a whole row at a time
/// so the inner loop runs over contiguous memory.
fn filter_cols(src: &[f32], w: usize, h: usize, k: &[f32]) -> Vec<f32> {
    let r = k.len() / 2;
    let mut out = vec![0.0f32; w * h];
    for (y, out_row) in out.chunks_exact_mut(w).enumerate() {
        for (j, &kj) in k.iter().enumerate() {
            let sy = (y as isize + j as isize - r as isize).clamp(0, h as isize - 1) as usize;
            let src_row = &src[sy * w..(sy + 1) * w];
            for (o, s) in out_row.iter_mut().zip(src_row) {
                *o += kj * s;
            }
        }
    }
    out
}

#[cfg(test)]
mod kernel_tests {
    use super::*;

    #[test]
    fn kernel_sizes_at_default_ppd() {
        let f = Filters::new(super::super::default_pixels_per_degree());
        // ⌈3·√(0.04/2π²)·67.02⌉ = ⌈9.05⌉ = 10 and ⌈3·0.041·67.02⌉ = ⌈8.24⌉ = 9.
        assert_eq!(f.csf_a.terms[0].1.len(), 21);
        assert_eq!(f.csf_by.terms.len(), 2);
        assert_eq!(f.gauss.len(), 19);
        for k in [&f.edge, &f.point] {
            let pos: f32 = k.iter().filter(|v| **v > 0.0).sum();
            let neg: f32 = k.iter().filter(|v| **v < 0.0).sum();
            assert!((pos - 1.0).abs() < 1e-5 && (neg + 1.0).abs() < 1e-5);
        }
        let wsum: f32 = f.csf_by.terms.iter().map(|t| t.0).sum();
        assert!((wsum - 1.0).abs() < 1e-6);
    }

    #[test]
    fn separable_passes_match_direct_2d_correlation() {
        // A 2D correlation of a small ramp-and-spike image with the outer product d(x)·g(y),
        // border replicated, against the two 1D passes.
        let (w, h) = (7usize, 5usize);
        let src: Vec<f32> = (0..w * h).map(|i| ((i * 37) % 11) as f32 * 0.1).collect();
        let d = normalise_signed(vec![1.0, 2.0, 0.0, -2.0, -1.0]);
        let g = normalise_sum(vec![0.2, 0.6, 1.0, 0.6, 0.2]);
        let sep = filter_cols(&filter_rows(&src, w, h, &d), w, h, &g);
        for y in 0..h as isize {
            for x in 0..w as isize {
                let mut acc = 0.0f32;
                for j in -2..=2isize {
                    for i in -2..=2isize {
                        let sx = (x + i).clamp(0, w as isize - 1) as usize;
                        let sy = (y + j).clamp(0, h as isize - 1) as usize;
                        acc += d[(i + 2) as usize] * g[(j + 2) as usize] * src[sy * w + sx];
                    }
                }
                assert!((acc - sep[y as usize * w + x as usize]).abs() < 1e-5, "({x}, {y})");
            }
        }
    }
}
