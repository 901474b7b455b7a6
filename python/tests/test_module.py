"""The Python module: fields from numpy and files, surfaces as arrays, the CLI's options."""

import os
import signal
import threading
import time

import numpy as np
import pytest

import orthofront
from orthofront import preview
from conftest import run_cli, write_vti


def helix_grid(n=17):
    """v = (-y, x, 1) on [-2, 2]^2 x [0, 4]: linear, so the trilinear grid field is exact."""
    axis = np.linspace(-2.0, 2.0, n)
    z = np.linspace(0.0, 4.0, n)
    zz, yy, xx = np.meshgrid(z, axis, axis, indexing="ij")
    values = np.stack([-yy, xx, np.ones_like(xx)], axis=-1).astype(np.float32)
    spacing = (axis[1] - axis[0], axis[1] - axis[0], z[1] - z[0])
    return values, (-2.0, -2.0, 0.0), spacing


def test_version_and_types():
    assert orthofront.__version__.count(".") == 2
    values, origin, spacing = helix_grid()
    field = orthofront.Field(values, origin=origin, spacing=spacing)
    assert "numpy" in repr(field)


def test_stream_surface_from_numpy_is_a_helicoid():
    values, origin, spacing = helix_grid()
    field = orthofront.Field(values, origin=origin, spacing=spacing)
    seed = np.array([[0.5, 0.0, 0.2], [1.5, 0.0, 0.2]])
    surface = orthofront.stream_surface(field, seed, seed_count=11, edge=0.1, steps=30)
    assert surface.report["complete"]
    assert surface.vertices.shape[1] == 3 and len(surface.vertices) > 200
    assert surface.faces.shape[1] == 4
    assert surface.quad_count > 0.9 * len(surface.faces)
    # Rotation about z keeps every stream line on its radius; the seed parameter s gives it.
    radius = np.hypot(surface.vertices[:, 0], surface.vertices[:, 1])
    expected = 0.5 + surface.attributes["s"]
    assert np.max(np.abs(radius - expected)) < 1e-6
    # dz/dt = 1 along every stream line.
    assert np.max(np.abs(surface.vertices[:, 2] - 0.2 - surface.attributes["time"])) < 1e-6


def test_numpy_field_gives_the_mesh_of_the_same_grid_read_from_a_file(tmp_path, orthofront_binary):
    values, origin, spacing = helix_grid(9)
    vti = tmp_path / "helix.vti"
    write_vti(vti, values, origin, spacing)
    options = dict(seed_count=8, edge=0.15, steps=20)
    from_numpy = orthofront.stream_surface(orthofront.Field(values, origin=origin, spacing=spacing),
                                           "line:0.5,0,0.2:1.5,0,0.2", **options)
    from_file = orthofront.stream_surface(str(vti), "line:0.5,0,0.2:1.5,0,0.2", **options)
    assert np.array_equal(from_numpy.vertices, from_file.vertices)
    assert np.array_equal(from_numpy.faces, from_file.faces)
    # ... and the command line with the same options writes that mesh too.
    out = tmp_path / "cli.vtp"
    run_cli(orthofront_binary, "stream", "--field", vti, "--seed", "line:0.5,0,0.2:1.5,0,0.2",
            "--seed-count", 8, "--edge", 0.15, "--steps", 20, "--out", out, "--quiet")
    vertices, faces, attributes = preview.read_mesh(out)
    assert np.allclose(vertices, from_file.vertices, rtol=0, atol=1e-12)
    assert np.array_equal(faces, from_file.faces)
    assert np.allclose(attributes["time"], from_file.attributes["time"], rtol=0, atol=1e-12)


def shear_series(steps=6, dt=0.5):
    """u = (1, t) on [0, 4]^2: linear in t, so path lines are x = x0 + t, y = y0 + t^2/2."""
    x = np.linspace(0.0, 4.0, 9)
    y = np.linspace(0.0, 4.0, 9)
    times = np.arange(steps) * dt
    values = np.zeros((steps, len(y), len(x), 2), dtype=np.float32)
    values[..., 0] = 1.0
    for i, t in enumerate(times):
        values[i, ..., 1] = t
    return values, times, (0.0, 0.0), (0.5, 0.5)


