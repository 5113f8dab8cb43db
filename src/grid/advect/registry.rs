//! The advection schemes: one table that the scene loader, the scene reference, the plan and
//! the grid's step all read, and [`register`] to add a scheme at run time (a research scheme
//! kept outside eddy, or a test's dummy) without touching any of them. A scheme is its step
//! function, in its own file, plus one line in [`BUILT_IN`].

use std::borrow::Cow;
use std::fmt;
use std::sync::RwLock;

use ndarray::Array3;
use schemars::{json_schema, JsonSchema, Schema, SchemaGenerator};
use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::{maccormack, semi_lagrangian, Band};
use crate::grid::interp::Stagger;
use crate::grid::mac::MacGrid;
use crate::Real;

/// One scheme's step: `field` (laid out as `stagger`) carried by `vel` over `dt` into `out` (of
/// the field's shape, standard layout). Only the samples in `band` need tracing; the others
/// must be set to zero (the caller's field is zero far enough outside `band` that they would
/// be).
pub type Step = fn(
    field: &Array3<Real>,
    stagger: Stagger,
    vel: &MacGrid,
    dt: Real,
    band: &Band,
    out: &mut Array3<Real>,
);

/// One advection scheme: the name scene files give it, what the plan and the scene reference
/// say of it, and its step.
pub struct Scheme {
    /// `grid.advection = "..."`, snake_case.
    pub name: &'static str,
    /// The scheme in the plan's sentences ("MacCormack advection of velocity").
    pub label: &'static str,
    /// What it is, one sentence, for the scene reference.
    pub summary: &'static str,
    /// Its step.
    pub advect: Step,
}

/// The schemes eddy ships, in the order the scene reference lists them.
pub static BUILT_IN: [&Scheme; 2] = [&semi_lagrangian::SCHEME, &maccormack::SCHEME];

/// Schemes added by [`register`].
static REGISTERED: RwLock<Vec<&'static Scheme>> = RwLock::new(Vec::new());

/// Adds a scheme for the rest of the process: scenes may name it from then on. A name that is
/// taken is refused.
pub fn register(scheme: Scheme) -> Result<(), String> {
    let mut registered = REGISTERED.write().unwrap_or_else(|e| e.into_inner());
    if BUILT_IN
        .iter()
        .chain(registered.iter())
        .any(|s| s.name == scheme.name)
    {
        return Err(format!(
            "an advection scheme named \"{}\" exists",
            scheme.name
        ));
    }
    registered.push(Box::leak(Box::new(scheme)));
    Ok(())
}

/// Every scheme: the built-in ones, then the registered ones.
pub fn schemes() -> Vec<Advection> {
    let registered = REGISTERED.read().unwrap_or_else(|e| e.into_inner());
    BUILT_IN
        .iter()
        .chain(registered.iter())
        .map(|&s| Advection(s))
        .collect()
}

/// The scheme named `name`.
pub fn find(name: &str) -> Option<Advection> {
    schemes().into_iter().find(|s| s.name() == name)
}

/// The advection scheme of velocity and scalars, as a scene or the solver's parameters hold it:
/// a handle on a scheme of [`schemes`], read and written as its name.
#[derive(Clone, Copy)]
pub struct Advection(&'static Scheme);

impl Advection {
    /// Semi-Lagrangian with a midpoint backtrace.
    pub const SEMI_LAGRANGIAN: Self = Self(&semi_lagrangian::SCHEME);
    /// MacCormack (Selle et al. 2008): the default.
    pub const MACCORMACK: Self = Self(&maccormack::SCHEME);

    /// The scheme this names.
    pub fn scheme(self) -> &'static Scheme {
        self.0
    }

    /// Its name in scene files.
    pub fn name(self) -> &'static str {
        self.0.name
    }

    /// Its name in the plan.
    pub fn label(self) -> &'static str {
        self.0.label
    }
}

impl Default for Advection {
    fn default() -> Self {
        Self::MACCORMACK
    }
}

/// Names are unique in the registry, so they tell schemes apart.
impl PartialEq for Advection {
    fn eq(&self, other: &Self) -> bool {
        self.name() == other.name()
    }
}

impl Eq for Advection {}

impl fmt::Debug for Advection {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_tuple("Advection").field(&self.name()).finish()
    }
}

impl Serialize for Advection {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.name())
    }
}

impl<'de> Deserialize<'de> for Advection {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let name = String::deserialize(deserializer)?;
        find(&name).ok_or_else(|| {
            let names: Vec<String> = schemes()
                .iter()
                .map(|s| format!("`{}`", s.name()))
                .collect();
            D::Error::custom(format!(
                "unknown scheme `{name}`, expected one of {}",
                names.join(", ")
            ))
        })
    }
}

/// One string per scheme with its summary, as schemars derives it for an enum of documented
/// unit variants, so that the scene reference lists the registered schemes too.
impl JsonSchema for Advection {
    fn schema_name() -> Cow<'static, str> {
        "Advection".into()
    }

    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        let choices: Vec<serde_json::Value> = schemes()
            .iter()
            .map(|s| {
                serde_json::json!({
                    "description": s.scheme().summary,
                    "type": "string",
                    "const": s.name(),
                })
            })
            .collect();
        json_schema!({
            "description": "Advection scheme of velocity and scalars.",
            "oneOf": choices,
        })
    }
}
