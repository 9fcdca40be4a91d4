"""JUnit XML of runs, for CI test reporters (GitLab, Jenkins, GitHub): ``--junit FILE``.

The shape pytest and launch_testing write: ``<testsuites>`` holding one ``<testsuite name tests
failures errors skipped time timestamp>`` of ``<testcase classname name time>``; a failed check
is a ``<failure message type>``, a fault or an error an ``<error message type>``. Seed,
metrics and swept values are ``<properties>`` of their testcase (Jenkins' junit-10.xsd
allows properties on a testsuite only; its newer schema and GitLab read them on testcases,
as pytest's record_property writes them). The file is written atomically.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable
from xml.etree import ElementTree as ET

from mobot_cli.common.files import write_text_atomic


@dataclass
class Case:
    """One testcase: a run, or one expectation of a run."""

    classname: str
    name: str
    time: float
    properties: list[tuple[str, str]] = field(default_factory=list)
    failure: str | None = None  # a failed expectation
    error: tuple[str, str] | None = None  # (type, message): a fault or an error


def run_cases(record, scenario: str) -> list[Case]:
    """The testcases of one run's RunRecord: one per expectation, or the run itself without any."""
    base = _properties(record)
    error = None
    if record.status.value not in ("ok",):
        kind = record.fault.kind if record.fault is not None else record.status.value
        error = (kind, record.error or record.status.value)
    results = record.expectations.results if record.expectations is not None else []
    if not results:
        return [Case(scenario, "run", record.sim_time, base, error=error)]
    return [Case(scenario, f"{r.robot}: {r.kind}: {r.expected}", record.sim_time, base,
                 failure=None if r.passed or error else f"robot '{r.robot}' was expected to {r.expected}; "
                                                          f"it {r.happened}", error=error)
            for r in results]


def sweep_cases(rows: Iterable[dict[str, str]], name: str) -> list[Case]:
    """One testcase per run of a sweep, from its results.csv rows: the row's values (seed, swept
    keys, metrics) as properties; a failed expectation a failure, a fault, error or timeout an error."""
    cases = []
    for row in rows:
        props = [(k, v) for k, v in row.items() if k not in ("run", "status", "failure", "reason", "wall_time")]
        case = Case(name, f"run {row['run']}", float(row.get("wall_time") or 0.0), props)
        if row["status"] != "passed":
            if row["failure"] == "expectation":
                case.failure = row["reason"]
            else:
                case.error = (row["failure"] or "error", row["reason"])
        cases.append(case)
    return cases


def _properties(record) -> list[tuple[str, str]]:
    props = [("seed", str(record.seed)), ("status", record.status.value), ("sim_time", _text(record.sim_time))]
    for name, robot in record.robots.items():
        props.append((f"{name}.collisions", str(robot.collisions)))
        if robot.metrics is not None:
            props.extend((f"{name}.{key}", _text(value)) for key, value in robot.metrics.to_dict().items()
                         if not isinstance(value, list) and key != "collisions")
        for goal in robot.goals:
            if goal.command is not None:
                props.extend((f"{name}.goal{goal.command}.{key}", _text(getattr(goal, key)))
                             for key in ("status", "success", "time", "path_length", "spl", "failure"))
    return props


def _text(value) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def document(suite: str, cases: Iterable[Case]) -> str:
    """The XML text of one test suite of ``cases``."""
    cases = list(cases)
    failures = sum(c.failure is not None for c in cases)
    errors = sum(c.error is not None for c in cases)
    total = sum(c.time for c in cases)
    root = ET.Element("testsuites", name="mobot", tests=str(len(cases)), failures=str(failures),
                      errors=str(errors), time=f"{total:.3f}")
    node = ET.SubElement(root, "testsuite", name=suite, tests=str(len(cases)), failures=str(failures),
                         errors=str(errors), skipped="0", time=f"{total:.3f}")
    for case in cases:
        element = ET.SubElement(node, "testcase", classname=case.classname, name=case.name, time=f"{case.time:.3f}")
        if case.properties:
            props = ET.SubElement(element, "properties")
            for key, value in case.properties:
                ET.SubElement(props, "property", name=key, value=value)
        if case.error is not None:
            ET.SubElement(element, "error", type=case.error[0], message=case.error[1]).text = case.error[1]
        elif case.failure is not None:
            ET.SubElement(element, "failure", type="expectation", message=case.failure).text = case.failure
    ET.indent(root)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def write(path: Path, suite: str, cases: Iterable[Case]) -> None:
    """Write the suite to ``path`` atomically (a reader never sees half a file)."""
    write_text_atomic(Path(path), document(suite, cases), durable=False)
