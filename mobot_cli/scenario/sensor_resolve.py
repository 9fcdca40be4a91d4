"""A robot's sensors for its plan: the description's, changed, added or turned off by the scenario.

A ``sensors:`` key names a described sensor by its <sensor name>, else by its topic or the
topic's last segment (``scan`` for turtlebot3's lds_lfcd_sensor, whose topic is scan); a key
that names none adds a sensor. Rates become whole physics steps (``every``), rounded like the
log period: a sensor reads at most once per step.
"""

from __future__ import annotations

import difflib
from dataclasses import replace
from typing import Protocol

from mobot_cli.assets.description.robot import RobotDescription
from mobot_cli.assets.description.sensors import (
    CAMERA_DEFAULTS,
    KINDS,
    DescribedSensor,
    check_values,
    default_topic,
    with_gazebo_collision,
)
from mobot_cli.errors import Location, ScenarioError, did_you_mean
from mobot_cli.plan import CAMERA_KINDS, SensorSpec
from mobot_cli.scenario.model import RobotSpec
from mobot_cli.scenario.sensor_model import CAMERA_FIELDS, LIDAR_FIELDS, TOPIC_RE, SensorOverride
from mobot_cli.scenario.units import steps


class Context(Protocol):
    """What resolving sensors needs of robots.RobotResolver."""

    rate_hz: int
    notices: list[str]

    def locate_key(self, path: tuple) -> Location | None: ...

    def describe(self, spec: RobotSpec, path: tuple) -> RobotDescription: ...

# A check about a pair of values names the larger; the scenario may have set the smaller.
PARTNER = {"max_angle": "min_angle", "vertical_max_angle": "vertical_min_angle",
           "range_max": "range_min", "samples": "vertical_samples", "clip_far": "clip_near"}
ONLY = {**{f: "lidar" for f in LIDAR_FIELDS}, "accel_noise_stddev": "imu", "collision": "contact",
        **{f: "camera" for f in CAMERA_FIELDS}}


def find_sensors(key: str, sensors: tuple[DescribedSensor, ...]) -> list[DescribedSensor]:
    """The described sensors a ``sensors:`` key names: by name, else by topic or its last segment."""
    named = [s for s in sensors if s.name == key]
    return named or [s for s in sensors if key in (s.topic, s.topic.rsplit("/", 1)[-1])]


def sensor_keys(sensors: tuple[DescribedSensor, ...]) -> list[str]:
    """Every key that names one of ``sensors``: names, topics and topics' last segments."""
    return sorted({k for s in sensors for k in (s.name, s.topic, s.topic.rsplit("/", 1)[-1])})


GROUP_RATES = 3  # more description sensors than this at rates between whole steps: one warning


def resolve_sensors(spec: RobotSpec, desc: RobotDescription, path: tuple,
                    ctx: Context) -> tuple[SensorSpec, ...]:
    """The plan's sensors of one robot entry (shared by every member of a fleet)."""
    sensors = {s.name: s for s in desc.sensors}
    touched: dict[str, str] = {}  # sensor name -> the key that changed or added it
    for key, entry in spec.sensors.items():
        where = path + ("sensors", key)
        found = find_sensors(key, desc.sensors)
        if len(found) > 1:
            raise ScenarioError(f"'{key}' names {len(found)} sensors of '{desc.name}': "
                                + ", ".join(f"'{s.name}' (topic {s.topic})" for s in found),
                                location=ctx.locate_key(where),
                                hint="Use a sensor's name or its whole topic as the key.")
        if found and found[0].name in touched:
            raise ScenarioError(f"'{key}' names sensor '{found[0].name}', as "
                                f"'{touched[found[0].name]}' does", location=ctx.locate_key(where),
                                hint="Give each sensor one entry.")
        if entry.enabled is False:
            if not found:
                added, _, _ = _switch(key, spec, desc, path, ctx) or ("", "", "")
                raise ScenarioError(f"'{key}' turns off a sensor that '{desc.name}' does "
                                    f"not have{added}", location=ctx.locate_key(where),
                                    hint="Without that argument it is off already: remove the entry."
                                    if added else _choices(key, desc, adding=False))
            del sensors[found[0].name]
            touched[found[0].name] = key
            continue
        if not found and (entry.type is None or entry.link is None):
            raise _missing(key, entry, spec, desc, path, ctx)
        sensor = _changed(found[0], entry, where, ctx) if found else _added(key, entry, where, ctx)
        sensors[sensor.name] = _check(sensor, entry, where, desc, ctx)
        touched[sensor.name] = key
    rounded: list[tuple[str, float, int]] = []  # description sensors at rates between whole steps
    out = tuple(_spec(s, touched.get(s.name), spec, desc, path, ctx, rounded) for s in sensors.values())
    rate = ctx.rate_hz
    if len(rounded) > GROUP_RATES:  # one warning, not one a sensor (TurtleBot 4 has 14 at 62 Hz)
        ctx.notices.append(f"robot '{spec.name}': {len(rounded)} sensors of {desc.source.name} read at rates that "
                           f"are not a whole number of physics steps at {rate} Hz, each every whole number of "
                           "steps instead: " + ", ".join(f"'{name}' {wanted:g} Hz -> {rate / every:.4g} Hz"
                                                          for name, wanted, every in rounded))
    else:
        ctx.notices.extend(f"robot '{spec.name}': sensor '{name}' of {desc.source.name} at {wanted:g} Hz is not a "
                           f"whole number of physics steps at {rate} Hz: reading every {every} steps "
                           f"({rate / every:.4g} Hz)" for name, wanted, every in rounded)
    return _unique_topics(out, spec, touched, path, ctx)


