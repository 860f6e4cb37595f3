#!/usr/bin/env python3
"""Runs one simulated exploration mission and writes its report.

Generates a house (or takes a scene file), exports its ground truth, starts
the simulator and every node (sim.launch) on a private ROS master, shows
progress while the MAV explores, stops when the planner reports the mission
finished or a limit is reached, saves the maps and writes report.md and
summary.json into the output directory.

Example:
  run_mission.py --mode semantic --seed 0 --size 15 12 3 --out results/run
  run_mission.py --scene my_scene_semantic.ply --mode classic --wall-limit-s 300
"""
import argparse
import csv
import os
import signal
import socket
import subprocess
import sys
import time


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _import_package():
    try:
        import semantic_exploration.sim  # noqa: F401
    except ImportError:  # running from the source tree
        sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src"))


def prepare_scene(args, out):
    """Generates the scene (unless given) and exports ground truth; returns (ply, gt doc).

    The ground truth's start is the pose the simulator will start from
    (--start, else the scene's, else the simulator's rule for a scene without
    one), which main() hands to the simulator too: the evaluation needs it to
    tell observable surface from the rest."""
    _import_package()
    from semantic_exploration.sim.classes import DEFAULT_CLASS_NAMES
    from semantic_exploration.sim.generator import generate
    from semantic_exploration.sim.scene import export_ground_truth, load_scene, save_habitat
    from semantic_exploration.sim.simulator import start_pose_of
    gt_dir = os.path.join(out, "ground_truth")
    if args.scene:
        scene = load_scene(args.scene)
        ply = os.path.abspath(args.scene)
    else:
        scene = generate(args.seed, args.size, None)
        ply = save_habitat(scene, os.path.join(out, "scene"))
    start = start_pose_of(scene, getattr(args, "start", None))
    doc = export_ground_truth(scene, gt_dir, DEFAULT_CLASS_NAMES, start=start)
    doc["gt_dir"] = gt_dir
    return ply, doc


def object_snapshots(out, gt, args):
    """Snapshots of the object map every --snapshot-period-s of sim time, matched to
    ground truth as the report matches (None with --snapshot-period-s 0)."""
    if args.snapshot_period_s <= 0:
        return None
    from semantic_exploration.eval import metrics
    from semantic_exploration.eval.snapshots import ObjectSnapshots
    from semantic_exploration.eval.truth import GroundTruthIndex
    index = GroundTruthIndex(metrics.load_ground_truth(gt["gt_dir"]), args.classes)
    index.objects  # sampled before the mission starts
    return ObjectSnapshots(index, lambda d: call_save("/object_map/save", d),
                           os.path.join(out, "snapshot", "objects"), args.snapshot_period_s,
                           keep_dir=os.path.join(out, "snapshot", "series"))


def launch_command(args, ply, overrides, port, start):
    """The roslaunch command line of a mission (sim.launch on a private master at port)."""
    return ["roslaunch", "-p", str(port), "semantic_exploration", "sim.launch",
            "mode:=" + args.mode, "scene:=" + ply, "overrides:=" + overrides,
            "classes_of_interest:=[%s]" % ", ".join(args.classes),
            "start_pose:=[%s]" % ", ".join(repr(float(v)) for v in start),
            "lockstep:=" + ("false" if args.no_lockstep and not args.deterministic else "true"),
            "real_time_factor:=%g" % args.real_time_factor, "rviz:=" + ("true" if args.rviz else "false"),
            "sim_overrides:=" + (os.path.abspath(args.sim_overrides) if args.sim_overrides else ""),
            ] + (["lockstep_nodes:=[background_map, object_map, depth_history, mission]"] if args.deterministic
                 else []) + [
            "bag:=" + (os.path.abspath(args.record_bag) if args.record_bag else ""),
            "output:=log"]


def write_overrides(path, gt, classes, margin_m=0.5):
    """Bounds of the C++ nodes = the scene's box plus a margin; classes of interest."""
    lo = [v - margin_m for v in gt["bounds_min"]]
    hi = [v + margin_m for v in gt["bounds_max"]]
    with open(path, "w") as f:
        f.write("# written by run_mission.py for this scene\n")
        f.write("bounds:\n  min_m: [%s]\n  max_m: [%s]\n" % (", ".join("%.3f" % v for v in lo),
                                                            ", ".join("%.3f" % v for v in hi)))
        f.write("classes:\n  of_interest: [%s]\n" % ", ".join(classes))


def combine_overrides(path, extra_path=""):
    """path with run_mission.py's own settings and --extra-overrides merged over it (eval/overrides.py)."""
    _import_package()
    from semantic_exploration.eval.overrides import combine_mission
    return combine_mission(path, extra_path)


