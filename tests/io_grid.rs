//! Round trips of the grid writers in `eddy::io`: VTK ImageData for ParaView and HDF5 grid frames
//! for h5py put every value at the cell it belongs to, and a failure leaves no half-written file.

mod common;

use std::fs;
use std::path::Path;

use eddy::io::{
    write_grid_vtk, AttrValue, GridField, GridFrame, Hdf5GridFrames, IoError, Precision, PvdSeries,
    VtkOptions, GRID_FORMAT, GRID_FORMAT_VERSION,
};
use eddy::{Real, Vec3};
use ndarray::{s, Array3, ShapeBuilder};

use common::vtk_read::read_vtk;

/// The scenes' default VTK storage.
const OPTIONS: VtkOptions = VtkOptions {
    precision: Precision::F32,
    compression: 4,
};

/// Distinct sizes per axis, so a swapped axis changes the shape, not just the values.
const DIMS: [usize; 3] = [4, 3, 2];

/// The marker field: its value names its own cell.
fn marker(i: usize, j: usize, k: usize) -> Real {
    (i + 10 * j + 100 * k) as Real
}

/// The three components of the test vector field; distinct from each other and from `marker`.
fn velocity(i: usize, j: usize, k: usize) -> [Real; 3] {
    let m = marker(i, j, k);
    [m + 0.25, -m, 1000.0 + m / 3.0]
}

/// The test fields in three memory layouts: C order, Fortran order, and a strided interior
/// slice of a larger array (as a solver with ghost cells would hand over).
struct Fields {
    marker: Array3<Real>,
    vx_fortran: Array3<Real>,
    vy: Array3<Real>,
    vz_padded: Array3<Real>,
}

impl Fields {
    fn new() -> Self {
        let [nx, ny, nz] = DIMS;
        let c = |f: fn(usize, usize, usize) -> Real| {
            Array3::from_shape_fn((nx, ny, nz), |(i, j, k)| f(i, j, k))
        };
        let mut padded = Array3::from_elem((nx + 2, 2 * ny + 1, nz + 2), Real::NAN);
        padded
            .slice_mut(s![1..nx + 1, 1..;2, 1..nz + 1])
            .indexed_iter_mut()
            .for_each(|((i, j, k), v)| *v = velocity(i, j, k)[2]);
        Fields {
            marker: c(marker),
            vx_fortran: Array3::from_shape_fn((nx, ny, nz).f(), |(i, j, k)| velocity(i, j, k)[0]),
            vy: c(|i, j, k| velocity(i, j, k)[1]),
            vz_padded: padded,
        }
    }

    fn frame(&self, step: u64, time: Real) -> GridFrame<'_> {
        let [nx, _, nz] = DIMS;
        GridFrame {
            step,
            time,
            origin: Vec3::new(0.1, -0.25, 1.0 / 3.0),
            spacing: 0.1,
            dims: DIMS,
            fields: vec![
                GridField::scalar("marker", self.marker.view()),
                GridField::vector(
                    "velocity",
                    [
                        self.vx_fortran.view(),
                        self.vy.view(),
                        self.vz_padded.slice(s![1..nx + 1, 1..;2, 1..nz + 1]),
                    ],
                ),
            ],
        }
    }
}

/// Every cell index of the grid.
fn cells() -> impl Iterator<Item = (usize, usize, usize)> {
    let [nx, ny, nz] = DIMS;
    (0..nx).flat_map(move |i| (0..ny).flat_map(move |j| (0..nz).map(move |k| (i, j, k))))
}

fn no_temp_files(dir: &Path) {
    let leftovers: Vec<_> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
}

// ---------------------------------------------------------------- VTK ImageData

/// VTK's flat index of cell (i, j, k): x fastest.
fn vtk_cell(i: usize, j: usize, k: usize) -> usize {
    let [nx, ny, _] = DIMS;
    i + nx * (j + ny * k)
}

