"""``python -m parakin.cli``: the ``parakin`` command."""

import sys

from parakin.cli import main

sys.exit(main())
