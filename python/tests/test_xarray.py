"""xarray input: axes by name, the same surfaces as numpy input, and typed refusals of what would
give a wrong surface (axes that are not axes, degrees with m/s, depth pointing down, times)."""

import numpy as np
import pytest

import orthofront
from test_module import helix_grid, shear_series

xr = pytest.importorskip("xarray", reason="SKIPPED: no xarray (Debian: python3-xarray)")

SEED = [[0.5, 0.0, 0.2], [1.5, 0.0, 0.2]]


def helix_dataset():
    values, origin, spacing = helix_grid(9)
    nz, ny, nx, _ = values.shape
    coords = {"z": origin[2] + spacing[2] * np.arange(nz), "y": origin[1] + spacing[1] * np.arange(ny),
              "x": origin[0] + spacing[0] * np.arange(nx)}
    dims = ("z", "y", "x")
    ds = xr.Dataset({name: (dims, values[..., i], {"units": "m s-1"})
                     for i, name in enumerate("uvw")}, coords=coords)
    for name in coords:
        ds[name].attrs["units"] = "m"
    return ds, values, origin, spacing


def numpy_surface():
    _, values, origin, spacing = helix_dataset()
    field = orthofront.Field(values, origin=origin, spacing=spacing)
    return orthofront.stream_surface(field, SEED, seed_count=8, edge=0.15, steps=20)


def test_a_dataset_gives_the_numpy_surface():
    ds, _, _, _ = helix_dataset()
    surface = orthofront.stream_surface(ds, SEED, seed_count=8, edge=0.15, steps=20)
    reference = numpy_surface()
    assert len(reference.vertices) > 50
    assert np.array_equal(surface.vertices, reference.vertices)
    assert np.array_equal(surface.faces, reference.faces)


def test_axes_are_taken_by_name_not_by_position_and_turned_round_where_they_decrease():
    ds, _, _, _ = helix_dataset()
    shuffled = ds.transpose("x", "z", "y")  # the same data, its dimensions in another order
    reference = numpy_surface()
    surface = orthofront.stream_surface(shuffled, SEED, seed_count=8, edge=0.15, steps=20)
    assert np.array_equal(surface.vertices, reference.vertices)
    flipped = ds.isel(y=slice(None, None, -1))  # y decreasing, as many files store latitude
    surface = orthofront.stream_surface(flipped, SEED, seed_count=8, edge=0.15, steps=20)
    assert np.array_equal(surface.vertices, reference.vertices)


def test_a_vector_dataarray_with_a_component_dimension():
    ds, _, _, _ = helix_dataset()
    array = ds.to_array("component").transpose("component", "y", "x", "z")
    surface = orthofront.stream_surface(array, SEED, seed_count=8, edge=0.15, steps=20)
    assert np.array_equal(surface.vertices, numpy_surface().vertices)


def test_dimensions_that_are_no_axis_are_refused():
    ds, _, _, _ = helix_dataset()
    with_member = ds.expand_dims(member=2)
    with pytest.raises(orthofront.AxisOrderError, match="member"):
        orthofront.from_xarray(with_member)
    with pytest.raises(orthofront.AxisOrderError, match="variables"):
        orthofront.from_xarray(ds.rename({"u": "a", "v": "b", "w": "c"}))


def test_degrees_with_metres_per_second_and_depth_pointing_down_are_refused():
    ds, _, _, _ = helix_dataset()
    lonlat = ds.rename({"x": "lon", "y": "lat"})
    lonlat["lon"].attrs["units"] = "degrees_east"
    lonlat["lat"].attrs["units"] = "degrees_north"
    with pytest.raises(orthofront.UnitsError, match="degrees_east.*m s-1"):
        orthofront.from_xarray(lonlat)
    # Velocities that state no unit could be either: refused too; degrees per second are taken.
    for name in "uvw":
        lonlat[name].attrs.pop("units")
    with pytest.raises(orthofront.UnitsError, match="no stated unit"):
        orthofront.from_xarray(lonlat)
    for name in "uvw":
        lonlat[name].attrs["units"] = "degrees s-1"
    assert isinstance(orthofront.from_xarray(lonlat), orthofront.Field)
    down = ds.rename({"z": "depth"})
    down["depth"].attrs["positive"] = "down"
    with pytest.raises(orthofront.UnitsError, match="positive down"):
        orthofront.from_xarray(down)


def shear_dataset(times):
    values, _, origin, spacing = shear_series()
    steps, ny, nx, _ = values.shape
    coords = {"time": times, "y": origin[1] + spacing[1] * np.arange(ny),
              "x": origin[0] + spacing[0] * np.arange(nx)}
    return xr.Dataset({"u": (("time", "y", "x"), values[..., 0]),
                       "v": (("time", "y", "x"), values[..., 1])}, coords=coords)


def test_datetime64_times_become_seconds_from_a_stated_reference():
    values, times, origin, spacing = shear_series()
    dates = np.datetime64("2020-01-01T00:00:00") + (times * 1000).astype("timedelta64[ms]")
    series = orthofront.from_xarray(shear_dataset(dates))
    assert series.time_reference == "seconds since 2020-01-01T00:00:00"
    assert np.allclose(series.times, times)
    seed = [[0.2, 0.2], [0.2, 0.6]]
    reference = orthofront.path_surface(
        orthofront.Series(values, times, origin=origin, spacing=spacing), seed, seed_count=9,
        edge=0.1, t0=0.0, t1=2.0)
    surface = orthofront.path_surface(series, seed, seed_count=9, edge=0.1, t0=dates[0],
                                      t1=np.datetime64("2020-01-01T00:00:02"))
    assert np.array_equal(surface.vertices, reference.vertices)
    with pytest.raises(orthofront.TimeError, match="plain seconds"):
        orthofront.path_surface(orthofront.Series(values, times, origin=origin, spacing=spacing),
                                seed, t0=dates[0])


def test_cf_numbers_since_a_date_and_object_times():
    values, times, _, _ = shear_series()
    ds = shear_dataset(times / 3600.0)
    ds["time"].attrs["units"] = "hours since 1950-01-01"
    series = orthofront.from_xarray(ds)
    assert series.time_reference == "seconds since 1950-01-01"
    assert np.allclose(series.times, times)
    objects = shear_dataset(np.array([object()] * len(times), dtype=object))
    with pytest.raises(orthofront.TimeError, match="objects"):
        orthofront.from_xarray(objects)
