//! The power spectral density of a time series by Welch's method (P. D. Welch, "The use of
//! fast Fourier transform for the estimation of power spectra: a method based on time averaging
//! over short, modified periodograms", IEEE Trans. Audio Electroacoust. 15 (1967) 70–73): the
//! series is cut into segments that overlap by half, each has its mean removed and is tapered
//! by a Hann window, and their periodograms are averaged, trading frequency resolution for a
//! variance that falls with the number of segments.
//!
//! A run's `probes.csv` has a row per solver step, and the step follows the CFL rule, so the
//! samples are not evenly spaced; [`resample`] puts them on a uniform grid first.

use rustfft::num_complex::Complex;
use rustfft::FftPlanner;

use super::SpectrumError;
use crate::Real;

/// The fewest samples a segment may have.
const MIN_SEGMENT: usize = 8;
/// The number of segments the default segment length aims at (at least this many).
const TARGET_SEGMENTS: usize = 8;

/// How [`welch`] cuts and transforms the series.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WelchOptions {
    /// Samples per segment (at least 8); None: the largest power of two that still gives at
    /// least 8 half-overlapping segments. Longer segments resolve finer frequencies, with fewer
    /// segments to average.
    pub segment: Option<usize>,
    /// Zero-padding factor: each segment is transformed at `pad` times its length (1: none).
    /// The density is then sampled `pad` times finer between the same values, and Parseval's
    /// identity is unchanged; it makes the peak's interpolation nearly unbiased (for a sine
    /// five or more bins from zero, the log-parabola of a Hann peak is off by up to 0.016 of a
    /// bin at `pad = 1`, by under 0.002 at 2).
    pub pad: usize,
}

impl Default for WelchOptions {
    fn default() -> Self {
        Self {
            segment: None,
            pad: 1,
        }
    }
}

/// A one-sided power spectral density.
#[derive(Debug, Clone, PartialEq)]
pub struct Psd {
    /// The bins' frequencies, Hz: `k rate / (pad segment)` for k = 0 to half the transform.
    pub frequency: Vec<Real>,
    /// The density at each bin, (unit of the signal)² per Hz.
    pub density: Vec<Real>,
    /// The uniform sampling rate, Hz.
    pub rate: Real,
    /// Samples per segment, and the number of segments averaged.
    pub segment: usize,
    pub segments: usize,
}

/// The largest bin of a [`Psd`] (the zero frequency left out), refined between bins.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Peak {
    /// Hz: the vertex of the parabola through the logarithms of the density at the largest bin
    /// and its two neighbours (a Hann window's main lobe is close to a Gaussian, whose
    /// logarithm is a parabola).
    pub frequency: Real,
    /// The parabola's value at the vertex, as a density.
    pub density: Real,
    /// The largest bin itself.
    pub bin: usize,
}

impl Psd {
    /// The spacing of the bins, Hz.
    pub fn resolution(&self) -> Real {
        self.frequency.get(1).copied().unwrap_or(0.0)
    }

    /// The density integrated over frequency, sum of density x resolution: what Parseval's
    /// identity equates to the variance (see [`welch`]).
    pub fn integral(&self) -> Real {
        self.density.iter().sum::<Real>() * self.resolution()
    }

    /// The largest bin above zero frequency, refined; None when the density is zero there (a
    /// constant signal).
    pub fn peak(&self) -> Option<Peak> {
        let d = &self.density;
        let bin = (1..d.len()).fold(None, |best: Option<usize>, k| match best {
            Some(b) if d[b] >= d[k] => Some(b),
            _ => Some(k),
        })?;
        if d[bin] <= 0.0 {
            return None;
        }
        let df = self.resolution();
        let plain = Peak {
            frequency: bin as Real * df,
            density: d[bin],
            bin,
        };
        let Some(&right) = d.get(bin + 1) else {
            return Some(plain);
        };
        let left = d[bin - 1];
        if left <= 0.0 || right <= 0.0 {
            return Some(plain);
        }
        let (a, b, c) = (left.ln(), d[bin].ln(), right.ln());
        let curvature = a - 2.0 * b + c;
        if curvature >= 0.0 {
            return Some(plain);
        }
        let offset = (0.5 * (a - c) / curvature).clamp(-0.5, 0.5);
        Some(Peak {
            frequency: (bin as Real + offset) * df,
            density: (b - 0.25 * (a - c) * offset).exp(),
            bin,
        })
    }
}

