"""The plan loader's child answers in JSON checked against the plan's types, never a pickle
(record/plan_loader.py, mobot_cli/plan_json.py).

Every bundled scenario's plan (and every plan of the bundled sweeps) comes back equal, with the
same types and the same float bits; a plan with every kind of field, inf, nan and -0.0 too.
Whatever else the parent is handed (random bytes, a pickle, wrong types, extra or missing keys,
a huge answer) is a PlanRefused of one line, never another exception, and only the plan's own
dataclasses and plain values ever come out. The child's output is read with a bound.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import pickle
import struct
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mobot_cli import plan as plan_types
from mobot_cli import plan_json
from mobot_cli.plan import (
    CommandStep,
    DriveSpec,
    Event,
    Expectation,
    FaultLimits,
    GoalControl,
    GoalStep,
    JointHold,
    MoverPlan,
    Physics,
    Plan,
    RayAxis,
    RobotPlan,
    Ros2Settings,
    SensorSpec,
    SpawnPose,
    StaticBody,
    StaticShape,
    TwistStep,
    WorldPlan,
)
from mobot_cli.record.plan_loader import (
    MESSAGE_CHARS,
    AnswerTooLong,
    PlanRefused,
    load_plan,
    read_reply,
    run_bounded,
)
from mobot_cli.record.reader import ReadLimits
from mobot_cli.scenario.prepare import prepare

REPO = Path(__file__).resolve().parents[2]
SCENARIOS = sorted((REPO / "scenarios").glob("*.yaml"))
SWEEPS = sorted((REPO / "scenarios" / "sweeps").glob("*.yaml"))
FOLDER = Path("/runs/hostile")
CAP = 64 << 20
PLAN_CLASSES = {c for c in vars(plan_types).values() if isinstance(c, type) and dataclasses.is_dataclass(c)}


def round_trip(plan: Plan) -> Plan:
    return read_reply(FOLDER, plan_json.dump((plan, None)), CAP)


def difference(a, b, where: str = "plan") -> str | None:
    """Where ``a`` and ``b`` differ in type or value (floats by their bits, any nan as nan); None if nowhere."""
    if type(a) is not type(b):
        return f"{where}: {type(a).__name__} != {type(b).__name__}"
    if dataclasses.is_dataclass(a):
        pairs = [(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}") for f in dataclasses.fields(a)]
    elif isinstance(a, tuple):
        if len(a) != len(b):
            return f"{where}: {len(a)} items != {len(b)}"
        pairs = [(x, y, f"{where}[{i}]") for i, (x, y) in enumerate(zip(a, b))]
    elif isinstance(a, float):
        same = (math.isnan(a) and math.isnan(b)) or struct.pack("<d", a) == struct.pack("<d", b)
        return None if same else f"{where}: {a!r} != {b!r}"
    else:
        return None if a == b else f"{where}: {a!r} != {b!r}"
    return next((d for x, y, w in pairs if (d := difference(x, y, w))), None)


def classes_in(value) -> set[type]:
    """Every type found in ``value``; anything but the plan's dataclasses, tuples and plain values fails."""
    if dataclasses.is_dataclass(value):
        assert type(value) in PLAN_CLASSES, type(value)
        found = {type(value)}
        for f in dataclasses.fields(value):
            found |= classes_in(getattr(value, f.name))
        return found
    if isinstance(value, tuple):
        return set().union(*(classes_in(v) for v in value)) | {tuple}
    assert value is None or type(value) in (str, int, float, bool), type(value)
    return {type(value)}


