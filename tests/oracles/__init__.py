"""Plain, independently written references that the tests (and benchmarks) hold the compiled
engine to. Nothing in ``src/`` imports them (tests/test_layers.py)."""
