#!/usr/bin/env python3
"""Screenshot of rviz with the project's config, without a display.

Runs a short lockstep simulation of a small generated house (sim.launch on a
private ROS master), waits until the background map has integrated some
frames, starts rviz -d config/rviz/exploration.rviz on a virtual X server
(Xvfb, Mesa's software OpenGL), saves a screenshot of the screen as
<out>/rviz.png and stops everything it started.

The 3D view is aimed at the scene: the screenshot uses a copy of the config
whose orbit view looks at the centre of the scene's box from a distance that
fits it; every display is the project's.

run_mission.py --rviz-screenshot calls screenshot_scene() for
results/<run>/rviz.png at the end of a mission; test/python/test_rviz_screenshot.py
runs this script and checks its PNGs with map_pixels().

Example:
  rviz_screenshot.py --out /tmp/shot              # -> /tmp/shot/rviz.png
  rviz_screenshot.py --out /tmp/shot --control    # also rviz_no_map.png (map display on an unused topic)
  rviz_screenshot.py --out /tmp/shot --uncut      # also rviz_uncut.png (the whole map: its ceiling hides the inside)

Needs rviz, Xvfb and ImageMagick's import (scripts/setup.sh installs them).
"""
import argparse
import math
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
RVIZ_CONFIG = os.path.join(HERE, "..", "config", "rviz", "exploration.rviz")
OCCUPIED_TOPIC = "/display_cut/occupied"  # the config's map display: the map below display_cut/max_z_m
SCREEN = (1400, 900)  # px, the config's window geometry
BACKGROUND_RGB = (48, 48, 48)  # the config's Background Color
ERROR_RGB = (192, 32, 32)  # rviz's colour for a display's error status text
# object_map's colour of class id 1 (chair: classColour in src/ros/object_map_node.cpp, hue 0.618 * 6 = 3.708):
# each object's box edges and "<class> #<id>" label. rviz lightens the lines (drawn as (51, 102-112, 255)), so
# an object pixel is any strong blue of that kind: B >= 200, R <= 90, 60 <= G <= 130. That leaves out tf's z
# axes (G < 60), frontiers, path, map and candidate views, but not the winner path line of the candidate
# markers (0.2, 0.4, 1.0): --no-candidates takes that display off for the object count.
CHAIR_RGB = (0, 74, 255)
CANDIDATES_TOPIC = "/planner/candidate_markers"
# The config's map displays pointed at the uncut clouds (the --uncut screenshot: the map's roof).
UNCUT_TOPICS = {OCCUPIED_TOPIC: "/background_map/occupied", "/display_cut/frontiers": "/background_map/frontiers"}


def missing_tools():
    """Names of the programs a headless screenshot needs that are not on PATH."""
    return [p for p in ("rviz", "Xvfb", "import") if shutil.which(p) is None]


def find_config():
    """The project's rviz config: the source tree's, else the installed package's."""
    if os.path.exists(RVIZ_CONFIG):
        return os.path.abspath(RVIZ_CONFIG)
    out = subprocess.run(["rospack", "find", "semantic_exploration"], stdout=subprocess.PIPE,
                         universal_newlines=True).stdout.strip()
    return os.path.join(out, "config", "rviz", "exploration.rviz")


