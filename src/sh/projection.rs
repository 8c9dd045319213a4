//! Projection `c_i = ∫ f(ω) y_i(ω) dω` of closures (deterministic Gauss–Legendre × uniform-φ
//! quadrature), equirectangular images and cube maps (exact per-texel solid angles).
//!
//! Why not Monte Carlo as the seeds do (the height-field thesis Eq. 3.23, the Ca3D-Engine thesis §5.1.3): a product rule with
//! n Gauss–Legendre nodes in z = cos θ and N uniform azimuths integrates every polynomial in
//! (x, y, z) of degree ≤ min(2n−1, N−1) exactly, so projecting a band-limited function is exact
//! to rounding and the results are reproducible bit for bit.

use super::basis::eval_unit;
use super::{check_bands, unit_dir, world_to_sh, ShError, ShResult, MAX_BANDS};
use glam::{DVec3, Vec3};
use std::f64::consts::{PI, TAU};

/// Largest node count per axis a quadrature accepts, and largest total.
const MAX_NODES_AXIS: usize = 4096;
const MAX_NODES_TOTAL: usize = 1 << 22;

/// Gauss–Legendre nodes and weights on [−1, 1], ascending (Newton iteration on P_n from the
/// Tricomi initial guess; converges to ~1e−15). `n` in 1..=4096.
pub fn gauss_legendre(n: usize) -> ShResult<(Vec<f64>, Vec<f64>)> {
    if !(1..=MAX_NODES_AXIS).contains(&n) {
        return Err(ShError::Range {
            what: "Gauss-Legendre node count",
            range: "1..=4096",
            got: n as f64,
        });
    }
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n.div_ceil(2) {
        let mut t = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            // P_n(t) and P_{n−1}(t) by the three-term recurrence.
            let (mut p0, mut p1) = (1.0f64, t);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * t * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 1 { t } else { p1 };
            let pn1 = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (t * pn - pn1) / (t * t - 1.0);
            let dx = pn / dp;
            t -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        let wi = 2.0 / ((1.0 - t * t) * dp * dp);
        x[i] = -t;
        x[n - 1 - i] = t;
        w[i] = wi;
        w[n - 1 - i] = wi;
    }
    Ok((x, w))
}

/// A product quadrature rule on the sphere (or a zone z0 ≤ cos θ ≤ z1 of it): Gauss–Legendre in
/// z = cos θ × uniform φ. Directions are in the SH frame.
#[derive(Debug, Clone)]
pub struct Quadrature {
    dirs: Vec<DVec3>,
    weights: Vec<f64>,
}

impl Quadrature {
    /// The zone `z_min ≤ cos θ ≤ z_max` with `n_theta` Gauss–Legendre nodes in z and `n_phi`
    /// azimuths φ_j = (j + ½)·2π/n_phi. Integrates exactly every polynomial in (x, y, z) of
    /// degree ≤ min(2·n_theta − 1, n_phi − 1) over the zone: the φ sum is exact for its
    /// trigonometric part, and what survives it is a polynomial in z. (So it integrates a
    /// polynomial exactly over a cap or a hemisphere too, e.g. a cosine lobe times an SH.)
    pub fn zone(z_min: f64, z_max: f64, n_theta: usize, n_phi: usize) -> ShResult<Self> {
        if !z_min.is_finite() || !z_max.is_finite() {
            return Err(ShError::NonFinite("zone bounds"));
        }
        if !(-1.0..=1.0).contains(&z_min) || !(z_min..=1.0).contains(&z_max) {
            return Err(ShError::Range {
                what: "zone bounds",
                range: "-1 <= z_min <= z_max <= 1",
                got: z_min,
            });
        }
        if !(1..=MAX_NODES_AXIS).contains(&n_phi) || n_theta.saturating_mul(n_phi) > MAX_NODES_TOTAL {
            return Err(ShError::Range {
                what: "quadrature size",
                range: "n_phi in 1..=4096, total <= 2^22",
                got: n_phi as f64,
            });
        }
        let (x, w) = gauss_legendre(n_theta)?;
        let (mid, half) = (0.5 * (z_max + z_min), 0.5 * (z_max - z_min));
        let dphi = TAU / n_phi as f64;
        let mut dirs = Vec::with_capacity(n_theta * n_phi);
        let mut weights = Vec::with_capacity(n_theta * n_phi);
        for (xi, wi) in x.iter().zip(&w) {
            let z = mid + half * xi;
            let s = (1.0 - z * z).max(0.0).sqrt();
            for j in 0..n_phi {
                let phi = (j as f64 + 0.5) * dphi;
                dirs.push(DVec3::new(s * phi.cos(), s * phi.sin(), z));
                weights.push(wi * half * dphi);
            }
        }
        Ok(Self { dirs, weights })
    }

