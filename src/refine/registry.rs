//! The refinement methods: one table that the scene loader, the validation, the plan, the bench,
//! the help and the scene reference all read, and [`register`] to add a method at run time (a research method kept
//! outside eddy, or a test's dummy) without touching any of them.
//!
//! A method is its parameter struct, in its own file: the keys of `[refinement]` besides
//! `method`, as serde reads them (`deny_unknown_fields`, the papers' defaults, doc comments
//! that the scene reference prints), implementing [`MethodParams`] (the step hook it builds),
//! with the ranges of its numeric keys, plus one line in [`BUILT_IN`].
//! The hook says itself what it does in the plan ([`StepHook::describe`]).

use std::any::Any;
use std::fmt;
use std::sync::RwLock;

use schemars::JsonSchema;
use serde::de::DeserializeOwned;
use serde::Serialize;

use super::{confinement, mcvsph, micropolar, rankine, vrsph, StepHook};
pub use crate::interval::Interval;
use crate::Real;

/// A method's parameters once read from the scene.
pub trait MethodParams: fmt::Debug + Send + Sync + 'static {
    /// The step hook for `n` fluid particles; `seed` is the scene's.
    fn build(&self, n: usize, seed: u64) -> Box<dyn StepHook>;
}

/// Each numeric key of a method and its range, in the order the validation checks them.
pub type Ranges = &'static [(&'static str, Interval<'static>)];

/// One refinement method: the name scene files give it, one line of what it is, and how its
/// keys are read.
pub struct Method {
    /// `method = "..."` in `[refinement]`.
    pub name: &'static str,
    /// What it is, with its paper, for help texts.
    pub summary: &'static str,
    /// The allowed range of each numeric key: the validation checks them, the scene reference
    /// (`eddy scene-keys`) prints them.
    pub ranges: Ranges,
    /// Bytes per fluid particle its step hook keeps from one step to the next (its state and
    /// the buffers it keeps for their memory), for the run's memory estimate; set with
    /// [`Self::keeping`].
    pub bytes_per_particle: u64,
    parse: fn(toml::Table) -> Result<Box<dyn Stored>, toml::de::Error>,
    schema: fn() -> schemars::Schema,
}

impl Method {
    /// The method `name` whose keys are the fields of `P`, its numeric ones in `ranges`.
    pub const fn new<P>(name: &'static str, summary: &'static str, ranges: Ranges) -> Self
    where
        P: MethodParams + Serialize + DeserializeOwned + Clone + PartialEq + JsonSchema,
    {
        Self {
            name,
            summary,
            ranges,
            bytes_per_particle: 0,
            parse: parse_as::<P>,
            schema: schema_of::<P>,
        }
    }

    /// The method whose hook keeps `bytes` per fluid particle between steps.
    pub const fn keeping(self, bytes: u64) -> Self {
        Self {
            bytes_per_particle: bytes,
            ..self
        }
    }

    /// The JSON schema of its keys (types, defaults, doc comments), for the scene reference.
    pub fn schema(&self) -> schemars::Schema {
        (self.schema)()
    }

    /// Checks that each key of its ranges is a number among its keys, so that the validation
    /// finds every value it checks.
    pub fn verify(&self) -> Result<(), String> {
        let schema = self.schema();
        for (key, _) in self.ranges {
            let kind = schema
                .as_value()
                .pointer(&format!("/properties/{key}/type"))
                .and_then(|t| t.as_str());
            if !matches!(kind, Some("number" | "integer")) {
                return Err(format!(
                    "refinement method \"{}\": its range names `{key}`, which is not one of \
                     its numeric keys",
                    self.name
                ));
            }
        }
        Ok(())
    }

    /// Reads the method's keys (all of `[refinement]` but `method`).
    pub(super) fn parse(&self, keys: toml::Table) -> Result<Box<dyn Stored>, toml::de::Error> {
        (self.parse)(keys)
    }
}

fn parse_as<P>(keys: toml::Table) -> Result<Box<dyn Stored>, toml::de::Error>
where
    P: MethodParams + Serialize + DeserializeOwned + Clone + PartialEq,
{
    Ok(Box::new(toml::Value::Table(keys).try_into::<P>()?))
}

/// The default of a gain whose ideal value is one (Rankine's beta, VRSPH's alpha).
pub(super) fn one() -> Real {
    1.0
}

fn schema_of<P: JsonSchema>() -> schemars::Schema {
    schemars::schema_for!(P)
}

/// The methods eddy ships, in the order help texts list them.
pub static BUILT_IN: [Method; 5] = [
    rankine::METHOD,
    vrsph::METHOD,
    mcvsph::METHOD,
    micropolar::METHOD,
    confinement::METHOD,
];

/// Methods added by [`register`].
static REGISTERED: RwLock<Vec<&'static Method>> = RwLock::new(Vec::new());

/// Adds a method for the rest of the process: scenes may name it from then on. A name that
/// is taken (or `none`), or ranges that name no numeric key ([`Method::verify`]), are refused.
pub fn register(method: Method) -> Result<(), String> {
    let mut registered = REGISTERED.write().unwrap_or_else(|e| e.into_inner());
    let taken = method.name == "none"
        || BUILT_IN.iter().any(|m| m.name == method.name)
        || registered.iter().any(|m| m.name == method.name);
    if taken {
        return Err(format!(
            "a refinement method named \"{}\" exists",
            method.name
        ));
    }
    method.verify()?;
    registered.push(Box::leak(Box::new(method)));
    Ok(())
}

/// Every method: the built-in ones, then the registered ones.
pub fn methods() -> Vec<&'static Method> {
    let registered = REGISTERED.read().unwrap_or_else(|e| e.into_inner());
    BUILT_IN.iter().chain(registered.iter().copied()).collect()
}

/// The method named `name`.
pub fn find(name: &str) -> Option<&'static Method> {
    methods().into_iter().find(|m| m.name == name)
}

/// A method's parameters behind one type, so that a scene can be cloned, compared and written
/// back (the resolved `scene.toml`) whatever its method.
pub(super) trait Stored: MethodParams + erased_serde::Serialize {
    fn clone_box(&self) -> Box<dyn Stored>;
    fn as_any(&self) -> &dyn Any;
    fn same_as(&self, other: &dyn Stored) -> bool;
}

impl<P: MethodParams + Serialize + Clone + PartialEq> Stored for P {
    fn clone_box(&self) -> Box<dyn Stored> {
        Box::new(self.clone())
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn same_as(&self, other: &dyn Stored) -> bool {
        other.as_any().downcast_ref::<P>() == Some(self)
    }
}
