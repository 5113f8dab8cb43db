//! `cargo bench --bench grid`: the MAC-grid benchmarks (smoke plume step time at 64^3 and
//! 128^3, Taylor–Green error against run time); `eddy bench-grid` takes other sizes.

fn main() -> Result<(), eddy::grid::GridError> {
    eddy::bench::grid::run(&eddy::bench::grid::GridBenchOptions {
        plume: vec![64, 128],
        warmup: 10,
        steps: 10,
        taylor_green: vec![32, 64, 128],
    })
}