def write_view_config(src, dst, bounds_min, bounds_max, occupied_topic=None, topics=None):
    """Copies the rviz config src to dst with the orbit view and the grid
    fitted to the box [bounds_min, bounds_max] (m, world); occupied_topic replaces the occupied
    map display's topic (the control screenshot points it at an unused one), topics maps
    other display topics to replacements (UNCUT_TOPICS: the whole map, ceiling included)."""
    import yaml
    with open(src) as f:
        cfg = yaml.safe_load(f)
    view = cfg["Visualization Manager"]["Views"]["Current"]
    centre = [(a + b) / 2 for a, b in zip(bounds_min, bounds_max)]
    diag = math.dist(bounds_min, bounds_max)
    view["Focal Point"] = {"X": centre[0], "Y": centre[1], "Z": bounds_min[2]}
    view["Distance"] = 1.3 * diag  # whole box in the view at rviz's default field of view
    for d in cfg["Visualization Manager"]["Displays"]:
        if d.get("Class") == "rviz/Grid":  # under the whole scene, 1 m cells
            d["Offset"] = {"X": round(centre[0]), "Y": round(centre[1]), "Z": bounds_min[2]}
            n = int(math.ceil(max(b - a for a, b in zip(bounds_min[:2], bounds_max[:2])))) + 4
            d["Plane Cell Count"] = n + n % 2  # even: lines on whole metres round the whole-metre offset
    replace = dict(topics or {})
    if occupied_topic is not None:
        replace[OCCUPIED_TOPIC] = occupied_topic
    for d in cfg["Visualization Manager"]["Displays"]:
        for key in ("Topic", "Marker Topic"):
            if d.get(key) in replace:
                d[key] = replace[d[key]]
    with open(dst, "w") as f:
        yaml.safe_dump(cfg, f, sort_keys=False)
    return dst


def _stop(proc, grace_s=10.0):
    """SIGINT to the process group of proc (started with start_new_session),
    then SIGTERM, then SIGKILL; whatever of the group outlives its leader is
    killed. A proc that had already ended is left alone (its group id may be reused)."""
    if proc is None or proc.poll() is not None:
        return
    for sig, wait_s in ((signal.SIGINT, grace_s), (signal.SIGTERM, 3.0), (signal.SIGKILL, 3.0)):
        if proc.poll() is not None:
            break
        try:
            os.killpg(proc.pid, sig)
        except ProcessLookupError:
            break
        try:
            proc.wait(timeout=wait_s)
            break
        except subprocess.TimeoutExpired:
            pass
    try:
        os.killpg(proc.pid, signal.SIGKILL)  # stragglers of the group, if any
    except (ProcessLookupError, PermissionError):
        pass


class RvizExited(RuntimeError):
    """rviz ended by itself (it occasionally crashes while starting on Xvfb)."""


# rviz 1.14 on Xvfb and llvmpipe sometimes dies while loading its displays
# ("free(): invalid next size", SIGSEGV or SIGABRT), before any screenshot.
# One CI run saw two such crashes in a row, so a shot gets this many starts.
RVIZ_START_ATTEMPTS = 4