    /// The whole sphere: [`Quadrature::zone`]`(−1, 1, n_theta, n_phi)`.
    pub fn sphere(n_theta: usize, n_phi: usize) -> ShResult<Self> {
        Self::zone(-1.0, 1.0, n_theta, n_phi)
    }

    /// The smallest sphere rule exact for polynomials of total degree ≤ `degree`:
    /// `degree/2 + 1` nodes in z, `degree + 1` azimuths. Projecting a function band-limited to
    /// L onto B bands needs `degree ≥ L + B − 1`; the triple product `3(B − 1)`.
    pub fn exact_for_degree(degree: usize) -> ShResult<Self> {
        Self::sphere(degree / 2 + 1, degree + 1)
    }

    /// The rule [`project`] uses for `bands`: exact for `f` band-limited to `3·bands + 17`.
    pub fn default_for(bands: usize) -> ShResult<Self> {
        check_bands(bands)?;
        Self::exact_for_degree(4 * bands + 16)
    }

    /// Node directions (unit, SH frame).
    pub fn dirs(&self) -> &[DVec3] {
        &self.dirs
    }
    /// Node weights (they sum to the zone's solid angle).
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }
    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.dirs.len()
    }
    /// Whether the rule has no nodes (never, for rules built by the constructors).
    pub fn is_empty(&self) -> bool {
        self.dirs.is_empty()
    }
    /// `∫ f dω` over the rule's domain.
    pub fn integrate(&self, mut f: impl FnMut(DVec3) -> f64) -> f64 {
        self.dirs.iter().zip(&self.weights).map(|(d, w)| w * f(*d)).sum()
    }

    /// Projects scalar `f(dir)` (SH-frame direction) onto `bands` bands, in f64.
    pub fn project_scalar(&self, mut f: impl FnMut(DVec3) -> f64, bands: usize) -> ShResult<Vec<f64>> {
        check_bands(bands)?;
        let n = bands * bands;
        let mut acc = vec![0.0f64; n];
        let mut y = [0.0f64; MAX_BANDS * MAX_BANDS];
        for (d, w) in self.dirs.iter().zip(&self.weights) {
            let v = f(*d) * w;
            eval_unit(*d, bands, &mut y);
            for (a, yi) in acc.iter_mut().zip(&y[..n]) {
                *a += v * yi;
            }
        }
        Ok(acc)
    }

    /// Projects RGB `f(dir)` (SH-frame direction) onto `bands` bands, in f64.
    pub fn project_rgb(&self, mut f: impl FnMut(DVec3) -> DVec3, bands: usize) -> ShResult<Vec<DVec3>> {
        check_bands(bands)?;
        let n = bands * bands;
        let mut acc = vec![DVec3::ZERO; n];
        let mut y = [0.0f64; MAX_BANDS * MAX_BANDS];
        for (d, w) in self.dirs.iter().zip(&self.weights) {
            let v = f(*d) * *w;
            eval_unit(*d, bands, &mut y);
            for (a, yi) in acc.iter_mut().zip(&y[..n]) {
                *a += v * *yi;
            }
        }
        Ok(acc)
    }
}

