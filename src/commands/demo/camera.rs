//! The fly camera and its bookmarks, saved next to the scene.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use glam::Vec3;
use winit::keyboard::KeyCode;

use crate::error::{Error, Result};
use crate::scene::Camera;

/// A fly camera: position plus yaw/pitch, seeded from the scene's camera.
#[derive(Clone, Debug)]
pub struct FlyCamera {
    pub base: Camera,
    pub yaw: f32,
    pub pitch: f32,
    /// Metres per second (Shift: four times as fast).
    pub speed: f32,
    /// The scene's own view until the camera turns: the same matrices as a headless capture.
    turned: bool,
}

impl FlyCamera {
    pub fn new(base: Camera) -> Self {
        let d = (base.target - base.position).normalize_or(Vec3::NEG_Z);
        FlyCamera {
            yaw: d.x.atan2(-d.z),
            pitch: d.y.clamp(-1.0, 1.0).asin(),
            base,
            speed: 2.0,
            turned: false,
        }
    }
    pub fn forward(&self) -> Vec3 {
        Vec3::new(
            self.yaw.sin() * self.pitch.cos(),
            self.pitch.sin(),
            -self.yaw.cos() * self.pitch.cos(),
        )
    }
    pub fn camera(&self) -> Camera {
        let mut c = self.base.clone();
        if self.turned {
            c.target = c.position + self.forward();
            c.up = Vec3::Y;
        }
        c
    }
    pub fn look(&mut self, dx: f32, dy: f32) {
        self.turn(dx * 0.003, -dy * 0.003);
    }
    /// Turns by yaw and pitch in radians.
    pub fn turn(&mut self, yaw: f32, pitch: f32) {
        if yaw == 0.0 && pitch == 0.0 {
            return;
        }
        let offset = self.base.target - self.base.position;
        self.yaw += yaw;
        self.pitch = (self.pitch + pitch).clamp(-1.5, 1.5);
        self.turned = true;
        self.base.target = self.base.position + self.forward() * offset.length().max(1e-3);
    }
    /// Moves by `offset` in world space.
    pub fn translate(&mut self, offset: Vec3) {
        self.base.position += offset;
        self.base.target += offset;
    }
    pub fn fly(&mut self, keys: &HashSet<KeyCode>, dt: f32) {
        let f = self.forward();
        let right = f.cross(Vec3::Y).normalize_or_zero();
        let mut v = Vec3::ZERO;
        for (k, d) in [
            (KeyCode::KeyW, f),
            (KeyCode::KeyS, -f),
            (KeyCode::KeyD, right),
            (KeyCode::KeyA, -right),
            (KeyCode::KeyE, Vec3::Y),
            (KeyCode::KeyQ, -Vec3::Y),
        ] {
            if keys.contains(&k) {
                v += d;
            }
        }
        let speed = if keys.contains(&KeyCode::ShiftLeft) {
            4.0 * self.speed
        } else {
            self.speed
        };
        let step = v.normalize_or_zero() * speed * dt;
        if step != Vec3::ZERO {
            self.translate(step);
        }
    }
}

/// One saved view.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Bookmark {
    pub position: [f32; 3],
    pub yaw: f32,
    pub pitch: f32,
}

#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Bookmarks {
    #[serde(default)]
    pub bookmark: Vec<Bookmark>,
}

/// Where a scene's bookmarks live: `scene.toml.bookmarks.toml` beside it (the built-in scene's
/// in the working directory).
pub fn bookmarks_path(scene: Option<&Path>) -> PathBuf {
    match scene {
        Some(p) => {
            let mut s = p.as_os_str().to_owned();
            s.push(".bookmarks.toml");
            PathBuf::from(s)
        }
        None => PathBuf::from("default-scene.bookmarks.toml"),
    }
}

impl Bookmarks {
    /// The saved bookmarks; none when the file does not exist. A malformed file is an error
    /// naming it.
    pub fn load(path: &Path) -> Result<Bookmarks> {
        let text = match std::fs::read_to_string(path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Bookmarks::default()),
            Err(e) => return Err(Error::Usage(format!("{}: {e}", path.display()))),
        };
        toml::from_str(&text).map_err(|e| Error::Usage(format!("{}: {}", path.display(), e.message())))
    }

    pub fn save(&self, path: &Path) -> Result<()> {
        let text = toml::to_string(self).map_err(|e| Error::Usage(format!("{}: {e}", path.display())))?;
        crate::util::image_io::write_file(path, text.as_bytes())
            .map_err(|e| Error::Usage(format!("{}: {e}", path.display())))
    }

    pub fn add(&mut self, camera: &FlyCamera) {
        self.bookmark.push(Bookmark {
            position: camera.base.position.into(),
            yaw: camera.yaw,
            pitch: camera.pitch,
        });
    }

    /// Moves `camera` to bookmark `i`.
    pub fn apply(&self, i: usize, camera: &mut FlyCamera) -> bool {
        let Some(b) = self.bookmark.get(i) else { return false };
        camera.translate(Vec3::from(b.position) - camera.base.position);
        camera.turn(b.yaw - camera.yaw, b.pitch - camera.pitch);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            position: Vec3::new(0.0, 1.0, 4.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 60.0,
            near: 0.1,
        }
    }

    #[test]
    fn a_bookmark_round_trips_through_its_file() {
        let dir = crate::util::test_files::TestDir::new("bookmarks");
        let path = bookmarks_path(Some(&dir.join("scene.toml")));
        assert!(path.ends_with("scene.toml.bookmarks.toml"));
        let mut cam = FlyCamera::new(camera());
        cam.translate(Vec3::new(1.0, 2.0, 3.0));
        cam.turn(0.5, 0.1);
        let mut marks = Bookmarks::default();
        marks.add(&cam);
        marks.save(&path).unwrap();
        let loaded = Bookmarks::load(&path).unwrap();
        let mut other = FlyCamera::new(camera());
        assert!(loaded.apply(0, &mut other));
        assert!((other.base.position - cam.base.position).length() < 1e-5);
        assert!((other.forward() - cam.forward()).length() < 1e-5);
        std::fs::write(&path, "bookmark = 3").unwrap();
        let e = Bookmarks::load(&path).unwrap_err().to_string();
        assert!(e.contains("scene.toml.bookmarks.toml"), "{e}");
    }
}
