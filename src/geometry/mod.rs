//! Obstacles and containers on parry3d: shapes, meshes, signed distance, rigid motion, surface sampling.
//!
//! Everything public takes and returns nalgebra types ([`Vec3`], [`Point3`], `Isometry3`);
//! parry 0.31 works in glam, so the conversions stay inside this module.

mod mesh;
mod motion;
mod sampling;
mod spec;

use std::path::PathBuf;

use nalgebra::Isometry3;
use parry3d_f64::math::Vector as GVec;
use parry3d_f64::shape::{Ball, Capsule, Cuboid, Cylinder, Shape as ParryShape, TriMesh};

use crate::{Point3, Real, Vec3};
use motion::Kinematics;
pub use spec::{AblLink, Body, Keyframe, Motion, Shape};

/// Why a body could not be built from its scene entry. Every message names the body, and the
/// file where there is one.
#[derive(Debug, thiserror::Error)]
pub enum GeometryError {
    #[error("body '{body}': mesh file {} not found", .path.display())]
    MeshNotFound { body: String, path: PathBuf },
    #[error("body '{body}': cannot read mesh file {}: {reason}", .path.display())]
    MeshUnreadable {
        body: String,
        path: PathBuf,
        reason: String,
    },
    #[error("body '{body}': cannot parse mesh file {}: {message}", .path.display())]
    MeshParse {
        body: String,
        path: PathBuf,
        message: String,
    },
    #[error("body '{body}': mesh file {} has no triangles", .path.display())]
    EmptyMesh { body: String, path: PathBuf },
    #[error(
        "body '{body}': mesh file {} has extension '{ext}'; only .obj and .stl are supported",
        .path.display()
    )]
    UnsupportedFormat {
        body: String,
        path: PathBuf,
        ext: String,
    },
    #[error(
        "body '{body}': mesh file {} is not a closed, consistently oriented surface ({problem}); \
         signed distance needs a watertight mesh",
        .path.display()
    )]
    MeshNotClosed {
        body: String,
        path: PathBuf,
        problem: String,
    },
    #[error("body '{body}': {message}")]
    InvalidShape { body: String, message: String },
    #[error("body '{body}': {message}")]
    InvalidMotion { body: String, message: String },
}

/// The solid, in the body's own frame.
#[derive(Debug, Clone)]
enum Geometry {
    Box(Cuboid),
    Sphere(Ball),
    Cylinder(Cylinder),
    Capsule(Capsule),
    Mesh(Box<TriMesh>),
}

impl Geometry {
    fn parry(&self) -> &dyn ParryShape {
        match self {
            Geometry::Box(s) => s,
            Geometry::Sphere(s) => s,
            Geometry::Cylinder(s) => s,
            Geometry::Capsule(s) => s,
            Geometry::Mesh(s) => s.as_ref(),
        }
    }
}

fn to_glam(p: &Point3) -> GVec {
    GVec::new(p.x, p.y, p.z)
}

fn to_point(v: GVec) -> Point3 {
    Point3::new(v.x, v.y, v.z)
}

/// A container or obstacle: a solid shape moving kinematically (its motion is prescribed, it
/// feels no forces).
#[derive(Debug, Clone)]
pub struct RigidBody {
    name: String,
    geometry: Geometry,
    kinematics: Kinematics,
    /// Half the diagonal of the local bounding box: the length scale for tolerances.
    size: Real,
}

impl RigidBody {
    /// Builds the body from its scene entry; mesh paths are already absolute or relative to cwd.
    /// `index` names an unnamed body (`"sphere_1"`).
    pub fn from_scene(body: &Body, index: usize) -> Result<Self, GeometryError> {
        let kind = match &body.shape {
            Shape::Box { .. } => "box",
            Shape::Sphere { .. } => "sphere",
            Shape::Cylinder { .. } => "cylinder",
            Shape::Capsule { .. } => "capsule",
            Shape::Mesh { .. } => "mesh",
        };
        let name = body
            .name
            .clone()
            .unwrap_or_else(|| format!("{kind}_{index}"));
        let invalid = |message: String| GeometryError::InvalidShape {
            body: name.clone(),
            message,
        };
        // Zero-size shapes have no surface to sample and no inside to keep fluid out of.
        let positive = |field: &str, v: Real| {
            if v > 0.0 && v.is_finite() {
                Ok(v)
            } else {
                Err(invalid(format!(
                    "shape.{field} must be positive and finite, got {v}"
                )))
            }
        };
        let geometry = match &body.shape {
            Shape::Box { half_extents } => {
                for (axis, &h) in half_extents.iter().enumerate() {
                    positive(&format!("half_extents[{axis}]"), h)?;
                }
                Geometry::Box(Cuboid::new(GVec::from_array(*half_extents)))
            }
            Shape::Sphere { radius } => Geometry::Sphere(Ball::new(positive("radius", *radius)?)),
            Shape::Cylinder {
                radius,
                half_height,
            } => Geometry::Cylinder(Cylinder::new(
                positive("half_height", *half_height)?,
                positive("radius", *radius)?,
            )),
            Shape::Capsule {
                radius,
                half_height,
            } => {
                // A capsule of half height 0 is a sphere; allow it.
                if !(*half_height >= 0.0 && half_height.is_finite()) {
                    return Err(invalid(format!(
                        "shape.half_height must be zero or positive and finite, got {half_height}"
                    )));
                }
                Geometry::Capsule(Capsule::new_y(*half_height, positive("radius", *radius)?))
            }
            Shape::Mesh { path, scale } => Geometry::Mesh(Box::new(mesh::load(
                &name,
                path,
                positive("scale", *scale)?,
            )?)),
        };
        let kinematics =
            Kinematics::new(&body.position, &body.rotation, &body.motion).map_err(|message| {
                GeometryError::InvalidMotion {
                    body: name.clone(),
                    message,
                }
            })?;
        let aabb = geometry.parry().compute_local_aabb();
        let size = 0.5 * (aabb.maxs - aabb.mins).length();
        Ok(Self {
            name,
            geometry,
            kinematics,
            size,
        })
    }

