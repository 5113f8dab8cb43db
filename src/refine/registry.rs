//! The refinement methods: one table that the scene loader, the validation, the plan, the bench
//! and the help all read, and [`register`] to add a method at run time (a research method kept
//! outside eddy, or a test's dummy) without touching any of them.
//!
//! A method is its parameter struct, in its own file: the keys of `[refinement]` besides
//! `method`, as serde reads them (`deny_unknown_fields`, the papers' defaults), implementing
//! [`MethodParams`] (its ranges and the step hook it builds), plus one line in [`BUILT_IN`].
//! The hook says itself what it does in the plan ([`StepHook::describe`]).

use std::any::Any;
use std::fmt;
use std::sync::RwLock;

use serde::de::DeserializeOwned;
use serde::Serialize;

use super::{confinement, mcvsph, micropolar, rankine, vrsph, StepHook};
use crate::Real;

/// A method's parameters once read from the scene.
pub trait MethodParams: fmt::Debug + Send + Sync + 'static {
    /// Checks every parameter against its allowed range (see [`check`]).
    fn validate(&self) -> Result<(), RangeError>;

    /// The step hook for `n` fluid particles; `seed` is the scene's.
    fn build(&self, n: usize, seed: u64) -> Box<dyn StepHook>;
}

/// A parameter outside its range: its key within `[refinement]`, its value and what is allowed.
#[derive(Debug, Clone, PartialEq)]
pub struct RangeError {
    pub key: &'static str,
    pub value: Real,
    pub allowed: String,
}

/// Checks that `value` is finite and inside the interval from `lo` to `hi` (open at an end
/// where `lo_open` or `hi_open`; `hi` infinite for no upper bound).
pub fn check(
    key: &'static str,
    value: Real,
    (lo, lo_open): (Real, bool),
    (hi, hi_open): (Real, bool),
) -> Result<(), RangeError> {
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
    Err(RangeError {
        key,
        value,
        allowed,
    })
}

/// One refinement method: the name scene files give it, one line of what it is, and how its
/// keys are read.
pub struct Method {
    /// `method = "..."` in `[refinement]`.
    pub name: &'static str,
    /// What it is, with its paper, for help texts.
    pub summary: &'static str,
    parse: fn(toml::Table) -> Result<Box<dyn Stored>, toml::de::Error>,
}

impl Method {
    /// The method `name` whose keys are the fields of `P`.
    pub const fn new<P>(name: &'static str, summary: &'static str) -> Self
    where
        P: MethodParams + Serialize + DeserializeOwned + Clone + PartialEq,
    {
        Self {
            name,
            summary,
            parse: parse_as::<P>,
        }
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
/// is taken (or `none`) is refused.
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