def full_plan() -> Plan:
    """A plan in which every dataclass and every optional field is there, with awkward floats."""
    lidar = SensorSpec("front", "lidar", "base_link", 4, (0.1, 0.0, 0.2), (0.0, 0.0, 0.0, 1.0), "scan", "laser",
                       RayAxis(360, -math.pi, math.pi, 1.0), RayAxis(16, -0.26, 0.26, 0.5), 0.1, math.inf, 0.01,
                       0.0, 0.01, 0.0, "", "robot.urdf", "", 0.0, 0.0)
    camera = SensorSpec("cam", "rgbd", "camera_link", 8, range_min=0.05, range_max=50.0, field_of_view=1.047,
                        width=64, height=48, encoding="rgb8", depth_clip=(0.1, math.inf))
    robot = RobotPlan(
        "bot", "/bot", "bot/", "<robot name='bot'><link name='base_link'/></robot>", "base_link",
        SpawnPose((1.0, -2.5, 0.0), (0.0, 0.0, math.sin(0.4), math.cos(0.4)), True),
        DriveSpec(("fl", "rl"), ("fr", "rr"), 0.1, 0.5, 1.02, 0.98, 7.5, 12.0, "ground_truth", True, "plugin",
                  (("fl", 1.0), ("fr", -1.0)), "ackermann", 0.8, ("steer_l", "steer_r"), 0.6, "urdf"),
        (CommandStep(0, 0.5, 0.0, -0.0),
         GoalStep(10, 1, "goto", ((3.0, 4.0),), yaw=1.5, control=GoalControl(timeout=500, planner="astar",
                                                                                    inflation=0.2, local="dwb")),
         GoalStep(20, 2, "patrol", ((0.0, 0.0), (1.0, 1.0)), laps=3),
         GoalStep(30, 3, "coverage", ((0.0, 0.0), (2.0, 0.0)), area=((0.0, 0.0), (2.0, 0.0), (2.0, 2.0)),
                  spacing=0.5),
         TwistStep(40, 4, 0.2, -0.1, hold=25, linear_y=0.05),
         TwistStep(41, 5, 0.0, 0.0)),
        spawn_step=3, source="/robots/bot.urdf.xacro", sensors=(lidar, camera),
        footprint=(-0.3, 0.3, -0.2, 0.2),
        holds=(JointHold("arm", "spring", 0.1, 5.0, 0.0, "springStiffness"), JointHold("lift", "position", 0.2,
                                                                                      0.0, 40.0, "ros2_control")))
    walker = MoverPlan("walker", "person", (0.3, 1.8), region=(-1.0, 1.0, -2.0, 2.0), speed=1.2, start=(0.0, 0.5),
                       source="scenario", spawn_step=7)
    actor = MoverPlan("actor", "box", (1.0, 1.0, 1.0), ((0.0, 0.0, 0.0, 0.0), (2.5, 1.0, 1.0, math.pi)),
                      loop=False, delay=0.5, auto_start=False, z=0.1, source="actor", curves=((0, 1, 0.5),))
    world = WorldPlan("w", False, (
        StaticBody("ground", shapes=(StaticShape("plane", (0.0, 0.0, 1.0)),)),
        StaticBody("shelf", "", (1.0, 2.0, 0.0), (0.0, 0.0, 0.0, 1.0),
                   (StaticShape("box", (1.0, 0.5, 2.0), "", (0.0, 0.0, 1.0), name="shelf::body"),
                    StaticShape("mesh", (1.0, 1.0, 1.0), "/meshes/shelf.obj")), friction=0.7, label="shelf"),
        StaticBody("urdf", "<robot name='u'><link name='l'/></robot>")),
        "/worlds/w.sdf", ("parked",), (actor,))
    return Plan(
        "full", Physics(1000, (0.0, 0.0, -9.80665), 20, "kinematic",
                        FaultLimits(1.0e-300, 5e-324, math.inf, 0.1 + 0.2), "tiny"),
        world, (robot,), 2**40, 7, 3, seed=2**32 - 1, formats=("csv", "mcap"),
        events=(Event(50, spawn=dataclasses.replace(robot, name="late")), Event(90, delete="late")),
        notices=("ünïcode ✓ text", ""),
        expectations=(Expectation("bot", "within", (("x", 5.0), ("radius", math.nan)), step=100),
                      Expectation("all", "visits", (), points=((1.0, 2.0),), status="reached", metric="spl")),
        ros2=Ros2Settings("n", "/ns", 7, 25, False, False, True),
        generated_world="<sdf version='1.7'><world name='g'/></sdf>", movers=(walker,), images="png")


# -- the round trip ----------------------------------------------------------------------------


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.stem)
def test_the_plan_of_every_bundled_scenario_comes_back_equal(path):
    plan = prepare(path).plan
    back = round_trip(plan)
    assert back == plan
    assert difference(plan, back) is None


@pytest.mark.parametrize("path", SWEEPS, ids=lambda p: p.stem)
def test_every_plan_of_the_bundled_sweeps_comes_back_equal(path):
    from mobot_cli.sweep.expand import expand
    from mobot_cli.sweep.spec import load_sweep_file

    plans = [prepared.plan for prepared in expand(load_sweep_file(path)).prepared]
    assert len(plans) >= 4
    for plan in plans:
        back = round_trip(plan)
        assert back == plan and difference(plan, back) is None


