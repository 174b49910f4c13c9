"""Speed and quality measurements of the project (not tests: their speeds depend on the machine).

Each ``benchmarks/<name>_benchmark.py`` runs on its own (``python benchmarks/<name>_benchmark.py``)
and prints its table; ``--json FILE`` also writes its figures for ``python -m benchmarks.report``,
which re-runs them and writes ``docs/benchmarks.md``.
"""
