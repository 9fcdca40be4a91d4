"""Every example in README.md and docs/*.md runs, as typer runs its docs' examples (STYLE.md item 9).

Each page runs in a fresh folder holding links to the checkout's scenarios/, robots/, worlds/ and
tests/ (and the corpus's folders, when it is there), its blocks in order:

- ```yaml starting with `version: 1`: saved as <name>.yaml, then `mobot run <name>.yaml --out
  runs/<name> --quiet`; exit 0 unless marked. A ```text block right after it that starts with
  `mobot:` is what the run must print on stderr.
- ```python: executed, in one namespace per page (a block may use what an earlier one made).
- ```bash: run as a bash script. ```console: every `$ mobot ...` line runs; `# exit N` in its
  comment is the exit code it must have, and the lines shown under it must match what it
  prints, in order (`...` stands for anything). `$ mobot serve ... &` starts a live world in
  the background; the page's lines talk to it through a private MOBOT_ENDPOINT.

`mobot` is this checkout's (`sys.executable -m mobot_cli`). An HTML comment right before a
block changes how it runs: `<!-- docs-test: exit N -->`, `corpus` (needs the corpus),
`serve ARGS` (a live world for that block), `skip (why)`.
"""

from __future__ import annotations

import os
import re
import shlex
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import pytest
import yaml

from mobot_cli.cli import invoke
from mobot_cli.errors import LiveWorldError
from mobot_cli.live.client import Client
from tests.conftest import CORPUS

REPO = Path(__file__).resolve().parent.parent
PAGES = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
FENCE = re.compile(r"^(\s*)```(\w*)\s*$")
DIRECTIVE = re.compile(r"^\s*<!--\s*docs-test:\s*(.*?)\s*-->\s*$")
EXIT = re.compile(r"#\s*exit (\d+)\b")
MAX_SKIPPED = 8  # blocks that truly cannot run in a test; keep them few
TIMEOUT = 600.0  # s for one command: the longest example runs ~170 simulated s


@dataclass
class Block:
    page: str
    line: int  # of the opening fence, 1-based
    lang: str
    text: str
    directives: list[str] = field(default_factory=list)
    follows: int = 0  # blank lines between this block and the one before it (-1: prose between)

    def directive(self, word: str) -> str | None:
        """The rest of the first directive that starts with `word`, or None."""
        for d in self.directives:
            if d == word or d.startswith(word + " "):
                return d[len(word):].strip()
        return None

    @property
    def where(self) -> str:
        return f"{self.page}:{self.line}"


def blocks(path: Path) -> list[Block]:
    """The fenced code blocks of a Markdown page, with the docs-test comments right before each."""
    lines = path.read_text().splitlines()
    found: list[Block] = []
    pending: list[str] = []
    gap, i = -1, 0
    while i < len(lines):
        opening = FENCE.match(lines[i])
        if opening is None:
            directive = DIRECTIVE.match(lines[i])
            if directive:
                pending.append(directive.group(1))
            elif lines[i].strip():
                pending, gap = [], -1
            elif gap >= 0:
                gap += 1
            i += 1
            continue
        indent, lang = opening.groups()
        body, i = [], i + 1
        while i < len(lines) and lines[i].strip() != "```":
            body.append(lines[i][len(indent):] if lines[i].startswith(indent) else lines[i].lstrip())
            i += 1
        found.append(Block(path.name, i - len(body), lang, "\n".join(body) + "\n", pending, gap))
        pending, gap, i = [], 0, i + 1
    return found


def all_blocks() -> list[Block]:
    return [b for page in PAGES for b in blocks(page)]


# --- what a block must leave behind, beyond exiting as documented -----------------------------

def _quickstart_fleet(ws: Path, scope: dict) -> None:
    assert sorted(p.name for p in (ws / "runs" / "quickstart" / "odom").iterdir()) == \
        ["mobot.csv", "mobot_0.csv", "mobot_1.csv", "mobot_2.csv"]