#[test]
fn vti_values_land_at_their_cells() {
    for (precision, level) in [
        (Precision::F64, 0),
        (Precision::F64, 6),
        (Precision::F32, 1),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("grid_000007.vti");
        let fields = Fields::new();
        let options = VtkOptions {
            precision,
            compression: level,
        };
        write_grid_vtk(&path, &fields.frame(7, 0.7), options).unwrap();
        no_temp_files(dir.path());

        let file = read_vtk(&path);
        assert_eq!(file.attr("VTKFile", "type"), "ImageData");
        let [nx, ny, nz] = DIMS;
        let points = format!("0 {nx} 0 {ny} 0 {nz}");
        assert_eq!(file.attr("ImageData", "WholeExtent"), points);
        assert_eq!(file.attr("Piece", "Extent"), points);
        // The geometry is exact whatever the arrays' precision.
        assert_eq!(
            file.attr("ImageData", "Origin"),
            "0.1 -0.25 0.3333333333333333"
        );
        assert_eq!(file.attr("ImageData", "Spacing"), "0.1 0.1 0.1");
        assert_eq!(file.section("FieldData")[0].values, [0.7]);
        assert!(file.section("PointData").is_empty(), "values are cell data");

        let arrays = file.section("CellData");
        assert_eq!(arrays.len(), 2);
        let n = DIMS.iter().product::<usize>();
        let (marker_values, velocity_values) = (&arrays[0].values, &arrays[1].values);
        assert_eq!(
            (arrays[0].name.as_str(), arrays[0].components),
            ("marker", 1)
        );
        assert_eq!(
            (arrays[1].name.as_str(), arrays[1].components),
            ("velocity", 3)
        );
        assert_eq!((marker_values.len(), velocity_values.len()), (n, 3 * n));
        let stored = |v: Real| match precision {
            Precision::F32 => v as f32 as Real,
            Precision::F64 => v,
        };
        for (i, j, k) in cells() {
            let c = vtk_cell(i, j, k);
            assert_eq!(
                marker_values[c],
                marker(i, j, k),
                "marker at cell {:?}",
                (i, j, k)
            );
            assert_eq!(
                velocity_values[3 * c..3 * c + 3],
                velocity(i, j, k).map(stored),
                "velocity at cell {:?}",
                (i, j, k)
            );
        }
    }
}

#[test]
fn vti_series_lists_grid_frames() {
    let dir = tempfile::tempdir().unwrap();
    let fields = Fields::new();
    let mut series = PvdSeries::new(&dir.path().join("grid.pvd"));
    fs::create_dir(dir.path().join("grid")).unwrap();
    for step in 0..2u64 {
        let name = format!("grid/grid_{step:06}.vti");
        let time = 0.5 * step as Real;
        write_grid_vtk(&dir.path().join(&name), &fields.frame(step, time), OPTIONS).unwrap();
        series.push(time, &name).unwrap();
    }
    let text = fs::read_to_string(series.path()).unwrap();
    let files: Vec<&str> = text
        .lines()
        .filter_map(|l| l.split(" file=\"").nth(1))
        .map(|rest| &rest[..rest.find('"').unwrap()])
        .collect();
    assert_eq!(files, ["grid/grid_000000.vti", "grid/grid_000001.vti"]);
    assert!(text.contains("timestep=\"0.5\""), "{text}");
    // Each entry resolves, relative to the .pvd, to a readable ImageData file.
    for f in files {
        let file = read_vtk(&dir.path().join(f));
        assert_eq!(file.attr("ImageData", "WholeExtent"), "0 4 0 3 0 2");
    }
}

#[test]
fn vti_rejects_bad_frames_without_writing() {
    let dir = tempfile::tempdir().unwrap();
    let fields = Fields::new();
    let wrong = Array3::<Real>::zeros((DIMS[0], DIMS[2], DIMS[1]));

    let mut swapped = fields.frame(0, 0.0);
    swapped
        .fields
        .push(GridField::scalar("pressure", wrong.view()));
    let mut twice = fields.frame(0, 0.0);
    twice
        .fields
        .push(GridField::scalar("marker", fields.marker.view()));
    let mut no_cells = fields.frame(0, 0.0);
    no_cells.dims = [0, 3, 2];
    no_cells.fields.clear();
    let mut bad_spacing = fields.frame(0, 0.0);
    bad_spacing.spacing = -0.1;
    let cases = [
        ("swapped.vti", swapped, "\"pressure\""),
        ("twice.vti", twice, "\"marker\" appears twice"),
        ("no_cells.vti", no_cells, "dims [0, 3, 2]"),
        ("spacing.vti", bad_spacing, "spacing -0.1"),
        ("ext.vtk", fields.frame(0, 0.0), ".vti"),
    ];
    for (name, frame, needle) in cases {
        let path = dir.path().join(name);
        let err = write_grid_vtk(&path, &frame, OPTIONS).unwrap_err();
        assert!(matches!(err, IoError::Invalid { .. }), "{name}: {err:?}");
        let msg = err.to_string();
        assert!(msg.contains(name) && msg.contains(needle), "{msg}");
    }
    assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn vti_failed_write_leaves_nothing_half_written() {
    let dir = tempfile::tempdir().unwrap();
    let fields = Fields::new();
    let frame = fields.frame(0, 0.0);

    let missing = dir.path().join("no_such_dir").join("g.vti");
    let err = write_grid_vtk(&missing, &frame, OPTIONS).unwrap_err();
    assert!(err.to_string().contains("no_such_dir"), "{err}");
    assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);

    // The whole file is written, then the rename onto a directory fails: the temporary goes.
    let blocked = dir.path().join("blocked.vti");
    fs::create_dir(&blocked).unwrap();
    let err = write_grid_vtk(&blocked, &frame, OPTIONS).unwrap_err();
    assert!(matches!(err, IoError::Io { .. }), "{err:?}");
    assert!(blocked.is_dir());
    no_temp_files(dir.path());
    assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1);
}

