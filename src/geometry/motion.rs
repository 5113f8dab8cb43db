//! Kinematic rigid motion: constant velocities or a keyframed path.
//!
//! Rotations between keyframes turn at a constant rate about a fixed world axis (the shortest
//! arc, i.e. slerp), so the angular velocity reported for a segment is exactly the derivative of
//! the pose reported for it.

use nalgebra::{Isometry3, Translation3, UnitQuaternion};

use super::spec::Motion;
use crate::{Real, Vec3};

/// An orientation.
type Rotation = UnitQuaternion<Real>;

/// A pose of the body origin at a time.
#[derive(Debug, Clone)]
pub(crate) struct Key {
    t: Real,
    position: Vec3,
    rotation: Rotation,
}

/// The prescribed motion of a body frame.
#[derive(Debug, Clone)]
pub(crate) enum Kinematics {
    /// The origin moves at `linear`; the body spins about its own origin at the world-frame
    /// `angular` velocity.
    Constant {
        position: Vec3,
        rotation: Rotation,
        linear: Vec3,
        angular: Vec3,
    },
    /// Linear in position and constant-rate in rotation between keys, held outside their range.
    /// `turns[k]` is the world-frame rotation vector that takes key `k` to key `k + 1`.
    Keyframed { keys: Vec<Key>, turns: Vec<Vec3> },
}

/// Rotation vector (axis times angle) to a quaternion.
fn rotation_from(v: &[Real; 3]) -> Rotation {
    Rotation::from_scaled_axis(Vec3::from(*v))
}

/// True when every component is finite.
fn finite(v: &[Real; 3]) -> bool {
    v.iter().all(|c| c.is_finite())
}

impl Kinematics {
    /// The motion of a body placed at `position`/`rotation` at t = 0. Keyframes, when given,
    /// replace all four (they are absolute poses of the body origin). Errors are messages for
    /// the caller to wrap with the body's name.
    pub(crate) fn new(
        position: &[Real; 3],
        rotation: &[Real; 3],
        motion: &Motion,
    ) -> Result<Self, String> {
        if motion.keyframes.is_empty() {
            for (what, v) in [
                ("position", position),
                ("rotation", rotation),
                ("motion.linear", &motion.linear),
                ("motion.angular", &motion.angular),
            ] {
                if !finite(v) {
                    return Err(format!("{what} must be finite, got {v:?}"));
                }
            }
            return Ok(Kinematics::Constant {
                position: Vec3::from(*position),
                rotation: rotation_from(rotation),
                linear: Vec3::from(motion.linear),
                angular: Vec3::from(motion.angular),
            });
        }
        if motion.keyframes.len() < 2 {
            return Err(format!(
                "motion.keyframes needs at least 2 keyframes, got {}",
                motion.keyframes.len()
            ));
        }
        let mut keys: Vec<Key> = Vec::with_capacity(motion.keyframes.len());
        for (i, k) in motion.keyframes.iter().enumerate() {
            if !k.t.is_finite() || !finite(&k.position) || !finite(&k.rotation) {
                return Err(format!("motion.keyframes[{i}] must be finite"));
            }
            if let Some(prev) = keys.last() {
                if k.t <= prev.t {
                    return Err(format!(
                        "motion.keyframes times must increase strictly, but keyframes[{i}].t = {} \
                         follows {}",
                        k.t, prev.t
                    ));
                }
            }
            keys.push(Key {
                t: k.t,
                position: Vec3::from(k.position),
                rotation: rotation_from(&k.rotation),
            });
        }
        // `scaled_axis` takes the angle in [0, pi]: the shortest arc, as slerp does.
        let turns = keys
            .windows(2)
            .map(|w| (w[1].rotation * w[0].rotation.inverse()).scaled_axis())
            .collect();
        Ok(Kinematics::Keyframed { keys, turns })
    }

    /// True when the body ever moves.
    pub(crate) fn is_moving(&self) -> bool {
        match self {
            Kinematics::Constant {
                linear, angular, ..
            } => *linear != Vec3::zeros() || *angular != Vec3::zeros(),
            Kinematics::Keyframed { .. } => true,
        }
    }

    /// The largest speed of the origin and the largest angular speed over all time.
    pub(crate) fn fastest(&self) -> (Real, Real) {
        match self {
            Kinematics::Constant {
                linear, angular, ..
            } => (linear.norm(), angular.norm()),
            Kinematics::Keyframed { keys, turns } => keys
                .windows(2)
                .zip(turns)
                .map(|(w, turn)| {
                    let dt = w[1].t - w[0].t;
                    (
                        (w[1].position - w[0].position).norm() / dt,
                        turn.norm() / dt,
                    )
                })
                .fold((0.0, 0.0), |(v, w), (sv, sw)| (v.max(sv), w.max(sw))),
        }
    }

    /// Local-to-world transform at time `t`.
    pub(crate) fn pose(&self, t: Real) -> Isometry3<Real> {
        match self {
            Kinematics::Constant {
                position,
                rotation,
                linear,
                angular,
            } => Isometry3::from_parts(
                Translation3::from(position + linear * t),
                Rotation::from_scaled_axis(angular * t) * rotation,
            ),
            Kinematics::Keyframed { keys, turns } => {
                let (position, rotation) = match segment(keys, t) {
                    Segment::Before => (keys[0].position, keys[0].rotation),
                    Segment::After => {
                        let last = &keys[keys.len() - 1];
                        (last.position, last.rotation)
                    }
                    Segment::Inside(k, s) => (
                        keys[k].position.lerp(&keys[k + 1].position, s),
                        Rotation::from_scaled_axis(turns[k] * s) * keys[k].rotation,
                    ),
                };
                Isometry3::from_parts(Translation3::from(position), rotation)
            }
        }
    }

    /// (velocity of the origin, world-frame angular velocity) at time `t`.
    pub(crate) fn velocities(&self, t: Real) -> (Vec3, Vec3) {
        match self {
            Kinematics::Constant {
                linear, angular, ..
            } => (*linear, *angular),
            Kinematics::Keyframed { keys, turns } => match segment(keys, t) {
                Segment::Inside(k, _) => {
                    let dt = keys[k + 1].t - keys[k].t;
                    (
                        (keys[k + 1].position - keys[k].position) / dt,
                        turns[k] / dt,
                    )
                }
                Segment::Before | Segment::After => (Vec3::zeros(), Vec3::zeros()),
            },
        }
    }
}

/// Where a time falls among the keys.
enum Segment {
    Before,
    After,
    /// Between keys `k` and `k + 1`, at fraction `s` in [0, 1).
    Inside(usize, Real),
}

/// Finds the segment `[t_k, t_k+1)` holding `t`; a NaN time counts as before the first key.
fn segment(keys: &[Key], t: Real) -> Segment {
    let next = keys.partition_point(|k| k.t <= t);
    if next == 0 {
        Segment::Before
    } else if next == keys.len() {
        Segment::After
    } else {
        let (a, b) = (&keys[next - 1], &keys[next]);
        Segment::Inside(next - 1, (t - a.t) / (b.t - a.t))
    }
}
