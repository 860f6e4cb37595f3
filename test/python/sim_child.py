"""A test that runs itself as a ROS node beside a launched simulator: its own
master on a free port, the test file started again as a child with the work
folder as its argument, and the events the child wrote to
WORK/events.json. Shared by test_sim_startup.py and test_sim_bad_requests.py."""
import json
import os
import subprocess
import sys
import time

# scripts/ (conftest.py puts it on the path): a free port, and stopping a process group.
import rviz_screenshot
import run_mission


def master(work, procs):
    """Starts roscore on a free port, appended to procs (for stop_all) before
    it is waited for; returns the environment that names that master."""
    port = run_mission._free_port()
    env = dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:%d" % port, ROS_HOSTNAME="127.0.0.1",
               ROS_HOME=os.path.join(work, "ros_home"))
    procs.append(subprocess.Popen(["roscore", "-p", str(port)], env=env, stdout=subprocess.DEVNULL,
                                  stderr=subprocess.STDOUT, start_new_session=True))
    time.sleep(3.0)
    return env


def start_child(script, work, env):
    """`script` (the test file) run again as the child node, logging to WORK/child.log."""
    return subprocess.Popen([sys.executable, script, work], env=env, stdout=open(os.path.join(work, "child.log"), "w"),
                            stderr=subprocess.STDOUT, start_new_session=True)


def child_events(kid, work, timeout_s, why):
    """Waits up to timeout_s for the child, prints its log, fails with `why`
    unless it finished cleanly, and returns the events it wrote."""
    try:
        kid.wait(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        pass
    with open(os.path.join(work, "child.log")) as f:
        print(f.read())
    assert kid.returncode == 0, why
    with open(os.path.join(work, "events.json")) as f:
        return json.load(f)


def stop_all(procs):
    """Stops the processes, the last started first."""
    for p in reversed(procs):
        rviz_screenshot._stop(p, grace_s=20.0)


def start_sim(work, env, *launch_args):
    """sim_only.launch with launch_args (scene:=..., ...), logging to WORK/sim.log."""
    return subprocess.Popen(["roslaunch", "semantic_exploration", "sim_only.launch"] + list(launch_args) +
                            ["output:=log"], env=env, stdout=open(os.path.join(work, "sim.log"), "w"),
                            stderr=subprocess.STDOUT, start_new_session=True)
