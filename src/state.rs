//! A run's state between two steps as named arrays: what a checkpoint stores and a resumed run
//! restores. Every part that carries something from one step to the next (a solver's fields
//! and warm starts, an emitter's phase, vortex particles, a random generator, running sums)
//! implements [`Persist`]: `save` puts its entries under its own section, `restore` reads them
//! back into a part freshly built from the same scene. What a step recomputes from these
//! (neighbour lists, solver hierarchies, caches) is not stored; it is rebuilt as it would be.
//!
//! This module knows no file format (`crate::io::checkpoint` writes a [`State`] to HDF5), so
//! the solvers, refinements and the vortex layer can implement [`Persist`] without naming one.

use std::collections::BTreeMap;

use rand_chacha::ChaCha8Rng;

use crate::{Real, Vec3};

/// One entry's values, flat (a field's shape is the part's to know).
#[derive(Debug, Clone, PartialEq)]
pub enum Values {
    F64(Vec<f64>),
    U64(Vec<u64>),
    I64(Vec<i64>),
    U8(Vec<u8>),
}

impl Values {
    /// The element type's name, for errors and the file.
    pub fn kind(&self) -> &'static str {
        match self {
            Values::F64(_) => "f64",
            Values::U64(_) => "u64",
            Values::I64(_) => "i64",
            Values::U8(_) => "u8",
        }
    }

    /// Number of values.
    pub fn len(&self) -> usize {
        match self {
            Values::F64(v) => v.len(),
            Values::U64(v) => v.len(),
            Values::I64(v) => v.len(),
            Values::U8(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Bytes the values hold.
    pub fn bytes(&self) -> usize {
        match self {
            Values::U8(v) => v.len(),
            _ => 8 * self.len(),
        }
    }
}

/// Why a state could not be restored.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StateError {
    #[error("the checkpoint has no entry '{0}'")]
    Missing(String),
    #[error("the checkpoint's entry '{name}' holds {found}, expected {expected}")]
    Mismatch {
        name: String,
        found: String,
        expected: String,
    },
}

/// A run's state: entries named by `/`-separated paths ("sph/fluid/x").
#[derive(Debug, Clone, Default, PartialEq)]
pub struct State {
    entries: BTreeMap<String, Values>,
    /// For a state made by [`State::sizing`]: the bytes saved so far, nothing kept.
    sized: Option<usize>,
}

impl State {
    pub fn new() -> Self {
        Self::default()
    }

    /// A state that only counts the bytes saved into it (a checkpoint's size for the plan,
    /// without copying the fields).
    pub fn sizing() -> Self {
        Self {
            entries: BTreeMap::new(),
            sized: Some(0),
        }
    }

    /// A writer for entries under `section`.
    pub fn section(&mut self, section: &str) -> Saver<'_> {
        Saver {
            state: self,
            prefix: section.to_owned(),
        }
    }

    /// A reader for entries under `section`.
    pub fn read(&self, section: &str) -> Restorer<'_> {
        Restorer {
            state: self,
            prefix: section.to_owned(),
        }
    }

    /// Every entry, by path, in order.
    pub fn entries(&self) -> impl Iterator<Item = (&str, &Values)> {
        self.entries.iter().map(|(k, v)| (k.as_str(), v))
    }

    /// Adds an entry by its full path (the file reader's way in).
    pub fn insert(&mut self, path: String, values: Values) {
        self.entries.insert(path, values);
    }

    /// Bytes the entries hold (or, made by [`State::sizing`], would hold).
    pub fn bytes(&self) -> usize {
        self.sized
            .unwrap_or_else(|| self.entries.values().map(Values::bytes).sum())
    }
}

fn join(prefix: &str, name: &str) -> String {
    if prefix.is_empty() {
        name.to_owned()
    } else {
        format!("{prefix}/{name}")
    }
}

/// Puts entries under one section of a [`State`].
pub struct Saver<'a> {
    state: &'a mut State,
    prefix: String,
}

