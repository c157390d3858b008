"""Adapters that plug into the node's ports."""