def test_path_surface_from_a_numpy_series_follows_the_path_lines():
    values, times, origin, spacing = shear_series()
    series = orthofront.Series(values, times, origin=origin, spacing=spacing)
    assert len(series) == 6 and series.times[-1] == 2.5
    surface = orthofront.path_surface(series, "line:0.2,0.2,0:0.2,0.6,0", t0=0, t1=2,
                                      seed_count=9, edge=0.1)
    assert surface.report["complete"] and surface.report["path"]["time_reached"] >= 2 - 1e-9
    t = surface.attributes["time"]
    s = surface.attributes["s"]
    assert np.max(np.abs(surface.vertices[:, 0] - (0.2 + t))) < 1e-6
    assert np.max(np.abs(surface.vertices[:, 1] - (0.2 + 0.4 * s + 0.5 * t * t))) < 1e-6
    assert surface.spacetime_vertices.shape == surface.vertices.shape
    assert np.allclose(surface.spacetime_vertices[:, 2] / surface.report["path"]["time_scale"], t)


def test_path_surface_front_on_the_bulk_backend_follows_the_path_lines():
    values, times, origin, spacing = shear_series()
    series = orthofront.Series(values, times, origin=origin, spacing=spacing)
    surface = orthofront.path_surface(series, "line:0.2,0.2,0:0.2,0.6,0", t0=0, t1=2,
                                      seed_count=9, edge=0.1, device="cpu")
    device = surface.report["path"]["device"]
    assert device["backend"] == "cpu" and device["calls"] > 0
    t = surface.attributes["time"]
    s = surface.attributes["s"]
    assert np.max(np.abs(surface.vertices[:, 0] - (0.2 + t))) < 1e-6
    assert np.max(np.abs(surface.vertices[:, 1] - (0.2 + 0.4 * s + 0.5 * t * t))) < 1e-6
    # An analytic flow has no grid to move through.
    with pytest.raises(ValueError, match="device"):
        orthofront.path_surface("double-gyre", "line:0.2,0.2,0:0.2,0.6,0", t0=0, t1=1,
                                device="cpu")


def test_series_equals_a_glob_of_files_on_the_command_line(tmp_path, orthofront_binary):
    values, times, origin, spacing = shear_series()
    for i in range(len(times)):
        write_vti(tmp_path / ("frame%d.vti" % i), values[i], origin, spacing)
    series = orthofront.Series(values, times, origin=origin, spacing=spacing)
    options = dict(t0=0, t1=2, seed_count=9, edge=0.1)
    from_numpy = orthofront.path_surface(series, "line:0.2,0.2,0:0.2,0.6,0", **options)
    pattern = str(tmp_path / "frame*.vti") + ":dt=0.5"
    from_glob = orthofront.path_surface(pattern, "line:0.2,0.2,0:0.2,0.6,0", **options)
    assert np.array_equal(from_numpy.vertices, from_glob.vertices)
    assert np.array_equal(from_numpy.faces, from_glob.faces)
    out = tmp_path / "path.vtp"
    run_cli(orthofront_binary, "path", "--field", pattern, "--seed", "line:0.2,0.2,0:0.2,0.6,0",
            "--t0", 0, "--t1", 2, "--seed-count", 9, "--edge", 0.1, "--out", out, "--quiet")
    vertices, faces, _ = preview.read_mesh(out)
    assert np.allclose(vertices, from_glob.vertices, rtol=0, atol=1e-12)
    assert np.array_equal(faces, from_glob.faces)


