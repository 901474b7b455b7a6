"""The compiled ParaView plugin under pvbatch, loaded through PV_PLUGIN_PATH: its properties are
the option schema's (names, defaults, ranges, documentation), and its stream, path and streak
surfaces are the command line's, point for point."""

import json
import os
import re
import subprocess

import numpy as np
import pytest

import orthofront
from conftest import pvbatch_inputs, run_cli
from orthofront import preview

SCRIPT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "paraview_plugin_run.py")


def property_name(option):
    """--flat-split -> FlatSplit, as the plugin's generator names properties."""
    return "".join(word[:1].upper() + word[1:] for word in option.lstrip("-").split("-"))


@pytest.fixture(scope="module")
def plugin_run(tmp_path_factory):
    plugin_dir = os.environ.get("ORTHOFRONT_PARAVIEW_PLUGIN_DIR", "")
    if not plugin_dir:
        pytest.skip("SKIPPED: built without the compiled ParaView plugin (Debian: paraview-dev)")
    pvbatch, work = pvbatch_inputs(tmp_path_factory, "plugin")
    env = dict(os.environ, PV_PLUGIN_PATH=os.path.join(plugin_dir, "OrthofrontSurfaces"))
    result = subprocess.run([pvbatch, SCRIPT, str(work)], capture_output=True, text=True,
                            timeout=300, env=env)
    assert result.returncode == 0 and (work / "plugin.json").exists(), (
        "pvbatch failed (%d):\n%s\n%s" % (result.returncode, result.stdout, result.stderr))
    return work, json.loads((work / "plugin.json").read_text()), result.stderr


# The command line's options the plugin leaves to it: the device, the streak surface's other
# routes, and the space-time output file.
COMMAND_LINE_ONLY = ("--device", "--route", "--point", "--spacetime-out")
# Their defaults come from the data: 0 or empty on the panel, as its documentation says.
FROM_DATA = ("--edge", "--max-vertices", "--t0", "--t1", "--release", "--frames")


def panel_options(kind):
    """The kind's options a ParaView user sets, as Python's keywords list them."""
    return [entry for entry in orthofront._orthofront._keywords(kind)
            if not entry["option"].startswith(COMMAND_LINE_ONLY)]


@pytest.mark.parametrize("kind,key", [("stream", "properties"), ("path", "path_properties"),
                                      ("streak", "streak_properties")])
def test_every_option_is_a_property_with_the_same_default_and_documentation(plugin_run, kind,
                                                                            key):
    _, result, _ = plugin_run
    properties = result[key]
    own = {"Input", "Vectors", "SeedPoint1", "SeedPoint2", "ZerosAreNoData", "TimestepValues"}
    expected = {property_name(entry["option"]) for entry in panel_options(kind)}
    assert set(properties) - own == expected
    for entry in panel_options(kind):
        prop = properties[property_name(entry["option"])]
        # The help's figures of the machine it runs on ("now 23.0 GiB") are left out.
        help_text = re.sub(r", now [^)]*|; the figure shown is for the memory available now", "",
                           entry["help"])
        assert prop["documentation"].startswith(help_text.rstrip(".")), entry["option"]
        assert "Command line: %s." % entry["option"] in prop["documentation"]
        if entry["option"] in FROM_DATA or not entry["default"]:
            assert prop["value"] in (0, "", None), entry["option"]
            continue  # from the data: 0 or empty on the panel (said in the documentation)
        if entry["flag"]:
            assert prop["value"] == (1 if entry["default"] == "true" else 0), entry["option"]
        elif entry["choices"]:
            enum = [d for d in prop["domains"] if d["class"] == "vtkSMEnumerationDomain"]
            assert enum and enum[0]["entries"] == entry["choices"], entry["option"]
            assert enum[0]["entries"][prop["value"]] == entry["default"], entry["option"]
        elif entry["type"] in ("FLOAT", "INT", "UINT"):
            assert float(prop["value"]) == float(entry["default"]), entry["option"]
        else:
            assert prop["value"] == entry["default"], entry["option"]


def test_ranges_are_domains_and_the_vectors_an_array_list(plugin_run):
    _, result, _ = plugin_run
    properties = result["properties"]
    damping = [d for d in properties["Damping"]["domains"] if "RangeDomain" in d["class"]]
    assert damping and (damping[0]["min"], damping[0]["max"]) == (0.0, 1.0)
    assert "greater than 0, less than 1" in properties["Damping"]["documentation"]
    steps = [d for d in properties["Steps"]["domains"] if d["class"] == "vtkSMIntRangeDomain"]
    assert steps and steps[0]["min"] == 0
    assert any(d["class"] == "vtkSMArrayListDomain" for d in properties["Vectors"]["domains"])
    assert result["vectors"] == ["POINTS", "velocity"]
    assert any(d["class"] == "vtkSMBoundsDomain" for d in properties["SeedPoint1"]["domains"])


