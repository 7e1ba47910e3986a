"""``python -m benchmarks CASE [ARGS]``: see :mod:`benchmarks.runner`."""

from benchmarks.runner import main

raise SystemExit(main())