class HeadlessRviz:
    """Xvfb plus rviz on it, for screenshots. env holds ROS_MASTER_URI etc.;
    logs go to log_dir. Use as a context manager; stop() ends both."""

    def __init__(self, env, log_dir):
        self.env = dict(env)
        self.log_dir = log_dir
        self.xvfb = None
        self.rviz = None
        self.display = None
        self._logs = []

    def __enter__(self):
        self.start_display()
        return self

    def __exit__(self, *exc):
        self.stop()

    def _log(self, name):
        f = open(os.path.join(self.log_dir, name), "a")
        self._logs.append(f)
        return f

    def start_display(self, timeout_s=20.0):
        """Starts Xvfb on a free display number (it reports the number it took)."""
        r, w = os.pipe()
        self.xvfb = subprocess.Popen(
            ["Xvfb", "-displayfd", str(w), "-screen", "0", "%dx%dx24" % SCREEN, "-nolisten", "tcp"],
            pass_fds=(w,), stdout=self._log("xvfb.log"), stderr=subprocess.STDOUT, start_new_session=True)
        os.close(w)
        deadline = time.time() + timeout_s
        buf = b""
        os.set_blocking(r, False)
        while not buf.endswith(b"\n"):
            if self.xvfb.poll() is not None or time.time() > deadline:
                os.close(r)
                raise RuntimeError("Xvfb did not start (see %s)" % os.path.join(self.log_dir, "xvfb.log"))
            try:
                buf += os.read(r, 64)
            except BlockingIOError:
                time.sleep(0.1)
        os.close(r)
        self.display = ":" + buf.decode().strip()
        self.env["DISPLAY"] = self.display
        self.env.pop("XAUTHORITY", None)
        return self.display

    def start_rviz(self, config):
        self.stop_rviz()
        line_buffered = ["stdbuf", "-oL"] if shutil.which("stdbuf") else []  # keep the log of a crash
        self.rviz = subprocess.Popen(line_buffered + ["rviz", "-d", config], env=self.env, stdout=self._log("rviz.log"),
                                     stderr=subprocess.STDOUT, start_new_session=True)

    def wait_subscribed(self, topic, timeout_s=60.0):
        """Waits until rviz subscribes to topic (its displays are loaded); True if it did."""
        import xmlrpc.client
        master = xmlrpc.client.ServerProxy(self.env["ROS_MASTER_URI"])
        deadline = time.time() + timeout_s
        while time.time() < deadline:
            if self.rviz.poll() is not None:
                return False
            try:
                _, _, (_, subs, _) = master.getSystemState("/rviz_screenshot")
                if any(t == topic and any("rviz" in n for n in nodes) for t, nodes in subs):
                    return True
            except OSError:
                pass
            time.sleep(0.5)
        return False

    def check_alive(self):
        """Raises RvizExited if rviz has ended."""
        if self.rviz is None or self.rviz.poll() is not None:
            raise RvizExited("rviz exited with code %s (see %s)" % (
                self.rviz.returncode if self.rviz else None, os.path.join(self.log_dir, "rviz.log")))

    def screenshot(self, png):
        """Saves the whole virtual screen as png (ImageMagick import)."""
        tmp = png + ".tmp.png"
        subprocess.run(["import", "-display", self.display, "-window", "root", tmp], env=self.env,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True, timeout=30)
        os.replace(tmp, png)
        return png

    def stop_rviz(self):
        _stop(self.rviz)
        self.rviz = None

    def stop(self):
        self.stop_rviz()
        _stop(self.xvfb, grace_s=5.0)
        self.xvfb = None
        for f in self._logs:
            f.close()
        self._logs = []


def view_region(rgb):
    """(row0, row1, col0, col1) of the rviz 3D view in a screenshot: the
    bounding box of rows and columns where at least a fifth of the pixels have
    the background colour (panels are Qt grey, images are small)."""
    import numpy as np
    bg = np.all(rgb == np.array(BACKGROUND_RGB, dtype=rgb.dtype), axis=2)
    rows = np.nonzero(bg.mean(axis=1) > 0.2)[0]
    cols = np.nonzero(bg.mean(axis=0) > 0.2)[0]
    if len(rows) == 0 or len(cols) == 0:
        return None
    return int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1