def test_streak_surface_frames_match_the_command_line(tmp_path, orthofront_binary):
    options = dict(release=(0, 1), frames=[1, 2], edge=0.05)
    streak = orthofront.streak_surface("double-gyre", "line:0.3,0.3,0:0.3,0.45,0", **options)
    assert streak.times == [1.0, 2.0] and streak.report["complete"]
    last = streak[-1]
    assert "age" in last.attributes and "particle_id" in last.attributes
    assert np.all(last.attributes["age"] >= -1e-12) and np.all(last.attributes["age"] <= 2 + 1e-12)
    out = tmp_path / "streak.pvd"
    run_cli(orthofront_binary, "streak", "--field", "double-gyre", "--seed",
            "line:0.3,0.3,0:0.3,0.45,0", "--release", "0:1", "--frames", "1,2", "--edge", 0.05,
            "--out", out, "--quiet")
    frames = sorted((tmp_path / "streak").glob("*.vtp"))
    assert len(frames) == 2
    vertices, faces, _ = preview.read_mesh(frames[-1])
    assert np.allclose(vertices, last.vertices, rtol=0, atol=1e-12)
    assert np.array_equal(faces, last.faces)


def test_keywords_are_the_command_line_options():
    # Named as Python spells them.
    with pytest.raises(TypeError, match="'no_such_option'"):
        orthofront.stream_surface("abc", "line:0,0,0:1,0,0", no_such_option=3)
    with pytest.raises(ValueError, match="mu_mode: 'sideways' is not one of damping, paper"):
        orthofront.stream_surface("abc", "line:0,0,0:1,0,0", mu_mode="sideways")
    with pytest.raises(ValueError, match="flat_split: -1 is below 0"):
        orthofront.streak_surface("double-gyre", "line:0.3,0.3,0:0.3,0.45,0", release=(0, 1),
                                  frames=[1], flat_split=-1)
    with pytest.raises(TypeError, match="edge: takes a value"):
        orthofront.stream_surface("abc", "line:0,0,0:1,0,0", edge=True)
    with pytest.raises(ValueError, match="seed_count must be at least 2"):
        orthofront.stream_surface("abc", "line:0,0,0:1,0,0", seed_count=1)
    with pytest.raises(TypeError, match="release"):
        orthofront.streak_surface("double-gyre", "line:0.3,0.3,0:0.3,0.45,0", frames=[1])


def test_bad_input_names_what_is_wrong(tmp_path):
    with pytest.raises(ValueError, match="components"):
        orthofront.Field(np.zeros((4, 4, 4, 2), dtype=np.float32))
    with pytest.raises(ValueError, match="spacing"):
        orthofront.Field(np.zeros((4, 4, 2), dtype=np.float32), spacing=(1, 1, 1))
    with pytest.raises(ValueError, match="times"):
        orthofront.Series(np.zeros((3, 4, 4, 2), dtype=np.float32), [0, 1])
    with pytest.raises(ValueError, match="increasing"):
        orthofront.Series(np.zeros((2, 4, 4, 2), dtype=np.float32), [1, 0])
    # datetime64 times (as xarray gives them) would be read as nanoseconds.
    stamps = np.array(["2024-01-01", "2024-01-02"], dtype="datetime64[ns]")
    with pytest.raises(ValueError, match="datetime64"):
        orthofront.Series(np.zeros((2, 4, 4, 2), dtype=np.float32), stamps)
    missing = str(tmp_path / "missing.vti")
    with pytest.raises((OSError, ValueError), match="missing.vti"):
        orthofront.Field.open(missing)
    values, origin, spacing = helix_grid(5)
    field = orthofront.Field(values, origin=origin, spacing=spacing)
    with pytest.raises(ValueError, match="outside the domain"):
        orthofront.stream_surface(field, "line:10,10,10:11,10,10")
    # An empty surface comes with a warning, as on the command line.
    with pytest.warns(RuntimeWarning, match="no faces"):
        empty = orthofront.stream_surface("saddle", "line:-1,1,0:1,1,0", steps=0, edge=0.05)
    assert len(empty.faces) == 0
    # (x, y) seed points on a 3D unsteady field would sit at z = 0 without a word.
    planar = np.array([[1.0, 1.0], [1.5, 1.0]])
    with pytest.raises(ValueError, match=r"\(n, 2\) points"):
        orthofront.path_surface("unsteady-abc", planar, t0=0, t1=1)
    with pytest.raises(ValueError, match=r"\(n, 2\) points"):
        orthofront.streak_surface("unsteady-abc", planar, release="0:1", frames="1")


