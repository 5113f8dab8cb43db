//! The precomputation over MPI ranks (`--mpi`, cargo feature `mpi`): rank 0 hands out
//! directions one at a time, so a slow direction does not hold the others back, and is the only
//! process that reads or writes the output; the other ranks compute the directions they are
//! given and send back their values. Rank 0 computes directions too, on a second thread (only
//! its main thread calls MPI), so one rank is the threaded run with one worker.
//!
//! Every direction is computed on one thread by [`compute_job`] wherever it runs and its values
//! travel as f64, so the database is the single-process one bit for bit.
//!
//! Messages (tags): a rank sends READY once, then RESULT (the seconds it took, then the P x 3
//! values) or FAILED (the error, UTF-8) per direction; rank 0 answers each with JOB (kind,
//! polar, azimuth as u64) or STOP.

use std::sync::mpsc::{self, TryRecvError};
use std::time::{Duration, Instant};

use anyhow::{bail, Context};
use eddy::abl::MotionKind;
use eddy::Vec3;
use mpi::point_to_point::{Destination, MatchedReceiveVec, Source};
use mpi::topology::{Communicator, SimpleCommunicator};
use mpi::Tag;

use crate::run::{compute_job, Engine, Finished, Job, JobQueue};
use crate::solve::Surface;
use crate::spec::ObstacleSpec;

const READY: Tag = 1;
const RESULT: Tag = 2;
const FAILED: Tag = 3;
const JOB: Tag = 4;
const STOP: Tag = 5;

/// How long rank 0 waits before looking for messages again when none came: far below a
/// direction's seconds, and enough to keep its main thread off the processor.
const POLL: Duration = Duration::from_millis(1);

/// Rank 0's side: an [`Engine`] over every rank of `world`.
pub struct Root<'a> {
    pub world: &'a SimpleCommunicator,
}

impl Engine for Root<'_> {
    fn compute(
        &mut self,
        spec: &ObstacleSpec,
        surface: &Surface,
        todo: &[Job],
        deliver: &mut dyn FnMut(Finished) -> bool,
    ) {
        let world = self.world;
        let queue = &JobQueue::new(todo);
        let (tx, rx) = mpsc::channel::<Finished>();
        std::thread::scope(|scope| {
            scope.spawn(move || queue.work(spec, surface, &tx));
            let mut in_flight: Vec<Option<Job>> = vec![None; world.size() as usize];
            let mut remote = world.size() - 1;
            let mut local = true;
            while remote > 0 || local {
                match rx.try_recv() {
                    Ok(finished) => {
                        if !deliver(finished) {
                            queue.stop();
                        }
                        continue;
                    }
                    Err(TryRecvError::Disconnected) => local = false,
                    Err(TryRecvError::Empty) => {}
                }
                let Some(probed) = world.any_process().immediate_matched_probe() else {
                    std::thread::sleep(POLL);
                    continue;
                };
                let from = probed.1.source_rank();
                let job = in_flight[from as usize].take();
                let finished = match (probed.1.tag(), job) {
                    (RESULT, Some(job)) => {
                        let (v, _) = probed.matched_receive_vec::<f64>();
                        Some((job, values(&v, surface.points.len()), v[0]))
                    }
                    (FAILED, Some(job)) => {
                        let (text, _) = probed.matched_receive_vec::<u8>();
                        let e = anyhow::anyhow!("{}", String::from_utf8_lossy(&text));
                        Some((job, Err(e.context(format!("on rank {from}"))), 0.0))
                    }
                    _ => {
                        probed.matched_receive_vec::<u8>();
                        None
                    }
                };
                if let Some(finished) = finished {
                    if !deliver(finished) {
                        queue.stop();
                    }
                }
                let to = world.process_at_rank(from);
                match queue.take() {
                    Some(job) => {
                        let kind = u64::from(job.kind == MotionKind::Rotation);
                        to.send_with_tag(&[kind, job.polar as u64, job.azimuth as u64][..], JOB);
                        in_flight[from as usize] = Some(job);
                    }
                    None => {
                        to.send_with_tag(&[0u8][..], STOP);
                        remote -= 1;
                    }
                }
            }
        });
    }
}

/// The values of a RESULT message (its first entry is the seconds), checked against the
/// point count.
fn values(message: &[f64], points: usize) -> anyhow::Result<Vec<Vec3>> {
    let values = message.get(1..).unwrap_or_default();
    if values.len() != points * 3 {
        bail!(
            "a rank sent {} values for {points} boundary points: were all ranks started on the \
             same obstacle file and overrides?",
            values.len()
        );
    }
    Ok(values
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect())
}

/// A rank other than 0: computes the directions rank 0 sends until it says stop.
pub fn serve(spec: &ObstacleSpec, world: &SimpleCommunicator) -> anyhow::Result<()> {
    let surface = Surface::of(spec)?;
    let root = world.process_at_rank(0);
    root.send_with_tag(&[0u8][..], READY);
    loop {
        let probed = root.matched_probe();
        match probed.1.tag() {
            JOB => {
                let (v, _) = probed.matched_receive_vec::<u64>();
                let job = job(&v).context("rank 0 sent a malformed job")?;
                let started = Instant::now();
                match compute_job(spec, &surface, &job) {
                    Ok(values) => {
                        let mut out = Vec::with_capacity(1 + 3 * values.len());
                        out.push(started.elapsed().as_secs_f64());
                        out.extend(values.iter().flat_map(|v| v.iter().copied()));
                        root.send_with_tag(&out[..], RESULT);
                    }
                    Err(e) => root.send_with_tag(format!("{e:#}").as_bytes(), FAILED),
                }
            }
            STOP => {
                probed.matched_receive_vec::<u8>();
                return Ok(());
            }
            tag => bail!("rank 0 sent a message with unknown tag {tag}"),
        }
    }
}

fn job(v: &[u64]) -> Option<Job> {
    let &[kind, polar, azimuth] = v else {
        return None;
    };
    let kind = *MotionKind::ALL.get(kind as usize)?;
    Some(Job {
        kind,
        polar: polar as usize,
        azimuth: azimuth as usize,
    })
}
