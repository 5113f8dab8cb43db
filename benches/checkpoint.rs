//! `cargo bench --bench checkpoint`: a checkpoint's size and write time against one frame's, on
//! the smoke plume at 128^3 cells and on the dam break of about 100k particles.

use std::time::Instant;

use eddy::bench::statistics::shipped;
use eddy::pipeline::{Run, RunError, RunOptions};

/// Bytes of the files in `dir` whose names `keep` accepts.
fn bytes(dir: &std::path::Path, keep: impl Fn(&str) -> bool) -> u64 {
    std::fs::read_dir(dir)
        .map(|d| {
            d.flatten()
                .filter(|e| keep(&e.file_name().to_string_lossy()))
                .filter_map(|e| e.metadata().ok())
                .map(|m| m.len())
                .sum()
        })
        .unwrap_or(0)
}

fn is_frame(name: &str) -> bool {
    [".vtp", ".vti", ".vtu"].iter().any(|e| name.ends_with(e))
}

fn main() -> Result<(), RunError> {
    let plume = shipped(
        "smoke_plume.toml",
        &["grid.resolution=[128,128,128]".into()],
    )?;
    let dam = shipped("bench_dam_break.toml", &["output.vtk=true".into()])?;
    println!("| scene | cells or particles | checkpoint, MiB | write, s | frame (VTK), MiB | frame write, s |");
    println!("|---|---|---|---|---|---|");
    for scene in [plume, dam] {
        let dir = tempfile::tempdir().map_err(|e| RunError::Unsupported(e.to_string()))?;
        let options = RunOptions {
            out: Some(dir.path().to_path_buf()),
            ..RunOptions::default()
        };
        let mut run = Run::start(&scene, &options)?;
        for _ in 0..3 {
            run.advance(None)?;
        }
        let before = bytes(dir.path(), is_frame);
        let started = Instant::now();
        run.pipeline.outputs.write(&run.pipeline.sim)?;
        let frame = started.elapsed().as_secs_f64();
        let frames = bytes(dir.path(), is_frame) - before;
        let started = Instant::now();
        let path = run.checkpoint()?;
        let write = started.elapsed().as_secs_f64();
        let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
        let sim = &run.pipeline.sim;
        let size = sim.grid.as_ref().map_or_else(
            || sim.sph.as_ref().map_or(0, |s| s.fluid.len()),
            |g| g.mac.cell_count(),
        );
        println!(
            "| {} | {size} | {:.1} | {write:.3} | {:.1} | {frame:.3} |",
            scene.name,
            mib(std::fs::metadata(&path).map_or(0, |m| m.len())),
            mib(frames),
        );
    }
    Ok(())
}