def _box_mean(mask, k):
    """Mean of mask over the k x k window centred on each pixel (edges padded with 0)."""
    import numpy as np
    p = np.pad(mask.astype(np.int32), k // 2 + 1)[:-1, :-1]
    c = p.cumsum(0).cumsum(1)
    h, w = mask.shape
    s = c[k:k + h, k:k + w] - c[:h, k:k + w] - c[k:k + h, :w] + c[:h, :w]
    return s / float(k * k)


def map_pixels(png):
    """Figures of a screenshot: the 3D view (row0, row1, col0, col1) and how
    many of its pixels show the occupied map. The map's boxes carry the
    scene's colours (walls, floor, ceiling: unsaturated, lit by rviz) and
    form solid areas; a map pixel differs from the background colour, is
    unsaturated (max - min channel <= half the max) and lies in a solid area
    (at least 90% of its 7 x 7 neighbourhood differs from the background).
    That leaves out the background, the grid's thin grey lines, text labels,
    frontiers (orange), the path (green) and TF axes (pure red, green, blue).
    error_pixels counts pixels outside the 3D view in rviz's error text colour
    (a display or the global status in error, e.g. "Global Status: Error").
    object_pixels counts pixels of the 3D view in the chair class colour
    (CHAIR_RGB): the boxes and labels object_map draws with each chair's
    mesh, seen only where nothing (a ceiling) hides them."""
    import numpy as np
    from PIL import Image
    rgb = np.asarray(Image.open(png).convert("RGB")).astype(np.int16)
    region = view_region(rgb)
    res = {"view": region, "view_pixels": 0, "map_pixels": 0, "map_fraction": 0.0, "error_pixels": 0,
           "object_pixels": 0}
    if region is None:
        return res
    r0, r1, c0, c1 = region
    error = np.all(rgb == np.array(ERROR_RGB, dtype=rgb.dtype), axis=2)
    error[r0:r1, c0:c1] = False
    res["error_pixels"] = int(error.sum())
    v = rgb[r0:r1, c0:c1]
    hi, lo = v.max(axis=2), v.min(axis=2)
    drawn = np.abs(v - np.array(BACKGROUND_RGB, dtype=v.dtype)).max(axis=2) > 6
    is_map = drawn & (2 * (hi - lo) <= hi) & (_box_mean(drawn, 7) >= 0.9)
    res["view_pixels"] = int(v.shape[0] * v.shape[1])
    res["map_pixels"] = int(is_map.sum())
    res["map_fraction"] = res["map_pixels"] / res["view_pixels"]
    res["object_pixels"] = int(((v[:, :, 2] >= 200) & (v[:, :, 0] <= 90) & (v[:, :, 1] >= 60) & (v[:, :, 1] <= 130)).sum())
    return res


def settled_screenshot(rviz, png, timeout_s, period_s=1.5, min_object_pixels=0):
    """Screenshots every period_s until the 3D view is drawn, its map pixel
    count is within 2% of the previous shot's and it shows at least
    min_object_pixels object pixels, or timeout_s; returns map_pixels() of
    the last. (The simulation runs on meanwhile: a chair first mapped under
    a desk is hidden by the desk top until the map holds one in the open.)"""
    deadline = time.time() + timeout_s
    prev = None
    while True:
        rviz.check_alive()
        rviz.screenshot(png)
        m = map_pixels(png)
        if m["view"] is not None and prev is not None and prev["view"] == m["view"] and \
                abs(m["map_pixels"] - prev["map_pixels"]) <= 0.02 * max(prev["map_pixels"], 100) and \
                m["object_pixels"] >= min_object_pixels:
            return m
        if time.time() + period_s > deadline:
            return m
        prev = m
        time.sleep(period_s)


class MapWatch:
    """Counts the occupied map clouds published (rospy.AnyMsg: not decoded).
    Being a subscriber also makes background_map publish them. Needs a rospy
    node in this process."""

    def __init__(self):
        import rospy
        self.count = 0
        self._sub = rospy.Subscriber(OCCUPIED_TOPIC, rospy.AnyMsg, self._on_cloud, queue_size=1)

    def _on_cloud(self, _):
        self.count += 1

    def close(self):
        self._sub.unregister()


def take(rviz, png, config, watch, timeout_s, wait_topic=OCCUPIED_TOPIC, min_object_pixels=0):
    """Starts rviz with config on rviz's display, waits until it subscribed to
    wait_topic and a map cloud was published after that (so rviz has one),
    then takes a settled screenshot (see settled_screenshot) into png and
    stops rviz. Returns map_pixels() of the screenshot."""
    deadline = time.time() + timeout_s
    rviz.start_rviz(config)
    try:
        if not rviz.wait_subscribed(wait_topic, deadline - time.time()):
            rviz.check_alive()
            raise RuntimeError("rviz did not subscribe to %s (see %s)" % (
                wait_topic, os.path.join(rviz.log_dir, "rviz.log")))
        n0 = watch.count
        while watch.count < n0 + 2:  # the second: rviz has had one cloud for a publish period
            if time.time() > deadline:
                raise RuntimeError("no occupied map was published while rviz ran")
            rviz.check_alive()
            time.sleep(0.2)
        return settled_screenshot(rviz, png, max(3.0, deadline - time.time()), min_object_pixels=min_object_pixels)
    finally:
        rviz.stop_rviz()


def screenshot_scene(env, png, bounds_min, bounds_max, log_dir, timeout_s=90.0, control_png=None, uncut_png=None,
                     hide=None, min_object_pixels=0):
    """The screenshot of a running exploration (the master in env, a rospy
    node in this process): rviz with the project's config, its view fitted to
    [bounds_min, bounds_max] (m), on Xvfb, into png. With control_png, a second
    one with the occupied map display on an unused topic; with uncut_png, one
    of the whole map (UNCUT_TOPICS: the ceiling left in); hide: display topics put
    on an unused one in every screenshot; min_object_pixels: png (only) is
    retaken until it shows that many object pixels or timeout_s. Returns
    {png: map_pixels()}; logs go to log_dir."""
    os.makedirs(log_dir, exist_ok=True)
    work = tempfile.mkdtemp(prefix="rviz_screenshot.")
    watch = MapWatch()
    res = {}
    try:
        with HeadlessRviz(env, log_dir) as rviz:
            shots = [(png, None, None)] + ([(control_png, "/rviz_screenshot/no_map", None)] if control_png else []) \
                + ([(uncut_png, None, UNCUT_TOPICS)] if uncut_png else [])
            for i, (path, topic, topics) in enumerate(shots):
                topics = dict(topics or {}, **{t: "/rviz_screenshot/hidden" for t in hide or []})
                cfg = write_view_config(find_config(), os.path.join(work, "view%d.rviz" % i), bounds_min,
                                        bounds_max, topic, topics)
                wait = topic or (topics or {}).get(OCCUPIED_TOPIC, OCCUPIED_TOPIC)
                for attempt in range(1, RVIZ_START_ATTEMPTS + 1):
                    try:
                        res[path] = take(rviz, path, cfg, watch, timeout_s, wait,
                                         min_object_pixels if path == png else 0)
                        break
                    except RvizExited as e:
                        if attempt == RVIZ_START_ATTEMPTS:
                            raise
                        print("[rviz] %s; starting it again (attempt %d of %d)" % (e, attempt + 1, RVIZ_START_ATTEMPTS),
                              file=sys.stderr, flush=True)
    finally:
        watch.close()
        shutil.rmtree(work, ignore_errors=True)
    return res


def _import_mission():
    sys.path.insert(0, HERE)
    import run_mission
    return run_mission


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True, help="directory for rviz.png (and logs/)")
    ap.add_argument("--seed", type=int, default=0, help="generator seed")
    ap.add_argument("--size", type=float, nargs=3, default=[6.0, 5.0, 3.0], metavar=("X", "Y", "H"))
    ap.add_argument("--min-explored-m3", type=float, default=10.0,
                    help="take the screenshot once the background map has explored this much, m^3")
    ap.add_argument("--min-objects", type=int, default=0,
                    help="and once the object map holds this many objects with a surface")
    ap.add_argument("--min-object-pixels", type=int, default=0,
                    help="retake rviz.png until it shows this many object (chair box and label) pixels, "
                         "or --timeout-s")
    ap.add_argument("--timeout-s", type=float, default=90.0, help="limit for the simulation and for each screenshot, s")
    ap.add_argument("--control", action="store_true",
                    help="also rviz_no_map.png: the same view with the occupied map display on an unused topic")
    ap.add_argument("--no-candidates", action="store_true",
                    help="candidate views off (their winner path line has the objects' blue)")
    ap.add_argument("--uncut", action="store_true",
                    help="also rviz_uncut.png: the same view of the whole map (no display cut: the ceiling shows)")
    args = ap.parse_args(argv)
    missing = missing_tools()
    if missing:
        print("[rviz] missing %s (scripts/setup.sh installs them)" % ", ".join(missing), file=sys.stderr)
        return 2
    mission = _import_mission()
    out = os.path.abspath(args.out)
    logs = os.path.join(out, "logs")
    os.makedirs(logs, exist_ok=True)
    t0 = time.time()
    work = tempfile.mkdtemp(prefix="rviz_screenshot.")
    launch = None
    try:
        ply, gt = mission.prepare_scene(argparse.Namespace(scene="", seed=args.seed, size=args.size), work)
        overrides = os.path.join(work, "overrides.yaml")
        mission.write_overrides(overrides, gt, ["chair"])
        port = mission._free_port()
        env = dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:%d" % port, ROS_HOSTNAME="127.0.0.1",
                   ROS_HOME=os.path.join(logs, "ros_home"))
        cmd = ["roslaunch", "-p", str(port), "semantic_exploration", "sim.launch", "scene:=" + ply,
               "overrides:=" + overrides, "lockstep:=true", "real_time_factor:=0", "rviz:=false",
               "output:=log"]
        launch = subprocess.Popen(cmd, env=env, stdout=open(os.path.join(logs, "roslaunch.log"), "w"),
                                  stderr=subprocess.STDOUT, start_new_session=True)
        explored = wait_explored(env, args.min_explored_m3, t0 + args.timeout_s, launch, args.min_objects)
        import rospy
        print("[rviz] background map explored %.1f m3 after %.0f s" % (explored, time.time() - t0), flush=True)
        shots = screenshot_scene(env, os.path.join(out, "rviz.png"), gt["bounds_min"], gt["bounds_max"], logs,
                                 args.timeout_s, os.path.join(out, "rviz_no_map.png") if args.control else None,
                                 os.path.join(out, "rviz_uncut.png") if args.uncut else None,
                                 [CANDIDATES_TOPIC] if args.no_candidates else None, args.min_object_pixels)
        for png, m in shots.items():
            print("[rviz] %s: 3D view %s, %d of %d pixels show the map (%.1f%%), %d error-coloured pixels, "
                  "%d object pixels" % (png, m["view"], m["map_pixels"], m["view_pixels"], 100 * m["map_fraction"],
                                        m["error_pixels"], m["object_pixels"]), flush=True)
        print("[rviz] sim time %.1f s" % rospy.get_time(), flush=True)
    finally:
        _stop(launch, grace_s=20.0)
        shutil.rmtree(work, ignore_errors=True)
    print("[rviz] done in %.0f s" % (time.time() - t0), flush=True)
    return 0


