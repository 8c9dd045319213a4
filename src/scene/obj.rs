//! Wavefront OBJ loading through `tobj`, with a line-aware pre-check so that a bad vertex or face
//! index is reported with its OBJ line (tobj's own errors carry no position).

use std::path::Path;

use glam::{Vec2, Vec3};

use super::error::SceneError;
use super::mesh::Mesh;

/// Loads every object/group of an OBJ file into one mesh: triangulated (fans), one index per
/// vertex, uv v flipped to the top-left convention, smooth normals where the file has none,
/// tangents generated. Materials (`mtllib`) are ignored; the scene assigns one material.
pub fn load_obj(path: &Path) -> Result<Mesh, SceneError> {
    let file = path.display().to_string();
    let (models, _materials) = read_obj(path, |_| Err(tobj::LoadError::OpenFileFailed))?
        .map_err(|e| SceneError::new(&file, None, "obj", format!("tobj: {e}")))?;
    models_mesh(models.iter(), &file)
}

/// Reads and pre-checks an OBJ file and hands it to tobj (triangulated, one index per vertex);
/// `load_mtl` is tobj's material loader, given the `mtllib` name.
pub(crate) fn read_obj(
    path: &Path,
    load_mtl: impl Fn(&Path) -> tobj::MTLLoadResult,
) -> Result<tobj::LoadResult, SceneError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| SceneError::new(&file, None, "file", format!("cannot read: {e}")))?;
    let text = String::from_utf8_lossy(&bytes);
    precheck(&text, &file)?;

    // `..Default::default()` covers fields that exist only with tobj features penumbra disables.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    Ok(tobj::load_obj_buf(&mut text.as_bytes(), &options, load_mtl))
}

/// Merges tobj models into one mesh: uv v flipped to the top-left convention, smooth normals
/// where the models have none, tangents generated. `file` names the mesh in errors.
pub(crate) fn models_mesh<'a>(models: impl Iterator<Item = &'a tobj::Model>, file: &str) -> Result<Mesh, SceneError> {
    let mut mesh = Mesh::default();
    let mut all_normals = true;
    for model in models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        let count = m.positions.len() / 3;
        mesh.positions
            .extend(m.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
        if m.normals.len() == m.positions.len() {
            mesh.normals
                .extend(m.normals.chunks_exact(3).map(|n| Vec3::new(n[0], n[1], n[2])));
        } else {
            all_normals = false;
            mesh.normals.extend(std::iter::repeat_n(Vec3::ZERO, count));
        }
        if m.texcoords.len() == 2 * count {
            mesh.uvs
                .extend(m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], 1.0 - t[1])));
        } else {
            // Zero uvs are degenerate for tangent generation, which then falls back.
            mesh.uvs.extend(std::iter::repeat_n(Vec2::ZERO, count));
        }
        mesh.indices.extend(m.indices.iter().map(|&i| base.saturating_add(i)));
    }
    if mesh.indices.is_empty() {
        return Err(SceneError::new(file, None, "f", "the file has no faces"));
    }
    mesh.tangents = vec![glam::Vec4::ZERO; mesh.positions.len()];
    // Validate before deriving attributes, so bad input is reported rather than smeared.
    mesh.validate(file)?;
    if all_normals {
        mesh.normalize_normals();
    } else {
        mesh.compute_smooth_normals(); // a partial set would leave seams; recompute them all
    }
    mesh.compute_tangents();
    mesh.validate(file)?;
    Ok(mesh)
}

