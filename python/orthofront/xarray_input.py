"""xarray input: a Dataset (one variable per velocity component) or a DataArray (a component
dimension) becomes a Field or, with a time dimension, a Series.

Axes are found by name and attributes, never by position: a coordinate's ``axis`` attribute
("X", "Y", "Z", "T"), its ``standard_name`` (longitude, latitude, depth, time, ...), then its name
(x, lon, longitude; y, lat, latitude; z, depth, lev, level, height; time, t). Coordinates that
decrease are turned round (with the data). Uniform coordinates become origin and spacing, others
rectilinear axes. What would give a silently wrong surface is refused with a typed error:
``AxisOrderError`` for a dimension that is no axis, ``UnitsError`` for positions in degrees with
velocities not in degrees per second (metres per second, or no unit stated) or a depth axis that
points down, ``TimeError`` for times that
are not numbers, datetime64 or CF "UNITS since DATE" values.

Times become seconds since a reference, ``time_reference`` (default: the first time), which the
returned Series keeps as ``series.time_reference`` ("seconds since 2020-01-01T00:00:00"); path
and streak surfaces of such a series take t0, t1, release and frames as datetime64 too.
"""

import re

import numpy as np

from ._orthofront import Field, Series

__all__ = ["AxisOrderError", "UnitsError", "TimeError", "from_xarray", "is_xarray",
           "time_seconds"]


class AxisOrderError(ValueError):
    """A dimension of the data is not an axis orthofront knows (x, y, z, time, components)."""


class UnitsError(ValueError):
    """Units that would make the surface wrong (degrees with m/s, depth pointing down)."""


class TimeError(ValueError):
    """Times that are not numbers, datetime64 values or CF "UNITS since DATE" numbers."""


_NAMES = {
    "x": ("x", "lon", "long", "longitude", "nav_lon", "xc", "x_rho", "xt_ocean", "xu_ocean"),
    "y": ("y", "lat", "latitude", "nav_lat", "yc", "y_rho", "yt_ocean", "yu_ocean"),
    "z": ("z", "depth", "lev", "level", "height", "altitude", "deptht", "depthu", "st_ocean",
          "s_rho"),
    "t": ("t", "time", "times", "time_counter", "ocean_time"),
}
_STANDARD = {
    "x": ("longitude", "grid_longitude", "projection_x_coordinate"),
    "y": ("latitude", "grid_latitude", "projection_y_coordinate"),
    "z": ("depth", "height", "altitude", "ocean_sigma_coordinate", "model_level_number"),
    "t": ("time",),
}
_COMPONENT_DIMS = ("component", "components", "vector", "dim", "uvw", "xyz")
_COMPONENT_NAMES = [("u", "v", "w"), ("U", "V", "W"), ("uo", "vo", "wo"), ("vx", "vy", "vz"),
                    ("velocity_x", "velocity_y", "velocity_z"), ("ux", "uy", "uz")]
_COMPONENT_STANDARD = [
    ("eastward_sea_water_velocity", "northward_sea_water_velocity", "upward_sea_water_velocity"),
    ("eastward_wind", "northward_wind", "upward_air_velocity"),
    ("x_wind", "y_wind", "upward_air_velocity"),
    ("sea_water_x_velocity", "sea_water_y_velocity", "upward_sea_water_velocity"),
]
_DEGREES = re.compile(r"^degrees?(_?(east|north|e|n))?$", re.IGNORECASE)
_DEGREES_PER_SECOND = re.compile(r"^degrees?(_?(east|north|e|n))?\s*(/\s*s|s-1|s\^-1|s\*\*-1)$",
                                 re.IGNORECASE)
_SINCE = re.compile(r"^\s*(\w+)\s+since\s+(.+?)\s*$", re.IGNORECASE)
_SECONDS_PER = {"s": 1, "sec": 1, "secs": 1, "second": 1, "seconds": 1, "min": 60, "mins": 60,
                "minute": 60, "minutes": 60, "h": 3600, "hr": 3600, "hrs": 3600, "hour": 3600,
                "hours": 3600, "d": 86400, "day": 86400, "days": 86400}


def is_xarray(value):
    """True for an xarray Dataset or DataArray (without importing xarray)."""
    return type(value).__module__.split(".")[0] == "xarray" and hasattr(value, "dims")


def _role(data, dim):
    """The axis a dimension stands for ("x", "y", "z", "t"), or None."""
    coord = data.coords.get(dim)
    attrs = coord.attrs if coord is not None else {}
    axis = str(attrs.get("axis", "")).upper()
    if axis in ("X", "Y", "Z", "T"):
        return axis.lower()
    standard = str(attrs.get("standard_name", "")).lower()
    for role, names in _STANDARD.items():
        if standard in names:
            return role
    if coord is not None and np.issubdtype(coord.dtype, np.datetime64):
        return "t"
    for role, names in _NAMES.items():
        if str(dim).lower() in names:
            return role
    return None


