"""``python -m benchmarks.cli``: the ``ogcp`` command without the console script."""

import sys

from benchmarks.cli.app import main

sys.exit(main())
