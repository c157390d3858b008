"""Scenario replay for Speech Event: load scenario files, play them to the node, report."""