def _goals_all_reached(ws: Path, scope: dict) -> None:
    import json
    record = json.loads((ws / "runs" / "goals" / "summary.json").read_text())
    assert [g["status"] for g in record["robots"]["mobot"]["goals"]] == ["reached"] * 4
    assert record["expectations"]["failed"] == 0


def _invoke_example(ws: Path, scope: dict) -> None:
    assert (ws / "runs" / "api" / "summary.json").is_file() and (ws / "runs" / "tty").is_dir()


def _go_to_goal(ws: Path, scope: dict) -> None:
    final = scope["sim"].record.robots["r1"].final_pose
    assert abs(final.x - 1.5) < 0.1 and abs(final.y - 0.5) < 0.1
    assert (ws / "runs" / "goal" / "odom" / "r1.csv").is_file()


def _stops_before_the_wall(ws: Path, scope: dict) -> None:
    sim, ahead, scan = scope["sim"], scope["ahead"], scope["scan"]
    assert 0.3 < ahead.min() < 0.4 and scan.t == pytest.approx(16.4, abs=0.3)  # 7.9 m at 0.5 m/s
    # The house's wall ahead of (-3, -2.5) has its face at x = 5.3 (8.3 m away at the start).
    assert sim.record.robots["r1"].final_pose.x + ahead.min() == pytest.approx(5.3, abs=0.03)
    assert (ws / "runs" / "stop" / "sensors" / "r1" / "lidar.npy").is_file()


def _gym_checked(ws: Path, scope: dict) -> None:
    assert scope["obs"].shape == (7,) and scope["info"]["t"] > 0


CHECKS: dict[tuple[str, str], Callable[[Path, dict], None]] = {
    ("README.md", "name: quickstart"): _quickstart_fleet,
    ("goals.md", "name: goals"): _goals_all_reached,
    ("development.md", "invoke("): _invoke_example,
    ("python-api.md", "goal = (1.5, 0.5)"): _go_to_goal,
    ("python-api.md", "sim.scan("): _stops_before_the_wall,
    ("python-api.md", "check_env("): _gym_checked,
}


# --- running a page ----------------------------------------------------------------------------

class Page:
    """One page's folder, shell environment, Python namespace and background live worlds."""

    def __init__(self, ws: Path, endpoint: str):
        self.ws, self.endpoint = ws, endpoint
        self.scope: dict[str, Any] = {"__name__": "__docs__"}
        self.servers: list[subprocess.Popen] = []
        bin_dir = ws.parent / "bin"
        bin_dir.mkdir()
        mobot = bin_dir / "mobot"
        mobot.write_text(f'#!/bin/sh\nexec {shlex.quote(sys.executable)} -m mobot_cli "$@"\n')
        mobot.chmod(0o755)
        self.env = dict(os.environ, PATH=f"{bin_dir}{os.pathsep}{os.environ['PATH']}", MOBOT_ENDPOINT=endpoint,
                        PYTHONPATH=str(REPO), NO_COLOR="1")

    def shell(self, command: str) -> subprocess.CompletedProcess:
        return subprocess.run(["bash", "-o", "pipefail", "-c", command], cwd=self.ws, env=self.env,
                              capture_output=True, text=True, timeout=TIMEOUT)

    def serve(self, command: str, where: str) -> None:
        """Start `mobot serve ...` in the background and wait until it answers on the endpoint."""
        log = open(self.ws.parent / f"serve-{len(self.servers)}.log", "w+")
        process = subprocess.Popen(["bash", "-c", f"exec {command}"], cwd=self.ws, env=self.env,
                                   stdout=log, stderr=subprocess.STDOUT)
        self.servers.append(process)
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            if process.poll() is not None:
                log.seek(0)
                pytest.fail(f"{where}: `{command}` exited with {process.returncode}:\n{log.read()}")
            try:
                with Client(self.endpoint, timeout=0.5) as world:
                    world.ping()
                return
            except LiveWorldError:
                time.sleep(0.1)
        pytest.fail(f"{where}: `{command}` did not answer within 60 s")

    def stop_servers(self) -> None:
        for process in self.servers:
            if process.poll() is None:
                process.send_signal(signal.SIGTERM)
                try:
                    process.wait(30)
                except subprocess.TimeoutExpired:
                    process.kill()
                    process.wait()
        self.servers.clear()


