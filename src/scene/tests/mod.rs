//! Scene-level tests: the shipped scenes parse, and malformed scenes fail with the exact file,
//! line and field.

mod lights;

use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};

use super::mesh::tests::assert_well_formed;
use super::obj::tests::temp_dir;
use super::*;

const CAM: &str = "[camera]\nposition = [0, 1, 5]\ntarget = [0, 0, 0]\n"; // lines 1-3

fn parse(text: &str) -> Result<Scene, SceneError> {
    Scene::from_str(text, "bad.toml", Path::new("."))
}

/// Parses `text`, expecting an error at exactly `line` and `field`; returns the error.
#[track_caller]
fn fails_at(text: &str, line: usize, field: &str) -> SceneError {
    let e = parse(text).expect_err("scene should be rejected");
    assert_eq!(
        (e.file.as_str(), e.line, e.field.as_str()),
        ("bad.toml", Some(line), field),
        "{e}"
    );
    assert!(!e.to_string().contains('\n'), "error spans lines: {e}");
    e
}

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

fn load_all(scene: &Scene) -> Vec<Mesh> {
    scene
        .objects
        .iter()
        .map(|o| {
            let m = o.load_mesh(Path::new(".")).unwrap();
            assert_well_formed(&m);
            m
        })
        .collect()
}

#[test]
fn default_scene_parses_and_has_what_it_promises() {
    let s = Scene::default_scene();
    assert_eq!(s.source, DEFAULT_SOURCE);
    assert_eq!(s.materials.len(), 3);
    assert!(
        s.materials.iter().any(|m| m.specular.x >= 0.5 && m.exponent >= 100.0),
        "a shiny material"
    );
    let names: Vec<&str> = s.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["ground", "crate", "ball"]);
    assert!(matches!(s.objects[0].mesh, MeshSource::Plane { .. }));
    assert!(matches!(s.objects[1].mesh, MeshSource::Box { .. }));
    assert!(matches!(s.objects[2].mesh, MeshSource::Sphere { .. }));
    let kinds: Vec<&str> = s
        .lights
        .iter()
        .map(|l| match l {
            Light::Directional { .. } => "directional",
            Light::Point { .. } => "point",
            Light::Spot { .. } => "spot",
            _ => "other",
        })
        .collect();
    assert_eq!(kinds, ["directional", "point", "spot"]);
    assert_eq!(s.methods, vec![MethodDecl::implicit_forward()]);
    assert!(matches!(s.environment, Some(Environment::Constant { .. })));
    let meshes = load_all(&s);
    assert!(meshes[1].is_closed_manifold() && meshes[2].is_closed_manifold());
    // The spot aims at the ball.
    if let Light::Spot {
        position, direction, ..
    } = &s.lights[2]
    {
        let to_ball = (s.objects[2].transform.w_axis.truncate() - *position).normalize();
        assert!(direction.dot(to_ball) > 0.9999);
    }
}

#[test]
fn shipped_default_toml_matches_the_built_in() {
    let shipped = std::fs::read_to_string(scenes_dir().join("default.toml")).unwrap();
    assert_eq!(
        shipped, DEFAULT_SCENE_TOML,
        "scenes/default.toml and src/scene/default.toml differ"
    );
    let s = Scene::from_file(scenes_dir().join("default.toml")).unwrap();
    assert_eq!(s.objects.len(), 3);
}

