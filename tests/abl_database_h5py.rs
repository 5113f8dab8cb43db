//! A boundary-layer database as a researcher reads it, with h5py: the attributes, shapes and
//! types the format documents, and values at known places against what eddy wrote. Its own
//! test binary: a Python child must not inherit another test's open HDF5 file (and its lock).

mod common;

use eddy::abl::{AblData, MotionKind, ABL_FORMAT, ABL_FORMAT_VERSION};
use eddy::Real;

const H5PY_LAYOUT: &str = r#"
import json, math, sys
import h5py, numpy as np
path, expected = sys.argv[1], json.loads(sys.argv[2])
f = h5py.File(path, "r")
assert f.attrs["format"] == expected["format"], f.attrs["format"]
assert "1/s per m/s" in f.attrs["units"]
assert f.attrs["obstacle"] == "sphere"
assert int(f.attrs["format_version"]) == expected["version"]
assert float(f.attrs["beta"]) == expected["beta"]
points = expected["points"]
for name in ("points", "normals"):
    assert f[name].dtype == np.float64 and f[name].shape == (points, 3), name
assert list(f["points"][1]) == expected["point_1"]
polar, azimuth = expected["polar"], expected["azimuth"]
for kind in expected["kinds"]:
    g = f[kind]
    assert (int(g.attrs["polar_samples"]), int(g.attrs["azimuth_samples"])) == (polar, azimuth)
    angles = g["polar_angles"][:]
    assert angles.shape == (polar,) and angles[0] == 0.0 and angles[-1] == math.pi
    assert g["azimuth_angles"].shape == (azimuth,)
    rows = polar * azimuth
    assert g["directions"].dtype == np.float64 and g["directions"].shape == (rows, 3)
    row = expected["row"]
    assert list(g["directions"][row]) == expected["direction"], kind
    omega = g["omega"]
    assert omega.dtype == np.float64 and omega.shape == (rows, points, 3)
    assert list(omega[row, 4]) == expected["omega"][kind], kind
    assert g["complete"].dtype == np.uint8 and np.all(g["complete"][:] == 1)
print("ok")
"#;

fn list(v: &[Real]) -> String {
    let items: Vec<String> = v.iter().map(|x| format!("{x:?}")).collect();
    format!("[{}]", items.join(", "))
}

#[test]
fn layout_is_as_documented_for_h5py() {
    let Some(python) = common::python_with(&["h5py", "numpy"]) else {
        return;
    };
    let tmp = tempfile::tempdir().expect("temp dir");
    let path = tmp.path().join("ball.h5");
    let points = 40;
    common::sphere_database(&path, 0.5, points, 4.0);
    let data = AblData::read(&path).expect("eddy reads it back");
    let s = data.translation.sampling;
    let row = s.row(2, 3);
    let omega: Vec<String> = MotionKind::ALL
        .iter()
        .map(|&kind| {
            let values = &data.table(kind).row(row, points)[12..15];
            format!("{:?}: {}", kind.name(), list(values))
        })
        .collect();
    let kinds: Vec<String> = MotionKind::ALL
        .iter()
        .map(|k| format!("{:?}", k.name()))
        .collect();
    let expected = format!(
        r#"{{"format": {ABL_FORMAT:?}, "version": {ABL_FORMAT_VERSION}, "beta": {:?},
            "points": {points}, "point_1": {}, "polar": {}, "azimuth": {}, "kinds": [{}],
            "row": {row}, "direction": {}, "omega": {{{}}}}}"#,
        data.header.beta,
        list(data.points[1].coords.as_slice()),
        s.polar,
        s.azimuth,
        kinds.join(", "),
        list(s.direction(2, 3).as_slice()),
        omega.join(", ")
    );
    let out = std::process::Command::new(python)
        .args(["-c", H5PY_LAYOUT])
        .arg(&path)
        .arg(&expected)
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}
