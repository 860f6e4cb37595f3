"""The core/ROS separation check: passes on the real core, fails on a core
file that includes a ROS header."""
import os
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CHECK = os.path.join(ROOT, "cmake", "check_core_ros_free.cmake")


def run_check(dirs):
    return subprocess.run(["cmake", "-DCORE_DIRS=" + ";".join(dirs), "-P", CHECK],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)


def test_real_core_is_ros_free():
    proc = run_check([os.path.join(ROOT, "src", "core"),
                      os.path.join(ROOT, "include", "semantic_exploration", "core")])
    assert proc.returncode == 0, proc.stdout


@pytest.mark.parametrize("header", ["ros/ros.h", "sensor_msgs/Image.h", "tf2_ros/buffer.h",
                                    "semantic_exploration/ros/params.hpp"])
def test_check_fails_on_ros_include(tmp_path, header):
    (tmp_path / "bad.cpp").write_text('#include <vector>\n#include <%s>\nint x;\n' % header)
    proc = run_check([str(tmp_path)])
    assert proc.returncode != 0, header
    assert "bad.cpp" in proc.stdout and "ROS-free" in proc.stdout


def test_check_ignores_non_ros_includes(tmp_path):
    (tmp_path / "ok.hpp").write_text(
        '#include <Eigen/Core>\n#include "semantic_exploration/core/camera.hpp"\n// ros/ros.h in a comment\n')
    assert run_check([str(tmp_path)]).returncode == 0