def test_a_plan_with_every_kind_of_field_comes_back_equal_to_the_bit():
    plan = full_plan()
    assert classes_in(plan) >= PLAN_CLASSES  # every dataclass of plan.py is in it
    text = plan_json.dump((plan, None))
    assert b"Infinity" in text and b"NaN" in text and b"-0.0" in text and b"5e-324" in text
    back = read_reply(FOLDER, text, CAP)
    assert difference(plan, back) is None
    assert back.physics.faults.max_speed == math.inf and math.isnan(back.expectations[0].limit("radius"))
    assert math.copysign(1.0, back.robots[0].commands[0].linear_y) == -1.0
    assert [type(c) for c in back.robots[0].commands] == [CommandStep, GoalStep, GoalStep, GoalStep, TwistStep,
                                                         TwistStep]
    assert back.robots[0].sensors[1].depth_clip == (0.1, math.inf) and back.total_steps == 2**40


finite = st.floats(allow_nan=False)
anything = st.floats(allow_nan=True, allow_infinity=True)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(gravity=st.tuples(anything, anything, anything), command=st.tuples(finite, anything, anything),
       steps=st.integers(0, 2**63), seed=st.integers(-2**70, 2**70), name=st.text(max_size=40),
       limits=st.lists(st.tuples(st.text(max_size=5), anything), max_size=4))
def test_any_floats_ints_and_text_come_back_exactly(gravity, command, steps, seed, name, limits):
    base = full_plan()
    robot = dataclasses.replace(base.robots[0], commands=(CommandStep(1, *command),) + base.robots[0].commands)
    plan = dataclasses.replace(base, name=name, seed=seed, total_steps=steps, robots=(robot,),
                               physics=dataclasses.replace(base.physics, gravity=gravity),
                               expectations=(Expectation("bot", "within", tuple(limits)),))
    assert difference(plan, round_trip(plan)) is None


@pytest.mark.parametrize("name", ["generated_barn", "house_people", "events"])
def test_a_run_folder_loaded_by_the_confined_child_gives_the_plan_resolved_here(name, tmp_path):
    """The real child and its JSON answer: the plan equals the one resolved in this process."""
    (tmp_path / "scenario.yaml").write_text(prepare(REPO / "scenarios" / f"{name}.yaml").resolved_yaml)
    loaded = load_plan(tmp_path, ReadLimits())
    here = prepare(tmp_path / "scenario.yaml").plan
    assert loaded == here and difference(here, loaded) is None


def test_text_json_cannot_hold_is_a_value_error_in_the_child():
    """A file name's undecodable bytes (surrogates): the child reports an error, not a traceback."""
    with pytest.raises(ValueError, match="not UTF-8"):
        plan_json.dump((dataclasses.replace(full_plan(), name="run\udcff"), None))


# -- hostile answers ---------------------------------------------------------------------------


def refusal(data: bytes, cap: int = CAP) -> str:
    with pytest.raises(PlanRefused) as caught:
        read_reply(FOLDER, data, cap)
    text = str(caught.value)
    assert "\n" not in text and text.startswith(str(FOLDER / "scenario.yaml")), text
    return text


def reply_json() -> list:
    return json.loads(plan_json.dump((full_plan(), None)))


def changed(edit) -> bytes:
    reply = reply_json()
    edit(reply[0])
    return json.dumps(reply).encode()


class _Evil:
    def __reduce__(self):
        return (os.system, (f"touch {_Evil.marker}",))


def test_a_pickle_is_refused_and_never_run(tmp_path):
    _Evil.marker = tmp_path / "pwned"
    assert "not a plan" in refusal(pickle.dumps(("ok", _Evil())))
    assert "not a plan" in refusal(pickle.dumps(("ok", full_plan())))
    assert not _Evil.marker.exists()


def _robot(p: dict) -> dict:
    return p["robots"][0]


CRAFTED = {
    "extra key in the plan": (lambda p: p.update(extra=1), "Unexpected keyword argument at 0.extra"),
    "extra key deep down": (lambda p: p["physics"]["faults"].update(__class__="os.system"), "0.physics.faults"),
    "class name as an object": (lambda p: p.update(world={"py/object": "os.system"}), "0.world"),
    "missing key": (lambda p: p.pop("name"), "Field required at 0.name"),
    "string for an int": (lambda p: p.update(total_steps="100"), "0.total_steps"),
    "float for an int": (lambda p: p.update(total_steps=1.5), "0.total_steps"),
    "bool for an int": (lambda p: p.update(seed=True), "0.seed"),
    "string for a float": (lambda p: p["physics"].update(gravity=[0, 0, "-9.81"]), "0.physics.gravity.2"),
    "int for a string": (lambda p: p.update(name=7), "0.name"),
    "dict for a tuple": (lambda p: p.update(robots={"0": _robot(p)}), "0.robots"),
    "tuple of the wrong length": (lambda p: p["physics"].update(gravity=[0.0, 0.0, -9.8, 1.0]), "gravity"),
    "command of no kind": (lambda p: _robot(p)["commands"][1].update(hold=3), "0.robots.0.commands.1"),
    "null for a plan": (lambda p: p.clear(), "Field required at 0.name (and 6 more)"),
}