def Monitor():
    """The run's log (semantic_exploration.eval.runlog.RunLog), subscribed live."""
    _import_package()
    from semantic_exploration.eval.runlog import RunLog
    return RunLog().subscribe()


def lockstep_timing(get_param):
    _import_package()
    from semantic_exploration.eval.lockstep import timing_of
    return timing_of(False, get_param)


def call_save(service, directory):
    import rospy
    from semantic_exploration.srv import SaveMap
    try:
        rospy.wait_for_service(service, timeout=5.0)
        res = rospy.ServiceProxy(service, SaveMap)(directory)
        return {"success": res.success, "message": res.message, "files": list(res.files)}
    except Exception as e:  # a node that died or does not answer must not lose the report
        return {"success": False, "message": "%s: %s" % (service, e), "files": []}


def rviz_screenshot(out, env, gt, timeout_s=60.0):
    """out/rviz.png: rviz with the project's config on Xvfb, its view fitted to
    the scene (scripts/rviz_screenshot.py); never fails the mission."""
    png = os.path.join(out, "rviz.png")
    try:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        import rviz_screenshot as shot
        missing = shot.missing_tools()
        if missing:
            return {"success": False, "message": "rviz screenshot: missing %s" % ", ".join(missing), "files": []}
        m = shot.screenshot_scene(env, png, gt["bounds_min"], gt["bounds_max"], os.path.join(out, "rviz_logs"),
                                  timeout_s)[png]
        return {"success": True, "files": [png], "message": "rviz screenshot: %.0f%% of the 3D view shows the map" % (
            100 * m["map_fraction"])}
    except Exception as e:
        return {"success": False, "message": "rviz screenshot: %s" % e, "files": []}


def stop_launch(launch):
    """SIGINT to roslaunch's process group (SIGKILL after 20 s); no-op once it has ended."""
    if launch.poll() is not None:
        return
    os.killpg(launch.pid, signal.SIGINT)
    try:
        launch.wait(timeout=20)
    except subprocess.TimeoutExpired:
        os.killpg(launch.pid, signal.SIGKILL)
        launch.wait()


