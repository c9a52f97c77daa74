"""``python -m esrl_rs`` is ``python -m esrl_rs.report``."""

import sys

from .report import main

sys.exit(main())