@pytest.mark.parametrize("case", CRAFTED, ids=str)
def test_crafted_answers_of_the_wrong_shape_are_refused(case):
    edit, expected = CRAFTED[case]
    assert expected in refusal(changed(edit))


@pytest.mark.parametrize("data", [
    b"", b"null", b"{}", b"[]", b"[null]", b'["ok", {}]', b'[null, ["a", "b", "c"]]', b'[null, [1, "b"]]',
    b'[null, "boom"]', b'[{}, null] trailing', b"[" * 100_000, b"\xff\xfe\x00", b'[{"name": NaN}, null]',
    b'[null, ["a", "\\udcff"]]', b"[null, null, null]",
], ids=repr)
def test_garbage_answers_are_refused(data):
    assert "is not a plan" in refusal(data)


def test_an_answer_with_neither_or_both_a_plan_and_an_error_is_refused():
    assert "neither a plan nor an error" in refusal(b"[null, null]")
    both = reply_json()
    both[1] = ["Refused", "no"]
    assert "both a plan and an error" in refusal(json.dumps(both).encode())


def test_a_truncated_answer_is_refused():
    whole = plan_json.dump((full_plan(), None))
    for cut in (1, len(whole) // 3, len(whole) // 2, len(whole) - 1):
        assert "is not a plan" in refusal(whole[:cut])


def test_an_answer_past_the_cap_is_refused_before_it_is_parsed():
    assert "more than the 1000 allowed" in refusal(b'[null, ["x", "' + b"x" * 2000 + b'"]]', cap=1000)


def test_a_long_error_message_is_told_in_one_short_line():
    text = refusal(json.dumps([None, ["Refused", "no\n" * 3_000_000]]).encode())
    assert "refused: no no" in text and len(text) < MESSAGE_CHARS + 300


def test_a_huge_but_valid_name_is_a_plan():
    plan = dataclasses.replace(full_plan(), name="n" * 5_000_000)
    assert read_reply(FOLDER, plan_json.dump((plan, None)), CAP).name == plan.name


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=2000))
def test_random_bytes_are_refused(data):
    refusal(data)


json_values = st.recursive(st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=10),
                           lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner,
                                                                                        max_size=4), max_leaves=12)


def _paths(value, at=()):
    yield at
    children = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, list) else ()
    for key, child in children:
        yield from _paths(child, (*at, key))


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_a_valid_answer_with_any_part_replaced_is_a_plan_of_plan_types_or_refused(data):
    reply = reply_json()
    paths = list(_paths(reply))[1:]
    path = data.draw(st.sampled_from(paths))
    parent = reply
    for key in path[:-1]:
        parent = parent[key]
    parent[path[-1]] = data.draw(json_values)
    try:
        plan = read_reply(FOLDER, json.dumps(reply).encode(), CAP)
    except PlanRefused as exc:
        assert "\n" not in str(exc)
        return
    assert type(plan) is Plan
    classes_in(plan)  # only plan.py's dataclasses, tuples and plain values


# -- reading the child's output ----------------------------------------------------------------


def child(code: str) -> list[str]:
    return [sys.executable, "-c", code]


def test_a_child_that_writes_without_end_is_stopped_at_the_cap():
    with pytest.raises(AnswerTooLong):
        run_bounded(child("import sys\nwhile True: sys.stdout.buffer.write(b'x' * 65536)"), 120, 1 << 20)


def test_only_the_end_of_the_childs_error_output_is_kept():
    code = "import sys; sys.stderr.write('noise\\n' * 2_000_000); sys.stderr.write('last words\\n'); print('[]')"
    returncode, out, err = run_bounded(child(code), 120, 1 << 20)
    assert (returncode, out) == (0, b"[]\n")
    assert err.endswith(b"last words\n") and len(err) <= 2 * (1 << 16)


def test_a_child_that_never_answers_is_stopped_at_the_wall_time():
    with pytest.raises(subprocess.TimeoutExpired):
        run_bounded(child("import time; time.sleep(600)"), 1.0, 1 << 20)