def _changed(sensor: DescribedSensor, entry: SensorOverride, where: tuple,
             ctx: Context) -> DescribedSensor:
    changes = entry.changes()
    new_type = changes.get("type")
    if new_type is not None and KINDS[new_type] != KINDS[sensor.type]:
        raise ScenarioError(f"sensor '{sensor.name}' is of type {sensor.type}; type {new_type} "
                            "would make it another kind of sensor", location=ctx.locate_key(
                                where + ("type",)),
                            hint="Turn it off (false) and add the new one under another key.")
    _fields_fit(sensor.kind, entry, where, ctx)  # a range sensor stays one: lidar fields fit it
    return replace(sensor, **changes)


def _missing(key: str, entry: SensorOverride, spec: RobotSpec, desc: RobotDescription, path: tuple,
             ctx: Context) -> ScenarioError:
    """The error for a key that names no sensor and cannot add one: it says which xacro argument
    would give the description that sensor, when one would."""
    missing = [k for k in ("type", "link") if getattr(entry, k) is None]
    added, args, others = _switch(key, spec, desc, path, ctx) or ("", "", "")
    if added:
        return ScenarioError(f"'{desc.name}' has no sensor named '{key}'{added}",
                             location=ctx.locate_key(path + ("sensors", key)),
                             hint=f"Give robot '{spec.name}' args: {args}.")
    hint = _choices(key, desc, adding=True) + (f" {others}" if others else "")
    return ScenarioError(f"'{desc.name}' has no sensor named '{key}' (by name or topic), and "
                         f"adding one needs {' and '.join(repr(m) for m in missing)}",
                         location=ctx.locate_key(path + ("sensors", key)), hint=hint)


def _switch(key: str, spec: RobotSpec, desc: RobotDescription, path: tuple,
            ctx: Context) -> tuple[str, str, str] | None:
    """What sensor_switches.switch_text says of ``key`` (error path only: it expands again)."""
    from mobot_cli.scenario.sensor_switches import arg_text, switch_text

    args = {k: arg_text(v) for k, v in spec.args.items()}
    return switch_text(desc, args, lambda sensors: bool(find_sensors(key, sensors)),
                       lambda other: ctx.describe(spec.model_copy(update={"args": other}), path))


def _added(key: str, entry: SensorOverride, where: tuple, ctx: Context) -> DescribedSensor:
    _fields_fit(KINDS[entry.type], entry, where, ctx)  # type: ignore[index]
    defaults = CAMERA_DEFAULTS if KINDS[entry.type] in CAMERA_KINDS else {}  # type: ignore[index]
    added = replace(DescribedSensor(name=key.replace("/", "_"), type=entry.type,  # type: ignore[arg-type]
                                    link=entry.link, **defaults), **entry.changes())  # type: ignore[arg-type]
    if added.topic:
        return added
    return replace(added, topic=key if TOPIC_RE.match(key) else default_topic(added))


def _fields_fit(kind: str, entry: SensorOverride, where: tuple, ctx: Context) -> None:
    for name in sorted(entry.model_fields_set):
        family = "lidar" if kind == "range" else "camera" if kind in CAMERA_KINDS else kind
        if ONLY.get(name, kind) not in (kind, family):
            raise ScenarioError(f"'{name}' applies to {ONLY[name]} sensors, and this one is "
                                f"{'an' if kind == 'imu' else 'a'} {kind}",
                                location=ctx.locate_key(where + (name,)),
                                hint=f"Remove '{name}'.")


def _check(sensor: DescribedSensor, entry: SensorOverride, where: tuple, desc: RobotDescription,
           ctx: Context) -> DescribedSensor:
    """``sensor`` when its values are sound (its collision named as Gazebo does), else an error."""
    links = {link.name: link for link in desc.links}
    if sensor.link not in links:
        raise ScenarioError(f"link '{sensor.link}' is not a link of '{desc.name}'",
                            location=ctx.locate_key(where + ("link",)),
                            hint=did_you_mean(sensor.link, links) or "Name one of its links.")
    problem = check_values(sensor, links[sensor.link].collisions)
    if problem is not None:
        field, message, hint = problem
        given = [f for f in (field, PARTNER.get(field)) if f in entry.model_fields_set]
        key = where + (given[0],) if given else where
        raise ScenarioError(f"sensor '{sensor.name}' {message}", location=ctx.locate_key(key),
                            hint=hint.replace("{field}", field))
    return with_gazebo_collision(sensor, links[sensor.link].collisions)


