"""Cameras: frames per second per renderer, size and world; what a camera costs a run.

    python3 bench/bench_camera.py [--corpus PATH] [--frames 30] [--repeat 3] [--seconds 10]

1. Frames per second of one camera (RGB: ``camera``; depth: ``depth_camera``) at 320x240 and
   640x480 in the empty world, the bundled house and the AWS small house (corpus), for each
   renderer that loads here (TinyRenderer always; the EGL plugin when it loads): the robot stands
   still, each frame is taken and read through the world's sensing as a run does, best of
   ``--repeat`` rounds of ``--frames`` frames, the configurations interleaved round by round.
2. The issue's goal: the bundled mobot with ``camera:=true`` (320x240 RGB-D at 15 Hz) driving in
   the bundled house for ``--seconds`` simulated seconds with the physics engine, recorded (the
   PNG frames written), against the same run without the camera: real-time factors, interleaved.
3. The same pair on the kinematic engine: the cost of one camera on a kinematic run.
4. Where a TinyRenderer frame goes in the bundled house: the frame's CPU time as drawn (the static
   world's tiled copies, sim/sensing/tiles.py), with the static bodies' collision shapes drawn
   instead (the copies made transparent), and with no static world.

Times are wall and CPU (``time.process_time``: the whole process, the EGL plugin's llvmpipe threads
included): on a shared machine CPU time is the steadier of the two.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.common import REPO, timed  # noqa: E402
from mobot_cli.api.simulation import Simulation  # noqa: E402
from mobot_cli.cli import invoke  # noqa: E402
from mobot_cli.sim.pb import p  # noqa: E402
from mobot_cli.sim.sensing import render  # noqa: E402

SMALL_HOUSE = "aws-robomaker-small-house-world/worlds/small_house.world"
POSES = {"empty": (0.0, 0.0, 0.0), "house": (-3.0, -2.5, 0.0), "small house": (3.5, 1.0, 0.0)}


def scenario(folder: Path, world: str, pose, kind: str, size: tuple[int, int], renderer: str) -> Path:
    path = folder / f"{abs(hash((world, kind, size, renderer)))}.yaml"
    x, y, yaw = pose
    path.write_text(f"version: 1\nname: cam\nworld: {world}\nduration: 1000\nsettle: 0.0\n"
                    f"physics: {{renderer: {renderer}}}\nrobots:\n  - name: r\n    description: mobot\n"
                    f"    pose: {{x: {x}, y: {y}, yaw: {yaw}}}\n    sensors:\n"
                    f"      cam: {{type: {kind}, link: base_link, width: {size[0]}, height: {size[1]}, "
                    f"rate_hz: 240, clip_far: 20.0, pose: {{xyz: [0.1, 0, 0.2]}}}}\n")
    return path


def fps(sim: Simulation, frames: int) -> tuple[float, float]:
    """Frames a second (by wall time, by CPU time), each taken and read as a run reads it."""
    world = sim._world  # noqa: SLF001 - the world's sensing, without the timeline's bookkeeping

    def take() -> None:
        for _ in range(frames):
            data = world.sense([("r", "cam")])[0]
            data.rgb, data.depth  # noqa: B018 - reading renders

    wall, cpu = timed(take)
    return frames / wall, frames / max(cpu, 1e-9)


def renderers() -> list[str]:
    out = ["tiny"]
    if render.egl_ships():
        with tempfile.TemporaryDirectory() as tmp, Simulation.open(
                scenario(Path(tmp), "empty", (0, 0, 0), "camera", (32, 24), "egl")) as sim:
            sim.image("r")
            if any("EGL plugin (OpenGL)" in n for n in sim._timeline.notices):  # noqa: SLF001
                out.append("egl")
    return out


def rendering(worlds: dict[str, str], frames: int, repeat: int, tmp: Path) -> None:
    configs = [(label, world, kind, size, renderer) for label, world in worlds.items()
               for renderer in renderers() for size in ((320, 240), (640, 480)) for kind in ("camera", "depth_camera")]
    sims = {}
    for label, world, kind, size, renderer in configs:
        sim = Simulation.open(scenario(tmp, world, POSES[label], kind, size, renderer))
        sim.step(10)
        fps(sim, 2)  # warm: the renderer is made, meshes are loaded
        sims[(label, kind, size, renderer)] = sim
    best = {key: (0.0, 0.0) for key in sims}
    for _ in range(repeat):
        for key, sim in sims.items():
            best[key] = tuple(map(max, best[key], fps(sim, frames)))
    print("| world | renderer | size | RGB fps (wall / CPU) | depth fps (wall / CPU) |\n|---|---|---|---|---|")
    for label in worlds:
        for renderer in renderers():
            for size in ((320, 240), (640, 480)):
                rgb, depth = best[(label, "camera", size, renderer)], best[(label, "depth_camera", size, renderer)]
                print(f"| {label} | {renderer} | {size[0]}x{size[1]} | {rgb[0]:.1f} / {rgb[1]:.1f} "
                      f"| {depth[0]:.1f} / {depth[1]:.1f} |")
    for sim in sims.values():
        sim.close()


def run_factor(tmp: Path, engine: str, camera: bool, seconds: float, renderer: str) -> tuple[float, float]:
    """Real-time factors (by wall time, by CPU time) of a recorded run of the bundled mobot driving
    in the bundled house."""
    path = tmp / f"run_{engine}_{camera}_{renderer}.yaml"
    path.write_text(f"version: 1\nname: run\nworld: house\nduration: {seconds}\nsettle: 0.5\n"
                    f"physics: {{engine: {engine}, renderer: {renderer}}}\n"
                    "robots:\n  - name: r\n    description: mobot\n"
                    f"    args: {{camera: '{str(camera).lower()}'}}\n    pose: {{x: -3.0, y: -2.5}}\n"
                    "    commands:\n      - {at: 0.5, linear: 0.2, angular: 0.1}\n")
    wall, cpu = time.perf_counter(), time.process_time()
    done = invoke(["run", str(path), "--out", str(tmp / f"out_{engine}_{camera}_{renderer}"), "--quiet"])
    assert done.exit_code == 0, done.stderr
    return seconds / (time.perf_counter() - wall), seconds / (time.process_time() - cpu)


def runs(tmp: Path, seconds: float, repeat: int, renderers: list[str]) -> None:
    for engine in ("bullet", "kinematic"):
        cases = [(False, "tiny")] + [(True, r) for r in renderers]
        best = {case: (0.0, 0.0) for case in cases}
        for _ in range(repeat):
            for camera, renderer in cases:
                best[(camera, renderer)] = tuple(map(max, best[(camera, renderer)],
                                                     run_factor(tmp, engine, camera, seconds, renderer)))
        without = best[(False, "tiny")]
        withs = ", ".join(f"{best[(True, r)][0]:.2f}x / {best[(True, r)][1]:.2f}x with it on {r}" for r in renderers)
        print(f"{engine}: {seconds:g} s in the bundled house, recorded, a 320x240 RGB-D camera at 15 Hz, "
              f"real-time factor by wall / CPU time: {without[0]:.1f}x / {without[1]:.1f}x without the camera, "
              f"{withs}; best of {repeat}")


def breakdown(tmp: Path, frames: int, repeat: int) -> None:
    """A TinyRenderer frame's CPU time in the bundled house: as drawn (the static world's tiled
    copies, sim/sensing/tiles.py), with its collision shapes drawn instead, and with no static world."""
    with Simulation.open(scenario(tmp, "house", POSES["house"], "camera", (320, 240), "tiny")) as sim:
        sim.step(10)
        cid = sim._world._cid  # noqa: SLF001 - the bench hides bodies from the renderer only

        def ids() -> list[int]:
            every = (p.getBodyUniqueId(i, physicsClientId=cid) for i in range(p.getNumBodies(physicsClientId=cid)))
            return [u for u in every if p.getBodyInfo(u, physicsClientId=cid)[1] != b"mobot"]

        statics = ids()
        shapes = {u: p.getVisualShapeData(u, physicsClientId=cid) for u in statics}  # as they were
        fps(sim, 2)  # the renderer makes the copies and hides the statics
        copies = [u for u in ids() if u not in shapes]
        shapes.update({u: p.getVisualShapeData(u, physicsClientId=cid) for u in copies})

        def show(uids, visible: bool) -> None:
            for uid in uids:
                for shape in shapes[uid]:
                    p.changeVisualShape(uid, shape[1], rgbaColor=shape[7] if visible else (0, 0, 0, 0),
                                        physicsClientId=cid)

        def ms() -> float:
            return min(1000.0 / fps(sim, frames)[1] for _ in range(repeat))

        tiled = ms()
        show(copies, False)
        show(statics, True)
        plain = ms()
        show(statics, False)
        bare = ms()
        print(f"house, TinyRenderer, 320x240 RGB: {tiled:.1f} ms CPU a frame as drawn ({len(copies)} bodies copying "
              f"its {len(statics)} static bodies), {plain:.1f} ms with the collision shapes drawn instead, "
              f"{bare:.1f} ms without the static world")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--corpus", type=Path, default=Path(os.environ.get(
        "MOBOT_CORPUS", REPO.parent / "shared" / "corpus")))
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--seconds", type=float, default=10.0)
    args = parser.parse_args()
    worlds = {"empty": "empty", "house": "house"}
    if (args.corpus / SMALL_HOUSE).is_file():
        worlds["small house"] = str((args.corpus / SMALL_HOUSE).resolve())
    with tempfile.TemporaryDirectory() as tmp:
        rendering(worlds, args.frames, args.repeat, Path(tmp))
        runs(Path(tmp), args.seconds, args.repeat, renderers())
        breakdown(Path(tmp), args.frames, args.repeat)


if __name__ == "__main__":
    main()
