//! The refinement metrics columns and `eddy compare`'s figure, on short runs of the sloshing
//! tank.

use eddy::io::plot::{compare, RunSeries};
use eddy::pipeline::{run, RunOptions};
use std::path::Path;

/// Two short runs write the new columns consistently (total = linear + rotational + potential
/// energy; vorticity mean <= max; enstrophy >= 0; refinement time only with a refinement), and
/// `compare` draws them into one PNG, or one SVG.
#[test]
fn metrics_columns_and_compare_figure() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/refine_sloshing.toml");
    let mut runs = Vec::new();
    for method in ["none", "micropolar"] {
        let out = dir.path().join(method);
        let options = RunOptions {
            out: Some(out.clone()),
            overrides: vec![
                format!("refinement.method=\"{method}\""),
                "time.steps=40".into(),
            ],
            ..RunOptions::default()
        };
        run(&scene, &options).expect("short run");
        let series = RunSeries::read(&out).expect("metrics.csv");
        let col = |name: &str| series.column(name).expect(name);
        let (ke, rot, pe, total) = (
            col("kinetic_energy"),
            col("rotational_energy"),
            col("potential_energy"),
            col("total_energy"),
        );
        assert_eq!(ke.len(), 40);
        for i in 0..ke.len() {
            assert!((ke[i] + rot[i] + pe[i] - total[i]).abs() <= 1e-9 * total[i].abs());
        }
        let (mean, max, ens, secs) = (
            col("vorticity_mean"),
            col("vorticity_max"),
            col("enstrophy"),
            col("refinement_seconds"),
        );
        assert!(mean.iter().zip(&max).all(|(a, b)| a <= b));
        assert!(ens.iter().all(|e| *e >= 0.0) && max.iter().any(|m| *m > 0.0));
        if method == "none" {
            assert!(secs.iter().all(|s| *s == 0.0) && rot.iter().all(|r| *r == 0.0));
        } else {
            assert!(secs.iter().all(|s| *s > 0.0) && rot.iter().any(|r| *r > 0.0));
        }
        runs.push(series);
    }
    let png = dir.path().join("compare.png");
    compare(&runs, &png).expect("plot");
    let bytes = std::fs::read(&png).expect("png written");
    assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n") && bytes.len() > 10_000);
    // The same figure as an SVG for a paper: vector paths, and its titles and labels as text.
    let svg = dir.path().join("compare.svg");
    compare(&runs, &svg).expect("svg plot");
    let text = std::fs::read_to_string(&svg).expect("svg written");
    assert!(text.contains("<svg") && text.trim_end().ends_with("</svg>"));
    for label in ["total energy (J)", "time (s)", "micropolar"] {
        assert!(text.contains(label), "the SVG lacks {label:?}");
    }
    assert!(
        text.matches("<polyline").count() >= 6,
        "a curve per run and panel"
    );
    assert!(compare(&[], &dir.path().join("none.png")).is_err());
}
