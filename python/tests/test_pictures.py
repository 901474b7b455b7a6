"""Pictures: rendered surfaces and quality histograms, from Python, the commands and the demo."""

import json
import os
import xml.etree.ElementTree as ElementTree

import numpy as np

import orthofront
from orthofront import preview
from conftest import assert_picture, read_png, run_cli


def assert_histograms(path):
    """An SVG with the two histogram panels (matplotlib names its axes axes_1, axes_2)."""
    assert os.path.isfile(path), path
    root = ElementTree.parse(path).getroot()
    ids = {element.get("id") for element in root.iter()}
    assert {"axes_1", "axes_2"} <= ids
    bars = [e for e in root.iter() if (e.get("id") or "").startswith("patch_")]
    assert len(bars) > 40  # 36 + 40 bins and the frames


def test_render_a_surface_from_python(tmp_path):
    surface = orthofront.stream_surface("abc", "line:0,0,0:1,0,0", steps=60, edge=0.05)
    png = tmp_path / "abc.png"
    surface.preview(png, size=(640, 480))
    assert_picture(png, (640, 480))
    quality_png = tmp_path / "abc-quality.png"
    preview.render_surface(surface, quality_png, color_by="quality", size=(320, 240))
    assert_picture(quality_png, (320, 240))


def test_quad_angle_deviation_of_a_square_and_a_rhombus():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                         [2, 0, 0], [3, 0, 0], [3.5, 0.866025403784, 0], [2.5, 0.866025403784, 0]])
    faces = np.array([[0, 1, 2, 3], [4, 5, 6, 7]])
    deviation = preview.quad_angle_deviation(vertices, faces)
    assert np.allclose(deviation[:4], 0, atol=1e-9)
    assert np.allclose(deviation[4:], 30, atol=1e-6)


def test_histograms_from_a_report(tmp_path):
    surface = orthofront.stream_surface("abc", "line:0,0,0:1,0,0", steps=40)
    report = tmp_path / "abc.json"
    report.write_text(json.dumps(surface.report))
    svg = preview.plot_histograms(report, tmp_path / "abc.histograms.svg")
    assert_histograms(svg)
    png = preview.plot_histograms(surface.report, tmp_path / "abc.histograms.png")
    pixels = read_png(png)
    assert pixels.shape[:2] == (380, 1000)


def test_a_failed_write_leaves_no_partial_file(tmp_path, monkeypatch):
    """A write that fails half way (a full disk, say) leaves neither the file nor its .part."""
    import matplotlib.figure
    surface = orthofront.stream_surface("abc", "line:0,0,0:1,0,0", steps=20)

    def half_written(self, path, **kwargs):
        with open(path, "wb") as out:
            out.write(b"<svg")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", half_written)
    out = tmp_path / "abc.histograms.svg"
    try:
        preview.plot_histograms(surface.report, out)
    except OSError:
        pass
    else:
        raise AssertionError("the failed write was not reported")
    assert sorted(os.listdir(tmp_path)) == []


def test_commands_write_a_preview_and_histograms(tmp_path, orthofront_binary):
    env = dict(os.environ, ORTHOFRONT_HISTOGRAMS="1")
    env.pop("DISPLAY", None)  # the helper starts its own Xvfb
    out, report, png = tmp_path / "s.vtp", tmp_path / "s.json", tmp_path / "s.png"
    result = run_cli(orthofront_binary, "stream", "--field", "abc", "--seed", "line:0,0,0:1,0,0",
                     "--steps", 40, "--out", out, "--report", report, "--preview", png,
                     "--preview-color", "alpha", env=env)
    assert "Wrote the picture" in result.stdout
    assert_picture(png, (1024, 768))
    assert_histograms(tmp_path / "s.histograms.svg")
    # path, and streak (its last frame), the same way
    run_cli(orthofront_binary, "path", "--field", "double-gyre", "--seed",
            "line:0.1,0.5,0:0.6,0.5,0", "--t1", 2, "--edge", 0.05, "--out", tmp_path / "p.vtp",
            "--report", tmp_path / "p.json", "--preview", tmp_path / "p.png", "--quiet", env=env)
    assert_picture(tmp_path / "p.png", (1024, 768))
    assert_histograms(tmp_path / "p.histograms.svg")
    run_cli(orthofront_binary, "streak", "--field", "double-gyre", "--seed",
            "line:0.3,0.3,0:0.3,0.45,0", "--release", "0:1", "--frames", "1,2", "--out",
            tmp_path / "k.pvd", "--report", tmp_path / "k.json", "--preview", tmp_path / "k.png",
            "--quiet", env=env)
    assert_picture(tmp_path / "k.png", (1024, 768))
    assert_histograms(tmp_path / "k.histograms.svg")


def test_a_bad_preview_is_refused_before_the_run(tmp_path, orthofront_binary):
    result = run_cli(orthofront_binary, "stream", "--field", "abc", "--seed", "line:0,0,0:1,0,0",
                     "--out", tmp_path / "s.vtp", "--preview", tmp_path / "s.jpg", check=False)
    assert result.returncode != 0 and "s.jpg" in result.stderr and ".png" in result.stderr
    assert not (tmp_path / "s.vtp").exists()
    result = run_cli(orthofront_binary, "stream", "--field", "abc", "--seed", "line:0,0,0:1,0,0",
                     "--out", tmp_path / "s.vtp", "--preview", tmp_path / "s.png",
                     "--preview-color", "nosuch", check=False)
    assert result.returncode != 0 and "nosuch" in result.stderr
    assert (tmp_path / "s.vtp").exists() and not (tmp_path / "s.png").exists()


def test_the_demo_draws_every_surface_and_report(tmp_path, orthofront_binary):
    env = dict(os.environ, ORTHOFRONT_HISTOGRAMS="1")
    out = tmp_path / "demo"
    result = run_cli(orthofront_binary, "demo", "--out-dir", out, env=env)
    assert "Wrote a picture of every surface" in result.stdout
    reports = sorted(out.glob("*.json"))
    assert len(reports) == 14  # 6 cases x 2 methods, the path and the streak surface
    for report in reports:
        assert_picture(report.with_suffix(".png"), (1024, 768))
        assert_histograms(report.with_name(report.stem + ".histograms.svg"))
