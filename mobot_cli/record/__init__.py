"""The run folder: written by the timeline's consumers, read back by one reader."""
