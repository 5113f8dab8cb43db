//! Finished directions of a run in progress, one small file each under `<out>.parts/`, written
//! atomically: a run killed at any moment loses at most the direction being computed, and
//! `--resume` picks the finished ones up.
//!
//! A part holds `EDDYABL1`, the run's fingerprint (u64 length + bytes), the point count P (u64)
//! and P x 3 f64, all little-endian.

use std::io::Read;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use eddy::abl::MotionKind;
use eddy::Vec3;

use crate::run::Job;

const MAGIC: &[u8; 8] = b"EDDYABL1";

/// The parts folder of the output `out`.
pub fn folder(out: &Path) -> PathBuf {
    let mut name = out.file_name().unwrap_or_default().to_os_string();
    name.push(".parts");
    out.with_file_name(name)
}

fn file_name(job: &Job) -> String {
    format!(
        "{}_{:03}_{:03}.bin",
        job.kind.name(),
        job.polar,
        job.azimuth
    )
}

/// Writes the values of a finished direction.
pub fn write(dir: &Path, fingerprint: &str, job: &Job, values: &[Vec3]) -> anyhow::Result<()> {
    let path = dir.join(file_name(job));
    eddy::io::write_atomic(&path, |out| {
        out.write_all(MAGIC)?;
        out.write_all(&(fingerprint.len() as u64).to_le_bytes())?;
        out.write_all(fingerprint.as_bytes())?;
        out.write_all(&(values.len() as u64).to_le_bytes())?;
        for v in values {
            for c in v.iter() {
                out.write_all(&c.to_le_bytes())?;
            }
        }
        Ok(())
    })?;
    Ok(())
}

/// Every part in `dir` as (job, values), checked against the run's fingerprint and point
/// count. Files that are not parts (an interrupted write's temporary) are skipped.
pub fn read_all(
    dir: &Path,
    fingerprint: &str,
    points: usize,
) -> anyhow::Result<Vec<(Job, Vec<Vec3>)>> {
    let mut out = Vec::new();
    if !dir.exists() {
        return Ok(out);
    }
    for entry in std::fs::read_dir(dir).with_context(|| format!("listing {}", dir.display()))? {
        let path = entry?.path();
        let Some(job) = path
            .file_name()
            .and_then(|n| n.to_str())
            .and_then(parse_name)
        else {
            continue;
        };
        let values = read_one(&path, fingerprint, points)
            .with_context(|| format!("reading finished direction {}", path.display()))?;
        out.push((job, values));
    }
    out.sort_by_key(|(j, _)| (j.kind.name(), j.polar, j.azimuth));
    Ok(out)
}

fn parse_name(name: &str) -> Option<Job> {
    let stem = name.strip_suffix(".bin")?;
    let mut it = stem.split('_');
    let kind = match it.next()? {
        "translation" => MotionKind::Translation,
        "rotation" => MotionKind::Rotation,
        _ => return None,
    };
    let polar = it.next()?.parse().ok()?;
    let azimuth = it.next()?.parse().ok()?;
    it.next().is_none().then_some(Job {
        kind,
        polar,
        azimuth,
    })
}

fn read_one(path: &Path, fingerprint: &str, points: usize) -> anyhow::Result<Vec<Vec3>> {
    let mut bytes = Vec::new();
    std::fs::File::open(path)?.read_to_end(&mut bytes)?;
    let take = |at: &mut usize, n: usize| -> anyhow::Result<&[u8]> {
        let s = bytes.get(*at..*at + n).context("the file is short")?;
        *at += n;
        Ok(s)
    };
    let u64_at = |at: &mut usize| -> anyhow::Result<u64> {
        Ok(u64::from_le_bytes(take(at, 8)?.try_into()?))
    };
    let mut at = 0;
    if take(&mut at, 8)? != MAGIC {
        bail!("not a part file");
    }
    let len = u64_at(&mut at)? as usize;
    if take(&mut at, len)? != fingerprint.as_bytes() {
        bail!(
            "it was computed with other settings (fingerprint differs): delete {} to start over",
            path.parent().unwrap_or(path).display()
        );
    }
    if u64_at(&mut at)? as usize != points {
        bail!("it holds another number of boundary points");
    }
    let data = take(&mut at, points * 24)?;
    if at != bytes.len() {
        bail!("the file is too long");
    }
    Ok(data
        .chunks_exact(24)
        .map(|c| {
            let f = |k: usize| f64::from_le_bytes(c[8 * k..8 * k + 8].try_into().expect("8 bytes"));
            Vec3::new(f(0), f(1), f(2))
        })
        .collect())
}
