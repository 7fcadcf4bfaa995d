"""The report's SVG charts (issue 12: a report in milliseconds, no matplotlib import)."""

import re
import subprocess
import sys

import numpy as np
import pytest

from robocal.report.svg import Panel, log_ticks, nice_ticks, viridis


def test_tick_rules():
    np.testing.assert_allclose(nice_ticks(0.0, 1.0), [0, 0.2, 0.4, 0.6, 0.8, 1.0])
    np.testing.assert_allclose(nice_ticks(-0.73, 0.61), [-0.5, 0, 0.5])
    np.testing.assert_allclose(nice_ticks(3.0, 2400.0), [500, 1000, 1500, 2000])
    np.testing.assert_allclose(log_ticks(0.004, 3.0), [0.01, 0.1, 1.0])
    np.testing.assert_allclose(log_ticks(0.3, 4.0), [0.5, 1, 2])


def test_viridis_matches_matplotlib_colour_map():
    mpl = pytest.importorskip("matplotlib")
    t = np.linspace(0, 1, 33)
    ours = np.array([[int(c[i:i + 2], 16) for i in (1, 3, 5)] for c in viridis(t)])
    ref = np.round(255 * np.asarray(mpl.colormaps["viridis"](t))[:, :3])
    assert np.max(np.abs(ours - ref)) <= 4  # 17 anchors, linear in between (at most 4/255 off)


def test_panel_maps_data_to_pixels():
    """A bar from 0 to 1 on a 0..1 axis fills the plot area's height exactly; log axes map decades evenly."""
    p = Panel(400, 300, margins=(50, 10, 20, 30))
    p.bars([0.5], [1.0], 1.0)
    p.limits(x=(0.0, 1.0), y=(0.0, 1.0))
    rect = re.search(r'<g fill="[^"]+" fill-opacity="[^"]+"><rect x="([\d.]+)" y="([\d.]+)" width="([\d.]+)" '
                     r'height="([\d.]+)"/>', p.svg())
    assert [float(v) for v in rect.groups()] == [50.0, 20.0, 340.0, 250.0]
    q = Panel(400, 300, y_log=True, margins=(50, 10, 20, 30))
    q.line([0, 1, 2], [0.01, 0.1, 1.0])
    q.limits(x=(0, 2), y=(0.01, 1.0))
    pts = re.search(r'<polyline points="([^"]+)"', q.svg()).group(1).split()
    ys = [float(s.split(",")[1]) for s in pts]
    assert ys == [270.0, 145.0, 20.0]


def test_report_renders_without_importing_matplotlib(tmp_path):
    code = ("import sys, json\n"
            "from robocal.report.html import render_report\n"
            "r = {'robot': 'x', 'residuals': {'per_point': {'pose': ['a', 'b'], 'before': [1.0, 2.0], 'after': [0.1, 0.2]}},\n"
            "     'parameters': [{'block': 'geometry', 'identifiable': True, 'unit': 'mm', 'change': 0.2, 'std': 0.01,\n"
            "                     'name': 'a1', 'initial': 100.0, 'value': 100.2}]}\n"
            "html = render_report(r, accuracy_map={'positions_mm': [[0, 0, 0], [100, 0, 50]], 'values_mm': [0.1, 0.2]})\n"
            "assert html.count('<div class=\"fig\"') == 4, html.count('<div class=\"fig\"')\n"
            "print('matplotlib' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_png_encoder_round_trips_through_opencv():
    cv2 = pytest.importorskip("cv2")
    from robocal.report.svg import png_gray

    rng = np.random.default_rng(0)
    gray = rng.integers(0, 256, (37, 53), dtype=np.uint8)
    decoded = cv2.imdecode(np.frombuffer(png_gray(gray), np.uint8), cv2.IMREAD_UNCHANGED)
    assert decoded.dtype == np.uint8 and np.array_equal(decoded, gray)