    /// The scene's name for the body, or the shape and index (`"sphere_1"`).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// True when the body ever moves (nonzero velocity or keyframes), so static bodies can be
    /// sampled and binned once.
    pub fn is_moving(&self) -> bool {
        self.kinematics.is_moving()
    }

    /// Local-to-world transform at time `t`. With keyframes the scene's `position` and
    /// `rotation` are unused: the keyframes are absolute poses of the body origin.
    pub fn pose(&self, t: Real) -> Isometry3<Real> {
        self.kinematics.pose(t)
    }

    /// Velocity of the body origin at time `t`.
    pub fn linear_velocity(&self, t: Real) -> Vec3 {
        self.kinematics.velocities(t).0
    }

    /// World-frame angular velocity at time `t`.
    pub fn angular_velocity(&self, t: Real) -> Vec3 {
        self.kinematics.velocities(t).1
    }

    /// Rigid-body velocity of the world point `x` (moving with the body) at time `t`:
    /// v + w x (x - origin(t)). This is the wall velocity boundary conditions need.
    pub fn velocity_at(&self, t: Real, x: &Point3) -> Vec3 {
        let (v, w) = self.kinematics.velocities(t);
        let origin = self.kinematics.pose(t).translation.vector;
        v + w.cross(&(x.coords - origin))
    }

    /// An upper bound on the speed of any point of the body at any time: the origin's fastest
    /// speed plus the fastest spin times the farthest corner of its bounding box.
    pub fn fastest_speed(&self) -> Real {
        let (v, w) = self.kinematics.fastest();
        let (lo, hi) = self.local_aabb();
        let reach = lo.coords.abs().sup(&hi.coords.abs()).norm();
        v + w * reach
    }

    /// Signed distance from the world point `x` to the surface at time `t`: negative inside the
    /// solid.
    pub fn signed_distance(&self, t: Real, x: &Point3) -> Real {
        self.signed_distance_local(&self.pose(t).inverse_transform_point(x))
    }

    /// Signed distance of a body-local point; cheaper than [`Self::signed_distance`] when many
    /// points are queried at one time (transform them with `pose(t).inverse()` once).
    pub fn signed_distance_local(&self, x: &Point3) -> Real {
        self.geometry
            .parry()
            .distance_to_local_point(to_glam(x), false)
    }

    /// Outward unit normal of the surface point nearest to the world point `x` at time `t`
    /// (the gradient of the signed distance), in world coordinates.
    pub fn normal(&self, t: Real, x: &Point3) -> Vec3 {
        let pose = self.pose(t);
        pose.rotation * self.normal_local(&pose.inverse_transform_point(x))
    }

    /// Outward unit normal of the surface point nearest to the body-local point `x`.
    pub fn normal_local(&self, x: &Point3) -> Vec3 {
        let proj = self.geometry.parry().project_local_point(to_glam(x), false);
        let d = x - to_point(proj.point);
        let len = d.norm();
        if len > 1e-9 * self.size {
            return if proj.is_inside { -d / len } else { d / len };
        }
        // On the surface the offset has no direction: take the gradient by central differences.
        let h = 1e-6 * self.size;
        let grad = Vec3::from_fn(|i, _| {
            let e = Vec3::ith(i, h);
            self.signed_distance_local(&(x + e)) - self.signed_distance_local(&(x - e))
        });
        grad.try_normalize(0.0).unwrap_or_else(Vec3::y)
    }

