"""The result files and figures of a command written at a fraction of their former cost with the
same content: the NetCDF-4 file of the direct h5py writer (:func:`flexrv.post.io.write_netcdf`)
against the file xarray's h5netcdf writer makes of the same dataset, object by object and
attribute by attribute; the datasets it does not take go through xarray; the figures drawn with
the cyclic collector paused, which frees every figure afterwards."""

from __future__ import annotations

import gc
import json
import weakref

import h5py
import numpy as np
import pytest
import xarray as xr

from flexrv.post.io import _netcdf4_writable, collector_paused, write_netcdf


def _ref_names(f, value):
    """An HDF5 attribute with object references as the names of the objects they point to."""
    if value.dtype.names == ("dataset", "dimension"):  # a dimension scale's REFERENCE_LIST
        return sorted((f[ref].name, int(axis)) for ref, axis in value)
    return [[f[ref].name for ref in refs] for refs in value]  # a variable's DIMENSION_LIST


def _dump(path) -> dict:
    """Every object of an HDF5 file: dtype, shape, maxshape, chunks, filters, fill value, values
    (bit for bit), whether it is a dimension scale, and every attribute with its stored type
    and shape (references resolved to names); the root's ``_NCProperties`` only as its prefix."""
    out = {}
    with h5py.File(path, "r") as f:
        for name, obj in [("/", f), *((k, f[k]) for k in f)]:
            attrs = {}
            for key in obj.attrs:
                aid = obj.attrs.get_id(key)
                value = obj.attrs[key]
                if key in ("REFERENCE_LIST", "DIMENSION_LIST"):
                    value = _ref_names(f, value)
                elif key == "_NCProperties":  # fixed-length ASCII text naming the writer
                    attrs[key] = (aid.dtype.kind, aid.shape, h5py.check_string_dtype(aid.dtype).encoding, value[:10])
                    continue
                else:
                    value = np.asarray(value).tolist()
                attrs[key] = (str(aid.dtype), aid.shape, h5py.check_string_dtype(aid.dtype), repr(value))
            entry = {"attrs": attrs}
            if name != "/":
                data = obj[()]
                entry.update(
                    dtype=str(obj.dtype),
                    shape=obj.shape,
                    maxshape=obj.maxshape,
                    chunks=obj.chunks,
                    compression=obj.compression,
                    fill=repr(obj.fillvalue),
                    values=data.tolist() if data.dtype.kind == "O" else data.tobytes(),
                    scale=h5py.h5ds.is_scale(obj.id),
                )
            out[name] = entry
    return out


def _results_like() -> xr.Dataset:
    """A dataset shaped like a run's results: an indexed time axis with units, plain dimensions
    (crank, pin), a text coordinate, float64/float32/int64 variables of one to three dimensions with NaN, text
    attributes (non-ASCII, JSON) and number attributes on the file and the variables."""
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 0.05, 1e-3)
    force = rng.random((t.size, 2, 5))
    force[3, 1, 2] = np.nan
    data = {
        "te": xr.Variable(("time",), rng.normal(size=t.size), {"units": "arcsec", "long_name": "TE ″"}),
        "crank_speed": xr.Variable(("time", "crank"), rng.normal(size=(t.size, 2)), {"units": "rad/s"}),
        "pin_force": xr.Variable(
            ("time", "crank", "pin"),
            force,
            {"units": "N", "long_name": "pin force", "summary_rows": json.dumps([["a", "N", "µ text", "max"]])},
        ),
        "pins_in_contact": xr.Variable(("time", "crank"), rng.integers(0, 5, (t.size, 2)), {"units": "1"}),
        "gap": xr.Variable(("pin",), np.linspace(0, 1, 5, dtype=np.float32), {"units": "m", "scale": 2}),
    }
    element = np.array(["first_stage_mesh", "pins", "µ-bearing"])
    data["share"] = xr.Variable(("element",), [20.0, 50.0, 30.0], {"units": "%"})
    coords = {"time": ("time", t, {"units": "s", "long_name": "time"}), "element": ("element", element)}
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update({"preset": "rv40e", "dt_s": 1e-3, "steady": 1, "ratio": np.float64(81.0), "note": "α – β"})
    return ds


def _both(ds, tmp_path):
    """The dataset written by write_netcdf and by xarray's h5netcdf writer."""
    direct, reference = tmp_path / "direct.nc", tmp_path / "xarray.nc"
    write_netcdf(ds, direct)
    ds.to_netcdf(reference, engine="h5netcdf")
    return direct, reference