#[test]
fn cornell_scene_expands_the_built_in_box() {
    let s = Scene::from_file(scenes_dir().join("cornell.toml")).unwrap();
    let names: Vec<&str> = s.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "cornell.floor",
            "cornell.ceiling",
            "cornell.back",
            "cornell.left",
            "cornell.right",
            "cornell.short_block",
            "cornell.tall_block"
        ]
    );
    let mat = |i: usize| s.materials[s.objects[i].material].name.as_str();
    assert_eq!(
        (mat(0), mat(3), mat(4), mat(6)),
        ("cornell_white", "cornell_red", "cornell_green", "cornell_white")
    );
    let [Light::Quad {
        corner,
        edge_u,
        edge_v,
        radiance,
        ..
    }] = s.lights.as_slice()
    else {
        panic!("expected one quad light, got {:?}", s.lights);
    };
    assert!(
        edge_u.cross(*edge_v).normalize().dot(Vec3::NEG_Y) > 0.9999,
        "light faces down"
    );
    assert!(corner.y > 1.99 && corner.y < 2.0 && *radiance == cornell::LIGHT_RADIANCE);
    let meshes = load_all(&s);
    // Walls face the inside of the box; blocks are closed and stand on the floor inside it.
    for (o, m) in s.objects.iter().zip(&meshes).take(5) {
        let w = m.transformed(&o.transform);
        let inward = Vec3::new(0.0, 1.0, 0.0) - w.positions[0];
        assert!(w.normals[0].dot(inward) > 0.0, "{} faces outward", o.name);
    }
    for (o, m) in s.objects.iter().zip(&meshes).skip(5) {
        assert!(m.is_closed_manifold());
        let (lo, hi) = m.transformed(&o.transform).bounds().unwrap();
        assert!(
            lo.y.abs() < 1e-5 && lo.min_element() > -1.0 && hi.max_element() < 1.3,
            "{}",
            o.name
        );
    }
}

#[test]
fn transform_order_is_scale_then_x_y_z_rotation_then_translate() {
    let text = format!(
        "{CAM}[[objects]]\nmesh = \"box\"\nrotate_deg = [90, 90, 0]\nscale = [1, 2, 3]\ntranslate = [5, 0, 0]\n"
    );
    let s = parse(&text).unwrap();
    let m: Mat4 = s.objects[0].transform;
    // +y, scaled to 2y, x-rotation sends it to 2z, y-rotation to 2x, then translated.
    assert!((m.transform_point3(Vec3::Y) - Vec3::new(7.0, 0.0, 0.0)).length() < 1e-5);
    assert_eq!(s.objects[0].name, "objects[0]");
    assert_eq!(s.materials[s.objects[0].material].name, "default");
}

#[test]
fn methods_keep_order_params_and_lines() {
    let text = format!("methods = [\"forward\", {{ name = \"shadow_map\", resolution = 2048 }}]\n{CAM}");
    let s = parse(&text).unwrap();
    assert_eq!(s.methods.len(), 2);
    assert_eq!((s.methods[0].name.as_str(), s.methods[0].line), ("forward", 1));
    assert_eq!(s.methods[1].param("resolution"), Some(&toml::Value::Integer(2048)));

    let text = format!("{CAM}[[methods]]\nname = \"deferred\"\n\n[[methods]]\nname = \"shadow_map\"\nresolution = 1024\nbias = [0.5, 2]\n");
    let s = parse(&text).unwrap();
    let m = &s.methods[1];
    assert_eq!((m.name.as_str(), m.line), ("shadow_map", 8));
    let params: Vec<(&str, usize)> = m.params.iter().map(|(n, _, l)| (n.as_str(), *l)).collect();
    assert_eq!(params, [("resolution", 9), ("bias", 10)]);
    let known = [
        MethodSchema {
            name: "forward",
            params: &[],
        },
        MethodSchema {
            name: "deferred",
            params: &[],
        },
        MethodSchema {
            name: "shadow_map",
            params: &[
                ParamSchema {
                    name: "resolution",
                    kind: ParamKind::Int,
                },
                ParamSchema {
                    name: "bias",
                    kind: ParamKind::FloatArray,
                },
            ],
        },
    ];
    s.check_methods(&known).unwrap();
    Scene::default_scene().check_methods(&known).unwrap();
}