def parse_args(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mode", choices=["semantic", "classic"], default="semantic")
    ap.add_argument("--scene", default="", help="scene file; default: generate a house")
    ap.add_argument("--start", type=float, nargs=4, default=None, metavar=("X", "Y", "Z", "YAW"),
                    help="start pose (m, rad); default: the scene's, else the centre of its box at 1.2 m")
    ap.add_argument("--seed", type=int, default=0, help="generator seed")
    ap.add_argument("--size", type=float, nargs=3, default=[10.0, 8.0, 3.0], metavar=("X", "Y", "H"),
                    help="generated house size, m (default 10 8 3)")
    ap.add_argument("--classes", nargs="+", default=["chair"], help="classes of interest")
    ap.add_argument("--out", default=os.path.join("results", "run-" + time.strftime("%Y%m%d-%H%M%S")))
    ap.add_argument("--wall-limit-s", type=float, default=None,
                    help="stop after this wall time, s: a guard against a stuck run, not the mission's end "
                         "(default 3 x --sim-limit-s, at least 1800 s: lockstep simulation runs slower than "
                         "real time on a loaded 2-core machine)")
    ap.add_argument("--sim-limit-s", type=float, default=600.0, help="stop after this sim time, s")
    ap.add_argument("--real-time-factor", type=float, default=0.0, help="0 = as fast as lockstep allows")
    ap.add_argument("--no-lockstep", action="store_true")
    ap.add_argument("--deterministic", action="store_true",
                    help="repeatable run: OMPL stops on iterations (config/deterministic.yaml), mav_sim asks the "
                    "planner for each path with sim time stopped and waits for this mission at every frame "
                    "(config/deterministic_sim.yaml); two runs give the same timeseries.csv but for wall-time "
                    "columns (make experiments' default; make run keeps wall-time budgets)")
    ap.add_argument("--rviz", action="store_true")
    ap.add_argument("--rviz-screenshot", action="store_true",
                    help="at the end, save rviz.png: rviz with the project's config on Xvfb "
                    "(scripts/rviz_screenshot.py)")
    ap.add_argument("--progress-period-s", type=float, default=10.0)
    ap.add_argument("--period-s", type=float, default=1.0, help="timeseries.csv row period, s of sim time")
    ap.add_argument("--background-snapshot-period-s", type=float, default=30.0,
                    help="background map snapshot period, s of sim time, for the time series' background "
                    "accuracy and completeness (scored after the run); 0 = none")
    ap.add_argument("--snapshot-period-s", type=float, default=5.0,
                    help="object map snapshot period, s of sim time: objects found in timeseries.csv "
                    "(ground_truth_found) are matched as in the report at each snapshot; 0 = none")
    ap.add_argument("--extra-overrides", default="", help="YAML for the C++ nodes loaded after the scene's")
    ap.add_argument("--record-bag", default="", help="also record the run into this bag (launch/record.launch); "
                    "scripts/evaluate_run.py --bag evaluates it")
    ap.add_argument("--no-eval", action="store_true",
                    help="skip scoring the saved meshes and map against ground truth (minutes on a loaded machine)")
    ap.add_argument("--sim-overrides", default="", help="YAML for the simulator loaded after config/sim.yaml "
                    "(e.g. faults: tf_gap_s, detector_scale, frame_drop_fraction)")
    args = ap.parse_args(argv)
    if not args.sim_limit_s > 0:
        ap.error("--sim-limit-s must be > 0 s")
    if args.wall_limit_s is None:
        args.wall_limit_s = max(1800.0, 3.0 * args.sim_limit_s)
    if not args.wall_limit_s > 0:
        ap.error("--wall-limit-s must be > 0 s")
    _import_package()
    from semantic_exploration.eval.overrides import unreadable
    why = unreadable(args.extra_overrides) if args.extra_overrides else ""
    if why:
        ap.error("--extra-overrides: " + why)
    return args


def main(argv=None):
    args = parse_args(argv)

    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    t0 = time.time()
    print("[mission] preparing the scene and its ground truth in %s" % out, flush=True)
    ply, gt = prepare_scene(args, out)
    from semantic_exploration.eval.report import detector_of, write_report
    overrides = os.path.join(out, "overrides.yaml")
    write_overrides(overrides, gt, args.classes)
    combine_overrides(overrides, args.extra_overrides)
    if args.deterministic:
        _import_package()
        from semantic_exploration.eval.lockstep import deterministic_setup
        deterministic_setup(args, out, overrides, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..",
                                                               "config"))
    print("[mission] scene %s: %d objects, %d of interest" % (
        gt["scene"], len(gt["objects"]), sum(o["class"] in args.classes for o in gt["objects"])), flush=True)

    port = _free_port()
    env = dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:%d" % port, ROS_HOSTNAME="127.0.0.1")
    env.setdefault("ROS_HOME", os.path.join(out, "ros_home"))
    os.environ.update(ROS_MASTER_URI=env["ROS_MASTER_URI"], ROS_HOSTNAME="127.0.0.1", ROS_HOME=env["ROS_HOME"])
    cmd = launch_command(args, ply, overrides, port, gt["start"])
    snaps = object_snapshots(out, gt, args)  # the ground truth's object samples, before the mission starts
    log_path = os.path.join(out, "roslaunch.log")
    print("[mission] %s  (log: %s)" % (" ".join(cmd), log_path), flush=True)
    log = open(log_path, "w")
    launch = subprocess.Popen(cmd, env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)

    reason = "wall_time_limit"
    saved = {}
    try:
        import rospy
        deadline = time.time() + 60.0
        while True:  # wait for the master that roslaunch starts and for its parameters:
            # rospy reads /use_sim_time once, in init_node; without it this node
            # would take wall time for sim time and stop at once on --sim-limit-s
            try:
                import rosgraph
                if rosgraph.is_master_online() and rosgraph.Master("/mission").hasParam("/use_sim_time"):
                    break
            except Exception:
                pass
            if launch.poll() is not None or time.time() > deadline:
                raise RuntimeError("roslaunch did not come up (see %s)" % log_path)
            time.sleep(0.5)
        # Deterministic: the node is mav_sim's lockstep node "mission" and must subscribe before frame 0.
        rospy.init_node("mission", anonymous=not args.deterministic, disable_signals=True)
        if args.deterministic:
            from semantic_exploration.eval import lockstep
            barrier = lockstep.FrameBarrier()
            mon = lockstep.RunLog()
            stamped = lockstep.StampedLog(mon).subscribe()
        else:
            mon = Monitor()
        detector = detector_of(getattr(args, "user_sim_overrides", args.sim_overrides),
                               rospy.get_param("/mav_sim/detector/min_mask_pixels", None))
        args.camera_rate_hz = rospy.get_param("/mav_sim/camera/rate_hz", None)
        gt_objs = [o for o in gt["objects"] if o["class"] in args.classes]
        n_gt = len(gt_objs)
        occupied = None
        if args.background_snapshot_period_s > 0:
            from semantic_exploration.eval.snapshots import OccupiedSnapshots, grab_occupied
            occupied = OccupiedSnapshots(grab_occupied, os.path.join(out, "snapshot", "series"),
                                         args.background_snapshot_period_s)
        series = open(os.path.join(out, "timeseries.csv"), "w")
        writer = None

        def write_row(sim_s, wall_s):
            nonlocal writer
            row = mon.row(sim_s, wall_s, gt_objs)
            if writer is None:
                writer = csv.DictWriter(series, fieldnames=list(row))
                writer.writeheader()
            writer.writerow(row)
            series.flush()

        def stop_reason(sim):
            if mon.finished():
                return mon.status.termination_reason or "finished"
            if launch.poll() is not None:
                return "a node died (see %s)" % log_path
            if time.time() - t0 > args.wall_limit_s:
                return "wall_time_limit"
            return "sim_time_limit" if sim is not None and sim > args.sim_limit_s else ""
        next_print = next_row = 0.0
        if args.deterministic:  # rows, snapshots and the stop at frame boundaries (eval/lockstep.py)
            args.timing = lockstep.timing_of(True, rospy.get_param)
            at = {"frame": rospy.Time(0)}
            if occupied is not None:  # the cloud of the frame the simulator waits at
                occupied.grab = lambda: grab_occupied(since=at["frame"])

            def take_snapshots(sim):
                at["frame"] = rospy.Time.from_sec(sim)
                if snaps is not None and snaps.due(sim):
                    snaps.take(sim, mon)
                if occupied is not None and occupied.due(sim):
                    occupied.take(sim)

            def progress(sim):
                nonlocal next_print
                if time.time() >= next_print:
                    print(mon.line(sim, time.time() - t0, n_gt), flush=True)
                    next_print = time.time() + args.progress_period_s
            reason, sim_end = lockstep.run_lockstep(
                barrier, stamped, lockstep.RowClock(args.period_s), lambda t: write_row(t, time.time() - t0),
                take_snapshots, stop_reason, progress)
        while not args.deterministic:
            wall = time.time() - t0
            sim = rospy.get_time()
            if snaps is not None and snaps.due(sim):
                snaps.take(sim, mon)
            if occupied is not None and occupied.due(sim) and sim > 0:
                occupied.take(sim)
            if sim >= next_row:  # one row every --period-s of sim time
                write_row(sim, wall)
                next_row = (sim // args.period_s + 1) * args.period_s
            if time.time() >= next_print:
                print(mon.line(sim, wall, n_gt), flush=True)
                next_print = time.time() + args.progress_period_s
            reason = stop_reason(sim)
            if reason:
                args.timing = lockstep_timing(rospy.get_param)
                break
            time.sleep(0.05)
        print(mon.line(rospy.get_time(), time.time() - t0, n_gt), flush=True)
        # The simulator runs on while the maps are saved: the report's figures are those at the stop.
        mon.freeze()
        wall_end = time.time() - t0
        sim_end = sim_end if args.deterministic else rospy.get_time()
        # Deterministic: the maps first, while the simulator still waits at the stop frame.
        for step in (["maps", "rviz"] if args.deterministic else ["rviz", "maps"]):
            if step == "rviz" and args.rviz_screenshot and launch.poll() is None:
                print("[mission] rviz screenshot (headless)", flush=True)
                saved["rviz"] = rviz_screenshot(out, env, gt)
                print("[mission] %s" % saved["rviz"]["message"], flush=True)
            elif step == "maps":
                print("[mission] stopping: %s; saving maps" % reason, flush=True)
                saved["background_map"] = call_save("/background_map/save", os.path.join(out, "map"))
                saved["object_map"] = call_save("/object_map/save", os.path.join(out, "objects"))
        if writer is not None:  # the last row: found as the report counts it, from the saved object map
            if snaps is not None and saved["object_map"]["success"]:
                from semantic_exploration.eval.metrics import load_reconstruction
                mon.found_ids = snaps.index.found(load_reconstruction(os.path.join(out, "objects")))
                mon.found_at_s = sim_end
            write_row(sim_end, wall_end)
        series.close()
        if snaps is not None:
            args.snapshot_summary = snaps.summary(wall_end)
        if occupied is not None:
            args.background_snapshot_summary = occupied.summary(wall_end)
        # The evaluation reads only the saved files: stop the simulator and
        # the nodes first instead of letting them run on beside it.
        stop_launch(launch)
        summary = write_report(out, args, gt, mon, saved, sim_end, wall_end, reason, detector)
    finally:
        stop_launch(launch)
        log.close()
    print("[mission] report: %s" % os.path.join(out, "report.md"))
    print("[mission] summary: %s" % os.path.join(out, "summary.json"))
    found = summary["ground_truth_found"]
    print("[mission] %s: %s of %d ground-truth objects found (%d map objects), explored %.1f m3, %d collisions, "
          "%.0f s wall" % (summary["termination_reason"], "?" if found is None else found,
                           summary["ground_truth_objects"], summary["map_objects"], summary["explored_volume_m3"],
                           summary["collisions"], summary["wall_time_s"]))
    print("[mission] %s\n[mission] %s" % (mon.drop_report_lines()[0], summary["cpu_budget"]["target_line"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
