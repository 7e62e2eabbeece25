//! Procedural voxel volumes: the 3D Shepp-Logan head phantom.

use crate::error::LoadError;

/// Largest accepted side of a generated volume (`phantom:N`, N^3 voxels).
pub const MAX_PHANTOM_SIDE: u32 = 512;

/// The ellipsoids of the modified 3D Shepp-Logan phantom, as in Schabel's `phantom3d` (after
/// Toft's modified intensities and Kak and Slaney's 3D extension): value added `A`, semi-axes
/// `a, b, c`, centre `x0, y0, z0`, Euler angles `phi, theta, psi` in degrees.
#[rustfmt::skip]
const SHEPP_LOGAN: [[f32; 10]; 10] = [
    //  A      a       b      c      x0     y0      z0     phi   theta  psi
    [ 1.0,  0.6900, 0.920, 0.810,  0.00,  0.0,    0.00,   0.0,  0.0,  0.0],
    [-0.8,  0.6624, 0.874, 0.780,  0.00, -0.0184, 0.00,   0.0,  0.0,  0.0],
    [-0.2,  0.1100, 0.310, 0.220,  0.22,  0.0,    0.00, -18.0,  0.0, 10.0],
    [-0.2,  0.1600, 0.410, 0.280, -0.22,  0.0,    0.00,  18.0,  0.0, 10.0],
    [ 0.1,  0.2100, 0.250, 0.410,  0.00,  0.35,  -0.15,   0.0,  0.0,  0.0],
    [ 0.1,  0.0460, 0.046, 0.050,  0.00,  0.1,    0.25,   0.0,  0.0,  0.0],
    [ 0.1,  0.0460, 0.046, 0.050,  0.00, -0.1,    0.25,   0.0,  0.0,  0.0],
    [ 0.1,  0.0460, 0.023, 0.050, -0.08, -0.605,  0.00,   0.0,  0.0,  0.0],
    [ 0.1,  0.0230, 0.023, 0.020,  0.00, -0.606,  0.00,   0.0,  0.0,  0.0],
    [ 0.1,  0.0230, 0.046, 0.020,  0.06, -0.605,  0.00,   0.0,  0.0,  0.0],
];

/// One ellipsoid of a phantom: `value` is added inside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ellipsoid {
    /// Value added inside.
    pub value: f32,
    /// Semi-axes.
    pub axes: [f32; 3],
    /// Centre (in the rotated frame, as `phantom3d` defines it).
    pub center: [f32; 3],
    /// Euler angles phi, theta, psi in degrees (z-x-z).
    pub angles: [f32; 3],
}

impl Ellipsoid {
    /// Whether point `p` of `[-1, 1]^3` is inside (boundary included).
    #[must_use]
    pub fn contains(&self, p: [f32; 3]) -> bool {
        let [phi, theta, psi] = self.angles.map(f32::to_radians);
        let (sp, cp) = phi.sin_cos();
        let (st, ct) = theta.sin_cos();
        let (ss, cs) = psi.sin_cos();
        let m = [
            [cp * cs - ct * sp * ss, cs * sp + ct * cp * ss, ss * st],
            [-ss * cp - ct * sp * cs, -sp * ss + ct * cp * cs, cs * st],
            [st * sp, -st * cp, ct],
        ];
        let mut sum = 0.0;
        for ((row, c), axis) in m.iter().zip(self.center).zip(self.axes) {
            let q = row[0] * p[0] + row[1] * p[1] + row[2] * p[2];
            let d = (q - c) / axis;
            sum += d * d;
        }
        sum <= 1.0
    }
}

/// The ten ellipsoids of the modified 3D Shepp-Logan phantom.
#[must_use]
pub fn shepp_logan_ellipsoids() -> Vec<Ellipsoid> {
    SHEPP_LOGAN
        .iter()
        .map(|e| Ellipsoid {
            value: e[0],
            axes: [e[1], e[2], e[3]],
            center: [e[4], e[5], e[6]],
            angles: [e[7], e[8], e[9]],
        })
        .collect()
}

/// Samples the sum of `ellipsoids` at the centres of `n^3` voxels over `[-1, 1]^3` (x
/// fastest, then y, then z).
#[must_use]
pub fn rasterize(ellipsoids: &[Ellipsoid], n: u32) -> Vec<f32> {
    let c = |i: u32| -1.0 + (2 * i + 1) as f32 / n as f32;
    let mut out = Vec::with_capacity((n as usize).pow(3));
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let p = [c(i), c(j), c(k)];
                out.push(
                    ellipsoids
                        .iter()
                        .filter(|e| e.contains(p))
                        .map(|e| e.value)
                        .sum(),
                );
            }
        }
    }
    out
}

/// Parses a volume source `phantom:N` into its side `N`.
///
/// # Errors
/// [`LoadError::Generator`] for other names or sides outside `1..=`[`MAX_PHANTOM_SIDE`].
pub fn parse_volume_spec(spec: &str) -> Result<u32, LoadError> {
    let err = |message: String| LoadError::Generator {
        spec: spec.to_owned(),
        message,
    };
    let Some(("phantom", arg)) = spec.split_once(':') else {
        return Err(err("expected phantom:N (N^3 voxels)".into()));
    };
    let n: u32 = arg
        .parse()
        .map_err(|_| err(format!("'{arg}' is not a whole number")))?;
    if n == 0 || n > MAX_PHANTOM_SIDE {
        return Err(err(format!("N must be in 1..={MAX_PHANTOM_SIDE}")));
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phantom_values() {
        let v = rasterize(&shepp_logan_ellipsoids(), 32);
        assert_eq!(v.len(), 32 * 32 * 32);
        // Corner outside the head, centre in the brain (1 - 0.8).
        assert_eq!(v[0], 0.0);
        let centre = v[(16 * 32 + 16) * 32 + 16];
        assert!((centre - 0.2).abs() < 1e-6, "{centre}");
        assert!(v.iter().all(|x| (-1e-6..=1.0 + 1e-6).contains(x)));
        assert!(parse_volume_spec("phantom:0").is_err());
        assert!(parse_volume_spec("phantom:9999").is_err());
        assert!(parse_volume_spec("blob:3").is_err());
        assert_eq!(parse_volume_spec("phantom:64").unwrap(), 64);
    }
}