def test_numpy_zeros_are_no_data_as_in_files_unless_told():
    # u = 1 east where x < 1; zero vectors (a wall) where x >= 1.
    x = np.linspace(0.0, 2.0, 21)
    values = np.zeros((11, 21, 2), dtype=np.float32)
    values[:, x < 1.0, 0] = 1.0
    grid = dict(origin=(0.0, 0.0), spacing=(0.1, 0.1))
    inside_wall = "line:1.5,0.2,0:1.5,0.8,0"
    with pytest.raises(ValueError, match="no data"):
        orthofront.stream_surface(orthofront.Field(values, **grid), inside_wall)
    with pytest.raises(ValueError, match="zero velocity"):
        orthofront.stream_surface(orthofront.Field(values, zero_is_no_data=False, **grid),
                                  inside_wall)
    steps = np.stack([values, values])
    with pytest.raises(ValueError, match="no data"):
        orthofront.path_surface(orthofront.Series(steps, [0.0, 1.0], **grid), inside_wall,
                                t0=0, t1=1)


def test_save_round_trips(tmp_path):
    values, origin, spacing = helix_grid(9)
    surface = orthofront.stream_surface(orthofront.Field(values, origin=origin, spacing=spacing),
                                        "line:0.5,0,0.2:1.5,0,0.2", seed_count=6, edge=0.2,
                                        steps=10)
    path = tmp_path / "saved.vtp"
    surface.save(path)
    vertices, faces, attributes = preview.read_mesh(path)
    assert np.array_equal(vertices, surface.vertices)
    assert np.array_equal(faces, surface.faces)
    assert np.array_equal(attributes["alpha"], surface.attributes["alpha"])


def test_the_build_releases_the_interpreter_lock():
    values, origin, spacing = helix_grid(17)
    field = orthofront.Field(values, origin=origin, spacing=spacing)
    ticks = []
    done = threading.Event()

    def count():
        while not done.is_set():
            ticks.append(1)
            time.sleep(0.001)

    counter = threading.Thread(target=count)
    counter.start()
    started = time.monotonic()
    try:
        orthofront.stream_surface(field, "line:0.3,0,0.1:1.8,0,0.1", seed_count=40, edge=0.003,
                                  steps=1200)
    finally:
        done.set()
        counter.join()
    elapsed = time.monotonic() - started
    assert elapsed > 0.2, "the build was too short to tell"
    # With the lock held the counter could not run at all during the build.
    assert len(ticks) > 20


def test_ctrl_c_stops_a_build():
    values, origin, spacing = helix_grid(17)
    field = orthofront.Field(values, origin=origin, spacing=spacing)
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    started = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        # Unbounded in practice: millions of steps at a tiny edge.
        orthofront.stream_surface(field, "line:0.3,0,0.1:1.8,0,0.1", seed_count=50, edge=0.002,
                                  steps=1000000, max_vertices=100000000)
    timer.cancel()
    assert time.monotonic() - started < 10


def test_to_vtk_round_trips_points_faces_and_attributes():
    pytest.importorskip("vtkmodules.vtkCommonDataModel")
    from vtkmodules.util import numpy_support
    surface = orthofront.stream_surface("sinus", "line:-1,0,0:1,0,0", steps=30, edge=0.1)
    streak = orthofront.streak_surface("double-gyre", "line:0.3,0.3,0:0.3,0.45,0", release="0:2",
                                       frames="2", edge=0.03)[0]
    for s in (surface, streak):
        mesh = s.to_vtk()
        assert mesh.GetNumberOfPoints() == len(s.vertices)
        np.testing.assert_array_equal(numpy_support.vtk_to_numpy(mesh.GetPoints().GetData()),
                                      s.vertices)
        assert mesh.GetNumberOfCells() == len(s.faces)
        for i in range(0, len(s.faces), 7):
            ids = mesh.GetCell(i).GetPointIds()
            corners = [ids.GetId(k) for k in range(ids.GetNumberOfIds())]
            assert corners == [v for v in s.faces[i] if v >= 0]
        for name, values in s.attributes.items():
            np.testing.assert_array_equal(
                numpy_support.vtk_to_numpy(mesh.GetPointData().GetArray(name)), values)
        # The padded cell array: a count, then that many corners, face after face.
        cells = s.vtk_faces()
        assert cells.dtype == np.int64
        assert len(cells) == len(s.faces) + int(np.count_nonzero(s.faces >= 0))
    assert surface.quad_count > 0 and streak.quad_count == 0
    assert list(streak.vtk_faces()[:4]) == [3] + list(streak.faces[0, :3])


