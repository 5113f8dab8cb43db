//! The vortex kernel (Pfaff et al. 2009, Eqs. 11–13 as derived in `eddy::vortex::kernel`):
//! divergence-free velocity, vorticity at the centre equal to omega_p for several axes, the
//! analytic vorticity equal to the curl of the velocity, and the energy constant.

use eddy::vortex::kernel;
use eddy::{Real, Vec3};

/// Central-difference Jacobian of the kernel velocity, entry [a][b] = d u_a / d x_b.
fn jacobian(omega: &Vec3, sigma: Real, d: &Vec3, h: Real) -> nalgebra::Matrix3<Real> {
    let mut j = nalgebra::Matrix3::zeros();
    for b in 0..3 {
        let mut e = Vec3::zeros();
        e[b] = h;
        let diff = (kernel::velocity(omega, sigma, &(d + e))
            - kernel::velocity(omega, sigma, &(d - e)))
            / (2.0 * h);
        j.set_column(b, &diff);
    }
    j
}

fn curl(j: &nalgebra::Matrix3<Real>) -> Vec3 {
    Vec3::new(
        j[(2, 1)] - j[(1, 2)],
        j[(0, 2)] - j[(2, 0)],
        j[(1, 0)] - j[(0, 1)],
    )
}

fn axes() -> Vec<Vec3> {
    vec![
        Vec3::new(0.0, 0.0, 3.0),
        Vec3::new(-2.0, 0.0, 0.0),
        Vec3::new(0.3, -1.2, 0.7),
        Vec3::new(-5.0, 4.0, -0.5),
    ]
}

#[test]
fn curl_at_centre_is_omega_p_and_field_is_divergence_free() {
    let sigma = 0.37;
    let h = 1e-3 * sigma;
    for w in axes() {
        let c = curl(&jacobian(&w, sigma, &Vec3::zeros(), h));
        assert!(
            (c - w).norm() < 5e-3 * w.norm(),
            "curl {c:?} vs omega_p {w:?}"
        );
        for d in [
            Vec3::new(0.1, 0.2, -0.3),
            Vec3::new(-0.5, 0.05, 0.4),
            Vec3::new(0.0, 0.6, 0.0),
        ] {
            let j = jacobian(&w, sigma, &d, h);
            let scale = w.norm();
            assert!(
                j.trace().abs() < 1e-6 * scale,
                "divergence {} at {d:?}",
                j.trace()
            );
            // The analytic vorticity is the curl everywhere, not only at the centre.
            let diff = curl(&j) - kernel::vorticity(&w, sigma, &d);
            assert!(
                diff.norm() < 1e-5 * scale,
                "vorticity off by {diff:?} at {d:?}"
            );
        }
        assert_eq!(kernel::vorticity(&w, sigma, &Vec3::zeros()), w);
    }
}

/// The velocity turns about omega_p in the right-hand sense: at +x of a +z vortex it points +y.
#[test]
fn velocity_turns_right_handed_about_the_axis() {
    let u = kernel::velocity(&Vec3::new(0.0, 0.0, 2.0), 1.0, &Vec3::new(0.5, 0.0, 0.0));
    assert!(u.y > 0.0 && u.x.abs() < 1e-15 && u.z.abs() < 1e-15);
}

/// 1/2 int |u|^2 dV by the midpoint rule over the kernel's velocity support (3 sigma) matches
/// (pi^(3/2) / 8) |omega_p|^2 sigma^5 within 1 %; the full-space integral, taken to 6 sigma,
/// within 1e-4.
#[test]
fn energy_matches_numerical_integration() {
    let (sigma, w) = (0.2, Vec3::new(0.4, -1.0, 2.0));
    let integrate = |reach: Real, n: usize| {
        let h = 2.0 * reach * sigma / n as Real;
        let mut e = 0.0;
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    let d = Vec3::new(i as Real + 0.5, j as Real + 0.5, k as Real + 0.5) * h
                        - Vec3::repeat(reach * sigma);
                    if d.norm() < reach * sigma {
                        e += 0.5 * kernel::velocity(&w, sigma, &d).norm_squared();
                    }
                }
            }
        }
        e * h * h * h
    };
    let formula = kernel::energy(w.norm(), sigma);
    let truncated = integrate(kernel::VELOCITY_REACH, 120);
    assert!(
        (truncated - formula).abs() < 0.01 * formula,
        "{truncated} vs {formula}"
    );
    let full = integrate(6.0, 160);
    assert!(
        (full - formula).abs() < 1e-4 * formula,
        "{full} vs {formula}"
    );
}
