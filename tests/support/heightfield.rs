//! Helpers of the height-field tests: a scene with one field, and the camera-less harness with
//! its validation check.
#![allow(dead_code)]

use penumbra::lighting::heightfield::standalone::Standalone;
use penumbra::scene::Scene;

/// A scene with one height field (`field`: the keys after `mesh = "heightfield"`), the method
/// declaration `method` (a TOML inline table) and `extra` (lights, environment).
pub fn scene(field: &str, method: &str, extra: &str) -> Scene {
    let toml = format!(
        r#"methods = [{method}]
[camera]
position = [0, 10, 10]
target = [0, 0, 0]
[[materials]]
name = "ground"
albedo = 1
[[objects]]
mesh = "heightfield"
material = "ground"
{field}
{extra}
"#
    );
    Scene::from_str(&toml, "<test>", std::path::Path::new("/")).unwrap_or_else(|e| panic!("{e}\n{toml}"))
}

pub fn harness(s: &Scene) -> Standalone {
    Standalone::new(crate::support::test_gpu(), s, &s.methods[0]).unwrap()
}

pub fn clean(h: &Standalone) {
    let m = h.validation_messages();
    assert!(m.is_empty(), "{} validation message(s):\n{}", m.len(), m.join("\n"));
}
