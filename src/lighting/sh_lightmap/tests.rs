//! The digest's end-to-end cases with analytic answers (the Ca3D-Engine thesis §5.2 A–G), on the CPU baker.
//! Every expected value is a closed form or a quadrature written here, not the baker's tables.

use glam::{DVec3, Vec3};

use super::normals::{self, NormalImage, Surfaces};
use super::samples::SampleSet;
use super::transfer::{self, Settings};
use crate::lighting::lightmap::patches::{Patches, Triangle};
use crate::lighting::lightmap::solve::{self, Mode, Occluders};
use crate::sh;
use crate::util::progress::Progress;

const BANDS: [usize; 5] = [2, 3, 4, 6, 8];

/// A quad `o + s·u + t·v` (s, t ∈ [0, 1]) as two triangles facing `u × v`.
fn quad(o: DVec3, u: DVec3, v: DVec3, object: usize, albedo: f64) -> [Triangle; 2] {
    let t = |p| Triangle {
        p,
        object,
        albedo: DVec3::splat(albedo),
        emission: DVec3::ZERO,
        sky: false,
        part: 0,
    };
    [t([o, o + u, o + u + v]), t([o, o + u + v, o + v])]
}

fn settings(bands: usize, bounces: bool) -> Settings {
    let solve = solve::Settings {
        mode: Mode::Corrected,
        threshold: 1e-4,
        ..solve::Settings::default()
    };
    Settings {
        solve,
        bands,
        bounces,
        tone: false,
    }
}

fn bake(
    tris: &[Triangle],
    size: f64,
    samples: &SampleSet,
    s: &Settings,
    normal_maps: Option<&Surfaces<'_>>,
) -> (Patches, Vec<f64>) {
    bake_among(tris, &[], size, samples, s, normal_maps)
}

/// [`bake`] with `others` occluding but not patched (after `tris`, so chart indices hold).
fn bake_among(
    tris: &[Triangle],
    others: &[Triangle],
    size: f64,
    samples: &SampleSet,
    s: &Settings,
    normal_maps: Option<&Surfaces<'_>>,
) -> (Patches, Vec<f64>) {
    let mut p = Patches::build(tris, size);
    if let Some(surfaces) = normal_maps {
        normals::perturb(&mut p, tris, surfaces, 16);
    }
    let occ = Occluders::new(&[tris, others].concat());
    let bits = transfer::visibility_cpu(&p, &occ, samples, s.solve.mode, &mut Progress::new("test"));
    let t = transfer::bake(&p, &occ, samples, &bits, s, &mut Progress::new("test"));
    (p, t.coeffs)
}

/// The patch whose sample point is nearest `at`, inside its polygon.
fn patch_at(p: &Patches, at: DVec3) -> usize {
    (0..p.patches.len())
        .filter(|&k| p.patches[k].coverage >= 1.0)
        .min_by(|&a, &b| {
            (p.patches[a].centre - at)
                .length()
                .total_cmp(&(p.patches[b].centre - at).length())
        })
        .unwrap_or(0)
}

fn coeffs(p: &[f64], k: usize, dim: usize) -> &[f64] {
    &p[k * dim..(k + 1) * dim]
}

/// SH radiance coefficients of a constant sky L₀: only c₀₀ = 2√π·L₀.
fn constant_sky(bands: usize, l0: f64) -> Vec<f64> {
    let mut c = vec![0.0; bands * bands];
    c[0] = sh::CONSTANT_ONE_C00 * l0;
    c
}

