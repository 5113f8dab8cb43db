//! The serde types of bodies: shape, placement and kinematic motion, as scene files write them
//! (`[container]`, `[[obstacles]]`, smoke sources, the precomputation's obstacle). The scene
//! re-exports them; [`super::RigidBody`] is built from a [`Body`].

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

use crate::Real;

/// A rigid body: the container or an obstacle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Body {
    /// Name used in messages and outputs; defaults to the shape and index.
    #[serde(default)]
    pub name: Option<String>,
    /// The shape, in the body's own frame.
    pub shape: Shape,
    /// Position of the body's origin at t = 0, m.
    #[serde(default)]
    pub position: [Real; 3],
    /// Orientation at t = 0 as a rotation vector (axis times angle, radians).
    #[serde(default)]
    pub rotation: [Real; 3],
    /// Kinematic motion; static when left out.
    #[serde(default)]
    pub motion: Motion,
    /// The artificial-boundary-layer database this obstacle sheds turbulence from, in grid and
    /// SPH scenes (obstacles only; the scene refuses it on the container).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub abl: Option<AblLink>,
    /// Kinematic viscosity of this body's wall against the SPH fluid (Liu et al. 2021 Eq. 4
    /// over the body's samples), m^2/s: equal to `viscosity.kinematic` for a no-slip wall
    /// (scaled so a steady shear flow feels no net force at the wall), 0 for free slip; `viscosity.boundary` when left out.
    /// Lets one scene hold a no-slip cylinder between free-slip slab walls (SPH scenes only;
    /// the grid's walls are set by `grid.boundary`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wall_viscosity: Option<Real>,
}

/// An obstacle's link to its precomputed boundary layer (Pfaff et al. 2009, section 5.1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AblLink {
    /// The database `eddy-precompute` wrote for this obstacle, relative to the scene file. Its
    /// geometry fingerprint must match the obstacle, scale included.
    pub database: PathBuf,
}

/// Shapes, after parry3d's conventions: cylinders and capsules lie along the local y axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Shape {
    /// A box with the given half extents, m.
    Box {
        /// Half the box's size along its local axes, m.
        half_extents: [Real; 3],
    },
    /// A sphere.
    Sphere {
        /// Radius, m.
        radius: Real,
    },
    /// A cylinder along local y.
    Cylinder {
        /// Radius, m.
        radius: Real,
        /// Half the length along local y, m.
        half_height: Real,
    },
    /// A capsule along local y (half_height is that of the cylindrical part).
    Capsule {
        /// Radius, m.
        radius: Real,
        /// Half the length of the cylindrical part, m.
        half_height: Real,
    },
    /// A closed triangle mesh from an OBJ or STL file, relative to the scene file.
    Mesh {
        /// The OBJ or STL file, relative to the scene file.
        path: PathBuf,
        /// Factor on the mesh's coordinates.
        #[serde(default = "default_scale")]
        scale: Real,
    },
}

fn default_scale() -> Real {
    1.0
}

/// Kinematic motion of a body: constant linear and angular velocity, or a keyframed path.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Motion {
    /// Linear velocity, m/s.
    #[serde(default)]
    pub linear: [Real; 3],
    /// Angular velocity about the body origin, rad/s.
    #[serde(default)]
    pub angular: [Real; 3],
    /// Keyframes (times strictly increasing); when given they replace `linear` and `angular`.
    /// Position is interpolated linearly, orientation by slerp; the pose is held outside the range.
    #[serde(default)]
    pub keyframes: Vec<Keyframe>,
}

impl Motion {
    /// At rest: no velocity and no keyframes.
    pub fn is_still(&self) -> bool {
        *self == Self::default()
    }
}

/// A pose at a time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Keyframe {
    /// Time, s.
    pub t: Real,
    /// Position of the body origin, m.
    pub position: [Real; 3],
    /// Orientation as a rotation vector, radians.
    #[serde(default)]
    pub rotation: [Real; 3],
}