def _components(data, u, v, w):
    """The velocity components as DataArrays, in x, y(, z) order."""
    if hasattr(data, "data_vars"):  # a Dataset
        names = [n for n in (u, v, w) if n is not None]
        if not names:
            variables = list(data.data_vars)
            for group in _COMPONENT_NAMES:
                if group[0] in variables and group[1] in variables:
                    names = [n for n in group if n in variables]
                    break
            else:
                by_standard = {str(data[n].attrs.get("standard_name", "")): n for n in variables}
                for group in _COMPONENT_STANDARD:
                    if group[0] in by_standard and group[1] in by_standard:
                        names = [by_standard[s] for s in group if s in by_standard]
                        break
        if len(names) < 2:
            raise AxisOrderError("cannot tell the velocity components among the variables %s: "
                                 "name them (u=, v=, w=)" % list(data.data_vars))
        for name in names:
            if name not in data.data_vars:
                raise AxisOrderError("the Dataset has no variable '%s' (it has %s)"
                                     % (name, list(data.data_vars)))
        return [data[n] for n in names]
    # A DataArray: one dimension holds the components.
    candidates = [d for d in data.dims if _role(data, d) is None]
    named = [d for d in candidates if str(d).lower() in _COMPONENT_DIMS]
    dims = named or [d for d in candidates if data.sizes[d] in (2, 3)]
    if len(dims) != 1 or data.sizes[dims[0]] not in (2, 3):
        raise AxisOrderError("the DataArray's dimensions %s: expected x, y(, z)(, time) and one "
                             "dimension of 2 or 3 velocity components (e.g. 'component')"
                             % list(data.dims))
    return [data.isel({dims[0]: i}) for i in range(data.sizes[dims[0]])]


def _check_units(components, coords):
    """UnitsError for positions in degrees unless the velocities are in degrees per second too:
    metres per second, or velocities that state no unit, would move degrees by metres."""
    degree_axes = [role for role, c in coords.items()
                   if c is not None and _DEGREES.match(str(c.attrs.get("units", "")).strip())]
    if not degree_axes:
        return
    speed_units = [str(c.attrs.get("units", "")).strip() for c in components]
    if all(_DEGREES_PER_SECOND.match(u) for u in speed_units):
        return
    raise UnitsError(
        "positions in degrees (%s) and velocities in %s: the surface would move degrees by "
        "metres. Give the coordinates in metres, velocities in degrees per second (units "
        "'degrees s-1'), or open the NetCDF file with "
        "orthofront.Series.open('FILE.nc:u,v,lonlat=metres')"
        % (", ".join("%s: %s" % (r, coords[r].attrs.get("units")) for r in degree_axes),
           ", ".join(sorted({u or "no stated unit" for u in speed_units}))))


def time_seconds(values, reference=None, units=""):
    """Times as seconds since `reference`, and the reference as text.

    values: datetime64 (reference: a datetime64 or its text; default the first value),
    timedelta64 (seconds as given), numbers with CF units "UNITS since DATE" (seconds since
    DATE; a reference given is refused unless it is DATE) or plain numbers (taken as seconds).
    """
    values = np.asarray(values)
    if np.issubdtype(values.dtype, np.datetime64):
        origin = values[0] if reference is None else np.datetime64(reference)
        seconds = (values - origin) / np.timedelta64(1, "s")
        whole = origin.astype("datetime64[s]")
        text = np.datetime_as_string(whole if whole == origin else origin)
        return seconds.astype(np.float64), "seconds since %s" % text
    if np.issubdtype(values.dtype, np.timedelta64):
        return (values / np.timedelta64(1, "s")).astype(np.float64), "seconds"
    if values.dtype == object:
        raise TimeError("times are objects (%s), e.g. cftime dates of a non-standard calendar: "
                        "give numbers of seconds (xarray: decode_times=False keeps the file's "
                        "'UNITS since DATE' numbers, which this reads)" % type(values.flat[0]).__name__)
    if not np.issubdtype(values.dtype, np.number):
        raise TimeError("times of type %s are neither numbers nor datetime64" % values.dtype)
    match = _SINCE.match(str(units))
    if match:
        unit = match.group(1).lower()
        if unit not in _SECONDS_PER:
            raise TimeError("time units '%s': unknown unit '%s'" % (units, match.group(1)))
        if reference is not None and str(reference) != match.group(2):
            raise TimeError("time_reference %s: the times are '%s'; give no reference or that "
                            "date" % (reference, units))
        return (values.astype(np.float64) * _SECONDS_PER[unit],
                "seconds since %s" % match.group(2))
    if units and str(units).lower() not in _SECONDS_PER:
        raise TimeError("time units '%s': expected seconds or 'UNITS since DATE'" % units)
    return values.astype(np.float64) * _SECONDS_PER.get(str(units).lower(), 1), "seconds"


