import sys

from omsd.cli import main

sys.exit(main())
