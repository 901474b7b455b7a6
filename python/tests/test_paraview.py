"""The ParaView plugin under pvbatch: each filter runs on small images, its output has the counts
of the command line's mesh for the same options, and a screenshot shows the surface."""

import json
import os
import subprocess

import numpy as np
import pytest

from conftest import assert_picture, pvbatch_inputs, run_cli
from orthofront import preview

SCRIPT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "paraview_run_filters.py")


@pytest.fixture(scope="module")
def paraview_run(tmp_path_factory):
    pvbatch, work = pvbatch_inputs(tmp_path_factory, "paraview")
    # A private Xvfb on a display number of its own (xvfb-run -a guesses a free number and fails
    # when another test's server takes it first), started with -noreset (see preview.display).
    with preview.display():
        result = subprocess.run([pvbatch, SCRIPT, str(work)], capture_output=True, text=True,
                                timeout=300)
    assert result.returncode == 0 and (work / "result.json").exists(), (
        "pvbatch failed (%d):\n%s\n%s" % (result.returncode, result.stdout, result.stderr))
    return work, json.loads((work / "result.json").read_text())


def mesh_counts(path):
    vertices, faces, attributes = preview.read_mesh(path)
    return len(vertices), len(faces), int(np.count_nonzero(faces[:, 3] >= 0)), sorted(attributes)


def test_stream_surface_filter_matches_the_command_line(paraview_run, orthofront_binary):
    work, result = paraview_run
    out = work / "stream-cli.vtp"
    run_cli(orthofront_binary, "stream", "--field", work / "helix.vti", "--seed",
            "line:0.5,0,0.2:1.5,0,0.2", "--seed-count", 8, "--edge", 0.15, "--steps", 20,
            "--out", out, "--quiet")
    points, cells, quads, arrays = mesh_counts(out)
    got = result["stream"]
    assert (got["points"], got["cells"], got["quads"]) == (points, cells, quads)
    assert set(arrays) <= set(got["arrays"])


def test_edge_left_at_zero_is_the_inputs_cell_size_as_on_the_command_line(paraview_run,
                                                                          orthofront_binary):
    work, result = paraview_run
    out = work / "stream-cell.vtp"
    run_cli(orthofront_binary, "stream", "--field", work / "helix.vti", "--seed",
            "line:0.5,0,0.2:1.5,0,0.2", "--seed-count", 8, "--steps", 20, "--out", out, "--quiet")
    points, cells, quads, _ = mesh_counts(out)
    got = result["stream_cell_edge"]
    assert (got["points"], got["cells"], got["quads"]) == (points, cells, quads)
    assert (points, cells) != (result["stream"]["points"], result["stream"]["cells"])


def test_path_surface_filter_reads_every_time_step(paraview_run, orthofront_binary):
    work, result = paraview_run
    out = work / "path-cli.vtp"
    # ParaView numbers a list of files 0, 1, 2, ...: the glob's default dt of 1.
    run_cli(orthofront_binary, "path", "--field", str(work / "frame*.vti"), "--seed",
            "line:0.2,0.2,0:0.2,0.6,0", "--seed-count", 9, "--edge", 0.1, "--t0", 0, "--t1", 3,
            "--out", out, "--quiet")
    points, cells, quads, _ = mesh_counts(out)
    got = result["path"]
    assert (got["points"], got["cells"], got["quads"]) == (points, cells, quads)
    vertices, _, attributes = preview.read_mesh(out)
    assert got["bounds"][1] == pytest.approx(vertices[:, 0].max(), abs=1e-6)
    assert attributes["time"].max() == pytest.approx(3, abs=0.02)  # the front's last step


def test_streak_surface_filter_has_a_time_step_per_frame(paraview_run, orthofront_binary):
    work, result = paraview_run
    assert result["streak_times"] == [2.0, 3.0]
    out = work / "streak-cli.pvd"
    run_cli(orthofront_binary, "streak", "--field", str(work / "frame*.vti"), "--seed",
            "line:0.2,0.2,0:0.2,0.6,0", "--release", "0:1", "--frames", "2,3", "--edge", 0.05,
            "--seed-count", 9, "--out", out, "--quiet")
    frames = sorted((work / "streak-cli").glob("*.vtp"))
    assert len(frames) == 2
    for time, frame in zip(("2.0", "3.0"), frames):
        points, cells, quads, _ = mesh_counts(frame)
        got = result["streak"][time]
        assert (got["points"], got["cells"], got["quads"]) == (points, cells, quads)
        assert "age" in got["arrays"] and "particle_id" in got["arrays"]


def test_screenshot_shows_the_surface(paraview_run):
    work, _ = paraview_run
    assert_picture(work / "stream.png", (800, 600))
