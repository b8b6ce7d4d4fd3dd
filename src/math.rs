//! Small rotation helpers (the conventions of gymnasium-robotics' observations).

/// Euler angles of a row-major rotation matrix, in the convention used by
/// gymnasium-robotics' Fetch observations (static x-y-z axes, returned as
/// `[x, y, z]`), with the same handling of the gimbal-lock case.
pub fn mat2euler(m: &[f64; 9]) -> [f64; 3] {
    let at = |i: usize, j: usize| m[3 * i + j];
    let cy = (at(2, 2) * at(2, 2) + at(1, 2) * at(1, 2)).sqrt();
    let regular = cy > 4.0 * f64::EPSILON;
    let z = if regular { -at(0, 1).atan2(at(0, 0)) } else { -(-at(1, 0)).atan2(at(1, 1)) };
    let y = -(-at(0, 2)).atan2(cy);
    let x = if regular { -at(1, 2).atan2(at(2, 2)) } else { 0.0 };
    [x, y, z]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Row-major matrix of R = Rz(c)·Ry(b)·Rx(a).
    fn rot(a: f64, b: f64, c: f64) -> [f64; 9] {
        let (sa, ca) = a.sin_cos();
        let (sb, cb) = b.sin_cos();
        let (sc, cc) = c.sin_cos();
        [
            cb * cc, sa * sb * cc - ca * sc, ca * sb * cc + sa * sc,
            cb * sc, sa * sb * sc + ca * cc, ca * sb * sc - sa * cc,
            -sb, sa * cb, ca * cb,
        ]
    }

    #[test]
    fn identity_is_zero() {
        assert_eq!(mat2euler(&[1., 0., 0., 0., 1., 0., 0., 0., 1.]), [0.0, 0.0, 0.0]);
    }

    #[test]
    fn round_trips_rotations() {
        // gymnasium-robotics' mat2euler inverts euler2mat, i.e. R = Rz·Ry·Rx for
        // angles (x, y, z) with its sign conventions.
        for &(a, b, c) in &[(0.3, -0.2, 1.1), (-1.0, 0.5, -2.5), (0.0, 0.0, 0.7)] {
            let e = mat2euler(&rot(a, b, c));
            for (got, want) in e.iter().zip([a, b, c]) {
                assert!((got - want).abs() < 1e-12, "{e:?} vs {:?}", (a, b, c));
            }
        }
    }
}
