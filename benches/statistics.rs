//! `cargo bench --bench statistics`: the statistics stage's share of a step on the smoke plume
//! at 128^3 cells and on the dam break of about 100k particles (target: at most 5 %).

use eddy::bench::statistics::{measure, shipped};

fn main() -> Result<(), eddy::pipeline::RunError> {
    let plume = shipped(
        "smoke_plume.toml",
        &["grid.resolution=[128,128,128]".into()],
    )?;
    let dam = shipped("bench_dam_break.toml", &[])?;
    println!("| scene | cells or particles | step, s | statistics, s | share |");
    println!("|---|---|---|---|---|");
    for (scene, warmup, steps) in [(plume, 5, 10), (dam, 20, 40)] {
        let c = measure(&scene, warmup, steps)?;
        println!(
            "| {} | {} | {:.4} | {:.5} | {:.1} % |",
            c.scene,
            c.size,
            c.step_seconds,
            c.statistics_seconds,
            100.0 * c.share()
        );
    }
    Ok(())
}
