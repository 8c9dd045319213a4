//! The generated `bush` mesh (Dickson et al. 2011's leafy bush) and its scene, `scenes/lpv_bush.toml`:
//! triangle counts, determinism in the seed, finite unit attributes in the README's tangent-frame
//! convention, the crown's bounds, the leaf maps' channel packing, and a capture of the scene.

use crate::support as common;

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use penumbra::scene::generators::{bush, BUSH_WOOD_TRIANGLES, CROWN_FLATTENING, LEAF_TRIANGLES, LEAF_VERTICES};
use penumbra::scene::{Environment, Light, Mesh, MeshSource, Scene};
use penumbra::util::image_io::HdrImage;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The bush at its defaults (scenes/README.md).
fn default_bush() -> Mesh {
    bush(5500, 1, 1.0, 1.2, 0.12)
}

/// Leaf `i`'s vertices: centre, tip, left (u = 0), stem, right (u = 1).
fn leaf_vertices(i: usize) -> std::ops::Range<usize> {
    LEAF_VERTICES * i..LEAF_VERTICES * (i + 1)
}

#[test]
fn triangle_count_is_four_per_leaf_plus_the_wood() {
    assert_eq!(BUSH_WOOD_TRIANGLES, 112, "seven six-sided prisms with capped tips");
    for leaves in [1u32, 7, 5500, 20_000] {
        let m = bush(leaves, 3, 1.0, 1.2, 0.12);
        assert_eq!(
            m.triangle_count(),
            LEAF_TRIANGLES * leaves as usize + BUSH_WOOD_TRIANGLES,
            "{leaves} leaves"
        );
        assert_eq!(
            m.vertex_count() - LEAF_VERTICES * leaves as usize,
            bush(1, 3, 1.0, 1.2, 0.12).vertex_count() - LEAF_VERTICES,
            "the wood's vertices"
        );
    }
    // At the defaults, about the seed's 22,100-face bush.
    let n = default_bush().triangle_count();
    assert_eq!(n, 22_112);
    assert!((21_000..=23_000).contains(&n), "{n}");
}

#[test]
fn same_seed_same_bush_other_seed_another() {
    let a = default_bush();
    assert!(a == default_bush(), "two runs with seed 1 differ");
    let b = bush(5500, 2, 1.0, 1.2, 0.12);
    assert_eq!(a.vertex_count(), b.vertex_count());
    let moved = a.positions.iter().zip(&b.positions).filter(|(p, q)| p != q).count();
    assert!(
        moved > a.vertex_count() * 9 / 10,
        "seed 2 moved only {moved} of {} vertices",
        a.vertex_count()
    );
    // The wood has its own random stream: the same whatever the leaf count.
    let few = bush(10, 1, 1.0, 1.2, 0.12);
    let wood = |m: &Mesh, leaves: usize| m.positions[LEAF_VERTICES * leaves..].to_vec();
    assert_eq!(wood(&few, 10), wood(&a, 5500));
    // The leaves come first: the first ten leaves do not depend on how many follow.
    assert_eq!(few.positions[..LEAF_VERTICES * 10], a.positions[..LEAF_VERTICES * 10]);
}

