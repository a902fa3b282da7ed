"""``python -m omsd.recording record|replay ...``: ``omsd record`` and ``omsd replay``."""

import sys

from omsd.recording.cli import main

sys.exit(main())