def expect_output(shown: list[str], printed: str, where: str) -> None:
    """Each shown line matches a printed line, in order; `...` stands for anything."""
    lines = [line.strip() for line in printed.splitlines()]
    at = 0
    for want in (line.strip() for line in shown):
        if not want or want == "...":
            continue
        pattern = re.compile(".*".join(re.escape(part) for part in want.split("...")))
        for k in range(at, len(lines)):
            if pattern.fullmatch(lines[k]):
                at = k + 1
                break
        else:
            pytest.fail(f"{where}: the page shows\n  {want}\nbut the command printed\n{printed}")


def run_console(page: Page, block: Block) -> None:
    commands: list[tuple[str, list[str]]] = []
    for line in block.text.splitlines():
        if line.startswith("$ "):
            commands.append((line[2:], []))
        elif commands:
            commands[-1][1].append(line)
    for command, shown in commands:
        code = shlex.split(command, comments=True)
        if not code or code[0] != "mobot":
            continue  # ros2, rviz2, ...: shown for the reader, not run here
        expected = int(EXIT.search(command).group(1)) if EXIT.search(command) else 0
        where = f"{block.where}: $ {command}"
        if code[-1] == "&":
            assert code[:2] == ["mobot", "serve"], f"{where}: only `mobot serve` runs in the background"
            page.serve(shlex.join(code[:-1]), where)
            continue
        done = page.shell(command)
        assert done.returncode == expected, f"{where}: exit {done.returncode}\n{done.stdout}{done.stderr}"
        expect_output(shown, done.stdout + done.stderr, where)
        if code[:2] == ["mobot", "stop"]:
            for process in page.servers:
                process.wait(30)


def run_scenario(page: Page, block: Block, after: Block | None) -> None:
    name = yaml.safe_load(block.text)["name"]
    (page.ws / f"{name}.yaml").write_text(block.text)
    expected = int(block.directive("exit") or 0)
    done = invoke(["run", f"{name}.yaml", "--out", f"runs/{name}", "--quiet"])
    assert done.exit_code == expected, f"{block.where}: exit {done.exit_code}\n{done.stderr}"
    if after is not None and after.lang == "text" and after.follows >= 0 and after.text.startswith("mobot:"):
        assert done.stderr.strip() == after.text.strip(), f"{block.where}: the page shows another message"


def run_block(page: Page, block: Block, after: Block | None) -> None:
    serve = block.directive("serve")
    if serve is not None:
        page.serve(f"mobot serve {serve}", block.where)
    try:
        if block.lang == "python":
            exec(compile(block.text, block.where, "exec"), page.scope)
        elif block.lang == "bash":
            done = page.shell(block.text)
            expected = int(block.directive("exit") or 0)
            assert done.returncode == expected, f"{block.where}: exit {done.returncode}\n{done.stdout}{done.stderr}"
        elif block.lang == "console":
            run_console(page, block)
        elif block.lang == "yaml" and block.text.startswith("version: 1"):
            run_scenario(page, block, after)
    finally:
        page.stop_servers()
    for (page_name, marker), check in CHECKS.items():
        if page_name == block.page and marker in block.text:
            check(page.ws, page.scope)


def runnable(block: Block) -> bool:
    return block.lang in ("python", "bash", "console") or \
        (block.lang == "yaml" and block.text.startswith("version: 1"))