#[test]
fn attributes_are_finite_unit_and_follow_the_tangent_convention() {
    let m = default_bush();
    m.validate("bush").unwrap();
    for (i, (n, t)) in m.normals.iter().zip(&m.tangents).enumerate() {
        assert!(
            m.positions[i].is_finite() && n.is_finite() && t.is_finite(),
            "vertex {i}"
        );
        assert!((n.length() - 1.0).abs() < 1e-4, "normal {i} = {n}");
        assert!((t.truncate().length() - 1.0).abs() < 1e-4, "tangent {i} = {t}");
        assert!(
            n.dot(t.truncate()).abs() < 1e-4,
            "tangent {i} is not orthogonal to the normal"
        );
        assert!(t.w == 1.0 || t.w == -1.0, "tangent {i} w = {}", t.w);
        assert!(
            m.uvs[i].cmpge(Vec2::ZERO).all() && m.uvs[i].cmple(Vec2::ONE).all(),
            "uv {i} = {}",
            m.uvs[i]
        );
    }
    // Every triangle winds counter-clockwise seen from its vertices' normals.
    for (k, tri) in m.triangles().enumerate() {
        let [a, b, c] = tri.map(|i| m.positions[i]);
        let face = (b - a).cross(c - a);
        assert!(
            tri.iter().all(|&i| face.dot(m.normals[i]) > 0.0),
            "triangle {k} winds against its normals"
        );
    }
    let leaves = 5500;
    let mut up = 0.0;
    for i in 0..leaves {
        let v = leaf_vertices(i);
        let [centre, tip, left, stem, right] = [0, 1, 2, 3, 4].map(|k| v.start + k);
        let uv = |k: usize| m.uvs[k];
        assert_eq!(
            [uv(centre), uv(tip), uv(left), uv(stem), uv(right)],
            [
                Vec2::new(0.5, 0.6),
                Vec2::new(0.5, 0.0),
                Vec2::new(0.0, 0.6),
                Vec2::new(0.5, 1.0),
                Vec2::new(1.0, 0.6)
            ]
        );
        let p = |k: usize| m.positions[k];
        for k in v.clone() {
            let (n, t) = (m.normals[k], m.tangents[k]);
            let bitangent = t.w * n.cross(t.truncate());
            // Tangent toward +u (left to right), bitangent toward −v (stem to tip).
            assert!(
                t.truncate().dot(p(right) - p(left)) > 0.0,
                "leaf {i} vertex {k}: tangent against +u"
            );
            assert!(
                bitangent.dot(p(tip) - p(stem)) > 0.0,
                "leaf {i} vertex {k}: bitangent against −v"
            );
        }
        let n = m.normals[centre];
        assert!(n.y > 0.25, "leaf {i} faces down or sideways: {n}");
        up += n.y;
    }
    let mean_up = up / leaves as f32;
    assert!(
        mean_up > 0.75 && mean_up < 0.99,
        "mean leaf normal y = {mean_up}: mostly upward, with tilt"
    );
}

#[test]
fn crown_lies_within_its_declared_bounds() {
    for (leaves, seed, radius, height, leaf_size) in [
        (5500u32, 1u32, 1.0f32, 1.2f32, 0.12f32),
        (400, 7, 0.5, 2.0, 0.05),
        (400, 9, 2.0, 0.5, 0.3),
    ] {
        let m = bush(leaves, seed, radius, height, leaf_size);
        let semi = Vec3::new(radius, CROWN_FLATTENING * radius, radius);
        let centre = Vec3::new(0.0, height, 0.0);
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for i in 0..leaves as usize {
            let v = leaf_vertices(i);
            let c = m.positions[v.start];
            let e = ((c - centre) / semi).length_squared();
            assert!(e <= 1.0 + 1e-5, "leaf {i}'s centre {c} is outside the crown ({e})");
            for k in v {
                let d = (m.positions[k] - c).length();
                assert!(
                    d <= 0.76 * leaf_size,
                    "leaf {i}: a vertex {d} m from its centre (leaf_size {leaf_size})"
                );
            }
            (lo, hi) = (lo.min(c), hi.max(c));
        }
        // The leaves fill the crown rather than a corner of it.
        assert!(
            (lo - centre).cmplt(-0.8 * semi).all() && (hi - centre).cmpgt(0.8 * semi).all(),
            "leaf centres span only {lo} to {hi}"
        );
        // Everything, the wood too, within the crown's cylinder plus a leaf, above the trunk's
        // base unless the crown reaches lower.
        let floor = (height - semi.y - leaf_size).min(0.0);
        for (k, p) in m.positions.iter().enumerate() {
            let horizontal = Vec2::new(p.x, p.z).length();
            assert!(
                horizontal <= radius + leaf_size,
                "vertex {k} at {p}: beyond the crown's radius"
            );
            assert!(
                p.y >= floor && p.y <= height + semi.y + leaf_size,
                "vertex {k} at {p}: beyond the crown's height"
            );
        }
        let wood = &m.positions[LEAF_VERTICES * leaves as usize..];
        let wood_lo = wood.iter().fold(f32::MAX, |a, p| a.min(p.y));
        assert_eq!(wood_lo, 0.0, "the trunk stands on the origin");
    }
}