#[test]
fn unknown_method_and_parameter_and_type_name_line_and_field() {
    let known = [
        MethodSchema {
            name: "forward",
            params: &[],
        },
        MethodSchema {
            name: "shadow_map",
            params: &[ParamSchema {
                name: "resolution",
                kind: ParamKind::Int,
            }],
        },
    ];
    let check = |text: String| parse(&text).unwrap().check_methods(&known).unwrap_err();

    let e = check(format!(
        "{CAM}[[methods]]\nname = \"forward\"\n[[methods]]\nname = \"shadowmap\"\n"
    ));
    assert_eq!((e.line, e.field.as_str()), (Some(7), "methods[1]"));
    assert!(
        e.message
            .contains("unknown method \"shadowmap\"; known methods: forward, shadow_map"),
        "{e}"
    );

    let e = check(format!("{CAM}[[methods]]\nname = \"shadow_map\"\n\nresolutoin = 4\n"));
    assert_eq!((e.line, e.field.as_str()), (Some(7), "methods[0].resolutoin"));
    assert!(e.message.contains("known parameters: resolution (int)"), "{e}");

    let e = check(format!("{CAM}[[methods]]\nname = \"shadow_map\"\nresolution = 1.5\n"));
    assert_eq!(
        e.to_string(),
        "bad.toml:6: methods[0].resolution: expected an integer, got 1.5"
    );

    let e = check(format!("methods = [{{ name = \"forward\", x = 1 }}]\n{CAM}"));
    assert_eq!((e.line, e.field.as_str()), (Some(1), "methods[0].x"));
    assert!(e.message.contains("takes no parameters"));
}

#[test]
fn syntax_error_gives_line() {
    let e = fails_at(&format!("{CAM}fov_y_deg = = 40\n"), 4, "syntax");
    assert!(e.message.contains("column"), "{e}");
    fails_at("[camera]\nposition = [0, 1,\ntarget = 3\n", 3, "syntax");
    fails_at(&format!("{CAM}position = [1, 1, 1]\n"), 4, "syntax"); // duplicate key
}

#[test]
fn unknown_fields_are_named() {
    let e = fails_at(&format!("{CAM}\n[lightz]\n"), 5, "lightz");
    assert!(e
        .message
        .contains("expected one of: camera, materials, objects, lights, environment, methods"));
    fails_at(&format!("{CAM}fov = 40\n"), 4, "camera.fov");
    // A misspelt key is reported before the required key it replaces.
    fails_at(
        &format!("{CAM}[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensty = 5\n"),
        7,
        "lights[0].intensty",
    );
    fails_at(&format!("{CAM}[[objects]]\nmseh = \"box\"\n"), 5, "objects[0].mseh");
    fails_at(
        &format!("{CAM}[[objects]]\nmesh = \"cornell_box\"\nmaterial = \"x\"\n"),
        6,
        "objects[0].material",
    );
    fails_at(
        &format!("{CAM}[[objects]]\nmesh = \"box\"\nradius = 2\n"),
        6,
        "objects[0].radius",
    );
}

#[test]
fn wrong_types_are_named() {
    let e = fails_at(&format!("{CAM}fov_y_deg = \"wide\"\n"), 4, "camera.fov_y_deg");
    assert_eq!(
        e.message,
        "expected a vertical field of view in degrees, in (0, 180), got \"wide\""
    );
    fails_at("camera = 3\n", 1, "camera");
    fails_at(
        &format!("{CAM}[[objects]]\nmesh = \"sphere\"\nsegments = 2.5\n"),
        6,
        "objects[0].segments",
    );
    fails_at(&format!("materials = {{ name = \"a\" }}\n{CAM}"), 1, "materials");
    let e = fails_at(&format!("{CAM}near = 1979-05-27\n"), 4, "camera.near");
    assert!(e.message.contains("date-time"));
}

#[test]
fn negative_intensity_is_rejected_with_exact_message() {
    let text = format!("{CAM}\n[[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = 1\n\n[[lights]]\ntype = \"point\"\nposition = [0, 2, 0]\nintensity = -2\n");
    let e = fails_at(&text, 13, "lights[1].intensity");
    assert_eq!(
        e.to_string(),
        "bad.toml:13: lights[1].intensity: expected 3 non-negative numbers, got -2"
    );
    fails_at(
        &format!("{CAM}[[lights]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nradiance = [1, nan, 1]\n"),
        8,
        "lights[0].radiance",
    );
}

