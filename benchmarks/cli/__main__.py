"""``python -m ogcp.benchmarks.cli``: the ``ogcp`` command without the console script."""

import sys

from ogcp.benchmarks.cli.app import main

sys.exit(main())
