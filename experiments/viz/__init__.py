"""Figures, the demo and the snapshot."""