#[test]
fn value_checks_name_their_field() {
    let light = |body: &str| format!("{CAM}[[lights]]\n{body}");
    fails_at(&light("type = \"spot\"\nposition = [0, 2, 0]\ndirection = [0, -1, 0]\nintensity = 1\ninner_deg = 40\nouter_deg = 30\n"), 9, "lights[0].inner_deg");
    fails_at(
        &light("type = \"spot\"\nposition = [0, 2, 0]\nintensity = 1\n"),
        4,
        "lights[0].direction",
    );
    fails_at(
        &light("type = \"directional\"\ndirection = [0, 0, 0]\nirradiance = 1\n"),
        6,
        "lights[0].direction",
    );
    fails_at(
        &light("type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 0\nradiance = 1\n"),
        7,
        "lights[0].radius",
    );
    fails_at(
        &light("type = \"quad\"\ncorner = [0, 0, 0]\nedge_u = [1, 0, 0]\nedge_v = [2, 0, 0]\nradiance = 1\n"),
        8,
        "lights[0].edge_v",
    );
    fails_at(&light("type = \"laser\"\n"), 5, "lights[0].type");
    fails_at(&light("position = [0, 1, 0]\n"), 4, "lights[0].type");
    fails_at(
        "[camera]\nposition = [0, 1, 5]\ntarget = [0, 1, 5]\n",
        3,
        "camera.target",
    );
    fails_at("[camera]\nposition = [0, 5, 0]\ntarget = [0, 0, 0]\n", 1, "camera.up");
    fails_at(
        "[camera]\nposition = [0, 1, 5]\ntarget = [0, 0, 0]\nfov_y_deg = 180\n",
        4,
        "camera.fov_y_deg",
    );
    fails_at(
        "[camera]\nposition = [0, 1]\ntarget = [0, 0, 0]\n",
        2,
        "camera.position",
    );
    let e = parse("[materials]\n").unwrap_err();
    assert_eq!((e.line, e.field.as_str()), (Some(1), "camera"));
    let mat = |body: &str| format!("{CAM}[[materials]]\nname = \"a\"\n{body}");
    fails_at(&mat("albedo = [0.5, 1.2, 0.5]\n"), 6, "materials[0].albedo");
    fails_at(&mat("opacity = 0\n"), 6, "materials[0].opacity");
    fails_at(&mat("albedo = 0.5\nopacity = 1.5\n"), 7, "materials[0].opacity");
    fails_at(
        &mat("albedo = 0.7\ntransmittance = 0.5\n"),
        7,
        "materials[0].transmittance",
    );
    fails_at(&mat("[[materials]]\nname = \"a\"\n"), 7, "materials[1].name");
    fails_at(
        &mat("albedo_map = \"textures/none.png\"\n"),
        6,
        "materials[0].albedo_map",
    );
    fails_at(
        &format!("{CAM}[environment]\ntype = \"image\"\npath = \"sky.hdr\"\n"),
        6,
        "environment.path",
    );
    fails_at(&format!("{CAM}[[objects]]\nmesh = \"teapot\"\n"), 5, "objects[0].mesh");
    fails_at(
        &format!("{CAM}[[objects]]\nmesh = \"plane\"\nsubdivisions = 0\n"),
        6,
        "objects[0].subdivisions",
    );
    fails_at(
        &format!("{CAM}[[objects]]\nmesh = \"box\"\nscale = [1, 0, 1]\n"),
        6,
        "objects[0].scale",
    );
}