def _spec(sensor: DescribedSensor, key: str | None, spec: RobotSpec, desc: RobotDescription,
          path: tuple, ctx: Context, rounded: list) -> SensorSpec:
    """``sensor`` reading every whole number of steps; ``key`` is the entry that touched it. A
    description's rate that falls between whole steps goes to ``rounded`` (said together)."""
    rate, wanted = ctx.rate_hz, sensor.rate_hz
    where = path + ("sensors", key, "rate_hz") if key is not None else None
    # Not the scenario's file and line: a resolved scenario must reload to an equal plan.
    source = str(desc.source) if sensor.name in {s.name for s in desc.sensors} else "scenario"
    if where is not None and spec.sensors[key].rate_hz is not None:  # type: ignore[index]
        what = f"{ctx.locate_key(where)}: rate_hz {wanted:g}"
        if wanted > rate:
            raise ScenarioError(f"rate_hz {wanted:g} is above physics.rate_hz {rate}",
                                location=ctx.locate_key(where),
                                hint="A sensor reads at most once per physics step.")
    else:
        what = f"robot '{spec.name}': sensor '{sensor.name}' of {desc.source.name} at {wanted:g} Hz"
    if wanted == 0:  # Gazebo without <update_rate>: every step
        return sensor.spec(1, source)
    if wanted > rate:
        ctx.notices.append(f"{what} is above physics.rate_hz {rate}: it reads every step")
        return sensor.spec(1, source)
    every = max(1, steps(1.0 / wanted, rate))
    if abs(rate / every - wanted) > 1e-9:
        if where is not None and spec.sensors[key].rate_hz is not None:  # type: ignore[index]
            ctx.notices.append(f"{what} is not a whole number of physics steps at {rate} Hz: reading "
                               f"every {every} steps ({rate / every:.4g} Hz)")
        else:
            rounded.append((sensor.name, wanted, every))
    return sensor.spec(every, source)


def _unique_topics(sensors: tuple[SensorSpec, ...], spec: RobotSpec, touched: dict[str, str], path: tuple,
                   ctx: Context) -> tuple[SensorSpec, ...]:
    """One sensor a topic: records, the bag and ROS 2 keep a sensor's readings by its topic. Two
    that the description puts on one topic (a sonar array, as Gazebo allows: one frame each) keep
    it for the first, and the others get a numbered topic, said in a notice; a topic the scenario
    gives twice is an error."""
    taken = {sensor.topic for sensor in sensors}
    seen: dict[str, str] = {}
    out = []
    for sensor in sensors:
        other = seen.setdefault(sensor.topic, sensor.name)
        if other != sensor.name:
            if any(touched.get(name) is not None and spec.sensors[touched[name]].topic is not None
                   for name in (other, sensor.name)):  # the scenario chose that topic
                raise ScenarioError(f"sensors '{other}' and '{sensor.name}' of robot '{spec.name}' both "
                                    f"publish on '{sensor.topic}'", location=ctx.locate_key(
                                        path + ("sensors",) if spec.sensors else path),
                                    hint=f"Give one of them another topic, e.g. sensors: "
                                         f"{{{sensor.name}: {{topic: {sensor.topic}_2}}}}.")
            number = 2
            while f"{sensor.topic}_{number}" in taken:
                number += 1
            topic = f"{sensor.topic}_{number}"
            ctx.notices.append(f"robot '{spec.name}': sensors '{other}' and '{sensor.name}' of its description both "
                               f"publish on '{sensor.topic}'; mobot keeps one sensor a topic, so '{sensor.name}' "
                               f"publishes on '{topic}' (sensors: {{{sensor.name}: {{topic: ...}}}} chooses another)")
            taken.add(topic)
            sensor = replace(sensor, topic=topic)
            seen[topic] = sensor.name
        out.append(sensor)
    return tuple(out)


def _choices(key: str, desc: RobotDescription, adding: bool) -> str:
    """A close key, else the keys that name its sensors (and how to add one)."""
    keys = sensor_keys(desc.sensors)
    close = difflib.get_close_matches(key, keys, n=1, cutoff=0.6)
    if close:
        return f"Did you mean '{close[0]}'?"
    named = (f"Its sensors answer to {', '.join(repr(k) for k in keys)}" if keys
             else f"'{desc.name}' has no sensors mobot simulates")
    return named + ("; to add one, give type (lidar, imu, contact or camera) and link." if adding else ".")
