"""Opens every VTK frame and every XDMF series of a run folder with VTK's own readers (the ones
ParaView uses) and checks what they read against the HDF5 frames, read by h5py.

Run by tests/vtk_readers.rs: python3 tests/vtk_readers.py RUN_FOLDER. Prints one line per
file and exits non-zero on the first disagreement.
"""

import pathlib
import sys

import h5py
import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkCommand
from vtkmodules.vtkCommonDataModel import vtkCompositeDataSet
from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline
from vtkmodules.vtkFiltersCore import vtkCellCenters
from vtkmodules.vtkIOXdmf2 import vtkXdmfReader
from vtkmodules.vtkIOXML import vtkXMLImageDataReader, vtkXMLPolyDataReader


class Errors:
    """Collects the errors and warnings a reader reports instead of printing them."""

    def __init__(self, reader):
        self.messages = []
        for event in (vtkCommand.ErrorEvent, vtkCommand.WarningEvent):
            reader.AddObserver(event, self.note)

    def note(self, _obj, _event, message=None):
        self.messages.append(str(message))

    note.CallDataType = "string0"


def read(reader, path):
    errors = Errors(reader)
    reader.SetFileName(str(path))
    reader.Update()
    assert not errors.messages, f"{path}: {errors.messages}"
    return reader.GetOutput()


def arrays(data):
    return {data.GetArrayName(i): vtk_to_numpy(data.GetArray(i)) for i in range(data.GetNumberOfArrays())}