@pytest.mark.parametrize("path", PAGES, ids=[p.name for p in PAGES])
def test_every_example_on_the_page_runs(path, tmp_path, monkeypatch):
    ws = tmp_path / "ws"
    ws.mkdir()
    for name in ("scenarios", "robots", "worlds", "tests"):
        (ws / name).symlink_to(REPO / name)
    have_corpus = (CORPUS / "README.md").is_file()
    if have_corpus:
        for entry in CORPUS.iterdir():
            if entry.is_dir() and not (ws / entry.name).exists():
                (ws / entry.name).symlink_to(entry)
    # Unix socket paths must stay short: pytest's tmp_path is often too long for one.
    sockets = Path(tempfile.mkdtemp(prefix="mobot-d-"))
    endpoint = f"ipc://{sockets / 's.sock'}"
    monkeypatch.chdir(ws)
    monkeypatch.setenv("MOBOT_ENDPOINT", endpoint)
    page = Page(ws, endpoint)
    found = blocks(path)
    left_out = []
    try:
        for k, block in enumerate(found):
            if not runnable(block) or block.directive("skip") is not None:
                continue
            if block.directive("corpus") is not None and not have_corpus:
                left_out.append(block.where)
                continue
            run_block(page, block, found[k + 1] if k + 1 < len(found) else None)
    finally:
        page.stop_servers()
        import shutil
        shutil.rmtree(sockets, ignore_errors=True)
    if left_out:
        pytest.skip(f"corpus not found at {CORPUS} (set MOBOT_CORPUS): not run: {', '.join(left_out)}")


def test_skipped_blocks_are_few_and_say_why():
    every = all_blocks()
    skipped = [b for b in every if b.directive("skip") is not None]
    run = [b for b in every if runnable(b) and b not in skipped]
    listing = "\n".join(f"  {b.where}: {b.directive('skip')}" for b in skipped)
    print(f"\ndocs examples: {len(run)} blocks run, {len(skipped)} skipped:\n{listing}")
    assert all(re.fullmatch(r"\(.+\)", b.directive("skip")) for b in skipped), \
        f"a skipped block says why, as `<!-- docs-test: skip (why) -->`:\n{listing}"
    assert len(skipped) <= MAX_SKIPPED, f"{len(skipped)} examples cannot run; keep them few:\n{listing}"
    known = {"skip", "exit", "corpus", "serve"}
    for b in every:
        for d in b.directives:
            assert d.split()[0] in known, f"{b.where}: unknown docs-test directive {d!r}"


def test_every_page_is_in_the_site_and_the_readme_links_it():
    site = yaml.safe_load((REPO / "mkdocs.yml").read_text())
    def pages(nav) -> list[str]:
        out = []
        for item in nav:
            value = next(iter(item.values())) if isinstance(item, dict) else item
            out += pages(value) if isinstance(value, list) else [value]
        return out
    in_nav = pages(site["nav"])
    on_disk = sorted(p.name for p in (REPO / "docs").glob("*.md"))
    assert sorted(in_nav) == on_disk
    readme = (REPO / "README.md").read_text()
    missing = [name for name in on_disk if f"docs/{name}" not in readme]
    assert not missing, f"README.md links no page {missing}"
    assert len(readme.splitlines()) <= 300, "the README is a front page: the manual is docs/"


def test_every_command_is_documented():
    """Each command `mobot --help` lists appears in the README's table and on a docs page."""
    done = invoke(["--help"])
    listed = re.findall(r"^  (\w+) ", done.stdout.split("Commands:")[1], re.M)
    assert len(listed) > 15
    readme = (REPO / "README.md").read_text()
    docs = "".join(p.read_text() for p in (REPO / "docs").glob("*.md"))
    for command in listed:
        assert re.search(rf"`(mobot )?{command}\b", readme), f"README's table lacks `{command}`"
        assert f"mobot {command}" in docs, f"no docs page shows `mobot {command}`"