/// Welch's PSD of `samples` taken evenly at `rate` Hz.
///
/// Segments of M samples start every M/2 (floored); samples after the last whole segment are
/// left out. Each segment x has its own mean removed and is tapered by the periodic Hann window
/// w_n = (1 - cos(2 pi n / M)) / 2, and transformed at N = pad M points (zero-padded). The
/// one-sided density at f_k = k rate / N is
///
/// P_k = c_k / (K rate S) sum over the K segments of |Y_k|², S = sum w_n², c_k = 2 but 1 at
/// k = 0 and at k = N/2,
///
/// so that, by Parseval's identity for the DFT, sum_k P_k rate / N equals exactly the mean over
/// the segments of sum w_n² (x_n - mean x)² / S: each segment's variance weighted by the
/// window. For a stationary signal that is its variance; a sine of A whose period divides the
/// segment gives A²/2 to round-off.
pub fn welch(samples: &[Real], rate: Real, options: &WelchOptions) -> Result<Psd, SpectrumError> {
    if !(rate.is_finite() && rate > 0.0) {
        return Err(SpectrumError::Invalid(format!(
            "the sampling rate must be positive, not {rate} Hz"
        )));
    }
    if let Some(index) = samples.iter().position(|v| !v.is_finite()) {
        return Err(SpectrumError::NotFinite {
            index,
            time: index as Real / rate,
            value: samples[index],
        });
    }
    if options.pad == 0 {
        return Err(SpectrumError::Invalid(
            "the zero-padding factor must be at least 1".into(),
        ));
    }
    let n = samples.len();
    let m = match options.segment {
        Some(m) if m < MIN_SEGMENT => {
            return Err(SpectrumError::Invalid(format!(
                "a segment of {m} samples: at least {MIN_SEGMENT}"
            )))
        }
        Some(m) if m > n => {
            return Err(SpectrumError::TooFewSamples { have: n, need: m });
        }
        Some(m) => m,
        None => default_segment(n).ok_or(SpectrumError::TooFewSamples {
            have: n,
            need: MIN_SEGMENT * (TARGET_SEGMENTS + 1) / 2,
        })?,
    };
    let hop = m / 2;
    let count = (n - m) / hop + 1;
    let window: Vec<Real> = (0..m)
        .map(|i| 0.5 * (1.0 - (2.0 * std::f64::consts::PI * i as Real / m as Real).cos()))
        .collect();
    let s: Real = window.iter().map(|w| w * w).sum();
    let size = options.pad * m;
    let fft = FftPlanner::<Real>::new().plan_fft_forward(size);
    let bins = size / 2 + 1;
    let mut sum = vec![0.0; bins];
    let mut buffer = vec![Complex::new(0.0, 0.0); size];
    for segment in 0..count {
        let x = &samples[segment * hop..segment * hop + m];
        let mean = x.iter().sum::<Real>() / m as Real;
        buffer.fill(Complex::new(0.0, 0.0));
        for ((b, v), w) in buffer.iter_mut().zip(x).zip(&window) {
            b.re = (v - mean) * w;
        }
        fft.process(&mut buffer);
        for (acc, y) in sum.iter_mut().zip(&buffer) {
            *acc += y.norm_sqr();
        }
    }
    let scale = 1.0 / (count as Real * rate * s);
    let density = sum
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let one_sided = if k == 0 || 2 * k == size { 1.0 } else { 2.0 };
            one_sided * scale * p
        })
        .collect();
    Ok(Psd {
        frequency: (0..bins).map(|k| k as Real * rate / size as Real).collect(),
        density,
        rate,
        segment: m,
        segments: count,
    })
}

/// The largest power of two (at least [`MIN_SEGMENT`]) that gives at least
/// [`TARGET_SEGMENTS`] half-overlapping segments of `n` samples: K segments of M span
/// M (K + 1) / 2 samples.
fn default_segment(n: usize) -> Option<usize> {
    let longest = 2 * n / (TARGET_SEGMENTS + 1);
    (longest >= MIN_SEGMENT).then(|| 1 << longest.ilog2())
}

