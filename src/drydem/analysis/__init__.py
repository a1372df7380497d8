"""Analyses built on the engine: tilting table and pushover (tilt), limit analysis (limit),
Eurocode 8 drift limits (drift), load paths and elastic settlement (support)."""
