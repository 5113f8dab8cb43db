//! The scene's `[refinement]` section: which SPH turbulence refinement runs (a method of
//! [`super::registry`]) with its parameters, read, validated and written back.
//!
//! ```toml
//! [refinement]
//! method = "vrsph"   # none | rankine | vrsph | mcvsph | micropolar | confinement
//! alpha = 1.0
//! walls = false
//! ```
//!
//! Each method takes only its own keys (any other key is an error); `none` takes only `walls`,
//! which a sweep across methods may set for all and which it ignores. `walls` (every method but
//! `none`, default false) lets the Akinci boundary samples into the shared difference operators
//! (see `crate::sph::operators`). The default is off because all three papers keep the walls
//! out of the vorticity: Wang et al. (Sec. 4.3) found the vorticity field unstable near rigid,
//! especially moving, bodies when boundary particles took part; Ye et al. set the loss of solid
//! particles to zero. Under eddy's free-slip-by-default walls (`viscosity.boundary = 0`) a
//! static wall in the curl would also read the fluid sliding along it as wall vorticity that
//! the momentum equation never produced, and the loss-based methods would feed it back every
//! step as a source. With `walls = true` the wall shear counts, which models no-slip walls;
//! pair it with `viscosity.boundary > 0`.

use std::fmt;

use serde::de::{Error as _, Unexpected};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::registry::{self, Method, Stored};
use super::StepHook;
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

/// The refinement of a scene and its parameters; the default is none (plain DFSPH or IISPH).
#[derive(Clone, Default)]
pub struct Refinement(Option<Chosen>);

/// A method and its parameters.
struct Chosen {
    method: &'static Method,
    params: Box<dyn Stored>,
}

impl Clone for Chosen {
    fn clone(&self) -> Self {
        Self {
            method: self.method,
            params: self.params.clone_box(),
        }
    }
}

impl Refinement {
    /// The method's name as written in scene files (`none` for none).
    pub fn method(&self) -> &'static str {
        self.0.as_ref().map_or("none", |c| c.method.name)
    }

    /// Whether no refinement runs.
    pub fn is_none(&self) -> bool {
        self.0.is_none()
    }

    /// Bytes per fluid particle its step hook keeps between steps (0 for none).
    pub fn bytes_per_particle(&self) -> u64 {
        self.0.as_ref().map_or(0, |c| c.method.bytes_per_particle)
    }

    /// Checks every numeric parameter against its method's range; errors name the key.
    pub fn validate(&self) -> Result<(), InvalidParam> {
        let Some(chosen) = &self.0 else {
            return Ok(());
        };
        let params = &*chosen.params as &dyn erased_serde::Serialize;
        let keys = toml::Table::try_from(params).unwrap_or_default();
        for (key, range) in chosen.method.ranges {
            let value = keys
                .get(*key)
                .and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as Real)));
            // Built-in methods are verified by a test, registered ones when registered.
            let value = value.unwrap_or_else(|| {
                panic!(
                    "method \"{}\": its range names `{key}`, not a number of its keys",
                    chosen.method.name
                )
            });
            if !(value.is_finite() && range.contains(value)) {
                return Err(InvalidParam {
                    key: format!("refinement.{key}"),
                    value,
                    allowed: format!(
                        "{} for method \"{}\"",
                        range.describe(true),
                        chosen.method.name
                    ),
                });
            }
        }
        Ok(())
    }

    /// The step hook for `n` fluid particles; None for none.
    pub fn build(&self, n: usize, seed: u64) -> Option<Box<dyn StepHook>> {
        self.0.as_ref().map(|c| c.params.build(n, seed))
    }
}

impl PartialEq for Refinement {
    fn eq(&self, other: &Self) -> bool {
        match (&self.0, &other.0) {
            (None, None) => true,
            (Some(a), Some(b)) => a.method.name == b.method.name && a.params.same_as(&*b.params),
            _ => false,
        }
    }
}

impl fmt::Debug for Refinement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.0 {
            None => f.write_str("Refinement(none)"),
            Some(c) => write!(f, "Refinement({}, {:?})", c.method.name, c.params),
        }
    }
}

/// `method = "..."` first, then the method's keys in its struct's order.
impl Serialize for Refinement {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        #[derive(Serialize)]
        struct Tagged<'a> {
            method: &'a str,
            #[serde(flatten)]
            params: Option<&'a dyn erased_serde::Serialize>,
        }
        let params = self
            .0
            .as_ref()
            .map(|c| &*c.params as &dyn erased_serde::Serialize);
        Tagged {
            method: self.method(),
            params,
        }
        .serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for Refinement {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let mut keys = toml::Table::deserialize(deserializer)?;
        let name = match keys.remove("method") {
            Some(toml::Value::String(name)) => name,
            Some(other) => {
                let shown = other.to_string();
                return Err(D::Error::invalid_type(
                    Unexpected::Other(&shown),
                    &"a method name",
                ));
            }
            None => return Err(D::Error::missing_field("method")),
        };
        if name == "none" {
            return match keys.keys().find(|k| *k != "walls") {
                Some(key) => Err(D::Error::custom(format!(
                    "unknown field `{key}`, method \"none\" takes no parameters"
                ))),
                None => Ok(Self(None)),
            };
        }
        let Some(method) = registry::find(&name) else {
            let names: Vec<String> = std::iter::once("none")
                .chain(registry::methods().iter().map(|m| m.name))
                .map(|n| format!("`{n}`"))
                .collect();
            return Err(D::Error::custom(format!(
                "unknown method `{name}`, expected one of {}",
                names.join(", ")
            )));
        };
        let params = method
            .parse(keys)
            .map_err(|e| D::Error::custom(e.message()))?;
        Ok(Self(Some(Chosen { method, params })))
    }
}