/// `values` at the times `time` (increasing, any spacing) resampled linearly onto the uniform
/// grid t_0 + j / rate that fits in [t_0, t_last], at `rate` Hz or, when None, at one over the
/// median step. Returns the rate and the samples.
///
/// Linear interpolation keeps a component much slower than the steps as it is; it damps one
/// near the steps' own Nyquist frequency, which the CFL step puts far above the flow's
/// frequencies of interest. The median rather than the mean step: a few steps shortened to
/// land on frame times do not move it.
pub fn resample(
    time: &[Real],
    values: &[Real],
    rate: Option<Real>,
) -> Result<(Real, Vec<Real>), SpectrumError> {
    if time.len() != values.len() {
        return Err(SpectrumError::LengthMismatch {
            times: time.len(),
            values: values.len(),
        });
    }
    if time.len() < 2 {
        return Err(SpectrumError::TooFewSamples {
            have: time.len(),
            need: 2,
        });
    }
    let bad = |i: usize| !(time[i].is_finite() && values[i].is_finite());
    if let Some(index) = (0..time.len()).find(|&i| bad(i)) {
        return Err(SpectrumError::NotFinite {
            index,
            time: time[index],
            value: values[index],
        });
    }
    if let Some(index) = (1..time.len()).find(|&i| time[i] <= time[i - 1]) {
        return Err(SpectrumError::NotIncreasing {
            index,
            before: time[index - 1],
            after: time[index],
        });
    }
    let rate = match rate {
        Some(r) if r.is_finite() && r > 0.0 => r,
        Some(r) => {
            return Err(SpectrumError::Invalid(format!(
                "the sampling rate must be positive, not {r} Hz"
            )))
        }
        None => {
            let mut steps: Vec<Real> = time.windows(2).map(|w| w[1] - w[0]).collect();
            steps.sort_by(Real::total_cmp);
            1.0 / steps[steps.len() / 2]
        }
    };
    let (t0, span) = (time[0], time[time.len() - 1] - time[0]);
    // The grid's last point may sit on t_last within round-off.
    let count = (span * rate * (1.0 + 1e-12)).floor() as usize + 1;
    let mut i = 0;
    let samples = (0..count)
        .map(|j| {
            let t = (t0 + j as Real / rate).min(time[time.len() - 1]);
            while i + 2 < time.len() && time[i + 1] < t {
                i += 1;
            }
            let f = ((t - time[i]) / (time[i + 1] - time[i])).clamp(0.0, 1.0);
            values[i] + f * (values[i + 1] - values[i])
        })
        .collect();
    Ok((rate, samples))
}

