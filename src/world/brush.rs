//! Brushes (convex solids given as planes) and the first compiler step: turning them into the
//! polygons of the solid's visible boundary (the seed's CaBSP step 1, plus the CSG clip that
//! removes faces buried in, or pressed against, other brushes).

use glam::DVec3;

use super::polygon::{Aabb, Plane, Polygon, Side, Split};
use super::MaterialId;

/// One bounding plane of a brush, normal pointing out of the solid, with the material of the
/// face that lies in it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BrushSide {
    pub plane: Plane,
    pub material: MaterialId,
}

/// A convex solid: the intersection of the back half-spaces of its sides.
#[derive(Clone, Debug, PartialEq)]
pub struct Brush {
    pub sides: Vec<BrushSide>,
}

/// Half-size of the starting square for a brush side or a node's portal winding. Levels are tens of metres; this is far
/// larger, and f64 keeps the clipped corners exact to well below the plane epsilon.
pub(super) const BASE_WINDING_SIZE: f64 = 1.0e5;

impl Brush {
    /// An axis-aligned box, every face with the same material.
    pub fn cuboid(min: DVec3, max: DVec3, material: MaterialId) -> Brush {
        Brush::cuboid_materials(min, max, [material; 6])
    }

    /// An axis-aligned box with one material per face, ordered +x, −x, +y, −y, +z, −z.
    pub fn cuboid_materials(min: DVec3, max: DVec3, materials: [MaterialId; 6]) -> Brush {
        let planes = Aabb { min, max }.planes();
        Brush {
            sides: planes
                .iter()
                .zip(materials)
                .map(|(&plane, material)| BrushSide { plane, material })
                .collect(),
        }
    }

    /// The boundary polygon of every side (normals outward), `None` for sides that are
    /// redundant or degenerate. A brush with fewer than four faces has no volume.
    pub fn side_polygons(&self) -> Vec<Option<Polygon>> {
        convex_faces(self.sides.iter().map(|s| s.plane))
    }

    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for p in self.side_polygons().iter().flatten() {
            b = b.union(&p.bounds());
        }
        b
    }

    /// Strictly inside, by more than the plane epsilon.
    pub fn contains_point(&self, p: DVec3) -> bool {
        self.sides.iter().all(|s| s.plane.side_of_point(p) == Side::Back)
    }
}

/// The faces of the convex polyhedron `∩ back(planes)`: for each plane, its base winding clipped
/// behind every other plane. Outward normals. Used for brushes and for BSP cells alike.
pub fn convex_faces(planes: impl IntoIterator<Item = Plane>) -> Vec<Option<Polygon>> {
    let planes: Vec<Plane> = planes.into_iter().collect();
    planes
        .iter()
        .enumerate()
        .map(|(i, plane)| {
            let mut poly = Some(Polygon::base_winding(plane, BASE_WINDING_SIZE));
            for (j, other) in planes.iter().enumerate() {
                if i == j {
                    continue;
                }
                // A duplicate plane would clip this face to nothing and the other to nothing
                // too; keep the face of the first copy only.
                if plane.coplanar_facing(other) == Some(true) {
                    if j < i {
                        return None;
                    }
                    continue;
                }
                poly = poly?.clip_back(other);
            }
            poly
        })
        .collect()
}

/// A face of the solid boundary after CSG, remembering where it came from.
#[derive(Clone, Debug)]
pub struct BrushFace {
    pub polygon: Polygon,
    pub material: MaterialId,
    pub brush: u32,
}

/// What the CSG step did, for the compile report.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CsgStats {
    /// Brushes with fewer than four non-degenerate faces (no volume); ignored.
    pub degenerate_brushes: usize,
    /// Brush sides whose polygon came out degenerate (redundant planes, slivers).
    pub degenerate_sides: usize,
    pub brush_faces: usize,
    /// Faces after clipping away the parts inside or against other brushes.
    pub faces_out: usize,
}

/// Every brush's faces minus the parts inside other brushes, so that what remains is exactly
/// the boundary of the union of the solids.
///
/// Coplanar contact is settled so that no surface is doubled: a face pressed against an
/// opposite-facing side of another brush is inside it (two solids touching), and where two
/// brushes have same-facing coplanar faces that overlap, the earlier brush keeps the face.
pub fn csg_faces(brushes: &[Brush]) -> (Vec<BrushFace>, CsgStats) {
    let mut stats = CsgStats::default();
    let mut solids: Vec<(usize, Aabb)> = Vec::new();
    let mut faces_of: Vec<Vec<Option<Polygon>>> = Vec::new();
    for (i, brush) in brushes.iter().enumerate() {
        let polys = brush.side_polygons();
        let count = polys.iter().flatten().count();
        if count < 4 {
            stats.degenerate_brushes += 1;
            faces_of.push(Vec::new());
            continue;
        }
        stats.degenerate_sides += polys.len() - count;
        let mut bounds = Aabb::EMPTY;
        for p in polys.iter().flatten() {
            bounds = bounds.union(&p.bounds());
        }
        solids.push((i, bounds));
        faces_of.push(polys);
    }
    let mut out = Vec::new();
    for &(i, _) in &solids {
        for (side, poly) in faces_of[i].iter().enumerate() {
            let Some(poly) = poly else { continue };
            stats.brush_faces += 1;
            let face_bounds = poly.bounds().expanded(super::PLANE_EPSILON * 2.0);
            let mut pieces = vec![poly.clone()];
            for &(j, ref bounds) in &solids {
                if j == i || !bounds.overlaps(&face_bounds) {
                    continue;
                }
                pieces = pieces
                    .into_iter()
                    .flat_map(|p| outside_of(p, &brushes[j], i < j))
                    .collect();
                if pieces.is_empty() {
                    break;
                }
            }
            let material = brushes[i].sides[side].material;
            out.extend(pieces.into_iter().map(|polygon| BrushFace {
                polygon,
                material,
                brush: i as u32,
            }));
        }
    }
    stats.faces_out = out.len();
    (out, stats)
}

/// The pieces of `poly` outside `brush`; the piece inside is discarded. `keep_shared` says
/// whether a same-facing coplanar overlap counts as outside (this face wins) or inside.
fn outside_of(poly: Polygon, brush: &Brush, keep_shared: bool) -> Vec<Polygon> {
    let mut outside = Vec::new();
    let mut inside = poly;
    for side in &brush.sides {
        match inside.split(&side.plane) {
            Split::Front(p) => {
                outside.push(p);
                return outside;
            }
            Split::Back(p) => inside = p,
            Split::On(p, same) => {
                if same && keep_shared {
                    outside.push(p);
                    return outside;
                }
                inside = p;
            }
            Split::Spanning { front, back } => {
                outside.extend(front);
                match back {
                    Some(b) => inside = b,
                    None => return outside,
                }
            }
        }
    }
    outside
}