def _assert_same_file(direct, reference) -> None:
    a, b = _dump(direct), _dump(reference)
    assert list(a) == list(b)  # the same objects in the same order
    for name in b:
        assert a[name] == b[name], name
    back, ref = xr.load_dataset(direct, engine="h5netcdf"), xr.load_dataset(reference, engine="h5netcdf")
    xr.testing.assert_identical(back, ref)
    assert list(back.variables) == list(ref.variables) and list(back.attrs) == list(ref.attrs)


def test_netcdf_direct_writer_makes_xarrays_file(tmp_path):
    """The direct writer's file equals xarray's h5netcdf file of the same dataset in every object
    (order, dtype, shape, layout, fill value, values bit for bit with NaN in place, dimension
    scales) and every attribute (stored type, shape, value; the scales' references by name);
    read back by xarray it is identical to the dataset written. The one difference allowed is
    the writer named in ``_NCProperties`` (its ``version=2`` prefix is compared)."""
    ds = _results_like()
    assert _netcdf4_writable(ds)
    direct, reference = _both(ds, tmp_path)
    _assert_same_file(direct, reference)
    xr.testing.assert_identical(xr.load_dataset(direct, engine="h5netcdf"), ds)
    with h5py.File(direct, "r") as f:
        assert f.attrs["_NCProperties"].decode().startswith("version=2,flexrv=")


@pytest.fixture(scope="module")
def run():
    """A 20 ms rigid rv40e run (every declared output; the figures' data)."""
    from flexrv.simulation import Simulation

    return Simulation("rv40e").run(t_end=0.02, dt=1e-4)


def test_netcdf_direct_writer_on_a_run(tmp_path, run):
    """A 20 ms rigid rv40e run's results (every declared output, the run's attributes) take the
    direct writer and give xarray's file (:func:`test_netcdf_direct_writer_makes_xarrays_file`);
    ``Results.load`` reads them back equal to the run in memory."""
    from flexrv.post.results import Results

    res = run
    assert _netcdf4_writable(res.ds)
    direct, reference = _both(res.ds, tmp_path)
    _assert_same_file(direct, reference)
    (tmp_path / "run").mkdir()
    direct.rename(tmp_path / "run" / "results.nc")
    back = Results.load(tmp_path / "run")
    xr.testing.assert_identical(back.ds, res.ds)


@pytest.mark.parametrize("case", ["date variable", "bool variable", "read from a file", "scalar", "list attribute"])
def test_netcdf_other_datasets_go_through_xarray(tmp_path, case):
    """Datasets the direct writer does not take (date or bool variables, a dataset carrying its
    file's encoding, a 0-d variable, an attribute that is a list) are written by xarray and read
    back identical to the dataset written."""
    ds = _results_like()
    if case == "date variable":
        ds["stamp"] = ("pin", np.arange(5).astype("datetime64[s]").astype("datetime64[ns]"))
    elif case == "bool variable":
        ds["contact"] = ("pin", np.array([True, False, True, True, False]))
    elif case == "read from a file":
        ds.to_netcdf(tmp_path / "src.nc", engine="h5netcdf")
        ds = xr.load_dataset(tmp_path / "src.nc", engine="h5netcdf")
    elif case == "scalar":
        ds["torque"] = ((), 3.0)
    else:
        ds.attrs["levels"] = [1.0, 2.0]
    assert not _netcdf4_writable(ds)
    write_netcdf(ds, tmp_path / "out.nc")
    xr.testing.assert_identical(xr.load_dataset(tmp_path / "out.nc", engine="h5netcdf"), ds)


def test_collector_paused_runs_no_collection_and_frees_afterwards():
    """Inside ``collector_paused`` the cyclic collector runs no pass (a callback counts them) while
    cyclic garbage is made; afterwards the collector is on again and one collection frees that
    garbage (a weak reference to it dies); a nested block leaves it as it found it."""
    passes = []

    def count(phase, info):
        if phase == "start":
            passes.append(info["generation"])

    class Node:
        pass

    gc.callbacks.append(count)
    try:
        with collector_paused():
            with collector_paused():
                pass
            assert not gc.isenabled()
            for _ in range(20000):  # cycles enough to trigger young collections ~30 times over
                a, b = Node(), Node()
                a.other, b.other = b, a
            probe = weakref.ref(a)
            del a, b
            inside = len(passes)
        assert inside == 0 and gc.isenabled()
        gc.collect()
        assert probe() is None
    finally:
        gc.callbacks.remove(count)