/// A zonal function about world `axis` as full coefficients.
fn zonal_about(zh: &[f64], axis_world: DVec3) -> Vec<f64> {
    sh::zh_rotate(zh, sh::world_to_sh(axis_world.as_vec3())).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_constant_sky_gives_rho_l0_at_every_band_count_and_orientation() {
    for bands in BANDS {
        let samples = SampleSet::new(10_000, bands).unwrap_or_else(|e| panic!("{e}"));
        // A floor, a wall and a ceiling, each alone.
        let floor = quad(
            DVec3::new(-1.0, 0.0, -1.0),
            DVec3::new(0.0, 0.0, 2.0),
            DVec3::new(2.0, 0.0, 0.0),
            0,
            0.5,
        );
        let wall = quad(
            DVec3::new(5.0, 0.0, -1.0),
            DVec3::new(0.0, 2.0, 0.0),
            DVec3::new(0.0, 0.0, 2.0),
            0,
            0.5,
        );
        let ceiling = quad(
            DVec3::new(-1.0, 3.0, -1.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 0.0, 2.0),
            0,
            0.5,
        );
        let light = constant_sky(bands, 2.0);
        for (tris, at) in [
            (floor, DVec3::new(0.25, 0.0, 0.25)),
            (wall, DVec3::new(5.0, 0.75, 0.25)),
            (ceiling, DVec3::new(0.25, 3.0, 0.25)),
        ] {
            let (p, t) = bake(&tris, 0.5, &samples, &settings(bands, false), None);
            let k = patch_at(&p, at);
            let e = transfer::shade(coeffs(&t, k, bands * bands), &light);
            assert!(
                (e - 2.0).abs() < 2e-3,
                "bands {bands} at {at}: {e} (normal {})",
                p.patches[k].normal
            );
        }
    }
}

#[test]
fn b_a_hemisphere_sky_gives_half_one_plus_cos_alpha() {
    for bands in BANDS {
        let samples = SampleSet::new(10_000, bands).unwrap_or_else(|e| panic!("{e}"));
        let sky = zonal_about(&sh::hemisphere_zh(bands).unwrap_or_default(), DVec3::Y);
        for alpha_deg in [0.0f64, 30.0, 90.0, 135.0] {
            let a = alpha_deg.to_radians();
            // A patch whose normal leans α from up, alone.
            let n = DVec3::new(a.sin(), a.cos(), 0.0);
            let u = DVec3::Z;
            let v = n.cross(u);
            let tris = quad(-u - v, u * 2.0, v * 2.0, 0, 0.5);
            let (p, t) = bake(&tris, 0.5, &samples, &settings(bands, false), None);
            let k = patch_at(&p, DVec3::ZERO);
            assert!(p.patches[k].normal.dot(n) > 0.999999);
            let e = transfer::shade(coeffs(&t, k, bands * bands), &sky);
            let want = (1.0 + a.cos()) / 2.0;
            assert!((e - want).abs() < 2e-3, "bands {bands} α {alpha_deg}: {e} want {want}");
        }
    }
}

#[test]
fn c_a_ground_plane_hides_the_sky_below_the_horizon() {
    let bands = 4;
    let samples = SampleSet::new(10_000, bands).unwrap_or_else(|e| panic!("{e}"));
    let light = constant_sky(bands, 1.0);
    for alpha_deg in [45.0f64, 90.0, 120.0] {
        let a = alpha_deg.to_radians();
        let n = DVec3::new(a.sin(), a.cos(), 0.0);
        let (u, v) = (DVec3::Z * 0.2, n.cross(DVec3::Z) * 0.2);
        // A small patch 0.5 above a black ground 2000 wide: the horizon it sees is within 0.03°.
        let tris = quad(DVec3::new(0.0, 0.5, 0.0) - u * 0.5 - v * 0.5, u, v, 0, 0.5);
        let ground = quad(
            DVec3::new(-1000.0, 0.0, -1000.0),
            DVec3::new(0.0, 0.0, 2000.0),
            DVec3::new(2000.0, 0.0, 0.0),
            1,
            0.0,
        );
        let (p, t) = bake_among(&tris, &ground, 0.2, &samples, &settings(bands, false), None);
        let k = patch_at(&p, DVec3::new(0.0, 0.5, 0.0));
        let e = transfer::shade(coeffs(&t, k, bands * bands), &light);
        let want = (1.0 + a.cos()) / 2.0;
        assert!((e - want).abs() < 3e-3, "α {alpha_deg}: {e} want {want}");
    }
}

#[test]
fn d_a_directional_light_rings_as_the_golden_values() {
    // (1/π)·Σ_l c_l·y_l0(cos) for E = ρ = 1 at cos = 1, 0.5, 0, −0.5, −1 (digest §5.2 D).
    let golden: [(usize, [f64; 5]); 5] = [
        (2, [0.2387, 0.1592, 0.0796, 0.0000, -0.0796]),
        (3, [0.3382, 0.1467, 0.0298, -0.0124, 0.0199]),
        (4, [0.3382, 0.1467, 0.0298, -0.0124, 0.0199]),
        (6, [0.3084, 0.1553, 0.0187, -0.0038, -0.0099]),
        (8, [0.3245, 0.1606, 0.0136, 0.0014, 0.0062]),
    ];
    for (bands, want) in golden {
        let samples = SampleSet::new(10_000, bands).unwrap_or_else(|e| panic!("{e}"));
        let tris = quad(
            DVec3::new(-1.0, 0.0, -1.0),
            DVec3::new(0.0, 0.0, 2.0),
            DVec3::new(2.0, 0.0, 0.0),
            0,
            0.5,
        );
        let (p, t) = bake(&tris, 0.5, &samples, &settings(bands, false), None);
        let k = patch_at(&p, DVec3::ZERO);
        for (cos, w) in [1.0f64, 0.5, 0.0, -0.5, -1.0].iter().zip(want) {
            let to_light = DVec3::new((1.0 - cos * cos).max(0.0).sqrt(), *cos, 0.0);
            let mut light = vec![0.0; bands * bands];
            sh::eval_basis_f64(sh::world_to_sh(to_light.as_vec3()).as_dvec3(), bands, &mut light)
                .unwrap_or_else(|e| panic!("{e}"));
            let e = transfer::shade(coeffs(&t, k, bands * bands), &light);
            // The exact band-limited value (the clamped cosine's ZH, a closed form) matches the
            // golden table to its 4 decimals; the baked transfer adds the 100 × 100 grid's
            // quadrature error, which grows with the band (measured: 2e-4 at 4 bands, 9.6e-4 at
            // 6, 2.8e-3 at 8, all at cos = 1).
            let zh = sh::clamped_cosine_zh(bands).unwrap_or_else(|e| panic!("{e}"));
            let p = sh::legendre(bands, *cos);
            let exact: f64 = (0..bands)
                .map(|l| zh[l] * ((2 * l + 1) as f64 / (4.0 * std::f64::consts::PI)).sqrt() * p[l])
                .sum::<f64>()
                / std::f64::consts::PI;
            assert!(
                (exact - w).abs() < 1e-4,
                "bands {bands} cos {cos}: exact {exact} want {w}"
            );
            let tolerance = match bands {
                0..=4 => 3e-4,
                6 => 1.5e-3,
                _ => 4e-3,
            };
            assert!((e - w).abs() < tolerance, "bands {bands} cos {cos}: {e} want {w}");
        }
    }
}

/// The open box of the digest: floor w = 2 centred on a patch centre, walls h = 1, no lid.
fn open_box(albedo: f64) -> Vec<Triangle> {
    let (lo, w, h) = (DVec3::new(-0.875, 0.0, -0.875), 2.0, 1.0);
    let (x, y, z) = (DVec3::X * w, DVec3::Y * h, DVec3::Z * w);
    let mut tris = quad(lo, z, x, 0, albedo).to_vec();
    tris.extend(quad(lo, y, z, 1, albedo)); // x = lo, facing +x
    tris.extend(quad(lo + x, z, y, 2, albedo)); // facing -x
    tris.extend(quad(lo, x, y, 3, albedo)); // facing +z
    tris.extend(quad(lo + z, y, x, 4, albedo)); // facing -z
    let centre = lo + (x + z) * 0.5 + y * 0.5;
    for t in &mut tris {
        if t.normal().dot(centre - t.p[0]) < 0.0 {
            t.p.swap(1, 2);
        }
    }
    tris
}

#[test]
fn e_the_open_box_floor_sees_the_opening_view_factor() {
    // F = 4·F_corner(a/h, a/h), a = w/2: 0.554126 for w = 2, h = 1.
    let corner = |a: f64, b: f64| {
        let (sa, sb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
        (a / sa * (b / sa).atan() + b / sb * (a / sb).atan()) / (2.0 * std::f64::consts::PI)
    };
    let f = 4.0 * corner(1.0, 1.0);
    assert!((f - 0.554126).abs() < 1e-6, "{f}");
    for bands in [2, 4, 8] {
        let samples = SampleSet::new(10_000, bands).unwrap_or_else(|e| panic!("{e}"));
        let (p, t) = bake(&open_box(0.5), 0.25, &samples, &settings(bands, false), None);
        let k = patch_at(&p, DVec3::new(0.125, 0.0, 0.125));
        assert!((p.patches[k].centre - DVec3::new(0.125, 0.0, 0.125)).length() < 1e-9);
        let e = transfer::shade(coeffs(&t, k, bands * bands), &constant_sky(bands, 1.0));
        assert!((e / f - 1.0).abs() < 0.01, "bands {bands}: {e} want {f}");
    }
}

#[test]
fn f_radiosity_and_sh_agree_under_a_constant_sky_with_bounces() {
    let tris = open_box(0.6);
    let bands = 3;
    let samples = SampleSet::new(10_000, bands).unwrap_or_else(|e| panic!("{e}"));
    let s = settings(bands, true);
    let (p, t) = bake(&tris, 0.25, &samples, &s, None);
    let (_, direct_only) = bake(&tris, 0.25, &samples, &settings(bands, false), None);
    // CaLight with the sun replaced by a uniform sky: each patch's direct irradiance by its own
    // cosine-weighted quadrature (not the SH sample set), reflected, then the radiosity solve.
    let occ = Occluders::new(&tris);
    let mut radiosity = Patches::build(&tris, 0.25);
    let m = 100;
    let mut rng = 0x853c_49e6_748f_ea9bu64;
    let mut jitter = move || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    for q in radiosity.patches.iter_mut().filter(|q| q.inside()) {
        let n = q.normal;
        let helper = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
        let (tu, tv) = (helper.cross(n).normalize(), n.cross(helper.cross(n).normalize()));
        let mut seen = 0usize;
        for i in 0..m {
            for j in 0..m {
                let (u, v) = ((i as f64 + jitter()) / m as f64, (j as f64 + jitter()) / m as f64);
                let (r, phi) = (u.sqrt(), 2.0 * std::f64::consts::PI * v);
                let d = tu * (r * phi.cos()) + tv * (r * phi.sin()) + n * (1.0 - u).sqrt();
                seen += usize::from(occ.first_hit(q.centre + n * 1e-5, d).is_none());
            }
        }
        let e = std::f64::consts::PI * seen as f64 / (m * m) as f64;
        q.total = q.albedo * e;
        q.unshot = q.total;
    }
    solve::solve(&mut radiosity, &occ, &s.solve, &mut Progress::new("test"));
    let light = constant_sky(bands, 1.0);
    let (mut worst, mut bounce_share) = (0.0f64, 0.0f64);
    for k in (0..p.patches.len()).filter(|&k| p.patches[k].coverage >= 1.0) {
        // The SH result is E/π; CaLight's radiosity is ρ·E.
        let sh_e = transfer::shade(coeffs(&t, k, bands * bands), &light) * std::f64::consts::PI;
        let rad_e = radiosity.patches[k].total.x / 0.6;
        worst = worst.max((sh_e / rad_e - 1.0).abs());
        bounce_share = bounce_share
            .max(1.0 - transfer::shade(coeffs(&direct_only, k, bands * bands), &light) * std::f64::consts::PI / sh_e);
    }
    assert!(worst < 0.01, "worst relative difference {worst}");
    // The bounces matter here (the test would not see a broken shooting loop otherwise).
    assert!(bounce_share > 0.1, "bounced share {bounce_share}");
}

#[test]
fn g_normal_maps_flat_is_neutral_and_tilted_equals_a_tilted_patch() {
    let bands = 4;
    let samples = SampleSet::new(10_000, bands).unwrap_or_else(|e| panic!("{e}"));
    let tris = quad(
        DVec3::new(-1.0, 0.0, -1.0),
        DVec3::new(0.0, 0.0, 2.0),
        DVec3::new(2.0, 0.0, 0.0),
        0,
        0.5,
    );
    let uvs: Vec<[[f32; 2]; 3]> = vec![
        [[0.0, 0.0], [0.0, 1.0], [1.0, 1.0]],
        [[0.0, 0.0], [1.0, 1.0], [1.0, 0.0]],
    ];
    let s = settings(bands, false);
    let (_, plain) = bake(&tris, 0.5, &samples, &s, None);
    let flat = NormalImage {
        width: 2,
        height: 2,
        texels: vec![DVec3::Z; 4],
    };
    let (_, mapped) = bake(
        &tris,
        0.5,
        &samples,
        &s,
        Some(&Surfaces {
            uvs: &uvs,
            maps: vec![Some(&flat); 2],
        }),
    );
    let diff = plain.iter().zip(&mapped).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(diff <= 1e-12, "a flat map changed the transfer by {diff}");
    // A constant map tilted by β: the patch leans β but keeps the plane's cut-off, so a constant
    // sky gives (1 + cos β)/2 (the hemisphere of the plane seen by a β-tilted cosine).
    let beta = 40f64.to_radians();
    let tilted = NormalImage {
        width: 1,
        height: 1,
        texels: vec![DVec3::new(beta.sin(), 0.0, beta.cos())],
    };
    let (p, t) = bake(
        &tris,
        0.5,
        &samples,
        &s,
        Some(&Surfaces {
            uvs: &uvs,
            maps: vec![Some(&tilted); 2],
        }),
    );
    let k = patch_at(&p, DVec3::new(0.25, 0.0, 0.25));
    assert!(
        (p.patches[k].normal.dot(DVec3::Y) - beta.cos()).abs() < 1e-9,
        "{}",
        p.patches[k].normal
    );
    let e = transfer::shade(coeffs(&t, k, 16), &constant_sky(bands, 1.0));
    assert!((e - (1.0 + beta.cos()) / 2.0).abs() < 2e-3, "{e}");
    // Without the plane's cut-off the tilted normal would see its whole hemisphere (e = 1).
    let _ = Vec3::ZERO;
}

#[test]
fn a_flat_map_on_a_curved_chart_keeps_each_patch_s_own_normal() {
    // A UV sphere of 24 rings, facing out: its facets merge into curved charts, up to 30° wide
    // about their normal. A flat normal map must leave each patch facing as the surface under it
    // does, not as its chart's plane (measured: 2.1° from the sphere's normal on average, 8.8°
    // with the plane's normal).
    let rings = 24;
    let at = |i: usize, j: usize| {
        let (th, ph) = (
            std::f64::consts::PI * i as f64 / rings as f64,
            std::f64::consts::TAU * j as f64 / (2 * rings) as f64,
        );
        DVec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin())
    };
    let mut tris = Vec::new();
    for i in 0..rings {
        for j in 0..2 * rings {
            let q = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            for p in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
                let mut t = quad(DVec3::ZERO, DVec3::X, DVec3::Y, 0, 0.5)[0];
                t.p = p;
                if t.normal().dot(p[0] + p[1] + p[2]) < 0.0 {
                    t.p.swap(1, 2);
                }
                tris.push(t);
            }
        }
    }
    let mut p = Patches::build(&tris, 0.25);
    assert!(p.charts.iter().any(|c| c.curved && c.triangles.len() > 8));
    let flat = NormalImage {
        width: 1,
        height: 1,
        texels: vec![DVec3::Z],
    };
    let uvs = vec![[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]; tris.len()];
    let surfaces = Surfaces {
        uvs: &uvs,
        maps: vec![Some(&flat); tris.len()],
    };
    assert!(normals::perturb(&mut p, &tris, &surfaces, 16) > 0);
    let angles: Vec<f64> = p
        .patches
        .iter()
        .filter(|q| q.inside())
        .map(|q| q.normal.dot(q.centre.normalize()).clamp(-1.0, 1.0).acos().to_degrees())
        .collect();
    let mean = angles.iter().sum::<f64>() / angles.len() as f64;
    println!(
        "mean {mean:.2} worst {:.2}",
        angles.iter().fold(0.0f64, |a, &b| a.max(b))
    );
    assert!(
        mean < 5.0,
        "patches face {mean:.1}° away from the sphere's normal under them on average"
    );
}

