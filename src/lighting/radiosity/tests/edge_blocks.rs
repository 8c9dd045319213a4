//! A shooting block at the edge of its polygon: its patches' cells overhang the surface, here
//! past a wall the panel almost touches.

use glam::DVec3;

use crate::lighting::lightmap::form_factor::point_to_polygon;
use crate::lighting::lightmap::patches::{Patches, Triangle};
use crate::lighting::lightmap::solve::{emitters_first_shot, Occluders, Settings};

/// Two triangles of the quad `c` (wound so that its normal is (c1 − c0) × (c2 − c0)).
fn quad(c: [DVec3; 4], object: usize, albedo: f64, radiance: f64) -> [Triangle; 2] {
    [[c[0], c[1], c[2]], [c[0], c[2], c[3]]].map(|p| Triangle {
        p,
        object,
        albedo: DVec3::splat(albedo),
        emission: DVec3::splat(radiance),
        sky: false,
        part: 0,
    })
}

/// Σ over a `step` grid of the rectangle `origin` + [0, a]·u + [0, b]·v of the exact irradiance
/// a unit-radiosity polygon `light` facing `light_normal` gives: the power it lands there.
fn exact_power(origin: DVec3, u: DVec3, v: DVec3, (a, b): (f64, f64), n: DVec3, light: &[DVec3; 4]) -> f64 {
    let step = 0.01;
    let light_normal = (light[1] - light[0]).cross(light[2] - light[0]).normalize();
    let mut sum = 0.0;
    for j in 0..(b / step).round() as usize {
        for i in 0..(a / step).round() as usize {
            let x = origin + u * ((i as f64 + 0.5) * step) + v * ((j as f64 + 0.5) * step);
            if light_normal.dot(x - light[0]) > 0.0 {
                sum += point_to_polygon(x, n, light) * step * step;
            }
        }
    }
    sum
}

/// A ceiling panel 3 cm from a wall, off the 0.32 m patch grid: its block's cells reach 10 cm
/// behind the wall. Shot from the whole cells, part of its light left from behind the wall,
/// which the wall's receivers cannot see, and the floor took 0.96 of its exact share; with the
/// wall's patches judged at their centres only, the row that straddles the panel's plane got
/// nothing, and the wall took 0.86 of its share.
#[test]
fn a_panel_whose_cells_overhang_a_wall_lights_it_by_its_own_extent() {
    let y = 2.0;
    let panel = [
        DVec3::new(-1.47, y, 0.05),
        DVec3::new(-0.99, y, 0.05),
        DVec3::new(-0.99, y, 0.45),
        DVec3::new(-1.47, y, 0.45),
    ];
    let (x0, x1, z0, z1, h) = (-1.5, 1.5, -1.5, 1.5, 2.5);
    let floor = [
        DVec3::new(x0, 0.0, z0),
        DVec3::new(x0, 0.0, z1),
        DVec3::new(x1, 0.0, z1),
        DVec3::new(x1, 0.0, z0),
    ];
    let wall = [
        DVec3::new(x0, 0.0, z0),
        DVec3::new(x0, h, z0),
        DVec3::new(x0, h, z1),
        DVec3::new(x0, 0.0, z1),
    ];
    let mut tris = Vec::new();
    tris.extend(quad(floor, 0, 0.5, 0.0));
    tris.extend(quad(wall, 1, 0.5, 0.0));
    tris.extend(quad(panel, 2, 0.0, 1.0 / std::f64::consts::PI));
    let p = Patches::build(&tris, 0.32);
    let received = emitters_first_shot(&p, &Occluders::new(&tris), &Settings::default());
    let power = |normal: DVec3| -> f64 {
        p.patches
            .iter()
            .zip(&received)
            .filter(|(q, _)| p.charts[q.chart].normal.dot(normal) > 0.99)
            .map(|(q, r)| q.area * r.x / 0.5)
            .sum()
    };
    let (floor_power, wall_power) = (power(DVec3::Y), power(DVec3::X));
    let floor_exact = exact_power(floor[0], DVec3::X, DVec3::Z, (x1 - x0, z1 - z0), DVec3::Y, &panel);
    let wall_exact = exact_power(wall[0], DVec3::Y, DVec3::Z, (h, z1 - z0), DVec3::X, &panel);
    eprintln!(
        "power landed: floor {floor_power:.4} (exact {floor_exact:.4}), wall {wall_power:.4} (exact {wall_exact:.4})"
    );
    for (name, got, want) in [("floor", floor_power, floor_exact), ("wall", wall_power, wall_exact)] {
        assert!(
            (got / want - 1.0).abs() < 0.05,
            "{name}: the panel's first shot landed {got:.4} W against the exact {want:.4} W"
        );
    }
}
