//! The interval a number must lie in, as the scene's validation and the refinement methods'
//! parameters declare it ([`Interval`]), and how messages print a number ([`Number`]): one
//! type, so that a range reads the same in an error, in the scene reference and in a
//! registered method's keys.

use std::fmt;

use crate::Real;

/// A number as a person reads it in a message: plain in the usual range, in exponent form when
/// very small or very large (`1e-308`, not 308 zeros).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Number(pub Real);

impl fmt::Display for Number {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        if v != 0.0 && v.is_finite() && !(1e-4..1e16).contains(&v.abs()) {
            write!(f, "{v:e}")
        } else {
            write!(f, "{v}")
        }
    }
}

/// One end of an interval.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Bound {
    Open(Real),
    Closed(Real),
    Unbounded,
}

/// An allowed range of a number, with an optional note on where its ends come from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval<'a> {
    lo: Bound,
    hi: Bound,
    note: Option<&'a str>,
    /// A count, whose closed range reads "2 to 8" (or "1 or 2").
    whole: bool,
}

impl<'a> Interval<'a> {
    const fn new(lo: Bound, hi: Bound) -> Self {
        Self {
            lo,
            hi,
            note: None,
            whole: false,
        }
    }
    pub const fn any() -> Self {
        Self::new(Bound::Unbounded, Bound::Unbounded)
    }
    pub const fn gt(lo: Real) -> Self {
        Self::new(Bound::Open(lo), Bound::Unbounded)
    }
    pub const fn ge(lo: Real) -> Self {
        Self::new(Bound::Closed(lo), Bound::Unbounded)
    }
    pub const fn le(hi: Real) -> Self {
        Self::new(Bound::Unbounded, Bound::Closed(hi))
    }
    pub const fn open_closed(lo: Real, hi: Real) -> Self {
        Self::new(Bound::Open(lo), Bound::Closed(hi))
    }
    pub const fn closed(lo: Real, hi: Real) -> Self {
        Self::new(Bound::Closed(lo), Bound::Closed(hi))
    }
    pub const fn open(lo: Real, hi: Real) -> Self {
        Self::new(Bound::Open(lo), Bound::Open(hi))
    }
    pub const fn closed_open(lo: Real, hi: Real) -> Self {
        Self::new(Bound::Closed(lo), Bound::Open(hi))
    }
    /// Says where a bound comes from, e.g. "`domain.min[0]`".
    pub const fn noted(self, note: &'a str) -> Self {
        Self {
            note: Some(note),
            ..self
        }
    }
    /// A count, whose closed range reads "2 to 8" (or "1 or 2").
    pub const fn whole(self) -> Self {
        Self {
            whole: true,
            ..self
        }
    }

    pub fn contains(&self, v: Real) -> bool {
        let above = match self.lo {
            Bound::Open(lo) => v > lo,
            Bound::Closed(lo) => v >= lo,
            Bound::Unbounded => true,
        };
        let below = match self.hi {
            Bound::Open(hi) => v < hi,
            Bound::Closed(hi) => v <= hi,
            Bound::Unbounded => true,
        };
        above && below
    }

    /// The allowed range in words: `(0, 1]`, `> 0`, `a finite number >= 0`, `2 to 8`.
    pub fn describe(&self, say_finite: bool) -> String {
        let range = match (self.lo, self.hi) {
            (Bound::Unbounded, Bound::Unbounded) => String::new(),
            (Bound::Open(lo), Bound::Unbounded) => format!("> {}", Number(lo)),
            (Bound::Closed(lo), Bound::Unbounded) => format!(">= {}", Number(lo)),
            (Bound::Unbounded, Bound::Open(hi)) => format!("< {}", Number(hi)),
            (Bound::Unbounded, Bound::Closed(hi)) => format!("<= {}", Number(hi)),
            (Bound::Closed(a), Bound::Closed(b)) if self.whole => {
                let join = if b == a + 1.0 { "or" } else { "to" };
                format!("{} {join} {}", Number(a), Number(b))
            }
            (lo, hi) => {
                let (open, a) = match lo {
                    Bound::Open(a) => ('(', a),
                    Bound::Closed(a) => ('[', a),
                    Bound::Unbounded => ('(', Real::NEG_INFINITY),
                };
                let (close, b) = match hi {
                    Bound::Open(b) => (')', b),
                    Bound::Closed(b) => (']', b),
                    Bound::Unbounded => (')', Real::INFINITY),
                };
                format!("{open}{}, {}{close}", Number(a), Number(b))
            }
        };
        let mut out = match (say_finite || range.is_empty(), range.is_empty()) {
            (true, true) => "a finite number".to_owned(),
            (true, false) => format!("a finite number {}", in_words(&range)),
            (false, _) => range,
        };
        if let Some(note) = self.note {
            out.push_str(&format!(" ({note})"));
        }
        out
    }
}

/// "in [a, b]" for an interval, the comparison itself otherwise.
fn in_words(range: &str) -> String {
    if range.starts_with(['(', '[']) {
        format!("in {range}")
    } else {
        range.to_owned()
    }
}
