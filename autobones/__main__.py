"""``python -m autobones``: the same command line as the ``autobones`` script."""
import sys

from .cli.main import main

sys.exit(main())