def _axis(coord, role, size):
    """(values increasing, reversed?) of a coordinate, or None where the dimension has none."""
    if coord is None:
        return None, False
    values = np.asarray(coord.values, dtype=np.float64)
    if values.ndim != 1 or len(values) != size:
        raise AxisOrderError("the %s coordinate '%s' is not one-dimensional: a curvilinear grid "
                             "(2D lon/lat) cannot be read as a rectilinear one" % (role, coord.name))
    if size > 1 and np.all(np.diff(values) < 0):
        return values[::-1], True
    if size > 1 and not np.all(np.diff(values) > 0):
        raise AxisOrderError("the %s coordinate '%s' neither increases nor decreases throughout"
                             % (role, coord.name))
    return values, False


def from_xarray(data, u=None, v=None, w=None, zero_is_no_data=True, time_reference=None):
    """A Field (no time dimension) or a Series (a time dimension) from an xarray object.

    data: a Dataset with a variable per component (u, v, w name them; by default u/v/w, U/V/W,
    uo/vo/wo or CF standard names) or a DataArray with a component dimension. A 2D flow has x
    and y (two components); a 3D flow x, y and z (three). zero_is_no_data: as for Field.
    time_reference: a datetime64 (or its text) the series' seconds count from.
    """
    components = _components(data, u, v, w)
    first = components[0]
    roles = {}
    for dim in first.dims:
        role = _role(first, dim)
        if role is None or role in roles.values():
            raise AxisOrderError(
                "dimension '%s' of '%s' is %s: the dimensions %s must be x, y(, z)(, time) "
                "(by the coordinates' axis or standard_name attributes, or by name)"
                % (dim, first.name, "a second " + role if role else "no axis", list(first.dims)))
        roles[dim] = role
    for c in components[1:]:
        if set(c.dims) != set(first.dims):
            raise AxisOrderError("the components have different dimensions: %s and %s"
                                 % (list(first.dims), list(c.dims)))
    dim_of = {role: dim for dim, role in roles.items()}
    spatial = [r for r in ("x", "y", "z") if r in dim_of]
    if "x" not in dim_of or "y" not in dim_of:
        raise AxisOrderError("no x and y among the dimensions %s" % list(first.dims))
    if len(components) != len(spatial):
        raise AxisOrderError("%d velocity components for the %d spatial axes %s"
                             % (len(components), len(spatial), spatial))
    coords = {r: first.coords.get(dim_of[r]) for r in spatial}
    _check_units(components, coords)
    if "z" in coords and coords["z"] is not None:
        if str(coords["z"].attrs.get("positive", "")).lower() == "down":
            raise UnitsError("the z axis '%s' is positive down: give z positive up (z = -%s, "
                             "its data reversed with it) and the vertical velocity positive up"
                             % (dim_of["z"], dim_of["z"]))
    order = ([dim_of["t"]] if "t" in dim_of else []) + [dim_of[r] for r in reversed(spatial)]
    stacked = np.stack([np.asarray(c.transpose(*order).values, dtype=np.float32)
                        for c in components], axis=-1)
    axes, uniform = [], True
    for r in spatial:
        values, reversed_axis = _axis(coords[r], r, first.sizes[dim_of[r]])
        if values is None:
            values = np.arange(first.sizes[dim_of[r]], dtype=np.float64)
        if reversed_axis:
            position = order.index(dim_of[r])
            stacked = np.flip(stacked, axis=position)
        axes.append(values)
        steps = np.diff(values)
        uniform = uniform and (len(steps) == 0 or np.allclose(steps, steps[0], rtol=1e-6, atol=0))
    stacked = np.ascontiguousarray(stacked)
    grid = dict(origin=[a[0] for a in axes], spacing=[a[1] - a[0] for a in axes]) if uniform \
        else dict(axes=[list(a) for a in axes])
    if "t" not in dim_of:
        return Field(stacked, zero_is_no_data=zero_is_no_data, **grid)
    time = first.coords.get(dim_of["t"])
    raw = time.values if time is not None else np.arange(first.sizes[dim_of["t"]])
    seconds, reference = time_seconds(raw, time_reference,
                                      time.attrs.get("units", "") if time is not None else "")
    series = _ReferencedSeries(stacked, seconds, zero_is_no_data=zero_is_no_data, **grid)
    series.time_reference = reference
    series.time_origin = None if not np.issubdtype(np.asarray(raw).dtype, np.datetime64) else (
        np.asarray(raw)[0] if time_reference is None else np.datetime64(time_reference))
    return series


class _ReferencedSeries(Series):
    """A Series whose times count seconds from time_reference (time_origin as datetime64)."""

    time_reference = "seconds"
    time_origin = None


def times_in_seconds(series, options, names):
    """The options among `names` given as datetime64 (or lists of them), as seconds of `series`."""
    origin = getattr(series, "time_origin", None)
    for name in names:
        value = options.get(name)
        if value is None:
            continue
        items = value if isinstance(value, (list, tuple, np.ndarray)) else [value]
        if not any(isinstance(i, np.datetime64) for i in items):
            continue
        if origin is None:
            raise TimeError("%s is a datetime64 but the series' times are plain seconds: give "
                            "seconds" % name)
        seconds = [float((np.datetime64(i) - origin) / np.timedelta64(1, "s")) for i in items]
        options[name] = seconds if isinstance(value, (list, tuple, np.ndarray)) else seconds[0]
    return options
