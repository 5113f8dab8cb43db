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

/// The cubic spline's constants: support h, 1 / h, k = 8 / (pi h^3) (W's) and l = 6 k
/// (dW/dq's).
#[derive(Debug, Clone, Copy)]
pub struct KernelConstants {
    pub h: Real,
    pub inv_h: Real,
    pub k: Real,
    pub l: Real,
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

    /// The kernel's constants, for evaluations written lane by lane.
    pub fn constants(&self) -> KernelConstants {
        KernelConstants {
            h: self.h,
            inv_h: self.inv_h,
            k: self.k,
            l: self.l,
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

    /// The quadratic form u^T H u of the Hessian H of W at x = x_i - x_j: the second
    /// derivative of W(|x + s u|) in s at s = 0. With W' and W'' the radial derivatives,
    /// H = (W' / r) (I - x^ x^T) + W'' x^ x^T (zero at and beyond the support, where the cubic
    /// spline is twice continuously differentiable).
    #[inline]
    pub fn hessian_form(&self, x: &Vec3, u: &Vec3) -> Real {
        let r2 = x.norm_squared();
        if r2 >= self.h * self.h {
            return 0.0;
        }
        let r = r2.sqrt();
        let q = r * self.inv_h;
        let h2 = self.h * self.h;
        // W'(r) / r and W''(r), from dW/dq = l q (3q - 2) or -l (1 - q)^2.
        let (w1_over_r, w2) = if q <= 0.5 {
            (self.l * (3.0 * q - 2.0) / h2, self.l * (6.0 * q - 2.0) / h2)
        } else {
            let t = 1.0 - q;
            (-self.l * t * t / (q * h2), 2.0 * self.l * t / h2)
        };
        let uu = u.norm_squared();
        let ux2 = if r > 0.0 { x.dot(u).powi(2) / r2 } else { 0.0 };
        w1_over_r * (uu - ux2) + w2 * ux2
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