def _figures(run, folder, monkeypatch=None, reference=False) -> dict:
    """The TE, speeds, pin-force and spectrum figures of ``run`` written into ``folder``; with
    ``reference`` as matplotlib places titles and compresses PNGs by default (automatic title
    placement, zlib's default level). Returns name -> (Figure, pixels)."""
    from PIL import Image

    import flexrv.viz.plots as vp

    if reference:
        monkeypatch.setattr(vp, "TITLE_Y", None)
        monkeypatch.setattr(vp, "PNG_COMPRESSION", {})
    figs = {}
    save = vp._save

    def keep(fig, path):
        figs[path.stem] = fig
        return save(fig, path)

    monkeypatch.setattr(vp, "_save", keep)
    for name, plot in (("te", vp.plot_te), ("speeds", vp.plot_speeds), ("pins", vp.plot_pin_forces)):
        plot(run, folder / f"{name}.png")
    vp.plot_te_spectrum(run, folder / "spectrum.png")
    monkeypatch.setattr(vp, "_save", save)
    return {k: (f, np.asarray(Image.open(folder / f"{k}.png"))) for k, f in figs.items()}


def test_figures_fixed_titles_and_png_settings_keep_the_pixels(run, tmp_path, monkeypatch):
    """Titles fixed at the axes' top and the fast PNG settings leave every pixel as matplotlib's
    automatic title placement and default compression make them (reference: the same figures
    drawn with those defaults); the fast settings write the smaller-effort PNG (zlib level 1 is
    read back from nothing but the pixels, so only the pixels are compared)."""
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    ours = _figures(run, tmp_path / "a", monkeypatch)
    with monkeypatch.context() as m:
        ref = _figures(run, tmp_path / "b", m, reference=True)
    assert set(ours) == set(ref) == {"te", "speeds", "pins", "spectrum"}
    for name in ours:
        a, b = ours[name][1], ref[name][1]
        assert a.shape == b.shape and np.array_equal(a, b), name


def test_fixed_layout_keeps_every_label_in_the_figure_near_tight_layout(run, tmp_path, monkeypatch):
    """The figures laid out from their size (:func:`flexrv.viz.plots._fixed_layout`): every visible
    text (tick labels, axis labels, titles, legends, the spectrum's key) lies inside the figure,
    no two panels overlap, and every axes edge is within 0.2 in of where matplotlib's
    ``tight_layout`` puts it (reference: the same figure laid out by ``tight_layout``); the data
    drawn is the run's (TE line)."""
    import flexrv.viz.plots as vp

    figs = _figures(run, tmp_path, monkeypatch)
    for name, (fig, _) in figs.items():
        renderer = fig.canvas.get_renderer()
        inches = fig.get_tightbbox(renderer)  # everything drawn: ticks, labels, titles, legends, texts
        w, h = fig.get_size_inches()
        assert inches.x0 >= -0.01 and inches.y0 >= -0.01 and inches.x1 <= w + 0.01 and inches.y1 <= h + 0.01, name
        boxes = [ax.get_tightbbox(renderer) for ax in fig.axes]
        for i in range(len(boxes)):
            for j in range(i + 1, len(boxes)):
                inter = boxes[i].intersection(boxes[i], boxes[j])
                assert inter is None or inter.width * inter.height < 4.0 or name == "pins", name
    assert np.allclose(figs["te"][0].axes[0].lines[0].get_ydata(), run["te"].values)
    tight = {}
    with monkeypatch.context() as m:
        m.setattr(vp, "_fixed_layout", lambda fig, **kw: fig.tight_layout())
        for name, (fig, _) in _figures(run, tmp_path, m).items():
            tight[name] = [ax.get_position() for ax in fig.axes]
    for name in ("te", "speeds", "spectrum"):
        fig = figs[name][0]
        w, h = fig.get_size_inches()
        for ax, ref in zip(fig.axes, tight[name]):
            p = ax.get_position()
            diffs = [(p.x0 - ref.x0) * w, (p.x1 - ref.x1) * w, (p.y0 - ref.y0) * h, (p.y1 - ref.y1) * h]
            assert max(abs(d) for d in diffs) < 0.2, (name, diffs)
