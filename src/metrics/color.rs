//! Colour spaces used by FLIP: linear sRGB (Rec. 709 primaries, D65), CIE XYZ, the opponent
//! space YCxCz (a linearised L*a*b*: the same axes without the cube root, so that spatial
//! filtering in it is filtering of light), CIE L*a*b*, and the Hunt-adjusted L*a*b* in which
//! FLIP measures colour distance with HyAB.
//!
//! All white points are D65 as the XYZ of linear RGB (1, 1, 1), which makes RGB white map to
//! L* = 100, a* = b* = 0 exactly up to rounding.

/// Linear sRGB → XYZ. The exact rational form of the sRGB matrix (each row scaled so that the
/// reference white has Y = 1), as used by FLIP.
pub const RGB_TO_XYZ: [[f32; 3]; 3] = [
    [
        (10135552.0 / 24577794.0) as f32,
        (8788810.0 / 24577794.0) as f32,
        (4435075.0 / 24577794.0) as f32,
    ],
    [
        (2613072.0 / 12288897.0) as f32,
        (8788810.0 / 12288897.0) as f32,
        (887015.0 / 12288897.0) as f32,
    ],
    [
        (1425312.0 / 73733382.0) as f32,
        (8788810.0 / 73733382.0) as f32,
        (70074185.0 / 73733382.0) as f32,
    ],
];

/// The inverse of [`RGB_TO_XYZ`], computed in exact rational arithmetic and rounded.
pub const XYZ_TO_RGB: [[f32; 3]; 3] = [
    [
        3.241_003_232_976_359_f64 as f32,
        -1.537_398_969_488_786_f64 as f32,
        -0.498_615_881_996_363_f64 as f32,
    ],
    [
        -0.969_224_252_202_517_f64 as f32,
        1.875_929_983_695_176_f64 as f32,
        0.041_554_226_340_085_f64 as f32,
    ],
    [
        0.055_639_419_851_975_f64 as f32,
        -0.204_011_206_123_910_f64 as f32,
        1.057_148_977_187_534_f64 as f32,
    ],
];

/// XYZ of linear RGB white (1, 1, 1): the row sums of [`RGB_TO_XYZ`].
pub const WHITE_XYZ: [f32; 3] = [
    0.950_428_545_377_180_7_f64 as f32,
    1.0,
    1.088_900_370_798_127_7_f64 as f32,
];

fn mul(m: &[[f32; 3]; 3], v: [f32; 3]) -> [f32; 3] {
    [0, 1, 2].map(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
}

pub fn linear_rgb_to_xyz(rgb: [f32; 3]) -> [f32; 3] {
    mul(&RGB_TO_XYZ, rgb)
}

pub fn xyz_to_linear_rgb(xyz: [f32; 3]) -> [f32; 3] {
    mul(&XYZ_TO_RGB, xyz)
}

/// XYZ → YCxCz: Y = 116·y − 16, Cx = 500·(x − y), Cz = 200·(y − z) on white-normalised x, y, z.
pub fn xyz_to_ycxcz(xyz: [f32; 3]) -> [f32; 3] {
    let [x, y, z] = [0, 1, 2].map(|i| xyz[i] / WHITE_XYZ[i]);
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

pub fn ycxcz_to_xyz(ycxcz: [f32; 3]) -> [f32; 3] {
    let y = (ycxcz[0] + 16.0) / 116.0;
    let x = y + ycxcz[1] / 500.0;
    let z = y - ycxcz[2] / 200.0;
    [x * WHITE_XYZ[0], y * WHITE_XYZ[1], z * WHITE_XYZ[2]]
}

/// XYZ → CIE L*a*b* with the standard piecewise cube root (linear below (6/29)³).
pub fn xyz_to_lab(xyz: [f32; 3]) -> [f32; 3] {
    const DELTA: f32 = 6.0 / 29.0;
    let f = |t: f32| {
        if t > DELTA * DELTA * DELTA {
            t.cbrt()
        } else {
            t / (3.0 * DELTA * DELTA) + 4.0 / 29.0
        }
    };
    let [fx, fy, fz] = [0, 1, 2].map(|i| f(xyz[i] / WHITE_XYZ[i]));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

pub fn linear_rgb_to_lab(rgb: [f32; 3]) -> [f32; 3] {
    xyz_to_lab(linear_rgb_to_xyz(rgb))
}

/// Hunt adjustment: chroma shrinks with lightness (a, b scaled by 0.01·L*), because colour
/// differences are harder to see in dark regions.
pub fn hunt(lab: [f32; 3]) -> [f32; 3] {
    let s = 0.01 * lab[0];
    [lab[0], s * lab[1], s * lab[2]]
}

/// HyAB distance: city-block in lightness plus Euclidean in chroma, which tracks large colour
/// differences better than ΔE*ab.
pub fn hyab(p: [f32; 3], q: [f32; 3]) -> f32 {
    let (dl, da, db) = (p[0] - q[0], p[1] - q[1], p[2] - q[2]);
    dl.abs() + (da * da + db * db).sqrt()
}
