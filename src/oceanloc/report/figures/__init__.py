"""Figures (matplotlib, written as PNG), one module per domain: survey, replay, field, flock, drift."""
