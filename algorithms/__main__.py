"""`python -m algorithms COMMAND ...`: the headless commands without the viewer."""

import sys

from .cli import main

sys.exit(main())
