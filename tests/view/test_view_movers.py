"""Movers in the live browser view: shapes that appear, move and go as the world's movers do."""

from __future__ import annotations

from pathlib import Path

import pytest

from mobot_cli.scenario.prepare import prepare

pytest.importorskip("viser", reason="the view extra (viser) is not installed")
DATA = Path(__file__).resolve().parents[1] / "data"


@pytest.fixture
def page():
    from mobot_cli.view.page import close_page, open_page

    server = open_page(0)
    yield server
    close_page(server)


def test_movers_are_drawn_where_they_are(page, tmp_path):
    from mobot_cli.sim.bullet.world import World
    from mobot_cli.timeline.loop import Timeline
    from mobot_cli.view.live import LiveView

    scenario = tmp_path / "s.yaml"
    scenario.write_text(f"version: 1\nworld: {DATA / 'actor_crossing.sdf'}\nduration: 3\n"
                        "movers:\n  - {name: crate, shape: box, size: [0.5, 0.4, 0.6], path: [[-2, 0], [-2, 2]]}\n")
    plan = prepare(scenario).plan
    live = LiveView(page, plan, rate_hz=50)
    try:
        with World(plan.physics, plan.world, seed=plan.seed) as world:
            timeline = Timeline(plan, world)
            timeline.attach(lambda record: None)
            timeline.start()
            live.watch(timeline)
            for _ in range(480):
                timeline.tick()
                timeline.advance()
            timeline.tick()
            live.draw(force=True)
            walker, crate = live.mover_shapes.handles["walker"][0], live.mover_shapes.handles["crate"][0]
            assert tuple(walker.position) == pytest.approx((2.0, -0.734375, 0.85))  # 1.5 s on the spline
            assert tuple(crate.position) == pytest.approx((-2.0, 2.0, 0.3))
            timeline.remove_mover("crate")
            for _ in range(24):
                timeline.tick()
                timeline.advance()
            timeline.tick()
            live.draw(force=True)
            assert "crate" not in live.mover_shapes.handles
    finally:
        live.close()


def test_a_replay_shows_the_movers_of_the_run(page, tmp_path, monkeypatch):
    from mobot_cli.cli import invoke
    from mobot_cli.view.replay import Replay
    from mobot_cli.view.runfolder import read_run

    scenario = tmp_path / "s.yaml"
    scenario.write_text(f"version: 1\nworld: {DATA / 'actor_crossing.sdf'}\nduration: 3\n"
                        "robots:\n  - {name: r, description: mobot}\n"
                        "movers:\n  - {name: crate, shape: box, size: [0.5, 0.4, 0.6], "
                        "path: [[-2, 0], [-2, 2]], at: 1}\n")
    assert invoke(["run", str(scenario), "--out", str(tmp_path / "run"), "--quiet"]).exit_code == 0
    # A run folder's world is read as a live spawn's (docs/security.md): only inside the folder and
    # the resource path, where a user puts the folder of their worlds.
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", str(DATA))
    view = read_run(tmp_path / "run")
    assert set(view.movers) == {"walker", "crate"}
    assert view.movers_at(0.5) == {"walker": (2.0, -2.0, 1.5708)}  # the crate comes at 1 s
    assert view.movers_at(2.0)["crate"] == (-2.0, 1.0, 1.570796)
    replay = Replay(page, [tmp_path / "run"], view)
    try:
        replay.slider.value = 2.0
        replay._scrub(type("Event", (), {"client": object()})())  # a user's scrub, as the page sends it
        assert tuple(replay.mover_shapes.handles["crate"][0].position) == pytest.approx((-2.0, 1.0, 0.3))
        assert tuple(replay.mover_shapes.handles["walker"][0].position) == pytest.approx((2.0, -0.734375, 0.85))
    finally:
        replay.close()
