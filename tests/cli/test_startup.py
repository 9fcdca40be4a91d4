"""The garbage collector is held back while a command starts and running when it works.

__main__.entry() disables it; the CLI starts it again, with start-up's objects frozen, once a
run's scenario is loaded (cli/run.py) or, for any other command, before it starts (cli/app.py).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]

# Records the collector's state when the command gets to work, then runs `mobot` as the console script does.
PROBE = """
import functools, gc, sys
import mobot_cli.run as execute
import mobot_cli.cli.check as check
seen = []
def probe(original):
    @functools.wraps(original)  # Typer reads the command's options from its signature
    def wrapped(*args, **kwargs):
        seen.append((gc.isenabled(), gc.get_freeze_count() > 1000))
        return original(*args, **kwargs)
    return wrapped
execute.execute = probe(execute.execute)
check.check = probe(check.check)
sys.argv = ["mobot", *sys.argv[1:]]
from mobot_cli.__main__ import entry
try:
    entry()
finally:
    print("seen", seen, "enabled at exit", gc.isenabled())
"""


def _probe(*args: str) -> str:
    done = subprocess.run([sys.executable, "-c", PROBE, *args], capture_output=True, text=True, cwd=REPO)
    return done.stdout.strip().splitlines()[-1]


def test_a_run_loads_without_the_collector_and_runs_with_it(tmp_path):
    line = _probe("run", str(REPO / "scenarios" / "quickstart.yaml"), "--out", str(tmp_path / "out"),
                  "--quiet", "--duration", "0.5")
    assert line == "seen [(True, True)] enabled at exit True"
    assert (tmp_path / "out" / "summary.json").exists()


def test_a_command_read_by_typer_runs_with_the_collector(tmp_path):
    line = _probe("check", str(REPO / "scenarios" / "quickstart.yaml"))
    assert line == "seen [(True, True)] enabled at exit True"


def test_in_process_commands_leave_the_collector_alone(tmp_path):
    import gc

    from mobot_cli.cli import invoke

    frozen = gc.get_freeze_count()
    out = invoke(["run", REPO / "scenarios" / "quickstart.yaml", "--out", tmp_path / "out", "--quiet",
                  "--duration", "0.2"])
    assert out.exit_code == 0 and gc.isenabled() and gc.get_freeze_count() == frozen