/// Welch's PSD of a series sampled at the increasing `time`: [`resample`] at `rate` (None: the
/// median step), then [`welch`].
pub fn welch_series(
    time: &[Real],
    values: &[Real],
    rate: Option<Real>,
    options: &WelchOptions,
) -> Result<Psd, SpectrumError> {
    let (rate, samples) = resample(time, values, rate)?;
    welch(&samples, rate, options)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn the_default_segment_is_a_power_of_two_with_at_least_eight_segments() {
        for n in [36, 100, 1000, 4096, 100_000] {
            let m = default_segment(n).expect("long enough");
            assert!(m.is_power_of_two(), "{n}: {m}");
            let segments = (n - m) / (m / 2) + 1;
            assert!((8..17).contains(&segments), "{n}: {m}, {segments}");
        }
        assert_eq!(default_segment(35), None);
    }

    #[test]
    fn resampling_a_uniform_series_returns_it() {
        let t: Vec<Real> = (0..50).map(|i| 0.1 * i as Real).collect();
        let v: Vec<Real> = t.iter().map(|t| (3.0 * t).sin()).collect();
        let (rate, u) = resample(&t, &v, None).expect("uniform");
        assert!((rate - 10.0).abs() < 1e-9, "{rate}");
        assert_eq!(u.len(), v.len());
        let worst = u
            .iter()
            .zip(&v)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, Real::max);
        assert!(worst < 1e-12, "{worst}");
    }

    #[test]
    fn resampling_is_linear_between_samples() {
        // A straight line is kept exactly by linear interpolation, whatever the spacing.
        let t = [0.0, 0.1, 0.35, 0.4, 0.9, 1.0];
        let v: Vec<Real> = t.iter().map(|t| 2.0 - 3.0 * t).collect();
        let (rate, u) = resample(&t, &v, Some(20.0)).expect("increasing");
        assert_eq!(rate, 20.0);
        assert_eq!(u.len(), 21, "0 to 1 s at 20 Hz");
        for (j, u) in u.iter().enumerate() {
            assert!(
                (u - (2.0 - 3.0 * j as Real / 20.0)).abs() < 1e-12,
                "{j}: {u}"
            );
        }
    }

    #[test]
    fn bad_series_are_refused_with_what_is_wrong() {
        let t = [0.0, 0.1, 0.1, 0.2];
        let v = [0.0; 4];
        assert_eq!(
            resample(&t, &v, None),
            Err(SpectrumError::NotIncreasing {
                index: 2,
                before: 0.1,
                after: 0.1
            })
        );
        assert!(matches!(
            resample(&t[..3], &v, None),
            Err(SpectrumError::LengthMismatch { .. })
        ));
        assert!(matches!(
            welch(&[0.0; 20], 1.0, &WelchOptions::default()),
            Err(SpectrumError::TooFewSamples { have: 20, .. })
        ));
        let options = WelchOptions {
            segment: Some(4),
            pad: 1,
        };
        assert!(matches!(
            welch(&[0.0; 64], 1.0, &options),
            Err(SpectrumError::Invalid(_))
        ));
    }

    /// Parseval, exactly as documented: the integral is the mean of the segments' window-weighted
    /// variances, for any signal, padding and segment length.
    #[test]
    fn the_density_integrates_to_the_window_weighted_variance() {
        let x: Vec<Real> = (0..1000)
            .map(|i| {
                let t = i as Real;
                (0.37 * t).sin() + 0.2 * (1.3 * t).cos() + 0.001 * t + ((i * 7919) % 13) as Real
            })
            .collect();
        for (segment, pad) in [(None, 1), (Some(200), 1), (Some(127), 4)] {
            let psd = welch(&x, 3.0, &WelchOptions { segment, pad }).expect("long enough");
            let m = psd.segment;
            let w: Vec<Real> = (0..m)
                .map(|i| (PI * i as Real / m as Real).sin().powi(2))
                .collect();
            let s: Real = w.iter().map(|w| w * w).sum();
            let expected = (0..psd.segments)
                .map(|k| {
                    let x = &x[k * (m / 2)..k * (m / 2) + m];
                    let mean = x.iter().sum::<Real>() / m as Real;
                    x.iter()
                        .zip(&w)
                        .map(|(x, w)| (w * (x - mean)).powi(2))
                        .sum::<Real>()
                        / s
                })
                .sum::<Real>()
                / psd.segments as Real;
            let got = psd.integral();
            assert!(
                ((got - expected) / expected).abs() < 1e-10,
                "{segment:?}, {pad}: {got} against {expected}"
            );
        }
    }

    /// A sine of 16 samples a period in segments of 256: a whole number of periods, so the
    /// window-weighted variance is A²/2 exactly and the peak falls on its bin.
    #[test]
    fn a_bin_centred_sine_has_its_variance_and_its_frequency() {
        let (a, rate) = (1.7, 64.0);
        let x: Vec<Real> = (0..4096)
            .map(|i| a * (2.0 * PI * i as Real / 16.0 + 0.3).sin())
            .collect();
        let options = WelchOptions {
            segment: Some(256),
            pad: 1,
        };
        let psd = welch(&x, rate, &options).expect("long enough");
        assert!(((psd.integral() - 0.5 * a * a) / (0.5 * a * a)).abs() < 1e-10);
        let peak = psd.peak().expect("a peak");
        assert_eq!(peak.bin, 16);
        assert!(
            (peak.frequency - rate / 16.0).abs() < 1e-9 * rate,
            "{peak:?}"
        );
    }
}