def test_the_filters_surface_is_the_command_lines(plugin_run, orthofront_binary):
    work, result, _ = plugin_run
    out = work / "cli-edge.vtp"
    run_cli(orthofront_binary, "stream", "--field", work / "helix.vti", "--seed",
            "line:0.5,0,0.2:1.5,0,0.2", "--seed-count", 8, "--edge", 0.15, "--steps", 20,
            "--out", out, "--quiet")
    cli_vertices, cli_faces, cli_attributes = preview.read_mesh(out)
    vertices, faces, attributes = preview.read_mesh(work / "plugin-edge.vtp")
    assert result["given_edge"]["points"] == len(cli_vertices) > 50
    assert np.array_equal(vertices, cli_vertices)
    assert np.array_equal(faces, cli_faces)
    for name in cli_attributes:
        assert np.array_equal(attributes[name], cli_attributes[name]), name
    assert result["given_edge"]["report"]["complete"] is True
    # The output says what it is, as the command line's .vtp files do.
    notes = result["given_edge"]["notes"]
    assert notes["orthofront_surface"].startswith("stream surface, orthofront ")
    assert notes["source"] == "ParaView input, array 'velocity'"
    assert "position_units" in notes and "time" in notes


def test_edge_left_at_zero_takes_the_cell_size_as_the_command_line_does(plugin_run,
                                                                        orthofront_binary):
    work, result, _ = plugin_run
    out = work / "cli-cell.vtp"
    run_cli(orthofront_binary, "stream", "--field", work / "helix.vti", "--seed",
            "line:0.5,0,0.2:1.5,0,0.2", "--seed-count", 8, "--steps", 20, "--out", out,
            "--quiet")
    report = result["cell_edge"]["report"]
    assert (report["edge"], report["edge_source"]) == (0.5, "grid cell")
    cli_vertices, _, _ = preview.read_mesh(out)
    vertices, _, _ = preview.read_mesh(work / "plugin-cell.vtp")
    assert np.array_equal(vertices, cli_vertices)


def test_a_refused_value_names_the_property_and_leaves_no_surface(plugin_run):
    _, result, stderr = plugin_run
    assert result["bad_edge"]["points"] == 0 and result["bad_edge"]["report"] is None
    assert re.search(r"Edge: .*-1.* not a positive number", stderr), stderr[-2000:]


def assert_same_mesh(plugin_file, cli_file):
    vertices, faces, attributes = preview.read_mesh(plugin_file)
    cli_vertices, cli_faces, cli_attributes = preview.read_mesh(cli_file)
    assert len(cli_vertices) > 10
    assert np.array_equal(vertices, cli_vertices)
    assert np.array_equal(faces, cli_faces)
    for name in cli_attributes:
        assert np.array_equal(attributes[name], cli_attributes[name]), name


def test_the_path_filter_reads_the_steps_and_makes_the_command_lines_surface(plugin_run,
                                                                             orthofront_binary):
    work, result, _ = plugin_run
    out = work / "path-cli.vtp"
    # ParaView numbers a list of files 0, 1, 2, ...: the glob's default dt of 1.
    run_cli(orthofront_binary, "path", "--field", str(work / "frame*.vti"), "--seed",
            "line:0.2,0.2,0:0.2,0.6,0", "--seed-count", 9, "--edge", 0.1, "--t0", 0, "--t1", 3,
            "--out", out, "--quiet")
    assert_same_mesh(work / "plugin-path.vtp", out)
    assert result["path"]["complete"] is True and result["path"]["path"]["t1"] == 3


def test_the_streak_filter_has_a_time_step_per_frame_each_the_command_lines(plugin_run,
                                                                            orthofront_binary):
    work, result, _ = plugin_run
    assert result["streak_times"] == [2.0, 3.0]
    out = work / "streak-cli.pvd"
    run_cli(orthofront_binary, "streak", "--field", str(work / "frame*.vti"), "--seed",
            "line:0.2,0.2,0:0.2,0.6,0", "--release", "0:1", "--frames", "2,3", "--edge", 0.05,
            "--seed-count", 9, "--out", out, "--quiet")
    frames = sorted((work / "streak-cli").glob("*.vtp"))
    assert len(frames) == 2
    for time, frame in zip((2, 3), frames):
        assert_same_mesh(work / ("plugin-streak-%g.vtp" % time), frame)
    # Release and frames left empty: the input's whole range, a frame at each later step.
    assert result["streak_default_times"] == [1.0, 2.0, 3.0, 4.0, 5.0]


def test_a_rectilinear_grid_gives_the_surface_of_the_same_grid_in_python(plugin_run):
    work, _, _ = plugin_run
    axes = [np.linspace(-2.0, 2.0, 9), np.linspace(-2.0, 2.0, 9),
            4.0 * np.linspace(0.0, 1.0, 9) ** 1.5]
    zz, yy, xx = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    values = np.stack([-yy, xx, np.ones_like(xx)], axis=-1).astype(np.float32)
    field = orthofront.Field(values, axes=[list(a) for a in axes])
    reference = orthofront.stream_surface(field, [[0.5, 0.0, 0.2], [1.5, 0.0, 0.2]], seed_count=8,
                                          edge=0.15, steps=20)
    vertices, faces, _ = preview.read_mesh(work / "plugin-rectilinear.vtp")
    assert len(reference.vertices) > 50
    assert np.array_equal(vertices, reference.vertices)
    assert np.array_equal(faces, reference.faces)