def test_signatures_and_docstrings_list_every_keyword_with_its_default():
    import inspect
    for function, kind in ((orthofront.stream_surface, "stream"),
                           (orthofront.path_surface, "path"),
                           (orthofront.streak_surface, "streak")):
        parameters = inspect.signature(function).parameters
        schema = orthofront._orthofront._keywords(kind)
        assert list(parameters)[:3] == ["field", "seed", "closed"]
        assert [p for p in parameters][3:] == [k["name"] for k in schema]
        doc = function.__doc__
        assert "Parameters\n----------\n" in doc
        for k in schema:
            assert "\n%s : " % k["name"] in doc, k["name"]
            assert "(%s; default: " % k["option"] in " ".join(doc.split()), k["name"]
    stream = inspect.signature(orthofront.stream_surface).parameters
    assert stream["steps"].default == 100
    assert stream["seed_count"].default == 20
    assert stream["tolerance"].default == 1e-9
    assert stream["no_rip"].default is False
    # From the data: None, and the docstring says from what.
    assert stream["edge"].default is None
    assert "the grid's cell size for gridded data, else 0.1" in " ".join(
        orthofront.stream_surface.__doc__.split())
    streak = inspect.signature(orthofront.streak_surface).parameters
    assert streak["flat_split"].default == 0.01
    assert streak["insert"].default == "exact"
    assert streak["mesh"].default == "remeshed"


def test_keywords_are_the_command_lines_flags_with_the_same_defaults(orthofront_binary):
    # One schema (apps/jobs) makes both: every keyword is a flag of the command, shown with the
    # same default, and the command's flags beyond them are its files, pictures and devices.
    import re
    cli_only = {"field", "seed", "out", "report", "quiet", "help", "exr", "exr_bins",
                "device", "device_min_vertices", "device_memory", "preview", "preview_size",
                "no_preview"}
    for kind in ("stream", "path", "streak"):
        text = run_cli(orthofront_binary, kind, "--help").stdout
        flags = {}
        for line in text.splitlines():
            m = re.match(r"\s+(?:-\w,\s*)?--([\w-]+)(.*)", line)
            if m:
                flags[m.group(1).replace("-", "_")] = m.group(2)
        keywords = orthofront._orthofront._keywords(kind)
        for k in keywords:
            assert k["name"] in flags, (kind, k["name"])
            if k["default"] and not k["flag"] and k["name"] != "max_vertices":  # from memory now
                shown = flags[k["name"]]
                assert ("=%s " % k["default"] in shown + " " or "[%s]" % k["default"] in shown), (
                    kind, k["name"], k["default"], shown)
        extra = set(flags) - {k["name"] for k in keywords}
        assert extra <= cli_only | {name for name in extra if name.startswith("preview")}, (
            kind, extra - cli_only)


