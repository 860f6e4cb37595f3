"""The headless rviz check (scripts/rviz_screenshot.py): rviz with the
project's config, on Xvfb during a short lockstep simulation of a generated
6 x 5 m house, shows the occupied map; the same view with the map display on
an unused topic (everything else live: frontiers, path, TF, candidates) does
not pass the same check, nor does a blank screen. Through the display cut
(display_cut: the map below 2 m) the chairs' boxes and labels, drawn with
their meshes, are visible once a chair has a surface. The candidate views are
off in these screenshots (--no-candidates): their winner path line has the
boxes' blue. (The same view of the whole map, rviz_screenshot.py --uncut,
hides them only once the ceiling above them is mapped: 0 px in one run, 107
in another, so that is not asserted.) The pixel measure itself is
checked on synthetic screenshots first. The full run is skipped where rviz,
Xvfb or ImageMagick are missing or the package is not built and sourced."""
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import rviz_screenshot as rs  # noqa: E402

PIL = pytest.importorskip("PIL.Image")

MIN_MAP_FRACTION = 0.03  # of the 3D view; measured 8-28% with the map, 0.2-0.4% without
# chair box and label pixels in the 3D view; measured 109, 176 and 214. The
# screenshot is retaken until it shows them (or the timeout): a chair mapped
# under a desk is hidden by the desk top (0 px in one CI run).
MIN_OBJECT_PIXELS = 50


def shows_map(m):
    """The check: a drawn 3D view, at least MIN_MAP_FRACTION of it map
    pixels, and no display or global status in rviz's error colour."""
    return m["view"] is not None and m["map_fraction"] >= MIN_MAP_FRACTION and m["error_pixels"] == 0


def _screen(tmp_path, name, paint=None):
    """A 1400 x 900 synthetic screenshot: Qt-grey panels on the left, the 3D
    view (background colour, grey grid lines) on the right; paint(view) draws
    into the view."""
    img = np.full((900, 1400, 3), 239, np.uint8)
    view = img[60:870, 360:1390]
    view[:] = rs.BACKGROUND_RGB
    view[20::40, :] = (104, 104, 106)
    view[:, 20::40] = (104, 104, 106)
    if paint:
        paint(view, img)
    path = str(tmp_path / name)
    PIL.fromarray(img).save(path)
    return path


def test_measure_on_synthetic_screens(tmp_path):
    grid = rs.map_pixels(_screen(tmp_path, "grid.png"))
    assert grid["view"] == (60, 870, 360, 1390)
    assert grid["map_pixels"] == 0 and not shows_map(grid)

    def walls(view, _):
        view[200:500, 300:700] = (180, 176, 165)  # lit wall colour
    m = rs.map_pixels(_screen(tmp_path, "walls.png", walls))
    assert abs(m["map_pixels"] - 300 * 400) < 0.05 * 300 * 400 and shows_map(m)

    def frontiers_and_path(view, _):
        view[200:500, 300:700] = (230, 150, 0)  # frontier orange
        view[100:104, 100:900] = (25, 255, 0)  # path green
    m = rs.map_pixels(_screen(tmp_path, "frontiers.png", frontiers_and_path))
    assert m["map_pixels"] == 0 and not shows_map(m)

    def walls_and_error(view, img):
        walls(view, img)
        img[550:560, 40:160] = rs.ERROR_RGB  # "Global Status: Error" in the displays panel
    m = rs.map_pixels(_screen(tmp_path, "error.png", walls_and_error))
    assert m["error_pixels"] == 1200 and not shows_map(m)

    def chair_and_tf(view, _):
        view[300:302, 100:400] = (51, 110, 255)  # a chair's box edge as rviz draws it
        view[400:402, 100:400] = (0, 0, 255)     # the z axis of a TF frame: not an object
    m = rs.map_pixels(_screen(tmp_path, "chair.png", chair_and_tf))
    assert m["object_pixels"] == 600

    black = str(tmp_path / "black.png")  # rviz before its first frame: no 3D view drawn
    PIL.fromarray(np.zeros((900, 1400, 3), np.uint8)).save(black)
    assert not shows_map(rs.map_pixels(black))


def test_a_crashed_rviz_is_started_again(tmp_path, monkeypatch):
    """screenshot_scene starts rviz again when it dies (RvizExited) and gives
    up after four starts (RVIZ_START_ATTEMPTS); nothing here runs rviz or ROS."""
    class Stub:
        def __init__(self, *_):
            pass

        def __enter__(self):
            return self

        def __exit__(self, *_):
            pass

        def close(self):
            pass

    monkeypatch.setattr(rs, "MapWatch", Stub)
    monkeypatch.setattr(rs, "HeadlessRviz", Stub)
    monkeypatch.setattr(rs, "write_view_config", lambda src, dst, *a: dst)
    monkeypatch.setattr(rs, "find_config", lambda: "exploration.rviz")
    starts = []

    def take_crashing(crashes):
        def take(rviz, path, *_):
            starts.append(path)
            if len(starts) <= crashes:
                raise rs.RvizExited("rviz exited with code -11")
            return {"map_pixels": 1}
        return take

    png = str(tmp_path / "rviz.png")
    monkeypatch.setattr(rs, "take", take_crashing(3))  # three crashes, then a screenshot on the fourth start
    assert rs.screenshot_scene({}, png, [0, 0, 0], [1, 1, 1], str(tmp_path / "logs")) == {png: {"map_pixels": 1}}
    assert len(starts) == 4
    starts.clear()
    monkeypatch.setattr(rs, "take", take_crashing(4))  # four crashes: given up after the fourth start
    with pytest.raises(rs.RvizExited):
        rs.screenshot_scene({}, png, [0, 0, 0], [1, 1, 1], str(tmp_path / "logs"))
    assert len(starts) == 4


ROS_SOURCED = shutil.which("roslaunch") is not None and (
    "ROS_PACKAGE_PATH" in os.environ or "CMAKE_PREFIX_PATH" in os.environ)


@pytest.mark.skipif(bool(rs.missing_tools()) or not ROS_SOURCED, reason="rviz, Xvfb, import or ROS environment missing")
def test_rviz_shows_the_map(tmp_path):
    out = tmp_path / "shot"
    proc = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "rviz_screenshot.py"), "--out", str(out),
                           "--control", "--no-candidates", "--min-objects", "1", "--min-object-pixels", str(MIN_OBJECT_PIXELS),
                           "--timeout-s", "75"], stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, universal_newlines=True, timeout=330)
    print(proc.stdout)
    assert proc.returncode == 0, proc.stdout
    with_map = rs.map_pixels(str(out / "rviz.png"))
    without = rs.map_pixels(str(out / "rviz_no_map.png"))
    print("with the map: %s\nmap display on an unused topic: %s" % (with_map, without))
    assert with_map["view"] is not None, "rviz drew no 3D view"
    assert with_map["error_pixels"] == 0, "a display or the global status is in error"
    assert shows_map(with_map), with_map
    assert without["view"] == with_map["view"]  # same layout: the difference is the map
    assert not shows_map(without), without
    # the objects inside the map are visible through the display cut
    assert with_map["object_pixels"] >= MIN_OBJECT_PIXELS, with_map
    # no node of the simulation survives the script (their command lines name its log directory)
    left = subprocess.run(["pgrep", "-f", str(out)], stdout=subprocess.PIPE, universal_newlines=True).stdout.split()
    assert left == [], left