impl Saver<'_> {
    /// A writer for the subsection `name`.
    pub fn section(&mut self, name: &str) -> Saver<'_> {
        Saver {
            prefix: join(&self.prefix, name),
            state: self.state,
        }
    }

    /// Keeps the entry `name` of `bytes` bytes that `values` makes, or only counts them.
    fn put(&mut self, name: &str, bytes: usize, values: impl FnOnce() -> Values) {
        if let Some(sized) = self.state.sized.as_mut() {
            *sized += bytes;
            return;
        }
        let path = join(&self.prefix, name);
        let earlier = self.state.entries.insert(path.clone(), values());
        debug_assert!(earlier.is_none(), "state entry {path} saved twice");
    }

    pub fn reals(&mut self, name: &str, v: &[Real]) {
        self.put(name, 8 * v.len(), || Values::F64(v.to_vec()));
    }

    pub fn real(&mut self, name: &str, v: Real) {
        self.reals(name, &[v]);
    }

    /// Vectors as x, y, z in turn.
    pub fn vec3s(&mut self, name: &str, v: &[Vec3]) {
        self.put(name, 24 * v.len(), || {
            Values::F64(v.iter().flat_map(|v| [v.x, v.y, v.z]).collect())
        });
    }

    pub fn u64s(&mut self, name: &str, v: &[u64]) {
        self.put(name, 8 * v.len(), || Values::U64(v.to_vec()));
    }

    pub fn u64(&mut self, name: &str, v: u64) {
        self.u64s(name, &[v]);
    }

    pub fn i64s(&mut self, name: &str, v: &[i64]) {
        self.put(name, 8 * v.len(), || Values::I64(v.to_vec()));
    }

    pub fn bytes(&mut self, name: &str, v: &[u8]) {
        self.put(name, v.len(), || Values::U8(v.to_vec()));
    }

    pub fn flag(&mut self, name: &str, v: bool) {
        self.bytes(name, &[v as u8]);
    }

    /// A ChaCha generator exactly: its seed, stream and position in the stream.
    pub fn rng(&mut self, name: &str, rng: &ChaCha8Rng) {
        let pos = rng.get_word_pos();
        let mut s = self.section(name);
        s.bytes("seed", &rng.get_seed());
        s.u64s(
            "stream_pos",
            &[rng.get_stream(), pos as u64, (pos >> 64) as u64],
        );
    }
}

/// Reads entries under one section of a [`State`], checking their type and length.
pub struct Restorer<'a> {
    state: &'a State,
    prefix: String,
}