def test_paraview_properties_are_keywords_with_the_same_defaults_and_choices():
    # The ParaView filters set the functions' keywords: each property's keyword is one of the
    # kind's options, its default the option's (Edge 0 stands for the data's cell size, which
    # the option leaves to the data too), and its list of words the option's choices.
    import re
    path = os.path.join(os.path.dirname(orthofront.__file__), os.pardir, "paraview",
                        "orthofront_filters.py")
    source = open(path).read()
    property_re = re.compile(
        r'@smproperty\.(\w+)\(name="(\w+)"(?P<args>[^)]*)\)(?P<decorators>(?:\s*@[^\n]*\n'
        r'(?:\s*\'[^\n]*\n)*)*)\s*def Set\2\(self[^)]*\):\n(?P<body>(?:\s{8}[^\n]*\n)+)')
    checked = 0
    for cls, kind in (("StreamSurface", "stream"), ("PathSurface", "path"),
                      ("StreakSurface", "streak")):
        start = source.index("class %s(" % cls)
        end = source.find("\nclass ", start + 1)
        body = source[start:end if end > 0 else len(source)]
        schema = {k["name"]: k for k in orthofront._orthofront._keywords(kind)}
        for m in property_re.finditer(body):
            key = re.search(r'self\._set\("(\w+)"', m.group("body"))
            if not key:
                continue  # Vectors, Options, SpacetimeOut: the filter's own
            key = key.group(1)
            assert key in schema, (cls, m.group(2), key)
            entry = schema[key]
            default = re.search(r"default_values=([^,)]+)", m.group("args"))
            if default and entry["default"] and key != "edge":
                shown = default.group(1).strip().strip('"')
                try:
                    assert float(shown) == float(entry["default"]), (cls, key, shown)
                except ValueError:
                    assert shown == entry["default"], (cls, key, shown)
            words = re.findall(r'<String value="([^"]+)"/>', m.group("decorators") or "")
            if words:
                assert words == entry["choices"], (cls, key, words, entry["choices"])
            checked += 1
    assert checked >= 15


def test_stream_surface_takes_the_device_as_the_command_line_does(orthofront_binary, tmp_path):
    # One runner (jobs::run_stream_job) for both: a linear field is exact on its grid, so the
    # bulk advance stays on y z = 0.2 as the per-vertex one does, and an analytic field is refused.
    h5 = str(tmp_path / "saddle.h5")
    run_cli(orthofront_binary, "generate", "--field", "saddle3d", "--resolution", "33,33,33",
            "--out", h5, "--quiet")
    seed = "line:-1,2,0.1:1,2,0.1"
    plain = orthofront.stream_surface(h5, seed, seed_count=20, edge=0.1, steps=100)
    bulk = orthofront.stream_surface(h5, seed, seed_count=20, edge=0.1, steps=100, device="cpu")
    assert len(bulk.vertices) == len(plain.vertices)
    assert np.max(np.abs(bulk.vertices[:, 1] * bulk.vertices[:, 2] - 0.2)) < 1e-6
    assert bulk.report["device"]["backend"] == "cpu"
    assert "device" not in plain.report
    with pytest.raises(ValueError, match="not a gridded field"):
        orthofront.stream_surface("saddle3d", seed, steps=5, device="cpu")
    with pytest.raises(ValueError, match="device: 'gpu' is not one of cpu, cuda, auto"):
        orthofront.stream_surface(h5, seed, device="gpu")


def test_stream_surface_warns_of_a_run_its_rows_would_stop_at_the_vertex_cap():
    # As `stream` prints it: 101 vertices a row for 100 steps cannot fit 2,000 vertices.
    with pytest.warns(UserWarning, match="past the vertex cap of 2000"):
        orthofront.stream_surface("saddle3d", "line:-0.5,2,0.1:0.5,2,0.1", edge=0.01,
                                  seed_count=101, max_vertices=2000)
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        orthofront.stream_surface("saddle3d", "line:-0.5,2,0.1:0.5,2,0.1", edge=0.1, steps=10)


def test_keywords_given_at_their_defaults_change_nothing():
    seed = "line:-2,1,0:-2,2,0"
    plain = orthofront.stream_surface("saddle", seed, edge=0.1, steps=20)
    spelled = orthofront.stream_surface("saddle", seed, edge=0.1, steps=20, seed_count=20,
                                        damping=0.5, mu=1.0, tolerance=1e-9, no_rip=False,
                                        skip_fraction=0.5)
    assert np.array_equal(plain.vertices, spelled.vertices)
    assert np.array_equal(plain.faces, spelled.faces)


def test_messages_name_the_keywords_a_python_user_types_not_the_flags():
    values, times, origin, spacing = shear_series()
    series = orthofront.Series(values, times, origin=origin, spacing=spacing)
    with pytest.raises(ValueError) as refused:
        orthofront.path_surface(series, [[0.2, 0.2], [0.2, 0.6]], cache_budget="100", t0=0, t1=2)
    assert "raise cache_budget" in str(refused.value)
    assert "--cache-budget" not in str(refused.value)
