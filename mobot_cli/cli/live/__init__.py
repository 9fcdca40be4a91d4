"""The live-world commands: clients of `mobot serve` that share one set of options."""
