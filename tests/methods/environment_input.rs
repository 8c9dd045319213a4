//! Environment images are checked where they enter, once, for every consumer (the raster
//! methods, the height-field projection, the path tracer): a NaN, an infinity or a negative
//! radiance is one error line naming the scene, the field, the file and the pixel, never an
//! image of NaN or a silently black environment term.

use crate::support as common;

use penumbra::util::image_io::HdrImage;

fn scene_with_sky(name: &str, bad: [f32; 4], methods: &str, object: &str) -> (std::path::PathBuf, std::path::PathBuf) {
    let mut img = HdrImage::new(16, 8);
    for p in img.pixels.iter_mut() {
        *p = [0.5, 0.6, 0.7, 1.0];
    }
    img.pixels[3 * 16 + 5] = bad;
    let sky = common::temp_path(&format!("{name}.exr"));
    img.write_exr(&sky).unwrap();
    let scene = common::temp_path(&format!("{name}.toml"));
    let text = format!("methods = {methods}\n[camera]\nposition = [0, 1, 3]\ntarget = [0, 0, 0]\n{object}\n[environment]\ntype = \"image\"\npath = {:?}\n", sky.display().to_string());
    std::fs::write(&scene, text).unwrap();
    (scene, sky)
}

#[test]
fn non_finite_or_negative_environment_texels_are_refused_by_every_consumer() {
    let plane = "[[objects]]\nmesh = \"plane\"\nsize = [2, 2]\n";
    let field = "[[objects]]\nmesh = \"heightfield\"\ngenerator = \"flat\"\nresolution = 16\n";
    for (tag, bad) in [
        ("nan", [f32::NAN, 0.5, 0.5, 1.0]),
        ("inf", [0.5, f32::INFINITY, 0.5, 1.0]),
        ("negative", [0.5, 0.5, -0.25, 1.0]),
    ] {
        for (who, methods, object) in [
            ("forward", "[\"forward\"]", plane),
            ("heightfield", "[\"heightfield_pyramid\"]", field),
        ] {
            let (scene, sky) = scene_with_sky(&format!("env-{tag}-{who}"), bad, methods, object);
            let o = common::penumbra(&[
                "capture",
                scene.to_str().unwrap(),
                "--size",
                "16x16",
                "-o",
                common::temp_path("env.png").to_str().unwrap(),
            ]);
            assert!(!o.status.success(), "{tag} {who}: accepted");
            let e = String::from_utf8_lossy(&o.stderr);
            assert_eq!(e.lines().count(), 1, "{tag} {who}: {e}");
            assert!(
                e.starts_with(&format!(
                    "error: {}: environment.path: {}: pixel (5, 3) is (",
                    scene.display(),
                    sky.display()
                )),
                "{tag} {who}: {e}"
            );
            assert!(e.contains("radiance must be finite and not negative"), "{e}");
        }
        let (scene, _) = scene_with_sky(&format!("env-{tag}-ref"), bad, "[\"forward\"]", plane);
        let o = common::penumbra(&[
            "reference",
            scene.to_str().unwrap(),
            "--size",
            "4x4",
            "--spp",
            "1",
            "-o",
            common::temp_path("env-ref.exr").to_str().unwrap(),
        ]);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && e.contains("pixel (5, 3) is ("),
            "{tag} reference: {e}"
        );
    }
}