#[test]
fn bush_keys_default_and_bad_values_name_their_field() {
    let s = parse(&format!("{CAM}[[objects]]\nmesh = \"bush\"\n")).unwrap();
    assert_eq!(
        s.objects[0].mesh,
        MeshSource::Bush {
            leaves: 5500,
            seed: 1,
            radius: 1.0,
            height: 1.2,
            leaf_size: 0.12
        }
    );
    let s = parse(&format!(
        "{CAM}[[objects]]\nmesh = \"bush\"\nleaves = 12\nseed = 0\nradius = 0.5\nheight = 2\nleaf_size = 0.05\n"
    ))
    .unwrap();
    assert_eq!(
        s.objects[0].mesh,
        MeshSource::Bush {
            leaves: 12,
            seed: 0,
            radius: 0.5,
            height: 2.0,
            leaf_size: 0.05
        }
    );
    assert_eq!(
        load_all(&s)[0].triangle_count(),
        4 * 12 + generators::BUSH_WOOD_TRIANGLES
    );

    // Lines: 4 [[objects]], 5 mesh, 6 the key under test.
    let bush = |body: &str| format!("{CAM}[[objects]]\nmesh = \"bush\"\n{body}");
    let e = fails_at(&bush("leaves = 0\n"), 6, "objects[0].leaves");
    assert_eq!(
        e.to_string(),
        "bad.toml:6: objects[0].leaves: expected an integer from 1 to 100000, got 0"
    );
    fails_at(&bush("leaves = 100001\n"), 6, "objects[0].leaves");
    fails_at(&bush("leaves = 5.5\n"), 6, "objects[0].leaves");
    let e = fails_at(&bush("seed = -1\n"), 6, "objects[0].seed");
    assert_eq!(e.message, "expected an integer from 0 to 4294967295, got -1");
    let e = fails_at(&bush("radius = -1\n"), 6, "objects[0].radius");
    assert_eq!(
        e.to_string(),
        "bad.toml:6: objects[0].radius: expected a positive number, got -1"
    );
    fails_at(&bush("radius = nan\n"), 6, "objects[0].radius");
    fails_at(&bush("height = 0\n"), 6, "objects[0].height");
    fails_at(&bush("leaves = 10\nleaf_size = -0.1\n"), 7, "objects[0].leaf_size");
    // A string where each number belongs.
    for key in ["leaves", "seed", "radius", "height", "leaf_size"] {
        let e = fails_at(&bush(&format!("{key} = \"big\"\n")), 6, &format!("objects[0].{key}"));
        assert!(e.message.ends_with("got \"big\""), "{e}");
    }
    // Keys of other meshes are not the bush's.
    let e = fails_at(&bush("subdivisions = 4\n"), 6, "objects[0].subdivisions");
    assert!(e.message.contains("leaves, seed, radius, height, leaf_size"), "{e}");
    let e = fails_at(&format!("{CAM}[[objects]]\nmesh = \"bushes\"\n"), 5, "objects[0].mesh");
    assert!(e.message.contains("sphere, bush, obj"), "{e}");
}

#[test]
fn unknown_material_reference_lists_defined_ones() {
    let text = format!("{CAM}[[materials]]\nname = \"red\"\nalbedo = [0.8, 0.1, 0.1]\n\n[[objects]]\nmesh = \"sphere\"\nmaterial = \"blue\"\n");
    let e = fails_at(&text, 10, "objects[0].material");
    assert!(
        e.message
            .contains("unknown material \"blue\"; defined materials: red, default, cornell_white"),
        "{e}"
    );
}

#[test]
fn missing_obj_file_is_named() {
    let e = fails_at(
        &format!("{CAM}[[objects]]\nmesh = \"obj\"\npath = \"meshes/nope.obj\"\n"),
        6,
        "objects[0].path",
    );
    assert!(e.message.starts_with("file not found: meshes/nope.obj"), "{e}");
}

#[test]
fn missing_scene_file_is_named() {
    let e = Scene::from_file("scenes/nope.toml").unwrap_err();
    assert_eq!(
        e.to_string(),
        "scenes/nope.toml: file: cannot read: No such file or directory (os error 2)"
    );
}