/// Projects RGB `f(dir)` (dir in the SH frame; use [`super::sh_to_world`] inside `f` for world
/// functions) onto `bands` bands with [`Quadrature::default_for`].
pub fn project(mut f: impl FnMut(Vec3) -> Vec3, bands: usize) -> ShResult<Vec<Vec3>> {
    let q = Quadrature::default_for(bands)?;
    let c = q.project_rgb(|d| f(d.as_vec3()).as_dvec3(), bands)?;
    Ok(c.into_iter().map(|v| v.as_vec3()).collect())
}

/// Scalar [`project`].
pub fn project_scalar(mut f: impl FnMut(Vec3) -> f32, bands: usize) -> ShResult<Vec<f32>> {
    let q = Quadrature::default_for(bands)?;
    let c = q.project_scalar(|d| f(d.as_vec3()) as f64, bands)?;
    Ok(c.into_iter().map(|v| v as f32).collect())
}

/// World direction of the centre of texel (x, y) of a `width`×`height` equirectangular map in
/// penumbra's convention (`scene::Environment::equirect_dir`): v = 0 is +y (up), u = 0.5 is −z,
/// u = 0.75 is +x. Zero sizes are treated as 1.
pub fn equirect_texel_dir_world(x: usize, y: usize, width: usize, height: usize) -> Vec3 {
    let u = (x as f64 + 0.5) / width.max(1) as f64;
    let v = (y as f64 + 0.5) / height.max(1) as f64;
    let (phi, theta) = ((u - 0.5) * TAU, v * PI);
    DVec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos()).as_vec3()
}

/// Exact solid angle of any texel in row `y` of a `width`×`height` equirectangular map:
/// `(φ1 − φ0)(cos θ0 − cos θ1)` with θ the polar angle of the row's edges, evaluated as
/// `(2π/w)·2 sin(θ_centre) sin(Δθ/2)` (no cancellation; the GLSL uses the same form). Sums to 4π.
pub fn equirect_texel_solid_angle(y: usize, width: usize, height: usize) -> f64 {
    let dt = PI / height.max(1) as f64;
    TAU / width.max(1) as f64 * 2.0 * ((y as f64 + 0.5) * dt).sin() * (0.5 * dt).sin()
}

/// Projects an RGB equirectangular map (`width`×`height` texels, row-major, row 0 at the top,
/// penumbra's mapping, see [`equirect_texel_dir_world`]) onto `bands` bands: each texel is its
/// centre value times its exact solid angle. Coefficients are in the SH frame. The midpoint rule
/// in θ is second-order accurate; the φ sum is exact for band-limited content.
pub fn project_equirect(pixels: &[[f32; 3]], width: usize, height: usize, bands: usize) -> ShResult<Vec<Vec3>> {
    check_bands(bands)?;
    let expected = width.checked_mul(height).filter(|&n| n > 0).ok_or(ShError::Range {
        what: "equirect size",
        range: "width, height >= 1",
        got: 0.0,
    })?;
    if pixels.len() != expected {
        return Err(ShError::Length {
            what: "equirect texels",
            expected,
            got: pixels.len(),
        });
    }
    let n = bands * bands;
    let mut total = vec![DVec3::ZERO; n];
    let mut row_acc = vec![DVec3::ZERO; n];
    let mut y = [0.0f64; MAX_BANDS * MAX_BANDS];
    for (row, texels) in pixels.chunks_exact(width).enumerate() {
        // Accumulate per row (constant weight) before adding to the total: fewer rounding steps.
        row_acc.iter_mut().for_each(|a| *a = DVec3::ZERO);
        for (x, t) in texels.iter().enumerate() {
            let d = world_to_sh(equirect_texel_dir_world(x, row, width, height)).as_dvec3();
            eval_unit(unit_dir(d), bands, &mut y);
            let v = DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64);
            for (a, yi) in row_acc.iter_mut().zip(&y[..n]) {
                *a += v * *yi;
            }
        }
        let w = equirect_texel_solid_angle(row, width, height);
        for (t, a) in total.iter_mut().zip(&row_acc) {
            *t += *a * w;
        }
    }
    Ok(total.into_iter().map(|v| v.as_vec3()).collect())
}

