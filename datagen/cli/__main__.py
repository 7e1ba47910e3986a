"""``python -m datagen.cli``: the ``drape`` command without its console script."""

import sys

from datagen.cli import main

sys.exit(main())