    /// Body-local points on the surface about `spacing` apart, for Akinci boundary particles:
    /// no gap wider than about `spacing`, no two points closer than about `spacing / 2`.
    ///
    /// Boxes: a grid on each face, edges and corners once. Spheres: a Fibonacci lattice of
    /// round(4 pi r^2 / spacing^2) points. Cylinders and capsules: staggered rings along the
    /// profile (concentric on the flat caps, latitude rings on the hemispheres), rims once.
    /// Meshes: vertices, edges and a lattice per triangle, thinned to spacing / 2.
    ///
    /// # Panics
    /// If `spacing` is not positive and finite (the scene validates the fluid spacing).
    pub fn sample_surface(&self, spacing: Real) -> Vec<Point3> {
        sample_geometry(&self.geometry, spacing)
    }

    /// Body-local points about `spacing` apart on the surface moved `offset` along its outward
    /// normal (negative: into the solid), as [`Self::sample_surface`] samples it. Spheres,
    /// cylinders, capsules and shrunk boxes are resized exactly (a dimension stops at zero, so
    /// a plate thinner than the offset is sampled on its mid-plane); a grown box's face grids
    /// continue the columns of a lattice filling the box (`sampling::sample_box_shell`); mesh
    /// samples move along the normal of their nearest surface point.
    ///
    /// # Panics
    /// As [`Self::sample_surface`].
    pub fn sample_offset_surface(&self, spacing: Real, offset: Real) -> Vec<Point3> {
        let grow = |x: Real| (x + offset).max(0.0);
        let offset_geometry = match &self.geometry {
            Geometry::Box(c) if offset > 0.0 => {
                let h = c.half_extents;
                return sampling::sample_box_shell(&Vec3::new(h.x, h.y, h.z), offset, spacing);
            }
            Geometry::Box(c) => Geometry::Box(Cuboid::new(c.half_extents.map(grow))),
            Geometry::Sphere(b) => Geometry::Sphere(Ball::new(grow(b.radius))),
            Geometry::Cylinder(c) => {
                Geometry::Cylinder(Cylinder::new(grow(c.half_height), grow(c.radius)))
            }
            Geometry::Capsule(c) => {
                Geometry::Capsule(Capsule::new_y(c.half_height(), grow(c.radius)))
            }
            Geometry::Mesh(_) => {
                return self
                    .sample_surface(spacing)
                    .into_iter()
                    .map(|p| p + offset * self.normal_local(&p))
                    .collect()
            }
        };
        sample_geometry(&offset_geometry, spacing)
    }

    /// The world-space bounding box of the body at time `t`.
    pub fn world_aabb(&self, t: Real) -> (Vec3, Vec3) {
        let (lo, hi) = self.local_aabb();
        let pose = self.pose(t);
        let mut min = Vec3::repeat(Real::INFINITY);
        let mut max = Vec3::repeat(Real::NEG_INFINITY);
        for corner in 0..8 {
            let p = Point3::new(
                if corner & 1 == 0 { lo.x } else { hi.x },
                if corner & 2 == 0 { lo.y } else { hi.y },
                if corner & 4 == 0 { lo.z } else { hi.z },
            );
            let w = pose * p;
            min = min.inf(&w.coords);
            max = max.sup(&w.coords);
        }
        (min, max)
    }

    /// Corners (min, max) of the body-local axis-aligned bounding box.
    pub fn local_aabb(&self) -> (Point3, Point3) {
        let aabb = self.geometry.parry().compute_local_aabb();
        (to_point(aabb.mins), to_point(aabb.maxs))
    }
}

/// Surface samples of `geometry` (see [`RigidBody::sample_surface`]).
fn sample_geometry(geometry: &Geometry, spacing: Real) -> Vec<Point3> {
    assert!(
        spacing > 0.0 && spacing.is_finite(),
        "sample spacing must be positive and finite, got {spacing}"
    );
    use sampling::Piece;
    use std::f64::consts::{FRAC_PI_2, PI};
    match geometry {
        Geometry::Box(c) => {
            let h = c.half_extents;
            sampling::sample_box(&Vec3::new(h.x, h.y, h.z), spacing)
        }
        Geometry::Sphere(b) => sampling::fibonacci_sphere(b.radius, spacing),
        // Profiles from the bottom pole to the top pole, revolved about y.
        Geometry::Cylinder(c) => {
            let (r, hh) = (c.radius, c.half_height);
            sampling::revolve(
                &[
                    Piece::line((0.0, -hh), (r, -hh)),
                    Piece::line((r, -hh), (r, hh)),
                    Piece::line((r, hh), (0.0, hh)),
                ],
                spacing,
            )
        }
        Geometry::Capsule(c) => {
            let (r, hh) = (c.radius, c.half_height());
            sampling::revolve(
                &[
                    Piece::arc(r, -hh, PI, FRAC_PI_2),
                    Piece::line((r, -hh), (r, hh)),
                    Piece::arc(r, hh, FRAC_PI_2, 0.0),
                ],
                spacing,
            )
        }
        Geometry::Mesh(m) => mesh::sample_mesh(m, spacing),
    }
}
