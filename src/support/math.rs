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

    /// gymnasium-robotics' `euler2mat` for angles `[x, y, z]` (row-major).
    fn euler2mat(e: [f64; 3]) -> [f64; 9] {
        let (ai, aj, ak) = (-e[2], -e[1], -e[0]);
        let (si, ci) = ai.sin_cos();
        let (sj, cj) = aj.sin_cos();
        let (sk, ck) = ak.sin_cos();
        let (cc, cs, sc, ss) = (ci * ck, ci * sk, si * ck, si * sk);
        [cj * ci, cj * si, -sj, sj * cs - sc, sj * ss + cc, cj * sk, sj * cc + ss, sj * sc - cs, cj * ck]
    }

    #[test]
    fn yaw_about_z_reads_as_z_angle() {
        let (s, c) = 0.4f64.sin_cos();
        let e = mat2euler(&[c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0]);
        assert!(e[0].abs() < 1e-15 && e[1].abs() < 1e-15 && (e[2] - 0.4).abs() < 1e-15, "{e:?}");
    }

    #[test]
    fn identity_is_zero() {
        assert_eq!(mat2euler(&[1., 0., 0., 0., 1., 0., 0., 0., 1.]), [0.0, 0.0, 0.0]);
    }

    #[test]
    fn round_trips_rotations() {
        for &(a, b, c) in &[(0.3, -0.2, 1.1), (-1.0, 0.5, -2.5), (0.0, 0.0, 0.7)] {
            let e = mat2euler(&euler2mat([a, b, c]));
            for (got, want) in e.iter().zip([a, b, c]) {
                assert!((got - want).abs() < 1e-12, "{e:?} vs {:?}", (a, b, c));
            }
        }
    }
}
