"""JUnit XML of runs, for CI test reporters (GitLab, Jenkins, GitHub): ``--junit FILE``.

The dialect pytest and launch_testing write, valid against Jenkins' junit-10.xsd (the schema
pytest's xunit2 follows): ``<testsuites>`` holding one ``<testsuite name tests failures errors
skipped time timestamp>`` per run, its seed, status, swept values and metrics as the suite's
``<properties>`` (junit-10.xsd allows properties on a suite only), and one ``<testcase
classname name time>`` per expectation (``run`` when there is none). A failed expectation is a
``<failure message type>``, a fault or an error an ``<error message type>``. Written atomically.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Optional
from xml.etree import ElementTree as ET

from mobot_cli.common.files import write_text_atomic


@dataclass
class Case:
    """One testcase: an expectation of a run, or the run itself."""

    name: str
    failure: Optional[str] = None  # a failed expectation
    error: Optional[tuple[str, str]] = None  # (type, message): a fault or an error


@dataclass
class Suite:
    """One run: its testcases and properties."""

    name: str
    time: float  # s simulated
    properties: list[tuple[str, str]] = field(default_factory=list)
    cases: list[Case] = field(default_factory=list)


def run_suite(record, name: str, extra: Iterable[tuple[str, str]] = ()) -> Suite:
    """The suite of one run's RunRecord (``extra``: more properties, e.g. a sweep's swept values)."""
    error = None
    if record.status.value != "ok":
        kind = record.fault.kind if record.fault is not None else record.status.value
        error = (kind, record.error or record.status.value)
    results = record.expectations.results if record.expectations is not None else []
    cases = [Case(f"{r.robot}: {r.kind}: {r.expected}",
                  failure=None if r.passed or error else f"robot '{r.robot}' was expected to {r.expected}; "
                                                         f"it {r.happened}", error=error)
             for r in results] or [Case("run", error=error)]
    return Suite(name, record.sim_time, [*_properties(record), *extra], cases)


def failed_suite(name: str, kind: str, message: str, extra: Iterable[tuple[str, str]] = ()) -> Suite:
    """A run that left no record (a crash, a timeout): one testcase in error."""
    return Suite(name, 0.0, list(extra), [Case("run", error=(kind or "error", message))])


def sweep_suites(rows: Iterable[dict[str, str]], out_dir: Path, name: str) -> list[Suite]:
    """One suite per run of a sweep, from its results.csv rows and its runs' summary.json: the
    row's values (seed, swept keys, figures and metrics) as properties."""
    from mobot_cli.record.summary import RunRecord

    suites = []
    for row in rows:
        extra = [(k, v) for k, v in row.items() if k not in ("run", "status", "failure", "reason", "wall_time",
                                                              "seed", "expect_passed", "expect_failed")]
        title = f"{name} run {row['run']}"
        record = RunRecord.load(out_dir / row["folder"]) if row.get("folder") else None
        if record is None:
            suites.append(failed_suite(title, row["failure"], row["reason"], [("seed", row["seed"]), *extra]))
        else:
            suites.append(run_suite(record, title, extra))
    return suites


def _properties(record) -> list[tuple[str, str]]:
    props = [("seed", str(record.seed)), ("status", record.status.value), ("sim_time", _text(record.sim_time))]
    for name, robot in record.robots.items():
        props.append((f"{name}.collisions", str(robot.collisions)))
        if robot.metrics is not None:
            props.extend((f"{name}.{key}", _text(value)) for key, value in robot.metrics.to_dict().items()
                         if key != "collisions" and not isinstance(value, list))
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


def document(suites: Iterable[Suite]) -> str:
    """The XML text of ``suites``."""
    suites = list(suites)
    root = ET.Element("testsuites", name="mobot")
    totals = [0, 0, 0, 0.0]
    for suite in suites:
        failures = sum(c.failure is not None for c in suite.cases)
        errors = sum(c.error is not None for c in suite.cases)
        node = ET.SubElement(root, "testsuite", name=suite.name, tests=str(len(suite.cases)),
                             failures=str(failures), errors=str(errors), skipped="0", time=_time(suite.time))
        if suite.properties:
            props = ET.SubElement(node, "properties")
            for key, value in suite.properties:
                ET.SubElement(props, "property", name=key, value=value)
        for k, case in enumerate(suite.cases):
            # every check covers the whole run: the first carries its time, so that the times add up
            element = ET.SubElement(node, "testcase", classname=suite.name, name=case.name,
                                    time=_time(suite.time if k == 0 else 0.0))
            if case.error is not None:
                ET.SubElement(element, "error", type=case.error[0], message=case.error[1]).text = case.error[1]
            elif case.failure is not None:
                ET.SubElement(element, "failure", type="expectation", message=case.failure).text = case.failure
        totals = [totals[0] + len(suite.cases), totals[1] + failures, totals[2] + errors, totals[3] + suite.time]
    root.set("tests", str(totals[0]))
    root.set("failures", str(totals[1]))
    root.set("errors", str(totals[2]))
    root.set("time", _time(totals[3]))
    ET.indent(root)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def _time(seconds: float) -> str:
    """Seconds with three decimals, as junit-10.xsd's SUREFIRE_TIME takes them."""
    return f"{seconds:.3f}"


def write(path: Path, suites: Iterable[Suite]) -> None:
    """Write the report to ``path`` atomically (a reader never sees half a file)."""
    write_text_atomic(Path(path), document(suites), durable=False)
