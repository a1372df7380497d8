"""Analyses built on the engine: tilting table and pushover (tilt.py), drift limits (drift.py)."""
