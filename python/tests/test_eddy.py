"""The Python bindings against the command line: the same runs bit for bit, documented arrays,
lookups equal to `eddy lookup`, and bad input raised as exceptions naming what is wrong.

Run by `./dev test` (pytest python/tests) after `maturin develop --release`; the CLI binary
is the one `cargo test --release` built (target/release/eddy, or $EDDY_BIN).
"""

import csv
import io
import os
import pathlib
import subprocess
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
    last = sim.metrics()
    assert last["step"] == sim.steps - 1 and last["time"] + last["dt"] == pytest.approx(sim.time)
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
    other = eddy.Scene.load(SCENES / "dam_break.toml", overrides={"fluid.spacing": 0.05})
    with pytest.raises(RuntimeError, match="another scene"):
        eddy.Simulation.resume(other, out=tmp_path / "stopped")


def test_particle_arrays_have_the_documented_shapes_and_units(tmp_path):
    sim = eddy.Simulation(eddy.Scene.load(SCENES / "dam_break.toml", overrides={"time.end": 0.02}),
                          out=tmp_path)
    sim.step()
    n = sim.metrics()["particles"] if "particles" in sim.metrics() else len(sim.position)
    assert n == 12500
    for name, shape in [("position", (n, 3)), ("velocity", (n, 3)), ("vorticity", (n, 3)),
                        ("density", (n,)), ("pressure", (n,))]:
        a = getattr(sim, name)
        assert a.shape == shape and a.dtype == np.float64, name
    # The column of water, 0.5 m wide and 1 m tall in the tank's corner, at rest density.
    assert sim.position[:, 0].max() < 0.6 and 900 < np.median(sim.density) < 1100
    # Under gravity the water starts to fall: velocities point down after a step.
    assert sim.velocity[:, 1].mean() < 0
    assert sim.dt > 0 and sim.time == pytest.approx(sim.dt)


def test_grid_arrays_have_the_documented_shapes(tmp_path, sphere):
    overrides = {"time.end": 0.3, "obstacles.0.abl.database": str(sphere)}
    sim = eddy.Simulation(eddy.Scene.load(SCENES / "abl_sphere_wake.toml", overrides=overrides),
                          out=tmp_path)
    sim.run()
    origin, h, (nx, ny, nz) = sim.grid_geometry
    assert (nx, ny, nz) == (64, 32, 32) and h == pytest.approx(6.0 / 64)
    assert sim.grid_velocity.shape == (nx, ny, nz, 3)
    fx, fy, fz = sim.grid_faces
    assert fx.shape == (nx + 1, ny, nz) and fy.shape == (nx, ny + 1, nz) and fz.shape == (nx, ny, nz + 1)
    # Cell velocity is the mean of the two faces of a cell.
    assert np.allclose(sim.grid_velocity[..., 0], 0.5 * (fx[1:] + fx[:-1]))
    assert sim.grid_pressure.shape == (nx, ny, nz)
    assert sim.smoke.shape == (nx, ny, nz) and sim.smoke.max() > 0
    v = sim.vortices()
    k = len(v["radius"])
    assert v["position"].shape == (k, 3) and v["vorticity"].shape == (k, 3)
    assert v["energy"].shape == (k,) and v["age"].shape == (k,)
    with pytest.raises(ValueError, match="no SPH fluid"):
        sim.position


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
    with pytest.raises(ValueError, match="no grid"):
        sim.grid_pressure
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