#[test]
fn scene_with_obj_and_texture_resolves_relative_paths() {
    let dir = temp_dir("objscene");
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    std::fs::write(dir.join("meshes/tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    image::RgbaImage::new(1, 1).save(dir.join("albedo.png")).unwrap();
    let text = format!("{CAM}[[materials]]\nname = \"m\"\nalbedo_map = \"albedo.png\"\n[[objects]]\nmesh = \"obj\"\npath = \"meshes/tri.obj\"\nmaterial = \"m\"\n");
    std::fs::write(dir.join("scene.toml"), text).unwrap();
    let s = Scene::from_file(dir.join("scene.toml")).unwrap();
    let MeshSource::Obj(path) = &s.objects[0].mesh else {
        panic!()
    };
    assert!(path.is_absolute() && path.ends_with("meshes/tri.obj"));
    assert!(s.materials[0].albedo_map.as_ref().is_some_and(|p| p.is_absolute()));
    let m = s.objects[0].load_mesh(Path::new("/elsewhere")).unwrap();
    assert_eq!(m.triangle_count(), 1);
    assert_well_formed(&m);
}

#[test]
fn truncated_and_mangled_input_never_panics() {
    let text = DEFAULT_SCENE_TOML;
    for end in (0..text.len()).filter(|&i| text.is_char_boundary(i)) {
        let _ = parse(&text[..end]);
    }
    for bad in ["nan", "-1", "\"x\"", "[]", "{}", "1e39", "true", "[1, 2, 3, 4]"] {
        for (i, _) in text.match_indices("= ") {
            let rest = &text[i + 2..];
            let end = rest.find('\n').unwrap_or(rest.len());
            let mangled = format!("{}= {bad}{}", &text[..i], &rest[end..]);
            let _ = parse(&mangled);
        }
    }
}

#[test]
fn readme_examples_parse() {
    let readme = std::fs::read_to_string(scenes_dir().join("README.md")).unwrap();
    let blocks: Vec<&str> = readme
        .split("```toml\n")
        .skip(1)
        .filter_map(|b| b.split("```").next())
        .collect();
    assert_eq!(blocks.len(), 7);
    let rig = parse(&format!("{CAM}{}", blocks[0])).unwrap();
    assert_eq!((rig.lights.len(), rig.lights[39].name()), (40, "rig[39]"));
    let board = parse(&format!("{CAM}{}", blocks[1])).unwrap();
    assert_eq!(
        board.light_board,
        Some(LightBoard {
            depth: 0.8,
            rate_hz: 0.4,
            seed: 7
        })
    );
    let sun = "[[lights]]\ntype = \"directional\"\nname = \"sun\"\ndirection = [0, -1, 0]\nirradiance = 1\n";
    let turning = parse(&format!("{CAM}{sun}{}", blocks[2])).unwrap();
    assert_eq!(
        turning.light_motion,
        Some(super::motion::LightMotion {
            light: 0,
            axis: glam::Vec3::Y,
            deg_per_s: 6.0
        })
    );
    let blocks = &blocks[3..];
    let dir = temp_dir("readme");
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    std::fs::write(dir.join("meshes/spot.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let example = Scene::from_str(blocks[3], "README.md", &dir).unwrap();
    let combo = parse(&format!("{}\n{CAM}", blocks[2])).unwrap();
    let c = &combo.combinations[0];
    let terms: Vec<(&str, &str)> = c.terms.iter().map(|(k, m, _)| (*k, m.as_str())).collect();
    assert_eq!(
        (c.name.as_str(), terms),
        (
            "shadowed_over_forward",
            vec![("base", "forward"), ("direct", "shadow_volumes")]
        )
    );
    assert_eq!((example.objects.len(), example.lights.len()), (2, 1));
    for methods in &blocks[..2] {
        let s = parse(&format!("{methods}\n{CAM}")).unwrap();
        let names: Vec<&str> = s.methods.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["forward", "shadow_volumes"]);
        assert_eq!(
            s.methods[1].param("mode"),
            Some(&toml::Value::String("physical".into()))
        );
    }
}

/// Writes six `size`² EXR faces into `dir` (face k filled with k + 1, or `bad` at texel 0 of
/// face `bad_face`) and returns the `[environment]` table that names them, from line 4.
fn cube_env(dir: &Path, sizes: [(u32, u32); 6], poison: Option<(usize, f32)>) -> String {
    let mut text = format!("{CAM}[environment]\ntype = \"cube\"\nscale = 2\n");
    for (k, key) in CUBE_FACE_KEYS.into_iter().enumerate() {
        let (w, h) = sizes[k];
        let mut img = crate::util::image_io::HdrImage::new(w, h);
        for p in &mut img.pixels {
            *p = [k as f32 + 1.0, 0.5, 0.25, 1.0];
        }
        if let Some((face, v)) = poison {
            if face == k {
                img.pixels[w as usize + 1][1] = v;
            }
        }
        let name = format!("{key}.exr");
        img.write_exr(&dir.join(&name)).unwrap();
        text += &format!("{key} = \"{name}\"\n");
    }
    text
}

#[test]
fn cube_environment_loads_six_faces_in_layer_order() {
    let dir = temp_dir("cube-ok");
    let text = cube_env(&dir, [(4, 4); 6], None);
    let s = Scene::from_str(&text, "cube.toml", &dir).unwrap();
    let Some(Environment::Cube { faces, scale }) = &s.environment else {
        panic!("{:?}", s.environment)
    };
    assert_eq!(*scale, 2.0);
    let c = CubeFaces::load(faces, *scale).unwrap();
    assert_eq!((c.size, c.texels.len()), (4, 96));
    for k in 0..6 {
        assert_eq!(c.texels[16 * k + 5], [2.0 * (k as f32 + 1.0), 1.0, 0.5, 0.0]);
    }
}

#[test]
fn bad_cube_faces_name_the_file_line_and_face() {
    let dir = temp_dir("cube-bad");
    let parse_in = |text: &str| Scene::from_str(text, "bad.toml", &dir).expect_err("scene should be rejected");
    let check = |e: SceneError, line: usize, field: &str, says: &str| {
        assert_eq!(
            (e.file.as_str(), e.line, e.field.as_str()),
            ("bad.toml", Some(line), field),
            "{e}"
        );
        assert!(e.to_string().contains(says), "{e}");
        assert!(!e.to_string().contains('\n'), "error spans lines: {e}");
    };
    // Lines: 4 [environment], 5 type, 6 scale, 7 px, 8 nx, 9 py, 10 ny, 11 pz, 12 nz.
    let mut sizes = [(4, 4); 6];
    sizes[3] = (4, 3);
    check(
        parse_in(&cube_env(&dir, sizes, None)),
        10,
        "environment.ny",
        "ny.exr: a cube face must be square",
    );
    let mut sizes = [(4, 4); 6];
    sizes[4] = (8, 8);
    check(
        parse_in(&cube_env(&dir, sizes, None)),
        11,
        "environment.pz",
        "pz.exr: is 8x8 but px is 4x4",
    );
    check(
        parse_in(&cube_env(&dir, [(4, 4); 6], Some((1, f32::NAN)))),
        8,
        "environment.nx",
        "nx.exr: texel (1, 1) is not finite",
    );
    check(
        parse_in(&cube_env(&dir, [(4, 4); 6], Some((5, f32::INFINITY)))),
        12,
        "environment.nz",
        "texel (1, 1) is not finite",
    );
    let good = cube_env(&dir, [(4, 4); 6], None);
    check(
        parse_in(&good.replace("py.exr", "missing.exr")),
        9,
        "environment.py",
        "file not found: missing.exr",
    );
    std::fs::write(dir.join("garbage.exr"), b"not an image").unwrap();
    check(
        parse_in(&good.replace("ny.exr", "garbage.exr")),
        10,
        "environment.ny",
        "garbage.exr: corrupt or truncated OpenEXR data",
    );
    check(
        parse_in(&good.replace("pz = \"pz.exr\"\n", "")),
        4,
        "environment.pz",
        "",
    );
    check(
        parse_in(&good.replace("scale = 2", "scale = -1")),
        6,
        "environment.scale",
        "",
    );
    check(
        parse_in(&good.replace("type = \"cube\"", "type = \"cubes\"")),
        5,
        "environment.type",
        "expected constant, image or cube",
    );
}