/// Checks `v`/`vn`/`vt` numbers are finite and `f` indices refer to elements defined before
/// them. Errors name the OBJ line, and the 1-based vertex or face number (as OBJ counts them).
fn precheck(text: &str, file: &str) -> Result<(), SceneError> {
    let (mut nv, mut nvt, mut nvn, mut nf) = (0usize, 0usize, 0usize, 0usize);
    for (lineno, raw) in text.lines().enumerate() {
        let line_no = Some(lineno + 1);
        let line = raw.split('#').next().unwrap_or("");
        let mut words = line.split_whitespace();
        let Some(tag) = words.next() else { continue };
        let err = |field: String, msg: String| SceneError::new(file, line_no, field, msg);
        let (count, what, min) = match tag {
            "v" => (&mut nv, "vertex", 3),
            "vt" => (&mut nvt, "texture coordinate", 1),
            "vn" => (&mut nvn, "normal", 3),
            "f" => {
                nf += 1;
                let corners: Vec<&str> = words.collect();
                if corners.len() < 3 {
                    return Err(err(
                        format!("face {nf}"),
                        format!("has {} vertices, need at least 3", corners.len()),
                    ));
                }
                for corner in corners {
                    for (slot, part) in corner.split('/').enumerate() {
                        if part.is_empty() && slot > 0 {
                            continue; // `a//c` or `a/b/` forms
                        }
                        let (defined, kind) = match slot {
                            0 => (nv, "vertex"),
                            1 => (nvt, "texture coordinate"),
                            2 => (nvn, "normal"),
                            _ => return Err(err(format!("face {nf}"), format!("malformed corner `{corner}`"))),
                        };
                        let idx: i64 = part
                            .parse()
                            .map_err(|_| err(format!("face {nf}"), format!("malformed corner `{corner}`")))?;
                        let ok =
                            (idx > 0 && idx as usize <= defined) || (idx < 0 && idx.unsigned_abs() as usize <= defined);
                        if !ok {
                            let msg = format!("refers to {kind} {idx}, but {defined} are defined before this line");
                            return Err(err(format!("face {nf}"), msg));
                        }
                    }
                }
                continue;
            }
            _ => continue,
        };
        *count += 1;
        let n = *count;
        let mut values = Vec::new();
        for w in words {
            let x: f32 = w
                .parse()
                .map_err(|_| err(format!("{what} {n}"), format!("`{w}` is not a number")))?;
            values.push(x);
        }
        if values.len() < min {
            return Err(err(
                format!("{what} {n}"),
                format!("has {} numbers, need at least {min}", values.len()),
            ));
        }
        if values.iter().any(|x| !x.is_finite()) {
            let shown: Vec<String> = values.iter().map(|x| x.to_string()).collect();
            return Err(err(
                format!("{what} {n}"),
                format!("has a non-finite coordinate: {}", shown.join(" ")),
            ));
        }
        if tag == "v" && values.len() == 4 && values.get(3) == Some(&0.0) {
            return Err(err(format!("{what} {n}"), "has weight w = 0".into()));
        }
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::scene::mesh::tests::assert_well_formed;

    /// A fresh directory under the system temp dir, unique per test, removed after it.
    pub(crate) fn temp_dir(name: &str) -> crate::util::test_files::TestDir {
        crate::util::test_files::TestDir::new(&format!("scene-{name}"))
    }

    const CUBE: &str = "# unit cube, quads, no normals
v -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\nv -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1
f 1 2 3 4\nf 6 5 8 7\nf 5 1 4 8\nf 2 6 7 3\nf 4 3 7 8\nf 5 6 2 1\n";

    #[test]
    fn loads_quads_computes_normals_and_is_closed() {
        let dir = temp_dir("cube");
        let path = dir.join("cube.obj");
        std::fs::write(&path, CUBE).unwrap();
        let m = load_obj(&path).unwrap();
        assert_eq!((m.vertex_count(), m.triangle_count()), (8, 12));
        assert_well_formed(&m);
        assert!(m.is_closed_manifold());
        assert!((m.area() - 24.0).abs() < 1e-4);
        for (p, n) in m.positions.iter().zip(&m.normals) {
            assert!(
                (*n - p.normalize()).length() < 1e-5,
                "smooth normal of corner {p} is {n}"
            );
        }
    }

    #[test]
    fn keeps_given_normals_and_flips_v() {
        let dir = temp_dir("tri");
        let path = dir.join("tri.obj");
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 0.25\nvn 0 0 2\nf 1/1/1 2/2/1 3/3/1\n";
        std::fs::write(&path, text).unwrap();
        let m = load_obj(&path).unwrap();
        assert_well_formed(&m);
        assert!(m.normals.iter().all(|&n| n == Vec3::Z));
        assert!(m.uvs.contains(&Vec2::new(0.0, 0.75)));
        // u along +x, OBJ v (image up) along +y: tangent +x, bitangent +y = cross(z, x): w = +1.
        assert!(m
            .tangents
            .iter()
            .all(|t| (t.truncate() - Vec3::X).length() < 1e-5 && t.w == 1.0));
    }

    #[test]
    fn nan_vertex_is_reported_with_file_line_and_vertex() {
        let dir = temp_dir("nan");
        let path = dir.join("bad.obj");
        std::fs::write(&path, "v 0 0 0\n# comment\nv 1 NaN 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        let e = load_obj(&path).unwrap_err();
        assert_eq!(e.file, path.display().to_string());
        assert_eq!((e.line, e.field.as_str()), (Some(3), "vertex 2"));
        assert!(
            e.to_string()
                .contains("bad.obj:3: vertex 2: has a non-finite coordinate"),
            "{e}"
        );
    }

    #[test]
    fn bad_faces_are_reported() {
        let dir = temp_dir("faces");
        let cases = [
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", 4, "face 1", "vertex 4"),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 -4 3\n",
                5,
                "face 2",
                "vertex -4",
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\n",
                4,
                "face 1",
                "texture coordinate 1",
            ),
            ("v 0 0 0\nv 1 0 0\nf 1 2\n", 3, "face 1", "need at least 3"),
            ("v 0 0 zero\n", 1, "vertex 1", "not a number"),
        ];
        for (i, (text, line, field, needle)) in cases.iter().enumerate() {
            let path = dir.join(format!("f{i}.obj"));
            std::fs::write(&path, text).unwrap();
            let e = load_obj(&path).unwrap_err();
            assert_eq!((e.line, e.field.as_str()), (Some(*line), *field), "{e}");
            assert!(e.message.contains(needle), "{e}");
        }
        let path = dir.join("empty.obj");
        std::fs::write(&path, "v 0 0 0\n").unwrap();
        assert_eq!(load_obj(&path).unwrap_err().field, "f");
        let e = load_obj(&dir.join("missing.obj")).unwrap_err();
        assert_eq!(e.field, "file");
    }

    #[test]
    fn real_meshes_load_with_expected_topology() {
        // The scanned and modelled meshes the repository carries (scenes/meshes/CREDITS.md).
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes");
        for (name, closed, boundary) in [
            ("spot.obj", true, 0usize),
            // Its source counts 1,036 boundary edges by OBJ index; many teapot vertices are
            // duplicated along patch seams, and welded by position only 160 boundary edges remain.
            ("teapot.obj", false, 160),
        ] {
            let m = load_obj(&dir.join(name)).unwrap();
            assert_well_formed(&m);
            assert_eq!(m.is_closed_manifold(), closed, "{name}");
            assert_eq!(m.boundary_edge_count(), boundary, "{name}");
        }
    }
}
