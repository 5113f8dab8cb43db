//! `cargo bench --bench sph`: the SPH step-time benchmark at the 25k and 100k sizes (the same
//! measurement as `eddy bench`, which also takes other sizes and solvers).

fn main() -> Result<(), eddy::pipeline::RunError> {
    eddy::bench::run(&eddy::bench::BenchOptions {
        sizes: vec![25_000, 100_000],
        solvers: vec!["dfsph".into(), "iisph".into()],
        warmup: 5,
        steps: 10,
        refinements: Vec::new(),
        mcvsph_error: false,
        passes: false,
        floors: true,
        threads: Vec::new(),
    })
}