/// Un-normalised world direction of the centre of texel (x, y) of cube face `face` (Vulkan
/// layer order +X, −X, +Y, −Y, +Z, −Z; the spec's face-selection table: +X has s = −z, t = −y;
/// +Y has s = x, t = z; +Z has s = x, t = −y; …). `face` is clamped to 0..=5, size 0 is 1.
pub fn cube_texel_dir_world(face: usize, x: usize, y: usize, size: usize) -> Vec3 {
    let n = size.max(1) as f32;
    let sc = 2.0 * (x as f32 + 0.5) / n - 1.0;
    let tc = 2.0 * (y as f32 + 0.5) / n - 1.0;
    match face.min(5) {
        0 => Vec3::new(1.0, -tc, -sc),
        1 => Vec3::new(-1.0, -tc, sc),
        2 => Vec3::new(sc, 1.0, tc),
        3 => Vec3::new(sc, -1.0, -tc),
        4 => Vec3::new(sc, -tc, 1.0),
        _ => Vec3::new(-sc, -tc, -1.0),
    }
}

/// Exact solid angle of texel (x, y) of a `size`² cube face (the same on every face):
/// `Ω = A(x0,y0) − A(x0,y1) − A(x1,y0) + A(x1,y1)` with `A(a,b) = atan2(ab, √(a²+b²+1))` at the
/// texel's corners in [−1, 1] face coordinates. Sums to 4π over the cube.
pub fn cube_texel_solid_angle(x: usize, y: usize, size: usize) -> f64 {
    let n = size.max(1) as f64;
    let a = |u: f64, v: f64| (u * v).atan2((u * u + v * v + 1.0).sqrt());
    let (x0, x1) = (2.0 * x as f64 / n - 1.0, 2.0 * (x as f64 + 1.0) / n - 1.0);
    let (y0, y1) = (2.0 * y as f64 / n - 1.0, 2.0 * (y as f64 + 1.0) / n - 1.0);
    a(x0, y0) - a(x0, y1) - a(x1, y0) + a(x1, y1)
}

/// Projects an RGB cube map onto `bands` bands: `texels` holds the six `size`×`size` faces in
/// Vulkan layer order (+X, −X, +Y, −Y, +Z, −Z), each row-major with row 0 at t = 0, sampled in
/// world directions (see [`cube_texel_dir_world`]). Each texel is its centre value times its
/// exact solid angle. Coefficients are in the SH frame.
pub fn project_cubemap(texels: &[[f32; 3]], size: usize, bands: usize) -> ShResult<Vec<Vec3>> {
    check_bands(bands)?;
    let face_len = size.checked_mul(size).filter(|&n| n > 0).ok_or(ShError::Range {
        what: "cube face size",
        range: ">= 1",
        got: 0.0,
    })?;
    let expected = face_len.checked_mul(6).ok_or(ShError::Range {
        what: "cube face size",
        range: "not overflowing",
        got: size as f64,
    })?;
    if texels.len() != expected {
        return Err(ShError::Length {
            what: "cube map texels",
            expected,
            got: texels.len(),
        });
    }
    let n = bands * bands;
    let mut total = vec![DVec3::ZERO; n];
    let mut y = [0.0f64; MAX_BANDS * MAX_BANDS];
    // Solid angles are the same on every face: compute them once.
    let omega: Vec<f64> = (0..face_len)
        .map(|i| cube_texel_solid_angle(i % size, i / size, size))
        .collect();
    for (face, face_texels) in texels.chunks_exact(face_len).enumerate() {
        for (i, t) in face_texels.iter().enumerate() {
            let d = world_to_sh(cube_texel_dir_world(face, i % size, i / size, size)).as_dvec3();
            eval_unit(unit_dir(d), bands, &mut y);
            let v = DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64) * omega[i];
            for (a, yi) in total.iter_mut().zip(&y[..n]) {
                *a += v * *yi;
            }
        }
    }
    Ok(total.into_iter().map(|v| v.as_vec3()).collect())
}
