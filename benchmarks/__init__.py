"""drape's benchmarks: scripts that print figures (speed, sizes, quality), never tests that assert them.

One runner, ``python -m benchmarks CASE [ARGS]`` from the repository's root (``--list`` prints the
cases); the cases are listed in :mod:`benchmarks.runner`, their shared helpers are in
:mod:`benchmarks.common`, and ``benchmarks/device_run.sh`` runs the GPU phases on a device machine.
Not part of the installed package.
"""