def wait_explored(env, min_m3, deadline, launch, min_objects=0):
    """Waits until background_map/stats reports min_m3 explored (m^3) and
    object_map/objects holds min_objects objects; returns the explored volume.
    Makes this process a rospy node on env's master."""
    os.environ.update(ROS_MASTER_URI=env["ROS_MASTER_URI"], ROS_HOSTNAME=env["ROS_HOSTNAME"],
                      ROS_HOME=env["ROS_HOME"])
    import rosgraph
    while not rosgraph.is_master_online():
        if launch.poll() is not None or time.time() > deadline:
            raise RuntimeError("roslaunch did not come up")
        time.sleep(0.3)
    import rospy
    from semantic_exploration.msg import MapStats, ObjectArray
    rospy.init_node("rviz_screenshot", anonymous=True, disable_signals=True)
    latest = [0.0]
    objects = [0]

    def on_stats(msg):
        latest[0] = msg.explored_volume_m3

    sub = rospy.Subscriber("/background_map/stats", MapStats, on_stats, queue_size=2)
    # objects with a surface: object_map draws their mesh, box and label
    obj_sub = rospy.Subscriber("/object_map/objects", ObjectArray, lambda m: objects.__setitem__(
        0, sum(1 for o in m.objects if o.voxel_count > 0)), queue_size=2)
    while latest[0] < min_m3 or objects[0] < min_objects:
        if launch.poll() is not None:
            raise RuntimeError("the simulation stopped before the map explored %.1f m3 with %d objects"
                               % (min_m3, min_objects))
        if time.time() > deadline:
            raise RuntimeError("the map explored only %.1f m3 with %d objects before the timeout"
                               % (latest[0], objects[0]))
        time.sleep(0.2)
    sub.unregister()
    obj_sub.unregister()
    return latest[0]


if __name__ == "__main__":
    sys.exit(main())