// ---------------------------------------------------------------- HDF5 grid frames

fn read_attr<T: hdf5::H5Type>(loc: &hdf5::Group, name: &str) -> T {
    loc.attr(name).unwrap().read_scalar::<T>().unwrap()
}

fn is_f64(ds: &hdf5::Dataset) -> bool {
    use hdf5::types::{FloatSize, TypeDescriptor};
    ds.dtype().unwrap().to_descriptor().unwrap() == TypeDescriptor::Float(FloatSize::U8)
}

#[test]
fn hdf5_grid_frames_roundtrip() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("grid.h5");
    let mut out = Hdf5GridFrames::create(
        &path,
        &[
            ("scene", AttrValue::from("smoke plume")),
            ("viscosity", AttrValue::Real(1e-3)),
        ],
    )
    .unwrap();
    assert!(out.is_empty());
    assert_eq!(out.path(), path);
    no_temp_files(dir.path());

    let fields = Fields::new();
    let frames = [(3u64, 0.03), (9, 0.09)];
    for &(step, time) in &frames {
        out.append(&fields.frame(step, time)).unwrap();
    }
    assert_eq!(out.len(), 2);

    let file = hdf5::File::open(&path).unwrap();
    let format: hdf5::types::VarLenUnicode = read_attr(&file, "format");
    assert_eq!(format.as_str(), GRID_FORMAT);
    assert_eq!(
        read_attr::<i64>(&file, "format_version"),
        GRID_FORMAT_VERSION
    );
    let scene: hdf5::types::VarLenUnicode = read_attr(&file, "scene");
    assert_eq!(scene.as_str(), "smoke plume");
    assert_eq!(read_attr::<f64>(&file, "viscosity"), 1e-3);
    assert_eq!(
        file.attr("origin").unwrap().read_raw::<f64>().unwrap(),
        [0.1, -0.25, 1.0 / 3.0]
    );
    assert_eq!(read_attr::<f64>(&file, "spacing"), 0.1);
    assert_eq!(
        file.attr("dims").unwrap().read_raw::<u64>().unwrap(),
        DIMS.map(|n| n as u64)
    );
    assert_eq!(file.member_names().unwrap(), ["frames"]);

    let group = file.group("frames").unwrap();
    assert_eq!(group.member_names().unwrap(), ["000000", "000001"]);
    for (f, &(step, time)) in frames.iter().enumerate() {
        let g = group.group(&format!("{f:06}")).unwrap();
        assert_eq!(read_attr::<u64>(&g, "step"), step);
        assert_eq!(read_attr::<f64>(&g, "time"), time);

        let m = g.dataset("marker").unwrap();
        assert_eq!(m.shape(), DIMS);
        assert!(is_f64(&m));
        let m = m.read::<f64, ndarray::Ix3>().unwrap();
        let v = g.dataset("velocity").unwrap();
        assert_eq!(v.shape(), [DIMS[0], DIMS[1], DIMS[2], 3]);
        assert!(is_f64(&v));
        let v = v.read::<f64, ndarray::Ix4>().unwrap();
        for (i, j, k) in cells() {
            assert_eq!(m[[i, j, k]], marker(i, j, k), "marker at {:?}", (i, j, k));
            for (c, want) in velocity(i, j, k).into_iter().enumerate() {
                assert_eq!(v[[i, j, k, c]], want, "velocity[{c}] at {:?}", (i, j, k));
            }
        }
    }
    drop(file);

    // h5py sees the same layout.
    if let Some(python) = common::python_with(&["h5py"]) {
        let script = "import sys, h5py\n\
                      f = h5py.File(sys.argv[1], 'r')\n\
                      g = f['frames/000001']\n\
                      m, v = g['marker'], g['velocity']\n\
                      print(m.shape, m.dtype, v.shape, v.dtype, int(g.attrs['step']))\n\
                      print(float(m[3, 2, 1]), float(v[3, 2, 1, 1]), [int(d) for d in f.attrs['dims']], f.attrs['format'])\n";
        let out = std::process::Command::new(python)
            .args(["-c", script])
            .arg(&path)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert_eq!(
            String::from_utf8_lossy(&out.stdout),
            format!(
                "(4, 3, 2) float64 (4, 3, 2, 3) float64 9\n{:?} {:?} [4, 3, 2] {GRID_FORMAT}\n",
                marker(3, 2, 1),
                velocity(3, 2, 1)[1]
            )
        );
    }
}