impl Restorer<'_> {
    /// A reader for the subsection `name`.
    pub fn section(&self, name: &str) -> Restorer<'_> {
        Restorer {
            prefix: join(&self.prefix, name),
            state: self.state,
        }
    }

    /// Whether the entry `name` is there (for optional parts).
    pub fn has(&self, name: &str) -> bool {
        let path = join(&self.prefix, name);
        let below = format!("{path}/");
        self.state.entries.contains_key(&path)
            || self
                .state
                .entries
                .range(below.clone()..)
                .next()
                .is_some_and(|(k, _)| k.starts_with(&below))
    }

    fn get(&self, name: &str) -> Result<(String, &Values), StateError> {
        let path = join(&self.prefix, name);
        match self.state.entries.get(&path) {
            Some(v) => Ok((path, v)),
            None => Err(StateError::Missing(path)),
        }
    }

    fn mismatch(name: String, found: &Values, expected: String) -> StateError {
        StateError::Mismatch {
            name,
            found: format!("{} {} values", found.len(), found.kind()),
            expected,
        }
    }

    /// Real values, any number.
    pub fn reals(&self, name: &str) -> Result<Vec<Real>, StateError> {
        match self.get(name)? {
            (_, Values::F64(v)) => Ok(v.clone()),
            (path, v) => Err(Self::mismatch(path, v, "f64 values".into())),
        }
    }

    /// Exactly `n` real values.
    pub fn reals_n(&self, name: &str, n: usize) -> Result<Vec<Real>, StateError> {
        let v = self.reals(name)?;
        if v.len() == n {
            Ok(v)
        } else {
            let path = join(&self.prefix, name);
            Err(Self::mismatch(
                path,
                &Values::F64(v),
                format!("{n} f64 values"),
            ))
        }
    }

    /// Restores into a slice of the same length (a field of a grid built from the scene).
    pub fn reals_into(&self, name: &str, into: &mut [Real]) -> Result<(), StateError> {
        into.copy_from_slice(&self.reals_n(name, into.len())?);
        Ok(())
    }

    pub fn real(&self, name: &str) -> Result<Real, StateError> {
        Ok(self.reals_n(name, 1)?[0])
    }

    /// Exactly `n` vectors (per-particle fields of a part whose count another entry gave).
    pub fn vec3s_n(&self, name: &str, n: usize) -> Result<Vec<Vec3>, StateError> {
        let v = self.reals_n(name, 3 * n)?;
        Ok(v.chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect())
    }

    /// The error for the entry `name`, which is there but holds what the part cannot take (an
    /// index out of range, a count that disagrees with another entry's).
    pub fn invalid(&self, name: &str, found: String, expected: String) -> StateError {
        StateError::Mismatch {
            name: join(&self.prefix, name),
            found,
            expected,
        }
    }

    pub fn vec3s(&self, name: &str) -> Result<Vec<Vec3>, StateError> {
        let v = self.reals(name)?;
        if v.len() % 3 != 0 {
            let path = join(&self.prefix, name);
            return Err(Self::mismatch(
                path,
                &Values::F64(v),
                "a multiple of 3".into(),
            ));
        }
        Ok(v.chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect())
    }

    pub fn u64s(&self, name: &str) -> Result<Vec<u64>, StateError> {
        match self.get(name)? {
            (_, Values::U64(v)) => Ok(v.clone()),
            (path, v) => Err(Self::mismatch(path, v, "u64 values".into())),
        }
    }

    pub fn u64(&self, name: &str) -> Result<u64, StateError> {
        match self.u64s(name)?.as_slice() {
            [x] => Ok(*x),
            v => Err(Self::mismatch(
                join(&self.prefix, name),
                &Values::U64(v.to_vec()),
                "1 u64 value".into(),
            )),
        }
    }

    pub fn i64s(&self, name: &str) -> Result<Vec<i64>, StateError> {
        match self.get(name)? {
            (_, Values::I64(v)) => Ok(v.clone()),
            (path, v) => Err(Self::mismatch(path, v, "i64 values".into())),
        }
    }

    pub fn bytes(&self, name: &str) -> Result<Vec<u8>, StateError> {
        match self.get(name)? {
            (_, Values::U8(v)) => Ok(v.clone()),
            (path, v) => Err(Self::mismatch(path, v, "u8 values".into())),
        }
    }

    pub fn flag(&self, name: &str) -> Result<bool, StateError> {
        match self.bytes(name)?.as_slice() {
            [b] => Ok(*b != 0),
            v => Err(Self::mismatch(
                join(&self.prefix, name),
                &Values::U8(v.to_vec()),
                "1 u8 value".into(),
            )),
        }
    }

    /// A generator saved by [`Saver::rng`].
    pub fn rng(&self, name: &str) -> Result<ChaCha8Rng, StateError> {
        use rand::SeedableRng;
        let s = self.section(name);
        let seed: [u8; 32] = s.bytes("seed")?.try_into().map_err(|v: Vec<u8>| {
            Self::mismatch(
                join(&s.prefix, "seed"),
                &Values::U8(v),
                "32 u8 values".into(),
            )
        })?;
        let sp = s.u64s("stream_pos")?;
        let [stream, lo, hi] = sp[..] else {
            return Err(Self::mismatch(
                join(&s.prefix, "stream_pos"),
                &Values::U64(sp),
                "3 u64 values".into(),
            ));
        };
        let mut rng = ChaCha8Rng::from_seed(seed);
        rng.set_stream(stream);
        rng.set_word_pos(((hi as u128) << 64) | lo as u128);
        Ok(rng)
    }
}

/// A part whose state carries from one step to the next.
pub trait Persist {
    /// Puts everything the next step reads and cannot rebuild under `into`.
    fn save(&self, into: &mut Saver);
    /// Restores what [`Persist::save`] put, into a part freshly built from the same scene.
    fn restore(&mut self, from: &Restorer) -> Result<(), StateError>;
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    #[test]
    fn entries_come_back_as_saved() {
        let mut state = State::new();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let _: u64 = rng.random();
        {
            let mut s = state.section("sph");
            s.vec3s(
                "x",
                &[Vec3::new(1.0, 2.0, 3.0), Vec3::new(-0.5, 0.25, 1e-300)],
            );
            s.section("open").u64("emitted", 7);
            s.flag("on", true);
            s.rng("rng", &rng);
        }
        let r = state.read("sph");
        assert_eq!(r.vec3s("x").unwrap()[1], Vec3::new(-0.5, 0.25, 1e-300));
        assert_eq!(r.section("open").u64("emitted").unwrap(), 7);
        assert!(r.flag("on").unwrap());
        assert!(r.has("open") && !r.has("ope"));
        let mut back = r.rng("rng").unwrap();
        assert_eq!(back.random::<u64>(), rng.random::<u64>());
        assert_eq!(
            r.u64("x").unwrap_err(),
            StateError::Mismatch {
                name: "sph/x".into(),
                found: "6 f64 values".into(),
                expected: "u64 values".into()
            }
        );
        assert_eq!(
            r.real("y").unwrap_err(),
            StateError::Missing("sph/y".into())
        );
    }
}
