//! The refinements' parameters, as the scene's `[refinement]` section writes them: which SPH
//! turbulence refinement runs, its parameters with the papers' defaults, and their validation.
//!
//! ```toml
//! [refinement]
//! method = "vrsph"   # none | rankine | vrsph | mcvsph | micropolar | confinement
//! alpha = 1.0
//! walls = false
//! ```
//!
//! Each method takes only its own keys (any other key is an error). `walls` (every method but
//! `none`, default false) lets the Akinci boundary samples into the shared difference operators
//! (see `crate::sph::operators`). The default is off because all three papers keep the walls
//! out of the vorticity: Wang et al. (Sec. 4.3) found the vorticity field unstable near rigid,
//! especially moving, bodies when boundary particles took part; Ye et al. set the loss of solid
//! particles to zero. Under eddy's free-slip-by-default walls (`viscosity.boundary = 0`) a
//! static wall in the curl would also read the fluid sliding along it as wall vorticity that
//! the momentum equation never produced, and the loss-based methods would feed it back every
//! step as a source. With `walls = true` the wall shear counts, which models no-slip walls;
//! pair it with `viscosity.boundary > 0`.

use serde::{Deserialize, Serialize};

use crate::Real;

/// A refinement parameter outside its allowed range: the dotted key, the value and what is
/// allowed (the scene names its file around it).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{key} = {value}: allowed is {allowed}")]
pub struct InvalidParam {
    pub key: String,
    pub value: Real,
    pub allowed: String,
}

/// The refinement of a scene and its parameters.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "snake_case", deny_unknown_fields)]
pub enum Refinement {
    /// Plain DFSPH / IISPH.
    #[default]
    None,
    /// Wang et al. 2020 (Algorithm 1): Rankine-vortex velocity refinement.
    Rankine {
        /// Core-radius factor beta in [0, 1]: r_c = beta sqrt(4 alpha_Oseen nu dt) (Eq. 11).
        #[serde(default = "one")]
        beta: Real,
        #[serde(default)]
        walls: bool,
    },
    /// Liu et al. 2021 (Algorithm 2): vorticity refinement through a local stream function.
    Vrsph {
        /// Gain alpha of the velocity refinement (Eq. 17), in [0, 2]; 1 is the ideal refinement.
        #[serde(default = "one")]
        alpha: Real,
        #[serde(default)]
        walls: bool,
    },
    /// Ye et al. (Algorithm 2): Monte Carlo vortical SPH.
    Mcvsph {
        /// Fraction N / N_f of fluid particles paired with vortex particles, in (0, 1].
        #[serde(default = "default_sample_fraction")]
        sample_fraction: Real,
        /// Volume coefficient c of the vortex particles (Eq. 24), in [0, 1).
        #[serde(default = "default_volume_coefficient")]
        volume_coefficient: Real,
        /// Opening parameter of the Biot–Savart treecode, in [0, 1): its error grows about as
        /// theta^2 and its cost falls; 0 sums every pair directly.
        #[serde(default = "default_theta")]
        theta: Real,
        #[serde(default)]
        walls: bool,
    },
    /// Micropolar SPH (Bender et al. 2019, as summarised by Wang et al. 2020 Eq. 16).
    Micropolar {
        /// Transfer coefficient nu_t, m^2/s, in [0, 1].
        #[serde(default = "default_nu_t")]
        nu_t: Real,
        /// Micro-inertia per unit mass epsilon, m^2, > 0.
        #[serde(default = "default_micro_inertia")]
        micro_inertia: Real,
        #[serde(default)]
        walls: bool,
    },
    /// Vorticity confinement in SPH form: a = epsilon (N x omega), N = grad|omega| / |grad|omega||.
    Confinement {
        /// Confinement strength epsilon, m/s, >= 0.
        #[serde(default = "default_epsilon")]
        epsilon: Real,
        #[serde(default)]
        walls: bool,
    },
}

fn one() -> Real {
    1.0
}
/// Ye et al. Sec. 5.1.1: about 1 % of the fluid particles.
fn default_sample_fraction() -> Real {
    0.01
}
/// Ye et al. Figs. 5, 8, 13.
fn default_volume_coefficient() -> Real {
    0.05
}
/// Under 1 % of the signal from the direct sum on the dam break (`crate::refine::biot_savart`).
fn default_theta() -> Real {
    super::biot_savart::DEFAULT_THETA
}
/// Wang et al. Sec. 5 and Liu et al. Sec. 5: nu_t = 0.05 matches beta = 1 and alpha = 1.
fn default_nu_t() -> Real {
    0.05
}
/// No paper gives one; 0.01 m^2 relaxes omega towards curl(v) / 2 in epsilon / (2 nu_t) = 0.1 s
/// at the default nu_t.
fn default_micro_inertia() -> Real {
    0.01
}
/// No paper gives one; 0.1 m/s gives about 0.1 g at a vorticity of 10 / s.
fn default_epsilon() -> Real {
    0.1
}

impl Refinement {
    /// The method's name as written in scene files.
    pub fn method(&self) -> &'static str {
        match self {
            Refinement::None => "none",
            Refinement::Rankine { .. } => "rankine",
            Refinement::Vrsph { .. } => "vrsph",
            Refinement::Mcvsph { .. } => "mcvsph",
            Refinement::Micropolar { .. } => "micropolar",
            Refinement::Confinement { .. } => "confinement",
        }
    }

    /// Checks every parameter against its allowed range; errors name the key.
    pub fn validate(&self) -> Result<(), InvalidParam> {
        let check = |key: &str, value: Real, lo: Real, hi: Real, lo_open: bool, hi_open: bool| {
            let inside = value.is_finite()
                && (if lo_open { value > lo } else { value >= lo })
                && (if hi_open { value < hi } else { value <= hi });
            if inside {
                return Ok(());
            }
            let allowed = if hi.is_infinite() {
                format!("a finite number {} {lo}", if lo_open { ">" } else { ">=" })
            } else {
                format!(
                    "a finite number in {}{lo}, {hi}{}",
                    if lo_open { '(' } else { '[' },
                    if hi_open { ')' } else { ']' }
                )
            };
            Err(InvalidParam {
                key: format!("refinement.{key}"),
                value,
                allowed: format!("{allowed} for method \"{}\"", self.method()),
            })
        };
        match *self {
            Refinement::None => Ok(()),
            Refinement::Rankine { beta, .. } => check("beta", beta, 0.0, 1.0, false, false),
            Refinement::Vrsph { alpha, .. } => check("alpha", alpha, 0.0, 2.0, false, false),
            Refinement::Mcvsph {
                sample_fraction,
                volume_coefficient,
                theta,
                ..
            } => {
                check("sample_fraction", sample_fraction, 0.0, 1.0, true, false)?;
                check(
                    "volume_coefficient",
                    volume_coefficient,
                    0.0,
                    1.0,
                    false,
                    true,
                )?;
                check("theta", theta, 0.0, 1.0, false, true)
            }
            Refinement::Micropolar {
                nu_t,
                micro_inertia,
                ..
            } => {
                check("nu_t", nu_t, 0.0, 1.0, false, false)?;
                check(
                    "micro_inertia",
                    micro_inertia,
                    0.0,
                    Real::INFINITY,
                    true,
                    true,
                )
            }
            Refinement::Confinement { epsilon, .. } => {
                check("epsilon", epsilon, 0.0, Real::INFINITY, false, true)
            }
        }
    }
}