#[test]
fn hdf5_grid_rejects_mismatched_frames() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.h5");
    let mut out = Hdf5GridFrames::create(&path, &[]).unwrap();
    let fields = Fields::new();

    let short = Array3::<Real>::zeros((DIMS[0], DIMS[1], DIMS[2] + 1));
    let mut frame = fields.frame(0, 0.0);
    frame.fields[1] = GridField::vector(
        "velocity",
        [fields.vy.view(), fields.vy.view(), short.view()],
    );
    let err = out.append(&frame).unwrap_err();
    assert!(matches!(err, IoError::Invalid { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("bad.h5")
            && msg.contains("\"velocity\" (z component)")
            && msg.contains("[4, 3, 3]")
            && msg.contains("[4, 3, 2]"),
        "{msg}"
    );
    assert!(out.is_empty());

    out.append(&fields.frame(0, 0.0)).unwrap();
    // The first frame fixed the grid; a frame on another grid is refused.
    let mut moved = fields.frame(1, 0.1);
    moved.origin.x += 1.0;
    let err = out.append(&moved).unwrap_err();
    assert!(matches!(err, IoError::Invalid { .. }), "{err:?}");
    assert!(err.to_string().contains("origin"), "{err}");
    assert_eq!(out.len(), 1);

    let file = hdf5::File::open(&path).unwrap();
    assert_eq!(
        file.group("frames").unwrap().member_names().unwrap(),
        ["000000"]
    );
    assert_eq!(file.member_names().unwrap(), ["frames"]);
}

#[test]
fn hdf5_grid_create_failures_leave_no_file() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let reserved = Hdf5GridFrames::create(&dir.path().join("r.h5"), &[("dims", AttrValue::Int(3))]);
    assert!(
        matches!(reserved, Err(IoError::Invalid { .. })),
        "{reserved:?}"
    );

    let missing = dir.path().join("no_such_dir").join("g.h5");
    let err = Hdf5GridFrames::create(&missing, &[]).unwrap_err();
    assert!(err.to_string().contains("no_such_dir"), "{err}");
    assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn hdf5_grid_first_append_replaces_stale_geometry() {
    let _serial = common::hdf5_or_child();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("retry.h5");
    let mut out = Hdf5GridFrames::create(&path, &[]).unwrap();
    // What a first append that failed after writing the grid leaves: geometry, no frame.
    {
        let file = hdf5::File::open_rw(&path).unwrap();
        for name in ["origin", "dims"] {
            let a = file.new_attr::<u64>().shape(3).create(name).unwrap();
            a.write_raw(&[7u64, 7, 7]).unwrap();
        }
    }
    let fields = Fields::new();
    out.append(&fields.frame(0, 0.0)).unwrap();
    let file = hdf5::File::open(&path).unwrap();
    assert_eq!(
        file.attr("origin").unwrap().read_raw::<f64>().unwrap(),
        [0.1, -0.25, 1.0 / 3.0]
    );
    assert_eq!(
        file.attr("dims").unwrap().read_raw::<u64>().unwrap(),
        DIMS.map(|n| n as u64)
    );
    assert_eq!(read_attr::<f64>(&file, "spacing"), 0.1);
}
