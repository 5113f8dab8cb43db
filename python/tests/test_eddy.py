"""The Python bindings against the command line: the same runs bit for bit, documented arrays,
lookups equal to `eddy lookup`, and bad input raised as exceptions naming what is wrong.

Run by `./dev test` (pytest python/tests) after `maturin develop --release`; the CLI binary
is the one `cargo test --release` built (target/release/eddy, or $EDDY_BIN).
"""

import csv
import fcntl
import io
import os
import pathlib
import pty
import re
import struct
import subprocess
import termios
import time
import tomllib

import numpy as np
import pytest

import eddy

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"
EDDY = pathlib.Path(os.environ.get("EDDY_BIN", ROOT / "target" / "release" / "eddy"))


def cli(*args):
    done = subprocess.run([str(EDDY), *map(str, args)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return done.stdout


def rows(path):
    """metrics.csv without its wall-time columns, which no two runs share."""
    with open(path) as f:
        table = list(csv.reader(f))
    keep = [i for i, c in enumerate(table[0]) if not c.endswith("_seconds")]
    return [[r[i] for i in keep] for r in table]


def sets(overrides):
    return [a for k, v in overrides.items() for a in ("--set", f"{k}={v}")]


DAM = {"time.end": 0.05, "output.interval": 0.01}
GREEN = {"time.end": 0.3, "output.interval": 0.1, "grid.resolution": "[32,32,1]",
         "domain.max": "[6.283185307179586,6.283185307179586,0.19634954084936207]"}


@pytest.mark.parametrize("scene, overrides", [("dam_break.toml", DAM), ("taylor_green.toml", GREEN)])
def test_a_run_from_python_equals_the_cli_bit_for_bit(tmp_path, scene, overrides):
    cli("run", SCENES / scene, "--out", tmp_path / "cli", *sets(overrides))
    py = {k: tomllib.loads(f"v = {v}")["v"] if isinstance(v, str) else v for k, v in overrides.items()}
    # In one piece ...
    sim = eddy.Simulation(eddy.Scene.load(SCENES / scene, overrides=py), out=tmp_path / "one")
    sim.run()
    assert sim.ended and not sim.step()
    # ... and in pieces: run(until=...) never shortens a step, so the steps are the same.
    pieces = eddy.Simulation(eddy.Scene.load(SCENES / scene, overrides=py), out=tmp_path / "pieces")
    pieces.run(until=0.4 * py["time.end"])
    pieces.run(steps=2)
    pieces.run()
    want = rows(tmp_path / "cli" / "metrics.csv")
    assert len(want) > 3
    assert rows(tmp_path / "one" / "metrics.csv") == want
    assert rows(tmp_path / "pieces" / "metrics.csv") == want
    # The metrics' history is the file's table, a row a step; its last row is last_metrics().
    history = sim.metrics()
    with open(tmp_path / "one" / "metrics.csv") as f:
        columns = next(csv.reader(f))
    table = np.loadtxt(tmp_path / "one" / "metrics.csv", delimiter=",", skiprows=1, ndmin=2)
    assert list(history) == columns
    for i, name in enumerate(columns):
        assert history[name].dtype == np.float64 and np.array_equal(history[name], table[:, i]), name
    assert np.array_equal(history["step"], np.arange(sim.steps)) and np.all(np.diff(history["time"]) > 0)
    last = sim.last_metrics()
    assert last == {name: column[-1] for name, column in history.items()}
    assert last["time"] + last["dt"] == pytest.approx(sim.time)
    assert sorted(p.name for p in (tmp_path / "one").iterdir()) == sorted(
        p.name for p in (tmp_path / "cli").iterdir())


def test_a_saved_run_resumed_from_python_ends_as_the_run_that_never_stopped(tmp_path):
    scene = eddy.Scene.load(SCENES / "dam_break.toml", overrides={"time.end": 0.05, "output.interval": 0.01})
    whole = eddy.Simulation(scene, out=tmp_path / "whole")
    whole.run()
    stopped = eddy.Simulation(scene, out=tmp_path / "stopped")
    stopped.run(steps=7)
    path = stopped.save()
    assert path == tmp_path / "stopped" / "checkpoint.h5" and path.exists()
    del stopped
    resumed = eddy.Simulation.resume(scene, out=tmp_path / "stopped")
    assert resumed.steps == 7
    resumed.run()
    assert resumed.steps == whole.steps
    assert np.array_equal(resumed.position, whole.position)
    assert np.array_equal(resumed.velocity, whole.velocity)
    assert rows(tmp_path / "stopped" / "metrics.csv") == rows(tmp_path / "whole" / "metrics.csv")
    # The history holds the rows before the checkpoint too: those are the file's.
    assert np.array_equal(resumed.metrics()["time"], whole.metrics()["time"])
    other = eddy.Scene.load(SCENES / "dam_break.toml", overrides={"fluid.spacing": 0.05})
    with pytest.raises(RuntimeError, match="another scene"):
        eddy.Simulation.resume(other, out=tmp_path / "stopped")


def test_particle_arrays_have_the_documented_shapes_and_units(tmp_path):
    sim = eddy.Simulation(eddy.Scene.load(SCENES / "dam_break.toml", overrides={"time.end": 0.02}),
                          out=tmp_path)
    sim.step()
    n = len(sim.position)
    assert n == 12500 and sim.metrics()["particles"].tolist() == [n]
    for name, shape in [("position", (n, 3)), ("velocity", (n, 3)), ("vorticity", (n, 3)),
                        ("density", (n,)), ("pressure", (n,))]:
        a = getattr(sim, name)
        assert a.shape == shape and a.dtype == np.float64, name
    # The column of water, 0.5 m wide and 1 m tall in the tank's corner, at rest density.
    assert sim.position[:, 0].max() < 0.6 and 900 < np.median(sim.density) < 1100
    # Under gravity the water starts to fall: velocities point down after a step.
    assert sim.velocity[:, 1].mean() < 0
    assert sim.dt > 0 and sim.time == pytest.approx(sim.dt)
    # What the scene does not have reads None, and writing it says what to write instead.
    for name in ("grid_velocity", "grid_vorticity", "grid_abl_vorticity", "grid_solid", "grid_faces",
                 "grid_pressure", "grid_geometry", "smoke", "abl_vorticity"):
        assert getattr(sim, name) is None, name
    with pytest.raises(ValueError, match=r"grid faces: the scene has no grid .*`velocity`"):
        sim.set_grid_faces(*[np.zeros((2, 2, 2))] * 3)


def test_grid_fields_have_the_documented_shapes_and_equal_the_last_frame(tmp_path, sphere):
    h5py = pytest.importorskip("h5py")
    overrides = {"time.end": 0.3, "obstacles.0.abl.database": str(sphere), "output.hdf5": True,
                 "output.vtk": False}
    sim = eddy.Simulation(eddy.Scene.load(SCENES / "abl_sphere_wake.toml", overrides=overrides),
                          out=tmp_path)
    sim.run()
    g = sim.grid_geometry
    assert isinstance(g, eddy.GridGeometry) and g == ((0.0, 0.0, 0.0), 6.0 / 64, (64, 32, 32))
    nx, ny, nz = g.dims
    fields = {"velocity": sim.grid_velocity, "vorticity": sim.grid_vorticity,
              "pressure": sim.grid_pressure, "solid": sim.grid_solid,
              "abl_vorticity": sim.grid_abl_vorticity, "smoke": sim.smoke}
    for name, shape in [("velocity", (nx, ny, nz, 3)), ("vorticity", (nx, ny, nz, 3)),
                        ("abl_vorticity", (nx, ny, nz, 3)), ("pressure", (nx, ny, nz)),
                        ("smoke", (nx, ny, nz))]:
        assert fields[name].shape == shape and fields[name].dtype == np.float64, name
    fx, fy, fz = sim.grid_faces
    assert fx.shape == (nx + 1, ny, nz) and fy.shape == (nx, ny + 1, nz) and fz.shape == (nx, ny, nz + 1)
    # Cell velocity is the mean of the two faces of a cell.
    assert np.allclose(fields["velocity"][..., 0], 0.5 * (fx[1:] + fx[:-1]))
    assert fields["smoke"].max() > 0 and np.abs(fields["abl_vorticity"]).max() > 0
    v = sim.vortices()
    k = len(v["radius"])
    assert v["position"].shape == (k, 3) and v["vorticity"].shape == (k, 3)
    assert v["energy"].shape == (k,) and v["age"].shape == (k,)
    with pytest.raises(ValueError, match=r'boundary layers are on the grid; ask for vortices\("grid"\)'):
        sim.vortices("particles")
    # A grid scene has no particles: their fields read None (so hasattr says True).
    for name in ("position", "velocity", "density", "pressure", "vorticity", "abl_vorticity"):
        assert getattr(sim, name) is None, name
    with pytest.raises(ValueError, match="no SPH fluid.*set_grid_faces"):
        sim.velocity = np.zeros((3, 3))
    del sim
    # Every field is the end's frame, as h5py reads it: the same axes, the same values.
    with h5py.File(tmp_path / "frames.h5", "r") as f:
        last = f["frames"][max(f["frames"])]
        for name, a in fields.items():
            stored = last[name][()]
            assert np.array_equal(a, stored > 0.5 if name == "solid" else stored), name
    # The solid cells are the sphere's (radius 0.5 at (1.5, 1.5, 1.5)) to within a cell.
    solid = fields["solid"]
    centres = [o + (np.arange(n) + 0.5) * g.spacing for o, n in zip(g.origin, g.dims)]
    x, y, z = np.meshgrid(*centres, indexing="ij")
    r = np.sqrt((x - 1.5) ** 2 + (y - 1.5) ** 2 + (z - 1.5) ** 2)
    assert solid.dtype == bool and solid[r < 0.5 - g.spacing].all() and not solid[r > 0.5 + g.spacing].any()


def central(f, axis, h):
    """The central difference of f along a periodic axis (one cell: zero, as the solver's)."""
    if f.shape[axis] == 1:
        return np.zeros_like(f)
    return (np.roll(f, -1, axis) - np.roll(f, 1, axis)) / (2 * h)


def test_grid_vorticity_is_the_curl_of_the_grid_velocity(tmp_path):
    overrides = {"grid.resolution": [16, 16, 1], "domain.max": [2 * np.pi, 2 * np.pi, 2 * np.pi / 16]}
    sim = eddy.Simulation(eddy.Scene.load(SCENES / "taylor_green.toml", overrides=overrides),
                          out=tmp_path)
    h = sim.grid_geometry.spacing
    # The Taylor-Green vortex: central differences of the cell velocity on the periodic grid.
    u, v, w = np.moveaxis(sim.grid_velocity, -1, 0)
    d = lambda f, axis: central(f, axis, h)
    curl = np.stack([d(w, 1) - d(v, 2), d(u, 2) - d(w, 0), d(v, 0) - d(u, 1)], axis=-1)
    assert np.abs(curl).max() > 0.5
    assert np.allclose(sim.grid_vorticity, curl, rtol=0, atol=1e-12)
    # A solid-body rotation at rate 2 about the z axis: vorticity 2 x 2 away from the seam.
    (x0, y0, _), _, (nx, ny, nz) = sim.grid_geometry
    xf, yf = x0 + np.arange(nx + 1) * h, y0 + np.arange(ny + 1) * h
    xc, yc = xf[:-1] + 0.5 * h, yf[:-1] + 0.5 * h
    fx = np.broadcast_to(-2.0 * (yc - np.pi)[None, :, None], (nx + 1, ny, nz))
    fy = np.broadcast_to(2.0 * (xc - np.pi)[:, None, None], (nx, ny + 1, nz))
    sim.set_grid_faces(np.ascontiguousarray(fx), np.ascontiguousarray(fy), np.zeros((nx, ny, nz + 1)))
    omega = sim.grid_vorticity[1:-1, 1:-1]
    assert np.allclose(omega[..., 2], 4.0, rtol=1e-12) and np.allclose(omega[..., :2], 0.0, atol=1e-12)


def test_numpy_values_override_as_lists_and_numbers_do(tmp_path):
    lists = {"time.end": 0.3, "output.interval": 0.1, "grid.resolution": [32, 32, 1],
             "domain.max": [6.283185307179586, 6.283185307179586, 0.19634954084936207],
             "grid.reflection": True}
    arrays = {"time.end": np.float64(0.3), "output.interval": np.array(0.1),
              "grid.resolution": np.array([32, 32, 1]), "domain.max": np.array(lists["domain.max"]),
              "grid.reflection": np.bool_(True)}
    runs = {}
    for name, overrides in [("lists", lists), ("arrays", arrays)]:
        scene = eddy.Scene.load(SCENES / "taylor_green.toml", overrides=overrides)
        runs[name] = scene.to_toml()
        eddy.Simulation(scene, out=tmp_path / name).run()
    assert runs["arrays"] == runs["lists"]
    assert rows(tmp_path / "arrays" / "metrics.csv") == rows(tmp_path / "lists" / "metrics.csv")
    # A scene dict may hold NumPy values too (NumPy integers in a list among them).
    table = tomllib.loads((SCENES / "taylor_green.toml").read_text())
    table["grid"]["resolution"] = [np.int64(32), np.int32(32), 1]
    table["time"]["end"] = np.float64(0.3)
    table["domain"]["max"] = np.array(lists["domain.max"])
    table["output"]["interval"] = 0.1
    assert eddy.Scene.from_dict(table).to_toml() == runs["lists"]
    with pytest.raises(eddy.SceneError, match="grid.resolution"):
        eddy.Scene.load(SCENES / "taylor_green.toml", overrides={"grid.resolution": np.array([1j])})


def test_progress_draws_the_share_of_time_elapsed_and_eta_on_a_terminal(tmp_path):
    """run(progress=True) draws eddy run's bar on a terminal: elapsed time, percent of the
    simulated time to go, ETA and the step's time (not a count over a length of 0)."""
    script = ("import eddy, math, sys\n"
              "small = {'grid.resolution': [16, 16, 1], 'domain.max': [2 * math.pi, 2 * math.pi, math.pi / 8]}\n"
              "scene = eddy.Scene.load(sys.argv[1], overrides=small)\n"
              "eddy.Simulation(scene, out=sys.argv[2]).run(until=0.5, progress=True)\n")
    terminal, child_end = pty.openpty()
    fcntl.ioctl(child_end, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 160, 0, 0))
    child = subprocess.Popen([os.sys.executable, "-c", script, SCENES / "taylor_green.toml", tmp_path],
                             stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=child_end)
    os.close(child_end)
    drawn = b""
    while True:
        try:
            chunk = os.read(terminal, 4096)
        except OSError:  # the child closed the terminal
            break
        if not chunk:
            break
        drawn += chunk
    os.close(terminal)
    assert child.wait() == 0, drawn
    assert re.search(r"\[\d\d:\d\d:\d\d\] .*\d+% ETA \d+s t = 0\.\d{4} s, step \d+",
                     drawn.decode(errors="replace")), drawn


def test_the_version_is_the_crates():
    for manifest in (ROOT / "Cargo.toml", ROOT / "python" / "Cargo.toml"):
        assert eddy.__version__ == tomllib.loads(manifest.read_text())["package"]["version"]


def test_written_particle_velocities_run_as_the_cli_with_that_initial_field(tmp_path):
    moving = {"time.end": 0.03, "fluid.blocks.0.velocity": "[0.5,0.0,0.25]"}
    cli("run", SCENES / "dam_break.toml", "--out", tmp_path / "cli", *sets(moving))
    sim = eddy.Simulation(eddy.Scene.load(SCENES / "dam_break.toml", overrides={"time.end": 0.03}),
                          out=tmp_path / "py")
    v = np.zeros_like(sim.velocity)
    v[:] = [0.5, 0.0, 0.25]
    sim.velocity = v
    sim.run()
    assert rows(tmp_path / "py" / "metrics.csv") == rows(tmp_path / "cli" / "metrics.csv")


def test_written_grid_faces_run_as_the_cli_with_that_initial_field(tmp_path):
    # The cavity behind a step starts at 1 m/s along x; from Python the same scene starts at
    # rest and the faces are written before the first step.
    small = {"time.end": 0.3, "grid.resolution": "[48,24,16]"}
    cli("run", SCENES / "cavity_flow.toml", "--out", tmp_path / "cli", *sets(small))
    overrides = {"time.end": 0.3, "grid.resolution": [48, 24, 16], "grid.initial_velocity": [0.0, 0.0, 0.0]}
    sim = eddy.Simulation(eddy.Scene.load(SCENES / "cavity_flow.toml", overrides=overrides),
                          out=tmp_path / "py")
    fx, fy, fz = sim.grid_faces
    assert not fx[1:].any() and fx[0].max() == 1.0  # at rest but for the inflow side
    sim.set_grid_faces(np.ones_like(fx), fy, fz)
    sim.run()
    want = rows(tmp_path / "cli" / "metrics.csv")
    assert len(want) > 3 and rows(tmp_path / "py" / "metrics.csv") == want
    # The walls and obstacles hold the written field to their conditions, as the scene's own.
    with pytest.raises(ValueError, match=r"grid faces: .*y faces of shape"):
        sim.set_grid_faces(fx, fx, fz)
    with pytest.raises(ValueError, match="finite"):
        sim.set_grid_faces(np.full_like(fx, np.inf), fy, fz)


def coarse(name, tmp_path_factory):
    """A small database of scenes/db/NAME.toml precomputed from Python (the shipped ones are
    precomputed by `./dev demo`); its obstacle is the scene's, so scenes accept it."""
    out = tmp_path_factory.mktemp("db") / f"{name}.h5"
    computed = eddy.precompute(SCENES / "db" / f"{name}.toml", out, jobs=2, overrides={
        "grid.resolution": 16, "grid.stabilise_steps": 5, "grid.average_steps": 5,
        "sampling.translation": [3, 3], "sampling.rotation": [3, 3]})
    assert computed > 0
    return out


@pytest.fixture(scope="module")
def sphere(tmp_path_factory):
    return coarse("sphere", tmp_path_factory)


@pytest.fixture(scope="module")
def ball(tmp_path_factory):
    return coarse("ball", tmp_path_factory)


def test_lookups_equal_the_clis_at_sampled_directions(ball, tmp_path):
    db = eddy.Database.open(ball)
    rng = np.random.default_rng(7)
    velocity, angular = rng.normal(size=(10_000, 3)), rng.normal(size=(10_000, 3))
    omega = db.lookup(velocity, angular)
    assert omega.shape == (10_000, len(db), 3)
    for k in [0, 17, 4_321, 9_999]:
        text = cli("lookup", ball, "--velocity", ",".join(repr(float(c)) for c in velocity[k]),
                   "--angular", ",".join(repr(float(c)) for c in angular[k]), "--csv", "-")
        table = np.loadtxt(io.StringIO(text), delimiter=",", skiprows=1)
        assert np.array_equal(table[:, :3], db.points)
        assert np.array_equal(table[:, 6:], omega[k]), k
    assert np.array_equal(db.lookup(velocity[3]), db.lookup(velocity[3:4], np.zeros((1, 3)))[0])


def test_lookups_run_at_least_ten_million_points_a_second(ball):
    db = eddy.Database.open(ball)
    velocity = np.random.default_rng(1).normal(size=(10_000, 3))
    db.lookup(velocity)
    best = min(_timed(lambda: db.lookup(velocity)) for _ in range(5))
    rate = 10_000 * len(db) / best
    print(f"{rate / 1e6:.1f} M points/s")
    assert rate >= 10e6


def _timed(f):
    start = time.perf_counter()
    f()
    return time.perf_counter() - start


def test_bad_input_is_raised_naming_what_is_wrong(tmp_path):
    with pytest.raises(eddy.SceneError, match="endd"):
        eddy.Scene.load(SCENES / "dam_break.toml", overrides={"time.endd": 1.0})
    with pytest.raises(eddy.SceneError, match="missing.toml"):
        eddy.Scene.load(tmp_path / "missing.toml")
    with pytest.raises(eddy.SceneError, match="fluid.spacing|spacing"):
        eddy.Scene.load(SCENES / "dam_break.toml", overrides={"fluid.spacing": -1.0})
    table = tomllib.loads((SCENES / "dam_break.toml").read_text())
    table["time"]["colour"] = "red"
    with pytest.raises(eddy.SceneError, match="colour"):
        eddy.Scene.from_dict(table)
    assert issubclass(eddy.SceneError, ValueError)
    sim = eddy.Simulation(eddy.Scene.load(SCENES / "dam_break.toml", overrides={"time.end": 0.01}),
                          out=tmp_path / "run")
    with pytest.raises(ValueError, match=r"velocity: expected shape \(12500, 3\)"):
        sim.velocity = np.zeros((3, 3))
    with pytest.raises(ValueError, match="finite"):
        sim.velocity = np.full((12500, 3), np.nan)
    assert sim.grid_pressure is None
    with pytest.raises(eddy.SceneError):
        eddy.Database.open(tmp_path / "none.h5")


def test_the_documented_example_runs_and_draws_the_smoke(tmp_path, sphere):
    """README's "Python" example, cut to 0.3 s: it runs, and its figure shows smoke."""
    figure = tmp_path / "smoke.png"
    done = subprocess.run(
        [os.sys.executable, ROOT / "python" / "examples" / "sphere_wake_smoke.py", "--end", "0.3",
         "--figure", figure, "--out", tmp_path / "run", "--database", sphere],
        cwd=ROOT, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "t = 0.30 s" in done.stdout
    import matplotlib.image
    pixels = matplotlib.image.imread(figure)
    assert pixels.shape[0] > 200 and pixels[..., :3].std() > 0.05


def test_ctrl_c_stops_a_precomputation_and_resume_keeps_what_was_done(tmp_path):
    out = tmp_path / "ball.h5"
    script = ("import eddy, sys\n"
              "try:\n"
              "    eddy.precompute(sys.argv[1], sys.argv[2], jobs=1, overrides={'grid.resolution': 20})\n"
              "    print('finished')\n"
              "except KeyboardInterrupt:\n"
              "    print('interrupted')\n")
    child = subprocess.Popen([os.sys.executable, "-c", script, SCENES / "db" / "ball.toml", out],
                             stdout=subprocess.PIPE, text=True)
    time.sleep(1.0)
    child.send_signal(2)  # SIGINT, as Ctrl-C
    said, _ = child.communicate(timeout=60)
    assert said.strip() == "interrupted" and not out.exists()
    parts = pathlib.Path(f"{out}.parts")
    assert parts.is_dir() and any(parts.iterdir())
    # 32 directions in all (ball.toml's sampling); the interrupted run's are not computed again.
    computed = eddy.precompute(SCENES / "db" / "ball.toml", out, jobs=2, resume=True,
                               overrides={"grid.resolution": 20})
    assert 0 < computed < 32
    assert len(eddy.Database.open(out)) > 0


def test_statistics_are_the_files_arrays_with_their_lattice(tmp_path):
    h5py = pytest.importorskip("h5py")
    overrides = {"time.end": 0.3, "output.interval": 0.1, "grid.resolution": [32, 32, 1],
                 "domain.max": [6.283185307179586, 6.283185307179586, 0.19634954084936207],
                 "statistics.from": 0.1}
    sim = eddy.Simulation(eddy.Scene.load(SCENES / "taylor_green.toml", overrides=overrides),
                          out=tmp_path)
    assert sim.statistics() is None
    sim.run()
    s = sim.statistics()
    assert s["dims"] == [32, 32, 1] and s["spacing"] == pytest.approx(6.283185307179586 / 32)
    assert s["time_from"] == pytest.approx(0.1) and s["time_to"] == pytest.approx(0.3)
    with h5py.File(tmp_path / "statistics.h5", "r") as f:
        assert f.attrs["sample_count"] == s["sample_count"] > 0
        for name in ("mean_velocity", "reynolds_stress", "k", "mean_vorticity", "mean_enstrophy",
                     "samples"):
            assert np.array_equal(f[name][()], s[name], equal_nan=True), name
    # The decaying vortex: its mean velocity lies between its start and its end.
    assert s["reynolds_stress"].shape == (32, 32, 1, 6)
    assert np.all(s["k"] >= 0)
    with pytest.raises(ValueError, match="medium"):
        sim.statistics("particles")


def test_a_run_into_an_earlier_run_s_folder_says_what_it_removed(tmp_path):
    """Starting a run removes the earlier run's outputs from its folder, and says so."""
    scene = eddy.Scene.load(SCENES / "taylor_green.toml", overrides={
        "time.end": 0.1, "output.interval": 0.1, "grid.resolution": [16, 16, 1],
        "domain.max": [6.283185307179586, 6.283185307179586, 0.39269908169872414]})
    eddy.Simulation(scene, out=tmp_path).run()
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.warns(UserWarning, match=r"removed \d+ output files of an earlier run"):
        eddy.Simulation(scene, out=tmp_path)
    assert (tmp_path / "notes.txt").read_text() == "mine"