def close(a, b, what):
    """Equal to f32 rounding: the VTK frames are f32 by default, HDF5 keeps f64."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    assert a.shape == b.shape, f"{what}: shapes {a.shape} and {b.shape}"
    assert np.array_equal(a, b.astype(a.dtype)) or np.allclose(a, b.astype(np.float32), rtol=1e-6, atol=1e-30), what


def index_of(run, kind):
    """The HDF5 index of one kind of frame: `KIND_frames.h5` in a coupled run, else `frames.h5`
    if it holds that kind (grid files carry a `format` attribute)."""
    for name in (f"{kind}_frames.h5", "frames.h5"):
        path = run / name
        if path.exists():
            with h5py.File(path, "r") as f:
                if "frames" in f and ("format" in f.attrs) == (kind == "grid"):
                    return path
    return None


def frame_files(index):
    with h5py.File(index, "r") as f:
        names = sorted(f["frames"].keys())
    return [index.with_name(f"{index.stem}_{k:06d}.h5") for k in range(len(names))]


def check_vtk_files(run):
    """Every .vtp and .vti opens; the last particle and grid frame hold the HDF5 values."""
    for path in sorted(run.glob("*.vt[ip]")):
        if path.suffix == ".vtp":
            out = read(vtkXMLPolyDataReader(), path)
            n = out.GetNumberOfPoints()
            assert out.GetNumberOfVerts() == n, path
            data = arrays(out.GetPointData())
        else:
            out = read(vtkXMLImageDataReader(), path)
            n = out.GetNumberOfCells()
            data = arrays(out.GetCellData())
        for name, values in data.items():
            assert len(values) == n, f"{path}: {name} has {len(values)} tuples for {n}"
        print(path.name, n, sorted(data))
    for kind in ("particles", "grid"):
        files = sorted(run.glob(f"{kind}_[0-9]*.vt[ip]"))
        index = index_of(run, kind)
        if not files or index is None:
            continue
        last, h5 = files[-1], frame_files(index)[len(files) - 1]
        with h5py.File(h5, "r") as f:
            if kind == "particles":
                out = read(vtkXMLPolyDataReader(), last)
                close(vtk_to_numpy(out.GetPoints().GetData()), f["position"][()], f"{last} points")
                for name, values in arrays(out.GetPointData()).items():
                    close(values, f[name][()], f"{last} {name}")
            else:
                out = read(vtkXMLImageDataReader(), last)
                for name, values in arrays(out.GetCellData()).items():
                    stored = f[name][()]
                    # VTK runs x fastest: the transpose of the [i, j, k] C order.
                    stored = np.transpose(stored, (2, 1, 0) + tuple(range(3, stored.ndim)))
                    close(values, stored.reshape(values.shape), f"{last} {name}")
        print(last.name, "matches", h5.name)


def blocks(output):
    it = output.NewIterator()
    it.InitTraversal()
    while not it.IsDoneWithTraversal():
        yield it.GetCurrentMetaData().Get(vtkCompositeDataSet.NAME()), it.GetCurrentDataObject()
        it.GoToNextItem()


def check_xdmf(xmf):
    """Every time step of the series reads; every block equals its HDF5 datasets, and every grid
    cell's value sits at that cell's centre."""
    reader = vtkXdmfReader()
    errors = Errors(reader)
    reader.SetFileName(str(xmf))
    reader.UpdateInformation()
    info = reader.GetOutputInformation(0)
    times = list(info.Get(vtkStreamingDemandDrivenPipeline.TIME_STEPS()) or [])
    assert times, f"{xmf}: no time steps"
    grids = sets = 0
    for t in times:
        reader.UpdateTimeStep(t)
        assert not errors.messages, f"{xmf} at t = {t}: {errors.messages}"
        for name, block in blocks(reader.GetOutputDataObject(0)):
            base = name.split("[")[0]
            index = xmf.with_suffix(".h5")
            with h5py.File(index, "r") as f:
                # A coupled run's frames.xmf includes the two series checked on their own.
                own = "frames" in f
            if block.IsA("vtkStructuredGrid"):
                if not own:
                    continue
                grids += 1
                with h5py.File(index, "r") as f:
                    origin, h = f.attrs["origin"], f.attrs["spacing"]
                centres = vtkCellCenters()
                centres.SetInputData(block)
                centres.Update()
                c = vtk_to_numpy(centres.GetOutput().GetPoints().GetData())
                ijk = np.rint((c - origin) / h - 0.5).astype(int)
                assert np.allclose((ijk + 0.5) * h + origin, c, atol=1e-9 * max(1.0, h)), f"{xmf}: cell centres off the lattice"
                k = times.index(t)
                with h5py.File(frame_files(index)[k], "r") as f:
                    for aname, values in arrays(block.GetCellData()).items():
                        stored = f[aname][()][ijk[:, 0], ijk[:, 1], ijk[:, 2]]
                        close(values, stored, f"{xmf} t = {t} {aname}")
            else:
                n = block.GetNumberOfPoints()
                assert block.GetNumberOfCells() == n, f"{xmf}: {name} vertices"
                if not own:
                    continue
                # The frame's own particles lie at the file's root, a set in its group.
                group = "" if base == "particles" else f"{base}/"
                sets += base != "particles"
                with h5py.File(frame_files(index)[times.index(t)], "r") as f:
                    points = vtk_to_numpy(block.GetPoints().GetData())
                    close(points, f[f"{group}position"][()], f"{xmf} t = {t} {name}")
                    for aname, values in arrays(block.GetPointData()).items():
                        close(values, f[f"{group}{aname}"][()], f"{xmf} t = {t} {aname}")
    print(xmf.name, len(times), "times", grids, "grid blocks", sets, "particle set blocks")


def full_tensor(six):
    """A symmetric tensor's six components (xx, yy, zz, xy, yz, xz) as the nine VTK's XDMF
    reader expands `Tensor6` to, row by row."""
    xx, yy, zz, xy, yz, xz = (six[..., c] for c in range(6))
    return np.stack([xx, xy, xz, xy, yy, yz, xz, yz, zz], axis=-1)


def check_statistics(h5):
    """A statistics file: its .vti and .xmf open in VTK's readers and hold the HDF5 values at
    every cell (NaN where no sample found fluid), the stress tensor as ParaView reads it."""
    with h5py.File(h5, "r") as f:
        assert f.attrs["format"] == "eddy-statistics", h5
        stored = {name: f[name][()] for name in f}
        origin, h = f.attrs["origin"], f.attrs["spacing"]
    assert sorted(stored) == ["k", "mean_enstrophy", "mean_velocity", "mean_vorticity", "reynolds_stress", "samples"], sorted(stored)
    assert stored["reynolds_stress"].shape[-1] == 6, h5
    k = 0.5 * (stored["reynolds_stress"][..., 0] + stored["reynolds_stress"][..., 1] + stored["reynolds_stress"][..., 2])
    assert np.allclose(k, stored["k"], rtol=1e-12, equal_nan=True), f"{h5}: k is not half the stress trace"
    vti = h5.with_suffix(".vti")
    if vti.exists():
        out = read(vtkXMLImageDataReader(), vti)
        for name, values in arrays(out.GetCellData()).items():
            s = np.transpose(stored[name], (2, 1, 0) + tuple(range(3, stored[name].ndim)))
            s = s.reshape(values.shape)
            assert np.allclose(values, s.astype(np.float32), rtol=1e-6, atol=1e-30, equal_nan=True), f"{vti} {name}"
    reader = vtkXdmfReader()
    block = read(reader, h5.with_suffix(".xmf"))
    if not block.IsA("vtkStructuredGrid"):
        block = next(b for _, b in blocks(block))
    centres = vtkCellCenters()
    centres.SetInputData(block)
    centres.Update()
    c = vtk_to_numpy(centres.GetOutput().GetPoints().GetData())
    ijk = np.rint((c - origin) / h - 0.5).astype(int)
    for name, values in arrays(block.GetCellData()).items():
        s = stored[name][ijk[:, 0], ijk[:, 1], ijk[:, 2]]
        if name == "reynolds_stress":
            s = full_tensor(s)
        assert np.allclose(values, s, rtol=0, atol=0, equal_nan=True), f"{h5.with_suffix('.xmf')} {name}"
    print(h5.name, "statistics", block.GetNumberOfCells(), "cells")


def main():
    run = pathlib.Path(sys.argv[1])
    check_vtk_files(run)
    xmfs = sorted(x for x in run.glob("*.xmf") if not x.stem.endswith("statistics"))
    assert xmfs or not list(run.glob("*frames.h5")), f"{run}: HDF5 frames without XDMF"
    for xmf in xmfs:
        check_xdmf(xmf)
    for h5 in sorted(run.glob("*statistics.h5")):
        check_statistics(h5)


if __name__ == "__main__":
    main()