#[test]
fn degenerate_sizes_never_panic() {
    assert_eq!(
        bush(0, 1, 1.0, 1.2, 0.12).triangle_count(),
        LEAF_TRIANGLES + BUSH_WOOD_TRIANGLES,
        "0 leaves is clamped to 1"
    );
    assert_eq!(
        bush(u32::MAX, 1, 1.0, 1.2, 0.001).triangle_count(),
        LEAF_TRIANGLES * 100_000 + BUSH_WOOD_TRIANGLES,
        "clamped to 100,000"
    );
    for (radius, height, leaf_size) in [(0.0, 0.0, 0.0), (-1.0, -1.0, -1.0), (1e-30, 1.0, 1e-30)] {
        let m = bush(50, 1, radius, height, leaf_size);
        m.validate("bush").unwrap();
        assert!(
            m.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-4),
            "radius {radius}, height {height}, leaf_size {leaf_size}"
        );
    }
    for bad in [f32::NAN, f32::INFINITY] {
        let e = bush(50, 1, bad, 1.2, 0.12).validate("bush").unwrap_err();
        assert!(e.to_string().contains("not finite"), "{e}");
        assert!(bush(50, 1, 1.0, 1.2, bad).validate("bush").is_err());
    }
}

#[test]
fn scene_loads_with_the_bush_the_ground_and_the_leaf_maps() {
    let s = Scene::from_file(root().join("scenes/lpv_bush.toml")).unwrap();
    let names: Vec<&str> = s.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["ground", "bush"]);
    assert_eq!(
        s.objects[1].mesh,
        MeshSource::Bush {
            leaves: 5500,
            seed: 1,
            radius: 1.0,
            height: 1.2,
            leaf_size: 0.12
        }
    );
    let ground = s.objects[0].load_mesh(Path::new(".")).unwrap();
    let plant = s.objects[1].load_mesh(Path::new(".")).unwrap();
    assert_eq!((ground.triangle_count(), plant.triangle_count()), (2738, 22_112));
    assert!(plant == default_bush());
    let leaf = s.material_of(&s.objects[1]).unwrap();
    assert_eq!(leaf.name, "leaf");
    assert!(leaf
        .albedo_map
        .as_ref()
        .is_some_and(|p| p.ends_with("textures/leaf_albedo.png")));
    assert!(leaf
        .normal_map
        .as_ref()
        .is_some_and(|p| p.ends_with("textures/leaf_normal.png")));
    assert!(leaf.transmittance.min_element() > 0.0 && (leaf.albedo + leaf.transmittance).max_element() <= 1.0);
    let names: Vec<&str> = s.methods.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["forward", "lpv"]);
    let combinations: Vec<&str> = s.combinations.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(combinations, ["lpv_over_forward"]);
    let [Light::Directional {
        direction, irradiance, ..
    }] = s.lights.as_slice()
    else {
        panic!("expected one sun, got {:?}", s.lights)
    };
    let zenith = (-direction.y).acos().to_degrees();
    assert!(
        (zenith - 35.0).abs() < 0.5 && *irradiance == Vec3::splat(3.0),
        "sun {zenith}° from the zenith, {irradiance}"
    );
    assert!(matches!(s.environment, Some(Environment::Constant { radiance }) if (radiance.y - 0.1).abs() < 0.02));
}

