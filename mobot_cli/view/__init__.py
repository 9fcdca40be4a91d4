"""The view: a local web page (viser) that draws a world, its robots, their paths and readings.

`mobot view RUN_DIR` replays a run folder (replay.py); `mobot run --view` and `mobot serve --view`
feed the same page live from the timeline (live.py). Nothing here is imported by a headless run:
viser and yourdfpy load only when a view is asked for. Imports point down: view -> run, scenario,
assets, sim, common.
"""
