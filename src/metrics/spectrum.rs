//! Spectra: the power spectral density of a probe's time series (Welch's method) and the
//! shell-averaged kinetic-energy spectrum E(k) of a grid's velocity field. A wake's shedding
//! frequency is then the peak of a spectrum rather than a count of zero crossings, and a
//! turbulent field's energy cascade can be read against Kolmogorov's k^(-5/3).
//!
//! Both are normalised so that Parseval's identity holds in a form the item's doc states
//! exactly: the PSD integrates to the (window-weighted) variance, E(k) to half the mean square
//! velocity. The FFTs are rustfft's.

mod shells;
mod welch;

pub use shells::{energy_spectrum, EnergySpectrum, Mean, ShellOptions};
pub use welch::{resample, welch, welch_series, Peak, Psd, WelchOptions};

/// Why a spectrum cannot be computed from the data given.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpectrumError {
    /// Fewer samples than the method needs.
    #[error("{have} samples, a spectrum needs at least {need}")]
    TooFewSamples { have: usize, need: usize },
    /// Times and values of different lengths.
    #[error("{times} times for {values} values")]
    LengthMismatch { times: usize, values: usize },
    /// A time or value that is not finite.
    #[error("sample {index} is not finite (time {time}, value {value})")]
    NotFinite {
        index: usize,
        time: crate::Real,
        value: crate::Real,
    },
    /// Times that do not increase.
    #[error("time does not increase at sample {index}: {before} then {after}")]
    NotIncreasing {
        index: usize,
        before: crate::Real,
        after: crate::Real,
    },
    /// A parameter out of its range (segment length, rate, padding, cell size, shapes).
    #[error("{0}")]
    Invalid(String),
}