#[test]
fn leaf_maps_pack_wind_weight_and_translucency() {
    let dir = root().join("scenes/textures");
    let open = |name: &str| {
        let path = dir.join(name);
        assert!(
            std::fs::metadata(&path).unwrap().len() < 100_000,
            "{name} is over 100 KB"
        );
        let img = image::open(&path).unwrap();
        assert_eq!(img.color(), image::ColorType::Rgba8, "{name}");
        img.to_rgba8()
    };
    let (albedo, normal) = (open("leaf_albedo.png"), open("leaf_normal.png"));
    let n = albedo.width();
    assert!(
        (n, albedo.height()) == (128, 128) || (n, albedo.height()) == (256, 256),
        "{n}x{}",
        albedo.height()
    );
    assert_eq!(normal.dimensions(), albedo.dimensions());
    let bark = |x: u32, y: u32| (x as f32 + 0.5) / (n as f32) < 0.2 && (y as f32 + 0.5) / (n as f32) > 0.85;
    // Albedo alpha: the wind weight, 1 on the tip's row, 0 on the stem's, growing toward the
    // tip; 0 on the bark.
    for x in 0..n {
        assert_eq!(albedo.get_pixel(x, 0).0[3], 255);
        assert_eq!(albedo.get_pixel(x, n - 1).0[3], 0);
        for y in 1..n {
            assert!(
                bark(x, y) || albedo.get_pixel(x, y).0[3] <= albedo.get_pixel(x, y - 1).0[3],
                "wind weight grows toward the stem at ({x}, {y})"
            );
        }
    }
    assert_eq!(albedo.get_pixel(2, n - 2).0[3], 0);
    // A leaf green on the lamina (G > R > B), brown on the bark (R > G > B).
    let [r, g, b, _] = albedo.get_pixel(n / 2 + n / 8, n / 2).0;
    assert!(g > r && r > b, "lamina {r} {g} {b}");
    let [r, g, b, _] = albedo.get_pixel(4, n - 4).0;
    assert!(r > g && g > b, "bark {r} {g} {b}");
    // Normal map: unit normals facing out of the surface; the midrib a ridge (its right flank
    // leans toward +u, its left toward −u); the bark flat and opaque.
    let decode = |x: u32, y: u32| {
        let p = normal.get_pixel(x, y).0;
        Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) / 127.5 - Vec3::ONE
    };
    for y in 0..n {
        for x in 0..n {
            let v = decode(x, y);
            assert!((v.length() - 1.0).abs() < 0.03 && v.z > 0.5, "normal ({x}, {y}) = {v}");
        }
    }
    let row = 3 * n / 4;
    assert!(
        decode(n / 2 + 1, row).x > 0.1 && decode(n / 2 - 2, row).x < -0.1,
        "the midrib is no ridge: {} {}",
        decode(n / 2 - 2, row),
        decode(n / 2 + 1, row)
    );
    assert_eq!(normal.get_pixel(4, n - 4).0, [128, 128, 255, 0]);
    // Normal alpha: translucency, lower on the midrib (thicker) than on the lamina.
    let (midrib, lamina) = (
        normal.get_pixel(n / 2, row).0[3],
        normal.get_pixel(n / 2 + n / 6, row + 5).0[3],
    );
    assert!(midrib + 40 < lamina && lamina > 180, "midrib {midrib}, lamina {lamina}");
}

/// `penumbra capture` of the scene at 64×48 through the binary, validation on: it succeeds, and
/// the bush in the middle of the frame is green over a brown ground.
#[test]
fn capture_of_the_scene_shows_a_green_bush() {
    let (png, exr) = (common::temp_path("bush.png"), common::temp_path("bush.exr"));
    let scene = root().join("scenes/lpv_bush.toml");
    let arg = |p: &Path| p.to_str().expect("utf-8 path").to_owned();
    let started = std::time::Instant::now();
    let o = common::penumbra(&[
        "capture",
        &arg(&scene),
        "--size",
        "64x48",
        "-o",
        &arg(&png),
        "--exr",
        &arg(&exr),
    ]);
    common::ok(&o);
    println!(
        "capture of lpv_bush.toml at 64x48: {:.2} s",
        started.elapsed().as_secs_f64()
    );
    assert!(png.exists());
    let img = HdrImage::read_exr(&exr).unwrap();
    assert_eq!((img.width, img.height), (64, 48));
    let mean = |xs: std::ops::Range<u32>, ys: std::ops::Range<u32>| {
        let mut sum = Vec3::ZERO;
        let mut count = 0.0;
        for y in ys {
            for x in xs.clone() {
                let p = img.get(x, y);
                sum += Vec3::new(p[0], p[1], p[2]);
                count += 1.0;
            }
        }
        sum / count
    };
    let bush = mean(24..40, 16..32);
    assert!(
        bush.is_finite() && bush.y > 1.2 * bush.x && bush.y > 1.5 * bush.z,
        "the middle is not leaf green: {bush}"
    );
    let ground = mean(0..64, 46..48);
    assert!(
        ground.x > ground.y && ground.y > ground.z,
        "the bottom rows are not soil: {ground}"
    );
}

/// A bad bush key through the binary: one error line naming the file, the line and the field.
#[test]
fn a_bad_bush_key_is_one_error_line() {
    let path = common::temp_path("bad_bush.toml");
    std::fs::write(
        &path,
        "[camera]\nposition = [0, 1, 3]\ntarget = [0, 0, 0]\n[[objects]]\nmesh = \"bush\"\nleaves = 0\n",
    )
    .unwrap();
    let out = common::temp_path("bad_bush.png");
    let o = common::penumbra(&[
        "capture",
        path.to_str().unwrap(),
        "--size",
        "16x16",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success() && !out.exists());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(
        err.trim_end(),
        format!(
            "error: {}:6: objects[0].leaves: expected an integer from 1 to 100000, got 0",
            path.display()
        )
    );
}
