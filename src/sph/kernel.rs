//! The cubic-spline kernel in 3D (Monaghan 1992), written with the support radius `h`
//! (twice the particle spacing in eddy), the form SPlisHSPlasH and Liu et al. 2021 use:
//! q = r / h, W = k (6q^3 - 6q^2 + 1) for q <= 1/2, W = 2k (1 - q)^3 for 1/2 < q <= 1, 0 beyond,
//! with k = 8 / (pi h^3), which makes W integrate to one over its support.

use crate::{Real, Vec3};
use std::f64::consts::PI;

/// Cubic-spline kernel with support radius `h`.
#[derive(Debug, Clone, Copy)]
pub struct CubicSpline {
    h: Real,
    inv_h: Real,
    k: Real,
    l: Real,
}

impl CubicSpline {
    /// The kernel with support radius `h` (> 0).
    pub fn new(h: Real) -> Self {
        let h3 = h * h * h;
        Self {
            h,
            inv_h: 1.0 / h,
            k: 8.0 / (PI * h3),
            l: 48.0 / (PI * h3),
        }
    }

    /// Support radius.
    #[inline]
    pub fn support(&self) -> Real {
        self.h
    }

    /// W(r) for a distance r >= 0.
    #[inline]
    pub fn w(&self, r: Real) -> Real {
        if r >= self.h {
            return 0.0;
        }
        let q = r * self.inv_h;
        if q <= 0.5 {
            self.k * (6.0 * q * q * (q - 1.0) + 1.0)
        } else {
            let t = (1.0 - q).max(0.0);
            self.k * 2.0 * t * t * t
        }
    }

    /// W at the origin (the self contribution to sums).
    #[inline]
    pub fn w_zero(&self) -> Real {
        self.k
    }

    /// W and its gradient at x = x_i - x_j together (one square root): the same values as
    /// [`Self::w`] at |x| and [`Self::grad`] at x.
    #[inline]
    pub fn w_grad(&self, x: &Vec3) -> (Real, Vec3) {
        let r2 = x.norm_squared();
        if r2 >= self.h * self.h {
            return (0.0, Vec3::zeros());
        }
        let r = r2.sqrt();
        if r2 < 1e-24 * self.h * self.h {
            return (self.w(r), Vec3::zeros());
        }
        let q = r * self.inv_h;
        let (w, dwdq) = if q <= 0.5 {
            (
                self.k * (6.0 * q * q * (q - 1.0) + 1.0),
                self.l * q * (3.0 * q - 2.0),
            )
        } else {
            let t = 1.0 - q;
            let tw = t.max(0.0);
            (self.k * 2.0 * tw * tw * tw, -self.l * t * t)
        };
        (w, x * (dwdq / (r * self.h)))
    }

    /// Gradient of W with respect to x_i, evaluated at x = x_i - x_j.
    /// It is antisymmetric: grad W(-x) = -grad W(x).
    #[inline]
    pub fn grad(&self, x: &Vec3) -> Vec3 {
        let r2 = x.norm_squared();
        if r2 >= self.h * self.h || r2 < 1e-24 * self.h * self.h {
            return Vec3::zeros();
        }
        let r = r2.sqrt();
        let q = r * self.inv_h;
        // dW/dq / (r h) times x gives the gradient.
        let dwdq = if q <= 0.5 {
            self.l * q * (3.0 * q - 2.0)
        } else {
            let t = 1.0 - q;
            -self.l * t * t
        };
        x * (dwdq / (r * self.h))
    }
}