#[test]
fn the_sample_set_is_orthonormal_to_the_digests_bound() {
    // max |G − I| ≤ 2e-3 at 10k samples, 4 bands (digest §5.1 item 2: measured 1.4e-3).
    let s = SampleSet::new(10_000, 4).unwrap_or_else(|e| panic!("{e}"));
    let mut worst = 0.0f64;
    for i in 0..16 {
        for j in 0..16 {
            let g: f64 = (0..s.len()).map(|k| s.y(k)[i] * s.y(k)[j]).sum::<f64>() * s.weight;
            worst = worst.max((g - f64::from(u8::from(i == j))).abs());
        }
    }
    assert!(worst <= 2e-3 && worst > 1e-4, "{worst}");
    assert!(SampleSet::new(10, 4).is_err() && SampleSet::new(200_000, 4).is_err());
}

/// `block` takes what the documentation and `radiosity` take: 1 to 16 patches per side.
#[test]
fn block_takes_one_to_sixteen_patches_per_side() {
    let decl = |b: i64| crate::scene::MethodDecl {
        name: super::NAME.into(),
        line: 1,
        params: vec![("block".into(), toml::Value::Integer(b), 1)],
    };
    for b in [1, 8, 16] {
        let c = super::config::Config::from_decl(&decl(b), None).unwrap_or_else(|e| panic!("block = {b}: {e}"));
        assert_eq!(c.transfer.solve.block, b as usize);
    }
    for b in [0, 17] {
        let e = match super::config::Config::from_decl(&decl(b), None) {
            Ok(_) => panic!("block = {b} accepted"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains("block") && e.contains("1 to 16"), "{e}");
    }
}
